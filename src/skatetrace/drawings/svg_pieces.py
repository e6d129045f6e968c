"""One SVG segment (svgelements') as a piece: exact lines, Béziers and elliptical arcs under the drawing's map.

:func:`svg_piece` turns a segment of a shape or of path data into a
:class:`~skatetrace.drawings.curves.Piece` under the affine map ``x -> A x + b`` (the element's
transforms and the y flip): lines and Béziers by their mapped control points, elliptical arcs
exactly (:func:`_arc_geometry`, :func:`_arc_piece`). :mod:`.svg` reads the file and assembles the
pieces into paths.
"""

from __future__ import annotations

import math

import numpy as np
import svgelements as se

from .curves import BezierPiece, EllipticArcPiece, LinePiece, Piece
from .lengths import MAX_COORD
from ..errors import DrawingError

__all__ = ["SAMPLES", "same_point", "segment_points", "is_zero_length", "svg_piece", "segment_notes"]

SAMPLES = np.linspace(0.0, 1.0, 17)
"""Where a piece is checked for finite, representable values."""


def segment_points(segment) -> list:
    """The defining points of a segment (an arc's start, end, centre and axis points)."""
    if isinstance(segment, se.Move):
        return [segment.end]
    if isinstance(segment, se.CubicBezier):
        return [segment.start, segment.control1, segment.control2, segment.end]
    if isinstance(segment, se.QuadraticBezier):
        return [segment.start, segment.control, segment.end]
    if isinstance(segment, se.Arc) and not hasattr(segment, "svg_parameters"):
        return [segment.start, segment.end, segment.center, segment.prx, segment.pry]
    return [segment.start, segment.end]


def _xy(A: np.ndarray, b: np.ndarray, point) -> tuple[float, float]:
    p = A @ np.array([float(point[0]), float(point[1])]) + b
    return float(p[0]) + 0.0, float(p[1]) + 0.0  # + 0.0: no -0.0 from the y flip


def same_point(p, q) -> bool:
    """Exactly the same point (svgelements' own ``==`` allows 1e-12)."""
    return float(p[0]) == float(q[0]) and float(p[1]) == float(q[1])


def _arc_geometry(arc) -> tuple[np.ndarray, float, float, float, float, float] | None:
    """``(c, rx, ry, phi, t0, dt)`` of an arc: ``point(s) = c + R(phi) (rx cos t, ry sin t)``,
    ``t = t0 + s dt``; None for a zero radius (SVG draws a straight line).

    From path data: the endpoint-to-centre conversion of SVG's implementation notes, with the
    radii scaled up to fit exactly when they are too small (then the centre is the midpoint of the
    chord, exactly). From svgelements' shapes (rounded rects, circles, ellipses): its centre and
    axis points, both ends' parameters from ``atan2`` in the ellipse's frame and the sweep within a
    turn of svgelements' (which fixes direction and size).
    """
    start = np.array([float(arc.start[0]), float(arc.start[1])])
    end = np.array([float(arc.end[0]), float(arc.end[1])])
    if hasattr(arc, "svg_parameters"):
        rx, ry, rotation, large, sweep = arc.svg_parameters
        rx, ry = abs(float(rx)), abs(float(ry))
        if rx == 0 or ry == 0:
            return None
        phi = math.radians(float(rotation) % 360.0)
        cos, sin = math.cos(phi), math.sin(phi)
        dx, dy = (start - end) / 2
        xp, yp = cos * dx + sin * dy, -sin * dx + cos * dy
        lam = (xp / rx) ** 2 + (yp / ry) ** 2
        if lam >= 1:
            rx, ry, co = rx * math.sqrt(lam), ry * math.sqrt(lam), 0.0
        else:
            co = math.sqrt(1.0 - lam) / math.sqrt(lam) if lam > 0 else math.inf
            co = -co if bool(large) == bool(sweep) else co
        cxp, cyp = co * rx * yp / ry, -co * ry * xp / rx
        c = np.array([cos * cxp - sin * cyp, sin * cxp + cos * cyp]) + (start + end) / 2
        t0 = math.atan2((yp - cyp) / ry, (xp - cxp) / rx)
        dt = math.atan2((-yp - cyp) / ry, (-xp - cxp) / rx) - t0
        if sweep and dt < 0:
            dt += 2 * math.pi
        elif not sweep and dt > 0:
            dt -= 2 * math.pi
        return c, rx, ry, phi, t0, dt
    c = np.array([float(arc.center[0]), float(arc.center[1])])
    u = np.array([float(arc.prx[0]), float(arc.prx[1])]) - c
    v = np.array([float(arc.pry[0]), float(arc.pry[1])]) - c
    rx, ry, phi = float(np.hypot(*u)), float(np.hypot(*v)), math.atan2(u[1], u[0])
    if rx == 0 or ry == 0:
        return None
    e, n = np.array([math.cos(phi), math.sin(phi)]), np.array([-math.sin(phi), math.cos(phi)])
    t0, t1 = (math.atan2(float((p - c) @ n) / ry, float((p - c) @ e) / rx) for p in (start, end))
    dt = t1 - t0
    dt += 2 * math.pi * round((float(arc.sweep) - dt) / (2 * math.pi))
    return c, rx, ry, phi, t0, dt


