"""Plane curves made of circular arcs, straight lines and spirals.

A piece of constant signed curvature is a :class:`Segment` (``curvature`` 0 is a line, positive
turns left). A :class:`Spiral` is a piece whose curvature is a cubic polynomial of arc length (a
clothoid when it is linear); a drawing's smooth stretch traced in exact mode is a chain of them.
A :class:`Pose` is a point with a heading. :func:`travel` and :func:`distance_to_segment` take
either kind of piece. Nothing here knows about mechanics.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from scipy.spatial import cKDTree

from .spiral_paths import cell_nodes, foot_points, positions

__all__ = ["Pose", "Segment", "Spiral", "advance", "travel", "segment_points", "distance_to_segment",
           "rigid_motion_centre", "shifted_polynomial", "cubic_at"]

_CELL_TURN = 0.2  # largest heading change (radians) over one quadrature cell of a spiral


class Pose(NamedTuple):
    """Position ``(x, y)`` and heading (radians, counter-clockwise from the x axis)."""

    x: float
    y: float
    heading: float


class Segment(NamedTuple):
    """An arc (``curvature != 0``) or a line (``curvature == 0``) of positive ``length``."""

    curvature: float
    length: float

    @property
    def turn(self) -> float:
        """Signed change of heading along the segment (radians)."""
        return self.curvature * self.length

    @property
    def coefficients(self) -> tuple[float, float, float, float]:
        """Curvature as a cubic of arc length from the start (constant here)."""
        return (float(self.curvature), 0.0, 0.0, 0.0)

    @property
    def constant(self) -> bool:
        return True

    def curvature_at(self, sigma) -> np.ndarray:
        """Curvature at arc length ``sigma`` from the start (array of the shape of ``sigma``)."""
        return np.full_like(np.asarray(sigma, dtype=float), self.curvature)

    def part(self, s0: float, s1: float) -> "Segment":
        """The stretch from ``s0`` to ``s1`` (arc lengths from the start)."""
        return Segment(self.curvature, s1 - s0)


class Spiral(NamedTuple):
    """A piece whose curvature is a cubic polynomial of arc length ``sigma`` from its start::

        kappa(sigma) = c0 + c1 sigma + c2 sigma^2 + c3 sigma^3,   0 <= sigma <= length

    ``coefficients`` is ``(c0, c1, c2, c3)``. The heading is then a quartic in ``sigma`` and the
    position its Fresnel-type integral, evaluated by Gauss-Legendre quadrature on cells over which
    the heading turns by at most 0.2 rad (accurate to rounding).
    """

    coefficients: tuple[float, float, float, float]
    length: float

    @property
    def constant(self) -> bool:
        return not any(self.coefficients[1:])

    def curvature_at(self, sigma) -> np.ndarray:
        return cubic_at(self.coefficients, np.asarray(sigma, dtype=float))

    def heading_change(self, sigma) -> np.ndarray:
        """Turn of the heading from the start to ``sigma`` (the integral of the curvature)."""
        c0, c1, c2, c3 = self.coefficients
        sigma = np.asarray(sigma, dtype=float)
        return sigma * (c0 + sigma * (c1 / 2.0 + sigma * (c2 / 3.0 + sigma * c3 / 4.0)))

    @property
    def turn(self) -> float:
        return float(self.heading_change(self.length))

    @property
    def start_curvature(self) -> float:
        return float(self.coefficients[0])

    @property
    def end_curvature(self) -> float:
        return float(self.curvature_at(self.length))

    def max_abs_curvature(self) -> float:
        """Largest ``|kappa|`` on the piece (at the ends or a stationary point of the cubic)."""
        c0, c1, c2, c3 = self.coefficients
        cand = [0.0, self.length]
        # stationary points: roots of 3 c3 x^2 + 2 c2 x + c1
        if c3 != 0.0:
            disc = c2 * c2 - 3.0 * c1 * c3
            if disc >= 0.0:
                q = -(c2 + math.copysign(math.sqrt(disc), c2))  # stable quadratic roots
                cand += [q / (3.0 * c3)] + ([c1 / q] if q != 0.0 else [])
        elif c2 != 0.0:
            cand.append(-c1 / (2.0 * c2))
        return max(abs(float(self.curvature_at(x))) for x in cand if 0.0 <= x <= self.length)

    def part(self, s0: float, s1: float) -> "Spiral":
        """The stretch from ``s0`` to ``s1`` (arc lengths from the start), coefficients re-expanded."""
        return Spiral(shifted_polynomial(self.coefficients, s0, 1.0), s1 - s0)


def cubic_at(coefficients, x):
    """``c0 + c1 x + c2 x^2 + c3 x^3`` by Horner's rule, for a number or an array ``x``."""
    c0, c1, c2, c3 = coefficients
    return c0 + x * (c1 + x * (c2 + x * c3))


