"""Exact mode's entry points: a path's smooth runs fitted as curvature splines (cubic curvature in arc length).

The engine traces exactly any curve whose signed curvature is a cubic polynomial of arc length on
each piece (:class:`~skatetrace.figures.geometry.Spiral`), as well as arcs and lines
(:class:`~skatetrace.figures.geometry.Segment`). Exact mode turns a :class:`~skatetrace.drawings.curves.Path` into
such pieces, without the arc approximation of :mod:`skatetrace.drawings.fitting`. This module holds
its entry points, :func:`fit_exact_path` and :func:`fit_exact_drawing`, and describes the method;
one span as a curvature spline is :mod:`skatetrace.drawings.exact_spans`, one run's layout, deviation
and refinement :mod:`skatetrace.drawings.exact_runs`, the results :mod:`skatetrace.drawings.exact_results`,
and the figure :mod:`skatetrace.drawings.exact_figure`.

1. The path is cut into tangent-continuous *runs* and spiral *spans* exactly as for arc fitting
   (:func:`skatetrace.drawings.splitting.split_path`).
2. A span of constant curvature ("arc" or "line") becomes one Segment of the span's curvature and
   length. A "spiral" span becomes a chain of Spirals: its curvature kappa(s) is sampled at knots
   in arc length s (arc length of the source by adaptive 5-point Gauss-Legendre, knots found by
   inverting s(t) with safeguarded Newton steps to rounding) and interpolated by a not-a-knot
   cubic spline; each spline interval is one Spiral. The knots are uniform in the mean of the arc
   length and the absolute turn, so that they crowd where the curvature peaks (a Bézier's sharp
   top, a hairpin), their spacing kept from growing by more than half the distance
   (:data:`~skatetrace.drawings.exact_spans.GRADING`). Curvature is therefore continuous,
   with a continuous derivative, inside a span; it may jump where spans of different source pieces
   meet (a G1 join of two Béziers, say), as it does on the source. Two refinements of that rule:
   a spline through points (:class:`~skatetrace.drawings.curves.SplinePiece`, whose curvature or its slope
   jumps at the data points) has its spans cut at its breakpoints too; and at a cusp end of a span,
   where the curvature is unbounded, the end interval is not interpolated but continues the spline
   (two derivatives) with the source's exact turn over it.
3. Each run is laid out piece after piece with :func:`skatetrace.figures.geometry.travel` from its start
   pose: the first run from the source's start point and direction, every later run from the end
   of the previous run's layout with the source's direction after the corner, as a figure's cusp
   join places it. The laid-out curve is what
   :func:`~skatetrace.drawings.exact_figure.figure_from_exact` hands to the engine.

Deviation. For each run, ``X_exact(s)`` (the layout) and ``X_src(s)`` (the source at arc length
``s`` from the run's start) are both unit-speed curves over the same length, so every point of either
is within ``e(s) = |X_exact(s) - X_src(s)|`` of the other: ``sup_s e(s)`` is an upper bound of the
Hausdorff distance between them. ``e`` is Lipschitz with constant at most the heading difference
``|dtheta(s)|`` (``|u - v| <= |angle(u, v)|`` for unit vectors), so with ``e`` and ``dtheta``
sampled at spacing ``g_i`` (at least 16 samples per piece) the reported ``deviation`` is
``max_i e_i + g_i * max(|dtheta_i|, |dtheta_{i+1}|)``. It is a measured bound, not a certificate:
it relies on the heading difference varying little between samples (it changes by a tiny fraction
of itself there) and on quadrature and rounding of order 1e-15 of the size. Errors carry forward
along a run, so the bound measures the laid-out figure, not each piece on its own.

Refinement. A spiral span starts with ``max(2, ceil(|turn| / 0.25), ceil(8 L_span / L_run))``
intervals. A layout whose spline overshoots between its knots (a piece turning by more than
:data:`~skatetrace.drawings.exact_spans.OVERSHOOT` radians) is not laid out: its deviation counts as
infinite and its spans are refined first. While a run's deviation exceeds its share of ``tol``
(``tol`` times the fraction of the path's length up to the run's end, so that the start offset
carried into later runs leaves them room), the spans that contribute most (their own heading error
integrated over the span, plus the heading error at their end times the rest of the run) get their
intervals doubled. The error of
a smooth span falls like ``h^4`` in the knot spacing ``h`` (only like ``sqrt(h)`` next to a cusp).
Refinement stops before ``max_pieces`` (``MAX_PIECES``) pieces per path, or when more knots stop
helping: what remains comes from arcs, lines, kinks within ``corner_tol_deg`` or a carried offset,
the deviation is down to rounding (``ROUNDING`` of the size or coordinates), or it stopped falling
(curvature noise of a finite-difference piece). If the deviation is then above ``tol`` the fit fails
with a message naming the path, the bound and ``tol``, and keeps the best layout found (no exception).
"""

from __future__ import annotations

import math

import numpy as np

