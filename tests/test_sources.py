"""From names, files and drawings to figures (`skatetrace.drawings.sources`), and the `fit` command."""

import json
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import numpy as np  # noqa: E402
import pytest  # noqa: E402

from skatetrace.cli import main  # noqa: E402
from skatetrace.errors import SkatetraceError  # noqa: E402
from skatetrace.figures.geometry import advance  # noqa: E402
from skatetrace.drawings.sources import resolve  # noqa: E402

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def test_builtin_and_json(tmp_path):
    r = resolve("double-flower")
    assert r.kind == "pattern" and r.unit == "model" and r.fit is None
    path = tmp_path / "fig.json"
    path.write_text(json.dumps(r.figure.to_dict()))
    assert resolve(str(path)).kind == "json"


def test_school_is_in_metres_with_the_si_skater():
    r = resolve("school:three", height=1.8, body_mass=70.0)
    assert r.kind == "school" and r.unit == "m"
    assert r.figure.params.M + r.figure.params.m == pytest.approx(70.0)
    assert 5.5 * 1.8 < r.figure.size() < 6.5 * 1.8  # two circles, each about three heights across


def test_svg_scaled_and_fitted_within_tolerance():
    r = resolve(str(EXAMPLES / "figure-eight.svg"), size="6m", tol="1mm")
    assert r.kind == "drawing" and r.unit == "m" and r.tol == pytest.approx(1e-3)
    assert r.drawing.size() == pytest.approx(6.0, rel=1e-9)
    assert r.fit.success and r.fit.hausdorff <= 1e-3
    # the circles of the eight come out as one arc each after merging equal curvatures
    curve = r.figure.curves[0]
    assert len(curve.pieces) == 2 and curve.pieces[0].curvature == pytest.approx(-curve.pieces[1].curvature)
    assert curve.closure()["closed"]


def test_merged_curve_lays_out_like_the_fit():
    r = resolve(str(EXAMPLES / "serpentine.svg"), size="8m", tol="2mm")
    for curve, pf in zip(r.figure.curves, r.fit.paths):
        lay = curve.layout()
        end = lay[-1]
        x, y, _ = advance(end.start, end.segment.curvature, end.segment.length)
        fitted_end = pf.runs[-1].poses()[-1]
        assert np.hypot(float(x) - fitted_end.x, float(y) - fitted_end.y) <= 1e-9 * r.drawing.size()


def test_default_tolerance_is_relative_to_size():
    r = resolve(str(EXAMPLES / "points-eight.csv"))
    assert r.unit == "model"
    assert r.tol == pytest.approx(1e-3 * r.drawing.size())


@pytest.mark.parametrize("kw, needle", [
    ({"size": "6m", "tol": "1e-3"}, None),      # a bare tolerance takes the figure's unit
    ({"size": "6", "tol": "1mm"}, "in m but the figure is in model units"),
    ({"size": "-3m"}, "size"),
    ({"size": "6m", "tol": "0"}, "tolerance"),
])
def test_size_and_tolerance_units(kw, needle):
    spec = str(EXAMPLES / "figure-eight.svg")
    if needle is None:
        assert resolve(spec, **kw).tol == pytest.approx(1e-3)
    else:
        with pytest.raises(SkatetraceError, match=needle):
            resolve(spec, **kw)


def test_unknown_names_say_what_is_accepted():
    with pytest.raises(SkatetraceError, match="school:NAME"):
        resolve("no-such-figure")
    with pytest.raises(SkatetraceError, match="valid names"):
        resolve("school:no-such-figure")


def test_cli_fit_writes_summary_and_plot(tmp_path, capsys):
    out = tmp_path / "fit"
    code = main(["fit", str(EXAMPLES / "serpentine.svg"), "--size", "8m", "--tol", "2mm", "--fit", "min",
                 "--out", str(out)])
    text = capsys.readouterr().out
    assert code == 0, text
    data = json.loads((out / "fit.json").read_text())
    assert data["schema"] == "skatetrace.fit/1" and data["unit"] == "m"
    assert data["hausdorff_certified"] <= 2e-3
    for p in data["paths"]:
        assert p["min_count"] is not None and p["min_count"] <= p["greedy_count"]
    assert (out / "fit.png").stat().st_size > 5000
    assert "certified Hausdorff distance" in text


