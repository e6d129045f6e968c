"""Independent programs solved side by side: forked worker processes, or one after another.

The planner's warm start solves every distinct section on its own, and each curve's linked
program is independent of the other curves': on a machine with two cores the two halves of such
a batch take half the time. IPOPT and MUMPS run on one core each, and CasADi's functions hold
Python's lock, so the programs are solved in processes, not threads.

Processes are forked (the children share the parent's imported modules and compiled code, so a
pool costs milliseconds, not the seconds of importing CasADi again); where forking is not safe
(no ``fork`` on the platform, or other threads running in this process, which a fork would
leave holding their locks) the programs are solved one after another, and so is a batch of one.
A worker that dies (a pool that breaks) costs nothing already solved: the programs without an
answer are solved here. Every program is solved by the same code either way, so the answers do
not depend on ``workers``.
"""

from __future__ import annotations

import multiprocessing
import os
import signal
import threading
from concurrent.futures import ProcessPoolExecutor
from concurrent.futures.process import BrokenProcessPool

from .collocation import ProgramSolution, solve_program

__all__ = ["available_workers", "solve_programs", "DEFAULT_MAX_WORKERS"]

#: Processes used when the caller does not say: each holds an IPOPT of up to a few hundred MB, so a
#: many-core machine is not filled with them by default.
DEFAULT_MAX_WORKERS = 8


def available_workers() -> int:
    """The cores this process may run on (its CPU affinity where the platform tells it)."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover - platforms without sched_getaffinity
        return max(1, os.cpu_count() or 1)


def _can_fork() -> bool:
    return "fork" in multiprocessing.get_all_start_methods() and threading.active_count() == 1


def _quiet_on_interrupt() -> None:
    """In a worker: Ctrl-C (which a terminal sends to every process of the run) ends it at once and
    quietly; the parent reports the interrupt."""
    signal.signal(signal.SIGINT, lambda signum, frame: os._exit(130))


def _stop(pool: ProcessPoolExecutor) -> None:
    """Cancel the programs not started and end the workers (an interrupt reached the parent only, say)."""
    pool.shutdown(wait=False, cancel_futures=True)
    for process in list((getattr(pool, "_processes", None) or {}).values()):
        process.terminate()


def _solve(job: tuple) -> ProgramSolution:
    sections, options, guess, meshes = job
    return solve_program(sections, options, guess=guess, meshes=meshes)


def solve_programs(jobs: list[tuple], workers: int | None = None) -> list[ProgramSolution]:
    """:func:`~skatetrace.planning.collocation.solve_program` on every job, in order.

    Parameters
    ----------
    jobs : list of tuple
        ``(sections, options, guess, meshes)`` per program, as :func:`solve_program` takes them.
    workers : int or None
        Processes to solve them in: None uses :func:`available_workers`, at most
        :data:`DEFAULT_MAX_WORKERS`; 1 (or a batch of one) solves them here, one after another.

    Returns
    -------
    list of ProgramSolution
        One per job, in the order of ``jobs``.
    """
    count = min(len(jobs), min(available_workers(), DEFAULT_MAX_WORKERS) if workers is None else int(workers))
    results: list[ProgramSolution | None] = [None] * len(jobs)
    if count > 1 and _can_fork():
        try:
            with ProcessPoolExecutor(max_workers=count, mp_context=multiprocessing.get_context("fork"),
                                     initializer=_quiet_on_interrupt) as pool:
                futures = [pool.submit(_solve, job) for job in jobs]
                try:
                    for i, future in enumerate(futures):
                        try:
                            results[i] = future.result()
                        except BrokenProcessPool:
                            break
                except KeyboardInterrupt:  # Ctrl-C: the workers stop at once and the interrupt goes on
                    _stop(pool)
                    raise
        except BrokenProcessPool:
            pass
    return [r if r is not None else _solve(job) for r, job in zip(results, jobs)]
