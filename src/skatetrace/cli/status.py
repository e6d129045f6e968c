"""Progress on standard error: one line per kind of long work, redrawn in place as it advances.

The command line's view of :mod:`skatetrace.progress`: the arc fit of a large drawing
(:class:`LongFit`), the planner's batches of programs (:func:`planning_progress`) and the
sections as they are traced share a :class:`StatusLine`, each kind keeping its count on a line of
its own.
"""

from __future__ import annotations

import sys
import time
from contextlib import nullcontext

from ..tracing.sections import TraceOptions

__all__ = ["StatusLine", "LongFit", "planning_progress"]


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


class LongFit:
    """The arc fit's progress (``fitting: 12000/20000 pieces of the drawing``), once a fit has run for a second.

    A callback for :func:`skatetrace.drawings.fitting.reporting`. A drawing of a few hundred
    pieces fits in well under a second: it prints nothing.
    """

    def __init__(self, status: StatusLine) -> None:
        self.status, self.started, self.shown = status, None, False

    def __call__(self, stage: str, done: int, total: int) -> None:
        now = time.perf_counter()
        if self.started is None:
            self.started = now
        last = done >= total
        if self.shown or now - self.started >= 1.0:
            self.status.show(stage, f"{stage}: {done}/{total} pieces of the drawing", last)
            self.shown = not last
        if last:
            self.started = None


def planning_progress(options: TraceOptions, status: StatusLine):
    """A block within which the planner's programs show on standard error as they are solved (nothing without a reach)."""
    if options.reach is None:
        return nullcontext()
    from ..planning.pool import reporting

    return reporting(lambda stage, done, total: status.show(stage, f"planning: {stage} solved {done}/{total}",
                                                            done == total))
