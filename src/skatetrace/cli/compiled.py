"""The compiled numerical core: is numba's on-disk cache of it ready, and compiling it ahead of a run.

The integrators (:mod:`skatetrace.dynamics.integrator`, :mod:`skatetrace.dynamics.replayer`, :mod:`skatetrace.dynamics.dop853`),
a manoeuvre leg's motion (:mod:`skatetrace.tracing.leg_motion`), the closed-loop replay
(:mod:`skatetrace.feedback.law_replay`) and the tracking law's Riccati equation
(:mod:`skatetrace.feedback.riccati`), the distance checks of :mod:`skatetrace.verification.distances`,
the spirals' geometry (:mod:`skatetrace.figures.spiral_paths`) and the planner's exact finish
(:mod:`skatetrace.planning.shooting`) are compiled by numba with ``cache=True``: the first run on a
machine compiles them (10-30 s, depending on the machine) and writes the machine code to numba's
cache (the ``__pycache__`` folders beside the sources, or, where those cannot be written, numba's
folder in the user's cache directory, or ``NUMBA_CACHE_DIR``); every later run loads it in a
fraction of a second.
The cache is keyed by the source file's time stamp and size, the function's bytecode and the CPU, so
it is rebuilt after an upgrade or on another machine, never reused wrongly.

:func:`cache_is_warm` says whether a run would load rather than compile; :func:`reporting` names
each part as a run compiles it, so that the command line can say what is happening while it
compiles only what that run needs (a launch-glide-stop trace never compiles the closed-loop replay,
the law's Riccati equation or the planner's finish: 13 s instead of 28 s on a first double flower); :func:`warm_up` compiles
(or loads) every part by tracing and verifying a small figure, so that an installer (a container
build, a ``postinstall`` step) can pay that once, ahead of any real work. :func:`compile_ahead`
compiles the verification's parts in a forked process while the run traces (and compiles the
integrator): on two cores a first double flower then takes the integrator's time, not the sum.
:func:`compile_later` compiles the parts such a run does not need (the planner's finish, the
closed loop and its law, the spirals) in a job at the lowest priority that outlives the run, so
that the next command finds them compiled. Processes that compile at once save into numba's cache
one at a time (:mod:`skatetrace.dynamics.numba_cache`). :func:`first_run` puts these together for a
command: what it compiles, and where, told line by line.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from importlib import import_module

__all__ = ["AHEAD", "ENTRY_POINTS", "LATER", "cache_is_warm", "compile_ahead", "compile_later", "first_run",
           "later_job_end", "reporting", "warm_up"]

#: The compiled functions called from Python, by part: compiling them compiles everything they call.
ENTRY_POINTS: tuple[tuple[str, tuple[tuple[str, str], ...]], ...] = (
    ("the manoeuvre integrator", (("skatetrace.dynamics.integrator", "_run"),
                                  ("skatetrace.dynamics.integrator", "_evaluate_steps"),
                                  ("skatetrace.tracing.leg_motion", "_motion"))),
    ("the verifying replay", (("skatetrace.dynamics.replayer", "_run"),)),
    ("the closed-loop replay", (("skatetrace.feedback.law_replay", "_run"),)),
    ("the tracking law's Riccati equation", (("skatetrace.feedback.riccati", "_run"),)),
    ("the distance checks", (("skatetrace.verification.distances", "_golden_distances"),
                             ("skatetrace.verification.distances", "_hermite_distance"))),
    ("the spirals' geometry", (("skatetrace.figures.spiral_paths", "cell_nodes"),
                               ("skatetrace.figures.spiral_paths", "positions"),
                               ("skatetrace.figures.spiral_paths", "foot_points"))),
    ("the planner's exact finish", (("skatetrace.planning.shooting", "legs_from"),
                                    ("skatetrace.planning.shooting", "segment_ends"),
                                    ("skatetrace.planning.shooting", "jacobian_columns"))),
)


def _dispatchers():
    for part, entries in ENTRY_POINTS:
        for module, name in entries:
            yield part, getattr(import_module(module), name)


def _is_cached(dispatcher) -> bool:
    """Whether numba's cache holds machine code of ``dispatcher`` for this source, bytecode and CPU."""
    if dispatcher.signatures:  # compiled (or loaded) in this process already
        return True
    cache = dispatcher._cache
    index = cache._cache_file._load_index()  # empty if missing or stale (another source time stamp)
    if not index:
        return False
    codegen = dispatcher.targetctx.codegen()
    _, magic, code = cache._index_key((), codegen)
    return any(key[1] == magic and key[2] == code for key in index)


