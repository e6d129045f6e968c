"""The compiled replay against scipy's solve_ivp, closed forms and its own failure reports."""

import importlib

import numpy as np
import pytest
from scipy.interpolate import CubicHermiteSpline

from skatetrace import trace_figure
from skatetrace.dynamics.controls import ControlSchedule
from skatetrace.dynamics.model import SleighParams, momenta
from skatetrace.figures.patterns import pattern
from skatetrace.dynamics.replayer import replay_chunk
from skatetrace.dynamics.simulate import simulate

verify_module = importlib.import_module("skatetrace.verification.verify")  # the package exports the function as verify


def _schedule(t, a, b, adot, bdot):
    n = t.size
    return ControlSchedule(t=t, a=a, b=b, adot=adot, bdot=bdot, section=np.zeros(n, int), piece=np.zeros(n, int))


def _wiggle(n=40, span=3.0):
    """A smooth swinging mass, sampled with its exact rates (knots unevenly spaced)."""
    t = span * np.linspace(0.0, 1.0, n) ** 1.3
    a = 0.4 * np.sin(1.7 * t) + 0.1
    b = 0.3 * np.cos(2.3 * t) - 0.2 * t / span
    return _schedule(t, a, b, 0.4 * 1.7 * np.cos(1.7 * t), -0.3 * 2.3 * np.sin(2.3 * t) - 0.2 / span)


@pytest.fixture(scope="module")
def flower():
    tr = trace_figure(pattern("double-flower"))
    schedule, _ = verify_module.schedule_from_trace(tr)
    return tr, schedule


def test_hermite_coefficients_are_scipys():
    s = _wiggle()
    knots, ca, cb = s.hermite(0, s.t.size)
    np.testing.assert_array_equal(knots, s.t)
    np.testing.assert_array_equal(ca, CubicHermiteSpline(s.t, s.a, s.adot).c.T)
    np.testing.assert_array_equal(cb, CubicHermiteSpline(s.t, s.b, s.bdot).c.T)
    f = s.interpolant(0, s.t.size)
    tt = np.linspace(0.0, s.t[-1], 333)
    spl = CubicHermiteSpline(s.t, s.a, s.adot)
    np.testing.assert_allclose(f(tt)[0], spl(tt), rtol=0, atol=1e-15)
    np.testing.assert_allclose(f(tt)[2], spl.derivative()(tt), rtol=0, atol=1e-14)


def test_hermite_rejects_rows_that_are_no_chunk():
    s = _wiggle()
    with pytest.raises(ValueError, match="no chunk"):
        s.hermite(3, 4)


def test_locked_mass_glides_in_a_straight_line():
    # mass fixed on the blade at a = 0.5: xi1 = 0 and xi2 = p2 / (M + m) = 1/3 for ever
    t = np.linspace(0.0, 2.0, 5)
    s = _schedule(t, np.full(5, 0.5), np.zeros(5), np.zeros(5), np.zeros(5))
    run = replay_chunk(SleighParams(), [0.0, 1.0, 0.0, 0.0, 0.0], s, 0, 5, [0.0, 1.0, 2.0])
    assert run.success and run.status == 0
    np.testing.assert_allclose(run.states[3], [0.0, 1 / 3, 2 / 3], rtol=0, atol=1e-14)
    np.testing.assert_allclose(run.states[[0, 2, 4]], 0.0, atol=1e-14)


@pytest.mark.parametrize("params", [SleighParams(), SleighParams(M=55.0, m=17.0, I=9.0)])
def test_is_scipys_dop853_step_for_step_on_smooth_controls(params):
    # one cubic per control (two rows): the right-hand side is analytic, so the two integrations
    # take the same steps and agree to rounding (at most 8e-15 relative under 60 draws of inputs
    # perturbed by 1e-15..1e-11; the bound leaves two orders of magnitude for other CPUs' rounding)
    t = np.array([0.0, 2.5])
    s = _schedule(t, np.array([0.1, -0.3]), np.array([0.4, 0.2]), np.array([0.5, -0.2]), np.array([-0.3, 0.6]))
    y0 = [0.3, 1.1, 0.2, -0.5, 0.4]
    tt = np.linspace(0.0, 2.5, 101)
    run = replay_chunk(params, y0, s, 0, 2, tt)
    ref = simulate(params, y0, s.scalar_interpolant(0, 2), (0.0, 2.5), rtol=1e-13, atol=1e-14)
    assert run.success and ref.success
    assert run.nsteps == ref.t.size - 1
    scale = np.max(np.abs(ref.state), axis=1, keepdims=True)
    assert np.max(np.abs(run.states - ref(tt)) / scale) < 1e-12


def test_matches_solve_ivp_on_a_swinging_mass():
    # Hermite controls have a kink in their second derivative at every knot; there the error
    # estimate is near the threshold, the two integrations part ways by rounding and agree to
    # their own accuracy, not to rounding: under 25 draws of the initial state and the controls
    # perturbed by 1e-15..1e-11 they differ by 4e-11..8e-10 (relative) and their step counts by
    # up to 5.5%. Agreement to 1e-8 with step counts within 15% is what is robust, and still
    # telling: the replay at rtol 1e-12 instead of 1e-13 takes 26% fewer steps, at 1e-10 it
    # differs by 6e-8.
    s = _wiggle()
    y0 = [0.3, 1.1, 0.2, -0.5, 0.4]
    tt = np.linspace(0.0, s.t[-1], 257)
    run = replay_chunk(SleighParams(), y0, s, 0, s.t.size, tt)
    ref = simulate(SleighParams(), y0, s.scalar_interpolant(0, s.t.size), (0.0, float(s.t[-1])), rtol=1e-13, atol=1e-14)
    scale = np.max(np.abs(ref.state), axis=1, keepdims=True)
    assert np.max(np.abs(run.states - ref(tt)) / scale) < 1e-8
    assert abs(run.nsteps - (ref.t.size - 1)) <= 0.15 * run.nsteps