def test_cli_fit_refuses_an_exact_figure(tmp_path, capsys):
    assert main(["fit", "double-flower", "--out", str(tmp_path)]) == 2
    assert "not a drawing" in capsys.readouterr().err


def test_cli_traces_a_drawing_end_to_end(tmp_path, capsys):
    # An SVG circle in model units: read, scaled, fitted, merged to one arc, traced, replayed.
    svg = tmp_path / "circle.svg"
    svg.write_text('<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 100 100">'
                   '<circle cx="50" cy="50" r="40"/></svg>')
    out = tmp_path / "t"
    code = main(["trace", str(svg), "--size", "4", "--tol", "1e-3", "--out", str(out), "--no-plots"])
    text = capsys.readouterr().out
    assert code == 0, text
    rep = json.loads((out / "report.json").read_text())
    fit = json.loads((out / "fit.json").read_text())
    assert rep["success"] and rep["max_deviation"] <= 1e-6 * rep["figure_size"]
    assert fit["hausdorff_certified"] + rep["max_deviation"] <= 1e-3 + 1e-6 * rep["figure_size"]
    assert len(fit["figure"]["curves"][0]["pieces"]) == 1


# --------------------------------------------------------------------------------------------------
# exact mode
# --------------------------------------------------------------------------------------------------
def test_exact_mode_builds_spirals_within_its_tolerance_and_keeps_the_arc_fit():
    from skatetrace.figures.geometry import Spiral

    r = resolve(str(EXAMPLES / "serpentine.svg"), size="6m", tol="1mm", exact=True)
    assert r.exact is not None and r.exact.success
    assert r.exact_tol == pytest.approx(1e-7 * r.drawing.size())
    assert r.exact.deviation <= r.exact_tol
    assert r.representation_error == r.exact.deviation and r.representation_tol == r.exact_tol
    # the arc fit is still made, for comparison, and is far coarser
    assert r.fit is not None and r.fit.success and r.fit.hausdorff > 100 * r.exact.deviation
    pieces = [p for c in r.figure.curves for p in c.pieces]
    assert sum(isinstance(p, Spiral) for p in pieces) == r.exact.n_spirals > 0
    assert any("exact mode" in n for n in r.notes) and any("arc mode" in n for n in r.notes)
    # an explicit tolerance with a unit
    loose = resolve(str(EXAMPLES / "serpentine.svg"), size="6m", exact="10um")
    assert loose.exact_tol == pytest.approx(1e-5)
    assert loose.exact.deviation <= 1e-5 and loose.exact.n_spirals < r.exact.n_spirals


def test_exact_mode_turns_kinks_of_the_drawing_into_corners():
    # three-turn.svg joins its Beziers with kinks of about 0.002 degrees: arc mode glides through
    # them, exact mode cannot (the offset would grow along the rest of the path), so it stops there.
    arc = resolve(str(EXAMPLES / "three-turn.svg"), size="6m", tol="1mm")
    ex = resolve(str(EXAMPLES / "three-turn.svg"), size="6m", tol="1mm", exact=True)
    assert len(ex.figure.curves[0].sections()) > len(arc.figure.curves[0].sections())
    assert ex.exact.deviation <= ex.exact_tol
    assert any("not tangent-continuous" in n for n in ex.notes)


def test_exact_mode_on_an_exact_figure_is_a_note():
    r = resolve("double-flower", exact=True)
    assert r.exact is None and any("exact mode applies to drawings" in n for n in r.notes)


def test_exact_mode_impossible_tolerance_is_a_clear_error():
    with pytest.raises(SkatetraceError, match="could not represent .* exactly within"):
        resolve(str(EXAMPLES / "serpentine.svg"), size="6m", exact="1e-15m")