def cache_is_warm() -> bool | None:
    """Whether a trace would load the compiled core from numba's cache instead of compiling it.

    Returns
    -------
    bool or None
        ``True``: every entry point is cached for this machine (or already compiled in this process);
        ``False``: some part would be compiled (10-30 s in all); ``None``: cannot tell (numba's cache
        internals changed, or JIT compilation is disabled with ``NUMBA_DISABLE_JIT=1``).
    """
    try:
        return all(_is_cached(d) for _, d in _dispatchers())
    except Exception:  # numba's private cache layout is not an API: never fail a run over it
        return None


@contextmanager
def reporting(progress: Callable[[str, float | None], None]) -> Iterator[None]:
    """Within the block, report each part of :data:`ENTRY_POINTS` that numba compiles.

    ``progress(part, None)`` is called when the compilation of a part starts, and
    ``progress(part, seconds)`` when its first entry point is compiled (once per part); nothing is
    called for parts loaded from the cache (or compiled before the block).
    """
    from numba.core import event

    parts = {id(d.py_func): part for part, d in _dispatchers()}
    started: list[tuple[str | None, float]] = []  # the compilations under way, outermost first
    seen: set[str] = set()

    class _Listener(event.Listener):
        def on_start(self, ev):
            part = parts.get(id(getattr(ev.data.get("dispatcher"), "py_func", None)))
            if part is not None and part not in seen:
                seen.add(part)
                progress(part, None)
            else:
                part = None  # a callee, or a part's second entry point (its first one's report covers it)
            started.append((part, time.perf_counter()))

        def on_end(self, ev):
            if started:
                part, t0 = started.pop()
                if part is not None:
                    progress(part, time.perf_counter() - t0)

    listener = _Listener()
    event.register("numba:compile", listener)
    try:
        yield
    finally:
        event.unregister("numba:compile", listener)


def _part_is_cached(part: str) -> bool:
    return all(_is_cached(d) for p, d in _dispatchers() if p == part)


def _exercise_replay() -> None:
    """The verifying replay on one tiny chunk, through :func:`~skatetrace.dynamics.replayer.replay_chunk`
    (so with the argument types of every replay)."""
    import numpy as np

    from ..dynamics.controls import ControlSchedule
    from ..dynamics.model import SleighParams
    from ..dynamics.replayer import replay_chunk

    zero = np.zeros(2)
    rows = ControlSchedule(t=np.array([0.0, 1.0]), a=zero, b=zero + 0.5, adot=zero, bdot=zero,
                           section=np.zeros(2, dtype=int), piece=np.zeros(2, dtype=int))
    replay_chunk(SleighParams(), np.array([0.0, 1.0, 0.0, 0.0, 0.0]), rows, 0, 2, [0.0, 1.0])


def _exercise_distances() -> None:
    """The figure-to-replay distance search on a replay of three samples, through the verification's own
    function (so with the argument types of every check)."""
    import numpy as np

    from ..dynamics.model import SleighParams
    from ..verification.distances import figure_to_replay
    from ..verification.verify import Replay

    n = 3
    state = np.zeros((5, n))
    state[1], state[3] = 1.0, np.arange(n, dtype=float)
    rep = Replay(t=np.arange(n, dtype=float), state=state, controls=np.zeros((4, n)), section=np.zeros(n, dtype=int),
                 piece=np.zeros(n, dtype=int))
    figure_to_replay(np.array([[0.5, 1.5], [0.1, 0.1]]), rep, np.arange(n), SleighParams())


