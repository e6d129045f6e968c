"""Specks: paths too small to trace as drawn, traced as the circle they lie close to (issue 17)."""

import math

import numpy as np
import pytest

import skatetrace as st
from skatetrace.drawings.curves import BezierPiece, LinePiece, Path
from skatetrace.drawings.specks import SPECK_RADIUS, find_specks, speck_circle
from skatetrace.pipeline import trace_and_verify

# The Rust book's Ferris drawings (panics.svg, path 4) hold a closed sliver: a line of 0.07 mm and
# a cubic back to its start with a cusp inside, 2.3 mm in all at 6 m. Traced as drawn, its three
# stretches between corners were sections no stop fits ("no stop of length 3.5e-05 found"), and the
# drawing failed verification.
SLIVER = "M284.891,563.596l0.007,0.015C285.083,563.755,285.255,563.887,284.891,563.596"


def _hausdorff(path: Path, speck, n: int = 20_001) -> float:
    """The distance between a path and a speck's circle, by brute force on dense samples (a lower bound)."""
    pts = path.points(n)
    c = np.asarray(speck.centre)[:, None]
    theta = np.linspace(0.0, 2.0 * math.pi, 4001)
    ring = c + speck.radius * np.vstack([np.cos(theta), np.sin(theta)])
    to_circle = np.max(np.abs(np.hypot(*(pts - c)) - speck.radius))
    from scipy.spatial import cKDTree

    to_path = np.max(cKDTree(pts.T).query(ring.T)[0])
    return float(max(to_circle, to_path))


def _svg(tmp_path, body: str, name: str = "d.svg"):
    path = tmp_path / name
    path.write_text(f'<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 1000 1000">{body}</svg>')
    return path


@pytest.mark.parametrize("path", [
    Path((LinePiece((0.0, 0.0), (1e-3, 0.0)),), False, "dash"),
    Path((LinePiece((0.0, 0.0), (8e-4, 0.0)), LinePiece((8e-4, 0.0), (8e-4, 8e-4)),
          LinePiece((8e-4, 8e-4), (0.0, 8e-4)), LinePiece((0.0, 8e-4), (0.0, 0.0))), True, "square"),
    Path((LinePiece((0.0, 0.0), (1e-3, 2e-4)), BezierPiece(((1e-3, 2e-4), (2e-3, 9e-4), (-5e-4, 9e-4), (0.0, 0.0)))),
         True, "blob"),
])
def test_a_speck_circle_is_certified_against_brute_force(path):
    speck = speck_circle(path, 1e-3, 2e-3 / 3)
    assert speck is not None
    exact = _hausdorff(path, speck)
    # certified: never below the distance, and within the certificate's slack (a share of the limit)
    assert exact <= speck.bound <= exact + 2e-3 / 3 / 8 + 1e-12
    assert speck.sampled <= exact + 1e-12
    # the radius is the best one: a tenth larger or smaller is farther from the path
    for k in (0.9, 1.1):
        other = type(speck)(centre=speck.centre, radius=k * speck.radius, bound=0.0, sampled=0.0,
                            clockwise=speck.clockwise, start=speck.start)
        assert _hausdorff(path, other) > exact


def test_a_dash_is_a_circle_of_a_quarter_of_its_length_and_keeps_its_direction():
    dash = Path((LinePiece((0.0, 0.0), (1e-3, 0.0)),), False, "dash")
    speck = speck_circle(dash, 1e-3, 2e-3 / 3)
    assert speck.radius == pytest.approx(2.5e-4, rel=1e-2) and speck.centre == pytest.approx((5e-4, 0.0))
    square = [(0.0, 0.0), (8e-4, 0.0), (8e-4, 8e-4), (0.0, 8e-4)]
    for pts, clockwise in ((square, False), (square[::-1], True)):
        ring = Path(tuple(LinePiece(a, b) for a, b in zip(pts, pts[1:] + pts[:1])), True, "ring")
        s = speck_circle(ring, 1e-3, 2e-3 / 3)
        assert s.clockwise is clockwise
        pose = s.pose()  # the circle starts towards the path's start, on the circle
        assert math.hypot(pose.x - s.centre[0], pose.y - s.centre[1]) == pytest.approx(s.radius)
        start = math.atan2(pts[0][1] - s.centre[1], pts[0][0] - s.centre[0])
        assert math.atan2(pose.y - s.centre[1], pose.x - s.centre[0]) == pytest.approx(start)
        assert abs(start) == pytest.approx(0.75 * math.pi)