def test_cli_traces_a_drawing_in_exact_mode(tmp_path, capsys):
    svg = tmp_path / "s.svg"
    svg.write_text('<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 100 100">'
                   '<path d="M 0 50 C 30 90, 70 10, 100 50"/></svg>')
    out = tmp_path / "t"
    code = main(["trace", str(svg), "--size", "4", "--exact", "--out", str(out), "--no-plots"])
    text = capsys.readouterr().out
    assert code == 0, text
    rep = json.loads((out / "report.json").read_text())
    fit = json.loads((out / "fit.json").read_text())
    ex = fit["exact"]
    assert rep["success"] and ex["n_spirals"] > 0 and ex["deviation"] <= ex["tol"] == pytest.approx(4e-7)
    assert ex["deviation"] + rep["max_deviation"] <= ex["tol"] + 1e-6 * rep["figure_size"]
    assert fit["hausdorff_certified"] > 10 * ex["deviation"]  # both deviations are reported
    assert "exact mode: deviation from the drawing" in text and "arc mode would deviate" in text
    types = {p["type"] for c in fit["figure"]["curves"] for p in c["pieces"]}
    assert "spiral" in types
    result = json.loads((out / "result.json").read_text())
    assert any(p.get("curvature_coefficients") for s in result["sections"] for p in s["pieces"])


def test_cli_fit_shows_both_modes(tmp_path, capsys):
    out = tmp_path / "fit"
    code = main(["fit", str(EXAMPLES / "serpentine.svg"), "--size", "6m", "--tol", "1mm", "--exact", "2um",
                 "--out", str(out), "--no-plots"])
    text = capsys.readouterr().out
    assert code == 0, text
    data = json.loads((out / "fit.json").read_text())
    assert data["hausdorff_certified"] <= 1e-3 and data["exact"]["deviation"] <= data["exact"]["tol"] == 2e-6
    assert "arc mode: certified Hausdorff distance" in text and "exact mode:" in text
    assert any(p["type"] == "spiral" for c in data["figure"]["curves"] for p in c["pieces"])


def test_a_tiny_kink_becomes_a_corner_when_keeping_it_smooth_would_break_the_fit(tmp_path, recwarn, capsys):
    """Issue 17's reproducer: a 0.086 degree kink, below the 0.5 degree corner threshold. Kept smooth,
    it turns the rest of the line and the fit fails (bound 2.8 mm at 1 mm); chosen from the tolerance,
    it is a corner (a rest) and the fit is certified."""
    path = tmp_path / "kink.svg"
    path.write_text('<svg xmlns="http://www.w3.org/2000/svg"><path d="M0 0 L10 0 L20 0.015" stroke="black" '
                    'fill="none"/></svg>')
    r = resolve(str(path), size="6m", tol="1mm")
    assert r.fit.success and r.fit.hausdorff <= 1e-3
    assert len(r.fit.paths[0].runs) == 2  # the kink split the path
    assert any("made corners (rests)" in n for n in r.notes)
    assert not [w for w in recwarn if "could not be fitted" in str(w.message)]  # the answered complaint is not shown
    # 'fit' says so too
    assert main(["fit", str(path), "--size", "6m", "--tol", "1mm", "--out", str(tmp_path / "o"), "--no-plots"]) == 0
    assert "note: joins turning by more than" in capsys.readouterr().out
    # a drawing the default threshold fits is left alone: no note, the same runs
    plain = resolve(str(EXAMPLES / "figure-eight.svg"), size="6m", tol="1mm")
    assert not any("made corners" in n for n in plain.notes)


def _polyline_svg(tmp_path, pts, closed=False, name="poly"):
    tag = "polygon" if closed else "polyline"
    path = tmp_path / f"{name}.svg"
    path.write_text(f'<svg xmlns="http://www.w3.org/2000/svg"><{tag} points="'
                    + " ".join(f"{float(x)!r},{float(y)!r}" for x, y in pts) + '" stroke="black" fill="none"/></svg>')
    return path


def test_a_circle_drawn_as_a_polygon_is_one_smooth_run_not_a_stop_at_every_vertex(tmp_path):
    # vpype-circle-3cm.svg: 189 lines, joins of 1.9 degrees (above the 0.5 of a corner) between
    # lines of 10 cm at 6 m: each was a corner, so 189 sections from rest to rest. Rounded within
    # half the tolerance (1.9 deg * 10 cm / 8 = 0.4 mm at 1 mm), it is one run of a few arcs.
    n = 189
    th = 2 * np.pi * np.arange(n) / n
    r = resolve(str(_polyline_svg(tmp_path, zip(np.cos(th), np.sin(th)), closed=True)), size="6m", tol="1mm")
    assert r.fit.success and r.fit.hausdorff <= 1e-3
    assert len(r.fit.paths[0].runs) == 1 and r.fit.n_arcs + r.fit.n_lines <= 8
    assert len(r.figure.curves[0].sections()) == 1
    from skatetrace.drawings.fitting import fit_drawing
    sharp = fit_drawing(r.drawing, 1e-3, soft_corners=False)  # as before: a corner at every vertex
    assert len(sharp.paths[0].runs) == n


