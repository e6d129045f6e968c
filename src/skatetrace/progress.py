"""Progress of long work told to whoever listens: a callback registered for a block of code, per thread and task.

Long stages (the arc fit of a drawing of thousands of segments, the planner's programs) report
``(stage, done, total)`` through a :class:`Channel`; a caller that wants to see them move (the
command line's status line, a notebook's progress bar) registers a callback with
:meth:`Channel.listening` around the call. Nothing is printed here, and a stage reports at no cost
when no one listens.
"""

from __future__ import annotations

import contextlib
import contextvars
from collections.abc import Callable, Iterator

__all__ = ["Channel"]


class Channel:
    """One kind of progress: the callback of the innermost :meth:`listening` block, or none.

    Parameters
    ----------
    name : str
        What is reported (for debugging: the context variable's name).

    Examples
    --------
    >>> fitting = Channel("fitting")
    >>> seen = []
    >>> with fitting.listening(lambda stage, done, total: seen.append((stage, done, total))):
    ...     fitting.report("fitting", 1, 2)
    >>> fitting.report("fitting", 2, 2)  # outside the block: nobody listens
    >>> seen
    [('fitting', 1, 2)]
    """

    def __init__(self, name: str) -> None:
        self._callback: contextvars.ContextVar[Callable[[str, int, int], None] | None] = contextvars.ContextVar(
            name, default=None)

    @contextlib.contextmanager
    def listening(self, callback: Callable[[str, int, int], None]) -> Iterator[None]:
        """Within the ``with`` block, call ``callback(stage, done, total)`` for every report.

        The registration is per thread and per task (a context variable); an inner block replaces
        an outer one until it ends.
        """
        token = self._callback.set(callback)
        try:
            yield
        finally:
            self._callback.reset(token)

    def report(self, stage: str, done: int, total: int) -> None:
        """Tell the registered callback (if any) that ``done`` of ``total`` steps of ``stage`` are done."""
        callback = self._callback.get()
        if callback is not None:
            callback(stage, done, total)