def test_matches_solve_ivp_on_the_double_flowers_controls(flower):
    tr, schedule = flower
    i0, i1 = schedule.chunks()[0]
    a, b, ad, bd = schedule.a[i0], schedule.b[i0], schedule.adot[i0], schedule.bdot[i0]
    p1, p2 = momenta(tr.params, 0.0, 0.0, a, b, ad, bd)
    y0 = [p1, p2, 0.3, 0.0, 0.0]
    t0, t1 = float(schedule.t[i0]), float(schedule.t[i1 - 1])
    tt = np.linspace(t0, t1, 300)
    run = replay_chunk(tr.params, y0, schedule, i0, i1, tt)
    ref = simulate(tr.params, y0, schedule.scalar_interpolant(i0, i1), (t0, t1), rtol=1e-13, atol=1e-14)
    scale = np.max(np.abs(ref.state), axis=1, keepdims=True)
    # 712 knots, each a kink of the second derivative: agreement to the integrations' accuracy,
    # which is not rounding (7e-11..1.7e-10 along the chunk, 8e-12..7e-11 at its end, under the
    # controls perturbed by 1e-15..1e-12; the swinging mass above reaches 8e-10)
    assert np.max(np.abs(run.states - ref(tt)) / scale) < 1e-8
    np.testing.assert_allclose(run.y_end, ref.state[:, -1], rtol=0, atol=1e-8 * float(scale.max()))


def test_verify_engines_agree(flower):
    tr, schedule = flower
    fast = verify_module.replay(tr, schedule)
    slow = verify_module.replay(tr, schedule, engine="scipy")
    np.testing.assert_array_equal(fast.t, slow.t)
    # the compiled replay reports the controls it integrated with: the schedule's own interpolant
    np.testing.assert_array_equal(fast.controls, slow.controls)
    # the open-loop replay carries rounding differences through 32 sections: still far below the tolerance
    # (2e-10..1.2e-9 x size under the controls perturbed by 1e-15..1e-12)
    assert np.max(np.abs(fast.state[3:] - slow.state[3:])) < 1e-7 * tr.figure.size()
    with pytest.raises(ValueError, match="engine"):
        verify_module.replay(tr, schedule, engine="rk4")


def test_exhausted_budget_is_reported_with_nan_beyond():
    s = _wiggle()
    tt = np.linspace(0.0, s.t[-1], 50)
    run = replay_chunk(SleighParams(), [0.3, 1.1, 0.2, -0.5, 0.4], s, 0, s.t.size, tt, max_nfev=200)
    assert not run.success and run.status == -1
    assert "budget" in run.message and "t = " in run.message
    assert 0.0 < run.t_end < s.t[-1]
    reached = tt <= run.t_end
    assert np.all(np.isfinite(run.states[:, reached])) and np.all(np.isnan(run.states[:, ~reached]))


def test_bad_arguments_are_rejected():
    s = _wiggle()
    y0 = [0.0, 1.0, 0.0, 0.0, 0.0]
    with pytest.raises(ValueError, match="state0"):
        replay_chunk(SleighParams(), [0.0, 1.0], s, 0, s.t.size, [0.0])
    with pytest.raises(ValueError, match="within the chunk"):
        replay_chunk(SleighParams(), y0, s, 0, s.t.size, [0.0, 99.0])
    with pytest.raises(ValueError, match="non-decreasing"):
        replay_chunk(SleighParams(), y0, s, 0, s.t.size, [1.0, 0.5])


def test_reused_sections_are_sampled_as_if_alone(flower):
    # trace_figure solves each shape once; the reused sections share its phases and are sampled
    # once. Copies with phases of their own are sampled afresh: the schedule must not change.
    from dataclasses import replace

    tr, schedule = flower
    fresh = replace(tr, sections=tuple(replace(s, phases=tuple(list(s.phases))) for s in tr.sections))
    again, states = verify_module.schedule_from_trace(fresh)
    _, states0 = verify_module.schedule_from_trace(tr)
    for k in ("t", "a", "b", "adot", "bdot", "section", "piece"):
        np.testing.assert_array_equal(getattr(again, k), getattr(schedule, k))
    for k in states:
        np.testing.assert_array_equal(states[k], states0[k])


def test_a_zero_trial_step_gives_a_zero_first_step_not_an_error():
    # a derivative beyond the range of its tolerance makes scipy's trial step 0 and d2 = inf (numpy's
    # division); compiled, the division raised ZeroDivisionError
    from skatetrace.dynamics import dop853

    f0, f1, scale = np.array([1.0, 2.0]), np.array([1.5, 2.0]), np.array([1e-9, 1e-9])
    assert dop853.initial_step(0.0, 1e300, scale, f0, f1, 1.0) == 0.0
    assert 0.0 < dop853.initial_step(1e-3, 1.0, scale, f0, f1, 1.0) <= 1.0