@pytest.mark.parametrize("side, turn_deg, corner", [
    (0.05, 1.0, False),  # short lines, a small turn: 4 * 1 mm / 5 cm = 4.6 degrees allowed
    (0.05, 4.0, False),
    (0.05, 6.0, True),   # above SOFT_MAX_DEG (5): a corner the drawing meant, however short the lines
    (3.0, 1.0, True),    # long lines: 4 * 1 mm / 3 m = 0.08 degrees allowed
    (0.2, 1.0, False),   # 1.1 degrees allowed
    (0.2, 2.0, True),
])
def test_a_join_is_soft_only_where_the_fit_can_round_it_within_the_tolerance(tmp_path, side, turn_deg, corner):
    # three lines of `side` metres (in a drawing 6 m across), turning by `turn_deg` at each join
    from skatetrace.drawings.splitting import split_path, _split

    pts, heading, x, y = [(0.0, 0.0)], 0.0, 0.0, 0.0
    for _ in range(3):
        x, y = x + side * np.cos(heading), y + side * np.sin(heading)
        pts.append((x, y))
        heading += np.radians(turn_deg)
    pts.append((6.0, -1.0))  # the drawing's size: 6 m (a corner of its own)
    from skatetrace.drawings.curves import LinePiece, Path as CurvePath
    path = CurvePath(tuple(LinePiece(a, b) for a, b in zip(pts, pts[1:])))
    runs, _prep = _split(path, 0.5, 1e-3, soft=True)
    first_joins = [sp.reason for sp in runs[0].spans]
    assert (first_joins.count("join") < 2) == corner, first_joins
    assert len(split_path(path)) == len(pts) - 1  # without softening every join above 0.5 degrees is a corner


def test_soft_joins_that_add_up_beyond_the_tolerance_are_corners_again(tmp_path, monkeypatch):
    # softened generously, joins of 4 degrees between 20 cm lines bend the run by 1.7 mm a line at
    # 1 mm: the fit fails, and the drawing is fitted again with those joins as corners, as before
    from skatetrace.drawings import splitting

    monkeypatch.setattr(splitting, "SOFT_SHARE", 1e3)
    pts, heading, x, y = [(0.0, 0.0)], 0.0, 0.0, 0.0
    for k in range(30):
        x, y = x + 0.2 * np.cos(heading), y + 0.2 * np.sin(heading)
        pts.append((x, y))
        heading += np.radians(4.0 if k % 6 < 3 else -4.0)
    r = resolve(str(_polyline_svg(tmp_path, pts)), size="6m", tol="1mm")
    assert r.fit.success and r.fit.hausdorff <= 1e-3
    assert len(r.fit.paths[0].runs) == len(pts) - 1  # every join a corner again


def test_paths_are_picked_by_id_or_subpath_name(tmp_path, capsys):
    path = tmp_path / "two.svg"
    path.write_text('<svg xmlns="http://www.w3.org/2000/svg"><path id="a" d="M0 0 L 10 0 M 0 5 L 10 5" stroke="black"/>'
                    '<path id="b" d="M0 20 C 5 10 10 30 15 20" stroke="black" fill="none"/></svg>')
    assert [p.name for p in resolve(str(path), paths=["a"]).drawing.paths] == ["a#1", "a#2"]
    assert [p.name for p in resolve(str(path), paths="a#2").drawing.paths] == ["a#2"]
    both = resolve(str(path), paths=["b", "a#1"], size="6m", tol="1mm")
    assert [p.name for p in both.drawing.paths] == ["a#1", "b"] and both.fit.success
    with pytest.raises(SkatetraceError, match=r"no path named 'c' in 'two'; its paths are a, b"):
        resolve(str(path), paths=["c"])
    with pytest.raises(SkatetraceError, match="paths are picked from drawings"):
        resolve("double-flower", paths=["a"])
    assert main(["fit", str(path), "--path", "zz", "--out", str(tmp_path / "o")]) == 2
    assert "no path named 'zz'" in capsys.readouterr().err


HEART = ('<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 100 100"><path d="M50 30 C 50 10, 90 10, 90 40 '
         'C 90 60, 60 75, 50 90 C 40 75, 10 60, 10 40 C 10 10, 50 10, 50.01 30" fill="none" stroke="red"/></svg>')


