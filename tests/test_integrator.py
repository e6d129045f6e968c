"""The compiled DOP853 manoeuvre integrator against scipy's solve_ivp on the same problems."""

import math
import pickle

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from skatetrace.dynamics.integrator import DenseSolution, _rhs, integrate_legs
from skatetrace.tracing.maneuver import constrained_rates, glide_state
from skatetrace.dynamics.model import SleighParams, velocities
from skatetrace.dynamics.model import rhs as model_rhs

P = SleighParams()
RTOL, ATOL = 1e-12, 1e-13


def _fun(params, kappa, alpha):
    def f(t, y):
        out = np.empty(5)
        if not _rhs.py_func(params.M, params.m, params.I, kappa, alpha, 0.0, t, np.asarray(y, dtype=float), out):
            raise FloatingPointError("singular point")
        return out

    return f


def _glide(kappa, b=0.3, speed=1.0):
    return np.r_[glide_state(P, kappa, 0.0, b, speed), 0.0, b, 0.0]


def _scipy_legs(kappas, switches, alpha, t_end, y0, events=()):
    """The same integration leg by leg with solve_ivp: the reference."""
    sols, t0, y = [], 0.0, y0
    for kappa, switch in zip(kappas, switches):
        evs = list(events)
        if math.isfinite(switch):
            def join(t, y, _s=switch):
                return abs(y[4]) - _s
            join.terminal = True
            evs.insert(0, join)
        sol = solve_ivp(_fun(P, kappa, alpha), (t0, t_end), y, method="DOP853", rtol=RTOL, atol=ATOL,
                        dense_output=True, events=evs or None)
        sols.append(sol)
        if sol.status == 1 and math.isfinite(switch) and len(sol.t_events[0]):
            t0, y = sol.t[-1], sol.y[:, -1]
            continue
        break
    return sols


@pytest.mark.parametrize("t_end", [4.0, -4.0])
def test_legs_and_dense_output_match_solve_ivp(t_end):
    y0 = _glide(1 / 1.2)
    kappas, switches = [1 / 1.2, -0.5, 0.0], [1.0, 2.0, math.inf]
    res = integrate_legs(P, y0, kappas, switches, 0.05, t_end, rtol=RTOL, atol=ATOL, dense=True)
    ref = _scipy_legs(kappas, switches, 0.05, t_end, y0)
    assert res.status == 0 and res.hit is None
    assert res.nlegs == len(ref) == 3
    scale = np.abs(ref[-1].y).max()
    # the joins are located by two different root finders, and each leg restarts from its join:
    # under the initial state perturbed by 1e-15..1e-11 the join times differ by up to 1.7e-13
    # and the states by 1.2e-11 x scale, so the bounds are 1e-11 and 1e-9 x scale (as for the
    # polynomial legs below), far below what a wrong right-hand side or join would give
    np.testing.assert_allclose(res.y, ref[-1].y[:, -1], atol=1e-9 * scale)
    for i, sol in enumerate(ref):
        assert res.leg_bounds[i + 1] == pytest.approx(sol.t[-1], abs=1e-11)
        tt = np.linspace(res.leg_bounds[i], res.leg_bounds[i + 1], 13)
        np.testing.assert_allclose(res.legs[i](tt), sol.sol(tt), atol=1e-9 * scale)
    # the joins are where |s| reaches the switch lengths
    for i, sw in enumerate(switches[:-1]):
        assert abs(res.legs[i](res.leg_bounds[i + 1])[4]) == pytest.approx(sw, abs=1e-12)


def test_an_offset_control_is_the_ramp_shifted_in_time():
    """``u = alpha t + beta`` from 0 is the ramp ``alpha t`` from ``beta / alpha``: the same motion."""
    y0 = _glide(1 / 1.2)
    alpha, beta, h = 0.05, 0.2, 1.5
    shifted = integrate_legs(P, y0, [1 / 1.2], [math.inf], alpha, h, rtol=RTOL, atol=ATOL, beta=beta)
    t0 = beta / alpha
    ref = solve_ivp(_fun(P, 1 / 1.2, alpha), (t0, t0 + h), y0, method="DOP853", rtol=RTOL, atol=ATOL)
    assert shifted.status == 0
    np.testing.assert_allclose(shifted.y, ref.y[:, -1], atol=1e-9 * np.abs(ref.y).max())
    # and the offset matters: without it the mass ends elsewhere
    plain = integrate_legs(P, y0, [1 / 1.2], [math.inf], alpha, h, rtol=RTOL, atol=ATOL)
    assert np.max(np.abs(plain.y - shifted.y)) > 1e-3


