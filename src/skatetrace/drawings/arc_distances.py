"""Exact distances to arcs and lines, well conditioned however large the radius.

From points to one segment or a chain of them (:func:`_seg_dist`, :func:`_chain_dist`), and the
pieces the certificate (:mod:`.certify`) builds on: coordinates in a segment's frame
(:func:`_local`), the signed distance to its circle (:func:`_phi`), its exact maximum over a chord
(:func:`_chord_max`) and the angle a point has swept round the centre (:func:`_swept`). Every
formula is multiplied through by ``|k|`` so that nothing cancels when ``k`` is tiny; a line is
``k = 0``, never a special radius.
"""

from __future__ import annotations

import math
from typing import Sequence

import numpy as np

from ..figures.geometry import Pose, Segment, advance

__all__: list[str] = []

_TWO_PI = 2.0 * math.pi


def _seg_dist(pts: np.ndarray, pose: Pose, k: float, L: float) -> np.ndarray:
    """Exact distance from points (shape ``(2, n)``) to an arc or a line, well conditioned for tiny ``k``.

    Same result as :func:`skatetrace.figures.geometry.distance_to_segment`, which goes through the centre and
    loses all digits when the radius dwarfs the distances (``k`` of 1e-14 on a unit drawing).
    """
    x0, y0, th = pose
    c, s = math.cos(th), math.sin(th)
    dx, dy = pts[0] - x0, pts[1] - y0
    u, v = c * dx + s * dy, -s * dx + c * dy
    ex, ey, _ = advance(pose, k, L)
    ends = np.minimum(np.hypot(dx, dy), np.hypot(pts[0] - float(ex), pts[1] - float(ey)))
    if k == 0.0:
        return np.where((u >= 0) & (u <= L), np.abs(v), ends)
    ak, w = abs(k), math.copysign(1.0, k) * v
    swept = np.mod(np.arctan2(ak * u, 1.0 - ak * w), _TWO_PI)
    rho = np.hypot(ak * u, 1.0 - ak * w)  # |k| times the distance to the centre
    radial = np.abs(ak * (u * u + w * w) - 2.0 * w) / (rho + 1.0)
    return np.where(swept <= ak * L, radial, ends)


def _chain_dist(pts: np.ndarray, poses: Sequence[Pose], segs: Sequence[Segment]) -> tuple[np.ndarray, np.ndarray]:
    """Exact distance from points (shape ``(2, n)``) to a chain of segments starting at ``poses``, and the
    index of the nearest segment."""
    d = np.vstack([_seg_dist(pts, p, k, L) for p, (k, L) in zip(poses, segs)])
    idx = np.argmin(d, axis=0)
    return d[idx, np.arange(d.shape[1])], idx


def _local(pose: Pose, k: float, x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Coordinates of points in a segment's start frame: ``u`` along the heading, ``w`` towards the centre."""
    c, s = math.cos(pose[2]), math.sin(pose[2])
    dx, dy = x - pose[0], y - pose[1]
    v = -s * dx + c * dy
    return c * dx + s * dy, (-v if k < 0 else v)


def _phi(ak: float, u: np.ndarray, w: np.ndarray) -> np.ndarray:
    """Signed distance to the circle (positive outside), or minus the signed distance to the line if ``ak == 0``.

    ``(|p - c|^2 - r^2) / (|p - c| + r)`` multiplied through by ``|k|``: no cancellation for huge radii.
    """
    return (ak * (u * u + w * w) - 2.0 * w) / (np.hypot(ak * u, 1.0 - ak * w) + 1.0)


def _chord_max(ak: float, u0, w0, u1, w1) -> np.ndarray:
    """Exact maximum over each chord ``[q0, q1]`` of the distance to a circle (or line).

    The signed distance ``|q - c| - r`` is convex along a segment: its maximum is at an end, its minimum
    at the point of the segment nearest the centre.
    """
    p0, p1 = _phi(ak, u0, w0), _phi(ak, u1, w1)
    lo = np.minimum(p0, p1)
    if ak > 0:
        du, dw = u1 - u0, w1 - w0
        with np.errstate(all="ignore"):
            lam = (-u0 * du * ak + (1.0 - ak * w0) * dw) / (ak * (du * du + dw * dw))
        lam = np.clip(np.nan_to_num(lam, nan=0.0, posinf=1.0, neginf=0.0), 0.0, 1.0)
        lo = np.minimum(lo, _phi(ak, u0 + lam * du, w0 + lam * dw))
    return np.maximum(np.maximum(p0, p1), -lo)


def _swept(ak: float, u: np.ndarray, w: np.ndarray) -> np.ndarray:
    """Angle turned from the segment's start to a point's radial direction, in ``(-pi, pi]``; ``u`` on a line."""
    return np.arctan2(ak * u, 1.0 - ak * w) if ak > 0 else u
