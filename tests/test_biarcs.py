"""Biarcs: G1 Hermite interpolation by two arcs, its errors, and its third-order accuracy."""

import math

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from fitting_cases import heading_gap
from skatetrace.drawings import biarcs
from skatetrace.drawings.biarcs import biarc
from skatetrace.drawings.curves import EllipticArcPiece
from skatetrace.errors import FitError
from skatetrace.figures.geometry import Pose, advance, distance_to_segment


@settings(max_examples=200, deadline=None)
@given(st.lists(st.floats(-3, 3), min_size=6, max_size=6))
def test_biarc_interpolates_hermite_data(v):
    start, end = Pose(v[0], v[1], v[2]), Pose(v[3], v[4], v[5])
    assume(math.hypot(v[3] - v[0], v[4] - v[1]) > 1e-3)
    try:
        segs = biarc(start, end)
    except FitError:
        return  # both directions back along the chord: no bounded biarc
    assert 1 <= len(segs) <= 2 and all(s.length > 0 for s in segs)
    pose = start
    for k, L in segs:
        pose = Pose(*(float(x) for x in advance(pose, k, L)))
    assert math.hypot(pose.x - end.x, pose.y - end.y) <= 1e-9 * (1 + sum(s.length for s in segs))
    assert heading_gap(pose.heading, end.heading) <= 1e-9


def test_biarc_errors_and_order_three():
    with pytest.raises(FitError, match="coincide"):
        biarc(Pose(1.0, 1.0, 0.0), Pose(1.0, 1.0, 1.0))
    # Meek & Walton: the biarc error on a span of length h of a smooth curve is O(h^3).
    piece = EllipticArcPiece((0.0, 0.0), 2.0, 1.0, 0.0, 0.3, 1.0)
    errs = []
    hs = [0.2, 0.1, 0.05, 0.025]
    for h in hs:
        t = np.array([0.0, h])
        p, d = piece.point(t), piece.d1(t)
        a, b = (Pose(p[0, i], p[1, i], math.atan2(d[1, i], d[0, i])) for i in (0, 1))
        segs = biarc(a, b)
        pts = piece.point(np.linspace(0.0, h, 2001))
        poses = biarcs._chain_poses(a, segs)
        errs.append(float(np.max(np.min([distance_to_segment(pts, q, s) for q, s in zip(poses, segs)], axis=0))))
    slopes = np.diff(np.log(errs)) / np.diff(np.log(hs))
    assert np.all((slopes > 2.8) & (slopes < 3.4)) and abs(slopes[-1] - 3) < 0.1, slopes


def test_an_arc_flatter_than_a_figure_allows_is_a_line():
    """A biarc between nearly aligned poses 2 m apart turning by 1e-10 rad has arcs of radius 2e10:
    a figure refuses radii over 1e9 ("use a line"), and a drawing's fit that made one could not be
    traced. Such an arc is a line (its end moves by 1e-10 m at most); flatter arcs within the
    figure's limit are kept."""
    from skatetrace import Curve, Figure
    from skatetrace.figures.figure import MAX_LENGTH, SMOOTH

    segs = biarc(Pose(0.0, 0.0, 0.0), Pose(2.0, 0.0, 1e-10))
    assert all(s.curvature == 0.0 for s in segs)
    assert sum(s.length for s in segs) == pytest.approx(2.0, rel=1e-12)
    Figure("flat", (Curve(tuple(segs), tuple(SMOOTH for _ in segs[1:]), name="flat"),))  # a figure takes it
    assert biarcs._straightened(2.0 / MAX_LENGTH, 2.0) == 2.0 / MAX_LENGTH
    assert biarcs._straightened(0.5 / MAX_LENGTH, 2.0) == 0.0
    assert biarcs._straightened(1.0, 1e-14) == 0.0  # turning by less than 1e-13, as before