def test_a_drawing_whose_ends_miss_by_less_than_the_tolerance_is_closed_exactly(tmp_path):
    """Issue 17: a heart whose ends miss by 0.75 mm at 6 m / 1 mm came back open."""
    path = tmp_path / "heart.svg"
    path.write_text(HEART)
    r = resolve(str(path), size="6m", tol="1mm")
    (pf,) = r.fit.paths
    assert pf.closed and any("closed 1 path(s)" in n for n in r.notes)
    # the bound is to the drawing as given: the fit's own distance plus the gap, within the tolerance
    assert 7.4e-4 <= pf.hausdorff <= 1e-3 and r.fit.hausdorff == pf.hausdorff
    closure = r.figure.curves[0].closure()
    assert closure["closed"] and closure["position_gap"] <= 1e-12 * 6
    # a looser drawing (a gap above the tolerance) stays open, and exact mode never closes
    assert not resolve(str(path), size="6m", tol="0.5mm").fit.paths[0].closed
    assert not any("closed 1 path" in n for n in resolve(str(path), size="6m", tol="1mm", exact=True).notes)


def test_closing_moves_no_point_further_than_the_gap_and_keeps_the_end_tangent():
    from skatetrace.drawings.curves import BezierPiece, Drawing, Path as DPath
    arc = BezierPiece(((0.0, 0.0), (1.0, 2.0), (3.0, 2.0), (4.0, 0.0)))
    back = BezierPiece(((4.0, 0.0), (3.0, -2.0), (1.0, -2.0), (0.003, 0.004)))  # misses the start by 0.005
    drawing = Drawing((DPath((arc, back), False, "p"),))
    closed, gaps = drawing.closed_within(0.01)
    assert gaps == {"p": pytest.approx(0.005)}
    (p,) = closed.paths
    assert p.closed and np.allclose(p.pieces[-1].end, p.pieces[0].start, atol=1e-15)
    t = np.linspace(0, 1, 401)
    assert np.max(np.hypot(*(p.pieces[-1].point(t) - back.point(t)))) <= 0.005 + 1e-15
    assert np.allclose(p.pieces[-1].d1(1.0), back.d1(1.0)) and np.allclose(p.pieces[-1].d2(1.0), back.d2(1.0))
    assert np.allclose(p.pieces[-1].d1(0.0), back.d1(0.0))
    assert drawing.closed_within(0.005)[1] == {}  # not closer than the gap: left open


def _notched_square(step: float = 4e-4):
    """A 6 m square whose right side steps out by ``step`` halfway up (two right-angle corners)."""
    from skatetrace.drawings.curves import Drawing, LinePiece, Path as DPath

    pts = [(0.0, 0.0), (6.0, 0.0), (6.0, 3.0), (6.0 + step, 3.0), (6.0 + step, 6.0), (0.0, 6.0), (0.0, 0.0)]
    pieces = tuple(LinePiece(a, b) for a, b in zip(pts[:-1], pts[1:]))
    return Drawing((DPath(pieces, True, "p"),), unit="m")


def test_a_tiny_piece_between_two_corners_is_absorbed_moving_no_point_further_than_half_its_length():
    drawing = _notched_square()
    absorbed, moves = drawing.absorbed(1e-3, 0.5)
    assert moves == {"p": pytest.approx(2e-4)}
    (p,) = absorbed.paths
    (orig,) = drawing.paths
    assert p.closed and len(p.pieces) == 5
    # the neighbours meet at the tiny piece's midpoint, their tangents at both ends kept
    before, after = p.pieces[1], p.pieces[2]
    np.testing.assert_allclose(before.end, [6.0002, 3.0], atol=1e-15)
    np.testing.assert_allclose(after.start, [6.0002, 3.0], atol=1e-15)
    t = np.linspace(0.0, 1.0, 401)
    for new, old in ((before, orig.pieces[1]), (after, orig.pieces[3])):
        assert np.max(np.hypot(*(new.point(t) - old.point(t)))) <= 2e-4 + 1e-15
        for end in (0.0, 1.0):
            np.testing.assert_allclose(new.d1(end), old.d1(end), atol=1e-12)
    # the rest untouched; the path still closes
    assert p.pieces[0] is orig.pieces[0] and p.pieces[3] is orig.pieces[4]
    np.testing.assert_allclose(p.pieces[-1].end, p.pieces[0].start, atol=1e-15)


