"""Tests of reading drawings (skatetrace.drawings.svg, .points, .functions, .lengths, .load) and their errors."""

from __future__ import annotations

import math
import pathlib
import re
import warnings

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from svgelements import Arc as SvgArc, Matrix, Path as SvgPath, Point

from skatetrace.drawings.curves import BezierPiece, Drawing, EllipticArcPiece, FunctionPiece, LinePiece, SplinePiece, curvature
from skatetrace.errors import DrawingError, SkatetraceError
from skatetrace.drawings.functions import from_function
from skatetrace.drawings.lengths import CLOSE_TOL, parse_length
from skatetrace.drawings.load import load_drawing
from skatetrace.drawings.points import read_points
from skatetrace.drawings.svg import parse_path_string, read_svg

EXAMPLES = pathlib.Path(__file__).resolve().parents[1] / "examples"
T = np.linspace(0.0, 1.0, 41)


def svg(body: str, **root) -> str:
    attrs = " ".join(f'{k}="{v}"' for k, v in root.items())
    return f'<svg xmlns="http://www.w3.org/2000/svg" {attrs}>{body}</svg>'


def flipped(points) -> np.ndarray:
    """svgelements' points ``(x, y)`` in our frame: rows x and -y."""
    xy = np.array([[float(p[0]), float(p[1])] for p in points]).T
    return np.vstack([xy[0], -xy[1]])


def svg_arc(start, rx, ry, rotation, large, sweep, end):
    """SVG's own arc, independent of svgelements: the endpoint-to-centre conversion of the SVG
    implementation notes (F.6.5, radii scaled up when too small) in long double. Returns
    ``(centre, rx, ry, phi, t1, dt)``: ``point(s) = c + R(phi) (rx cos t, ry sin t)``, ``t = t1 + s dt``."""
    L = np.longdouble
    (x1, y1), (x2, y2) = map(lambda p: (L(p[0]), L(p[1])), (start, end))
    rx, ry, phi = abs(L(rx)), abs(L(ry)), L(rotation) * L(np.pi) / 180
    c, s = np.cos(phi), np.sin(phi)
    xp, yp = c * (x1 - x2) / 2 + s * (y1 - y2) / 2, -s * (x1 - x2) / 2 + c * (y1 - y2) / 2
    lam = (xp / rx) ** 2 + (yp / ry) ** 2
    co = L(0) if lam >= 1 else np.sqrt((1 - lam) / lam) * (-1 if large == sweep else 1)
    rx, ry = (rx * np.sqrt(lam), ry * np.sqrt(lam)) if lam >= 1 else (rx, ry)
    cxp, cyp = co * rx * yp / ry, -co * ry * xp / rx
    centre = (c * cxp - s * cyp + (x1 + x2) / 2, s * cxp + c * cyp + (y1 + y2) / 2)
    t1 = np.arctan2((yp - cyp) / ry, (xp - cxp) / rx)
    dt = np.arctan2((-yp - cyp) / ry, (-xp - cxp) / rx) - t1
    dt = dt + 2 * L(np.pi) if sweep and dt < 0 else dt - 2 * L(np.pi) if not sweep and dt > 0 else dt
    return centre, rx, ry, phi, t1, dt


def arc_expected(arc, n: int, t=T) -> np.ndarray:
    """Point (n=0) or n-th derivative of :func:`svg_arc`'s arc at ``t``, y-flipped into our frame."""
    (cx, cy), rx, ry, phi, t1, dt = arc
    th = t1 + np.asarray(t, dtype=np.longdouble) * dt
    a, b = [(rx * np.cos(th), ry * np.sin(th)), (-rx * np.sin(th) * dt, ry * np.cos(th) * dt),
            (-rx * np.cos(th) * dt * dt, -ry * np.sin(th) * dt * dt)][n]
    x, y = np.cos(phi) * a - np.sin(phi) * b, np.sin(phi) * a + np.cos(phi) * b
    if n == 0:
        x, y = x + cx, y + cy
    return np.vstack([x.astype(float), -y.astype(float)])


def expected(segment, n: int, t=T, arc=None) -> np.ndarray:
    """A segment's point (n=0) or n-th derivative at ``t``, y-flipped into our frame: lines and
    Béziers from svgelements' control points (Bernstein polynomials), arcs from :func:`svg_arc`."""
    if isinstance(segment, SvgArc):
        return arc_expected(arc, n, t)
    p = flipped([segment.start, *[getattr(segment, k) for k in ("control", "control1", "control2")
                                  if getattr(segment, k, None) is not None], segment.end])
    t = np.asarray(t, dtype=float)
    for _ in range(n):  # the derivative of a Bezier of degree k is the Bezier of k (P[i+1] - P[i])
        p = (p.shape[1] - 1) * np.diff(p, axis=1)
    k = p.shape[1] - 1
    basis = np.array([math.comb(k, i) * t ** i * (1 - t) ** (k - i) for i in range(k + 1)])
    return p @ basis if k >= 0 else np.zeros((2, t.size))


def signed_area(points: np.ndarray) -> float:
    x, y = points
    return 0.5 * float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))


def all_finite(drawing: Drawing) -> bool:
    return all(np.all(np.isfinite(piece.point(T))) and np.all(np.isfinite(piece.d1(T)))
               for path in drawing.paths for piece in path.pieces)


# --------------------------------------------------------------------------------------------------
# SVG: exact conversion
# --------------------------------------------------------------------------------------------------
EVERY_COMMAND = ("M 10 20 L 30 25 H 40 V 10 C 50 0 60 30 70 20 S 90 0 100 20 Q 110 40 120 20 T 140 20 "
                 "A 15 10 30 0 1 160 40 A 15 10 -60 1 0 150 70 a 5 5 0 0 1 -10 0 Z")
# The arcs of EVERY_COMMAND (start, rx, ry, rotation, large, sweep, end); the second one's radii are too small.
EVERY_ARC = {7: ((140, 20), 15, 10, 30, 0, 1, (160, 40)), 8: ((160, 40), 15, 10, -60, 1, 0, (150, 70)),
             9: ((150, 70), 5, 5, 0, 0, 1, (140, 70))}


def every_command_segments():
    return [s for s in SvgPath(EVERY_COMMAND) if s.__class__.__name__ != "Move"]


