"""The planner's independent programs solved side by side (:mod:`skatetrace.processes`).

The planner's warm start solves every distinct section on its own, and each curve's linked
program is independent of the other curves': on a machine with two cores the two halves of such
a batch take half the time. IPOPT and MUMPS run on one core each, and CasADi's functions hold
Python's lock, so the programs are solved in forked processes (:func:`skatetrace.processes.run_jobs`:
where forking is not safe, and for a batch of one, one after another; a worker that dies costs
nothing already solved). Every program is solved by the same code either way, so the answers do
not depend on ``workers``.

Whoever wants to see a long planning run move (the command line) registers a callback with
:func:`reporting`; every batch then tells it, program by program, how far it is.

Whoever wants a plan only if it comes cheaply (the command line's default reach, a plan the user
did not ask for) bounds its work with :func:`spending`: the programs' IPOPT iterations times their
unknowns, counted in the order of the jobs, so that where the budget runs out does not depend on
the machine's speed or on ``workers``.
"""

from __future__ import annotations

import contextlib
import contextvars
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from typing import NamedTuple, TypeVar

from threadpoolctl import threadpool_limits

from ..processes import DEFAULT_MAX_WORKERS, available_workers, can_fork, map_forked, run_jobs, worker_count
from ..progress import Channel
from .collocation import ProgramSolution, iterations_within, solve_program

__all__ = ["available_workers", "solve_programs", "charged_in_order", "reporting", "spending", "BudgetSpent",
           "WorkBudget", "DEFAULT_MAX_WORKERS"]

J = TypeVar("J")
R = TypeVar("R")

# The planner's batches, program by program (see reporting).
_PROGRESS = Channel("planning")
# The budget of the innermost spending block, if any.
_BUDGET: contextvars.ContextVar[WorkBudget | None] = contextvars.ContextVar("plan budget", default=None)


class BudgetSpent(Exception):
    """Raised by :func:`solve_programs` once the programs solved within a :func:`spending` block have spent its budget."""


class _Charge(NamedTuple):
    """A program's work as charged, with what its cap came from: its ``batch`` (a count of the
    batches begun), the batch's ``share`` of the budget and its ``size`` (:func:`solve_programs`)."""

    work: int
    unknowns: int
    batch: int
    share: float
    size: int


@dataclass(slots=True)
class WorkBudget:
    """The IPOPT work a plan may spend (``limit``), and what its programs have spent so far.

    A program's work is its iterations times its unknowns
    (:attr:`~skatetrace.planning.collocation.ProgramSolution.work`): IPOPT's time grows with
    both, some 6 to 12 us a unit on one core of this project's 2-core machine (the time an
    iteration grows with the program's size). ``charges`` lists every program charged, where
    recorded (:func:`charged_in_order`); ``batches`` counts the batches begun.
    """

    limit: int
    spent: int = 0
    programs: int = 0
    charges: list[_Charge] | None = None
    batches: int = 0

    def charge(self, sol: ProgramSolution, share: float = 1.0, size: int = 1) -> None:
        """Count ``sol``'s work (solved in a batch of ``size`` with ``share``); raise :class:`BudgetSpent` once
        the total is over the limit."""
        if self.charges is not None:
            self.charges.append(_Charge(sol.work, sol.unknowns, self.batches, share, size))
        self.add(sol.work)

    def add(self, work: int) -> None:
        """Count a program of ``work``; raise :class:`BudgetSpent` once the total is over the limit."""
        self.spent += work
        self.programs += 1
        if self.spent > self.limit:
            raise BudgetSpent(f"the planning budget of {self.limit:,} (IPOPT iterations x unknowns) was spent after "
                              f"{self.programs} program{'' if self.programs == 1 else 's'} ({self.spent:,})")

    def cap(self, share: float = 1.0, size: int = 1) -> int:
        """The work each program of a batch of ``size`` with ``share`` may do from here (:func:`solve_programs`)."""
        left = self.limit - self.spent
        return int(share * left) // max(size, 1) if share < 1.0 else left


