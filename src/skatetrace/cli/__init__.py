"""The ``skatetrace`` command line: the only place that prints or exits.

The commands (:mod:`.commands`, and :mod:`skatetrace.cli.robustness` for ``skatetrace
robustness``), the values with units they read (:mod:`.values`), the compiled-code warm-up they
run first (:mod:`.compiled`) and the process's entry (:mod:`.entry`).
"""

from .commands import build_parser, main
from .entry import script

__all__ = ["build_parser", "main", "script"]
