"""The ``skatetrace`` command line: the only place that prints or exits.

The commands (:mod:`.commands`) and the compiled-code warm-up they run first (:mod:`.compiled`).
"""

from .commands import main

__all__ = ["main"]