def test_every_command_matches_svg_points_and_derivatives():
    segments = every_command_segments()
    drawing = parse_path_string(EVERY_COMMAND)
    (path,) = drawing.paths
    assert len(path.pieces) == len(segments) == 11
    assert [type(p) for p in path.pieces] == [LinePiece] * 3 + [BezierPiece] * 4 + [EllipticArcPiece] * 3 + [LinePiece]
    for k, (piece, segment) in enumerate(zip(path.pieces, segments)):
        arc = svg_arc(*EVERY_ARC[k]) if k in EVERY_ARC else None
        scale = max(1.0, float(np.abs(flipped([segment.start, segment.end])).max()))
        np.testing.assert_allclose(piece.point(T), expected(segment, 0, arc=arc), rtol=0, atol=1e-12 * scale)
        for n, method in ((1, piece.d1), (2, piece.d2)):
            np.testing.assert_allclose(method(T), expected(segment, n, arc=arc), rtol=0, atol=1e-9 * scale)
        if arc is None:  # svgelements' own evaluation agrees too (its arcs come through acos: see below)
            np.testing.assert_allclose(piece.point(T), flipped([segment.point(float(t)) for t in T]), atol=1e-12 * scale)
    assert path.closed


@pytest.mark.parametrize("seed", range(8))
def test_random_arcs_all_flags_match_svg(seed):
    rng = np.random.default_rng(seed)
    for _ in range(25):
        rx, ry = rng.uniform(0.2, 4.0, 2).tolist()
        rotation = float(rng.uniform(-360.0, 360.0))
        large, sweep = rng.integers(0, 2, 2).tolist()
        x0, y0, x1, y1 = rng.uniform(-3.0, 3.0, 4).tolist()
        d = f"M {x0!r} {y0!r} A {rx!r} {ry!r} {rotation!r} {large} {sweep} {x1!r} {y1!r}"
        arc = svg_arc((x0, y0), rx, ry, rotation, large, sweep, (x1, y1))
        (piece,) = parse_path_string(d).paths[0].pieces
        assert isinstance(piece, EllipticArcPiece) and piece.rx > 0 and piece.ry > 0
        np.testing.assert_allclose(piece.point(T), arc_expected(arc, 0), atol=1e-12)
        np.testing.assert_allclose(piece.d1(T), arc_expected(arc, 1), atol=1e-9)
        np.testing.assert_allclose(piece.d2(T), arc_expected(arc, 2), atol=1e-9)
        np.testing.assert_allclose(piece.point([0.0, 1.0]), [[x0, x1], [-y0, -y1]], atol=1e-14 * 8)


def test_y_flip_keeps_the_handedness_of_a_circle():
    # sweep=1 runs the angle up in SVG numbers (counter-clockwise in those numbers, clockwise on screen)
    d = "M 1 0 A 1 1 0 0 1 -1 0 A 1 1 0 0 1 1 0 Z"
    svg_points = flipped([SvgPath(d).point(t) for t in np.linspace(0, 1, 400, endpoint=False)])
    assert signed_area(svg_points * np.array([[1.0], [-1.0]])) > 0
    path = parse_path_string(d).paths[0]
    area = signed_area(np.hstack([p.point(np.linspace(0, 1, 200, endpoint=False)) for p in path.pieces]))
    assert area == pytest.approx(-math.pi, rel=1e-4)  # clockwise in ours, as it looks on screen
    assert np.all(curvature(path.pieces[0], T) == pytest.approx(-1.0))


# --------------------------------------------------------------------------------------------------
# SVG: transforms
# --------------------------------------------------------------------------------------------------
def test_nested_group_transforms_by_hand():
    text = svg('<g transform="translate(10,20)"><g transform="rotate(90)">'
               '<path id="p" d="M 1 0 L 2 0" transform="scale(3)"/></g></g>')
    (piece,) = read_svg(text).paths[0].pieces
    # scale 3: (3,0),(6,0); rotate 90 (x,y)->(-y,x): (0,3),(0,6); translate: (10,23),(10,26); flip y
    assert piece.start.tolist() == pytest.approx([10.0, -23.0])
    assert piece.end.tolist() == pytest.approx([10.0, -26.0])


def test_non_uniform_scale_turns_a_circle_into_an_ellipse():
    text = svg('<g transform="scale(2,3)"><circle id="c" cx="1" cy="1" r="1"/></g>')
    path = read_svg(text).paths[0]
    assert path.closed and all(isinstance(p, EllipticArcPiece) for p in path.pieces)
    pts = np.hstack([p.point(T) for p in path.pieces])
    # the circle (x-1)^2 + (y-1)^2 = 1 scaled: ((x-2)/2)^2 + ((-y-3)/3)^2 = 1 after the flip
    np.testing.assert_allclose(((pts[0] - 2) / 2) ** 2 + ((-pts[1] - 3) / 3) ** 2, 1.0, atol=1e-12)
    assert {round(p.rx, 12) for p in path.pieces} | {round(p.ry, 12) for p in path.pieces} == {2.0, 3.0}


def test_swapping_reflection_maps_an_arc_exactly():
    # matrix(0 1 1 0) swaps x and y (a reflection). The quarter circle from (1,0) to (0,1) through
    # (cos 45, sin 45) maps onto itself; after our flip its midpoint is (0.7071, -0.7071).
    text = svg('<g transform="matrix(0 1 1 0 0 0)"><path d="M 1 0 A 1 1 0 0 1 0 1"/></g>')
    (piece,) = read_svg(text).paths[0].pieces
    h = math.sqrt(0.5)
    np.testing.assert_allclose(piece.point([0.0, 0.5, 1.0]), [[0.0, h, 1.0], [-1.0, -h, 0.0]], atol=1e-12)
    np.testing.assert_allclose(np.hypot(*piece.point(T)), 1.0, atol=1e-12)


@pytest.mark.parametrize("seed", range(6))
def test_any_affine_map_is_applied_exactly_to_every_kind_of_segment(seed):
    rng = np.random.default_rng(100 + seed)
    a, b, c, d_, e, f = rng.uniform(-2.0, 2.0, 6).tolist()
    if abs(a * d_ - b * c) < 0.1:
        d_ += 1.0
    M = np.array([[a, c], [b, d_]])
    text = svg(f'<g transform="matrix({a!r},{b!r},{c!r},{d_!r},{e!r},{f!r})"><path d="{EVERY_COMMAND}"/></g>')
    pieces = read_svg(text).paths[0].pieces
    for k, (piece, segment) in enumerate(zip(pieces, every_command_segments())):
        arc = svg_arc(*EVERY_ARC[k]) if k in EVERY_ARC else None
        for n, method in ((0, piece.point), (1, piece.d1), (2, piece.d2)):
            raw = expected(segment, n, arc=arc)  # flipped; unflip, map, flip again
            want = np.diag([1.0, -1.0]) @ (M @ (np.diag([1.0, -1.0]) @ raw) + (np.array([[e], [f]]) if n == 0 else 0))
            np.testing.assert_allclose(method(T), want, atol=1e-8 * max(1.0, np.abs(want).max()))


