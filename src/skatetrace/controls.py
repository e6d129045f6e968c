"""Control schedules: sampled a(t), b(t) with their rates, interpolated by cubic Hermite splines.

A schedule is what ``controls.csv`` holds. Rows are in time order; a repeated time marks an
instant where the rates (or, at a cusp, the controls themselves) jump, and splits the schedule
into smooth *chunks*. Within a chunk, ``a`` and ``b`` are the cubic Hermite interpolants of the
samples and their rates, and ``adot``, ``bdot`` are the derivatives of those interpolants, so the
replayed controls are exactly consistent.
"""

from __future__ import annotations

from bisect import bisect_right
from dataclasses import dataclass

import numpy as np
from scipy.interpolate import CubicHermiteSpline

__all__ = ["ControlSchedule", "sample_adaptively"]


@dataclass(frozen=True, slots=True, kw_only=True)
class ControlSchedule:
    """Sampled controls, shape ``(n,)`` each; ``section`` and ``piece`` label every row."""

    t: np.ndarray
    a: np.ndarray
    b: np.ndarray
    adot: np.ndarray
    bdot: np.ndarray
    section: np.ndarray
    piece: np.ndarray

    def __post_init__(self) -> None:
        n = self.t.shape
        for name in ("a", "b", "adot", "bdot", "section", "piece"):
            if getattr(self, name).shape != n:
                raise ValueError(f"control column {name!r} has shape {getattr(self, name).shape}, expected {n}")
        if np.any(np.diff(self.t) < 0):
            raise ValueError("control times must be non-decreasing")
        if not np.all(np.isfinite(self.t)) or not all(
            np.all(np.isfinite(getattr(self, k))) for k in ("a", "b", "adot", "bdot")
        ):
            raise ValueError("control samples must be finite")

    def chunks(self) -> list[tuple[int, int]]:
        """Index ranges ``[i0, i1)`` of the smooth chunks (split at repeated times)."""
        cut = np.flatnonzero(np.diff(self.t) == 0.0) + 1
        bounds = np.concatenate([[0], cut, [self.t.size]])
        return [(int(i0), int(i1)) for i0, i1 in zip(bounds[:-1], bounds[1:]) if i1 - i0 >= 2]

    def interpolant(self, i0: int, i1: int):
        """Callable ``f(t) -> (a, b, adot, bdot)`` on chunk ``[i0, i1)`` (arrays in, arrays out)."""
        t = self.t[i0:i1]
        sa = CubicHermiteSpline(t, self.a[i0:i1], self.adot[i0:i1])
        sb = CubicHermiteSpline(t, self.b[i0:i1], self.bdot[i0:i1])
        da, db = sa.derivative(), sb.derivative()
        return lambda tt: (sa(tt), sb(tt), da(tt), db(tt))

    def scalar_interpolant(self, i0: int, i1: int):
        """Fast scalar version of :meth:`interpolant` for use inside an ODE right-hand side."""
        t = self.t[i0:i1]
        ca = CubicHermiteSpline(t, self.a[i0:i1], self.adot[i0:i1]).c.T.tolist()
        cb = CubicHermiteSpline(t, self.b[i0:i1], self.bdot[i0:i1]).c.T.tolist()
        knots = t.tolist()
        last = len(knots) - 2

        def f(tt: float):
            i = min(max(bisect_right(knots, tt) - 1, 0), last)
            h = tt - knots[i]
            a3, a2, a1, a0 = ca[i]
            b3, b2, b1, b0 = cb[i]
            return (((a3 * h + a2) * h + a1) * h + a0, ((b3 * h + b2) * h + b1) * h + b0,
                    (3 * a3 * h + 2 * a2) * h + a1, (3 * b3 * h + 2 * b2) * h + b1)

        return f


def sample_adaptively(fn, t0: float, t1: float, *, value_tol: float = 1e-10, rate_tol: float = 1e-8,
                      n0: int = 16, max_points: int = 200_000) -> np.ndarray:
    """Times on ``[t0, t1]`` at which Hermite interpolation of ``fn`` meets the tolerances.

    ``fn(t)`` returns ``(a, b, adot, bdot)`` arrays. Intervals are bisected until the Hermite
    interpolant's values at the midpoints agree with ``fn`` to ``value_tol`` and its derivative
    with the rates to ``rate_tol`` (absolute).
    """
    t = np.linspace(t0, t1, n0)
    while True:
        a, b, ad, bd = fn(t)
        mid = 0.5 * (t[:-1] + t[1:])
        am, bm, adm, bdm = fn(mid)
        bad = np.zeros(mid.size, dtype=bool)
        for v, d, vm, dm in ((a, ad, am, adm), (b, bd, bm, bdm)):
            s = CubicHermiteSpline(t, v, d)
            bad |= np.abs(s(mid) - vm) > value_tol
            bad |= np.abs(s.derivative()(mid) - dm) > rate_tol
        if not np.any(bad) or t.size >= max_points:
            return t
        t = np.sort(np.concatenate([t, mid[bad]]))