@contextlib.contextmanager
def spending(limit: int | None) -> Iterator[WorkBudget | None]:
    """Within the ``with`` block, :func:`solve_programs` counts every program's work against ``limit``.

    Once the total passes it, the batch stops (the jobs not yet solved are dropped, their workers
    ended) and :class:`BudgetSpent` is raised. The work is added in the order of the jobs, so the
    same programs are solved before the budget runs out on any machine and with any ``workers``.
    ``limit`` None counts nothing (yields None). Per thread and per task, like :func:`reporting`.

    Raises
    ------
    ValueError
        If ``limit`` is not a whole number >= 0 or None.
    """
    if limit is not None and (isinstance(limit, bool) or not isinstance(limit, int) or limit < 0):
        raise ValueError(f"a planning budget must be a whole number >= 0 or None, got {limit!r}")
    budget = None if limit is None else WorkBudget(limit)
    token = _BUDGET.set(budget)
    try:
        yield budget
    finally:
        _BUDGET.reset(token)


def reporting(report: Callable[[str, int, int], None]) -> contextlib.AbstractContextManager[None]:
    """Within the ``with`` block, call ``report(stage, done, total)`` after each program a batch solves.

    ``stage`` names the batch (``"warm starts"``, ``"warm starts with free ends"``, ``"warm starts
    pinned again"``, ``"linked programs"``, ``"programs again"``),
    ``done`` of its ``total`` programs are solved. The registration is per thread and per task (a
    context variable); an inner block replaces an outer one (:class:`skatetrace.progress.Channel`).
    """
    return _PROGRESS.listening(report)


def _solve(job: tuple) -> ProgramSolution:
    sections, options, guess, meshes, max_work = job
    return solve_program(sections, options, guess=guess, meshes=meshes, max_work=max_work)


def solve_programs(jobs: list[tuple], workers: int | None = None, stage: str = "programs",
                   share: float = 1.0) -> list[ProgramSolution]:
    """:func:`~skatetrace.planning.collocation.solve_program` on every job, in order.

    Parameters
    ----------
    jobs : list of tuple
        ``(sections, options, guess, meshes)`` per program, as :func:`solve_program` takes them.
    workers : int or None
        Processes to solve them in: None uses :func:`available_workers`, at most
        :data:`DEFAULT_MAX_WORKERS`; 1 (or a batch of one) solves them here, one after another.
    stage : str
        What the batch is, for the callback of :func:`reporting`.
    share : float
        Within a :func:`spending` block, the share of what is left of its budget that the batch
        may spend, split evenly between its programs: each stops (IPOPT's
        ``Maximum_Iterations_Exceeded``) after its part, and the rest is kept for what follows
        (1: every program may spend all that is left, and the budget is spent where they do).

    Returns
    -------
    list of ProgramSolution
        One per job, in the order of ``jobs``.

    Raises
    ------
    BudgetSpent
        Within a :func:`spending` block, once the programs have spent its budget.
    ValueError
        If ``share`` is not in (0, 1].
    """
    if not 0.0 < share <= 1.0:  # also refuses NaN
        raise ValueError(f"a batch's share of the planning budget must be in (0, 1], got {share!r}")
    budget = _BUDGET.get()
    if budget is not None and budget.spent > budget.limit:
        raise BudgetSpent(f"the planning budget of {budget.limit:,} was spent before this batch")
    # each program stops where it alone would spend what is left (past it the budget is spent
    # anyway), or its part of the batch's share of it
    left = None if budget is None else budget.cap(share, len(jobs))
    if budget is not None:
        budget.batches += 1
    out = []
    solved = run_jobs(_solve, [(*job, left) for job in jobs], workers)
    try:
        for sol in solved:
            out.append(sol)
            _PROGRESS.report(stage, len(out), len(jobs))
            if budget is not None:
                budget.charge(sol, share, len(jobs))
    finally:
        solved.close()  # where the budget ran out: the jobs not started are dropped, the workers ended
    return out