def test_stop_event_matches_solve_ivp():
    y0 = _glide(1 / 1.2)
    kappa, alpha = 1 / 1.2, -0.3

    def stopped(t, y):
        return _fun(P, kappa, alpha)(t, y)[4]

    stopped.terminal = True
    res = integrate_legs(P, y0, [kappa], [math.inf], alpha, -20.0, rtol=RTOL, atol=ATOL, stop_event=True)
    ref = _scipy_legs([kappa], [math.inf], alpha, -20.0, y0, events=(stopped,))[0]
    assert res.hit == "stopped" and ref.status == 1
    assert res.t == pytest.approx(ref.t_events[0][0], abs=1e-10)
    np.testing.assert_allclose(res.y, ref.y_events[0][0], atol=1e-10)
    assert abs(stopped(res.t, res.y)) < 1e-12


def test_singular_event_ends_near_the_singular_point():
    # ramping the mass towards the singular point (0, -kappa I / M) must end there, not blow up
    kappa = 1.0
    sb = -kappa * P.I / P.M
    y0 = np.r_[glide_state(P, kappa, 0.0, sb + 0.05, 1.0), 0.0, sb + 0.05, 0.0]
    for alpha in (-1.0, 1.0):
        res = integrate_legs(P, y0, [kappa], [math.inf], alpha, 30.0, rtol=RTOL, atol=ATOL, singular_limit=0.01)
        if res.hit == "singular":
            assert math.hypot(res.y[2], res.y[3] - sb) == pytest.approx(0.01, abs=1e-9)
            return
    pytest.fail("neither ramp direction reached the singular point's neighbourhood")


def test_failure_at_the_singular_point_is_a_status_not_an_exception():
    kappa = 1.0
    y0 = np.array([0.1, 0.2, 0.0, -kappa * P.I / P.M, 0.0])  # exactly at the singular point
    res = integrate_legs(P, y0, [kappa], [math.inf], 0.0, 1.0, rtol=RTOL, atol=ATOL)
    assert res.status < 0 and "singular" in res.message


def test_evaluation_budget_ends_the_run():
    res = integrate_legs(P, _glide(1 / 1.2), [1 / 1.2], [math.inf], 0.05, 50.0, rtol=RTOL, atol=ATOL, max_nfev=200)
    assert res.status < 0 and "budget" in res.message


def test_dense_solution_pickles_and_evaluates_scalars():
    res = integrate_legs(P, _glide(0.5), [0.5], [math.inf], 0.02, -3.0, rtol=RTOL, atol=ATOL, dense=True)
    sol = res.legs[0]
    assert isinstance(sol, DenseSolution)
    again = pickle.loads(pickle.dumps(sol))
    tt = np.linspace(-3.0, 0.0, 9)
    np.testing.assert_array_equal(again(tt), sol(tt))
    assert sol(-1.5).shape == (5,)
    np.testing.assert_allclose(sol(0.0), _glide(0.5), atol=1e-15)
    np.testing.assert_allclose(sol(-3.0), res.y, atol=1e-15)


def test_a_failed_dense_run_reports_where_it_stopped():
    res = integrate_legs(P, _glide(1 / 1.2), [1 / 1.2, -0.5], [1.0, math.inf], 0.05, 50.0, rtol=RTOL, atol=ATOL,
                         max_nfev=300, dense=True)
    assert res.status < 0 and res.legs == ()
    assert res.leg_bounds[-1] == res.t and np.all(np.isfinite(res.leg_bounds))


# --- legs of variable (cubic polynomial) curvature -------------------------------------------------

RTOL_POLY = ATOL_POLY = 1e-12


def _kappa(coef, s0, s):
    """Curvature of a leg with coefficients ``coef`` starting at ``|s| = s0``, at arc length ``s``."""
    sigma = abs(s) - s0
    return sum(c * sigma ** k for k, c in enumerate(coef))


