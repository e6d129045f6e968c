"""Specks: paths too small to trace as drawn, traced as the circle they lie close to.

At skater scale an illustration's highlight or stray dot is a path of a millimetre or two whose
stretches between corners are fractions of a millimetre: sections started and stopped within them.
Absorbing its tiny pieces into their neighbours (:meth:`~skatetrace.drawings.curves.Drawing.absorbed`)
cannot help a path made of nothing else. Such a path, within :data:`SPECK_RADIUS` tolerances of its
centre and within a share of the tolerance of a circle (a certified Hausdorff bound,
:mod:`.certify`), is traced as that circle: a closed smooth loop, which needs no rest. Its fit is
the circle itself, two half arcs, and its bound is the circle's distance to the path as drawn.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
from scipy.optimize import minimize_scalar
from scipy.spatial import cKDTree

from .certify import _certify
from .curves import Drawing, Path, piece_length
from .fit_results import FitStatus, FittedRun, PathFit
from ..figures.geometry import Pose, Segment

__all__ = ["Speck", "SPECK_RADIUS", "speck_circle", "speck_fit", "find_specks"]

#: A path is a speck only if every point of it lies within this many tolerances of its centre.
SPECK_RADIUS = 2.0
#: Samples a piece when choosing the circle (the certificate samples on its own).
_SAMPLES = 129
#: Smallest circle tried, as a share of the path's radius (a dash's best circle has half of it).
_LEAST_RADIUS = 0.25


@dataclass(frozen=True, slots=True, kw_only=True)
class Speck:
    """A path replaced by a circle.

    Attributes
    ----------
    centre : (float, float)
    radius : float
    bound : float
        Certified upper bound of the Hausdorff distance between the circle and the path.
    sampled : float
        Largest sampled distance between them (a lower bound of it).
    clockwise : bool
        The circle's direction of travel: the path's, by the sign of the area it encloses (closed
        at its ends if open).
    start : float
        Angle (radians) of the circle's start about its centre: towards the path's start.
    """

    centre: tuple[float, float]
    radius: float
    bound: float
    sampled: float
    clockwise: bool
    start: float

    def pose(self) -> Pose:
        """The circle's start point and heading."""
        x = self.centre[0] + self.radius * math.cos(self.start)
        y = self.centre[1] + self.radius * math.sin(self.start)
        return Pose(x, y, self.start + (-0.5 if self.clockwise else 0.5) * math.pi)

    def segments(self) -> tuple[Segment, Segment]:
        """The circle as two half arcs (an arc of a certificate sweeps less than a full turn)."""
        half = Segment((-1.0 if self.clockwise else 1.0) / self.radius, math.pi * self.radius)
        return half, half


def _spread(points: np.ndarray, tree: cKDTree, centre: np.ndarray, dist: np.ndarray, r: float) -> float:
    """Largest sampled distance between the circle of radius ``r`` about ``centre`` and the sampled path.

    The path's samples to the circle, and points of the circle (spaced a tenth of the path's radius or
    closer) to their nearest path sample: an estimate, to choose the radius; the certificate follows.
    """
    theta = np.linspace(0.0, 2.0 * math.pi, max(64, int(20 * math.pi * r / max(float(np.max(dist)), 1e-300))),
                        endpoint=False)
    ring = centre[:, None] + r * np.vstack([np.cos(theta), np.sin(theta)])
    return max(float(np.max(np.abs(dist - r))), float(np.max(tree.query(ring.T)[0])))


