"""The ``skatetrace`` process: :func:`~skatetrace.cli.commands.main`, then an exit without the teardown's collection.

When a Python process exits, the interpreter's last garbage collections destroy every object left
in a reference cycle. After a run that is mostly numba's compiled code (its LLVM modules and
dispatchers) and CasADi's functions: measured on the double flower, 0.4 s between the last line
printed and the end of the process, about a third of the whole command from a cold start, and the
same after any other command. The operating system frees the memory at once, so
:func:`script` moves the objects still alive out of the collector's reach (:func:`gc.freeze`)
before it returns. Nothing of the run's output depends on those collections: by then the files
are written and closed and the worker processes joined, and the exit still flushes the standard
streams and runs the ``atexit`` handlers.

Only the process's entry does this: :func:`~skatetrace.cli.commands.main`, which tests and
notebooks call, leaves the collector as it found it.
"""

from __future__ import annotations

import gc

from .commands import main

__all__ = ["script"]


def script(argv: list[str] | None = None) -> int:
    """Run the command line as the ``skatetrace`` script does; returns the exit code.

    Call it only as a process's last act (``sys.exit(script())``): the objects alive when the
    command ends are never collected afterwards.
    """
    try:
        return main(argv)
    finally:
        gc.freeze()