def test_similarity_transforms_agree_with_svgelements_own_transforms():
    import io

    from svgelements import SVG, Shape

    body = ('<g transform="translate(7,-3) rotate(25) scale(1.5)"><path id="a" d="M 0 0 C 10 0 10 10 20 10 '
            'A 8 6 20 0 1 30 12 q 5 5 10 0"/></g>')
    ours = read_svg(svg(body)).paths[0].pieces
    (shape,) = [s for s in SVG.parse(io.StringIO(svg(body))).select() if isinstance(s, Shape)]  # reified
    theirs = [s for s in shape.segments() if s.__class__.__name__ != "Move"]
    assert len(ours) == len(theirs) == 3
    for piece, segment in zip(ours, theirs):
        np.testing.assert_allclose(piece.point(T), flipped([segment.point(float(t)) for t in T]), atol=1e-9)


@pytest.mark.parametrize("transform", ["matrix(0 1 1 0 0 0)", "scale(-1,1)", "rotate(30) scale(2)", "scale(2,0.5)",
                                       "matrix(-1 0 0 3 5 5)", "rotate(20) scale(3,1) skewX(10)", "scale(1e-3,1e3)"])
@pytest.mark.parametrize("d", ["M 10 0 A 12 8 30 0 1 0 9", "M 10 0 A 12 8 30 1 0 0 9", "M 10 0 A 12 8 -75 1 1 9.5 0.5",
                               "M 0 0 A 5 5 0 0 0 10 0"])
def test_arcs_under_any_map_agree_with_svgelements_points_mapped(d, transform):
    # svgelements' own point evaluation of the untransformed arc, mapped point by point: the exact image.
    # (Its own transform of an arc keeps the axes perpendicular: right for reflections and similarities,
    # several units off for a rotated ellipse under a non-uniform scale, so it is not the reference.)
    (piece,) = read_svg(svg(f'<g transform="{transform}"><path d="{d}"/></g>')).paths[0].pieces
    arc = [s for s in SvgPath(d) if isinstance(s, SvgArc)][0]
    mapped = flipped([Point(arc.point(float(t))) * Matrix(transform) for t in T])
    np.testing.assert_allclose(piece.point(T), mapped, atol=1e-12 * max(1.0, np.abs(mapped).max()))
    assert isinstance(piece, EllipticArcPiece) and piece.rx >= piece.ry > 0


# --------------------------------------------------------------------------------------------------
# SVG: structure, shapes, names, closure
# --------------------------------------------------------------------------------------------------
def test_several_subpaths_become_several_paths():
    text = svg('<path id="two" d="M 0 0 L 10 0 L 10 10 Z M 20 20 l 5 0 l 0 5"/><path d="M 0 0 L 1 1"/>')
    drawing = read_svg(text)
    assert [(p.name, p.closed, len(p.pieces)) for p in drawing.paths] == [
        ("two#1", True, 3), ("two#2", False, 2), ("path-2", False, 1)]


@pytest.mark.parametrize("d, closed", [
    ("M 0 0 L 10 0 L 10 10 Z", True),
    ("M 0 0 L 10 0 L 10 10 L 0 0", True),                     # ends at its start without Z
    ("M 0 0 L 10 0 L 10 10 L 0 1e-12", True),                 # within CLOSE_TOL of the size
    ("M 0 0 L 10 0 L 10 10 L 0 1e-6", False),                 # a visible gap
    ("M 0 0 L 10 0 L 10 10", False),
])
def test_closed_detection(d, closed):
    assert parse_path_string(d).paths[0].closed is closed


def test_basic_shapes_are_read():
    body = ('<rect id="r" x="0" y="0" width="4" height="2"/>'
            '<rect id="rr" x="10" y="0" width="4" height="2" rx="0.5"/>'
            '<circle id="c" cx="1" cy="2" r="3"/><ellipse id="e" cx="0" cy="0" rx="2" ry="1"/>'
            '<line id="l" x1="0" y1="0" x2="3" y2="4"/><polyline id="pl" points="0,0 1,1 2,0"/>'
            '<polygon id="pg" points="0,0 1,1 2,0"/>')
    drawing = read_svg(svg(body))
    by_name = {p.name: p for p in drawing.paths}
    assert list(by_name) == ["r", "rr", "c", "e", "l", "pl", "pg"]  # document order
    assert by_name["r"].closed and len(by_name["r"].pieces) == 4
    assert by_name["r"].length() == pytest.approx(12.0)
    assert by_name["rr"].closed and sum(isinstance(p, EllipticArcPiece) for p in by_name["rr"].pieces) == 4
    assert by_name["c"].closed and by_name["c"].length() == pytest.approx(6 * math.pi, rel=1e-9)
    centre = by_name["c"].pieces[0].centre
    assert centre == pytest.approx((1.0, -2.0))
    assert by_name["l"].length() == pytest.approx(5.0) and not by_name["l"].closed
    assert not by_name["pl"].closed and by_name["pg"].closed


def test_svg_without_namespace_and_from_a_file(tmp_path):
    file = tmp_path / "plain.svg"
    file.write_text('<svg><g transform="translate(1,1)"><path d="M 0 0 L 1 0"/></g></svg>')
    drawing = read_svg(file)
    assert drawing.name == "plain" and drawing.source == str(file)
    assert drawing.paths[0].pieces[0].start.tolist() == pytest.approx([1.0, -1.0])
    assert read_svg(str(file)).paths[0].length() == pytest.approx(1.0)


def test_defs_are_not_drawn_and_page_size_is_noted():
    body = '<defs><path id="hidden" d="M 0 0 L 100 100"/></defs><path id="shown" d="M 0 0 L 1 0"/>'
    drawing = read_svg(svg(body, width="210mm", height="297mm", viewBox="0 0 210 297"))
    assert [p.name for p in drawing.paths] == ["shown"]
    assert drawing.unit == "model"
    assert any("210mm" in note and "viewBox" in note for note in drawing.notes)


def test_no_warning_escapes_the_svg_parser_but_becomes_a_note():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        drawing = parse_path_string("M 0 0 A 0 5 0 0 1 10 0")  # a zero radius arc is a line
    assert isinstance(drawing.paths[0].pieces[0], LinePiece)
    assert any("zero radius" in note for note in drawing.notes)


