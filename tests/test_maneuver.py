"""The manoeuvre solver: its compiled right-hand side against the model's formulas, and its solves."""

import math

import numpy as np
import pytest

from skatetrace.integrator import _rhs
from skatetrace.maneuver import constrained_rates, solve_stop
from skatetrace.model import SleighParams, curvature_coefficients, rhs, velocities


@pytest.mark.parametrize("params", [SleighParams(), SleighParams(M=2.3, m=1.7, I=0.9)])
def test_inlined_rhs_matches_model(params):
    rng = np.random.default_rng(3)
    for _ in range(20):
        p1, p2, a, b, kappa, u = rng.normal(size=6)
        out = np.empty(5)
        assert _rhs(params.M, params.m, params.I, kappa, u, 1.0, np.array([p1, p2, a, b, 0.0]), out)  # u = alpha t at t = 1
        dp1, dp2, da, db, ds = out
        ad, bd, _ = constrained_rates(params, kappa, p1, p2, a, b, u)
        ref = rhs(params, np.array([p1, p2, 0.0, 0.0, 0.0]), a, b, ad, bd)
        xi1, xi2, _ = velocities(params, p1, p2, a, b, ad, bd)
        np.testing.assert_allclose([dp1, dp2, da, db, ds], [ref[0], ref[1], ad, bd, xi2], rtol=1e-12, atol=1e-12)
        # the rates hold the curvature: c . rates + c0 = 0, i.e. xi1 = kappa xi2
        c_a, c_b, c_0 = curvature_coefficients(params, kappa, p1, p2, a, b)
        assert abs(c_a * ad + c_b * bd + c_0) < 1e-10 * (1 + abs(c_0))
        assert abs(xi1 - kappa * xi2) < 1e-10 * (1 + abs(xi2))


def test_stop_and_launch_are_mirror_images():
    p = SleighParams()
    stop = solve_stop(p, [(1 / 1.2, 1.0)], (0.0, 0.0), 1.0)
    launch = solve_stop(p, [(1 / 1.2, 1.0)], (0.0, 0.0), 1.0, backward=True)
    assert stop.success and launch.success
    assert launch.duration == pytest.approx(-stop.duration, rel=1e-9)
    t = np.linspace(0, stop.duration, 7)
    ys, yl = stop.legs[0].sol(t), launch.legs[0].sol(-t)
    np.testing.assert_allclose(yl[2], -ys[2], atol=1e-9)  # a -> -a
    np.testing.assert_allclose(yl[3], ys[3], atol=1e-9)  # b -> b


def test_stop_reports_failure_as_data_at_the_singular_point():
    p = SleighParams()
    k = 1.0
    res = solve_stop(p, [(k, 1.0)], (0.0, -k * p.I / p.M), 1.0)
    assert not res.success and "singular" in res.message


def test_polish_rejects_a_duration_of_the_wrong_sign(monkeypatch):
    # Newton's method may land on a root whose duration has the other sign (the manoeuvre would run
    # backwards in time: a stop before its glide). Seen on the change-loop school figure, where it
    # gave a section of negative duration; such a root must be refused, not assembled. Here every
    # candidate meets the boundary conditions, so only the sign of the duration can reject it.
    from types import SimpleNamespace

    from skatetrace import maneuver
    from skatetrace.model import SleighParams

    length = 1.0
    monkeypatch.setattr(maneuver, "root", lambda *a, **k: SimpleNamespace(x=np.array([1.0, -0.5])))
    monkeypatch.setattr(maneuver, "_integrate", lambda params, y0, legs_spec, u, tau, **kw: (
        [None] * len(legs_spec), 0, tau, np.array([0.0, 0.0, 0.0, 0.0, length]), None))
    monkeypatch.setattr(maneuver, "_end_speed", lambda *a: 0.0)
    params = SleighParams()
    y0 = np.zeros(5)
    sol, res, _ = maneuver._polish_stop(params, [(1.0, math.inf)], y0, 1.0, 1.0, length, 0.3, 2.0, 1e-10, 1e-12)
    assert sol is None and res is None
    # the same root with a positive duration is accepted
    monkeypatch.setattr(maneuver, "root", lambda *a, **k: SimpleNamespace(x=np.array([1.0, 0.5])))
    sol, res, _ = maneuver._polish_stop(params, [(1.0, math.inf)], y0, 1.0, 1.0, length, 0.3, 2.0, 1e-10, 1e-12)
    assert sol == pytest.approx((0.3, 1.0)) and res == {"end_speed": 0.0, "length": 0.0}
