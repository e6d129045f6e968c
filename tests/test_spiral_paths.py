"""The compiled spiral quadrature and foot-point search (skatetrace.figures.spiral_paths).

geometry's tests check the positions against Fresnel integrals and an integrated ODE, and the
distances against brute force; these check the compiled kernels' own contracts.
"""

import math

import numpy as np
import pytest

from skatetrace.figures.geometry import Pose, Spiral, travel
from skatetrace.figures.spiral_paths import cell_nodes, foot_points, positions

COEFFS = np.array([0.3, 1.2, -0.4, 0.05])
LENGTH = 4.0


def _path(n, pose=(0.5, -1.0, 0.7)):
    node_x, node_y = cell_nodes(COEFFS, LENGTH, n, *pose)
    return (COEFFS, LENGTH, n, pose[2], node_x, node_y)


def test_the_cells_are_a_partition_not_an_approximation():
    # 8 cells turn by up to 0.36 rad each, 64 by 0.05: the ten-point rule is exact to rounding on both
    s = np.linspace(0.0, LENGTH, 101)
    coarse, fine = np.array(positions(*_path(8), s)), np.array(positions(*_path(64), s))
    np.testing.assert_allclose(coarse, fine, rtol=0, atol=1e-13)


def test_cell_boundaries_are_the_positions_there():
    args = _path(12)
    s = np.arange(13) * (LENGTH / 12)
    s[-1] = LENGTH
    x, y, th = positions(*args, s)
    np.testing.assert_array_equal(x, args[4])
    np.testing.assert_array_equal(y, args[5])
    assert th[0] == 0.7
    assert th[-1] == pytest.approx(0.7 + Spiral(tuple(COEFFS), LENGTH).turn, abs=1e-14)


def _tangent_offset(args, px, py, u):
    x, y, th = positions(*args, np.array([u]))
    return (x[0] - px) * math.cos(th[0]) + (y[0] - py) * math.sin(th[0])


def test_foot_points_are_where_the_offset_is_normal():
    args = _path(16)
    s = np.array([0.4, 1.3, 2.2, 3.1])
    x, y, th = positions(*args, s)
    # points 0.3 to the left of the spiral (inside its radius of curvature, > 0.6 everywhere here)
    px, py = x - 0.3 * np.sin(th), y + 0.3 * np.cos(th)
    start = s + np.array([0.05, -0.05, 0.04, -0.04])
    got = foot_points(*args, px, py, start, 0.1, 8)
    np.testing.assert_allclose(got, s, rtol=0, atol=1e-12)
    for i in range(4):
        assert abs(_tangent_offset(args, px[i], py[i], got[i])) < 1e-13


def test_foot_points_keep_to_the_spiral_and_to_their_steps():
    args = _path(16)
    x, y, th = positions(*args, np.array([0.0, LENGTH]))
    # half a unit beyond each end along its tangent: the foot point is the end itself
    px, py = x + 0.5 * np.array([-1.0, 1.0]) * np.cos(th), y + 0.5 * np.array([-1.0, 1.0]) * np.sin(th)
    np.testing.assert_array_equal(foot_points(*args, px, py, np.array([0.2, 3.8]), 0.5, 8), [0.0, LENGTH])
    # a step of at most max_step an iteration: three iterations move by 0.3 at most
    far = foot_points(*args, px[1:], py[1:], np.array([0.0]), 0.1, 3)
    assert 0.0 < far[0] <= 0.3 + 1e-15


def test_integer_coefficients_give_the_float_spiral():
    s = np.linspace(0.0, 2.0, 9)
    got = np.array(travel(Pose(0, 0, 0), Spiral((0, 1, 0, 0), 2), s))
    want = np.array(travel(Pose(0.0, 0.0, 0.0), Spiral((0.0, 1.0, 0.0, 0.0), 2.0), s))
    np.testing.assert_array_equal(got, want)
