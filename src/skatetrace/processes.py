"""Independent jobs side by side: forked worker processes, or one after another.

The planner's programs (each distinct section's warm start, each curve's linked program), the
tracer's distinct sections and the five plots are independent of one another: on a machine with two
cores the two halves of such a batch take half the time. IPOPT and MUMPS run on one core each,
CasADi's functions hold Python's lock, and the tracer's manoeuvres are many short compiled
integrations called from Python, so the jobs run in processes, not threads.

Processes are forked (the children share the parent's imported modules and compiled code, so a
pool costs milliseconds, not the seconds of importing CasADi or loading numba's cache again);
where forking is not safe (no ``fork`` on the platform, or other threads running in this process,
which a fork would leave holding their locks) the jobs run one after another, and so does a batch
of one. A worker that dies (a pool that breaks) costs nothing already done: the jobs without an
answer are run here. Every job runs the same code either way, so the answers do not depend on
``workers``.
"""

from __future__ import annotations

import contextlib
import functools
import itertools
import math
import multiprocessing
import os
import pickle
import signal
import threading
import time
from concurrent.futures import ProcessPoolExecutor
from concurrent.futures.process import BrokenProcessPool
from typing import Callable, Generic, Iterable, Iterator, Sequence, TypeVar

__all__ = ["DEFAULT_MAX_WORKERS", "IDLE_NICENESS", "Background", "Primed", "available_workers", "can_fork",
           "evaluated_ahead", "map_forked", "quiet_on_interrupt", "recording_interrupts", "run_jobs", "worker_count"]

#: Processes used when the caller does not say: each planner worker holds an IPOPT of up to a few
#: hundred MB, so a many-core machine is not filled with them by default.
DEFAULT_MAX_WORKERS = 8

J = TypeVar("J")
R = TypeVar("R")