def test_what_is_not_absorbed():
    from skatetrace.drawings.curves import Drawing, LinePiece, Path as DPath

    # longer than the limit
    assert _notched_square(2e-3).absorbed(1e-3, 0.5)[1] == {}
    # smooth at one end: a short piece continuing a line is part of a run, which the fit spans
    line = (LinePiece((0.0, 0.0), (6.0, 0.0)), LinePiece((6.0, 0.0), (6.0004, 0.0)), LinePiece((6.0004, 0.0), (6.0004, 6.0)))
    assert Drawing((DPath(line, False, "q"),)).absorbed(1e-3, 0.5)[1] == {}
    # an open path's first and last pieces longer than half the limit (dropping one would move the
    # drawing by its whole length), or smooth at their inner end
    ends = (LinePiece((0.0, 0.0), (0.0, 0.0006)), LinePiece((0.0, 0.0006), (6.0, 0.0006)),
            LinePiece((6.0, 0.0006), (6.0, 6.0)))
    assert Drawing((DPath(ends, False, "r"),)).absorbed(1e-3, 0.5)[1] == {}
    smooth = (LinePiece((-0.0004, 0.0), (0.0, 0.0)), LinePiece((0.0, 0.0), (6.0, 0.0)), LinePiece((6.0, 0.0), (6.0, 6.0)))
    assert Drawing((DPath(smooth, False, "t"),)).absorbed(1e-3, 0.5)[1] == {}
    # a path of one piece keeps it
    assert Drawing((DPath((LinePiece((0.0, 0.0), (0.0, 0.0004)),), False, "u"),)).absorbed(1e-3, 0.5)[1] == {}
    # two tiny pieces in a row: the shorter goes, its neighbour (the other) stays
    pts = [(0.0, 0.0), (6.0, 0.0), (6.0, 3.0), (6.0003, 3.0), (6.0003, 3.0004), (6.0, 6.0), (0.0, 6.0), (0.0, 0.0)]
    pieces = tuple(LinePiece(a, b) for a, b in zip(pts[:-1], pts[1:]))
    absorbed, moves = Drawing((DPath(pieces, True, "s"),)).absorbed(1e-3, 0.5)
    assert moves == {"s": pytest.approx(1.5e-4)} and len(absorbed.paths[0].pieces) == 6


def test_a_piece_of_rounding_keeps_no_neighbour_from_being_absorbed():
    # octicons' versions-16 at 6 m: a path starts with a line of 0.375 mm after a corner and its "z"
    # adds a line of 3e-16 m before it. Absorbed first (the shortest), the rounding kept its
    # neighbour, the 0.375 mm line, from being absorbed: a section nothing traced. Now the pieces of
    # rounding go in a pass of their own, and the line after them.
    from skatetrace.drawings.curves import Drawing, LinePiece, Path as DPath

    pts = [(0.0, 0.0), (0.000375, 0.0), (0.000375, 6.0), (-6.0, 6.0), (0.0, 1e-16)]
    pieces = tuple(LinePiece(a, b) for a, b in zip(pts, pts[1:] + pts[:1]))
    absorbed, moves = Drawing((DPath(pieces, True, "v"),)).absorbed(4e-3 / 3, 0.5)
    kept = absorbed.paths[0].pieces
    assert len(kept) == 3 and min(float(np.hypot(*(p.end - p.start))) for p in kept) > 1.0
    assert moves == {"v": pytest.approx(0.000375 / 2)}  # the line's half; the rounding moved nothing
    # where the rounding comes first alone, it is absorbed and the rest stays as drawn
    only = (LinePiece((0.0, 0.0), (6.0, 0.0)), LinePiece((6.0, 0.0), (6.0, 6.0)), LinePiece((6.0, 6.0), (0.0, 1e-16)),
            LinePiece((0.0, 1e-16), (0.0, 0.0)))
    absorbed, moves = Drawing((DPath(only, True, "w"),)).absorbed(4e-3 / 3, 0.5)
    assert len(absorbed.paths[0].pieces) == 3 and moves["w"] < 1e-15


