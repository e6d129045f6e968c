"""Exact mode: curvature splines (Segments and Spirals) for a drawing's runs, their deviation, figures."""

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from scipy.spatial import cKDTree

from skatetrace.drawings import exact_runs
from skatetrace.drawings.curves import BezierPiece, Drawing, EllipticArcPiece, FunctionPiece, Path, curvature
from skatetrace.errors import FitError
from skatetrace.drawings.corners import corner_join
from skatetrace.drawings.exact import fit_exact_drawing, fit_exact_path
from skatetrace.drawings.exact_figure import figure_from_exact
from skatetrace.drawings.exact_results import ExactDrawingFit, ExactPathFit, ExactStatus
from skatetrace.drawings.fitting import fit_path
from skatetrace.drawings.splitting import _split
from skatetrace.figures.geometry import Pose, Segment, Spiral, distance_to_segment, end_pose, segment_points
from skatetrace.drawings.points import read_points


def ellipse_quarter():
    return Path((EllipticArcPiece((0.0, 0.0), 2.0, 1.0, 0.0, 0.0, math.pi / 2),), name="ellipse-quarter")


def s_curve():
    # One inflection (t = 1/2) and two curvature extrema.
    return Path((BezierPiece(((0.0, 0.0), (1.0, 1.0), (2.0, -1.0), (3.0, 0.0))),), name="s-curve")


def bezier_spiral():
    # Curvature of one sign, monotone: a single spiral span.
    return Path((BezierPiece(((0.0, 0.0), (1.0, 0.0), (2.0, 0.2), (2.8, 0.8))),), name="bezier-spiral")


def corner_path():
    # Two Béziers meeting at (3, 0) at 90 degrees.
    return Path((BezierPiece(((0.0, 0.0), (1.0, 0.6), (2.0, 0.0), (3.0, 0.0))),
                 BezierPiece(((3.0, 0.0), (3.0, 1.0), (2.6, 2.0), (3.0, 3.0)))), name="corner")


def size_of(path):
    pts = path.points(513)
    return float(max(np.ptp(pts[0]), np.ptp(pts[1])))


def laid_out(fit):
    """(start pose, piece) of every piece of the fit, runs laid out from their own starts."""
    return [(pose, piece) for run in fit.runs for pose, piece in zip(run.poses()[:-1], run.pieces)]


def source_to_exact(path, fit, n=20000):
    """Largest distance from dense source points to the laid-out pieces (independent of the fit's samples)."""
    t = np.linspace(0.0, 1.0, n)
    pts = np.hstack([p.point(t) for p in path.pieces])
    d = np.full(pts.shape[1], np.inf)
    margin = 1e-6 * size_of(path)  # far above any deviation tested: only pieces this near can be nearest
    for pose, piece in laid_out(fit):
        box = segment_points(pose, piece, 65)
        lo, hi = box.min(axis=1) - margin - piece.length / 32, box.max(axis=1) + margin + piece.length / 32
        near = np.all((pts >= lo[:, None]) & (pts <= hi[:, None]), axis=0)
        if np.any(near):
            d[near] = np.minimum(d[near], distance_to_segment(pts[:, near], pose, piece))
    far = d > margin  # none expected; measured against every piece if so
    for pose, piece in laid_out(fit) if np.any(far) else []:
        d[far] = np.minimum(d[far], distance_to_segment(pts[:, far], pose, piece))
    return float(np.max(d))


def exact_to_source(path, fit, n=400_001, per_piece=24):
    """Largest distance from points of the pieces to a dense source polyline, and the polyline's own error."""
    t = np.linspace(0.0, 1.0, n)
    verts = [p.point(t) for p in path.pieces]
    sag = 0.0
    for p, v in zip(path.pieces, verts):
        step = float(np.max(np.hypot(*np.diff(v, axis=1))))
        k = curvature(p, t)
        sag = max(sag, float(np.nanmax(np.abs(k))) * step ** 2 / 8.0)  # chord-to-arc distance
    P = np.hstack(verts)
    q = np.hstack([segment_points(pose, piece, per_piece) for pose, piece in laid_out(fit)])
    _, j = cKDTree(P.T).query(q.T)
    best = np.full(q.shape[1], np.inf)
    for a, b in ((j - 1, j), (j, j + 1)):
        a, b = np.clip(a, 0, P.shape[1] - 1), np.clip(b, 0, P.shape[1] - 1)
        A, B = P[:, a], P[:, b]
        AB, AQ = B - A, q - A
        ll = np.sum(AB * AB, axis=0)
        lam = np.clip(np.sum(AQ * AB, axis=0) / np.where(ll > 0, ll, 1.0), 0.0, 1.0)
        best = np.minimum(best, np.hypot(*(A + lam * AB - q)))
    return float(np.max(best)), sag