def _exercise_law_replay() -> None:
    """The closed-loop replay over one span of a two-row reference under a law of zero gains, through
    :func:`~skatetrace.feedback.law_replay.replay_span` (so with the argument types of every closed loop)."""
    import numpy as np

    from ..dynamics.model import SleighParams
    from ..feedback.law_replay import replay_span

    z = np.zeros((7, 2))
    z[1] = 1.0  # gliding ahead on a line
    arrays = (np.array([0.0, 1.0]), z, np.zeros((7, 2)), np.array([0.0, 1.0]), np.zeros((2, 2, 7)))
    replay_span(arrays, SleighParams(), z[:, 0], (0.0, 1.0), [0.0, 1.0], rtol=1e-6, atol=1e-9, max_nfev=10_000)


def _exercise_riccati() -> None:
    """The tracking law's Riccati equation over two rows of a zero linearisation, through
    :func:`~skatetrace.feedback.riccati.solve_backwards` (so with the argument types of every law's design)."""
    import numpy as np

    from ..feedback.riccati import solve_backwards

    t = np.array([0.0, 1.0])
    solve_backwards(t, np.zeros((2, 7, 7)), np.zeros((2, 7, 2)), np.ones(2), t, rtol=1e-6, atol=1e-9, max_nfev=10_000)


#: The verification's parts, which :func:`compile_ahead` compiles while a first run traces.
AHEAD = ("the verifying replay", "the distance checks")


def _compile_parts(parts: tuple[str, ...]) -> None:
    from ..processes import quiet_on_interrupt

    quiet_on_interrupt()
    for part in parts:
        _EXERCISES[part]()


def compile_ahead(parts: tuple[str, ...] = AHEAD):
    """Compile ``parts`` of the core into numba's cache in a forked process, in the background.

    For a first run: the process compiles the verification's parts while the caller traces (and
    compiles the manoeuvre integrator), and the verification then loads them from the cache.
    Returns the process (``join`` it to wait), or None where nothing is to be compiled (every part
    cached, or the cache's state unknown), where forking is not safe (another thread running) or
    where JIT compilation is disabled. The answers do not depend on it: a part the process has not
    finished compiling when the run needs it is compiled by the run as usual.
    """
    import multiprocessing

    from numba.core.config import DISABLE_JIT

    from ..processes import can_fork

    if DISABLE_JIT or not can_fork():
        return None
    try:
        todo = tuple(p for p in parts if not _part_is_cached(p))
    except Exception:  # numba's private cache layout is not an API: never fail a run over it
        return None
    if not todo:
        return None
    process = multiprocessing.get_context("fork").Process(target=_compile_parts, args=(todo,), daemon=True,
                                                          name="skatetrace-compile-ahead")
    process.start()
    return process


#: The parts a launch-glide-stop trace does not need, in the order :func:`compile_later` compiles
#: them: the planner's finish (every school figure is planned by default), the closed loop and its
#: law (an ill-conditioned section's verification, ``skatetrace robustness``), the spirals (exact mode).
LATER = ("the planner's exact finish", "the closed-loop replay", "the tracking law's Riccati equation",
         "the spirals' geometry")
#: A job of :func:`compile_later` still compiling after this many seconds is stopped (it takes some 11 s
#: of one core).
LATER_TIMEOUT = 600
#: The lock a job of :func:`compile_later` holds while it runs, in the integrator's folder of numba's cache.
LATER_LOCK = "skatetrace-compile-later.lock"