def shifted_polynomial(coefficients, origin: float, sign: float) -> tuple[float, ...]:
    """Coefficients of ``q(x) = p(origin + sign * x)`` for ``p(x) = sum c_k x^k``."""
    c = [float(v) for v in coefficients]
    n = len(c)
    out = [0.0] * n
    for k in range(n):
        # p^(k)(origin) / k! * sign^k
        acc = 0.0
        for j in range(k, n):
            acc += math.comb(j, k) * c[j] * origin ** (j - k)
        out[k] = acc * sign**k
    return tuple(out)


def _cells(spiral: Spiral) -> int:
    """Number of equal cells of ``spiral`` over which the heading turns by at most ``_CELL_TURN``."""
    return max(1, math.ceil(spiral.max_abs_curvature() * spiral.length / _CELL_TURN))


def _spiral_path(pose: Pose, spiral: Spiral):
    """``s -> (x, y, heading)`` along ``spiral`` laid out from ``pose``, for 1-D arrays ``s``.

    The positions of the cell boundaries (:func:`~skatetrace.figures.spiral_paths.cell_nodes`) are
    integrated once, here, and each query from the nearest of them (at most half a cell away): a
    search that travels along the same spiral again and again (Newton's method on a foot point)
    pays for them once. Returns the function and the compiled path's arguments (for
    :func:`~skatetrace.figures.spiral_paths.foot_points`).
    """
    c = np.array(spiral.coefficients, dtype=float)
    length, n, heading = float(spiral.length), _cells(spiral), float(pose[2])
    node_x, node_y = cell_nodes(c, length, n, float(pose[0]), float(pose[1]), heading)
    args = (c, length, n, heading, node_x, node_y)

    def at(s: np.ndarray):
        return positions(*args, np.ascontiguousarray(s, dtype=float))

    return at, args


def travel(pose: Pose, piece, s):
    """Pose reached after travelling ``s`` (scalar or array) along ``piece`` (a Segment or a Spiral).

    Returns ``(x, y, heading)`` with the shape of ``s``.
    """
    if isinstance(piece, Spiral):
        s = np.asarray(s, dtype=float)
        x, y, th = _spiral_path(pose, piece)[0](s.ravel())
        return x.reshape(s.shape), y.reshape(s.shape), th.reshape(s.shape)
    return advance(pose, piece.curvature, s)


def end_pose(pose: Pose, piece) -> Pose:
    """Pose at the end of ``piece`` laid out from ``pose``."""
    return Pose(*(float(v) for v in travel(pose, piece, piece.length)))


def advance(pose: Pose, curvature: float, s):
    """Pose reached after travelling ``s`` (scalar or array) along a curve of ``curvature``.

    Returns ``(x, y, heading)`` with the shape of ``s``.
    """
    s = np.asarray(s, dtype=float)
    x0, y0, th0 = pose
    th = th0 + curvature * s
    if curvature == 0.0:
        return x0 + s * math.cos(th0), y0 + s * math.sin(th0), th
    # Chord formulas are exact and well conditioned for small curvature * s.
    half = 0.5 * curvature * s
    chord = s * np.sinc(half / math.pi)
    mid = th0 + half
    return x0 + chord * np.cos(mid), y0 + chord * np.sin(mid), th