def speck_circle(path: Path, tol: float, limit: float) -> Speck | None:
    """The circle ``path`` is traced as, if it is a speck for the tolerance ``tol``; else None.

    A speck lies within ``SPECK_RADIUS * tol`` of its bounding box's centre and within ``limit``
    (certified) of a circle about that centre. The radius, between a quarter of the path's and all
    of it, is the one of least sampled distance (a grid, then a bounded search beside its best).

    Parameters
    ----------
    path : Path
    tol : float
        The fit's tolerance, in the path's units.
    limit : float
        Largest Hausdorff distance allowed between the path and its circle.

    Examples
    --------
    >>> from skatetrace.drawings.curves import LinePiece
    >>> dash = Path((LinePiece((0.0, 0.0), (1.0, 0.0)),))
    >>> speck = speck_circle(dash, 1.0, 0.5)
    >>> round(speck.radius, 3), speck.bound <= 0.5, speck.centre
    (0.25, True, (0.5, 0.0))
    >>> speck_circle(dash, 0.2, 0.1) is None  # half a unit from its centre: no speck at 0.2
    True
    """
    coarse = path.points(9)
    if not (limit > 0.0 and max(float(np.ptp(coarse[0])), float(np.ptp(coarse[1]))) <= 2.0 * SPECK_RADIUS * tol):
        return None
    points = path.points(_SAMPLES)
    if not np.all(np.isfinite(points)):
        return None
    lo, hi = points.min(axis=1), points.max(axis=1)
    centre = 0.5 * (lo + hi)
    dist = np.hypot(*(points - centre[:, None]))
    rho = float(np.max(dist))
    if not (0.0 < rho <= SPECK_RADIUS * tol):
        return None
    tree = cKDTree(points.T)
    radii = np.linspace(_LEAST_RADIUS * rho, rho, 25)
    spreads = [_spread(points, tree, centre, dist, r) for r in radii]
    k = int(np.argmin(spreads))
    best = minimize_scalar(lambda r: _spread(points, tree, centre, dist, r), method="bounded",
                           bounds=(radii[max(k - 1, 0)], radii[min(k + 1, radii.size - 1)]),
                           options={"xatol": 1e-3 * rho})
    r = float(best.x) if best.fun < spreads[k] else float(radii[k])
    rest = np.hstack([points, points[:, :1]]) if not path.closed else points
    area = 0.5 * float(np.sum(rest[0, :-1] * rest[1, 1:] - rest[0, 1:] * rest[1, :-1]))
    first = points[:, 0] - centre
    speck = Speck(centre=(float(centre[0]), float(centre[1])), radius=r, bound=math.inf, sampled=math.inf,
                  clockwise=area < 0.0, start=math.atan2(first[1], first[0]) if np.any(first) else 0.0)
    window = [(i, 0.0, 1.0) for i in range(len(path.pieces))]
    cert = _certify(path.pieces, window, speck.pose(), speck.segments(), limit, limit / 8.0)
    if not (cert.ok and cert.bound <= limit):
        return None
    return replace(speck, bound=cert.bound, sampled=cert.sampled)


def speck_fit(path: Path, speck: Speck, tol: float, method: str = "greedy") -> PathFit:
    """The fit of a speck: its circle, with the circle's certified distance to the path as its bound."""
    segs = speck.segments()
    length = sum(piece_length(p) for p in path.pieces)
    run = FittedRun(start=speck.pose(), segments=segs, corner=0.0, hausdorff=speck.bound, curve_length=length)
    return PathFit(
        success=True, status=FitStatus.SUCCESS,
        message=(f"a speck, traced as a circle of radius {speck.radius:.3g} about ({speck.centre[0]:.6g}, "
                 f"{speck.centre[1]:.6g}), Hausdorff distance <= {speck.bound:.3g} (tol {tol:.3g})"),
        runs=(run,), hausdorff=speck.bound, hausdorff_sampled=speck.sampled, where=None, n_arcs=len(segs),
        n_lines=0, curve_length=length, spline_length=2.0 * math.pi * speck.radius, tol=tol, method=method,
        greedy_count=len(segs), min_count=len(segs) if method == "min" else None, certificates=1, closed=True,
        name=path.name, size=2.0 * speck.radius)


def find_specks(drawing: Drawing, tol: float, limit: float) -> dict[int, Speck]:
    """The specks of a drawing (:func:`speck_circle`), by the index of their path."""
    found = {}
    for i, path in enumerate(drawing.paths):
        speck = speck_circle(path, tol, limit)
        if speck is not None:
            found[i] = speck
    return found