def compile_later() -> tuple[str, ...]:
    """Compile the parts of :data:`LATER` missing from numba's cache in a job of its own, for later runs.

    A first run compiles only the parts it needs (:func:`compile_ahead`, :func:`reporting`); the
    next command may need others, and would spend seconds compiling them (a first planned school
    figure 4 s on the finish, a first closed loop 6-7 s). The job compiles them for it, each
    through its own callers on tiny inputs (so with the argument types of every run), skipping a
    part that is cached by the time it comes to it (a run compiled it meanwhile).

    It starts compiling once the run (with the children it forks) has ended, so as to take nothing
    from the run's own work at low priority (its plots); where :func:`skatetrace.cli.main` is
    called in a longer process (a notebook, the tests), once that process ends. It runs at the
    lowest priority (``nice``) in the run's session, so it takes only what other work leaves of
    the processors. It ignores Ctrl-C, outlives the run (the shell that starts it ends at once, so
    no child is left to this process), holds :data:`LATER_LOCK` while it runs (a second run starts
    no second job), and is stopped :data:`LATER_TIMEOUT` seconds after it starts compiling. Its
    output goes nowhere: a part it fails to compile is compiled by the run that needs it, as
    without the job. The answers never depend on it.

    Returns
    -------
    tuple of str
        The parts the job was started for, in order; empty where none was started: every part
        cached, the cache's state unknown, a job already running for this cache, JIT compilation
        disabled, no POSIX shell, or ``SKATETRACE_COMPILE_LATER=0`` in the environment.
    """
    import os
    import shutil
    import subprocess
    import sys
    from pathlib import Path

    from numba.core.config import DISABLE_JIT

    try:
        import fcntl
    except ImportError:  # pragma: no cover - not POSIX
        return ()
    enabled = os.environ.get("SKATETRACE_COMPILE_LATER", "1").strip().lower() not in ("0", "no", "false", "off")
    sh = shutil.which("sh")
    if DISABLE_JIT or not enabled or sh is None:
        return ()
    try:
        todo = tuple(p for p in LATER if not _part_is_cached(p))
        folder = Path(next(d for p, d in _dispatchers() if p == ENTRY_POINTS[0][0])._cache.cache_path)
    except Exception:  # numba's private cache layout is not an API: never fail a run over it
        return ()
    if not todo:
        return ()
    try:
        with open(folder / LATER_LOCK, "a+b") as lock:  # the job keeps its own copy, and the lock
            try:
                fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except OSError:
                return ()  # a job is compiling into this cache already
            # The job reads the pipe until every copy of its write end is closed: until this run
            # (with the children it forks) has ended, so that it takes nothing from the run's own
            # work at low priority (its plots); it imports skatetrace only then.
            waited, running = os.pipe()
            code = (f"import os, signal\nwhile os.read({waited}, 1):\n    pass\nsignal.alarm({LATER_TIMEOUT})\n"
                    f"from skatetrace.cli.compiled import _compile_later\n_compile_later({todo!r})")
            command = [sys.executable, "-c", code]
            if shutil.which("nice"):
                command = ["nice", "-n", "19"] + command
            try:
                subprocess.run([sh, "-c", 'trap "" INT; "$@" &', "sh", *command], pass_fds=(lock.fileno(), waited),
                               stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                               check=True, timeout=30)
            except BaseException:
                os.close(running)
                raise
            finally:
                os.close(waited)
            # ``running`` stays open, on purpose, for as long as this process runs
    except (OSError, subprocess.SubprocessError):
        return ()
    return todo


def _compile_later(parts: tuple[str, ...]) -> None:
    """The job of :func:`compile_later`: each of ``parts`` not yet cached, in order."""
    for part in parts:
        try:
            if not _part_is_cached(part):
                _EXERCISES[part]()
        except Exception:  # noqa: S112 - nobody to tell: the run that needs the part compiles it
            continue


def later_job_end(cache, timeout: float = 600.0) -> float | None:
    """Wait for the job of :func:`compile_later` whose lock is under ``cache`` (a folder of numba's cache) to end.

    Returns the seconds waited, None where no job was started there (no lock file), or ``inf``
    where it was still running after ``timeout`` seconds. For a test or a benchmark that runs a
    first run in a cache of its own (``NUMBA_CACHE_DIR``) and must not remove it under the job.
    """
    import fcntl
    import math
    from pathlib import Path

    t0 = time.perf_counter()
    while time.perf_counter() - t0 < timeout:
        locks = list(Path(cache).rglob(LATER_LOCK))
        if not locks:
            return None
        with open(locks[0], "a+b") as fh:
            try:
                fcntl.flock(fh, fcntl.LOCK_EX | fcntl.LOCK_NB)
                return time.perf_counter() - t0
            except OSError:
                pass
        time.sleep(0.2)
    return math.inf


@contextmanager
def first_run(say: Callable[[str], None]) -> Iterator[None]:
    """A run's compiling, told line by line to ``say``: nothing where every part loads from the cache.

    On a first run it starts :func:`compile_ahead` and :func:`compile_later` (each said where it
    starts), then, within the block, says each part as the run compiles it and how long it took
    (:func:`reporting`).
    """
    if compile_ahead() is not None:  # the verification compiles while the run traces
        say("  compiling the verification's parts alongside, in a second process")
    later = compile_later()
    if later:  # for the next commands: a planned figure, a closed loop, exact mode
        say(f"  compiling for later runs, in the background at the lowest priority: {', '.join(later)}")
    with reporting(lambda part, seconds: say(f"  compiling {part}" if seconds is None
                                             else f"  compiled {part} in {seconds:.0f} s")):
        yield


