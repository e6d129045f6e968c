import math

import numpy as np
import pytest

import skatetrace as st

from skatetrace import SleighParams, pattern, trace_figure
from skatetrace.dynamics.controls import ControlSchedule
from skatetrace.dynamics.model import mass_energy, skate_energy, velocities
from skatetrace.dynamics.simulate import simulate
from skatetrace.verification.verify import schedule_from_trace

P = SleighParams(M=2.3, m=1.7, I=0.9)


def _wiggle(t):
    return (0.5 + 0.3 * math.sin(t), 0.2 * math.cos(1.3 * t), 0.3 * math.cos(t), -0.26 * math.sin(1.3 * t))


def test_locked_mass_conserves_energy():
    tr = simulate(P, [0.3, 1.0, 0.2, 0.0, 0.0], lambda t: (0.4, -0.3, 0.0, 0.0), (0.0, 10.0))
    assert tr.success
    t = np.linspace(0, 10, 500)
    s = tr(t)
    xi1, xi2, _ = velocities(P, s[0], s[1], 0.4, -0.3, 0.0, 0.0)
    e = skate_energy(P, xi1, xi2) + mass_energy(P, xi1, xi2, 0.4, -0.3, 0.0, 0.0)
    assert np.ptp(e) < 1e-10 * e[0]
    assert np.ptp(xi1) > 1e-3  # the motion is not trivially steady


def test_sampled_schedule_reproduces_callable_controls():
    t = np.linspace(0.0, 5.0, 2001)
    a, b, ad, bd = np.array([_wiggle(x) for x in t]).T
    sched = ControlSchedule(t=t, a=a, b=b, adot=ad, bdot=bd, section=np.zeros(t.size, int), piece=np.zeros(t.size, int))
    y0 = [0.2, 0.5, 0.0, 0.0, 0.0]
    exact = simulate(P, y0, _wiggle, (0.0, 5.0))
    sampled = simulate(P, y0, sched)
    assert exact.success and sampled.success
    tt = np.linspace(0, 5, 50)
    np.testing.assert_allclose(sampled(tt), exact(tt), atol=1e-9)


def test_schedule_jumps_restart_the_integration():
    t = np.array([0.0, 0.5, 1.0, 1.0, 1.5, 2.0])
    z = np.zeros(6)
    bd = np.array([0.0, 0.0, 0.0, 1.0, 1.0, 1.0])
    b = np.array([0.0, 0.0, 0.0, 0.0, 0.5, 1.0])
    sched = ControlSchedule(t=t, a=z + 0.5, b=b, adot=z, bdot=bd, section=z.astype(int), piece=z.astype(int))
    assert sched.chunks() == [(0, 3), (3, 6)]
    tr = simulate(P, [0.0, 1.0, 0.0, 0.0, 0.0], sched)
    assert tr.success and len(tr.pieces) == 2


def test_bad_inputs_are_rejected():
    with pytest.raises(ValueError, match="state0"):
        simulate(P, [0, 1, 2], _wiggle, (0, 1))
    with pytest.raises(ValueError, match="t_span"):
        simulate(P, [0, 1, 0, 0, 0], _wiggle)
    with pytest.raises(ValueError, match="t_span"):
        simulate(P, [0, 1, 0, 0, 0], _wiggle, (1.0, 1.0))


def test_breakdown_is_reported_not_raised():
    def blowup(t):
        return (1.0 / (1.0 - t), 0.0, 1.0 / (1.0 - t) ** 2, 0.0)

    tr = simulate(P, [0.0, 1.0, 0.0, 0.0, 0.0], blowup, (0.0, 2.0), max_nfev=20_000)
    assert not tr.success and "failed" in tr.message


def test_written_schedule_meets_the_hermite_tolerance():
    """controls.csv promise: Hermite interpolation of (a, b) with their rates reproduces the controls."""
    trace = trace_figure(pattern("s-bend"))
    sched, _ = schedule_from_trace(trace)
    sec = trace.sections[0]
    worst_value = worst_rate = 0.0
    for i0, i1 in sched.chunks():
        f = sched.interpolant(i0, i1)
        mid = 0.5 * (sched.t[i0:i1 - 1] + sched.t[i0 + 1:i1])
        a, b, ad, bd = f(mid)
        v = sec.evaluate(mid)
        worst_value = max(worst_value, np.max(np.abs(a - v["a"])), np.max(np.abs(b - v["b"])))
        worst_rate = max(worst_rate, np.max(np.abs(ad - v["adot"])), np.max(np.abs(bd - v["bdot"])))
    assert worst_value <= 1e-9
    assert worst_rate <= 1e-7


def test_a_controller_that_ignores_the_state_is_the_open_loop():
    """State feedback that returns the rates of a known mass motion moves the sleigh exactly as
    that motion given as controls does (the mass integrated from its rates)."""
    p = st.SleighParams()
    a0, b0, ra, rb = 0.3, -0.2, 0.1, 0.05
    open_loop = st.simulate(p, [0.2, 1.0, 0.0, 0.0, 0.0],
                            lambda t: (a0 + ra * t, b0 + rb * t, ra, rb), (0.0, 2.0))
    feedback = st.simulate(p, [0.2, 1.0, 0.0, 0.0, 0.0, a0, b0], st.Controller(lambda t, z: (ra, rb)), (0.0, 2.0))
    assert open_loop.success and feedback.success
    assert feedback.state.shape[0] == 7
    np.testing.assert_allclose(feedback(2.0)[:5, 0], open_loop(2.0)[:, 0], rtol=0, atol=1e-9)
    np.testing.assert_allclose(feedback(2.0)[5:, 0], [a0 + 2 * ra, b0 + 2 * rb], rtol=0, atol=1e-12)


def test_a_controller_needs_the_mass_in_the_state():
    with pytest.raises(ValueError, match="7 finite numbers"):
        st.simulate(st.SleighParams(), [0.0, 1.0, 0.0, 0.0, 0.0], st.Controller(lambda t, z: (0.0, 0.0)), (0.0, 1.0))
    with pytest.raises(ValueError, match="t_span is required"):
        st.simulate(st.SleighParams(), [0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0], st.Controller(lambda t, z: (0.0, 0.0)))
