"""Tests of skatetrace.verification.deviation: the paper's deviation cost C, eq. (C_control), and its targets."""

import math

import numpy as np
import pytest

from skatetrace.verification.deviation import DeviationCost, deviation_cost, segments_target
from skatetrace.figures.geometry import Pose, Segment, advance


def _circle_path(radius, start_angle, length, n):
    """Points on the circle of ``radius`` about the origin, counter-clockwise from ``start_angle``."""
    phi = start_angle + np.linspace(0.0, length / radius, n)
    return np.vstack([radius * np.cos(phi), radius * np.sin(phi)])


def _line(x0, x1, y, n=50):
    return np.vstack([np.linspace(x0, x1, n), np.full(n, float(y))])


# --------------------------------------------------------------------------------------------------
# C itself
# --------------------------------------------------------------------------------------------------
def test_path_on_the_target_has_zero_cost():
    r = 1.3
    X, L = segments_target(Pose(0.0, -r, 0.0), [Segment(1 / r, 1.1 * math.pi * r)])
    path = _circle_path(r, -math.pi / 2, L, 20001)
    res = deviation_cost(path, X, L)
    assert isinstance(res, DeviationCost)
    # chords of length h = L / 20000 sag by h^2 / (8 r) ~ 1e-9, so C ~ L * 1e-18
    assert res.max_distance < 1e-7, res
    assert 0.0 <= res.value < 1e-10, res
    assert res.path_length == pytest.approx(L, rel=1e-8)
    assert res.compared_length == pytest.approx(L, rel=1e-8)
    assert res.target_length == L


def test_coarse_sampling_of_the_target_costs_more_than_dense():
    r = 1.0
    X, L = segments_target(Pose(0.0, -r, 0.0), [Segment(1 / r, math.pi)])
    coarse = deviation_cost(_circle_path(r, -math.pi / 2, L, 21), X, L).value
    dense = deviation_cost(_circle_path(r, -math.pi / 2, L, 2001), X, L).value
    assert dense < 1e-3 * coarse
    assert coarse > 0


@pytest.mark.parametrize("p", [1.5, 2.0, 3.0, 4.5])
@pytest.mark.parametrize("offset", [0.1, 0.7])
def test_parallel_offset_line_costs_offset_to_the_p_times_length(p, offset):
    X, L = segments_target(Pose(0.0, 0.0, 0.0), [Segment(0.0, 2.0)])
    res = deviation_cost(_line(0.0, 2.0, offset), X, L, p=p)
    assert res.value == pytest.approx(offset ** p * 2.0, rel=1e-12)
    assert res.max_distance == pytest.approx(offset, rel=1e-12)
    assert res.p == p


def test_p_scaling_and_componentwise_sum():
    """|dx|^p + |dy|^p, not the distance to the p: a diagonal offset (u, v) costs (|u|^p + |v|^p) L."""
    X, L = segments_target(Pose(0.0, 0.0, 0.0), [Segment(0.0, 3.0)])
    u, v = 0.3, -0.2
    path = np.vstack([np.linspace(0.0, 3.0, 40) + u, np.full(40, v)])
    # the path is shifted along the line by u and is 3 long: compared over [0, 3]
    for p in (2.0, 3.0):
        res = deviation_cost(path, X, L, p=p)
        assert res.value == pytest.approx((abs(u) ** p + abs(v) ** p) * 3.0, rel=1e-12)
        assert res.max_distance == pytest.approx(math.hypot(u, v), rel=1e-12)
    ratio = deviation_cost(_line(0, 3, 0.25), X, L, p=3.0).value / deviation_cost(_line(0, 3, 0.25), X, L, p=2.0).value
    assert ratio == pytest.approx(0.25, rel=1e-12)


def test_shorter_path_is_compared_over_its_own_length():
    X, L = segments_target(Pose(0.0, 0.0, 0.0), [Segment(0.0, 3.0)])
    res = deviation_cost(_line(0.0, 1.0, 0.2), X, L)
    assert res.path_length == pytest.approx(1.0, rel=1e-12)
    assert res.target_length == 3.0
    assert res.compared_length == pytest.approx(1.0, rel=1e-12)
    assert res.value == pytest.approx(0.2 ** 2 * 1.0, rel=1e-12)


def test_longer_path_is_compared_over_the_target_length():
    X, L = segments_target(Pose(0.0, 0.0, 0.0), [Segment(0.0, 2.0)])
    res = deviation_cost(_line(0.0, 5.0, 0.2, n=101), X, L)
    assert res.path_length == pytest.approx(5.0, rel=1e-12)
    assert res.compared_length == 2.0
    assert res.value == pytest.approx(0.2 ** 2 * 2.0, rel=1e-12)


def test_drift_along_the_right_circle_counts():
    """On the target circle but started a quarter-turn late: zero distance to the curve, large C."""
    r, L = 1.0, math.pi
    X, _ = segments_target(Pose(0.0, -r, 0.0), [Segment(1 / r, L)])
    phi = math.pi / 2
    path = _circle_path(r, -math.pi / 2 + phi, L, 20001)
    # distance to the curve (the circle) is zero up to round-off ...
    assert np.max(np.abs(np.hypot(path[0], path[1]) - r)) < 1e-12
    # ... but the point at equal arc length is a chord 2 r sin(phi / 2) away, all along
    res = deviation_cost(path, X, L)
    chord = 2 * r * math.sin(phi / 2)
    assert res.max_distance == pytest.approx(chord, rel=1e-6)
    assert res.value == pytest.approx(chord ** 2 * L, rel=1e-6)
    assert res.value > 1.0


