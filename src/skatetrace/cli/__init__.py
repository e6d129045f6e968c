"""The ``skatetrace`` command line: the only place that prints or exits.

The commands (:mod:`.commands`) and the compiled-code warm-up they run first (:mod:`.compiled`).
"""

from .commands import build_parser, main

__all__ = ["build_parser", "main"]