def finite_fit(fit):
    assert not math.isnan(fit.deviation) and not math.isnan(fit.sampled)
    for run in fit.runs:
        assert all(math.isfinite(v) for v in run.start)
        assert not math.isnan(run.deviation)
        for p in run.pieces:
            assert math.isfinite(p.length) and p.length > 0
            assert all(math.isfinite(c) for c in p.coefficients)


# --------------------------------------------------------------------------------------------------
# Accuracy, checked independently of the fit's own samples
# --------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("make", [ellipse_quarter, s_curve])
def test_tight_fit_is_within_its_bound_both_ways(make):
    path = make()
    size = size_of(path)
    tol = 1e-9 * size
    fit = fit_exact_path(path, tol)
    assert fit.success and fit.status is ExactStatus.SUCCESS, fit.message
    assert fit.deviation <= tol
    assert fit.sampled <= fit.deviation
    assert fit.n_spirals > 0 and fit.n_arcs == fit.n_lines == 0
    assert fit.size == pytest.approx(size, rel=1e-6)
    assert fit.length == pytest.approx(fit.curve_length, rel=1e-12)
    assert fit.curve_length == pytest.approx(path.length(), rel=1e-12)
    finite_fit(fit)
    # Source points to the laid-out pieces: within the reported bound.
    assert source_to_exact(path, fit) <= fit.deviation
    # Points of the pieces to the source (a dense polyline, whose own chord error is allowed for).
    d, sag = exact_to_source(path, fit)
    assert d <= fit.deviation + sag + 1e-14 * size
    assert fit.where is not None and fit.where.run == 0


@pytest.mark.parametrize("make", [ellipse_quarter, s_curve])
def test_curvature_is_continuous_inside_a_run(make):
    path = make()
    fit = fit_exact_path(path, 1e-9 * size_of(path))
    [run] = fit.runs
    kmax = max(p.max_abs_curvature() for p in run.pieces)
    for a, b in zip(run.pieces[:-1], run.pieces[1:]):
        assert abs(a.end_curvature - b.start_curvature) <= 1e-9 * kmax
    # The spline's own end curvatures are the source's.
    k0 = float(curvature(path.pieces[0], 0.0)[0])
    k1 = float(curvature(path.pieces[0], 1.0)[0])
    assert run.pieces[0].start_curvature == pytest.approx(k0, rel=1e-12)
    assert run.pieces[-1].end_curvature == pytest.approx(k1, rel=1e-12)


def test_curvature_derivative_is_continuous_inside_a_span():
    path = ellipse_quarter()  # one spiral span
    assert len(_split(path, 0.5)[0][0].spans) == 1
    fit = fit_exact_path(path, 1e-9 * size_of(path))
    pieces = fit.runs[0].pieces
    slope = max(abs(p.coefficients[1]) for p in pieces)
    for a, b in zip(pieces[:-1], pieces[1:]):
        c = a.coefficients
        end_slope = c[1] + 2 * c[2] * a.length + 3 * c[3] * a.length ** 2
        assert abs(end_slope - b.coefficients[1]) <= 1e-6 * slope


def test_circle_gives_arcs_only():
    # An SVG elliptic arc with equal radii, all the way round.
    circle = Path((EllipticArcPiece((1.0, 2.0), 1.5, 1.5, 0.0, 0.3, 2 * math.pi),), closed=True, name="circle")
    fit = fit_exact_path(circle, 1e-9 * 3.0)
    assert fit.success, fit.message
    assert fit.n_spirals == 0 and fit.n_lines == 0 and fit.n_arcs >= 1
    assert all(isinstance(p, Segment) and p.curvature == pytest.approx(1 / 1.5, rel=1e-12)
               for r in fit.runs for p in r.pieces)
    assert fit.length == pytest.approx(3 * math.pi, rel=1e-12)
    assert fit.deviation <= 1e-12
    assert fit.runs[0].corner == 0.0 and fit.runs[0].join() is not None and not fit.runs[0].join().is_cusp