def test_what_is_not_a_speck():
    # beyond SPECK_RADIUS tolerances of its centre
    far = Path((LinePiece((0.0, 0.0), (2.02 * SPECK_RADIUS * 1e-3, 0.0)),), False, "far")
    assert speck_circle(far, 1e-3, 1e-3) is None
    # near enough, but no circle within the limit: a line of 3.6 mm is 0.9 mm from its best circle
    line = Path((LinePiece((0.0, 0.0), (3.6e-3, 0.0)),), False, "line")
    assert speck_circle(line, 1e-3, 2e-3 / 3) is None
    assert speck_circle(line, 1e-3, 0.95e-3) is not None
    # an L of two 2 mm lines: within 2 tolerances of its centre, farther than 2/3 of one from any circle
    ell = Path((LinePiece((0.0, 2e-3), (0.0, 0.0)), LinePiece((0.0, 0.0), (2e-3, 0.0))), False, "ell")
    assert speck_circle(ell, 1e-3, 2e-3 / 3) is None


def test_a_drawing_keeps_its_paths_in_order_with_the_specks_as_circles(tmp_path):
    svg = _svg(tmp_path, '<rect id="big" x="0" y="0" width="1000" height="600" fill="none" stroke="black"/>'
                         '<path id="sliver" d="M500 300 l0.07 0.15 l0.1 -0.15 z" stroke="black"/>'
                         '<circle id="ring" cx="300" cy="300" r="100" fill="none" stroke="black"/>')
    r = st.resolve(svg, size="6m", tol="1mm")
    assert [p.name for p in r.fit.paths] == ["big", "sliver", "ring"]
    sliver = r.fit.paths[1]
    assert sliver.closed and sliver.n_arcs == 2 and sliver.runs[0].corner == 0.0
    assert 0.0 < sliver.hausdorff <= 2e-3 / 3 and r.fit.hausdorff <= 1e-3
    assert any(n.startswith("traced 1 path(s) too small to trace as drawn") and "sliver" in n for n in r.notes)
    curve = r.figure.curves[1]
    assert curve.closing is not None and curve.closing.kind == "smooth"
    radius = 1.0 / abs(curve.pieces[0].curvature)
    assert sum(p.length for p in curve.pieces) == pytest.approx(2.0 * math.pi * radius)
    # exact mode traces every path as drawn
    ex = st.resolve(svg, size="6m", tol="1mm", exact=True)
    assert not any("too small to trace as drawn" in n for n in ex.notes)


def test_a_drawing_of_specks_only_is_their_circles(tmp_path):
    svg = _svg(tmp_path, '<path d="M0 0 l1 0" stroke="black"/><path d="M999 999 l1 0" stroke="black"/>')
    r = st.resolve(svg, size="1m", tol="2mm")
    assert r.fit.success and [p.n_arcs for p in r.fit.paths] == [2, 2]
    assert len(r.figure.curves) == 2


def test_ferris_sliver_is_traced_as_a_circle_and_verified(tmp_path, monkeypatch):
    # the sliver beside a 6 m square (which sets the scale: 1 unit = 2 mm), as in the drawing
    svg = tmp_path / "ferris.svg"
    svg.write_text('<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 3000 3000">'
                   f'<path d="M0 0 h3000 v3000 h-3000 z" fill="none" stroke="black"/><path id="sliver" d="{SLIVER}"/>'
                   '</svg>')
    r = st.resolve(svg, size="6m", tol="1mm")
    assert len(find_specks(r.drawing, 1e-3, 2e-3 / 3)) == 1
    done = trace_and_verify(r.figure, r.figure.params, st.TraceOptions(speed=2.0))
    assert done.success, done.message
    assert len(r.figure.curves[1].sections()) == 1  # a smooth loop: no rest
    # traced as drawn (no specks), its three stretches between corners are sections of their own, each
    # started and stopped (sections of lines this short were ones no stop fitted before 4fd1761)
    import skatetrace.drawings.specks as specks

    monkeypatch.setattr(specks, "find_specks", lambda *args: {})
    drawn = st.resolve(svg, size="6m", tol="1mm")
    assert len(drawn.figure.curves[1].pieces) > 1 and len(drawn.figure.curves[1].sections()) == 3
