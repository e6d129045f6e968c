"""A fit turned into a figure: layout reproduces the fit, one cusp join per corner, reversal above a threshold."""

import math

import pytest

from fitting_cases import heading_gap, size_of
from skatetrace.drawings.curves import BezierPiece, Drawing, EllipticArcPiece, LinePiece, Path
from skatetrace.drawings.fit_results import DrawingFit
from skatetrace.drawings.fitting import fit_drawing, fit_path
from skatetrace.drawings.splitting import split_path
from skatetrace.drawings.to_figure import figure_from_fit


def figure_path():
    """Open path: a smooth join, corners of +45 and -45 degrees, then a true cusp inside a piece."""
    return Path((
        BezierPiece(((0.0, 0.0), (1.0, 0.0), (2.0, 1.0), (3.0, 1.0))),
        BezierPiece(((3.0, 1.0), (4.0, 1.0), (4.0, 2.0), (3.5, 2.5))),  # smooth continuation
        LinePiece((3.5, 2.5), (2.5, 2.5)),  # corner of +45 degrees
        BezierPiece(((2.5, 2.5), (1.5, 3.5), (2.5, 3.5), (1.5, 2.5))),  # -45 degrees, then a cusp
    ), name="mixed")


def test_figure_path_has_what_it_says():
    runs = split_path(figure_path())
    assert [round(math.degrees(r.corner), 6) if r.corner is not None else None for r in runs] == [
        None, 45.0, -45.0, 180.0]
    assert [r.spans[0].reason for r in runs] == ["start", "corner", "corner", "cusp"]


@pytest.mark.parametrize("path", [
    figure_path(),
    Path((BezierPiece(((0.0, 0.0), (1.0, 1.0), (0.0, 1.0), (1.0, 0.0))),
          BezierPiece(((1.0, 0.0), (2.0, -1.0), (1.0, -1.0), (0.0, 0.0)))), closed=True, name="closed-cusps"),
    Path((EllipticArcPiece((0.0, 0.0), 2.0, 1.0, 0.4, 0.0, 2 * math.pi),), closed=True, name="ellipse"),
])
def test_figure_layout_reproduces_fit(path):
    fit = fit_path(path, 1e-3 * size_of(path))
    fig = figure_from_fit(fit, name="fitted")
    [curve] = fig.curves
    size = size_of(path)
    poses = [q for r in fit.runs for q in r.poses()[:-1]]
    placed = curve.layout()
    assert len(placed) == len(poses) == fit.n_segments
    for pl, q, (seg) in zip(placed, poses, [s for r in fit.runs for s in r.segments]):
        assert pl.segment == seg
        assert math.hypot(pl.start.x - q.x, pl.start.y - q.y) <= 1e-9 * size
        assert heading_gap(pl.start.heading, q.heading) <= 1e-9
    end, _ = curve.end_pose()
    last = fit.runs[-1].poses()[-1]
    if not path.closed:
        assert math.hypot(end.x - last.x, end.y - last.y) <= 1e-9 * size
    else:
        assert curve.closure()["position_gap"] <= 1e-9 * size
        assert curve.closure()["closed"] or abs(curve.closure()["heading_gap"]) <= 1e-9
    # joins: smooth inside runs, one cusp per corner; reversal above 90 degrees only
    cusps = [j for j in curve.joins if j.is_cusp]
    assert len(cusps) == len(fit.runs) - 1
    for run, j in zip(fit.runs[1:], cusps):
        assert j.reverse == (abs(run.corner) > math.pi / 2)
        turn = j.pivot + (math.pi if j.reverse else 0.0)
        assert heading_gap(turn, run.corner) <= 1e-12
    assert fig.provenance.startswith("arc-spline fit")


def test_figure_from_drawing_and_reverse_threshold():
    vee = Path((LinePiece((0.0, 0.0), (1.0, 0.0)), LinePiece((1.0, 0.0), (0.0, 0.5))), name="vee")
    ell = Path((EllipticArcPiece((5.0, 0.0), 2.0, 1.0, 0.0, 0.0, math.pi),), name="arc")
    dfit = fit_drawing(Drawing((vee, ell)), 1e-3)
    assert isinstance(dfit, DrawingFit) and dfit.success and len(dfit.paths) == 2
    assert dfit.n_arcs == sum(p.n_arcs for p in dfit.paths) and dfit.hausdorff <= 1e-3
    fig = figure_from_fit(dfit, name="two", reverse_above_deg=170.0)
    assert [c.name for c in fig.curves] == ["vee", "arc"]
    j = fig.curves[0].joins[0]
    assert not j.reverse and math.degrees(j.pivot) == pytest.approx(180 - math.degrees(math.atan2(0.5, 1.0)))