# --------------------------------------------------------------------------------------------------
# SVG: errors
# --------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("source, match", [
    ("no/such/figure.svg", r"SVG file not found: 'no/such/figure.svg'"),
    ('<svg xmlns="http://www.w3.org/2000/svg"><g></svg>', r"not well-formed XML \(mismatched tag"),
    ("<svg", r"not well-formed XML"),
    (svg('<text>hello</text>'), r"no paths found in the SVG text: expected <path>"),
    ('<html><body/></html>', r"no paths found .*root element is <html>, not <svg>"),
    (svg('<path id="empty" d=""/>'), r"no paths found"),
    (svg('<path id="dot" d="M 5 5 L 5 5 Z"/>'), r"<path id='dot'> has only zero-length segments"),
    (svg('<circle id="zero" cx="1" cy="1" r="0"/>'), r"<circle id='zero'> has no extent: .*'r': '0'.*give it r > 0"),
    (svg('<path id="inf" d="M 0 0 L 1e999 1"/>'), r"<path id='inf'>.*non-finite coordinates"),
    (svg('<path id="big" d="M 0 0 L 1e120 1"/>'), r"coordinates reach 1e\+120, beyond the supported 1e\+100"),
    (svg('<path id="loop" d="M 0 0 A 1 1 0 0 1 0 0"/>'), r"<path id='loop'> has only zero-length segments"),
    (svg('<path id="wide" d="M 0 0 A 1e300 1e300 0 0 1 3 4"/>'),
     r"<path id='wide'>, wide segment 1: the elliptical arc from \(0.0, 0.0\) to \(3.0, 4.0\) cannot be evaluated"),
    (svg('<path id="cut" d="M 0 0 L 1"/>'), r"<path id='cut'>: the path data 'M 0 0 L 1' cannot be read"),
    (svg('<path id="junk" d="hello"/>'), r"cannot be read .*expected SVG path commands"),
    (svg('<g transform="scale(0)"><path id="p" d="M 0 0 L 1 1"/></g>'),
     r"<path id='p'>: its transform matrix\(0, 0, 0, 0, 0, 0\) is singular"),
    (svg('<g transform="scale(1,0)"><path id="p" d="M 0 0 A 1 1 0 0 1 1 1"/></g>'), r"is singular"),
    # issue 19: this said "singular (determinant inf)"
    (svg('<path id="p" transform="scale(1e200)" d="M 0 0 L 1 1"/>'), r"scales beyond floating point"),
    (svg('<g transform="rotate(abc)"><path d="M 0 0 L 1 1"/></g>'), r"a transform attribute cannot be read"),
    (svg('<circle id="c" cx="1" cy="1"/>'), r"<circle id='c'> has no extent: its size is zero, missing"),
    (svg('<rect id="r" width="3"/>'), r"<rect id='r'> has no extent: .*give it width and height > 0"),
])
def test_svg_errors(source, match):
    with pytest.raises(DrawingError, match=match):
        read_svg(source)


@pytest.mark.parametrize("nothing, note", [
    # a graph layout's invisible node (Graphviz writes these; the Rust book's trpl15-04.svg has one)
    ('<ellipse id="z" cx="270" cy="-46" rx="0" ry="0"/>', r"skipped 1 element\(s\) of zero size, which SVG does not "
                                                           r"draw: <ellipse id='z'>"),
    ('<circle id="z" cx="1" cy="1" r="0"/>', r"of zero size.*<circle id='z'>"),
    ('<rect id="z" x="1" y="1" width="0" height="3"/>', r"of zero size.*<rect id='z'>"),
    ('<path id="z" d="M 5 5 L 5 5 Z"/>', r"skipped 1 element\(s\) of only zero-length segments.*<path id='z'>"),
])
def test_an_element_that_draws_nothing_is_skipped_where_anything_else_is_drawn(nothing, note):
    # SVG draws nothing for a zero size (and a point for a path of zero length): the drawing is the rest,
    # with a note; alone, such an element is still an error (test_svg_errors)
    d = read_svg(svg(f'<path id="line" d="M 0 0 L 10 0"/>{nothing}'))
    assert [p.name for p in d.paths] == ["line"]
    assert sum(bool(re.search(note, n)) for n in d.notes) == 1, d.notes
    with pytest.raises(DrawingError, match="has only zero-length segments|has no extent"):
        read_svg(svg(nothing))


def test_svg_error_types():
    assert issubclass(DrawingError, SkatetraceError) and issubclass(DrawingError, ValueError)
    with pytest.raises(DrawingError, match="expects a file name or SVG text, got int"):
        read_svg(3)


def test_unreadable_file_names_the_path(tmp_path):
    with pytest.raises(DrawingError, match=f"cannot read SVG file '{tmp_path}'"):
        read_svg(tmp_path)  # a directory
    binary = tmp_path / "binary.svg"
    binary.write_bytes(b"\x89PNG\r\n\x1a\n\x00\x00")
    with pytest.raises(DrawingError, match=f"{binary} is not well-formed XML"):
        read_svg(binary)


@pytest.mark.parametrize("d, match", [
    ("", "the path data is empty"),
    ("   ", "the path data is empty"),
    ("M 3 4", "draws nothing"),
    ("M 0 0 L nan 1", "cannot be read"),
    ("M 0 0 C 0 0 0 0 0 0", "only zero-length segments"),
    (None, "must be a string"),
])
def test_path_string_errors(d, match):
    with pytest.raises(DrawingError, match=match):
        parse_path_string(d)


# --------------------------------------------------------------------------------------------------
# Degenerate input: the catalogue from arc fitters' bug trackers
# --------------------------------------------------------------------------------------------------
def test_zero_length_segments_are_dropped_with_a_note():
    drawing = parse_path_string("M 0 0 L 1 0 L 1 0 C 1 0 1 0 1 0 L 2 0")
    pieces = drawing.paths[0].pieces
    assert [p.start.tolist() for p in pieces] == [[0.0, 0.0], [1.0, 0.0]]
    assert sum("zero length and was dropped" in n for n in drawing.notes) == 2


def test_zero_length_handle_is_kept_and_noted():
    drawing = parse_path_string("M 0 0 C 0 0 10 10 20 0")  # P0 == P1
    (piece,) = drawing.paths[0].pieces
    assert isinstance(piece, BezierPiece)
    assert np.allclose(piece.d1(0.0), 0.0) and np.all(np.isfinite(piece.d1(T)))
    assert np.all(np.isfinite(piece.d2(T))) and not np.allclose(piece.d2(0.0), 0.0)
    assert any("zero-length handle at its start (t=0)" in n for n in drawing.notes)
    end = parse_path_string("M 0 0 Q 10 10 10 10")  # quadratic with its control on the end point
    assert any("zero-length handle at its end (t=1)" in n for n in end.notes)


def test_collinear_control_points_and_self_intersections_are_fine():
    collinear = parse_path_string("M 0 0 C 2 0 -1 0 1 0")  # doubles back along the x axis: a cusp inside
    loop = parse_path_string("M 0 0 C 10 10 -10 10 0 0")  # starts and ends at the same point: a loop
    bowtie = parse_path_string("M 0 0 L 1 1 L 1 0 L 0 1 Z")
    for drawing in (collinear, loop, bowtie):
        assert all_finite(drawing)
    assert np.allclose(collinear.paths[0].pieces[0].point(T)[1], 0.0)
    assert loop.paths[0].closed and bowtie.paths[0].closed


