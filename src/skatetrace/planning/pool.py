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
"""

from __future__ import annotations

import contextlib
from collections.abc import Callable

from ..processes import DEFAULT_MAX_WORKERS, available_workers, run_jobs
from ..progress import Channel
from .collocation import ProgramSolution, solve_program

__all__ = ["available_workers", "solve_programs", "reporting", "DEFAULT_MAX_WORKERS"]

# The planner's batches, program by program (see reporting).
_PROGRESS = Channel("planning")


def reporting(report: Callable[[str, int, int], None]) -> contextlib.AbstractContextManager[None]:
    """Within the ``with`` block, call ``report(stage, done, total)`` after each program a batch solves.

    ``stage`` names the batch (``"warm starts"``, ``"warm starts with free ends"``, ``"warm starts
    pinned again"``, ``"linked programs"``, ``"programs again"``),
    ``done`` of its ``total`` programs are solved. The registration is per thread and per task (a
    context variable); an inner block replaces an outer one (:class:`skatetrace.progress.Channel`).
    """
    return _PROGRESS.listening(report)


def _solve(job: tuple) -> ProgramSolution:
    sections, options, guess, meshes = job
    return solve_program(sections, options, guess=guess, meshes=meshes)


def solve_programs(jobs: list[tuple], workers: int | None = None, stage: str = "programs") -> list[ProgramSolution]:
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

    Returns
    -------
    list of ProgramSolution
        One per job, in the order of ``jobs``.
    """
    out = []
    for sol in run_jobs(_solve, jobs, workers):
        out.append(sol)
        _PROGRESS.report(stage, len(out), len(jobs))
    return out
