"""The distance from the figure to a replayed path, and from the replay to a placed piece of the figure.

The replayed path between two dense samples is the cubic Hermite curve of their positions and
velocities (the model's); the nearest point of it to a point of the figure is found by
golden-section search and Newton's method (compiled), so that the chord error of a polyline does
not count against the replay (:func:`figure_to_replay`). The other way, a replayed point's distance
to a piece is the piece's own (:func:`nearer_pieces`). :func:`~skatetrace.verification.verify.verify`
measures both ways with them.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np
from numba import njit
from scipy.spatial import cKDTree

from ..dynamics.controls import distinct_steps
from ..dynamics.model import SleighParams, velocities
from ..dynamics.numba_cache import guard_saves
from ..figures.geometry import distance_to_segment

if TYPE_CHECKING:  # pragma: no cover - for the annotations only (verify imports this module)
    from .verify import Replay

__all__ = ["figure_to_replay", "nearer_pieces"]

guard_saves()  # this module's compiled functions share numba's cache with other processes


@njit(cache=True)
def _hermite_point(x0, y0, vx0, vy0, x1, y1, vx1, vy1, h, u):
    """Point of the cubic Hermite curve of one interval at ``u`` in [0, 1], with its first two
    derivatives in ``u``: ``(px, py, dpx, dpy, ddpx, ddpy)``."""
    h00, h10, h01, h11 = 2 * u**3 - 3 * u**2 + 1, u**3 - 2 * u**2 + u, -2 * u**3 + 3 * u**2, u**3 - u**2
    d00, d10, d01, d11 = 6 * u**2 - 6 * u, 3 * u**2 - 4 * u + 1, -6 * u**2 + 6 * u, 3 * u**2 - 2 * u
    s00, s10, s01, s11 = 12 * u - 6, 6 * u - 4, -12 * u + 6, 6 * u - 2
    return (h00 * x0 + h10 * h * vx0 + h01 * x1 + h11 * h * vx1,
            h00 * y0 + h10 * h * vy0 + h01 * y1 + h11 * h * vy1,
            d00 * x0 + d10 * h * vx0 + d01 * x1 + d11 * h * vx1,
            d00 * y0 + d10 * h * vy0 + d01 * y1 + d11 * h * vy1,
            s00 * x0 + s10 * h * vx0 + s01 * x1 + s11 * h * vx1,
            s00 * y0 + s10 * h * vy0 + s01 * y1 + s11 * h * vy1)


@njit(cache=True)
def _hermite_distance(qx, qy, x0, y0, vx0, vy0, x1, y1, vx1, vy1, h, u):
    """Distance from ``(qx, qy)`` to the cubic Hermite curve of one interval at ``u`` in [0, 1]."""
    px, py, _, _, _, _ = _hermite_point(x0, y0, vx0, vy0, x1, y1, vx1, vy1, h, u)
    return math.hypot(px - qx, py - qy)


@njit(cache=True)
def _golden_distances(qx, qy, t, x, y, vx, vy, cand, best):
    """Lower ``best[i]`` to the least distance from point i to the interval ``cand[i]``.

    The interval ``(j, j + 1)`` of the samples is interpolated by the cubic Hermite curve of the
    positions and velocities. Its distance is minimised by golden-section search (24 iterations,
    to 1e-5 of the interval), then polished by Newton's method on the squared distance inside the
    final bracket. Every evaluated distance is a distance to the curve, so the least of them is an
    upper bound of the true one that only gets closer. Intervals out of range or of zero length
    are skipped.
    """
    g = (math.sqrt(5.0) - 1.0) / 2.0
    last = t.size - 2
    for i in range(qx.size):
        j = cand[i]
        if j < 0 or j > last or not t[j + 1] - t[j] > 0.0:
            continue
        k = j + 1
        h = t[k] - t[j]
        # The curve stays within |x_k - x_j| + 4/27 h (|v_j| + |v_k|) of x_j (the Hermite basis
        # functions of the velocities peak at 4/27): skip the interval if that cannot beat best.
        reach = math.hypot(x[k] - x[j], y[k] - y[j]) + 4.0 / 27.0 * h * (
            math.hypot(vx[j], vy[j]) + math.hypot(vx[k], vy[k]))
        if math.hypot(qx[i] - x[j], qy[i] - y[j]) - reach > best[i]:
            continue
        curve = (x[j], y[j], vx[j], vy[j], x[k], y[k], vx[k], vy[k], h)
        lo, hi = 0.0, 1.0
        c, d = hi - g * (hi - lo), lo + g * (hi - lo)
        fc, fd = _hermite_distance(qx[i], qy[i], *curve, c), _hermite_distance(qx[i], qy[i], *curve, d)
        for _ in range(24):
            if fc < fd:
                hi, d, fd = d, c, fc
                c = hi - g * (hi - lo)
                fc = _hermite_distance(qx[i], qy[i], *curve, c)
            else:
                lo, c, fc = c, d, fd
                d = lo + g * (hi - lo)
                fd = _hermite_distance(qx[i], qy[i], *curve, d)
        u = 0.5 * (lo + hi)
        dist = min(fc, fd)
        for _ in range(4):
            px, py, dx, dy, ddx, ddy = _hermite_point(*curve, u)
            ex, ey = px - qx[i], py - qy[i]
            dist = min(dist, math.hypot(ex, ey))
            slope = ex * dx + ey * dy
            curv = dx * dx + dy * dy + ex * ddx + ey * ddy
            if not curv > 0.0:
                break
            step = slope / curv
            if not lo <= u - step <= hi:
                break
            u -= step
            if step == 0.0:
                break
        dist = min(dist, _hermite_distance(qx[i], qy[i], *curve, u))
        best[i] = min(best[i], dist)


def figure_to_replay(points: np.ndarray, rep: Replay, rows: np.ndarray, params: SleighParams) -> np.ndarray:
    """Distance from target points (2, k) to the replayed path on ``rows`` of ``rep``.

    ``rows`` are indices of the replay's rows, increasing. The nearest dense
    sample is found with a k-d tree; the distance is then minimised over the cubic Hermite
    interpolant of the positions (velocities from the model) on the two adjacent sample intervals,
    by golden-section search (compiled), so the chord error of a polyline does not count.
    """
    # Chunks share their end instants: a repeated time carries the limits from the left and from the
    # right, and the blade's speed jumps there with the control rates (the momenta are continuous).
    # Both rows are kept, so each interval is interpolated with its own one-sided velocities. For
    # the nearest sample, the two proper intervals (of positive length) before it and the two after
    # it are searched, however many repeated rows lie between.
    sel = np.asarray(rows)
    if sel.dtype.kind not in "iu":
        raise TypeError(f"rows must be indices of the replay's rows (integers), got an array of {sel.dtype}")
    t = rep.t[sel]
    st = rep.state[:, sel]
    ctl = rep.controls[:, sel]
    _, xi2, _ = velocities(params, st[0], st[1], *ctl)
    vx, vy = xi2 * np.cos(st[2]), xi2 * np.sin(st[2])
    x, y = st[3], st[4]
    _, idx = cKDTree(np.vstack([x, y]).T).query(points.T)
    best = np.hypot(x[idx] - points[0], y[idx] - points[1])
    if t.size < 2:
        return best
    proper = distinct_steps(t)  # interval i = samples (i, i + 1)
    ids = np.arange(proper.size)
    # last proper interval ending at or before sample j, first one starting at or after it (-1 / size: none)
    prev_end = np.maximum.accumulate(np.where(proper, ids, -1))  # index <= i
    next_start = np.minimum.accumulate(np.where(proper, ids, proper.size)[::-1])[::-1]
    prev_end = np.concatenate([[-1], prev_end])  # for sample j: intervals with index <= j - 1
    next_start = np.concatenate([next_start, [proper.size]])  # for sample j: intervals with index >= j
    p1 = prev_end[idx]
    p2 = prev_end[np.maximum(p1, 0)]  # the one before (its end is at or before p1's start)
    n1 = next_start[idx]
    n2 = next_start[np.minimum(n1 + 1, proper.size)]
    for cand in (p2, p1, n1, n2):
        _golden_distances(points[0], points[1], t, x, y, vx, vy, cand, best)
    return best


def nearer_pieces(d: np.ndarray, pts: np.ndarray, pieces, samples) -> np.ndarray:
    """``d`` lowered, piece after piece, to the distance from ``pts`` to each placed piece where that is nearer.

    ``samples`` are 65 points along each piece. An arc's or a line's distance is closed-form and
    taken for every point. A spiral's takes Newton iterations, so it is computed only for the points
    that its bounding disc does not already rule out; those are looked up in a k-d tree of ``pts``,
    within the disc grown by the largest of ``d`` (no point farther can be nearer), so that a
    section of thousands of spirals costs in proportion to the points near each one rather than
    all of them for every spiral (nanosvg-drawing in exact mode, 7,916 spirals: its replay measured
    in 2.9 s instead of 11.7). The answer is the same as testing every point.
    """
    out = np.array(d, dtype=float)
    grow = float(out.max()) if out.size else 0.0
    tree = None
    for placed, xy in zip(pieces, samples):
        seg = placed.segment
        if seg.constant:
            out = np.minimum(out, distance_to_segment(pts, placed.start, seg))
            continue
        centre = xy.mean(axis=1)
        # chords of the 65-point sample lie within L^2 max|k| / (8 * 64^2) of the curve
        radius = float(np.max(np.hypot(xy[0] - centre[0], xy[1] - centre[1])))
        radius += seg.length**2 * seg.max_abs_curvature() / (8 * 64**2) + 1e-12 * seg.length
        if tree is None:
            tree = cKDTree(pts.T)
        # every point that the test below can accept, and more: the margin covers the tree's rounding
        ball = tree.query_ball_point(centre, (radius + grow) * (1.0 + 1e-9), return_sorted=True)
        cand = np.asarray(ball, dtype=np.intp)
        near = cand[np.hypot(pts[0, cand] - centre[0], pts[1, cand] - centre[1]) - radius < out[cand]]
        if near.size:
            out[near] = np.minimum(out[near], distance_to_segment(pts[:, near], placed.start, seg))
    return out