def test_tiny_segments_are_kept_and_noted():
    drawing = parse_path_string("M 0 0 L 10 0 L 10 1e-11 L 10 10")
    assert len(drawing.paths[0].pieces) == 3
    assert any("shorter than" in n and "[2]" in n for n in drawing.notes)


def test_huge_and_tiny_coordinates():
    huge = parse_path_string("M 1e90 1e90 C 2e90 1e90 2e90 2e90 3e90 2e90")
    tiny = parse_path_string("M 1e-200 0 C 2e-200 0 2e-200 1e-200 3e-200 1e-200")
    for drawing in (huge, tiny):
        assert all_finite(drawing)
        assert np.all(np.isfinite(drawing.paths[0].pieces[0].d2(T)))
    assert tiny.size() == pytest.approx(2e-200)


def test_cusp_within_rounding_of_an_endpoint():
    drawing = parse_path_string("M 0 0 C 1e-13 0 5 5 10 0")  # derivative ~0 at t=0, not exactly
    piece = drawing.paths[0].pieces[0]
    assert all_finite(drawing) and np.hypot(*piece.d1(0.0)) < 1e-12
    assert not any("zero-length handle" in n for n in drawing.notes)


def test_empty_element_next_to_a_real_one_is_skipped_with_a_note():
    drawing = read_svg(svg('<path id="empty" d=""/><path id="real" d="M 0 0 L 1 0"/>'))
    assert [p.name for p in drawing.paths] == ["real"]
    assert any("<path id='empty'> is empty" in n for n in drawing.notes)


def test_zero_length_subpath_next_to_a_real_one_is_dropped_with_a_note():
    drawing = parse_path_string("M 0 0 L 1 0 M 5 5 L 5 5")
    assert [p.name for p in drawing.paths] == ["path#1"]
    assert any("subpath path#2 has only zero-length segments" in n for n in drawing.notes)


# --------------------------------------------------------------------------------------------------
# Point lists
# --------------------------------------------------------------------------------------------------
def circle_text(n=64, tangents=False, repeat_first=False, header="x,y") -> str:
    th = 2 * np.pi * np.arange(n) / n
    rows = [np.cos(th), np.sin(th)] + ([-np.sin(th), np.cos(th)] if tangents else [])
    lines = [header] + [",".join(repr(float(v)) for v in row) for row in np.array(rows).T]
    if repeat_first:
        lines.append(lines[1])
    return "\n".join(lines) + "\n"


@pytest.mark.parametrize("tangents", [False, True])
@pytest.mark.parametrize("how", ["closed=True", "repeated first point"])
def test_spline_through_a_circle(tangents, how):
    if how == "closed=True":
        drawing = read_points(circle_text(tangents=tangents), closed=True)
    else:
        drawing = read_points(circle_text(tangents=tangents, repeat_first=True))
    (path,) = drawing.paths
    (piece,) = path.pieces
    assert path.closed and isinstance(piece, SplinePiece)
    t = np.linspace(0.0, 1.0, 4001)
    assert np.abs(np.hypot(*piece.point(t)) - 1.0).max() < 1e-5
    assert np.abs(curvature(piece, t) - 1.0).max() < 2e-3  # counter-clockwise: +1
    assert path.length() == pytest.approx(2 * math.pi, rel=1e-6)
    # periodic: position, tangent and curvature continuous across the start
    np.testing.assert_allclose(piece.point(1.0), piece.point(0.0), atol=1e-14)
    np.testing.assert_allclose(piece.d1(1.0), piece.d1(0.0), atol=1e-9)
    if not tangents:
        np.testing.assert_allclose(piece.d2(1.0), piece.d2(0.0), atol=1e-6)


def test_given_tangents_are_honoured():
    drawing = read_points("0 0 1 0\n1 1 0 1\n0 2 -1 0\n")
    piece = drawing.paths[0].pieces[0]
    u = piece.spline.x  # knots
    for ui, direction in zip(u, [(1, 0), (0, 1), (-1, 0)]):
        d1 = piece.d1(ui)[:, 0]
        assert d1 / np.hypot(*d1) == pytest.approx(direction, abs=1e-12)


def test_corners_split_a_path_into_pieces_that_meet():
    text = "# an L with rounded arms\nx y\n0 0\n1 0.1\n2 0\n2 0\n2.1 1\n2 2\n"
    (path,) = read_points(text).paths
    assert len(path.pieces) == 2 and not path.closed
    a, b = path.pieces
    np.testing.assert_allclose(a.end, [2.0, 0.0], atol=1e-14)
    np.testing.assert_allclose(b.start, [2.0, 0.0], atol=1e-14)
    ta, tb = a.d1(1.0)[:, 0], b.d1(0.0)[:, 0]
    assert abs(ta[0] * tb[1] - ta[1] * tb[0]) / (np.hypot(*ta) * np.hypot(*tb)) > 0.5  # a real corner


def test_corner_tangents_in_and_out():
    text = "0,0,1,0\n1,0,1,0\n1,0,0,1\n1,1,0,1\n"  # at (1, 0) in along +x, out along +y
    a, b = read_points(text).paths[0].pieces
    assert a.d1(1.0)[:, 0] / np.hypot(*a.d1(1.0)[:, 0]) == pytest.approx([1.0, 0.0])
    assert b.d1(0.0)[:, 0] / np.hypot(*b.d1(0.0)[:, 0]) == pytest.approx([0.0, 1.0])


def test_square_of_corners_closed():
    text = "0 0\n0 0\n1 0\n1 0\n1 1\n1 1\n0 1\n0 1\n0 0\n"
    (path,) = read_points(text).paths
    assert path.closed and len(path.pieces) == 4 and all(isinstance(p, LinePiece) for p in path.pieces)
    assert path.length() == pytest.approx(4.0)


def test_closed_path_with_one_corner_starts_at_it():
    th = np.linspace(0, 2 * np.pi, 13)[:-1]
    pts = np.c_[np.cos(th), np.sin(th)]
    rows = [pts[k].tolist() for k in range(12)]
    rows.insert(4, pts[3].tolist())  # (cos 90, sin 90) repeated: a corner at the top
    text = "\n".join(f"{x!r} {y!r}" for x, y in rows) + "\n"
    drawing = read_points(text, closed=True)
    (path,) = drawing.paths
    (piece,) = path.pieces
    np.testing.assert_allclose(piece.start, pts[3], atol=1e-14)
    np.testing.assert_allclose(piece.end, pts[3], atol=1e-14)
    assert path.closed and any("starts at its first corner" in n for n in drawing.notes)


