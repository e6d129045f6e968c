"""Plane curves made of circular arcs and straight lines.

A piece of constant signed curvature is a :class:`Segment` (``curvature`` 0 is a line, positive
turns left). A :class:`Pose` is a point with a heading. Nothing here knows about mechanics.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

__all__ = ["Pose", "Segment", "advance", "segment_points", "distance_to_segment", "rigid_motion_centre"]


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


def segment_points(pose: Pose, segment: Segment, n: int = 200) -> np.ndarray:
    """``n`` points along a segment, shape ``(2, n)``."""
    x, y, _ = advance(pose, segment.curvature, np.linspace(0.0, segment.length, n))
    return np.vstack([x, y])


def distance_to_segment(points, pose: Pose, segment: Segment) -> np.ndarray:
    """Exact Euclidean distance from each of ``points`` (shape ``(2, n)``) to a segment."""
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
