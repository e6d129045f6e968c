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
    # the arc fit lays each half, a run between the path's end and the tip within 1e-3 of its chord,
    # along that chord: the reversal then turns by the chords' angle, pi - 2e-3
    assert len(res.runs) == 2 and abs(res.runs[1].corner) == pytest.approx(math.pi, abs=2.5e-3)
    if fit == "arcs":
        assert [len(r.segments) for r in res.runs] == [1, 1]
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


# simple-icons' CorelDRAW logo (CC0 1.0, simple-icons 16.37.0, icons/coreldraw.svg): a 24 x 24 view box
CORELDRAW = ("M10.651 0C10.265.019 9.4.272 8.584.657c-.816.39-3.696 2.161-3.752 6.536.072 4.145 3.847 11.191 6.397 "
             "13.455 0 0-4.141-6.952-4.439-13.013C6.488 1.575 10.651 0 10.651 0Zm2.679 0s4.159 1.575 3.861 7.635c-.299 "
             "6.061-4.439 13.013-4.439 13.013 2.547-2.264 6.324-9.31 6.396-13.455-.057-4.375-2.936-6.146-3.752-6.536C14.58"
             ".272 13.715.019 13.33 0Zm-1.38.019a1.088 1.088 0 0 0-.555.144C9.864.99 8.909 3.982 9.177 8.66c.185 3.242 "
             "1.009 7.291 2.422 11.988h.7c1.413-4.697 2.24-8.742 2.425-11.984.268-4.677-.688-7.674-2.219-8.501a1.088 1.088 "
             "0 0 0-.555-.144ZM7.017 1.066S2.543 2.909 3.431 8.225c.884 5.32 5.588 10.995 6.986 12.2.503.457-5.777-6.548-"
             "6.386-12.699-.291-2.323.39-4.9 2.986-6.66Zm9.966 0c2.595 1.76 3.276 4.337 2.985 6.66-.608 6.151-6.888 "
             "13.156-6.386 12.699 1.398-1.205 6.103-6.88 6.987-12.2.888-5.316-3.586-7.159-3.586-7.159Zm-6.815 20.78L10.647 "
             "24h2.599l.488-2.154h-3.566Z")


def test_the_turn_across_a_tip_is_the_whole_turn_not_the_angle_between_its_ends():
    # A circle's arc of 220 degrees turns by 220 degrees: the angle between its end tangents folds
    # back to 140, which a rule about how far a tip turns must not read
    from skatetrace.drawings.splitting import _turn_across

    for sweep in (60.0, 150.0, 220.0, 300.0):
        arc = EllipticArcPiece((0.0, 0.0), 1e-4, 1e-4, 0.0, 0.0, math.radians(sweep))
        assert math.degrees(_turn_across(arc, 0.5, 1.0)) == pytest.approx(sweep, abs=1e-6)
        back = EllipticArcPiece((0.0, 0.0), 1e-4, 1e-4, 0.0, 0.0, -math.radians(sweep))
        assert math.degrees(_turn_across(back, 0.5, 1.0)) == pytest.approx(sweep, abs=1e-6)


def test_a_tip_that_turns_by_143_degrees_within_a_fifth_of_a_millimetre_is_a_cusp():
    # The tips of CorelDRAW's outer petals at 6 m (0.25 m a unit): a cubic that leaves its corner
    # along (0.503, 0.457) and turns back through a tip of radius 0.187 mm, 143 degrees across 1 mm.
    # At the 150 degrees asked of a tip before, it was fitted smoothly by arcs of 1 to 6 mm radius
    # turning back and forth, sections no launch fits: the logo failed after nine rounds of rests (62 s)
    from skatetrace.drawings.fitting import fit_path
    from skatetrace.drawings.splitting import TIP_RADIUS, TIP_TURN_DEG, _cusps, _turn_across
    from skatetrace.drawings.svg import parse_path_string

    d = parse_path_string(CORELDRAW)
    d = d.scaled_to(d.size() * 0.25, "m")
    for name, index, expect in (("path#4", 2, 0.0344), ("path#5", 1, 0.9656)):  # the mirror images
        (path,) = [p for p in d.paths if p.name == name]
        (tip,) = _cusps(path.pieces[index], 1.0, TIP_RADIUS * 1e-3)
        assert tip == pytest.approx(expect, abs=2e-4)
        turn = math.degrees(_turn_across(path.pieces[index], tip, 1e-3))
        assert 140.0 < turn < 145.0 and turn >= TIP_TURN_DEG
        fit = fit_path(path, 1e-3)
        assert fit.success and fit.hausdorff <= 1e-3
        assert sum(abs(r.corner or 0.0) > 3.0 for r in fit.runs) == 1  # the tip is a reversal
        assert all(abs(s.curvature) < 300.0 for r in fit.runs for s in r.segments)  # none of 1 mm radius (now 80)


def _hooked_join():
    """Two cubics shaped like the hook in ionicons' logo-vk at 6 m (its 512-unit page, y up): the second
    leaves the join on a handle 6 mm long pointing back against its travel, so its tangent makes a
    121-degree corner with the first, and turns back through 125 degrees within a tenth of a millimetre."""
    k = 6.0 / 512

    def rel(p0, *ds):
        return tuple((p0[0] + k * dx, p0[1] - k * dy) for dx, dy in ((0.0, 0.0), *ds))

    a = rel((0.0, 0.0), (-7.62, -10.25), (-5.59, -14.35), (0.0, -23.57))
    b = rel(a[-1], (-0.51, 0.0), (63.55, -91.22), (70.15, -122.0))
    return Path((BezierPiece(a), BezierPiece(b)))


def test_an_end_that_hooks_within_the_tolerance_is_taken_by_its_chord():
    from skatetrace.drawings.fitting import fit_path
    from skatetrace.drawings.splitting import HOOK_DEG, _split

    path = _hooked_join()
    [_, tangents] = split_path(path)  # no tolerance: the tangents' corner
    assert math.degrees(abs(tangents.corner)) > 120
    [_, chord] = _split(path, 0.5, 0.5e-3, soft=True)[0]
    assert math.degrees(abs(chord.corner)) < HOOK_DEG
    fit = fit_path(path, 1e-3)
    assert fit.success and fit.hausdorff <= 1e-3
    # the join is a corner of about ten degrees, not a reversal, and no arc follows the hook (the
    # tangents' corner gave 105 degrees, a line of 20 um and arcs of 0.8 and 2 mm radius)
    assert math.degrees(abs(fit.runs[1].corner)) < HOOK_DEG
    assert min(1 / abs(s.curvature) for s in fit.runs[1].segments if s.curvature) > 0.03


def test_a_rounded_corner_is_no_hook():
    from skatetrace.drawings.splitting import _split

    # a quarter circle of radius 2 mm between two lines, fitted at 1 mm: its chords across the balls of a
    # millimetre about its ends turn 14.5 degrees from its end tangents, which stay its own
    r = 2e-3
    c = 4 / 3 * (math.sqrt(2) - 1) * r
    path = Path((LinePiece((0.0, -1.0), (0.0, 0.0)),
                 BezierPiece(((0.0, 0.0), (0.0, c), (r - c, r), (r, r))), LinePiece((r, r), (1.0, r))))
    [run] = _split(path, 0.5, 1e-3, soft=True)[0]
    [plain] = _split(path, 0.5, 0.0, soft=True)[0]
    assert [(sp.t0, sp.t1, sp.heading0, sp.heading1) for sp in run.spans] == \
        [(sp.t0, sp.t1, sp.heading0, sp.heading1) for sp in plain.spans]