def _ref_fun(coef, s0, alpha):
    """Independent right-hand side: the model's rates and momenta equations, kappa from ``|s|``."""
    def f(t, y):
        p1, p2, a, b, s = y
        kappa = _kappa(coef, s0, s)
        ad, bd, n = constrained_rates(P, kappa, p1, p2, a, b, alpha * t)
        if not n > 0.0:
            raise FloatingPointError("singular point")
        dp = model_rhs(P, np.array([p1, p2, 0.0, 0.0, 0.0]), a, b, ad, bd)
        _xi1, xi2, _eta = velocities(P, p1, p2, a, b, ad, bd)
        return np.array([dp[0], dp[1], ad, bd, xi2])

    return f


def _scipy_poly_legs(coefs, switches, alpha, t_end, y0):
    """Leg by leg with solve_ivp on :func:`_ref_fun`, each leg's sigma measured from its start."""
    sols, t0, y, s0 = [], 0.0, y0, 0.0
    for coef, switch in zip(coefs, switches):
        events = None
        if math.isfinite(switch):
            def join(t, y, _s=switch):
                return abs(y[4]) - _s
            join.terminal = True
            events = [join]
        sol = solve_ivp(_ref_fun(coef, s0, alpha), (t0, t_end), y, method="DOP853", rtol=RTOL_POLY,
                        atol=ATOL_POLY, dense_output=True, events=events)
        assert sol.status >= 0, sol.message
        sols.append(sol)
        if sol.status == 1:
            t0, y, s0 = sol.t[-1], sol.y[:, -1], switch
            continue
        break
    return sols


_POLY_CASES = {
    "clothoid": ([[0.3, 0.2, 0.0, 0.0]], [math.inf]),
    "cubic": ([[0.5, -0.3, 0.1, -0.02]], [math.inf]),
    "constant_then_cubic": ([[1 / 1.2, 0.0, 0.0, 0.0], [-0.5, 0.4, -0.1, 0.05]], [1.0, math.inf]),
    "three_polynomial_legs": ([[0.3, 0.2, 0.0, 0.0], [-0.5, 0.4, -0.1, 0.05], [0.2, -0.1, 0.03, -0.01]],
                              [1.0, 2.2, math.inf]),
}


def _leg_starts(switches):
    return [0.0] + list(switches[:-1])


@pytest.mark.parametrize("t_end", [4.0, -4.0])
@pytest.mark.parametrize("case", list(_POLY_CASES))
def test_polynomial_curvature_matches_solve_ivp(case, t_end):
    coefs, switches = _POLY_CASES[case]
    alpha = 0.05
    y0 = _glide(coefs[0][0])
    res = integrate_legs(P, y0, np.array(coefs), switches, alpha, t_end, rtol=RTOL_POLY, atol=ATOL_POLY, dense=True)
    ref = _scipy_poly_legs(coefs, switches, alpha, t_end, y0)
    assert res.status == 0 and res.hit is None
    assert res.nlegs == len(ref) == len(coefs)
    assert res.t == t_end and ref[-1].t[-1] == t_end
    if t_end < 0:
        assert res.y[4] < -switches[-2] if len(switches) > 1 else res.y[4] < 0.0  # s runs negative
    scale = max(np.abs(sol.y).max() for sol in ref)
    np.testing.assert_allclose(res.y, ref[-1].y[:, -1], rtol=0.0, atol=1e-9 * scale)
    for i, sol in enumerate(ref):
        # join times (and the final time)
        assert res.leg_bounds[i] == pytest.approx(sol.t[0], abs=1e-9 * abs(t_end))
        assert res.leg_bounds[i + 1] == pytest.approx(sol.t[-1], abs=1e-9 * abs(t_end))
        tt = np.linspace(res.leg_bounds[i], res.leg_bounds[i + 1], 13)
        np.testing.assert_allclose(res.legs[i](tt), sol.sol(tt), rtol=0.0, atol=1e-9 * scale)
        # the same initial step as scipy's on every leg (it samples the RHS a little way along the leg)
        h_first = res.legs[i].h[0] if t_end > 0 else res.legs[i].h[-1]
        assert h_first == pytest.approx(sol.t[1] - sol.t[0], rel=1e-9)
    for i, sw in enumerate(switches[:-1]):
        assert abs(res.legs[i](res.leg_bounds[i + 1])[4]) == pytest.approx(sw, abs=1e-12)
    # the curvature really varies along the polynomial legs (the test is not a constant one in disguise)
    s_end = abs(res.y[4]) - _leg_starts(switches)[-1]
    assert s_end > 0.5 and _kappa(coefs[-1], 0.0, s_end) != pytest.approx(coefs[-1][0], abs=0.05)


