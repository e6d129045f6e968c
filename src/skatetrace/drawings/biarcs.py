"""Biarcs: the pair of circular arcs through two points with given travel directions.

:func:`biarc` is G1 Hermite interpolation by two arcs (the equal-chord choice); :func:`_chain_poses`
lays a chain of arcs and lines out from a pose. Arc-spline fitting (:mod:`.fitting`) replaces each
stretch of curve by one biarc and certifies it (:mod:`.certify`).

References
----------
D. S. Meek, D. J. Walton, "Approximation of discrete data by G1 arc splines", Computer-Aided Design
(1992); "Approximating smooth planar curves by arc splines", J. Comput. Appl. Math. 59 (1995) 221-231;
"Spiral arc spline approximation to a planar spiral", J. Comput. Appl. Math. 107 (1999) 21-30 (ways
of choosing a biarc's free parameter).
"""

from __future__ import annotations

import math
from typing import Sequence

from .corners import _wrap
from ..errors import FitError
from ..figures.figure import MAX_LENGTH
from ..figures.geometry import Pose, Segment, advance

__all__ = ["biarc"]


def _biarc(x0: float, y0: float, h0: float, x1: float, y1: float, h1: float) -> tuple[Segment, ...] | None:
    """Equal-chord biarc from ``(x0, y0)`` heading ``h0`` to ``(x1, y1)`` heading ``h1``; ``None`` if undefined."""
    dx, dy = x1 - x0, y1 - y0
    d = math.hypot(dx, dy)
    if not (d > 0 and math.isfinite(d)):
        return None
    phi = math.atan2(dy, dx)
    alpha, beta = _wrap(h0 - phi), _wrap(h1 - phi)
    omega = 0.25 * (alpha - beta)
    cos_w = math.cos(omega)
    if cos_w < 1e-8:
        return None
    chord = 0.5 * d / cos_w
    segs = []
    for gamma in (-0.5 * (3 * alpha + beta), 0.5 * (alpha + 3 * beta)):
        half = 0.5 * gamma
        sinc = math.sin(half) / half if half != 0.0 else 1.0  # chord / length of the arc
        if sinc < 1e-8:
            return None
        segs.append(Segment(2.0 * math.sin(0.5 * gamma) / chord, chord / sinc))
    (k1, l1), (k2, l2) = segs
    if abs(k1 - k2) * (l1 + l2) ** 2 <= 1e-12 * (l1 + l2):
        k = (k1 * l1 + k2 * l2) / (l1 + l2)  # keeps the total turn, hence the end heading
        return (Segment(_straightened(k, l1 + l2), l1 + l2),)
    return tuple(Segment(_straightened(k, ln), ln) for k, ln in segs)


def _straightened(k: float, length: float) -> float:
    """``k``, or 0 (a line) where the arc turns by less than 1e-13 or its radius exceeds a figure's
    largest (:data:`~skatetrace.figures.figure.MAX_LENGTH`; a figure refuses such an arc)."""
    return 0.0 if abs(k) * length <= 1e-13 or abs(k) < 1.0 / MAX_LENGTH else k


def biarc(start: Pose, end: Pose) -> tuple[Segment, ...]:
    """The equal-chord biarc from ``start`` to ``end`` (G1 Hermite interpolation by two arcs).

    Parameters
    ----------
    start, end : Pose
        Points and travel directions (radians) to interpolate.

    Returns
    -------
    tuple of Segment
        Two segments, or one when both arcs lie on one circle (or line). Laid out from ``start`` with
        :func:`skatetrace.figures.geometry.advance` they end at ``end``.

    Raises
    ------
    FitError
        If the points coincide or the directions make the biarc unbounded (both pointing back along
        the chord).

    Notes
    -----
    The biarcs interpolating given G1 Hermite data form a one-parameter family; their join points lie
    on a circle through both end points. We take the join point where that circle crosses the
    perpendicular bisector of the chord, so both arcs have the same chord (the *equal-chord* biarc,
    one of the standard choices discussed by Meek & Walton). With the chord at angle phi and the end
    directions at ``alpha = h0 - phi`` and ``beta = h1 - phi`` (wrapped to ``(-pi, pi]``), the arcs
    turn by ``-(3 alpha + beta)/2`` and ``(alpha + 3 beta)/2``; both chords are ``d / (2 cos w)`` with
    ``w = (alpha - beta)/4``, so neither arc is ever shorter than half the chord ``d``. For data read
    from a circle the two arcs lie on that circle and are merged into one. Fitting does not rely on an
    a-priori error bound: every biarc's distance to the curve is certified numerically.

    Examples
    --------
    >>> segs = biarc(Pose(1.0, 0.0, math.pi / 2), Pose(0.0, 1.0, math.pi))   # a quarter of the unit circle
    >>> [(round(s.curvature, 12), round(s.length, 12)) for s in segs]
    [(1.0, 1.570796326795)]
    >>> [len(biarc(Pose(0.0, 0.0, 0.0), Pose(1.0, 1.0, a))) for a in (0.0, math.pi / 2)]
    [2, 1]
    """
    out = _biarc(float(start[0]), float(start[1]), float(start[2]), float(end[0]), float(end[1]), float(end[2]))
    if out is None:
        raise FitError(f"no bounded biarc from {tuple(start)} to {tuple(end)}: the points coincide or both "
                       "directions point back along the chord")
    return out


def _chain_poses(pose: Pose, segs: Sequence[Segment]) -> list[Pose]:
    """Start pose of each segment, and the end pose."""
    out = [pose]
    for k, L in segs:
        out.append(Pose(*(float(v) for v in advance(out[-1], k, L))))
    return out