def test_two_points_with_tangents_close_into_a_loop():
    (path,) = read_points("1,0,0,1\n-1,0,0,-1\n", closed=True).paths
    (piece,) = path.pieces
    assert path.closed and isinstance(piece, SplinePiece)
    assert all_finite(Drawing((path,)))
    np.testing.assert_allclose(piece.point([0.0, 0.5, 1.0]), [[1.0, -1.0, 1.0], [0.0, 0.0, 0.0]], atol=1e-14)
    for t, direction in ((0.0, [0.0, 1.0]), (0.5, [0.0, -1.0]), (1.0, [0.0, 1.0])):
        np.testing.assert_allclose(unit(piece.d1(t)), direction, atol=1e-14)


def test_two_points_make_a_line_three_a_parabola():
    assert isinstance(read_points("0,0\n3,4\n").paths[0].pieces[0], LinePiece)
    piece = read_points("0,0\n1,1\n2,0\n").paths[0].pieces[0]
    x, y = piece.point(np.linspace(0, 1, 11))
    np.testing.assert_allclose(y, x * (2 - x), atol=1e-12)  # not-a-knot through 3 points: the parabola


def test_blank_lines_separate_paths_and_comments_do_not(tmp_path):
    text = "x,y  # header\n0,0\n# a comment line does not end the path\n1,0\n2,1\n\n\n5,5\n6,5\n"
    file = tmp_path / "two.csv"
    file.write_text(text)
    drawing = read_points(file)
    assert drawing.name == "two" and [p.name for p in drawing.paths] == ["two#1", "two#2"]
    assert [len(p.pieces) for p in drawing.paths] == [1, 1]
    assert isinstance(drawing.paths[0].pieces[0], SplinePiece)


def test_closed_false_keeps_a_returning_path_open():
    text = circle_text(n=16, repeat_first=True)
    assert not read_points(text, closed=False).paths[0].closed
    assert read_points(text).paths[0].closed


@pytest.mark.parametrize("text, closed, match", [
    ("x,y\n0,0\n1,1\n2,2,3\n", None, r"line 4: 3 values in '2,2,3'; expected 2 \(x, y\) or 4"),
    ("0,0\n1,1\n2,2,1,0\n", None, r"line 3: 4 values, but line 1 has 2"),
    ("x,y\n0,0\n1,abc\n", None, r"line 3: cannot read '1,abc' as numbers"),
    ("0,0\n1,nan\n", None, r"line 2: '1,nan' is not finite"),
    ("0,0\n1e999,0\n", None, r"line 2: '1e999,0' is not finite"),
    ("0,0,0,0\n1,0,1,0\n", None, r"line 1: the tangent \(0, 0\) has no direction"),
    ("1,1\n1,1\n", None, r"all points coincide"),
    ("0,0\n1,0\n\n5,5\n5,5\n", None, r"lines 4-5: a path needs at least 2 distinct points, got 1"),
    ("0,0\n1,0\n", True, r"a closed path needs at least 3 distinct points \(2 with tangents\), got 2"),
    ("# nothing\n\n", None, r"no points found in the point text"),
    ("0,0\n1e120,0\n", None, r"coordinates reach 1e\+120, beyond the supported 1e\+100"),
    ("1,5;2,5\n3,5;4,5\n", None, r"line 2: cannot read '3,5;4,5'"),  # decimal commas: line 1 is a header
])
def test_point_list_errors(text, closed, match):
    with pytest.raises(DrawingError, match=match):
        read_points(text, closed=closed)


def test_point_list_file_errors(tmp_path):
    with pytest.raises(DrawingError, match="point list file not found: 'missing.csv'"):
        read_points("missing.csv")
    bad = tmp_path / "latin1.csv"
    bad.write_bytes("x,y # caf\xe9\n0,0\n1,1\n".encode("latin-1"))
    with pytest.raises(DrawingError, match="is not a UTF-8 text file"):
        read_points(bad)
    with pytest.raises(DrawingError, match="closed must be None, True or False"):
        read_points("0,0\n1,1\n", closed="yes")
    with pytest.raises(DrawingError, match="expects a file name or text, got list"):
        read_points([(0, 0), (1, 1)])


# --------------------------------------------------------------------------------------------------
# Parametric functions
# --------------------------------------------------------------------------------------------------
def test_from_function_circle_with_and_without_derivatives():
    fn = lambda u: (2 * np.cos(u), 2 * np.sin(u))  # noqa: E731
    exact = from_function(fn, 0.0, 2 * np.pi, closed=True, dfn=lambda u: (-2 * np.sin(u), 2 * np.cos(u)),
                          d2fn=lambda u: (-2 * np.cos(u), -2 * np.sin(u)), name="c")
    numeric = from_function(fn, 0.0, 2 * np.pi, closed=True)
    for drawing, tol in ((exact, 1e-12), (numeric, 1e-6)):
        (path,) = drawing.paths
        (piece,) = path.pieces
        assert isinstance(piece, FunctionPiece) and path.closed
        np.testing.assert_allclose(curvature(piece, T), 0.5, atol=tol * 100)
        assert path.length() == pytest.approx(4 * np.pi, rel=tol)
    assert exact.name == "c" and exact.paths[0].name == "c"


@pytest.mark.parametrize("kwargs, match", [
    (dict(fn=3), "fn must be a function"),
    (dict(fn=lambda u: (math.cos(u), math.sin(u))), r"evaluating fn .* failed .*accept a numpy array"),
    (dict(fn=lambda u: (1.0, 2.0)), r"evaluating fn .* failed .*shape \(2, n\)"),
    (dict(fn=lambda u: (u, np.log(u - 0.5))), r"fn is not finite"),
    (dict(fn=lambda u: (0 * u + 1, 0 * u)), r"the curve is a single point"),
    (dict(fn=lambda u: (u, u), closed=True), r"closed=True but fn\(u1\)"),
    (dict(fn=lambda u: (u, u), u1=0.0), r"must be finite and not empty"),
    (dict(fn=lambda u: (u, u), u1="x"), r"u0 and u1 must be numbers"),
    (dict(fn=lambda u: (u, np.sqrt(u))), r"its derivative is not finite.*give dfn/d2fn"),
    (dict(fn=lambda u: (u, u), dfn="no"), r"dfn must be a function"),
    (dict(fn=lambda u: (1e120 * u, u)), r"coordinates reach 1e\+120"),
])
def test_from_function_errors(kwargs, match):
    args = dict(u0=0.0, u1=1.0) | kwargs
    fn = args.pop("fn")
    with pytest.raises(DrawingError, match=match):
        from_function(fn, args.pop("u0"), args.pop("u1"), **args)


# --------------------------------------------------------------------------------------------------
# Lengths and files
# --------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("text, value, unit", [
    ("6m", 6.0, "m"), ("6 m", 6.0, "m"), ("600cm", 6.0, "m"), ("6000mm", 6.0, "m"),
    ("20ft", 6.096, "m"), ("240in", 6.096, "m"), ("6", 6.0, "model"), ("6u", 6.0, "model"),
    (" 2.5 M ", 2.5, "m"), ("1e1cm", 0.1, "m"), (".5m", 0.5, "m"), ("7.", 7.0, "model"),
    ("10um", 1e-5, "m"), ("10 \u00b5m", 1e-5, "m"), ("0.5\u03bcm", 5e-7, "m"),
])
def test_parse_length(text, value, unit):
    got_value, got_unit = parse_length(text)
    assert got_value == pytest.approx(value, rel=1e-15) and got_unit == unit