@pytest.mark.parametrize("t_end", [4.0, -4.0])
@pytest.mark.parametrize("case", ["cubic", "three_polynomial_legs"])
def test_polynomial_curvature_is_held_along_the_solution(case, t_end):
    coefs, switches = _POLY_CASES[case]
    alpha = 0.05
    res = integrate_legs(P, _glide(coefs[0][0]), coefs, switches, alpha, t_end, rtol=RTOL_POLY, atol=ATOL_POLY,
                         dense=True)
    assert res.status == 0 and res.nlegs == len(coefs)
    for i, (coef, s0) in enumerate(zip(coefs, _leg_starts(switches))):
        t0, t1 = res.leg_bounds[i], res.leg_bounds[i + 1]
        tt = np.linspace(t0, t1, 41)[1:-1]  # inside the leg
        p1, p2, a, b, s = res.legs[i](tt)
        kappa = _kappa(coef, s0, s)
        # the rates that hold kappa(|s|) give xi1 = kappa xi2 (algebraically, up to rounding)
        ad, bd, _n = constrained_rates(P, kappa, p1, p2, a, b, alpha * tt)
        xi1, xi2, _eta = velocities(P, p1, p2, a, b, ad, bd)
        assert np.all(np.abs(xi1 - kappa * xi2) <= 1e-12 * (np.abs(xi1) + np.abs(kappa * xi2)))
        # and the integrated motion follows them: the dense output's own rates (central differences)
        # give the same xi1 = kappa(|s|) xi2, so the integrator used kappa at the current |s|
        dt = 1e-5
        yp, ym = res.legs[i](tt + dt), res.legs[i](tt - dt)
        ad_fd, bd_fd = (yp[2] - ym[2]) / (2 * dt), (yp[3] - ym[3]) / (2 * dt)
        np.testing.assert_allclose(ad_fd, ad, rtol=0.0, atol=1e-7 * np.abs(ad).max())
        np.testing.assert_allclose(bd_fd, bd, rtol=0.0, atol=1e-7 * np.abs(bd).max())
        xi1_fd, xi2_fd, _eta = velocities(P, p1, p2, a, b, ad_fd, bd_fd)
        assert np.all(np.abs(xi1_fd - kappa * xi2_fd) <= 1e-7 * np.abs(xi2_fd).max())
        # the speed along the blade is ds/dt
        np.testing.assert_allclose((yp[4] - ym[4]) / (2 * dt), xi2, rtol=0.0, atol=1e-7 * np.abs(xi2).max())


@pytest.mark.parametrize("t_end", [4.0, -4.0])
def test_constant_curvature_as_1d_or_zero_padded_2d_is_bit_identical(t_end):
    y0 = _glide(1 / 1.2)
    kappas, switches = [1 / 1.2, -0.5, 0.0], [1.0, 2.0, math.inf]
    padded = np.zeros((3, 4))
    padded[:, 0] = kappas
    kw = dict(rtol=RTOL, atol=ATOL, stop_event=True, singular_limit=1e-3, dense=True)
    r1 = integrate_legs(P, y0, kappas, switches, 0.05, t_end, **kw)
    r2 = integrate_legs(P, y0, padded, switches, 0.05, t_end, **kw)
    assert (r1.status, r1.hit, r1.t) == (r2.status, r2.hit, r2.t) and r1.nlegs == r2.nlegs >= 2
    np.testing.assert_array_equal(r1.y, r2.y)
    np.testing.assert_array_equal(r1.leg_bounds, r2.leg_bounds)
    for l1, l2 in zip(r1.legs, r2.legs):
        for name in ("t_old", "h", "y_old", "F"):
            np.testing.assert_array_equal(getattr(l1, name), getattr(l2, name))


