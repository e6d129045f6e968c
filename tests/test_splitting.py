"""Splitting a path into smooth runs: corners, cusps, closures, and spiral spans at inflections and extrema."""

import math

import numpy as np
import pytest

from fitting_cases import bezier_spiral, ellipse_quarter, sine_piece
from skatetrace.drawings.curves import BezierPiece, EllipticArcPiece, FunctionPiece, LinePiece, Path
from skatetrace.drawings.splitting import split_path


def test_sine_inflection_and_extrema():
    for analytic in (True, False):
        [run] = split_path(Path((sine_piece(analytic),)))
        u = [s.t0 * 2 * math.pi for s in run.spans[1:]]
        reasons = [s.reason for s in run.spans]
        assert reasons == ["start", "extremum", "inflection", "extremum"]
        assert u == pytest.approx([math.pi / 2, math.pi, 3 * math.pi / 2], abs=1e-8 if analytic else 1e-4)
        assert [s.kind for s in run.spans] == ["spiral"] * 4


def test_reference_spirals_are_single_spans():
    for path in (ellipse_quarter(), bezier_spiral()):
        [run] = split_path(path)
        assert len(run.spans) == 1 and run.spans[0].kind == "spiral" and run.corner is None


@pytest.mark.parametrize("p1, angle", [((1.0, 1.0), 90.0), ((1.0, -1.0), -90.0), ((2.0, 1.0), 45.0),
                                       ((0.0, 1.0), 135.0),
                                       ((0.0, -0.001), -180.0 + math.degrees(math.atan(0.001)))])
def test_corner_signed_angle(p1, angle):
    path = Path((LinePiece((0.0, 0.0), (1.0, 0.0)), LinePiece((1.0, 0.0), p1)))
    runs = split_path(path)
    assert [r.corner for r in runs][0] is None
    assert math.degrees(runs[1].corner) == pytest.approx(angle, abs=1e-6)
    assert runs[1].spans[0].reason == "corner"


def test_cusps_inside_pieces():
    # A cubic cusp: control polygon crossing itself symmetrically; and an out-and-back quadratic.
    for piece, n_cusp in [(BezierPiece(((0.0, 0.0), (1.0, 1.0), (0.0, 1.0), (1.0, 0.0))), 1),
                          (BezierPiece(((0.0, 0.0), (1.0, 0.0), (0.5, 0.0))), 1)]:
        runs = split_path(Path((piece,)))
        assert len(runs) == 1 + n_cusp
        for r in runs[1:]:
            assert abs(r.corner) == pytest.approx(math.pi, abs=1e-6)
            assert r.spans[0].reason == "cusp"
    # An astroid has four cusps, all true reversals.
    astroid = Path((FunctionPiece(lambda u: (np.cos(u) ** 3, np.sin(u) ** 3), 0.0, 2 * math.pi),), closed=True)
    runs = split_path(astroid)
    assert len(runs) == 4 and all(abs(r.corner) == pytest.approx(math.pi, abs=1e-3) for r in runs)


def test_zero_length_handle_joins_smoothly():
    # The second piece starts with a zero-length handle; its limit tangent continues the first piece.
    a = BezierPiece(((0.0, 0.0), (1.0, 0.0), (2.0, 1.0), (3.0, 1.0)))
    b = BezierPiece(((3.0, 1.0), (3.0, 1.0), (4.0, 1.0), (5.0, 0.0)))
    runs = split_path(Path((a, b)))
    assert len(runs) == 1
    assert "join" in [s.reason for s in runs[0].spans]
    # ... and a small real corner is still a corner.
    c = BezierPiece(((3.0, 1.0), (3.0, 1.0), (4.0, 1.1), (5.0, 0.0)))
    runs = split_path(Path((a, c)))
    assert len(runs) == 2 and math.degrees(runs[1].corner) == pytest.approx(math.degrees(math.atan2(0.1, 1.0)))


def test_closed_path_closure():
    teardrop = Path((BezierPiece(((0.0, 0.0), (2.0, 1.0), (-1.0, 1.0), (0.0, 0.0))),), closed=True)
    [run] = split_path(teardrop)
    # leaves along (2, 1), arrives along (1, -1): the travel direction turns left by their difference
    assert run.corner == pytest.approx(math.atan2(1.0, 2.0) - math.atan2(-1.0, 1.0))
    ellipse = Path((EllipticArcPiece((0.0, 0.0), 2.0, 1.0, 0.0, 0.0, 2 * math.pi),), closed=True)
    runs = split_path(ellipse)
    assert len(runs) == 1 and runs[0].corner == 0.0
    # A closed path with corners elsewhere and a smooth closure: the closure lies inside a run.
    a = EllipticArcPiece((1.0, 0.0), 1.0, 1.0, 0.0, -math.pi / 2, math.pi)  # right end of a stadium
    b = LinePiece((1.0, 1.0), (-1.0, 1.0))
    c = LinePiece((-1.0, 1.0), (-1.0, -1.0))  # corners of +90 degrees at both its ends
    d = LinePiece((-1.0, -1.0), (1.0, -1.0))  # ... and the path closes smoothly into the arc
    runs = split_path(Path((a, b, c, d), closed=True))
    assert [[s.piece for s in r.spans] for r in runs] == [[2], [3, 0, 1]]
    assert [r.corner for r in runs] == pytest.approx([math.pi / 2, math.pi / 2])
    assert [s.kind for s in runs[1].spans] == ["line", "arc", "line"]