@pytest.mark.parametrize("text, match", [
    ("-6m", "must be positive"), ("0", "must be positive"), ("0cm", "must be positive"),
    ("1e999m", "must be positive and finite"), ("six metres", "cannot read the length 'six metres'"),
    ("6km", "cannot read"), ("6 m m", "cannot read"), ("", "cannot read"), ("1,5m", "cannot read"),
    ("nan", "cannot read"), (6, "must be text"),
])
def test_parse_length_errors(text, match):
    with pytest.raises(DrawingError, match=match) as info:
        parse_length(text)
    assert "'6m', '6 m', '600cm', '6000mm', '20ft'" in str(info.value)


def test_load_drawing_dispatches_on_the_suffix(tmp_path):
    (tmp_path / "a.SVG").write_text(svg('<path d="M 0 0 L 1 0"/>'))
    (tmp_path / "b.txt").write_text("0 0\n1 0\n")
    (tmp_path / "c.dat").write_text("0 0\n1 0\n")
    assert isinstance(load_drawing(tmp_path / "a.SVG").paths[0].pieces[0], LinePiece)
    assert load_drawing(str(tmp_path / "b.txt")).name == "b"
    assert load_drawing(tmp_path / "c.dat").paths[0].length() == pytest.approx(1.0)
    with pytest.raises(DrawingError, match=r"unsupported file type '.dxf'; supported: .svg .*\.csv, \.txt, \.dat"):
        load_drawing(tmp_path / "d.dxf")
    with pytest.raises(DrawingError, match=r"unsupported file type '\(no suffix\)'"):
        load_drawing("figure")
    with pytest.raises(DrawingError, match="file not found"):
        load_drawing(tmp_path / "missing.csv")


# --------------------------------------------------------------------------------------------------
# Examples
# --------------------------------------------------------------------------------------------------
def unit(v):
    v = np.asarray(v, float).reshape(2)
    return v / np.hypot(*v)


def test_example_figure_eight():
    drawing = load_drawing(EXAMPLES / "figure-eight.svg")
    (path,) = drawing.paths
    assert path.name == "eight" and path.closed and len(path.pieces) == 8
    assert all(isinstance(p, EllipticArcPiece) and p.rx == pytest.approx(45) and p.ry == pytest.approx(45)
               for p in path.pieces)
    # layer translate(105,148.5): the circles' centres are (60, -148.5) and (150, -148.5) after the flip
    assert {tuple(np.round(p.centre, 9)) for p in path.pieces} == {(60.0, -148.5), (150.0, -148.5)}
    for a, b in zip(path.pieces, path.pieces[1:] + path.pieces[:1]):  # tangent continuous everywhere
        np.testing.assert_allclose(a.end, b.start, atol=1e-12)
        np.testing.assert_allclose(unit(a.d1(1.0)), unit(b.d1(0.0)), atol=1e-12)
    kappa = [float(curvature(p, 0.5)[0]) for p in path.pieces]
    np.testing.assert_allclose(kappa, [1 / 45] * 4 + [-1 / 45] * 4)  # left loop anticlockwise, right clockwise
    assert drawing.size() == pytest.approx(180.0)
    on_ice = drawing.scaled_to(6.0, "m")
    assert on_ice.size() == pytest.approx(6.0) and on_ice.unit == "m"


def test_example_serpentine():
    drawing = load_drawing(EXAMPLES / "serpentine.svg")
    (path,) = drawing.paths
    assert not path.closed
    assert [type(p).__name__ for p in path.pieces] == ["LinePiece"] + ["BezierPiece"] * 4
    # m 0,0 -> matrix(.., 20, 100) -> (20, 100) -> layer translate(10, 20) -> (30, 120) -> flip
    assert path.pieces[0].start.tolist() == pytest.approx([30.0, -120.0])
    # the lead-in l 30,0 is rotated by 30 degrees and halved; on screen it goes right and down
    assert path.pieces[0].end.tolist() == pytest.approx([30 + 15 * math.cos(math.pi / 6), -120 - 7.5])
    for piece in path.pieces[1:4]:  # an inflection inside each S-shaped cubic
        k = curvature(piece, np.linspace(0.05, 0.95, 19))
        assert k.min() < 0 < k.max()
    for a, b in zip(path.pieces, path.pieces[1:]):
        np.testing.assert_allclose(unit(a.d1(1.0)), unit(b.d1(0.0)), atol=1e-6)


def test_example_three_turn():
    drawing = load_drawing(EXAMPLES / "three-turn.svg")
    (path,) = drawing.paths
    assert path.closed and len(path.pieces) == 6 and all(isinstance(p, BezierPiece) for p in path.pieces)
    first, last = path.pieces[0], path.pieces[-1]
    tip = np.array([105.0, -103.5])  # (0, -45) in the layer, translated, flipped
    np.testing.assert_allclose(first.start, tip)
    np.testing.assert_allclose(last.end, tip)
    # the cusp: the tangent reverses (leaving upwards, away from the centre; arriving downwards)
    np.testing.assert_allclose(unit(first.d1(0.0)), [0.0, 1.0], atol=1e-12)
    np.testing.assert_allclose(unit(last.d1(1.0)), [0.0, -1.0], atol=1e-12)
    for a, b in zip(path.pieces, path.pieces[1:]):  # smooth everywhere else
        np.testing.assert_allclose(unit(a.d1(1.0)), unit(b.d1(0.0)), atol=1e-3)
    circle = np.hstack([p.point(T) for p in path.pieces[1:5]])
    np.testing.assert_allclose(np.hypot(circle[0] - 105.0, circle[1] + 148.5), 60.0, rtol=1e-3)
    assert np.all(curvature(path.pieces[2], T) < 0)  # clockwise round the circle


def test_example_point_list_eight():
    drawing = load_drawing(EXAMPLES / "points-eight.csv")
    (path,) = drawing.paths
    (piece,) = path.pieces
    assert path.closed and isinstance(piece, SplinePiece)
    assert drawing.size() == pytest.approx(6.0, abs=1e-4)
    # every point on the spline is on the lemniscate (x^2 + y^2)^2 = a^2 (x^2 - y^2), a = 3
    x, y = piece.point(np.linspace(0, 1, 2001))
    residual = (x ** 2 + y ** 2) ** 2 - 9 * (x ** 2 - y ** 2)
    assert np.abs(residual).max() < 2e-3 * 81
    rows = sum(1 for line in (EXAMPLES / "points-eight.csv").read_text().splitlines()
               if line and line[0] in "-0123456789")
    assert 60 <= rows <= 100