def test_polynomial_leg_singular_event_uses_the_curvature_at_the_current_s():
    # the singular point (0, -kappa(|s|) I / M) moves along the leg: the event must end at the
    # distance singular_limit from where it is at the final |s|, not where it was at the leg's start
    coef = [1.0, 0.2, 0.0, 0.0]
    for alpha in (-1.0, 1.0):
        sb0 = -coef[0] * P.I / P.M
        y0 = np.r_[glide_state(P, coef[0], 0.0, sb0 + 0.05, 1.0), 0.0, sb0 + 0.05, 0.0]
        res = integrate_legs(P, y0, [coef], [math.inf], alpha, 30.0, rtol=RTOL, atol=ATOL, singular_limit=0.01)
        if res.hit == "singular":
            sb = -_kappa(coef, 0.0, res.y[4]) * P.I / P.M
            assert abs(res.y[4]) > 1e-3  # the point has moved
            assert math.hypot(res.y[2], res.y[3] - sb) == pytest.approx(0.01, abs=1e-9)
            return
    pytest.fail("neither ramp direction reached the singular point's neighbourhood")


@pytest.mark.parametrize("kappas, switches", [
    (np.zeros((2, 3)), [1.0, math.inf]),
    (np.zeros((2, 4, 1)), [1.0, math.inf]),
    (np.zeros((2, 5)), [1.0, math.inf]),
    (0.5, [math.inf]),
    ([0.5, 0.2], [math.inf]),
    (np.zeros((2, 4)), [math.inf]),
    ([], []),
])
def test_bad_kappas_shape_raises(kappas, switches):
    with pytest.raises(ValueError, match="kappas|switches|leg"):
        integrate_legs(P, _glide(0.5), kappas, switches, 0.05, 1.0, rtol=RTOL, atol=ATOL)


# ---- issue 6: the lean entry point and the compiled dense evaluation -----------------------------


@pytest.mark.parametrize("t_end,stop", [(30.0, True), (-30.0, True), (1.5, False)])
def test_final_state_is_where_integrate_legs_ends(t_end, stop):
    from skatetrace.dynamics.integrator import final_state

    y0 = _glide(1 / 1.2)
    coef = np.array([[1 / 1.2, 0.0, 0.0, 0.0], [-0.5, 0.1, 0.0, 0.0]])
    switches = np.array([0.6, math.inf])
    ref = integrate_legs(P, y0, coef, switches, 2.0, t_end, rtol=RTOL, atol=ATOL, stop_event=stop,
                         singular_limit=1e-3)
    hit, t, y = final_state(P, y0, coef, switches, 2.0, t_end, rtol=RTOL, atol=ATOL, stop_event=stop,
                            singular_limit=1e-3)
    assert ref.status == 0 and hit == (ref.hit or "reached")
    assert t == ref.t and np.array_equal(y, ref.y)  # the same compiled run, bit for bit


def test_dense_evaluation_is_scipys_formula_bit_for_bit():
    res = integrate_legs(P, _glide(1.0), [1.0], [math.inf], 0.7, -3.0, rtol=RTOL, atol=ATOL, dense=True)
    sol = res.legs[0]
    # past both ends too (extrapolated from the nearest step), and on every step's two ends (each on
    # the step it starts), the steps of a launch's leg running backwards in time
    t = np.concatenate([np.linspace(-3.1, 0.1, 1001), sol._ends, sol.t_old + sol.h])
    # scipy's Dop853DenseOutput, vectorised over the points
    i = np.clip(np.searchsorted(sol._ends, t, side="right") - 1, 0, sol._ends.size - 1)
    x = ((t - sol.t_old[i]) / sol.h[i])[:, None]
    F = sol.F[i]
    ref = np.zeros((t.size, 5))
    for j in range(F.shape[1] - 1, -1, -1):
        ref += F[:, j]
        ref *= x if (F.shape[1] - 1 - j) % 2 == 0 else (1.0 - x)
    ref += sol.y_old[i]
    assert np.array_equal(sol(t), ref.T)
    assert np.array_equal(sol(t[17]), ref[17])
    assert np.isnan(sol(np.nan)).all()


def test_load_leaves_the_integrator_compiled():
    """``load`` makes the machine code ready (compiled, or read from numba's cache) before any figure's work."""
    from skatetrace.dynamics import integrator

    integrator.load()
    assert integrator._run.signatures and integrator._evaluate_steps.signatures