def _hairpin(h):
    """A quadratic out and back whose tip, at (1, 0), has radius h^2 / 2 (and turns by nearly pi)."""
    return Path((BezierPiece(((0.0, -h), (2.0, 0.0), (0.0, h))),))


@pytest.mark.parametrize("fit", ["arcs", "exact"])
def test_a_hairpin_tighter_than_the_tolerance_is_a_cusp(fit):
    from skatetrace.drawings.exact import fit_exact_path
    from skatetrace.drawings.fitting import fit_path

    fitter = fit_path if fit == "arcs" else fit_exact_path
    path = _hairpin(1e-3)  # tip radius 5e-7 on a path of size 1
    assert len(split_path(path)) == 1  # without a tolerance: smooth (the radius is far above rounding)
    res = fitter(path, 1e-3)
    assert res.success, res.message
    assert len(res.runs) == 2 and abs(res.runs[1].corner) == pytest.approx(math.pi, abs=1e-3)
    assert (res.hausdorff if fit == "arcs" else res.deviation) <= 1e-3
    # where the tolerance is finer than the tip (radius above tol / 4), it stays one smooth run
    res = fit_path(_hairpin(0.05), 1e-4)  # radius 1.25e-3
    assert res.success and len(res.runs) == 1


def test_a_hairpin_of_a_quarter_of_the_tolerance_is_a_cusp():
    # The Rust documentation's favicon (rustdoc's favicon-de23e50b.svg, its "D") at 6 m: an S command
    # whose second control point is its end overshoots and comes back through a tip of radius 0.126 mm
    # (radius bound 0.1257 mm), turning by 150.2 degrees across 1 mm. Above an eighth of the tolerance,
    # it was one smooth run, fitted by arcs of a millimetre turning back and forth, and the section
    # through it was one that no stop fits (the figure failed after nine rounds of rests, 74 s)
    from skatetrace.drawings.splitting import TIP_RADIUS, _cusps
    from skatetrace.drawings.svg import parse_path_string

    d = parse_path_string("M59.6,122.8L73.8,80c0,0,7,0,10.8,0s28.8-1.7,25.4,17.5c-3.4,19.2-18.8,25.2-36.8,25.4"
                          "S59.6,122.8,59.6,122.8z")
    s_piece = d.scaled_to(d.size() * 6.0 / 199.7, "m").paths[0].pieces[4]
    tips = _cusps(s_piece, 1.0, TIP_RADIUS * 1e-3)
    assert len(tips) == 2 and tips[0] == pytest.approx(0.67175, abs=1e-4)
    assert tips[1] == 1.0  # the zero-length handle at its end, where the speed vanishes
    assert _cusps(s_piece, 1.0, 0.125 * 1e-3) == [1.0]  # at an eighth of the tolerance the tip was smooth


def test_a_tight_turn_that_does_not_come_back_is_not_a_cusp():
    from skatetrace.drawings.fitting import fit_path
    from skatetrace.drawings.splitting import _turn_across

    # A quadratic hairpin turns by nearly pi across its tip; a quarter turn of a circle by a
    # quarter: only the first is made a cusp whatever its radius.
    pin = _hairpin(1e-3).pieces[0]
    assert math.degrees(_turn_across(pin, 0.5, 1e-3)) > 170
    quarter = EllipticArcPiece((0.0, 0.0), 1e-4, 1e-4, 0.0, 0.0, math.pi / 2)
    assert math.degrees(_turn_across(quarter, 0.5, 1.0)) == pytest.approx(90.0, abs=1e-6)
    bend = Path((LinePiece((-1.0, 0.0), (0.0, 0.0)), BezierPiece(((0.0, 0.0), (1e-5, 0.0), (1e-5, 1e-5))),
                 LinePiece((1e-5, 1e-5), (1e-5, 1.0))))
    res = fit_path(bend, 1e-3)
    assert res.success and all(abs(r.corner or 0.0) < 3.0 for r in res.runs)
