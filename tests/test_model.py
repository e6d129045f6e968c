"""Tests of skatetrace.dynamics.model against independent derivations (see shared/PHYSICS.md)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from skatetrace.dynamics import model
from skatetrace.tracing.maneuver import solve_stop
from skatetrace.dynamics.model import SleighParams

# Non-default parameters, so that a formula that silently assumes the paper's M=2, m=1, I=3 fails.
PARAMS = SleighParams(M=2.3, m=1.7, I=0.9)


# --------------------------------------------------------------------------------------------------
# Independent kinetic energy and momenta
# --------------------------------------------------------------------------------------------------
def kinetic_energy(params, xi1, xi2, a, b, adot, bdot):
    """T = 1/2 M xi2^2 + 1/2 I xi1^2 + 1/2 m [(xi2 - xi1 b + adot)^2 + (xi1 a + bdot)^2]."""
    M, m, I = params.M, params.m, params.I
    return 0.5 * M * xi2**2 + 0.5 * I * xi1**2 + 0.5 * m * ((xi2 - xi1 * b + adot) ** 2 + (xi1 * a + bdot) ** 2)


def momentum_map(params, a, b, adot, bdot):
    """(H, g) with p = dT/dxi = H xi + g, extracted from T alone.

    T is quadratic in xi, so these differences with unit steps are exact up to round-off.
    """

    def T(x1, x2):
        return kinetic_energy(params, x1, x2, a, b, adot, bdot)

    T0 = T(0.0, 0.0)
    g = np.array([(T(1.0, 0.0) - T(-1.0, 0.0)) / 2, (T(0.0, 1.0) - T(0.0, -1.0)) / 2])
    h11 = T(1.0, 0.0) + T(-1.0, 0.0) - 2 * T0
    h22 = T(0.0, 1.0) + T(0.0, -1.0) - 2 * T0
    h12 = (T(1.0, 1.0) - T(1.0, -1.0) - T(-1.0, 1.0) + T(-1.0, -1.0)) / 4
    H = np.array([[h11, h12], [h12, h22]])
    return H, g


def independent_momenta(params, xi1, xi2, a, b, adot, bdot):
    H, g = momentum_map(params, a, b, adot, bdot)
    return H @ np.array([xi1, xi2]) + g


def independent_velocities(params, p1, p2, a, b, adot, bdot):
    H, g = momentum_map(params, a, b, adot, bdot)
    return np.linalg.solve(H, np.array([p1, p2]) - g)


def random_inputs(rng, n):
    """Rows of (p1, p2, a, b, adot, bdot), O(1) values of both signs."""
    return rng.uniform(-2.0, 2.0, size=(n, 6))


# --------------------------------------------------------------------------------------------------
# 1. velocities / momenta
# --------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("params", [PARAMS, SleighParams()])
def test_velocities_invert_independent_momenta(params):
    rng = np.random.default_rng(1)
    for p1, p2, a, b, adot, bdot in random_inputs(rng, 200):
        xi1, xi2, eta = model.velocities(params, p1, p2, a, b, adot, bdot)
        ref1, ref2 = independent_velocities(params, p1, p2, a, b, adot, bdot)
        assert xi1 == pytest.approx(ref1, rel=1e-12, abs=1e-12)
        assert xi2 == pytest.approx(ref2, rel=1e-12, abs=1e-12)
        # eta is the lateral body-frame velocity of the mass.
        assert eta == pytest.approx(a * ref1 + bdot, rel=1e-12, abs=1e-12)


def test_velocities_vectorised_matches_scalar():
    rng = np.random.default_rng(2)
    X = random_inputs(rng, 50)
    vec = np.array(model.velocities(PARAMS, *X.T))
    for j, row in enumerate(X):
        np.testing.assert_allclose(vec[:, j], model.velocities(PARAMS, *row), rtol=1e-14, atol=1e-15)


def test_momenta_match_independent_derivative_of_T():
    rng = np.random.default_rng(3)
    for xi1, xi2, a, b, adot, bdot in random_inputs(rng, 200):
        p = model.momenta(PARAMS, xi1, xi2, a, b, adot, bdot)
        np.testing.assert_allclose(p, independent_momenta(PARAMS, xi1, xi2, a, b, adot, bdot),
                                   rtol=1e-12, atol=1e-12)


def test_momenta_is_inverse_of_velocities():
    rng = np.random.default_rng(4)
    X = random_inputs(rng, 300)
    p1, p2, a, b, adot, bdot = X.T
    xi1, xi2, _ = model.velocities(PARAMS, p1, p2, a, b, adot, bdot)
    q1, q2 = model.momenta(PARAMS, xi1, xi2, a, b, adot, bdot)
    np.testing.assert_allclose(q1, p1, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(q2, p2, rtol=1e-12, atol=1e-12)
    # and the other way round
    y1, y2, _ = model.velocities(PARAMS, *model.momenta(PARAMS, p1, p2, a, b, adot, bdot), a, b, adot, bdot)
    np.testing.assert_allclose(y1, p1, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(y2, p2, rtol=1e-12, atol=1e-12)


# --------------------------------------------------------------------------------------------------
# 2. Independent Lagrange-d'Alembert simulation in spatial coordinates
# --------------------------------------------------------------------------------------------------
# Prescribed controls and their first and second derivatives.
def ctrl(t):
    a = 0.5 + 0.3 * math.sin(t)
    b = 0.2 * math.cos(1.3 * t)
    ad = 0.3 * math.cos(t)
    bd = -0.26 * math.sin(1.3 * t)
    add = -0.3 * math.sin(t)
    bdd = -0.338 * math.cos(1.3 * t)
    return a, b, ad, bd, add, bdd


def spatial_rhs(params):
    """q = (x, y, theta); mass at P = (x, y) + R(theta) (a, b); knife edge -xdot s + ydot c = 0.

    L = 1/2 M |xdot|^2 + 1/2 I thetadot^2 + 1/2 m |Pdot|^2. With P = q_xy + R rho, rho = (a, b),
    S = [[0, -1], [1, 0]]:  Pdot = J qdot + R rhodot,  Pddot = J qddot + h,
    J = [I2 | R S rho],  h = R (rhoddot + 2 thetadot S rhodot - thetadot^2 rho).
    Euler-Lagrange for a point mass gives m J^T Pddot, so the Lagrange-d'Alembert equations are
        (diag(M, M, I) + m J^T J) qddot + m J^T h = lambda A^T,   A = (-s, c, 0),
    closed by the differentiated constraint A qddot = thetadot (xdot c + ydot s).
    """
    M, m, I = params.M, params.m, params.I
    S = np.array([[0.0, -1.0], [1.0, 0.0]])

    def f(t, z):
        x, y, th, xd, yd, thd = z
        a, b, ad, bd, add, bdd = ctrl(t)
        c, s = math.cos(th), math.sin(th)
        R = np.array([[c, -s], [s, c]])
        rho, rhod, rhodd = np.array([a, b]), np.array([ad, bd]), np.array([add, bdd])
        J = np.zeros((2, 3))
        J[:, :2] = np.eye(2)
        J[:, 2] = R @ S @ rho
        h = R @ (rhodd + 2 * thd * (S @ rhod) - thd**2 * rho)
        K = np.zeros((4, 4))
        K[:3, :3] = np.diag([M, M, I]) + m * J.T @ J
        A = np.array([-s, c, 0.0])
        K[:3, 3] = -A
        K[3, :3] = A
        rhs = np.zeros(4)
        rhs[:3] = -m * J.T @ h
        rhs[3] = thd * (xd * c + yd * s)
        sol = np.linalg.solve(K, rhs)
        return [xd, yd, thd, sol[0], sol[1], sol[2]]

    return f


def test_rhs_agrees_with_spatial_lagrange_dalembert():
    params = PARAMS
    x0, y0, th0 = 0.1, -0.2, 0.3
    xi1_0, xi2_0 = 0.4, 0.8  # initial angular velocity and speed along the blade
    t_span = (0.0, 5.0)
    t_eval = np.linspace(*t_span, 51)

    z0 = [x0, y0, th0, xi2_0 * math.cos(th0), xi2_0 * math.sin(th0), xi1_0]
    ref = solve_ivp(spatial_rhs(params), t_span, z0, method="DOP853", rtol=1e-12, atol=1e-12, t_eval=t_eval)
    assert ref.success
    # The knife-edge constraint holds along the reference (a sanity check of the reference itself).
    knife = -ref.y[3] * np.sin(ref.y[2]) + ref.y[4] * np.cos(ref.y[2])
    assert np.max(np.abs(knife)) < 1e-10

    a, b, ad, bd, _, _ = ctrl(0.0)
    p0 = independent_momenta(params, xi1_0, xi2_0, a, b, ad, bd)

    def f(t, state):
        a, b, ad, bd, _, _ = ctrl(t)
        return model.rhs(params, state, a, b, ad, bd)

    out = solve_ivp(f, t_span, [p0[0], p0[1], th0, x0, y0], method="DOP853", rtol=1e-12, atol=1e-12,
                    t_eval=t_eval)
    assert out.success
    # The motion is non-trivial (so agreement is meaningful).
    assert np.ptp(ref.y[0]) > 1.0 and np.ptp(ref.y[2]) > 0.5
    np.testing.assert_allclose(out.y[2], ref.y[2], rtol=0, atol=1e-9)  # theta
    np.testing.assert_allclose(out.y[3], ref.y[0], rtol=0, atol=1e-9)  # x
    np.testing.assert_allclose(out.y[4], ref.y[1], rtol=0, atol=1e-9)  # y
    # Body velocities agree too: xi1 = thetadot, xi2 = xdot cos + ydot sin.
    xi1, xi2, _ = model.velocities(params, out.y[0], out.y[1], *np.array([ctrl(t)[:4] for t in t_eval]).T)
    np.testing.assert_allclose(xi1, ref.y[5], rtol=0, atol=1e-9)
    np.testing.assert_allclose(xi2, ref.y[3] * np.cos(ref.y[2]) + ref.y[4] * np.sin(ref.y[2]), rtol=0, atol=1e-9)


# --------------------------------------------------------------------------------------------------
# 3. Energy with the mass locked
# --------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("params, a, b", [(PARAMS, 0.6, -0.4), (SleighParams(), -0.3, 0.7)])
def test_energy_conserved_with_mass_locked(params, a, b):
    state0 = [0.7, 1.1, 0.2, 0.0, 0.0]
    sol = solve_ivp(lambda t, s: model.rhs(params, s, a, b, 0.0, 0.0), (0.0, 10.0), state0,
                    method="DOP853", rtol=1e-12, atol=1e-12, t_eval=np.linspace(0.0, 10.0, 201))
    assert sol.success
    xi1, xi2, eta = model.velocities(params, sol.y[0], sol.y[1], a, b, 0.0, 0.0)
    E = model.skate_energy(params, xi1, xi2) + model.mass_energy(params, xi1, xi2, a, b, 0.0, 0.0)
    # The energy is independently T(xi) as written in PHYSICS.md.
    np.testing.assert_allclose(E, kinetic_energy(params, xi1, xi2, a, b, 0.0, 0.0), rtol=1e-14)
    # The dynamics is non-trivial: momenta exchange (eta != 0 since a != 0).
    assert np.ptp(sol.y[0]) > 1e-2
    assert np.max(np.abs(E - E[0])) < 1e-10 * max(1.0, E[0])


def test_energy_not_conserved_when_mass_moves():
    # Guard that the conservation test can fail: with the controls doing work the energy changes.
    params = PARAMS

    def f(t, s):
        a, b, ad, bd, _, _ = ctrl(t)
        return model.rhs(params, s, a, b, ad, bd)

    sol = solve_ivp(f, (0.0, 5.0), [0.7, 1.1, 0.2, 0.0, 0.0], method="DOP853", rtol=1e-10, atol=1e-12,
                    t_eval=np.linspace(0.0, 5.0, 51))
    ctl = np.array([ctrl(t)[:4] for t in sol.t]).T
    xi1, xi2, _ = model.velocities(params, sol.y[0], sol.y[1], *ctl)
    E = model.skate_energy(params, xi1, xi2) + model.mass_energy(params, xi1, xi2, *ctl)
    assert np.ptp(E) > 1e-3


# --------------------------------------------------------------------------------------------------
# 4. Curvature condition
# --------------------------------------------------------------------------------------------------
def test_curvature_condition_equals_D_times_xi1_minus_kappa_xi2():
    rng = np.random.default_rng(5)
    X = random_inputs(rng, 500)
    p1, p2, a, b, adot, bdot = X.T
    kappa = rng.uniform(-3.0, 3.0, size=500)
    M, m, I = PARAMS.M, PARAMS.m, PARAMS.I
    D = (M + m) * (I + m * a**2) + M * m * b**2
    xi1, xi2, _ = model.velocities(PARAMS, p1, p2, a, b, adot, bdot)
    c_a, c_b, c_0 = model.curvature_coefficients(PARAMS, kappa, p1, p2, a, b)
    lhs = c_a * adot + c_b * bdot + c_0
    rhs = D * (xi1 - kappa * xi2)
    scale = np.abs(c_a * adot) + np.abs(c_b * bdot) + np.abs(c_0)
    assert np.all(np.abs(lhs - rhs) <= 1e-13 * scale + 1e-14)


def test_rhs_jacobian_is_the_complex_step_derivative_of_rhs():
    """The exact derivatives of the tracking law's linearisation against complex steps through
    ``rhs`` itself (no subtraction, so accurate to round-off: an independent check of every entry)."""
    rng = np.random.default_rng(11)
    X = random_inputs(rng, 300)
    theta = rng.uniform(-4.0, 4.0, size=300)
    v = [X[:, 0], X[:, 1], theta, rng.normal(size=300), rng.normal(size=300), X[:, 2], X[:, 3], X[:, 4], X[:, 5]]
    J = model.rhs_jacobian(PARAMS, np.array(v[:5]), *v[5:])
    assert J.shape == (5, 9, 300)
    h = 1e-30
    for j in range(9):
        w = [np.asarray(x, dtype=complex) for x in v]
        w[j] = w[j] + 1j * h
        cs = model.rhs(PARAMS, np.array(w[:5]), *w[5:]).imag / h
        scale = np.max(np.abs(cs), axis=1, keepdims=True) + 1.0
        assert np.all(np.abs(J[:, j] - cs) <= 1e-12 * scale), f"column {j}"
    # one point: shapes without the trailing axis
    assert model.rhs_jacobian(PARAMS, np.array(v[:5])[:, 0], *(x[0] for x in v[5:])).shape == (5, 9)


@pytest.mark.parametrize("kappa", [1 / 1.2, -0.5, 2.0, 1e-3])
def test_singular_point_is_where_both_coefficients_vanish(kappa):
    params = PARAMS
    a_s, b_s = model.singular_point(params, kappa)
    assert (a_s, b_s) == pytest.approx((0.0, -kappa * params.I / params.M), abs=1e-15)
    c_a, c_b, _ = model.curvature_coefficients(params, kappa, 0.3, -0.2, a_s, b_s)
    assert abs(c_a) < 1e-14 and abs(c_b) < 1e-14
    # Nearby, at least one coefficient is non-zero.
    for da, db in [(1e-3, 0.0), (0.0, 1e-3), (-1e-3, 1e-3)]:
        c_a, c_b, _ = model.curvature_coefficients(params, kappa, 0.3, -0.2, a_s + da, b_s + db)
        assert math.hypot(c_a, c_b) > 1e-5
    # The other zero set of c_b, b = (M+m)/(kappa m), never makes c_a vanish (it is the unique point).
    b_other = (params.M + params.m) / (kappa * params.m)
    for a in np.linspace(-3.0, 3.0, 13):
        c_a, c_b, _ = model.curvature_coefficients(params, kappa, 0.3, -0.2, a, b_other)
        assert abs(c_b) < 1e-9 * (1 + abs(b_other))
        assert abs(c_a) > 1e-3


# --------------------------------------------------------------------------------------------------
# 5. Invariant on an arc
# --------------------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def stop_on_arc():
    return solve_stop(SleighParams(), [(1 / 1.2, 1.0)], (0.0, 0.0), 1.0)


def test_stop_solution_converged(stop_on_arc):
    sol = stop_on_arc
    assert sol.success is True
    assert sol.residuals, "residuals should be reported"
    for name, value in sol.residuals.items():
        assert abs(value) <= 1e-10, name


def test_p1_plus_r_p2_is_conserved_on_arc(stop_on_arc):
    r = 1.2
    leg = stop_on_arc.legs[0]
    t = np.linspace(leg.t0, leg.t1, 400)
    p1, p2, a, b, s = leg.sol(t)
    # The run really brings the glide to rest along the whole length.
    assert s[-1] == pytest.approx(1.0, abs=1e-10)
    correct = p1 + r * p2  # PHYSICS.md "Invariant on an arc"
    paper = p1 + p2 / r  # the paper's lemma (p1_p2_const), which is wrong
    assert np.ptp(correct) <= 1e-10
    assert np.ptp(paper) > 1e-2
    # The blade really follows curvature 1/r: xi1 = xi2 / r along the solution.
    from skatetrace.tracing.maneuver import constrained_rates

    u = stop_on_arc.control(t)
    ad, bd, _ = constrained_rates(SleighParams(), 1 / r, p1, p2, a, b, u)
    xi1, xi2, _ = model.velocities(SleighParams(), p1, p2, a, b, ad, bd)
    np.testing.assert_allclose(xi1 * r, xi2, rtol=0, atol=1e-10)


# --------------------------------------------------------------------------------------------------
# 6. SleighParams validation
# --------------------------------------------------------------------------------------------------
@pytest.mark.parametrize(
    "kwargs, exc, match",
    [
        ({"M": 0.0}, ValueError, r"`M` \(sleigh mass\)"),
        ({"m": 0}, ValueError, r"`m` \(moving mass\)"),
        ({"I": -1.0}, ValueError, r"`I` \(sleigh moment of inertia\)"),
        ({"M": -2.5}, ValueError, r"`M`.*positive finite"),
        ({"m": float("nan")}, ValueError, r"`m`.*positive finite"),
        ({"I": float("inf")}, ValueError, r"`I`.*positive finite"),
        ({"M": float("-inf")}, ValueError, r"`M`"),
        ({"I": np.nan}, ValueError, r"`I`"),
        ({"M": "2"}, TypeError, r"`M`.*must be a number"),
        ({"m": None}, TypeError, r"`m`.*must be a number"),
        ({"I": True}, TypeError, r"`I`.*must be a number"),
        ({"M": False}, TypeError, r"`M`"),
        ({"m": [1.0]}, TypeError, r"`m`"),
    ],
)
def test_sleigh_params_rejects_bad_values(kwargs, exc, match):
    with pytest.raises(exc, match=match):
        SleighParams(**kwargs)


def test_sleigh_params_accepts_and_normalises_numbers():
    p = SleighParams(M=3, m=np.float32(0.5), I=np.int64(2))
    assert (p.M, p.m, p.I) == (3.0, 0.5, 2.0)
    assert all(type(v) is float for v in (p.M, p.m, p.I))
    assert SleighParams() == SleighParams(M=2.0, m=1.0, I=3.0)


# --------------------------------------------------------------------------------------------------
# 7. Skate energy on an arc
# --------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("r", [1.2, 0.7, -2.0])
def test_skate_energy_on_arc(r):
    # Source: shared/PHYSICS.md, "Energies": KE_skate = 1/2 M xi2^2 + 1/2 I xi1^2, and on an arc
    # xi1 = xi2 / r gives 1/2 xi2^2 (M + I / r^2). The paper's 1/2 M xi2^2 (1 + M r / I) is wrong.
    params = SleighParams()  # the paper's M = 2, m = 1, I = 3
    xi2 = np.array([0.3, 1.0, -1.7, 2.5])
    xi1 = xi2 / r
    E = model.skate_energy(params, xi1, xi2)
    np.testing.assert_allclose(E, 0.5 * xi2**2 * (params.M + params.I / r**2), rtol=1e-14)
    paper = 0.5 * params.M * xi2**2 * (1 + params.M * r / params.I)
    assert np.all(np.abs(E - paper) > 0.05 * E)


def test_mass_energy_formula():
    rng = np.random.default_rng(6)
    for xi1, xi2, a, b, adot, bdot in random_inputs(rng, 50):
        total = model.skate_energy(PARAMS, xi1, xi2) + model.mass_energy(PARAMS, xi1, xi2, a, b, adot, bdot)
        assert total == pytest.approx(kinetic_energy(PARAMS, xi1, xi2, a, b, adot, bdot), rel=1e-13)