def test_load_integrates_once_a_process(monkeypatch):
    """Every ``trace_figure`` calls the loads; after the first they do nothing (their integration took some 30 us)."""
    from skatetrace.dynamics import integrator
    from skatetrace.tracing import leg_motion

    integrator.load()
    leg_motion.load()
    ran = []
    monkeypatch.setattr(integrator, "integrate_legs", lambda *a, **kw: ran.append("integrator"))
    monkeypatch.setattr(leg_motion, "integrate_legs", lambda *a, **kw: ran.append("leg motion"))
    integrator.load()
    leg_motion.load()
    assert ran == []


# ----------------------------------------------------------------------------------------------
# Event location: the false position on the dense output (integrator._event_time)
# ----------------------------------------------------------------------------------------------


def _events(coef, alpha, switch, stop, sing, t_old, h, y_old, F, t):
    """The three event functions at ``t`` on the step ``(t_old, h, y_old, F)``."""
    from skatetrace.dynamics import dop853 as rk
    from skatetrace.dynamics.integrator import _event_values

    g, work = np.empty(3), np.empty(5)
    y = rk.interpolate_into(t_old, h, y_old, F, t, np.empty(5))
    _event_values(P.M, P.m, P.I, coef, 0.0, alpha, 0.0, t, y, switch, stop, sing, g, work, np.nan)
    return g


def _located(coef, alpha, switch, stop, sing, e, t_old, h, y_old, F):
    """``_event_time`` on the step, with the event functions at its two ends."""
    from skatetrace.dynamics.integrator import _event_time

    g0 = _events(coef, alpha, switch, stop, sing, t_old, h, y_old, F, t_old)[e]
    g1 = _events(coef, alpha, switch, stop, sing, t_old, h, y_old, F, t_old + h)[e]
    root, count = _event_time(P.M, P.m, P.I, coef, 0.0, alpha, 0.0, t_old, h, y_old, F, t_old + h, switch, stop,
                              sing, e, g0, g1, np.empty(5), np.empty(5))
    return root, count, g0


def _bisection_count(coef, alpha, switch, stop, sing, e, t_old, h, y_old, F, g0):
    """How many evaluations a bisection down to adjacent floats takes on the same step."""
    lo, hi, glo, count = t_old, t_old + h, g0, 0
    while (mid := 0.5 * (lo + hi)) not in (lo, hi):
        g = _events(coef, alpha, switch, stop, sing, t_old, h, y_old, F, mid)[e]
        count += 1
        if (g <= 0.0) == (glo <= 0.0) and g != 0.0:
            lo, glo = mid, g
        else:
            hi = mid
    return count


def _is_sign_change(g_at, root, toward, g0):
    """Whether the event is past at ``root`` and not yet at the float beside it towards the step's start."""
    before = float(np.nextafter(root, toward))
    g_root, g_before = g_at(root), g_at(before)
    past = g_root == 0.0 or (g_root <= 0.0) != (g0 <= 0.0)
    return past and (g_before <= 0.0) == (g0 <= 0.0) and g_before != 0.0


@pytest.mark.parametrize("kappa,b,alpha,switch,stop,sing,event", [
    (1 / 1.2, 0.3, -0.3, math.inf, True, 0.0, 1),  # the speed vanishing
    (2.0, 0.1, -2.0, math.inf, True, 1e-3, 1),
    (1 / 1.2, 0.3, 0.05, 1.0, False, 0.0, 0),  # a join
    (0.5, 0.7, 0.2, 0.8, True, 0.01, 0),
    (1.0, -1.45, -1.0, math.inf, False, 0.01, 2),  # the singular point's neighbourhood
])
@pytest.mark.parametrize("t_end", [20.0, -20.0])
def test_events_are_located_to_adjacent_floats_in_few_evaluations(kappa, b, alpha, switch, stop, sing, event, t_end):
    """The integration ends at a sign change between adjacent floats, found in a third of a bisection's evaluations."""
    from skatetrace.dynamics.integrator import _run, _step_rows

    coef = np.array([[kappa, 0.0, 0.0, 0.0]])
    y0 = np.r_[glide_state(P, kappa, 0.0, b, 1.0), 0.0, b, 0.0]
    out = _run(P.M, P.m, P.I, y0, coef, np.array([switch]), alpha, 0.0, t_end, RTOL, ATOL, stop, sing, 10**6, True)
    status, t_hit, last = out[0], out[2], out[6] - 1
    assert last >= 0 and status in (0, 1, 2)
    steps = _step_rows(out[5], out[6], y0.size)
    t_old, h, y_old, F = steps[0][last], steps[1][last], steps[3][last].copy(), steps[4][last].copy()
    assert t_old < t_hit <= t_old + h if t_end > 0 else t_old + h <= t_hit < t_old
    args = (coef[0], alpha, switch, stop, sing)
    root, count, g0 = _located(*args, event, t_old, h, y_old, F)
    assert root == t_hit  # the integration ends where the locator says
    assert _is_sign_change(lambda t: _events(*args, t_old, h, y_old, F, t)[event], root, t_old, g0)
    bisection = _bisection_count(*args, event, t_old, h, y_old, F, g0)
    assert bisection >= 40 and count <= bisection // 3


