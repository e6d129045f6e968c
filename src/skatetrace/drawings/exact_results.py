"""Results of exact mode: a run, a path and a drawing as curvature splines, and the fit's status.

:func:`~skatetrace.drawings.exact.fit_exact_path` and :func:`~skatetrace.drawings.exact.fit_exact_drawing`
return them; :func:`~skatetrace.drawings.exact_figure.figure_from_exact` turns them into a figure. The
deviation they report is defined in :mod:`skatetrace.drawings.exact`.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum
from typing import NamedTuple

from ..figures.figure import Join
from .corners import corner_join
from ..figures.geometry import Pose, end_pose

__all__ = ["ExactStatus", "ExactWhere", "ExactRun", "ExactPathFit", "ExactDrawingFit"]


class ExactStatus(Enum):
    """Outcome of an exact-mode fit; the value is the message."""

    SUCCESS = "every run is within the tolerance (measured)"
    PIECE_LIMIT = "the curvature spline reached the piece limit before the deviation was within the tolerance"
    UNREFINABLE = "more spline knots no longer reduce the deviation"


class ExactWhere(NamedTuple):
    """Where the largest sampled distance was found: the source point ``(x, y)`` and its run."""

    x: float
    y: float
    run: int


@dataclass(frozen=True, slots=True, kw_only=True)
class ExactRun:
    """One run of a path as Segments and Spirals laid out tangentially from ``start``.

    Attributes
    ----------
    start : Pose
        Start point and travel direction of the layout.
    pieces : tuple of Segment or Spiral
        Laid out one after the other with :func:`skatetrace.figures.geometry.end_pose`.
    corner : float or None
        As :attr:`skatetrace.drawings.splitting.Run.corner`, recomputed from the laid-out directions: the signed
        turn of travel direction at the corner before this run.
    deviation : float
        Measured upper bound of ``sup_s |X_exact(s) - X_src(s)|`` over the run (see
        :mod:`skatetrace.drawings.exact`), hence of the Hausdorff distance between the layout and the run of source curve.
    sampled : float
        Largest sampled ``|X_exact(s) - X_src(s)|``.
    curve_length : float
        Length of the run of source curve (the pieces have the same total length, up to rounding).
    """

    start: Pose
    pieces: tuple
    corner: float | None
    deviation: float
    sampled: float
    curve_length: float

    @property
    def length(self) -> float:
        return float(sum(p.length for p in self.pieces))

    def poses(self) -> list[Pose]:
        """Start pose of every piece, then the end pose (``len(pieces) + 1`` poses)."""
        out = [self.start]
        for p in self.pieces:
            out.append(end_pose(out[-1], p))
        return out

    def join(self, reverse_above_deg: float = 90.0) -> Join | None:
        """The figure join at the corner before this run; see :func:`skatetrace.drawings.corners.corner_join`."""
        return corner_join(self.corner, reverse_above_deg)


@dataclass(frozen=True, slots=True, kw_only=True)
class ExactPathFit:
    """A path as curvature splines, one G1 chain of Segments and Spirals per run.

    Attributes
    ----------
    success, status, message
        ``success`` is every run's ``deviation <= tol``; otherwise ``message`` names the path, the bound
        reached and ``tol``.
    runs : tuple of ExactRun
        On failure, the best layout found (every run present).
    deviation : float
        Largest run deviation (measured upper bound of the Hausdorff distance to the path).
    sampled : float
        Largest sampled distance.
    where : ExactWhere or None
        Where ``sampled`` was found.
    n_spirals, n_arcs, n_lines : int
    curve_length, length : float
        Length of the source path (as split) and of the pieces.
    tol, closed, name, size
        ``size`` is the larger side of the path's bounding box.
    """

    success: bool
    status: ExactStatus
    message: str
    runs: tuple[ExactRun, ...]
    deviation: float
    sampled: float
    where: ExactWhere | None
    n_spirals: int
    n_arcs: int
    n_lines: int
    curve_length: float
    length: float
    tol: float
    closed: bool
    name: str
    size: float

    @property
    def n_pieces(self) -> int:
        return self.n_spirals + self.n_arcs + self.n_lines


@dataclass(frozen=True, slots=True, kw_only=True)
class ExactDrawingFit:
    """Every path of a drawing in exact mode; the deviation and counts are over all paths."""

    success: bool
    message: str
    paths: tuple[ExactPathFit, ...]
    deviation: float
    n_spirals: int
    n_arcs: int
    n_lines: int
    worst_path: int
    name: str = ""

    @property
    def status(self) -> ExactStatus:
        bad = [p.status for p in self.paths if not p.success]
        return bad[0] if bad else ExactStatus.SUCCESS
