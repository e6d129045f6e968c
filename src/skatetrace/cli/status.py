"""Progress on standard error: one line per kind of long work, redrawn in place as it advances.

The command line's view of :mod:`skatetrace.progress`: the long stages of a large drawing (its arc
fit, its verification, the writing of its rows: :class:`LongWork`), the planner's batches of
programs (:func:`planning_progress`) and the sections as they are traced share a
:class:`StatusLine`, each kind keeping its count on a line of its own.
"""

from __future__ import annotations

import sys
import time
from contextlib import nullcontext

from ..tracing.sections import TraceOptions

__all__ = ["StatusLine", "LongWork", "long_fit", "planning_progress"]


class StatusLine:
    """A line of progress on stderr, redrawn in place; progress of another kind starts a line of its own."""

    def __init__(self) -> None:
        self.kind: str | None = None

    def show(self, kind: str, text: str, last: bool) -> None:
        """Show ``text`` as the progress of ``kind``; ``last`` ends its line."""
        if self.kind not in (None, kind):
            print(file=sys.stderr)  # keep the other kind's count where it stopped
        print(f"\r{text}", end="\n" if last else "", file=sys.stderr, flush=True)
        self.kind = None if last else kind


class LongWork:
    """Progress of a long stage (``fitting: 12000/20000 pieces of the drawing``), once it has run for a second.

    A callback for the ``reporting`` blocks of :mod:`skatetrace.progress`'s channels (the arc fit,
    the verification, the writing of ``controls.csv``). Work that ends within a second (nearly
    all) prints nothing; a stage that starts anew waits its own second. The line is redrawn at
    most ten times a second, and at the stage's end.

    Parameters
    ----------
    status : StatusLine
        Where the line is shown.
    text : str
        The line, formatted with ``stage``, ``done`` and ``total``.
    """

    def __init__(self, status: StatusLine, text: str) -> None:
        self.status, self.text, self.started, self.drawn = status, text, None, None

    def __call__(self, stage: str, done: int, total: int) -> None:
        now = time.perf_counter()
        if self.started is None:
            self.started = now
        last = done >= total
        # redrawn at most ten times a second (a zigzag's 2,000 sections are replayed in seconds)
        due = now - self.drawn >= 0.1 if self.drawn is not None else now - self.started >= 1.0
        if due or (last and self.drawn is not None):
            self.status.show(stage, self.text.format(stage=stage, done=done, total=total), last)
            self.drawn = None if last else now
        if last:
            self.started = None


def long_fit(status: StatusLine) -> LongWork:
    """The arc fit's progress: ``fitting: 12000/20000 pieces of the drawing``."""
    return LongWork(status, "{stage}: {done}/{total} pieces of the drawing")


def planning_progress(options: TraceOptions, status: StatusLine):
    """A block within which the planner's programs show on standard error as they are solved (nothing without a reach)."""
    if options.reach is None:
        return nullcontext()
    from ..planning.pool import reporting

    return reporting(lambda stage, done, total: status.show(stage, f"planning: {stage} solved {done}/{total}",
                                                            done == total))