def available_workers() -> int:
    """The cores this process may run on (its CPU affinity where the platform tells it)."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover - platforms without sched_getaffinity
        return max(1, os.cpu_count() or 1)


def worker_count(jobs: int, workers: int | None) -> int:
    """Processes for ``jobs`` jobs: ``workers``, or with None :func:`available_workers` up to
    :data:`DEFAULT_MAX_WORKERS`; never more than there are jobs."""
    return min(jobs, min(available_workers(), DEFAULT_MAX_WORKERS) if workers is None else int(workers))


def can_fork() -> bool:
    """Whether this process may fork: the platform has ``fork``, no other thread runs (a fork
    copies only the calling thread, and would leave another's locks held in the child), and this
    is not itself a child of :func:`map_forked` (a daemonic process may not have children)."""
    return ("fork" in multiprocessing.get_all_start_methods() and threading.active_count() == 1
            and not multiprocessing.current_process().daemon)


def quiet_on_interrupt() -> None:
    """In a worker: Ctrl-C (which a terminal sends to every process of the run) ends it at once and
    quietly; the parent reports the interrupt."""
    signal.signal(signal.SIGINT, lambda signum, frame: os._exit(130))


@contextlib.contextmanager
def recording_interrupts():
    """Record a SIGINT (Ctrl-C) that arrives while the block runs (the list yielded gets an item), and
    raise KeyboardInterrupt as Python does. Only in the main thread, where Python handles signals.

    For code that calls into libraries which catch the interrupt themselves (CasADi turns it into
    a failed solve or a ``RuntimeError``): after the block, a non-empty list means the user asked
    to stop, whatever the library made of it.
    """
    caught: list[bool] = []
    previous = signal.getsignal(signal.SIGINT)
    if threading.current_thread() is not threading.main_thread() or not callable(previous):
        yield caught
        return

    def handler(signum, frame):
        caught.append(True)
        previous(signum, frame)

    signal.signal(signal.SIGINT, handler)
    try:
        yield caught
    finally:
        signal.signal(signal.SIGINT, previous)


def _stop(pool: ProcessPoolExecutor) -> None:
    """Cancel the jobs not started and end the workers (an interrupt reached the parent only, say).

    The workers are taken before the shutdown, which forgets them: a worker left at its job would
    hold the interpreter's exit until the job ends (a dropped planning program: seconds).
    """
    processes = list((getattr(pool, "_processes", None) or {}).values())
    pool.shutdown(wait=False, cancel_futures=True)
    for process in processes:
        process.terminate()


def _each(fn: Callable[[J], R], batch: Sequence[J]) -> list[R]:
    """``fn`` on every job of a batch, in a worker of :func:`run_jobs`."""
    return [fn(job) for job in batch]


def run_jobs(fn: Callable[[J], R], jobs: Sequence[J], workers: int | None = None, chunk: int = 1) -> Iterator[R]:
    """``fn(job)`` for every job, yielded in the order of ``jobs`` as each becomes known.

    Parameters
    ----------
    fn : callable
        A module-level function (the workers are forked, but its results come back pickled).
    jobs : sequence
        The arguments, one per call; they and the results must pickle.
    workers : int or None
        Processes to run them in (:func:`worker_count`); 1, or a batch of one, runs them here, one
        after another.
    chunk : int
        Jobs handed to a worker at a time, their results sent back together: for many jobs of a
        few milliseconds, where handing each over on its own costs about as much as the job.

    Yields
    ------
    The results, in order. A job whose worker died is run here. Ctrl-C stops the workers at once
    and raises :class:`KeyboardInterrupt` here.
    """
    count = worker_count(len(jobs), workers)
    done = 0
    if count > 1 and can_fork():
        try:
            with ProcessPoolExecutor(max_workers=count, mp_context=multiprocessing.get_context("fork"),
                                     initializer=quiet_on_interrupt) as pool:
                size = max(1, int(chunk))
                futures = [pool.submit(_each, fn, jobs[k:k + size]) for k in range(0, len(jobs), size)]
                try:
                    for future in futures:
                        try:
                            results = future.result()
                        except BrokenProcessPool:
                            break
                        for result in results:
                            done += 1
                            yield result
                except (KeyboardInterrupt, GeneratorExit):  # Ctrl-C, or the caller stopped asking
                    _stop(pool)
                    raise
        except BrokenProcessPool:
            pass
    for job in jobs[done:]:
        yield fn(job)


#: The niceness of a child that works only on what the machine leaves idle (:class:`Background`):
#: the lowest priority, a share of about 1.5 % of a core that other work wants.
IDLE_NICENESS = 19


def _forked_part(fn: Callable, items: list, conn, niceness: int = 0) -> None:
    """In a forked child: ``fn`` on its share of the items, the results sent back (None on any failure).

    ``niceness`` is added to the child's (:func:`os.nice`) before it starts, where the platform can.
    """
    _child_set_up(niceness)
    _send_answers(conn, lambda: [fn(item) for item in items])


def _child_set_up(niceness: int) -> None:
    """In a forked child, first: quiet on Ctrl-C (:func:`quiet_on_interrupt`), and ``niceness`` added to its
    own (:func:`os.nice`) where it is not 0 and the platform allows."""
    quiet_on_interrupt()
    if niceness:
        with contextlib.suppress(AttributeError, OSError):  # no os.nice (Windows), or not allowed
            os.nice(niceness)


def _send_answers(conn, compute: Callable[[], list]) -> None:
    """In a forked child: ``compute()`` sent back through ``conn`` (None on any failure), and ``conn`` closed."""
    try:
        results = compute()
    except BaseException:  # the parent runs this share again, and reports the error there
        results = None
    try:
        conn.send(results)
    finally:
        conn.close()


def map_forked(fn: Callable[[J], R], items: Sequence[J], workers: int | None = None) -> list[R]:
    """``[fn(item) for item in items]``, the items shared out between this process and forked children.

    Unlike :func:`run_jobs`, nothing is pickled on the way in: the children are forks of this
    process and inherit ``fn`` (a closure will do) and everything it reads; only the results come
    back pickled. Item ``i`` goes to process ``i % count`` (this one is process 0). A child that fails
    or dies has its share run here (so an error is raised here, as without children); where forking
    is not safe, with ``workers=1`` or a single item, everything runs here.
    """
    count = worker_count(len(items), workers)
    if count <= 1 or not can_fork():
        return [fn(item) for item in items]
    children = []
    try:
        for k in range(1, count):
            children.append((k, _Child(fn, list(items[k::count]))))
        results: list = [None] * len(items)
        results[0::count] = [fn(item) for item in items[0::count]]
        for k, child in children:
            part = child.answer()
            results[k::count] = part if part is not None else [fn(item) for item in items[k::count]]
        return results
    finally:
        for _, child in children:
            child.end()  # an interrupt here (or an error) while the child still draws


class _Child:
    """A forked child computing ``[fn(item) for item in items]`` (:func:`_forked_part`), its answer piped back."""

    def __init__(self, fn: Callable, items: list, niceness: int = 0):
        context = multiprocessing.get_context("fork")
        self._receive, send = context.Pipe(duplex=False)
        self._process = context.Process(target=_forked_part, args=(fn, items, send, niceness), daemon=True)
        self._process.start()
        send.close()

    def answer(self) -> list | None:
        """The child's results, waited for; None where it failed or died before it could answer."""
        try:
            part = self._receive.recv()
        except EOFError:
            part = None
        self._process.join()
        return part if self._process.exitcode == 0 else None

    def end(self) -> None:
        """Close the pipe, and end the child if it is still at work."""
        self._receive.close()
        if self._process.is_alive():
            self._process.terminate()
            self._process.join()

    def wait(self, seconds: float = 0.0) -> bool:
        """Whether the child answers, or ends without an answer, within ``seconds`` (at once by default):
        then :meth:`answer` will not wait."""
        return self._receive.poll(seconds)

    def cpu_seconds(self) -> float | None:
        """The processor time the child has used so far (Linux's ``/proc``), or None where it cannot be read."""
        return _cpu_seconds(self._process.pid)


def _cpu_seconds(pid: int) -> float | None:
    """The processor time process ``pid`` has used so far (Linux's ``/proc``), or None where it cannot be read."""
    try:
        with open(f"/proc/{pid}/stat", "rb") as f:
            fields = f.read().rsplit(b")", 1)[1].split()
        return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")
    except (OSError, ValueError, IndexError):
        return None


def _while_running(ready: Callable[[float], bool], cpu: Callable[[], float | None], share: float,
                   window: float) -> bool:
    """Whether ``ready(window)`` comes true while a child runs on at least ``share`` of a core.

    Its processor time ``cpu()`` is read every ``window`` seconds; False as soon as it used less
    (other work on the machine starves it), or where its processor time cannot be read (not Linux).
    """
    used = cpu()
    while used is not None:
        if ready(window):
            return True
        now = cpu()
        if now is None or now - used < share * window:
            return False
        used = now
    return False


def _primed_part(prime: Callable[[], object], conn) -> None:
    """In a forked child of :class:`Primed`, at idle priority: ``prime()``, then one batch from ``conn``
    (``fn`` and ``shared`` pickled together, then its items), answered with ``[fn(shared, item) ...]``
    (None on any failure)."""
    _child_set_up(IDLE_NICENESS)
    with contextlib.suppress(Exception):  # a failed preparation only costs the batch its head start
        prime()
    try:
        fn, shared = pickle.loads(conn.recv_bytes())  # pickled once for every child
        items = conn.recv()
    except (EOFError, OSError):  # never given a batch: the parent went on without it
        return
    _send_answers(conn, lambda: [fn(shared, item) for item in items])


class Primed(Generic[R]):
    """Forked children started before their work is known, each made ready by ``prime()`` meanwhile.

    For work that needs a slow preparation (an import of some tenths of a second) and whose inputs
    come late: the command line's plots need matplotlib, imported in the children while the figure
    is traced, and the trace, known only at the end. The children work at the lowest priority
    (:data:`IDLE_NICENESS`), on what the machine leaves idle, so that their preparation does not
    slow the work it waits for (a planner busy on every core). :meth:`submit` hands them one
    batch, ``fn(shared, item)`` for every item (``fn``, ``shared`` and the items pickled on the way
    in, the results on the way out), and returns; this process goes on with other work;
    :meth:`results` collects the answers in order. Where there are no children (``workers=1``,
    forking not safe, the batch would not pickle) the batch is computed by :func:`map_forked`;
    where a child fails, dies or is starved by other work, its share is computed here, so an
    error is raised here, as without children. Use it as a context manager: leaving the block
    ends the children still waiting or at work.
    """

    def __init__(self, prime: Callable[[], object], children: int = 2, workers: int | None = None):
        count = worker_count(children, workers)
        self._workers = workers
        self._children: list = []
        self._batch: tuple | None = None
        if count > 1 and can_fork():
            context = multiprocessing.get_context("fork")
            for _ in range(count):
                here, there = context.Pipe(duplex=True)
                process = context.Process(target=_primed_part, args=(prime, there), daemon=True)
                process.start()
                there.close()
                self._children.append((process, here))

    @property
    def children(self) -> int:
        """How many children wait for the batch (0: :meth:`results` computes it here)."""
        return len(self._children)

    def submit(self, fn: Callable[[object, J], R], shared: object, items: Iterable[J]) -> None:
        """Hand the children ``fn(shared, item)`` for every item, shared out in turn; returns at once
        unless a child is still being primed (a pickled batch larger than a pipe holds waits for it)."""
        if self._batch is not None:
            raise RuntimeError("a Primed takes one batch; this one has been given its batch already")
        items = list(items)
        self._batch = (fn, shared, items)
        n = len(self._children)
        try:
            payload = pickle.dumps((fn, shared), protocol=pickle.HIGHEST_PROTOCOL)
            for k, (_process, conn) in enumerate(self._children):
                conn.send_bytes(payload)
                conn.send(items[k::n])
        except (pickle.PicklingError, TypeError, AttributeError, OSError, ValueError):
            # the batch does not pickle, or a child is gone: :meth:`results` computes it all here
            self._end()

    def results(self, share: float = 0.5, window: float = 0.25) -> list[R]:
        """``[fn(shared, item) for item in items]`` of the batch, in order, waited for.

        A child is waited for while it runs on at least ``share`` of a core, its processor time read
        every ``window`` seconds (as :meth:`Background.awaited`); one that other work on the machine
        starves (it works at idle priority) is ended, and its share computed here.
        """
        if self._batch is None:
            raise RuntimeError("no batch was submitted to this Primed")
        fn, shared, items = self._batch
        n = len(self._children)
        if n == 0:
            return map_forked(functools.partial(fn, shared), items, self._workers)
        out: list = [None] * len(items)
        try:
            for k, (process, conn) in enumerate(self._children):
                part = None
                # an answer already sent is taken whatever the child's processor time says
                cpu = functools.partial(_cpu_seconds, process.pid)
                if conn.poll() or _while_running(conn.poll, cpu, share, window):
                    with contextlib.suppress(EOFError, OSError):
                        part = conn.recv()
                if part is not None:
                    process.join()
                out[k::n] = part if part is not None and process.exitcode == 0 else [fn(shared, item)
                                                                                   for item in items[k::n]]
        finally:
            self._end()
        return out

    def _end(self) -> None:
        children, self._children = self._children, []
        for process, conn in children:
            conn.close()
            if process.is_alive():
                process.terminate()
                process.join()

    def __enter__(self) -> "Primed[R]":
        return self

    def __exit__(self, *exc) -> None:
        self._end()


def _called(fn: Callable[[], R]) -> R:
    return fn()


class Background(Generic[R]):
    """``fn()`` computed in a forked child while this process goes on with other work.

    Use it as a context manager; :meth:`result` waits for the answer (it comes back pickled).
    With ``workers=1`` (one process asked for), where forking is not safe (:func:`can_fork`), or
    where the child fails or dies, :meth:`result` calls ``fn()`` here instead, so an error is
    raised here, as without a child. Leaving the ``with`` block (an error, an interrupt) ends a
    child still at work.

    For work whose inputs are known early and whose answer is wanted late, beside work that
    leaves a core idle part of the time: the command line draws fit.png while the figure is traced.
    With ``idle=True`` the child runs at the lowest priority (:data:`IDLE_NICENESS`), on what
    the machine leaves idle, for work that may not be wanted at all: the default reach's
    launch-glide-stop trace, kept only where the plan is given up, is made while the planner
    leaves a core idle. Ask :meth:`ready` before :meth:`result`: such a child, behind other work,
    may be far from done.
    """

    def __init__(self, fn: Callable[[], R], workers: int | None = None, *, idle: bool = False):
        self._fn = fn
        self._child = (_Child(_called, [fn], IDLE_NICENESS if idle else 0)
                       if worker_count(2, workers) > 1 and can_fork() else None)

    def ready(self) -> bool:
        """Whether the child has answered (or ended without an answer), so that :meth:`result` will not
        wait for it; False where there is no child (:meth:`result` would compute ``fn()`` here)."""
        return self._child is not None and self._child.wait()

    def cancel(self) -> None:
        """End the child, if it is still at work; :meth:`result` then computes ``fn()`` here."""
        child, self._child = self._child, None
        if child is not None:
            child.end()

    def awaited(self, share: float = 0.5, window: float = 0.25) -> tuple[R] | None:
        """``(fn(),)`` from the child, waited for as long as it runs on at least ``share`` of a core; else None.

        For an ``idle`` child whose answer is now wanted: with this process waiting, it has a core
        to itself unless other work on the machine takes it, and it has a head start over ``fn()``
        made afresh here. Every ``window`` seconds its processor time is read: a child that used
        less than ``share`` of the window (the machine busy with other work, which its lowest
        priority yields to) is ended, and None returned, as where there is no child, it failed, or
        its processor time cannot be read (not Linux): the caller then computes ``fn()`` itself.
        """
        child = self._child
        if child is None:
            return None
        if _while_running(child.wait, child.cpu_seconds, share, window):
            part = self._taken()
            return None if part is None else (part[0],)
        self.cancel()
        return None

    def result(self) -> R:
        """``fn()``: the child's answer, else computed here."""
        part = self._taken()
        return part[0] if part is not None else self._fn()

    def _taken(self) -> list | None:
        """The child's answer, waited for, the child ended and let go; None where there is none."""
        child, self._child = self._child, None
        if child is None:
            return None
        try:
            return child.answer()
        finally:
            child.end()

    def __enter__(self) -> "Background[R]":
        return self

    def __exit__(self, *exc) -> None:
        self.cancel()


def evaluated_ahead(fn: Callable[[J], R], items: Iterable[J], wanted: Callable[[J], bool], *,
                    alone_for: float = 0.2, batch: int = 8, round_for: float = 0.25,
                    workers: int | None = None) -> Iterator[tuple[J, R | None]]:
    """``(item, fn(item))`` for each item in order, lazily: a search that stops at its answer, sped up when it runs long.

    ``fn`` is called only on the items ``wanted`` accepts (the others are yielded with None).
    Items are evaluated here, one at a time as the caller asks for them, for ``alone_for``
    seconds; after that, in rounds of up to ``batch`` per process (:func:`worker_count`), shared
    out by :func:`map_forked` among this process and forked children. A round is sized to take
    about ``round_for`` seconds at the time an item has taken so far (at least one item a
    process): ``wanted`` is asked when a round is made, so the longer the round, the more items
    it evaluates that the search, had it gone on one at a time, would have turned away (a search
    for the best of a few placements of 0.2 s each, batches of 8 a process gained nothing on two
    cores); the shorter, the more often it forks. A round may evaluate items the caller never
    asks for (it stopped in the middle): that costs time, never a different answer, since every
    item is evaluated by ``fn`` alike either way. ``wanted`` must only ever turn more items away
    as the search goes on. Only the main process forks: in a worker of a pool (which has a
    sibling per core) everything runs here.
    """
    items = iter(items)
    started = time.perf_counter()
    evaluated = 0
    for item in items:
        want = wanted(item)
        yield item, (fn(item) if want else None)
        evaluated += want
        if time.perf_counter() - started > alone_for:
            break
    else:
        return
    count = worker_count(DEFAULT_MAX_WORKERS, workers)
    forks = count > 1 and multiprocessing.parent_process() is None
    per_item = (time.perf_counter() - started) / max(evaluated, 1)  # seconds an item, as measured so far
    while True:
        size = max(1, min(batch, int(round_for / per_item) if per_item > 0 else batch))
        chunk = list(itertools.islice(items, size * count if forks else 1))
        if not chunk:
            return
        keep = [wanted(item) for item in chunk]
        todo = [item for item, k in zip(chunk, keep) if k]
        began = time.perf_counter()
        results = iter(map_forked(fn, todo, count) if forks else [fn(item) for item in todo])
        if todo:  # the items shared out between the processes ran side by side
            per_item = (time.perf_counter() - began) / math.ceil(len(todo) / count if forks else len(todo))
        for item, k in zip(chunk, keep):
            yield item, (next(results) if k else None)