def segment_points(pose: Pose, segment, n: int = 200) -> np.ndarray:
    """``n`` points along a segment or spiral, shape ``(2, n)``."""
    x, y, _ = travel(pose, segment, np.linspace(0.0, segment.length, n))
    return np.vstack([x, y])


def distance_to_segment(points, pose: Pose, segment) -> np.ndarray:
    """Euclidean distance from each of ``points`` (shape ``(2, n)``) to a segment or a spiral.

    Exact (closed form) for arcs and lines. For a spiral: the nearest of a dense sample, refined
    by Newton's method on the foot point (accurate to rounding).
    """
    if isinstance(segment, Spiral):
        return _distance_to_spiral(np.asarray(points, dtype=float), pose, segment)
    px, py = np.asarray(points, dtype=float)
    x0, y0, th0 = pose
    k, L = segment
    ex, ey = advance(pose, k, L)[:2]
    to_ends = np.minimum(np.hypot(px - x0, py - y0), np.hypot(px - float(ex), py - float(ey)))
    if k == 0.0:
        t = (px - x0) * math.cos(th0) + (py - y0) * math.sin(th0)
        n = -(px - x0) * math.sin(th0) + (py - y0) * math.cos(th0)
        return np.where((t >= 0) & (t <= L), np.abs(n), to_ends)
    r = 1.0 / abs(k)
    cx, cy = x0 - math.sin(th0) / k, y0 + math.cos(th0) / k
    # Angle swept from the start to the point's radial direction, in the direction of travel.
    start = math.atan2(y0 - cy, x0 - cx)
    ang = np.arctan2(py - cy, px - cx)
    swept = np.mod((ang - start) * math.copysign(1.0, k), 2 * math.pi)
    inside = swept <= abs(k) * L
    return np.where(inside, np.abs(np.hypot(px - cx, py - cy) - r), to_ends)


def _distance_to_spiral(points: np.ndarray, pose: Pose, spiral: Spiral) -> np.ndarray:
    L = spiral.length
    if points.shape[1] == 0:
        return np.zeros(0)
    # Samples closer than a quarter of the smallest radius of curvature keep the nearest sample
    # inside the basin of the true foot point.
    kmax = spiral.max_abs_curvature()
    n = int(min(max(65, math.ceil(4.0 * kmax * L) * 8 + 1), 20001))
    sig = np.linspace(0.0, L, n)
    path, args = _spiral_path(pose, spiral)  # its cells integrated once for the search below
    x, y, _ = path(sig)
    _, idx = cKDTree(np.column_stack([x, y])).query(points.T)
    px, py = np.ascontiguousarray(points[0]), np.ascontiguousarray(points[1])
    t = foot_points(*args, px, py, sig[idx], L / (n - 1), 8)
    fx, fy, _ = path(t)
    d = np.hypot(fx - px, fy - py)
    return np.minimum(d, np.hypot(x[idx] - px, y[idx] - py))


def rigid_motion_centre(start: Pose, end: Pose) -> tuple[float, float] | None:
    """Fixed point of the plane rigid motion that takes ``start`` to ``end``.

    Returns ``None`` when the motion is a pure translation (no rotation).
    """
    phi = math.remainder(end.heading - start.heading, 2 * math.pi)
    if abs(phi) < 1e-12:
        return None
    # end = R(phi) (start - c) + c  =>  (I - R) c = end - R start
    c, s = math.cos(phi), math.sin(phi)
    bx = end.x - (c * start.x - s * start.y)
    by = end.y - (s * start.x + c * start.y)
    a11, a12, a21, a22 = 1 - c, s, -s, 1 - c
    det = a11 * a22 - a12 * a21
    return ((a22 * bx - a12 * by) / det, (-a21 * bx + a11 * by) / det)
