"""Shared pieces of the benchmark scripts: the distinct-arcs generator, a warm-up, timing helpers.

Not a benchmark itself. The scripts put this folder on ``sys.path`` so that they can import it both
when run as ``python bench/NAME.py`` and when loaded from a file by the tests or by ``run_all.py``.
"""

from __future__ import annotations

import contextlib
import math
import statistics
import time

import numpy as np

from skatetrace import PAPER_PARAMS, Curve, Figure, Join, Segment, trace_figure, verify
from skatetrace.verification.verify import schedule_from_trace

KAPPA = (0.2, 2.0)  # |curvature| range of the generated arcs
SWEEP_DEG = (30.0, 200.0)  # sweep range (degrees)
PIVOT_DEG = (-150.0, 150.0)  # pivot range at the cusps between arcs (degrees)


def distinct_arcs(n: int, seed: int = 0) -> Figure:
    """``n`` distinct arcs, each its own section: every join a cusp with a pivot, nothing smooth.

    Curvature magnitudes are uniform in ``KAPPA`` with a random sign, sweeps uniform in
    ``SWEEP_DEG`` (length = sweep / |curvature|), pivots uniform in ``PIVOT_DEG``; the paper's
    parameters M = 2, m = 1, I = 3. Reproducible from ``seed`` (``numpy.random.default_rng``), and
    nested: the first k arcs of ``distinct_arcs(n, seed)`` are ``distinct_arcs(k, seed)``. The
    (curvature, length) pairs are checked to be distinct, so the tracer's cache of solved sections
    (keyed by curvatures and lengths) cannot reuse any solution.
    """
    if n < 1:
        raise ValueError(f"need at least one arc, got {n}")
    rng = np.random.default_rng(seed)
    # Drawn arc by arc, so distinct_arcs(k, seed) is the first k arcs of distinct_arcs(n, seed), n > k:
    # the sizes of a scaling run are nested figures.
    draws = [(rng.uniform(*KAPPA), rng.choice([-1.0, 1.0]), math.radians(rng.uniform(*SWEEP_DEG)),
              math.radians(rng.uniform(*PIVOT_DEG))) for _ in range(n)]
    kappa = [k * sign for k, sign, _, _ in draws]
    length = [sweep / abs(k) for k, (_, _, sweep, _) in zip(kappa, draws)]
    pivot = [d[3] for d in draws[1:]]  # the pivot drawn with arc i is at the cusp before it (i >= 1)
    pieces = tuple(Segment(float(k), float(s)) for k, s in zip(kappa, length))
    keys = {(round(p.curvature, 12), round(p.length, 12)) for p in pieces}
    if len(keys) != n:  # pragma: no cover - a coincidence of random floats
        raise RuntimeError(f"seed {seed} gave repeated arcs; pick another seed")
    joins = tuple(Join("cusp", float(p)) for p in pivot)
    return Figure(f"distinct-arcs-{n}-seed{seed}", (Curve(pieces, joins, name=f"arcs-{n}"),), PAPER_PARAMS,
                  f"{n} distinct arcs joined at cusps with pivots (bench/_common.py, seed {seed})")


def warm_up() -> float:
    """Trace, sample and verify one small figure so numba's compiled integrator is loaded.

    Returns the time it took (compilation, or loading numba's on-disk cache, plus the work).
    """
    t0 = time.perf_counter()
    tr = trace_figure(distinct_arcs(1, seed=12345))
    sch, _ = schedule_from_trace(tr)
    verify(tr, sch)
    return time.perf_counter() - t0


@contextlib.contextmanager
def replay_timer():
    """Time spent in ``skatetrace.verification.verify.replay`` (integrating the full dynamics) while active.

    Yields a list that collects one duration per call. ``verify`` calls the module-level ``replay``,
    which is wrapped for the duration of the block (and restored after), so ``verify`` time splits
    into the replay and the checks (deviation both ways, cusp speeds, invariants) without running
    anything twice. The library is not changed.
    """
    import importlib

    # the module itself: the package attribute skatetrace.verification.verify is the function of that name
    sv = importlib.import_module("skatetrace.verification.verify")
    original = sv.replay
    spent: list[float] = []

    def wrapped(*args, **kwargs):
        t0 = time.perf_counter()
        try:
            return original(*args, **kwargs)
        finally:
            spent.append(time.perf_counter() - t0)

    sv.replay = wrapped
    try:
        yield spent
    finally:
        sv.replay = original


def timed_verify(trace, schedule):
    """``(report, seconds, replay seconds)`` of one ``verify(trace, schedule)``."""
    with replay_timer() as spent:
        rep, dt = timed(verify, trace, schedule)
    return rep, dt, sum(spent)


def timed(fn, *args, **kwargs):
    """``(result, seconds)`` of one call."""
    t0 = time.perf_counter()
    out = fn(*args, **kwargs)
    return out, time.perf_counter() - t0


def median(values) -> float:
    values = [v for v in values if v is not None and math.isfinite(v)]
    return statistics.median(values) if values else math.nan


def loglog_slope(x, y) -> float:
    """Least-squares slope of log(y) against log(x) (NaN with fewer than two usable points)."""
    pts = [(math.log(a), math.log(b)) for a, b in zip(x, y)
           if a is not None and b is not None and a > 0 and b > 0 and math.isfinite(b)]
    if len(pts) < 2 or len({p[0] for p in pts}) < 2:
        return math.nan
    lx, ly = np.array(pts).T
    return float(np.polyfit(lx, ly, 1)[0])


def quiet_print(quiet: bool):
    """``print`` (flushed) unless ``quiet``."""
    if quiet:
        return lambda *a, **k: None
    return lambda *a, **k: print(*a, **k, flush=True)