def test_degenerate_path_of_zero_length():
    X, L = segments_target(Pose(0.0, 0.0, 0.0), [Segment(0.0, 1.0)])
    res = deviation_cost(np.array([[0.0, 0.0], [0.5, 0.5]]), X, L)
    assert res.value == 0.0 and res.compared_length == 0.0 and res.path_length == 0.0
    assert res.max_distance == pytest.approx(0.5, rel=1e-12)


# --------------------------------------------------------------------------------------------------
# segments_target
# --------------------------------------------------------------------------------------------------
SEGS = [Segment(1 / 1.2, 2.0), Segment(0.0, 1.5), Segment(-1 / 0.8, 1.7)]
START = Pose(0.3, -1.0, 0.4)


def test_segments_target_length_start_and_end():
    X, L = segments_target(START, SEGS)
    assert L == pytest.approx(2.0 + 1.5 + 1.7, rel=1e-15)
    np.testing.assert_allclose(X(np.array([0.0]))[:, 0], [START.x, START.y], atol=1e-15)
    pose = START
    for k, length in SEGS:
        pose = Pose(*(float(v) for v in advance(pose, k, length)))
    np.testing.assert_allclose(X(np.array([L]))[:, 0], [pose.x, pose.y], atol=1e-12)


def test_segments_target_is_continuous_with_continuous_heading_at_the_joins():
    X, L = segments_target(START, SEGS)
    h = 1e-6
    for join in (2.0, 3.5):
        left, mid, right = X(np.array([join - h, join, join + h])).T
        assert np.hypot(*(right - left)) == pytest.approx(2 * h, rel=1e-6)  # no jump across the join
        assert np.hypot(*(mid - left)) == pytest.approx(h, rel=1e-6)
        # one-sided tangents agree to O(h * curvature)
        t_left = (mid - left) / h
        t_right = (right - mid) / h
        assert np.hypot(*(t_left - t_right)) < 5e-6
    # the heading at the join is the first arc's end heading
    tl = (X(np.array([2.0]))[:, 0] - X(np.array([2.0 - h]))[:, 0]) / h
    assert math.atan2(tl[1], tl[0]) == pytest.approx(START.heading + 2.0 / 1.2, abs=1e-6)


def test_segments_target_is_unit_speed_and_has_each_pieces_curvature():
    X, L = segments_target(START, SEGS)
    s = np.linspace(0.0, L, 5201)
    P = X(s)
    step = np.hypot(np.diff(P[0]), np.diff(P[1]))
    np.testing.assert_allclose(step, np.diff(s), rtol=1e-6)  # chords of a unit-speed curve
    # curvature from three consecutive points, well inside each piece
    for s0, k in ((1.0, 1 / 1.2), (2.75, 0.0), (4.3, -1 / 0.8)):
        h = 1e-3
        a, b, c = X(np.array([s0 - h, s0, s0 + h])).T
        cross = (b - a)[0] * (c - b)[1] - (b - a)[1] * (c - b)[0]
        kappa = 2 * cross / (np.hypot(*(b - a)) * np.hypot(*(c - b)) * np.hypot(*(c - a)))
        assert kappa == pytest.approx(k, abs=1e-5)


# --------------------------------------------------------------------------------------------------
# errors
# --------------------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def line_target():
    return segments_target(Pose(0.0, 0.0, 0.0), [Segment(0.0, 1.0)])


@pytest.mark.parametrize("p", [1.0, 0.5, 0.0, -2.0, math.inf, math.nan])
def test_bad_p_is_rejected(line_target, p):
    X, L = line_target
    with pytest.raises(ValueError, match="p must be"):
        deviation_cost(_line(0, 1, 0.1), X, L, p=p)


@pytest.mark.parametrize("path", [np.zeros((3, 10)), np.zeros((2, 1)), np.zeros(10), np.zeros((10, 2)),
                                  np.zeros((2, 5, 2))])
def test_bad_path_shapes_are_rejected(line_target, path):
    X, L = line_target
    with pytest.raises(ValueError, match="shape"):
        deviation_cost(path, X, L)


@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf])
def test_non_finite_paths_are_rejected(line_target, bad):
    X, L = line_target
    path = _line(0, 1, 0.1)
    path[1, 7] = bad
    with pytest.raises(ValueError, match="non-finite"):
        deviation_cost(path, X, L)


@pytest.mark.parametrize("length", [0.0, -1.0, math.inf, math.nan])
def test_bad_target_length_is_rejected(line_target, length):
    X, _ = line_target
    with pytest.raises(ValueError, match="target_length"):
        deviation_cost(_line(0, 1, 0.1), X, length)


@pytest.mark.parametrize("segments", [[], [Segment(1.0, 0.0)], [Segment(0.0, 1.0), Segment(1.0, -2.0)]])
def test_segments_target_rejects_empty_and_non_positive_lengths(segments):
    with pytest.raises(ValueError, match="positive length"):
        segments_target(Pose(0.0, 0.0, 0.0), segments)