from .curves import Drawing, Path
from ..errors import FitError
from .exact_results import ExactDrawingFit, ExactPathFit, ExactRun, ExactStatus, ExactWhere
from .exact_runs import RunGeom, RunResult, refine
from .corners import _wrap
from .fitting import _check_tol
from .splitting import Run, _split
from ..figures.geometry import Pose, Segment, Spiral

__all__ = ["MAX_PIECES", "fit_exact_path", "fit_exact_drawing"]

MAX_PIECES = 20_000  # pieces per path before refinement gives up
ROUNDING = 1e-14  # relative to the larger of the size and the coordinates: a deviation this small is rounding


def fit_exact_path(path: Path, tol: float, *, corner_tol_deg: float = 0.5,
                   max_pieces: int = MAX_PIECES) -> ExactPathFit:
    """A path as G1 chains of Segments and Spirals (curvature splines), within a measured deviation ``tol``.

    Parameters
    ----------
    path : skatetrace.drawings.curves.Path
    tol : float
        Largest allowed deviation (see the module docstring), in the path's units.
    corner_tol_deg : float
        See :func:`skatetrace.drawings.splitting.split_path`. A kink of up to this much at a smooth join inside a
        run stays in the run; the layout keeps its direction there, so the kink costs about its angle
        times the rest of the run: lower ``corner_tol_deg`` (make it a corner) for tight ``tol``.
    max_pieces : int
        Refinement stops before the path would need more pieces than this.

    Returns
    -------
    ExactPathFit
        ``success`` False (status ``PIECE_LIMIT``) when a run's deviation stayed above ``tol`` at
        ``max_pieces`` pieces, or (``UNREFINABLE``) when more knots cannot reduce it: curvature noise
        of a finite-difference piece, a kink at a smooth join, or a ``tol`` below rounding (about
        1e-14 of the size or of the coordinates). The runs then hold the best layout found and
        ``message`` names the path, the run, the bound reached and ``tol``.

    Raises
    ------
    FitError
        Invalid ``tol``, ``corner_tol_deg`` or ``max_pieces``, or a path that cannot be split (see
        :func:`skatetrace.drawings.splitting.split_path`).

    Examples
    --------
    >>> from skatetrace.drawings.curves import EllipticArcPiece
    >>> quarter = Path((EllipticArcPiece((0.0, 0.0), 2.0, 2.0, 0.0, 0.0, np.pi / 2),))
    >>> fit = fit_exact_path(quarter, 1e-9)
    >>> fit.success, [(round(p.curvature, 12), round(p.length, 12)) for p in fit.runs[0].pieces]
    (True, [(0.5, 3.14159265359)])
    >>> ellipse = Path((EllipticArcPiece((0.0, 0.0), 2.0, 1.0, 0.0, 0.0, np.pi / 2),))
    >>> fit = fit_exact_path(ellipse, 1e-6)
    >>> fit.success, fit.deviation <= 1e-6, fit.n_spirals > 0, fit.n_arcs + fit.n_lines
    (True, True, True, 0)
    """
    tol = _check_tol(tol)
    if isinstance(max_pieces, bool) or not isinstance(max_pieces, (int, np.integer)) or max_pieces < 1:
        raise FitError(f"max_pieces must be a whole number >= 1, got {max_pieces!r}")
    try:
        runs, prep = _split(path, corner_tol_deg, tol)
        with np.errstate(all="ignore"):
            return _fit_runs(path, runs, prep.scale, tol, int(max_pieces))
    except ArithmeticError as exc:  # overflow in a user's piece, say; never a wrong answer
        raise FitError(f"path {path.name!r}: numerical failure in exact mode ({exc})") from exc