# --------------------------------------------------------------------------------------------------
# Properties: random (and degenerate) input never gives NaN, never anything but a DrawingError
# --------------------------------------------------------------------------------------------------
SPECIAL = [0.0, 1.0, -1.0, 1e-300, -1e-300, 5e-324, 1e-12, 1e12, 1e99, -1e99, 1e120, 1e300, float("nan"), float("inf")]
numbers = st.one_of(st.floats(-1e3, 1e3), st.sampled_from(SPECIAL), st.floats(allow_nan=True, allow_infinity=True))


@st.composite
def path_data(draw):
    pool = draw(st.lists(st.tuples(numbers, numbers), min_size=1, max_size=5))
    pool += [(k * pool[0][0], k * pool[0][1]) if all(map(math.isfinite, pool[0])) else (k, 2 * k)
             for k in (2.0, 3.0)]  # collinear with the first point
    point = st.sampled_from(pool)
    fmt = lambda p: f"{p[0]!r} {p[1]!r}"  # noqa: E731
    parts = [f"M {fmt(draw(point))}"]
    for _ in range(draw(st.integers(1, 6))):
        kind = draw(st.sampled_from("LQCAZ"))
        if kind == "L":
            parts.append(f"L {fmt(draw(point))}")
        elif kind == "Q":
            parts.append(f"Q {fmt(draw(point))} {fmt(draw(point))}")
        elif kind == "C":
            parts.append(f"C {fmt(draw(point))} {fmt(draw(point))} {fmt(draw(point))}")
        elif kind == "A":
            rx, ry = draw(numbers), draw(numbers)
            flags = f"{draw(st.integers(0, 1))} {draw(st.integers(0, 1))}"
            parts.append(f"A {rx!r} {ry!r} {draw(numbers)!r} {flags} {fmt(draw(point))}")
        else:
            parts.append("Z")
    return " ".join(parts)


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(path_data())
def test_random_path_data_never_nan_never_a_crash(d):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            drawing = parse_path_string(d)
        except DrawingError:
            return
    assert all_finite(drawing)
    for path in drawing.paths:
        assert isinstance(path.closed, bool) and path.pieces


@st.composite
def point_text(draw):
    pool = draw(st.lists(st.tuples(numbers, numbers), min_size=2, max_size=6))
    tangents = draw(st.booleans())
    rows = draw(st.lists(st.sampled_from(pool), min_size=1, max_size=12))  # repeats: corners
    lines = []
    for x, y in rows:
        row = [x, y] + ([draw(numbers), draw(numbers)] if tangents else [])
        lines.append(", ".join(repr(v) for v in row))
        if draw(st.integers(0, 9)) == 0:
            lines.append("")  # a new path
    return "x, y\n" + "\n".join(lines) + "\n"


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(point_text(), st.sampled_from([None, True, False]))
def test_random_point_lists_never_nan_never_a_crash(text, closed):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            drawing = read_points(text, closed=closed)
        except DrawingError:
            return
    assert all_finite(drawing)
    for path in drawing.paths:
        for a, b in zip(path.pieces, path.pieces[1:]):
            np.testing.assert_allclose(a.end, b.start, rtol=1e-9, atol=CLOSE_TOL * drawing.size())


# --- what an SVG draws: hidden and unpainted elements (issue 17) -----------------------------------------

def _names(svg: str) -> list[str]:
    return [p.name for p in read_svg(svg).paths]


def test_an_icon_frame_that_paints_nothing_and_a_hidden_layer_are_not_traced():
    svg = ('<svg xmlns="http://www.w3.org/2000/svg"><path id="frame" d="M0 0h24v24H0z" fill="none"/>'
           '<g style="display:none"><path id="draft" d="M0 0 L 100 100"/></g>'
           '<path id="arc" d="M2 12 C 6 2 18 2 22 12" stroke="black" fill="none"/></svg>')
    drawing = read_svg(svg)
    assert [p.name for p in drawing.paths] == ["arc"]
    assert drawing.size() < 24  # the frame no longer sets the scale
    assert any("paint nothing" in n and "frame" in n for n in drawing.notes)
    assert any("hidden" in n and "draft" in n for n in drawing.notes)


@pytest.mark.parametrize("attrs, drawn", [
    ('fill="none" stroke="black"', True),
    ('fill="none" style="stroke: none"', False),           # style wins over nothing; both none
    ('fill="none" stroke="black" style="stroke:none"', False),  # style wins over the attribute
    ('style="fill:none;stroke:#333"', True),
    ("", True),                                           # SVG's default fill is black
    ('fill="none" stroke="inherit"', False),              # inherits the root's (default) none
])
def test_paint_follows_style_over_attributes(attrs, drawn):
    svg = (f'<svg xmlns="http://www.w3.org/2000/svg"><path id="p" d="M0 0 L 10 0" {attrs}/>'
           '<path id="ref" d="M0 5 L 10 5" stroke="black"/></svg>')
    assert ("p" in _names(svg)) is drawn


def test_visibility_is_inherited_and_can_be_set_back():
    svg = ('<svg xmlns="http://www.w3.org/2000/svg"><g visibility="hidden" stroke="black">'
           '<path id="gone" d="M0 0 L 10 0"/><path id="back" d="M0 5 L 10 5" visibility="visible"/></g></svg>')
    assert _names(svg) == ["back"]


def test_a_drawing_where_nothing_is_painted_is_read_anyway_but_all_hidden_is_an_error():
    plain = '<svg xmlns="http://www.w3.org/2000/svg"><path id="p" d="M0 0 L 10 0" fill="none"/></svg>'
    drawing = read_svg(plain)
    assert [p.name for p in drawing.paths] == ["p"] and any("nothing in the drawing is painted" in n
                                                             for n in drawing.notes)
    hidden = '<svg xmlns="http://www.w3.org/2000/svg"><path id="p" d="M0 0 L 10 0" style="display:none"/></svg>'
    with pytest.raises(DrawingError, match="every drawable element .* is hidden"):
        read_svg(hidden)


def test_points_too_close_for_double_precision_are_refused_with_a_reason():
    """Found by hypothesis: a step of 1e3 beside a run of 1e12 vanished from the knots and scipy raised."""
    text = ("x, y\n0.0, -95.0\n0.0, -95.0\n0.0, 906.0\n\n0.0, -95.0\n0.0, 906.0\n\n0.0, -95.0\n0.0, 0.0\n"
            "0.0, 906.0\n0.0, -95.0\n0.0, 1000000000000.0\n\n")
    with pytest.raises(DrawingError, match="too close to tell apart in double precision"):
        read_points(text)