def _arc_piece(arc, geometry, A: np.ndarray, b: np.ndarray, where: str) -> EllipticArcPiece:
    """The exact image under ``x -> A x + b`` of an arc of :func:`_arc_geometry`.

    The arc is ``point(t) = c + R(phi) (rx cos t, ry sin t)``, ``t`` from ``t0`` by ``dt``. The image
    is ``A c + b + M (cos t, sin t)`` with ``M = A R(phi) diag(rx, ry)``. Write ``M = U S V^T`` with
    ``U`` and ``V`` rotations (the reflection, if any, goes into the sign ``s`` of the second
    singular value); then ``V^T (cos t, sin t) = (cos(t - a), sin(t - a))`` and a negative second
    radius is the same ellipse run with the angle negated.
    """
    c, rx, ry, phi, t0, dt = geometry
    if not all(math.isfinite(v) for v in (*c, rx, ry, phi, t0, dt)):
        ends = f"{_xy(np.eye(2), np.zeros(2), arc.start)} to {_xy(np.eye(2), np.zeros(2), arc.end)}"
        raise DrawingError(f"{where}: the elliptical arc from {ends} cannot be evaluated in double precision "
                           "(it has no finite centre and radii): give it radii of a size comparable to the distance "
                           "between its end points")
    R = np.array([[math.cos(phi), -math.sin(phi)], [math.sin(phi), math.cos(phi)]])
    M = A @ R @ np.diag([rx, ry])
    if not np.all(np.isfinite(M)):
        raise DrawingError(f"{where}: an elliptical arc's radii overflow under its transform; rescale the drawing")
    U, singular, Vt = np.linalg.svd(M)
    su, sv = np.sign(np.linalg.det(U)), np.sign(np.linalg.det(Vt))
    U = U @ np.diag([1.0, su])
    Vt = np.diag([1.0, sv]) @ Vt
    sign = float(su * sv)
    alpha = math.atan2(Vt[0, 1], Vt[0, 0])
    return EllipticArcPiece(
        centre=_xy(A, b, c), rx=float(singular[0]), ry=float(singular[1]),
        rotation=math.atan2(U[1, 0], U[0, 0]), theta0=sign * (t0 - alpha), dtheta=sign * dt,
    )


def is_zero_length(segment) -> bool:
    points = segment_points(segment)[:2] if isinstance(segment, se.Arc) else segment_points(segment)
    return all(same_point(q, points[0]) for q in points)


def _is_flat_arc(segment) -> bool:
    """An arc with a zero radius: SVG draws a straight line."""
    if not isinstance(segment, se.Arc):
        return False
    try:
        return _arc_geometry(segment) is None
    except (ArithmeticError, ValueError, TypeError):
        return False


def svg_piece(segment, A: np.ndarray, b: np.ndarray, where: str) -> Piece:
    def finite(points) -> bool:
        return all(math.isfinite(float(q[0])) and math.isfinite(float(q[1])) for q in points)

    given = segment_points(segment)
    if not finite(given):
        raise DrawingError(f"{where}: non-finite coordinates (NaN or infinity); check the numbers in its path data")
    with np.errstate(all="ignore"):  # overflow shows up as non-finite samples, checked next
        if isinstance(segment, se.Linear) or _is_flat_arc(segment):
            piece = LinePiece(_xy(A, b, segment.start), _xy(A, b, segment.end))
        elif isinstance(segment, (se.QuadraticBezier, se.CubicBezier)):
            piece = BezierPiece(tuple(_xy(A, b, q) for q in given))
        else:
            piece = _arc_piece(segment, _arc_geometry(segment), A, b, where)
        _check_samples(piece, where)
    return piece


def segment_notes(segment, label: str):
    """Notes on Bézier handles of zero length (the derivative vanishes at that end) and zero radii."""
    if isinstance(segment, (se.QuadraticBezier, se.CubicBezier)):
        p = segment_points(segment)
        kind = "cubic" if len(p) == 4 else "quadratic"
        for end, (a, c) in (("start (t=0)", (p[0], p[1])), ("end (t=1)", (p[-1], p[-2]))):
            if same_point(a, c):
                yield (f"{label}: {kind} Bézier with a zero-length handle at its {end}: its derivative "
                       "vanishes there and the tangent is only the limit direction")
    elif _is_flat_arc(segment):
        yield f"{label}: an elliptical arc with a zero radius is a straight line (as SVG draws it)"


def _check_samples(piece: Piece, where: str) -> None:
    with np.errstate(all="ignore"):
        values = np.hstack([piece.point(SAMPLES), piece.d1(SAMPLES), piece.d2(SAMPLES)])
    if not np.all(np.isfinite(values)):
        raise DrawingError(f"{where}: non-finite coordinates (NaN or infinity); check the numbers in its path data "
                           "and transforms")
    largest = float(np.abs(values[:, : SAMPLES.size]).max())
    if largest > MAX_COORD:
        raise DrawingError(f"{where}: coordinates reach {largest:.3g}, beyond the supported {MAX_COORD:.0e}: "
                           "rescale the drawing")