def warm_up(progress: Callable[[str, int, int], None] | None = None) -> float:
    """Compile (or load from numba's cache) everything tracing and verifying a figure needs.

    Traces and verifies the built-in ``circle``: compilation depends only on the argument types, never
    on the figure, so this covers every figure (in the same process and, through the cache, in later
    ones).

    Parameters
    ----------
    progress : callable, optional
        Called as ``progress(part, index, count)`` when the compilation of a part starts (``part`` as in
        :data:`ENTRY_POINTS`, ``index`` from 1 to ``count``); not called for parts loaded from the cache.

    Returns
    -------
    float
        Seconds taken.
    """
    start = time.perf_counter()
    order = [part for part, _ in ENTRY_POINTS]

    def started(part: str, seconds: float | None) -> None:
        if progress is not None and seconds is None:
            progress(part, order.index(part) + 1, len(order))

    with reporting(started):
        from ..figures.patterns import pattern
        from ..pipeline import trace_and_verify
        from ..tracing.sections import TraceOptions

        _replay_under_a_law(trace_and_verify(pattern("circle"), options=TraceOptions()).trace)
        _spiral_distance()
        _finish_at_rest()
    return time.perf_counter() - start


def _replay_under_a_law(trace) -> None:
    """Compile the closed-loop replay and the law's Riccati equation, which verification reaches only on
    an ill-conditioned section: a law designed for ``trace``'s first section, and a replay of the
    section under a law of zero gains (their types are every law's)."""
    import numpy as np

    from ..feedback.closed_loop import replay_law
    from ..feedback.lqr import TrackingLaw, default_gains, design
    from ..feedback.reference import section_reference

    if not (trace.sections and trace.sections[0].success):
        return
    ref = section_reference(trace.sections[0], trace.params, points=8, max_points=8)
    design(ref, trace.params, default_gains(trace.figure.size()))
    law = TrackingLaw(reference=ref, t=ref.grid, K=np.zeros((ref.grid.size, 2, 7)), params=trace.params)
    replay_law(ref, law, trace.params, ref.state_at(0.0)[0][:, 0], [0.0, ref.duration])


def _spiral_distance() -> None:
    """Compile the spirals' geometry, which only the exact mode's figures reach: a point's distance to a
    clothoid (its cells, positions and foot point)."""
    import numpy as np

    from ..figures.geometry import Pose, Spiral, distance_to_segment

    distance_to_segment(np.array([[0.5], [0.5]]), Pose(0.0, 0.0, 0.0), Spiral((0.0, 1.0, 0.0, 0.0), 1.0))


def _finish_at_rest() -> None:
    """Compile the planner's exact finish (:mod:`skatetrace.planning.shooting`), which a trace without a reach
    never runs: one Gauss-Newton iteration on a section at rest on a line (converged or not: its types are
    every section's)."""
    import numpy as np

    from ..dynamics.model import SleighParams
    from ..figures.geometry import Spiral
    from ..planning.finish import RestState, finish_section

    rest = RestState(0.0, -0.3, 0.0, 0.0)
    states = np.zeros((6, 5))
    states[3] = rest.b
    finish_section(SleighParams(), [Spiral((0.0, 0.0, 0.0, 0.0), 1.0)], np.linspace(0.0, 1.0, 5), np.zeros(5), rest,
                   rest, states, max_iter=1)


#: What compiles each part on its own, without a trace (:func:`compile_ahead`, :func:`compile_later`):
#: through its own callers on tiny inputs, so with the argument types of every run.
_EXERCISES = {"the verifying replay": _exercise_replay, "the distance checks": _exercise_distances,
              "the planner's exact finish": _finish_at_rest, "the closed-loop replay": _exercise_law_replay,
              "the tracking law's Riccati equation": _exercise_riccati, "the spirals' geometry": _spiral_distance}