def test_quarter_circle_is_one_arc():
    quarter = Path((EllipticArcPiece((0.0, 0.0), 2.0, 2.0, 0.0, 0.0, math.pi / 2),))
    fit = fit_exact_path(quarter, 1e-9)
    assert fit.success and fit.n_pieces == 1
    [[arc]] = [r.pieces for r in fit.runs]
    assert arc == (pytest.approx(0.5, rel=1e-12), pytest.approx(math.pi, rel=1e-12))


@pytest.mark.parametrize("tangents", [False, True])
def test_point_list_splines_are_cut_at_their_knots(tangents):
    # Splines through points: curvature (Hermite) or its slope (cubic spline) jumps at the data points,
    # so the spline pieces are cut there; the fit then stays small.
    th = np.linspace(0.0, 1.5 * math.pi, 14)
    rows = [(2 * math.cos(a), math.sin(a)) + ((-2 * math.sin(a), math.cos(a)) if tangents else ()) for a in th]
    header = "x, y, tx, ty" if tangents else "x, y"
    drawing = read_points("\n".join([header] + [", ".join(map(repr, r)) for r in rows]) + "\n")
    [path] = drawing.paths
    fit = fit_exact_path(path, 1e-9 * size_of(path))
    assert fit.success and fit.deviation <= fit.tol, fit.message
    assert fit.n_pieces < 2000
    assert source_to_exact(path, fit, n=4000) <= fit.deviation


# --------------------------------------------------------------------------------------------------
# Convergence
# --------------------------------------------------------------------------------------------------


def test_tighter_tol_needs_more_pieces():
    path = s_curve()
    size = size_of(path)
    counts, bounds = [], []
    for rel in (1e-5, 1e-7, 1e-9):
        fit = fit_exact_path(path, rel * size)
        assert fit.success and fit.deviation <= rel * size
        counts.append(fit.n_pieces)
        bounds.append(fit.deviation)
    assert counts[0] < counts[1] < counts[2]
    assert bounds[0] > bounds[1] > bounds[2]


def test_deviation_falls_like_h4_on_a_smooth_spiral_span():
    path = bezier_spiral()
    [run], _ = _split(path, 0.5)
    assert len(run.spans) == 1 and run.spans[0].kind == "spiral"
    geom = exact_runs.RunGeom(path.pieces, run, "test")
    x, y = path.pieces[0].point(0.0)[:, 0]
    start = Pose(float(x), float(y), run.spans[0].heading0)
    devs = [geom.evaluate(start, [n]).deviation for n in (16, 32, 64)]
    assert devs[0] / devs[1] > 8 and devs[1] / devs[2] > 8, devs


def arches(n: int = 4) -> Path:
    """``n`` Bézier arches joined tangentially, up and down: the curvature peaks sharply (radius 0.77
    against 7 and more elsewhere) at each arch's top and jumps where the arches meet."""
    return Path(tuple(BezierPiece(((10.0 * k, 0.0), (10.0 * k + 3.6, (-20.0, 20.0)[k % 2]),
                                   (10.0 * k + 6.4, (-20.0, 20.0)[k % 2]), (10.0 * k + 10.0, 0.0)))
                      for k in range(n)), name="arches")


#: The control points of a quadratic Bézier of the SVG corpus (vpype-few-quad-beziers.svg, path 6): it
#: runs out some 1,900 units and back, its tip a hairpin of radius about 1e-3 of its length.
HAIRPIN = ((1151.9704537892883, -1911.6237888459702), (201.99325677294033, -347.76494685913326),
           (1093.4026869946988, -1827.5314414984855))


def test_knots_follow_the_turn_in_a_gently_graded_mesh():
    """Knots crowd where the curvature peaks, and no interval is much longer than its neighbour."""
    path = arches(1)
    [run], _ = _split(path, 0.5)
    geom = exact_runs.RunGeom(path.pieces, run, "test")
    for span in geom.spans:
        for n in (8, 64):
            s = span._knots(n)
            h = np.diff(s)
            assert s[0] == 0.0 and s[-1] == span.length and np.all(h > 0) and s.size == n + 1
            assert np.max(h[1:] / h[:-1]) < 2.0 and np.max(h[:-1] / h[1:]) < 2.0
            # each span runs from an end of the arch to its top, where the curvature peaks
            peak = -1 if span.span.reason != "extremum" else 0
            assert h[peak] == np.min(h) and h[peak] < 0.5 * span.length / n


