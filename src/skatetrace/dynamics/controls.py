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

__all__ = ["ControlSchedule", "distinct_steps", "sample_adaptively", "sample_intervals"]


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
        knots, ca, cb = self.hermite(i0, i1)
        last = knots.size - 2

        def f(tt):
            tt = np.asarray(tt, dtype=float)
            k = np.clip(np.searchsorted(knots, tt, side="right") - 1, 0, last)
            h = tt - knots[k]
            a3, a2, a1, a0 = ca[k].T
            b3, b2, b1, b0 = cb[k].T
            return (((a3 * h + a2) * h + a1) * h + a0, ((b3 * h + b2) * h + b1) * h + b0,
                    (3 * a3 * h + 2 * a2) * h + a1, (3 * b3 * h + 2 * b2) * h + b1)

        return f

    def hermite(self, i0: int, i1: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The cubics of chunk ``[i0, i1)``: ``(knots, ca, cb)``.

        ``ca[k]`` holds ``(c3, c2, c1, c0)`` of ``a`` on ``[knots[k], knots[k + 1]]`` in powers of
        ``t - knots[k]`` (``cb`` likewise for ``b``), computed as scipy's ``CubicHermiteSpline``
        computes them.
        """
        t = np.ascontiguousarray(self.t[i0:i1])
        dt = np.diff(t)
        if t.size < 2 or not np.all(dt > 0):
            raise ValueError(f"rows {i0}:{i1} are no chunk: a chunk has two or more strictly increasing times")

        def cubic(y, dydx):
            slope = np.diff(y) / dt
            c3 = (dydx[:-1] + dydx[1:] - 2.0 * slope) / dt
            return np.ascontiguousarray(np.stack([c3 / dt, (slope - dydx[:-1]) / dt - c3, dydx[:-1], y[:-1]], axis=1))

        return t, cubic(self.a[i0:i1], self.adot[i0:i1]), cubic(self.b[i0:i1], self.bdot[i0:i1])

    def scalar_interpolant(self, i0: int, i1: int):
        """Fast scalar version of :meth:`interpolant` for use inside an ODE right-hand side."""
        t, ca, cb = self.hermite(i0, i1)
        ca, cb, knots = ca.tolist(), cb.tolist(), t.tolist()
        last = len(knots) - 2

        def f(tt: float):
            i = min(max(bisect_right(knots, tt) - 1, 0), last)
            h = tt - knots[i]
            a3, a2, a1, a0 = ca[i]
            b3, b2, b1, b0 = cb[i]
            return (((a3 * h + a2) * h + a1) * h + a0, ((b3 * h + b2) * h + b1) * h + b0,
                    (3 * a3 * h + 2 * a2) * h + a1, (3 * b3 * h + 2 * b2) * h + b1)

        return f


def distinct_steps(t) -> np.ndarray:
    """Per step ``t[i] -> t[i + 1]`` of sampled times, whether the two differ by more than their round-off.

    Rows at one time up to round-off (``1e-12`` of the largest time, at least ``1e-12``) stand for
    the two sides of a jump: a finite difference across them measures the jump, not a rate.
    """
    t = np.asarray(t, dtype=float)
    if t.size < 2:
        return np.zeros(0, dtype=bool)
    return np.diff(t) > 1e-12 * max(1.0, float(np.max(np.abs(t))))


def sample_adaptively(fn, t0: float, t1: float, *, value_tol: float = 1e-11, rate_tol: float = 1e-9,
                      n0: int = 16, max_points: int = 200_000, min_step: float = 1e-7) -> np.ndarray:
    """Times on ``[t0, t1]`` at which Hermite interpolation of ``fn`` meets the tolerances.

    ``fn(t)`` returns ``(a, b, adot, bdot)`` arrays. Every interval is checked: the cubic Hermite
    interpolant of its end values and rates must agree with ``fn`` at its midpoint to
    ``value_tol`` times the largest ``|a|, |b|``, and its derivative at its first quarter to
    ``rate_tol`` times the largest rate (relative tolerances, so that metres and model units
    sample alike). An interval that fails is split into as many equal parts as its error calls
    for (the value error of the interpolant falls like h^4, the rate error like h^3; at most 16
    parts, at least 2), and the parts are checked in turn. No interval is made shorter than
    ``min_step`` times the span. Only new points are evaluated, so the cost is linear in the
    result. :func:`sample_intervals` does the same on many spans at once.
    """
    return sample_intervals(lambda t, left: fn(t), [t0, t1], value_tol=value_tol, rate_tol=rate_tol, n0=n0,
                            max_points=max_points, min_step=min_step)[0]


def sample_intervals(fn, bounds, *, value_tol: float = 1e-11, rate_tol: float = 1e-9, n0: int = 16,
                     max_points: int = 200_000, min_step: float = 1e-7, values: bool = False,
                     scale_floor: float = 0.0):
    """:func:`sample_adaptively` on every span ``[bounds[k], bounds[k + 1]]``, all spans at once.

    Parameters
    ----------
    fn : callable
        ``fn(t, left)`` for an array of times ``t`` and a boolean array ``left`` that marks the
        times standing for the end of their span (at a breakpoint, where the rates jump, the span
        before it needs the limit from the left). It returns a sequence of arrays (or a 2-D
        array) whose first four rows are ``a, b, adot, bdot``; further rows are carried along.
    bounds : array_like
        Increasing breakpoints.
    values : bool
        Also return everything ``fn`` returned at the sampled times.
    scale_floor : float
        A span's scales (its largest ``|a|, |b|`` and its largest rate) are taken as at least this
        share of the largest over all spans. With the default 0 each span is sampled as alone; a
        span whose values are all tiny (the mass passing through the blade's contact point) is
        otherwise held to tolerances far below the round-off of the others.

    Returns
    -------
    spans : list of ndarray
        The times of each span, its two ends included; with ``scale_floor=0`` the same as
        :func:`sample_adaptively` on that span alone (tolerances relative to the span's own largest
        values), at a fraction of the Python overhead when there are many spans.
    rows : ndarray, shape (k, n)
        With ``values=True``: ``fn``'s rows at ``np.concatenate(spans)``.
    """
    bounds = np.asarray(bounds, dtype=float)
    nspan = bounds.size - 1
    t = np.concatenate([np.linspace(lo, hi, n0) for lo, hi in zip(bounds[:-1], bounds[1:])])
    span = np.repeat(np.arange(nspan), n0)  # the span each time belongs to
    end = np.zeros(t.size, dtype=bool)
    end[n0 - 1::n0] = True
    v = np.vstack(fn(t, end))  # (k, n): a, b, adot, bdot, then whatever fn carries along
    v_scale = np.maximum(np.max(np.abs(v[:2]), axis=0).reshape(nspan, n0).max(axis=1), 1e-300)
    r_scale = np.maximum(np.max(np.abs(v[2:4]), axis=0).reshape(nspan, n0).max(axis=1), 1e-300)
    todo = np.flatnonzero(~end)  # intervals [t[i], t[i + 1]] still to check
    # Intervals are never split below the resolution of the times either: in a span a few ulps long (two
    # breakpoints apart by round-off) a midpoint rounds onto an end, and splitting a step in the
    # values there added copies of it until max_points (one-foot eight's plan: hours).
    h_min = np.maximum(min_step * np.diff(bounds), 64.0 * np.finfo(float).eps * np.max(np.abs(bounds), initial=0.0))
    while todo.size:
        # spans grown to max_points are left as they are
        todo = todo[np.bincount(span, minlength=nspan)[span[todo]] < max_points]
        if not todo.size:
            break
        k = span[todo]
        n = todo.size
        lo, hi = t[todo], t[todo + 1]
        h = hi - lo
        mid = 0.5 * (lo + hi)
        # midpoints and first quarters in one call (each call of fn has an overhead of its own)
        both = np.vstack(fn(np.concatenate([mid, lo + 0.25 * h]), np.zeros(2 * n, dtype=bool)))
        vm, vq = both[:, :n], both[:4, n:]
        np.maximum.at(v_scale, k, np.max(np.abs(vm[:2]), axis=0))
        np.maximum.at(r_scale, k, np.max(np.abs(vm[2:4]), axis=0))
        if scale_floor:
            np.maximum(v_scale, scale_floor * v_scale.max(), out=v_scale)
            np.maximum(r_scale, scale_floor * r_scale.max(), out=r_scale)
        y0, y1, d0, d1 = v[:2, todo], v[:2, todo + 1], v[2:4, todo], v[2:4, todo + 1]
        # The Hermite cubic's value error peaks at the midpoint; its derivative error vanishes
        # there and peaks near u = 0.21 and 0.79, so the rates are checked at u = 1/4 (97% of it).
        value = 0.5 * (y0 + y1) + h * (d0 - d1) / 8.0
        # a span of zero length (two breakpoints at one time: a planned piece of no duration) has
        # nothing to check and is never split (h <= 2 h_min below): its quotients are left as NaN
        with np.errstate(divide="ignore", invalid="ignore"):
            rate = 1.125 * (y1 - y0) / h + 0.1875 * d0 - 0.3125 * d1
            # Below the rounding error of the difference quotient (y1 - y0) / h no halving can help.
            floor = 16.0 * np.finfo(float).eps * v_scale[k] / h
            value_excess = np.max(np.abs(value - vm[:2]), axis=0) / (value_tol * v_scale[k])
            rate_excess = np.max(np.abs(rate - vq[2:4]), axis=0) / (rate_tol * r_scale[k] + floor)
        # Intervals are not split below h_min: where the values come from a piecewise interpolant
        # (an ODE solver's dense output) their slope may jump between steps by more than the rate
        # tolerance, and no splitting would ever satisfy it there.
        bad = ((value_excess > 1.0) | (rate_excess > 1.0)) & (h > 2.0 * h_min[k])
        if not np.any(bad):
            break
        # parts the errors call for, with 5% to spare; a bisection (the common case near the
        # end) reuses the midpoint already evaluated
        want = np.ceil(1.05 * np.maximum(value_excess[bad] ** 0.25, rate_excess[bad] ** (1.0 / 3.0)))
        parts = np.clip(np.nan_to_num(want, nan=2.0, posinf=16.0), 2, 16)
        parts = np.minimum(parts, np.maximum(np.floor(h[bad] / h_min[k[bad]]), 2)).astype(int)
        halves = parts == 2
        new_t = [mid[bad][halves]]
        new_v = [vm[:, bad][:, halves]]
        new_at = [todo[bad][halves]]
        many = ~halves
        if np.any(many):
            reps = parts[many] - 1
            owner = np.repeat(np.arange(reps.size), reps)
            j = np.arange(owner.size) - np.repeat(np.cumsum(reps) - reps, reps)  # 0 .. parts - 2 per interval
            frac = (j + 1) / parts[many][owner]
            tt = lo[bad][many][owner] + frac * h[bad][many][owner]
            new_t.append(tt)
            new_v.append(np.vstack(fn(tt, np.zeros(tt.size, dtype=bool))))
            new_at.append(todo[bad][many][owner])
        at = np.concatenate(new_at)
        order = np.argsort(at, kind="stable")  # points after the same row stay in increasing time
        at, tnew, vnew = at[order], np.concatenate(new_t)[order], np.hstack(new_v)[:, order]
        t = np.insert(t, at + 1, tnew)
        v = np.insert(v, at + 1, vnew, axis=1)
        span = np.insert(span, at + 1, span[at])
        end = np.insert(end, at + 1, False)
        # the intervals to check next: every part of every split interval
        shift = np.searchsorted(at, todo[bad], side="left")  # points inserted before each split interval
        first = todo[bad] + shift
        todo = np.repeat(first, parts) + (np.arange(parts.sum()) - np.repeat(np.cumsum(parts) - parts, parts))
    spans = np.split(t, np.flatnonzero(end)[:-1] + 1)
    return (spans, v) if values else spans