def test_a_join_into_a_zero_length_handle_turns_by_its_limit_direction():
    # phosphor's phone-incoming (duotone) at 6 m: a 0.3 mm closing line meets a cubic whose first
    # handle has zero length. Read from the vanishing derivative, the join turned by 0 degrees, so
    # the line counted as part of a smooth run and was never absorbed; the fit, which takes the
    # limit direction, made a corner there, and the line was a section no stop fits.
    from skatetrace.drawings.curves import BezierPiece, Drawing, LinePiece, Path as DPath, _turn_deg

    line = LinePiece((0.0, -0.0003), (0.0, 0.0))
    cubic = BezierPiece(((0.0, 0.0), (0.0, 0.0), (-3.0, 0.0), (-6.0, 0.0)))  # leaves along -x
    assert _turn_deg(line, cubic) == pytest.approx(90.0)
    back = BezierPiece(((-6.0, 0.0), (-3.0, 0.0), (0.0, 0.0), (0.0, 0.0)))  # arrives along +x
    assert _turn_deg(back, LinePiece((0.0, 0.0), (0.0, 6.0))) == pytest.approx(90.0)
    square = (line, cubic, LinePiece((-6.0, 0.0), (-6.0, -6.0)), LinePiece((-6.0, -6.0), (0.0, -0.0003)))
    absorbed, moves = Drawing((DPath(square, True, "p"),)).absorbed(4e-3 / 3, 0.5)
    assert moves == {"p": pytest.approx(1.5e-4)} and len(absorbed.paths[0].pieces) == 3


def test_tiny_pieces_are_absorbed_where_the_fit_then_needs_its_soft_joins_as_corners(tmp_path, recwarn):
    # tabler's compass (filled) at 6 m: a closing line of 0.3 mm between two corners. Absorbed, the
    # fit gets 0.85 mm, in which the soft joins of its needle's rounded tip (lines of 1.5 to 10 mm
    # turning a few degrees) add up beyond the tolerance: the drawing was fitted without the
    # absorption, the 0.3 mm line a section that no stop fits ("no stop of length 0.00015 found").
    # Now the absorbed drawing is fitted with those joins as corners, as the drawing itself would be.
    d = ("M15.684 7.051l-6 2a1 1 0 0 0 -.633 .633l-2.007 6.026l-.023 .086l-.017 .113l-.004 .068v.044l.009 "
         ".111l.012 .07l.04 .144l.045 .1l.054 .095l.064 .09l.069 .075l.084 .074l.098 .07l.1 .054l.078 "
         ".033l.105 .033l.109 .02l.043 .005l.068 .004h.044l.111 -.009l.07 -.012l.02 -.006l.019 -.002l.074 "
         "-.022l6 -2a1 1 0 0 0 .633 -.633l2 -6a1 1 0 0 0 -1.265 -1.265z")
    svg = tmp_path / "compass.svg"
    svg.write_text('<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 24 24"><path d="M0 0h24v24h-24z" '
                   f'fill="none" stroke="black"/><path d="{d}"/></svg>')
    r = resolve(str(svg), size="6m", tol="1mm")
    assert r.fit.success and r.fit.hausdorff <= 1e-3
    assert any(n.startswith("absorbed the pieces between two corners") for n in r.notes), r.notes
    lengths = [sum(p.segment.length for p in s.pieces) for c in r.figure.curves for s in c.sections()]
    assert min(lengths) > 1e-3
    assert not [w for w in recwarn if "could not be fitted" in str(w.message)]  # the answered complaint is not shown