def test_a_sharply_bent_span_needs_fewer_knots_than_uniform_ones_would():
    """Four arches within 1e-7 of their length: 1,536 spirals (knots uniform in length needed 6,144)."""
    path = arches()
    fit = fit_exact_path(path, 4e-6)
    assert fit.success and fit.deviation <= 4e-6
    assert fit.n_spirals <= 2048


def test_a_hairpin_tip_is_fitted_and_its_overshooting_splines_are_not_laid_out(monkeypatch):
    """A spline through too few knots about a hairpin overshoots by millions of radians between them;
    such a layout is refined without being laid out (its samples would take gigabytes), and the tip is
    fitted to 1e-7 of its length."""
    deviations = []
    evaluate = exact_runs.RunGeom.evaluate

    def recorded(self, start, ns):
        out = evaluate(self, start, ns)
        deviations.append(out.deviation)
        return out

    monkeypatch.setattr(exact_runs.RunGeom, "evaluate", recorded)
    fit = fit_exact_path(Path((BezierPiece(HAIRPIN),), name="hairpin"), 1e-4)
    assert fit.success and fit.deviation <= 1e-4
    assert math.isinf(deviations[0]) and math.isfinite(deviations[-1])  # (the second's pieces turn 9e3 rad)
    # refined no further, it fails cleanly, keeping no overshooting layout
    fit = fit_exact_path(Path((BezierPiece(HAIRPIN),), name="hairpin"), 1e-4, max_pieces=20)
    assert not fit.success and fit.status is ExactStatus.PIECE_LIMIT and math.isinf(fit.deviation)
    assert all(run.pieces == () for run in fit.runs) and "deviation bound of inf" in fit.message
    assert "kept no layout" in fit.message


# --------------------------------------------------------------------------------------------------
# Runs, corners and figures
# --------------------------------------------------------------------------------------------------


def test_corner_path_runs_and_figure():
    path = corner_path()
    size = size_of(path)
    fit = fit_exact_path(path, 1e-9 * size)
    assert fit.success, fit.message
    assert len(fit.runs) == 2 and fit.runs[0].corner is None
    assert fit.runs[1].corner == pytest.approx(math.pi / 2, abs=1e-6)
    # The second run starts where the first one's layout ends, in the source's direction.
    end = fit.runs[0].poses()[-1]
    assert (fit.runs[1].start.x, fit.runs[1].start.y) == (end.x, end.y)
    d1 = path.pieces[1].d1(0.0)[:, 0]
    assert fit.runs[1].start.heading == pytest.approx(math.atan2(d1[1], d1[0]), abs=1e-12)
    assert fit.runs[1].corner == pytest.approx(math.remainder(fit.runs[1].start.heading - end.heading, 2 * math.pi),
                                               abs=1e-15)
    assert fit.deviation <= fit.tol
    assert source_to_exact(path, fit) <= fit.deviation

    fig = figure_from_exact(fit, name="corner")
    [curve] = fig.curves
    assert "exact-mode" in fig.provenance
    assert fig.extra["exact"] == {"tol": fit.tol, "deviation": fit.deviation, "n_spirals": fit.n_spirals,
                                  "n_arcs": fit.n_arcs, "n_lines": fit.n_lines}
    n0 = len(fit.runs[0].pieces)
    assert curve.joins[n0 - 1] == fit.runs[1].join() == corner_join(fit.runs[1].corner)
    assert curve.joins[n0 - 1].is_cusp
    assert all(not j.is_cusp for i, j in enumerate(curve.joins) if i != n0 - 1)
    placed = curve.layout()
    assert [p.segment for p in placed] == [p for r in fit.runs for p in r.pieces]
    assert sum(p.segment.length for p in placed) == pytest.approx(fit.length, rel=1e-14)
    # Layout reproduces the fit's run starts (heading as a direction) and every piece's start.
    for run, k in ((fit.runs[0], 0), (fit.runs[1], n0)):
        s = placed[k].start
        assert math.hypot(s.x - run.start.x, s.y - run.start.y) <= 1e-12 * size
        assert abs(math.remainder(s.heading - run.start.heading, 2 * math.pi)) <= 1e-12
    poses = fit.runs[0].poses()[:-1] + fit.runs[1].poses()[:-1]
    for p, q in zip(placed, poses):
        assert math.hypot(p.start.x - q.x, p.start.y - q.y) <= 1e-12 * size
    last = placed[-1]
    e = end_pose(last.start, last.segment)
    e_fit = fit.runs[1].poses()[-1]
    assert math.hypot(e.x - e_fit.x, e.y - e_fit.y) <= 1e-12 * size