def charged_in_order(fn: Callable[[J], R], items: Sequence[J],
                     workers: int | None = None) -> tuple[list[R], str | None]:
    """``fn`` on every item side by side, the programs it solves charged to the budget as one after another.

    Each ``fn(item)`` may solve programs (:func:`solve_programs`) within the :func:`spending`
    block around the call. The items run in forked processes (:func:`~skatetrace.processes.map_forked`),
    each from the budget as it stands now, and their programs are then charged in the order of
    the items, each at the work it would have done had the items before it spent theirs first:
    where its batch's cap (:meth:`WorkBudget.cap`) would have stopped it sooner, at that cap, and
    the budget is then spent where it would have been. A program's iterations do not depend on a
    cap that does not stop it, so the items kept are the same, to the bit, as one after another.
    Where a program that its batch's share of the budget would have stopped (leaving the budget
    unspent, :func:`solve_programs`) ran on, that item and those after it are run again here, one
    after another.

    Returns
    -------
    results, spent : list, str or None
        The results of the items before the one in which the budget runs out (all, without a
        budget or where it does not), and why it ran out (:class:`BudgetSpent`'s message) or None.
        With one worker, one item, or where forking is not safe, the items run here one after
        another, and none after the one in which the budget runs out.

    Notes
    -----
    numpy's and scipy's BLAS run on one thread meanwhile, side by side or not (the answers then
    do not depend on the cores either): each starts a thread per core, which wait spinning, and
    two processes with two each on two cores made svgpathtools-groups' exact finishes ten times
    slower (5 s -> 52 s in all).
    """
    with threadpool_limits(1, user_api="blas"):
        return _charged_in_order(fn, items, workers)


def _charged_in_order(fn: Callable[[J], R], items: Sequence[J], workers: int | None) -> tuple[list[R], str | None]:
    budget = _BUDGET.get()
    if budget is None:
        return map_forked(fn, items, workers), None
    if worker_count(len(items), workers) <= 1 or not can_fork():
        return _one_after_another(fn, items, [])
    start = (budget.limit, budget.spent, budget.programs)

    def recorded(item):
        own = WorkBudget(*start, charges=[])
        token = _BUDGET.set(own)
        try:
            return fn(item), own.charges, None
        except BudgetSpent as exc:
            return None, own.charges, str(exc)
        finally:
            _BUDGET.reset(token)

    out: list[R] = []
    for k, (result, charges, ran_out) in enumerate(map_forked(recorded, items, workers)):
        batch, cap, before = None, 0, (budget.spent, budget.programs)
        try:
            for c in charges:
                if c.batch != batch:
                    batch, cap = c.batch, budget.cap(c.share, c.size)
                # stopped at the cap, a program has done the iterations solve_program allows on it
                capped = iterations_within(cap, c.unknowns) * c.unknowns if c.unknowns else c.work
                if c.work > capped and c.share < 1.0:
                    # stopped by a share of the budget, the program would have been left unsolved
                    # with the budget not spent, and the item gone on from there: solved again here
                    budget.spent, budget.programs = before
                    return _one_after_another(fn, items[k:], out)
                budget.add(min(c.work, capped))
        except BudgetSpent as exc:
            return out, str(exc)
        if ran_out is not None:  # raised by the item itself, not by its programs' work
            return out, ran_out
        out.append(result)
    return out, None


def _one_after_another(fn: Callable[[J], R], items: Sequence[J], out: list[R]) -> tuple[list[R], str | None]:
    """``out`` and ``fn`` on each item in turn, charged to the budget as they go, up to the one that spends it."""
    for item in items:
        try:
            out.append(fn(item))
        except BudgetSpent as exc:
            return out, str(exc)
    return out, None
