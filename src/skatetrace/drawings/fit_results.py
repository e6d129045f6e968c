"""What an arc-spline fit returns: fitted runs, where they sit on the path, and the path and drawing results.

:class:`FittedRun` is one run of a path replaced by arcs and lines, with its certified bound;
:class:`PathFit` and :class:`DrawingFit` gather them with ``success``/``status``/``message`` (as
scipy's results do) and the counts and bounds over the whole path or drawing. :mod:`.fitting` makes
them; :mod:`.to_figure` turns them into a figure.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import Enum
from typing import NamedTuple

from .biarcs import _chain_poses
from .corners import corner_join
from ..figures.figure import Join
from ..figures.geometry import Pose, Segment

__all__ = ["Knot", "Where", "FittedRun", "FitStatus", "PathFit", "DrawingFit", "gathered"]


class Knot(NamedTuple):
    """Where a biarc (or line) of a fitted run starts on the path: ``piece``, ``t``, and its first segment."""

    piece: int
    t: float
    segment: int


class Where(NamedTuple):
    """Where the largest sampled distance between a fit and its curve was found.

    ``x, y`` is the curve point (on ``piece`` at parameter ``t``); ``run`` and ``segment`` locate the
    nearest fitted segment; ``distance`` is the sampled distance there.
    """

    x: float
    y: float
    piece: int
    t: float
    run: int
    segment: int
    distance: float


@dataclass(frozen=True, slots=True, kw_only=True)
class FittedRun:
    """One run replaced by arcs and lines joined tangentially.

    Attributes
    ----------
    start : Pose
        Start point and travel direction (the curve's).
    segments : tuple of Segment
        Laid out one after the other from ``start`` (G1 by construction).
    corner : float or None
        As :attr:`~skatetrace.drawings.splitting.Run.corner`: the signed turn of travel direction at the
        corner before this run.
    hausdorff : float
        Certified upper bound of the Hausdorff distance between these segments and the run.
    curve_length : float
        Length of the run of curve.
    knots : tuple of Knot
        Curve locations where each biarc (or line) starts.
    """

    start: Pose
    segments: tuple[Segment, ...]
    corner: float | None
    hausdorff: float
    curve_length: float
    knots: tuple[Knot, ...] = ()

    @property
    def length(self) -> float:
        return float(sum(s.length for s in self.segments))

    def poses(self) -> list[Pose]:
        """Start pose of every segment, then the end pose (``len(segments) + 1`` poses)."""
        return _chain_poses(self.start, self.segments)

    def join(self, reverse_above_deg: float = 90.0) -> Join | None:
        """The figure join at the corner before this run (``None`` if there is none).

        See :func:`~skatetrace.drawings.corners.corner_join`.
        """
        return corner_join(self.corner, reverse_above_deg)


class FitStatus(Enum):
    """Outcome of fitting a path; the value is the message."""

    SUCCESS = "every run is within the tolerance (certified)"
    SUBDIVISION_LIMIT = "a span could not be fitted within the tolerance before reaching the minimum span length"
    TOO_MANY_ARCS = "the fit needed more biarcs than the limit"


@dataclass(frozen=True, slots=True, kw_only=True)
class PathFit:
    """A path approximated by G1 arc splines, one per run, with a certified distance.

    Attributes
    ----------
    success, status, message
        ``success`` is ``hausdorff <= tol``; otherwise ``status``/``message`` say what failed where.
    runs : tuple of FittedRun
    hausdorff : float
        Certified upper bound of the Hausdorff distance between the arc splines (each run laid out
        from its own start) and the path, the largest over all runs.
    hausdorff_sampled : float
        Largest exact distance from a sampled curve point to its arcs: a lower bound of the largest
        distance from the curve to the fit, and within ``tol / 8`` of ``hausdorff`` when the fit
        succeeds.
    where : Where or None
        Where ``hausdorff_sampled`` was found.
    n_arcs, n_lines : int
        Segments of non-zero and of zero curvature.
    curve_length, spline_length : float
    greedy_count, min_count : int, int or None
        Segments used by the greedy fit, and by the minimum-count fit (``None`` unless ``method="min"``).
        The result uses the smaller.
    certificates : int
        Number of biarc certificates computed (the cost of the fit).
    """

    success: bool
    status: FitStatus
    message: str
    runs: tuple[FittedRun, ...]
    hausdorff: float
    hausdorff_sampled: float
    where: Where | None
    n_arcs: int
    n_lines: int
    curve_length: float
    spline_length: float
    tol: float
    method: str
    greedy_count: int
    min_count: int | None
    certificates: int
    closed: bool
    name: str
    size: float

    @property
    def n_segments(self) -> int:
        return self.n_arcs + self.n_lines


@dataclass(frozen=True, slots=True, kw_only=True)
class DrawingFit:
    """Every path of a drawing fitted; the bound and counts are over all paths."""

    success: bool
    message: str
    paths: tuple[PathFit, ...]
    hausdorff: float
    hausdorff_sampled: float
    n_arcs: int
    n_lines: int
    worst_path: int
    name: str = ""
    extra: dict = field(default_factory=dict, compare=False)

    @property
    def status(self) -> FitStatus:
        bad = [p.status for p in self.paths if not p.success]
        return bad[0] if bad else FitStatus.SUCCESS


def gathered(paths, *, name: str, tol: float) -> DrawingFit:
    """The fit of a drawing made of its paths' fits (in the drawing's order), fitted within ``tol``."""
    paths = tuple(paths)
    worst = max(range(len(paths)), key=lambda i: paths[i].hausdorff)
    bad = [f"path {i} ({f.name!r}): {f.message}" for i, f in enumerate(paths) if not f.success]
    message = (f"{len(paths)} paths, Hausdorff distance <= {paths[worst].hausdorff:.3g} (tol {tol:.3g})"
               if not bad else "; ".join(bad))
    return DrawingFit(success=not bad, message=message, paths=paths, hausdorff=paths[worst].hausdorff,
                      hausdorff_sampled=max(f.hausdorff_sampled for f in paths),
                      n_arcs=sum(f.n_arcs for f in paths), n_lines=sum(f.n_lines for f in paths),
                      worst_path=worst, name=name)