def test_event_location_ends_at_adjacent_floats_on_any_interpolant():
    """On dense outputs of random shape (several roots, flat stretches) the bracket still ends at a sign change."""
    from skatetrace.dynamics.integrator import _FALSE_POSITION_STEPS

    rng = np.random.default_rng(7)
    coef, y_old = np.array([1.0, 0.0, 0.0, 0.0]), np.zeros(5)
    counts = []
    for _ in range(300):
        F = np.zeros((7, 5))
        F[:, 4] = rng.standard_normal(7) * 10.0 ** rng.uniform(-3, 3, 7)
        t_old, h = rng.uniform(-5, 5), rng.choice([-1.0, 1.0]) * 10.0 ** rng.uniform(-6, 1)
        end = _events(coef, 0.0, 1.0, False, 0.0, t_old, h, y_old, F, t_old + h)[0] + 1.0  # |s| at the step's end
        switch = end * rng.uniform(0.01, 0.99)
        root, count, g0 = _located(coef, 0.0, switch, False, 0.0, 0, t_old, h, y_old, F)
        assert _is_sign_change(lambda t: _events(coef, 0.0, switch, False, 0.0, t_old, h, y_old, F, t)[0],
                               root, t_old, g0)
        counts.append(count)
    # the false position's share is bounded, and a bisection finishes what it leaves
    assert max(counts) <= _FALSE_POSITION_STEPS + 64
    assert np.median(counts) <= 12


def test_an_event_exactly_at_a_float_is_found_there():
    """Where the event function is exactly zero at a float the false position lands on, that float is the answer."""
    F = np.zeros((7, 5))
    F[0, 4] = 1.0  # |s| = x on the step [1, 2]: the join at |s| = 0.25 is t = 1.25 exactly
    coef = np.array([1.0, 0.0, 0.0, 0.0])
    root, count, g0 = _located(coef, 0.0, 0.25, False, 0.0, 0, 1.0, 1.0, np.zeros(5), F)
    assert root == 1.25 and count <= 4


_PLAIN_RUN = """
import json
from skatetrace import Curve, Figure, Join, PAPER_PARAMS, Segment, trace_figure, verify
from skatetrace.verification.verify import schedule_from_trace
fig = Figure("two arcs", (Curve((Segment(0.8, 1.1), Segment(-1.3, 0.7)), (Join("cusp", 0.4),)),), PAPER_PARAMS)
trace = trace_figure(fig)
schedule, _ = schedule_from_trace(trace)
report = verify(trace, schedule)
print(json.dumps({"traced": trace.success, "verified": report.success,
                  "alphas": [ph.maneuver.params[0] for s in trace.sections for ph in s.phases if ph.maneuver]}))
"""


def test_the_same_code_runs_as_plain_python():
    """``NUMBA_DISABLE_JIT=1`` runs the tracer and the replay uncompiled (a debugging aid), to the same answer."""
    import json
    import os
    import subprocess
    import sys

    def run(disabled):
        env = dict(os.environ, NUMBA_DISABLE_JIT="1" if disabled else "0")
        done = subprocess.run([sys.executable, "-c", _PLAIN_RUN], env=env, capture_output=True, text=True,
                              timeout=600)
        assert done.returncode == 0, done.stderr[-2000:]
        return json.loads(done.stdout.strip().splitlines()[-1])

    compiled, plain = run(False), run(True)
    assert compiled["traced"] and compiled["verified"]
    assert plain["traced"] == compiled["traced"] and plain["verified"] == compiled["verified"]
    # the same operations in the same order, but numpy's sums are pairwise where numba's loop is not
    np.testing.assert_allclose(plain["alphas"], compiled["alphas"], rtol=1e-9)
