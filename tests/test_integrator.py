"""The compiled DOP853 manoeuvre integrator against scipy's solve_ivp on the same problems."""

import math
import pickle

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from skatetrace.integrator import DenseSolution, _rhs, integrate_legs
from skatetrace.maneuver import glide_state
from skatetrace.model import SleighParams

P = SleighParams()
RTOL, ATOL = 1e-12, 1e-13


def _fun(params, kappa, alpha):
    def f(t, y):
        out = np.empty(5)
        if not _rhs.py_func(params.M, params.m, params.I, kappa, alpha, t, np.asarray(y, dtype=float), out):
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
    np.testing.assert_allclose(res.y, ref[-1].y[:, -1], atol=1e-10 * scale)
    for i, sol in enumerate(ref):
        assert res.leg_bounds[i + 1] == pytest.approx(sol.t[-1], abs=1e-12)
        tt = np.linspace(res.leg_bounds[i], res.leg_bounds[i + 1], 13)
        np.testing.assert_allclose(res.legs[i](tt), sol.sol(tt), atol=1e-10 * scale)
    # the joins are where |s| reaches the switch lengths
    for i, sw in enumerate(switches[:-1]):
        assert abs(res.legs[i](res.leg_bounds[i + 1])[4]) == pytest.approx(sw, abs=1e-12)


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