def _fit_runs(path: Path, runs: list[Run], scale: float, tol: float, max_pieces: int) -> ExactPathFit:
    geoms = [RunGeom(path.pieces, run, f"path {path.name!r}") for run in runs]
    floor = ROUNDING * max(scale, float(np.max(np.abs(path.points(65)))))
    total = max(sum(g.length for g in geoms), 1e-300)
    results: list[RunResult] = []
    starts: list[Pose] = []
    used, done = 0, 0.0
    failure: tuple[int, ExactStatus, str] | None = None
    for r, (geom, run) in enumerate(zip(geoms, runs)):
        sp0 = run.spans[0]
        if r == 0:
            x, y, _ = geom.spans[0].source(np.array([0.0]))
            start = Pose(float(x[0]), float(y[0]), float(sp0.heading0))
        else:
            prev = results[-1].ev.end
            start = Pose(prev.x, prev.y, float(sp0.heading0))
        # The run's share of tol: the fraction of the path's length up to its end, so that the offset it
        # carries into the next run leaves that one room (more if an earlier run used more than its share).
        sx, sy, _ = geom.spans[0].source(np.array([0.0]))
        offset = math.hypot(start.x - float(sx[0]), start.y - float(sy[0]))
        done += geom.length
        target = min(tol, max(tol * done / total, offset + tol * geom.length / total))
        res = refine(geom, start, target, tol, max_pieces - used, floor, failure is None)
        if res.failed is not None and failure is None:
            failure = (r, res.failed, res.why)
        used += len(res.ev.pieces)
        results.append(res)
        starts.append(start)
    # Corners from the directions actually laid out.
    out: list[ExactRun] = []
    for r, (run, res, geom) in enumerate(zip(runs, results, geoms)):
        corner = run.corner
        if corner is not None and corner != 0.0 and (r > 0 or path.closed):
            corner = _wrap(starts[r].heading - results[r - 1].ev.end.heading)
        out.append(ExactRun(start=starts[r], pieces=res.ev.pieces, corner=corner, deviation=res.ev.deviation,
                            sampled=res.ev.sampled, curve_length=geom.length))
    pieces = [p for r in out for p in r.pieces]
    n_spirals = sum(1 for p in pieces if isinstance(p, Spiral))
    n_lines = sum(1 for p in pieces if isinstance(p, Segment) and p.curvature == 0.0)
    n_arcs = len(pieces) - n_spirals - n_lines
    deviation = max(r.deviation for r in out)
    worst = max(range(len(out)), key=lambda r: out[r].sampled)
    where = ExactWhere(*results[worst].ev.where, worst)
    success = failure is None and deviation <= tol
    if success:
        status = ExactStatus.SUCCESS
        message = (f"{len(pieces)} pieces ({n_spirals} spirals, {n_arcs} arcs, {n_lines} lines) in {len(out)} runs, "
                   f"deviation <= {deviation:.3g} (tol {tol:.3g})")
    else:
        r, status, why = failure if failure is not None else (
            max(range(len(out)), key=lambda i: out[i].deviation), ExactStatus.PIECE_LIMIT, "")
        message = (f"path {path.name!r}: {status.value}: run {r} reached a deviation bound of "
                   f"{out[r].deviation:.3g} > tol {tol:.3g} with {len(out[r].pieces)} pieces "
                   f"({len(pieces)} in the path, limit {max_pieces})" + (f"; {why}" if why else ""))
        if math.isinf(out[r].deviation):
            message += ("; it kept no layout: every one tried overshoots between its knots (a hairpin tip needs "
                        "more pieces than that)")
        later = [i for i in range(r + 1, len(out)) if math.isinf(out[i].deviation)]
        if later:
            which = ", ".join(map(str, later[:5])) + (", ..." if len(later) > 5 else "")
            plural = len(later) > 1
            message += (f"; after it, run{'s' if plural else ''} {which}, laid out at {'their' if plural else 'its'} "
                        "first knots only, overshot between them and kept no pieces: the path's deviation is unbounded")
        if geoms[r].noisy:
            message += "; its curvature is a finite difference (noise about 1e-8 relative): give exact derivatives"
        kink = geoms[r].kink_deg()
        if kink > 1e-9:
            message += (f"; a smooth join inside the run turns by {kink:.3g} degrees: lower corner_tol_deg "
                        "to make it a corner")
    return ExactPathFit(success=success, status=status, message=message, runs=tuple(out), deviation=deviation,
                        sampled=max(r.sampled for r in out), where=where, n_spirals=n_spirals, n_arcs=n_arcs,
                        n_lines=n_lines, curve_length=float(sum(g.length for g in geoms)),
                        length=float(sum(p.length for p in pieces)), tol=tol, closed=path.closed, name=path.name,
                        size=scale)


def fit_exact_drawing(drawing: Drawing, tol: float, *, corner_tol_deg: float = 0.5,
                      max_pieces: int = MAX_PIECES) -> ExactDrawingFit:
    """Every path of a drawing in exact mode (see :func:`fit_exact_path`); ``tol`` in the drawing's units.

    ``max_pieces`` applies to each path.

    Examples
    --------
    >>> from skatetrace.drawings.curves import EllipticArcPiece, LinePiece
    >>> quarter = EllipticArcPiece((0.0, 0.0), 2.0, 1.0, 0.0, 0.0, np.pi / 2)
    >>> stem = LinePiece((0.0, 1.0), (-1.0, 1.0))
    >>> fit = fit_exact_drawing(Drawing((Path((quarter, stem)),)), 1e-9)
    >>> fit.success, fit.n_spirals > 10, fit.n_lines, fit.deviation <= 1e-9
    (True, True, 1, True)
    """
    if not isinstance(drawing, Drawing):
        raise FitError(f"expected a skatetrace.drawings.curves.Drawing, got {type(drawing).__name__}")
    tol = _check_tol(tol)
    fits = tuple(fit_exact_path(p, tol, corner_tol_deg=corner_tol_deg, max_pieces=max_pieces) for p in drawing.paths)
    worst = max(range(len(fits)), key=lambda i: fits[i].deviation)
    bad = [f"path {i} ({f.name!r}): {f.message}" for i, f in enumerate(fits) if not f.success]
    message = (f"{len(fits)} paths, deviation <= {fits[worst].deviation:.3g} (tol {tol:.3g})" if not bad
               else "; ".join(bad))
    return ExactDrawingFit(success=not bad, message=message, paths=fits, deviation=fits[worst].deviation,
                           n_spirals=sum(f.n_spirals for f in fits), n_arcs=sum(f.n_arcs for f in fits),
                           n_lines=sum(f.n_lines for f in fits), worst_path=worst, name=drawing.name)
