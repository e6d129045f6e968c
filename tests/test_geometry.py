"""Tests of skatetrace.figures.geometry: poses along arcs and lines, distances, rigid motions."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.integrate import solve_ivp

from skatetrace.figures.geometry import (Pose, Segment, Spiral, advance, distance_to_segment, end_pose, rigid_motion_centre,
                                 segment_points, shifted_polynomial, travel)


# --------------------------------------------------------------------------------------------------
# advance
# --------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("kappa", [0.7, -1.3, 1 / 1.2, 25.0])
def test_advance_full_circle_returns_to_start(kappa):
    pose = Pose(0.4, -1.1, 0.9)
    x, y, th = advance(pose, kappa, 2 * math.pi / abs(kappa))
    assert float(x) == pytest.approx(pose.x, abs=1e-12)
    assert float(y) == pytest.approx(pose.y, abs=1e-12)
    # heading is unwrapped: it gains exactly one full signed turn
    assert float(th) == pytest.approx(pose.heading + math.copysign(2 * math.pi, kappa), abs=1e-12)


def test_advance_half_circle_is_diametrically_opposite():
    r = 1.5
    x, y, th = advance(Pose(0.0, 0.0, 0.0), 1 / r, math.pi * r)
    assert (float(x), float(y), float(th)) == pytest.approx((0.0, 2 * r, math.pi), abs=1e-12)
    x, y, th = advance(Pose(0.0, 0.0, 0.0), -1 / r, math.pi * r)
    assert (float(x), float(y), float(th)) == pytest.approx((0.0, -2 * r, -math.pi), abs=1e-12)


@pytest.mark.parametrize("kappa", [0.0, 0.37, -2.1, 4.0])
def test_advance_agrees_with_integrated_ode(kappa):
    pose = Pose(1.0, 2.0, -0.6)
    s = np.linspace(0.0, 6.0, 61)
    sol = solve_ivp(lambda _s, z: [math.cos(z[2]), math.sin(z[2]), kappa], (0.0, 6.0), list(pose),
                    method="DOP853", rtol=1e-13, atol=1e-13, t_eval=s)
    assert sol.success
    x, y, th = advance(pose, kappa, s)
    assert x.shape == s.shape
    np.testing.assert_allclose(x, sol.y[0], rtol=0, atol=1e-10)
    np.testing.assert_allclose(y, sol.y[1], rtol=0, atol=1e-10)
    np.testing.assert_allclose(th, sol.y[2], rtol=0, atol=1e-10)


@pytest.mark.parametrize("kappa", [1e-3, -1e-5, 1e-8, -1e-12, 1e-300])
def test_advance_continuous_as_curvature_vanishes(kappa):
    pose = Pose(-0.3, 0.8, 2.2)
    s = np.linspace(0.0, 10.0, 101)
    xl, yl, _ = advance(pose, 0.0, s)
    xk, yk, thk = advance(pose, kappa, s)
    # Deviation of an arc from its tangent line is s^2 |kappa| / 2 to leading order.
    dev = np.hypot(xk - xl, yk - yl)
    assert np.all(dev <= 0.5 * abs(kappa) * s**2 * (1 + 1e-2) + 1e-14)
    if abs(kappa) >= 1e-8:  # and of exactly that size (not just small)
        np.testing.assert_allclose(dev[1:], 0.5 * abs(kappa) * s[1:] ** 2, rtol=1e-2)
    np.testing.assert_allclose(thk, pose.heading + kappa * s, rtol=0, atol=1e-15)


def test_advance_matches_closed_form_for_moderate_curvature():
    pose, k = Pose(0.2, 0.1, 0.5), 0.8
    s = np.linspace(0.0, 5.0, 11)
    x, y, _ = advance(pose, k, s)
    np.testing.assert_allclose(x, pose.x + (np.sin(pose.heading + k * s) - math.sin(pose.heading)) / k, atol=1e-13)
    np.testing.assert_allclose(y, pose.y - (np.cos(pose.heading + k * s) - math.cos(pose.heading)) / k, atol=1e-13)


def test_segment_points_endpoints():
    pose, seg = Pose(0.0, 0.0, 0.0), Segment(1.0, math.pi / 2)
    pts = segment_points(pose, seg, 5)
    assert pts.shape == (2, 5)
    np.testing.assert_allclose(pts[:, 0], [0.0, 0.0], atol=1e-15)
    np.testing.assert_allclose(pts[:, -1], [1.0, 1.0], atol=1e-14)
    assert seg.turn == pytest.approx(math.pi / 2)


# --------------------------------------------------------------------------------------------------
# distance_to_segment: exact values
# --------------------------------------------------------------------------------------------------
def d(point, pose, seg):
    out = distance_to_segment(np.array(point, dtype=float).reshape(2, 1), pose, seg)
    return float(out[0])


@pytest.mark.parametrize("kappa", [1.0, -1.0, 1 / 1.2, -3.0])
def test_distance_from_arc_centre_is_radius(kappa):
    pose = Pose(0.3, -0.4, 1.0)
    seg = Segment(kappa, 0.5 / abs(kappa))
    r = 1 / abs(kappa)
    cx, cy = pose.x - math.sin(pose.heading) / kappa, pose.y + math.cos(pose.heading) / kappa
    assert d((cx, cy), pose, seg) == pytest.approx(r, rel=1e-13)


def test_distance_to_left_arc_exact_values():
    # Quarter circle from (0, 0) heading east, curvature +1: centre (0, 1), ends at (1, 1).
    pose, seg = Pose(0.0, 0.0, 0.0), Segment(1.0, math.pi / 2)
    assert d((2.0, 0.0), pose, seg) == pytest.approx(math.sqrt(5) - 1, abs=1e-14)  # inside the sweep
    assert d((0.3, 1.0 - math.sqrt(0.91)), pose, seg) == pytest.approx(0.0, abs=1e-14)  # on the arc
    assert d((1.0, 3.0), pose, seg) == pytest.approx(2.0, abs=1e-14)  # beyond the end: to (1, 1)
    # On the circle but off the arc: nearest is the end point (1, 1), not 0.
    assert d((0.0, 2.0), pose, seg) == pytest.approx(math.sqrt(2), abs=1e-14)
    assert d((-1.0, 1.0), pose, seg) == pytest.approx(math.sqrt(2), abs=1e-14)
    # Before the start (behind it along the circle): nearest is the start point.
    assert d((-0.5, -0.5), pose, seg) == pytest.approx(math.sqrt(0.5), abs=1e-14)


def test_distance_to_right_arc_exact_values():
    # Quarter circle from (0, 0) heading east, curvature -1: centre (0, -1), ends at (1, -1).
    pose, seg = Pose(0.0, 0.0, 0.0), Segment(-1.0, math.pi / 2)
    assert d((2.0, 0.0), pose, seg) == pytest.approx(math.sqrt(5) - 1, abs=1e-14)
    assert d((0.0, -2.0), pose, seg) == pytest.approx(math.sqrt(2), abs=1e-14)
    assert d((1.0, -3.0), pose, seg) == pytest.approx(2.0, abs=1e-14)


def test_distance_to_line_exact_values():
    th = math.radians(30)
    u, n = np.array([math.cos(th), math.sin(th)]), np.array([-math.sin(th), math.cos(th)])
    o = np.array([1.0, -2.0])
    pose, seg = Pose(o[0], o[1], th), Segment(0.0, 2.0)
    assert d(o + 1.0 * u + 0.7 * n, pose, seg) == pytest.approx(0.7, abs=1e-14)
    assert d(o + 0.4 * u - 1.3 * n, pose, seg) == pytest.approx(1.3, abs=1e-14)
    assert d(o + 5.0 * u, pose, seg) == pytest.approx(3.0, abs=1e-14)  # on the extension, beyond the end
    assert d(o - 0.5 * u, pose, seg) == pytest.approx(0.5, abs=1e-14)  # on the extension, before the start
    assert d(o + 3.0 * u + 4.0 * n, pose, seg) == pytest.approx(math.hypot(1.0, 4.0), abs=1e-14)


def test_distance_is_vectorised():
    pose, seg = Pose(0.0, 0.0, 0.0), Segment(1.0, math.pi / 2)
    pts = np.array([[2.0, 1.0, 0.0], [0.0, 3.0, 2.0]])
    np.testing.assert_allclose(distance_to_segment(pts, pose, seg), [math.sqrt(5) - 1, 2.0, math.sqrt(2)],
                               atol=1e-14)


# --------------------------------------------------------------------------------------------------
# distance_to_segment: properties
# --------------------------------------------------------------------------------------------------
coords = st.floats(-10.0, 10.0, allow_nan=False)
headings = st.floats(-10.0, 10.0, allow_nan=False)
curvatures = st.one_of(st.just(0.0), st.floats(-5.0, 5.0, allow_nan=False).filter(lambda k: abs(k) > 1e-3))
lengths = st.floats(0.01, 20.0)
fractions = st.floats(0.0, 1.0)


@settings(max_examples=200, deadline=None)
@given(coords, coords, headings, curvatures, lengths, fractions)
def test_points_on_segment_have_zero_distance(x, y, th, k, L, u):
    pose, seg = Pose(x, y, th), Segment(k, L)
    px, py, _ = advance(pose, k, u * L)
    assert d((float(px), float(py)), pose, seg) < 1e-9


@settings(max_examples=200, deadline=None)
@given(coords, coords, headings, curvatures, st.floats(0.05, 0.95), st.floats(-0.9, 0.9))
def test_offset_along_normal_gives_offset_distance(x, y, th, k, u, frac):
    # A point displaced along the normal from the interior of an arc (less than a full turn) or a
    # line is at exactly that distance (the radial projection lies on the arc).
    L = 5.0 if k == 0.0 else 0.95 * 2 * math.pi / abs(k)
    r = math.inf if k == 0.0 else 1 / abs(k)
    off = frac * min(r, 2.0)  # never through the centre
    pose, seg = Pose(x, y, th), Segment(k, L)
    px, py, ph = (float(v) for v in advance(pose, k, u * L))
    q = (px - off * math.sin(ph), py + off * math.cos(ph))
    assert d(q, pose, seg) == pytest.approx(abs(off), abs=1e-9)


# --------------------------------------------------------------------------------------------------
# rigid_motion_centre
# --------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("phi", [0.3, -2.0, math.pi, 1e-6, 2 * math.pi + 0.5])
def test_rigid_motion_centre_of_rotation(phi):
    c = np.array([1.7, -0.4])
    start = Pose(0.2, 0.9, 0.35)
    R = np.array([[math.cos(phi), -math.sin(phi)], [math.sin(phi), math.cos(phi)]])
    p = R @ (np.array([start.x, start.y]) - c) + c
    end = Pose(p[0], p[1], start.heading + phi)
    got = rigid_motion_centre(start, end)
    assert got is not None
    # Conditioning of (I - R) c = ... is 1/|2 sin(phi/2)|.
    tol = 1e-12 / abs(2 * math.sin(phi / 2))
    assert got == pytest.approx(tuple(c), abs=tol)


@pytest.mark.parametrize("turns", [0, 1, -2])
def test_rigid_motion_centre_none_for_translation(turns):
    start = Pose(0.0, 0.0, 0.4)
    end = Pose(3.0, -1.0, 0.4 + 2 * math.pi * turns)
    assert rigid_motion_centre(start, end) is None


# --------------------------------------------------------------------------------------------------
# spirals (curvature a cubic of arc length)
# --------------------------------------------------------------------------------------------------
def test_clothoid_matches_fresnel_integrals():
    from scipy.special import fresnel

    # kappa = s: x = sqrt(pi) C(s / sqrt(pi)), y = sqrt(pi) S(s / sqrt(pi)) (Abramowitz & Stegun 7.3)
    s = np.linspace(0.0, 5.0, 51)
    x, y, th = travel(Pose(0.0, 0.0, 0.0), Spiral((0.0, 1.0, 0.0, 0.0), 5.0), s)
    S, C = fresnel(s / math.sqrt(math.pi))
    np.testing.assert_allclose(x, math.sqrt(math.pi) * C, rtol=0, atol=1e-13)
    np.testing.assert_allclose(y, math.sqrt(math.pi) * S, rtol=0, atol=1e-13)
    np.testing.assert_allclose(th, 0.5 * s**2, rtol=0, atol=1e-13)


@pytest.mark.parametrize("coeffs", [(0.3, -0.2, 0.05, 0.01), (-1.0, 0.0, 0.4, -0.06), (2.0, 0.0, 0.0, 0.0)])
def test_spiral_agrees_with_integrated_ode(coeffs):
    pose = Pose(0.5, -1.0, 2.0)
    sp = Spiral(coeffs, 6.0)

    def f(s, z):
        return [math.cos(z[2]), math.sin(z[2]), float(sp.curvature_at(s))]

    s = np.linspace(0.0, 6.0, 37)
    sol = solve_ivp(f, (0.0, 6.0), list(pose), method="DOP853", rtol=1e-13, atol=1e-13, t_eval=s)
    x, y, th = travel(pose, sp, s)
    np.testing.assert_allclose(np.vstack([x, y, th]), sol.y, rtol=0, atol=1e-10)
    assert sp.turn == pytest.approx(float(sol.y[2, -1] - pose.heading), abs=1e-10)


def test_constant_spiral_is_the_arc():
    pose = Pose(1.0, 2.0, 0.3)
    s = np.linspace(0.0, 3.0, 13)
    got = np.array(travel(pose, Spiral((0.5, 0.0, 0.0, 0.0), 3.0), s))
    want = np.array(advance(pose, 0.5, s))
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-14)


@given(st.lists(st.floats(-2.0, 2.0), min_size=4, max_size=4), st.floats(0.1, 3.0), st.floats(0.0, 1.0),
       st.sampled_from([1.0, -1.0]))
@settings(max_examples=60, deadline=None)
def test_shifted_polynomial(coeffs, x0, x, sign):
    p = np.polynomial.Polynomial(coeffs)
    q = np.polynomial.Polynomial(shifted_polynomial(coeffs, x0, sign))
    assert q(x) == pytest.approx(p(x0 + sign * x), rel=1e-12, abs=1e-12)


def test_spiral_part_continues_the_whole():
    sp = Spiral((0.2, 0.5, -0.1, 0.02), 4.0)
    pose = Pose(0.0, 0.0, 0.0)
    mid = end_pose(pose, sp.part(0.0, 1.5))
    x, y, th = travel(mid, sp.part(1.5, 4.0), np.array([0.0, 1.0, 2.5]))
    xw, yw, thw = travel(pose, sp, np.array([1.5, 2.5, 4.0]))
    np.testing.assert_allclose(np.vstack([x, y, th]), np.vstack([xw, yw, thw]), rtol=0, atol=1e-13)


def test_distance_to_spiral_matches_brute_force():
    sp = Spiral((0.1, 0.6, -0.05, 0.0), 5.0)
    pose = Pose(-1.0, 0.5, 0.4)
    dense = segment_points(pose, sp, 200001)
    pts = np.random.default_rng(3).uniform(-3.0, 4.0, (2, 300))
    brute = np.min(np.hypot(dense[0][None, :] - pts[0][:, None], dense[1][None, :] - pts[1][:, None]), axis=1)
    got = distance_to_segment(pts, pose, sp)
    # the brute force is a polyline of 2e5 points: it over-estimates by at most a few 1e-10
    assert np.all(got <= brute + 1e-12)
    np.testing.assert_allclose(got, brute, rtol=0, atol=1e-9)


def test_spiral_max_abs_curvature():
    sp = Spiral((0.0, 3.0, -1.0, 0.0), 4.0)  # kappa = 3s - s^2: peak 2.25 at s = 1.5, -4 at s = 4
    assert sp.max_abs_curvature() == pytest.approx(4.0)
    assert Spiral((0.0, 3.0, -1.0, 0.0), 2.0).max_abs_curvature() == pytest.approx(2.25)


@given(st.lists(st.floats(-3.0, 3.0), min_size=4, max_size=4), st.floats(0.05, 5.0))
@settings(max_examples=80, deadline=None)
def test_spiral_max_abs_curvature_bounds_dense_samples(coeffs, length):
    sp = Spiral(tuple(coeffs), length)
    dense = float(np.max(np.abs(sp.curvature_at(np.linspace(0.0, length, 20001)))))
    assert dense <= sp.max_abs_curvature() * (1 + 1e-12) + 1e-300
    assert sp.max_abs_curvature() <= dense * (1 + 1e-6) + 1e-12