def test_an_open_paths_tiny_end_piece_at_a_corner_is_dropped_moving_the_drawing_by_its_length():
    # An open path that starts with a line of 0.08 mm at 6 m and turns a corner into the rest: alone
    # between its start and the corner, that line was a section nothing traces ("no stop of length
    # 4e-05 found", as in drawings of the Rust book's Ferris). An end piece has one neighbour to be
    # absorbed into, so it is dropped: each of its points lies within its length of the corner,
    # which stays.
    from skatetrace.drawings.curves import Drawing, LinePiece, Path as DPath

    pieces = (LinePiece((0.0, 0.0), (0.0, 0.0004)), LinePiece((0.0, 0.0004), (6.0, 0.0004)),
              LinePiece((6.0, 0.0004), (6.0, 6.0)), LinePiece((6.0, 6.0), (6.0003, 6.0)))
    drawing = Drawing((DPath(pieces, False, "r"),))
    dropped, moves = drawing.absorbed(1e-3, 0.5)
    assert moves == {"r": pytest.approx(4e-4)}
    (p,) = dropped.paths
    assert not p.closed and p.pieces == pieces[1:3]  # both ends dropped, the rest untouched
    # two tiny pieces at an end: the shorter of them goes, the piece beside it stays
    two = (LinePiece((0.0, 0.0), (0.0, 0.0002)), LinePiece((0.0, 0.0002), (0.0003, 0.0002)),
           LinePiece((0.0003, 0.0002), (6.0, 0.0002)))
    kept, moves = Drawing((DPath(two, False, "s"),)).absorbed(1e-3, 0.5)
    assert moves == {"s": pytest.approx(2e-4)} and kept.paths[0].pieces == two[1:]
    # end to end: an SVG of such a path is fitted within the tolerance and traced
    import tempfile

    with tempfile.TemporaryDirectory() as tmp:
        svg = Path(tmp) / "tail.svg"
        svg.write_text('<svg xmlns="http://www.w3.org/2000/svg" viewBox="-1 -1 8 8"><path d="M0 0 L0 0.00008 '
                       'L6 0.00008 L6 6" stroke="black" fill="none"/></svg>')
        r = resolve(str(svg), size="6m", tol="1mm")
    assert any(n.startswith("absorbed the pieces between two corners") and "is dropped" in n for n in r.notes)
    assert r.fit.success and r.fit.hausdorff <= 1e-3
    lengths = [sum(p.segment.length for p in s.pieces) for c in r.figure.curves for s in c.sections()]
    assert len(lengths) == 2 and min(lengths) > 1e-3


def test_a_drawing_with_a_tiny_closing_piece_is_fitted_without_it_and_within_the_tolerance():
    """Issue 17: closing lines of 0.25-1.2 mm at 6 m (icon sets) made sections too short to trace."""
    corpus = Path(__file__).parent / "data" / "svg-corpus" / "simpleicons-markdown.svg"
    r = resolve(str(corpus), size="6m", tol="1mm")
    assert any(n.startswith("absorbed the pieces between two corners") for n in r.notes)
    assert r.fit.success and r.fit.hausdorff <= 1e-3  # to the drawing as given, the move included
    # no section is shorter than the tolerance any more (the 0.25 mm step was one)
    shortest = min(sum(p.segment.length for p in s.pieces) for c in r.figure.curves for s in c.sections())
    assert shortest > 1e-3


def test_a_tiny_piece_between_two_kinks_made_corners_is_absorbed_too(tmp_path):
    # An Adwaita icon (emotes/face-sick-symbolic): its joins turn too little to be corners (under
    # 0.5 degrees) yet too much to be kept smooth, so they are made corners from the tolerance; a
    # closing line of 0.43 mm between two of them was then a section of its own, which nothing
    # traces from rest to rest ("no stop of length 0.000214 found"). Here: 0.1 degree kinks at both
    # ends of a 0.6 mm line.
    d = np.radians([0.0, 0.1, 0.2])
    pts = [(0.0, 0.0), (10.0, 0.0)]
    for angle, length in ((d[1], 0.002), (d[2], 10.0)):
        pts.append((pts[-1][0] + length * np.cos(angle), pts[-1][1] + length * np.sin(angle)))
    pts.append((pts[-1][0], 8.0))
    path = tmp_path / "kinks.svg"
    path.write_text('<svg xmlns="http://www.w3.org/2000/svg"><path d="M' + " L".join(f"{float(x)!r} {float(y)!r}" for x, y in pts)
                    + ' Z" stroke="black" fill="none"/></svg>')
    r = resolve(str(path), size="6m", tol="1mm")
    assert any("made corners (rests)" in n for n in r.notes)
    assert any(n.startswith("absorbed the pieces between two such corners") for n in r.notes)
    assert r.fit.success and r.fit.hausdorff <= 1e-3  # to the drawing as given, the move included
    lengths = [sum(p.segment.length for p in s.pieces) for c in r.figure.curves for s in c.sections()]
    assert len(lengths) == 4 and min(lengths) > 1e-3
    from skatetrace import TraceOptions, trace_and_verify

    done = trace_and_verify(r.figure, r.figure.params, TraceOptions(speed=2.0))
    assert done.success, done.message
