"""The paper's general deviation cost C, its equation (C_control).

A simulated path ``(x_s, y_s)`` is re-parametrised by its own arc length and compared with the
target curve ``(X(s), Y(s))`` at equal arc length from their starts::

    C = integral_0^S |x_s(s) - X(s)|^p + |y_s(s) - Y(s)|^p ds,   S = min(S_s, S_d),  p > 1.

It scores a whole trajectory against a target, including drift along the curve (a path that runs
along the right circle at the wrong place scores badly), which a distance-to-curve measure does not.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable, Sequence

import numpy as np

from ..figures.geometry import Pose, Segment, advance

__all__ = ["DeviationCost", "deviation_cost", "segments_target"]

Target = Callable[[np.ndarray], np.ndarray]


@dataclass(frozen=True, slots=True, kw_only=True)
class DeviationCost:
    """Value of C and what it was computed over.

    Attributes
    ----------
    value : float
        C itself.
    p : float
    compared_length : float
        ``S = min(S_s, S_d)``.
    path_length, target_length : float
        ``S_s`` and ``S_d``.
    max_distance : float
        Largest pointwise distance ``|(x_s, y_s)(s) - (X, Y)(s)|`` over ``[0, S]``.
    """

    value: float
    p: float
    compared_length: float
    path_length: float
    target_length: float
    max_distance: float


def segments_target(start: Pose, segments: Sequence[Segment]) -> tuple[Target, float]:
    """Target ``s -> (X(s), Y(s))`` for arcs and lines joined smoothly from ``start``, and its length.

    Examples
    --------
    >>> X, L = segments_target(Pose(0.0, -1.0, 0.0), [Segment(1.0, math.pi)])
    >>> np.round(X(np.array([0.0, L])), 12) + 0.0
    array([[ 0.,  0.],
           [-1.,  1.]])
    """
    segs = [Segment(float(k), float(L)) for k, L in segments]
    if not segs or any(not (s.length > 0) for s in segs):
        raise ValueError("a target needs at least one segment, each of positive length")
    poses, pose = [], start
    for s in segs:
        poses.append(pose)
        x, y, th = advance(pose, s.curvature, s.length)
        pose = Pose(float(x), float(y), float(th))
    ends = np.cumsum([s.length for s in segs])

    def X(s: np.ndarray) -> np.ndarray:
        s = np.asarray(s, dtype=float)
        idx = np.clip(np.searchsorted(ends, s, side="left"), 0, len(segs) - 1)
        out = np.empty((2, s.size))
        for i, (seg, p0) in enumerate(zip(segs, poses)):
            m = idx == i
            if np.any(m):
                local = s[m] - (ends[i] - seg.length)
                x, y, _ = advance(p0, seg.curvature, local)
                out[0, m], out[1, m] = x, y
        return out

    return X, float(ends[-1])


def deviation_cost(path, target: Target, target_length: float, *, p: float = 2.0,
                   samples: int = 4001) -> DeviationCost:
    """C of a simulated path against a target curve, the paper's equation (C_control).

    Parameters
    ----------
    path : array_like, shape (2, n)
        Points of the simulated curve in the order travelled, dense enough that chords follow
        the curve (their summed length is taken as the arc length).
    target : callable
        ``target(s)`` for an array of arc lengths returns points of shape ``(2, len(s))``; see
        :func:`segments_target`.
    target_length : float
        ``S_d``.
    p : float
        Exponent, ``p > 1`` as in the paper.
    samples : int
        Quadrature points on ``[0, S]`` (trapezoidal rule).

    Returns
    -------
    DeviationCost

    Examples
    --------
    >>> X, L = segments_target(Pose(0.0, 0.0, 0.0), [Segment(0.0, 2.0)])
    >>> path = np.vstack([np.linspace(0, 2, 50), np.full(50, 0.1)])  # a parallel line 0.1 away
    >>> round(deviation_cost(path, X, L).value, 12)  # 0.1^2 over length 2
    0.02
    """
    pts = np.asarray(path, dtype=float)
    if pts.ndim != 2 or pts.shape[0] != 2 or pts.shape[1] < 2:
        raise ValueError(f"path must have shape (2, n) with n >= 2, got {pts.shape}")
    if not np.all(np.isfinite(pts)):
        raise ValueError("path has non-finite points: the simulation broke down; C is undefined")
    if not (p > 1 and math.isfinite(p)):
        raise ValueError(f"p must be a finite number > 1 (the paper's p > 1), got {p!r}")
    if not (target_length > 0 and math.isfinite(target_length)):
        raise ValueError(f"target_length must be positive and finite, got {target_length!r}")
    seg = np.hypot(np.diff(pts[0]), np.diff(pts[1]))
    s_path = np.concatenate([[0.0], np.cumsum(seg)])
    S_s = float(s_path[-1])
    S = min(S_s, float(target_length))
    if S <= 0.0:
        return DeviationCost(value=0.0, p=p, compared_length=0.0, path_length=S_s, target_length=target_length,
                             max_distance=float(np.hypot(*(pts[:, 0] - target(np.zeros(1))[:, 0]))))
    s = np.linspace(0.0, S, int(samples))
    xs = np.interp(s, s_path, pts[0])
    ys = np.interp(s, s_path, pts[1])
    T = target(s)
    dx, dy = np.abs(xs - T[0]), np.abs(ys - T[1])
    integrand = dx ** p + dy ** p
    value = float(np.sum(0.5 * (integrand[1:] + integrand[:-1]) * np.diff(s)))
    return DeviationCost(value=value, p=p, compared_length=S, path_length=S_s, target_length=float(target_length),
                         max_distance=float(np.max(np.hypot(dx, dy))))