def test_sharp_corner_reverses():
    # Out along a curve and back along another: a turn of more than 90 degrees is a true cusp.
    path = Path((BezierPiece(((0.0, 0.0), (1.0, 0.5), (2.0, 0.5), (3.0, 0.0))),
                 BezierPiece(((3.0, 0.0), (2.0, -0.2), (1.0, -0.6), (0.0, -1.0)))), name="hairpin")
    fit = fit_exact_path(path, 1e-8)
    assert fit.success, fit.message
    join = fit.runs[1].join()
    assert join.is_cusp and join.reverse
    assert fit.runs[1].join(reverse_above_deg=180.0).reverse is False
    fig = figure_from_exact(fit, name="hairpin", reverse_above_deg=90.0)
    placed = fig.curves[0].layout()
    k = len(fit.runs[0].pieces)
    assert placed[k].direction == -1
    assert abs(math.remainder(placed[k].start.heading - fit.runs[1].start.heading, 2 * math.pi)) <= 1e-12


def test_closed_path_with_corners_gets_a_closing_join():
    lens = Path((BezierPiece(((0.0, 0.0), (1.0, 1.0), (2.0, 1.0), (3.0, 0.0))),
                 BezierPiece(((3.0, 0.0), (2.0, -1.0), (1.0, -1.0), (0.0, 0.0)))), closed=True, name="lens")
    fit = fit_exact_path(lens, 1e-8)
    assert fit.success and fit.closed and len(fit.runs) == 2
    assert fit.runs[0].corner is not None and fit.runs[0].corner != 0.0
    fig = figure_from_exact(fit, name="lens")
    assert fig.curves[0].closing == fit.runs[0].join() and fig.curves[0].closing.is_cusp
    closure = fig.curves[0].closure()
    assert closure["position_gap"] <= 3 * fit.deviation + 1e-12


def test_drawing_fit_and_status():
    drawing = Drawing((ellipse_quarter(), corner_path()), name="two")
    fit = fit_exact_drawing(drawing, 1e-8)
    assert isinstance(fit, ExactDrawingFit) and all(isinstance(p, ExactPathFit) for p in fit.paths)
    assert fit.success and fit.status is ExactStatus.SUCCESS and fit.name == "two"
    assert fit.deviation == max(p.deviation for p in fit.paths) == fit.paths[fit.worst_path].deviation
    assert fit.n_spirals == sum(p.n_spirals for p in fit.paths)
    fig = figure_from_exact(fit, name="two")
    assert len(fig.curves) == 2 and fig.extra["exact"]["n_spirals"] == fit.n_spirals


def test_arc_fit_figure_unchanged_by_the_refactor():
    path = corner_path()
    fit = fit_path(path, 1e-3)
    assert [r.join() for r in fit.runs] == [corner_join(r.corner) for r in fit.runs]


# --------------------------------------------------------------------------------------------------
# Invalid arguments and clean failures
# --------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("tol", [0.0, -1e-6, math.nan, math.inf, "1e-6", True])
def test_bad_tol_raises(tol):
    with pytest.raises(FitError):
        fit_exact_path(ellipse_quarter(), tol)
    with pytest.raises(FitError):
        fit_exact_drawing(Drawing((ellipse_quarter(),)), tol)


def test_bad_arguments_raise():
    with pytest.raises(FitError):
        fit_exact_path(ellipse_quarter(), 1e-6, corner_tol_deg=-1.0)
    with pytest.raises(FitError):
        fit_exact_path(ellipse_quarter(), 1e-6, max_pieces=0)
    with pytest.raises(FitError):
        fit_exact_drawing(ellipse_quarter(), 1e-6)
    with pytest.raises(FitError):
        figure_from_exact(fit_exact_path(ellipse_quarter(), 1e-6), name="x", reverse_above_deg=200.0)
    with pytest.raises(FitError):
        figure_from_exact(fit_path(ellipse_quarter(), 1e-3), name="x")


def test_absurd_tol_fails_cleanly():
    path = bezier_spiral()
    size = size_of(path)
    fit = fit_exact_path(path, 1e-16 * size)
    assert not fit.success and fit.status is not ExactStatus.SUCCESS
    assert "bezier-spiral" in fit.message and "tol" in fit.message and f"{fit.deviation:.3g}" in fit.message
    assert fit.runs and fit.deviation > fit.tol
    finite_fit(fit)
    assert math.isfinite(fit.deviation) and fit.deviation <= 1e-12 * size  # still the best layout found
    with pytest.raises(FitError, match="failed fit"):
        figure_from_exact(fit, name="x")
    drawing = fit_exact_drawing(Drawing((path,)), 1e-16 * size)
    assert not drawing.success and drawing.status is fit.status and "bezier-spiral" in drawing.message


def test_piece_limit_fails_cleanly():
    path = s_curve()
    fit = fit_exact_path(path, 1e-12 * size_of(path), max_pieces=100)
    assert not fit.success and fit.status is ExactStatus.PIECE_LIMIT
    assert "limit 100" in fit.message and "s-curve" in fit.message
    assert fit.n_pieces <= 100
    finite_fit(fit)


def test_finite_difference_curvature_fails_cleanly_at_tight_tol():
    sine = FunctionPiece(lambda u: (u, np.sin(u)), 0.0, 2 * math.pi)  # no derivatives: noisy curvature
    path = Path((sine,), name="noisy-sine")
    loose = fit_exact_path(path, 1e-5)
    assert loose.success and loose.deviation <= 1e-5
    fit = fit_exact_path(path, 1e-11)
    finite_fit(fit)
    if not fit.success:
        assert "noisy-sine" in fit.message and "finite difference" in fit.message
    else:  # pragma: no cover - would mean the noise happened to be small enough
        assert fit.deviation <= 1e-11


def test_cusp_inside_a_piece():
    # A cubic with a true cusp at t = 1/2: two runs, the second starting backwards.
    path = Path((BezierPiece(((0.0, 0.0), (1.0, 1.0), (0.0, 1.0), (1.0, 0.0))),), name="cusp")
    fit = fit_exact_path(path, 1e-3)
    finite_fit(fit)
    assert fit.success, fit.message
    assert len(fit.runs) == 2 and abs(fit.runs[1].corner) == pytest.approx(math.pi, abs=1e-2)
    assert source_to_exact(path, fit, n=4000) <= fit.deviation


# --------------------------------------------------------------------------------------------------
# Property: random cubic Béziers
# --------------------------------------------------------------------------------------------------

coord = st.floats(-10.0, 10.0, allow_nan=False, allow_infinity=False)


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(st.tuples(coord, coord), min_size=4, max_size=4))
def test_random_beziers_succeed_or_fail_cleanly(ctrl):
    path = Path((BezierPiece(tuple(ctrl)),), name="random")
    pts = path.points(257)
    size = float(max(np.ptp(pts[0]), np.ptp(pts[1])))
    try:
        fit = fit_exact_path(path, 1e-6 * size, max_pieces=2000)
    except FitError as exc:  # a degenerate drawing (zero extent or length)
        assert size < 1e-6 or "zero" in str(exc), str(exc)
        return
    finite_fit(fit)
    if fit.success:
        assert fit.deviation <= fit.tol
        for run in fit.runs:
            assert all(isinstance(p, (Segment, Spiral)) for p in run.pieces)
    else:
        assert "random" in fit.message and "tol" in fit.message
        assert fit.status in (ExactStatus.PIECE_LIMIT, ExactStatus.UNREFINABLE)
    # unbounded only where a run kept no layout (its spline overshoots between its knots), and said so
    unbounded = [run for run in fit.runs if math.isinf(run.deviation)]
    assert math.isfinite(fit.deviation) == (not unbounded)
    assert all(run.pieces == () for run in unbounded)
    assert not unbounded or "kept no" in fit.message


def test_a_run_laid_out_after_the_piece_limit_that_overshoots_is_named_unbounded():
    # a thin loop out and back along a line, found by the property test above: its first run spends
    # the piece limit, and the second, laid out at its first knots only, overshoots there
    ctrl = ((0.0, 0.0), (1.90625, 1.609375), (-5.75, -4.875), (0.0, 0.0))
    path = Path((BezierPiece(ctrl),), name="loop")
    fit = fit_exact_path(path, 1e-6 * size_of(path), max_pieces=2000)
    assert not fit.success and fit.status is ExactStatus.PIECE_LIMIT and math.isinf(fit.deviation)
    assert len(fit.runs) == 2 and fit.runs[0].pieces and math.isfinite(fit.runs[0].deviation)
    assert fit.runs[1].pieces == () and math.isinf(fit.runs[1].deviation)
    assert "run 0 reached" in fit.message and "after it, run 1" in fit.message and "unbounded" in fit.message
