"""The compiled closed loop (skatetrace.feedback.law_replay) against the law in numpy and scipy's solve_ivp."""

import dataclasses

import numpy as np
import pytest

import skatetrace as st
from skatetrace.feedback import default_gains, design
from skatetrace.feedback.closed_loop import replay_law
from skatetrace.feedback.law_replay import _Law, _rhs, law_arrays
from skatetrace.feedback.reference import rhs, section_reference
from skatetrace.figures.figure import figure_from_dict
from skatetrace.planning.planner import plan_figure


@pytest.fixture(scope="module")
def planned_arc():
    """A planned section (many rate jumps), its reference, its law and the times verification reports."""
    fig = figure_from_dict({"schema": "skatetrace.figure/1",
                            "curves": [{"pieces": [{"type": "arc", "radius": 1.2, "sweep_deg": 198}]}]})
    trace = plan_figure(fig, options=st.TraceOptions(reach=1.0))
    assert trace.success, trace.message
    params = trace.params
    ref = section_reference(trace.sections[0], params)
    law = design(ref, params, default_gains(fig.size()))
    assert law.success, law.message
    assert len(ref.spans()) > 10  # the planner's pieces: the rates jump between them
    t = np.linspace(0.0, ref.duration, 400)
    return params, ref, law, ref.state_at(0.0)[0][:, 0], t


def _jumping(ref, law):
    """``ref`` and ``law`` with the rates made to jump at every repeated time of the reference (the
    planner's rates are continuous there): a tenth of the fastest rate added to the slopes after it."""
    zdot = ref.zdot.copy()
    right = np.flatnonzero(np.diff(ref.grid) == 0.0) + 1
    zdot[5:7, right] += 0.1 * np.max(np.abs(ref.zdot[5:7]))
    jumping = dataclasses.replace(ref, zdot=zdot)
    return jumping, dataclasses.replace(law, reference=jumping)


@pytest.mark.parametrize("jumps", [False, True], ids=["planned", "jumping"])
def test_the_compiled_right_hand_side_is_the_law_in_numpy(planned_arc, jumps):
    params, ref, law, _, _ = planned_arc
    if jumps:
        ref, law = _jumping(ref, law)
    g = ref.grid
    jumps = g[1:][np.diff(g) == 0.0]
    rng = np.random.default_rng(3)
    # inside, at every jump (read from the right), at the ends and beyond them (clamped), in random order
    # so that the walk to the interval goes both ways
    t = np.concatenate([rng.uniform(-0.1, 1.1, 300) * ref.duration, jumps, g[:5], g[-5:], [0.0, ref.duration]])
    t = rng.permutation(t)
    zr, _ = ref.state_at(np.clip(t, 0.0, ref.duration))
    # states off the reference, the heading a turn or more away (the law wraps its error)
    scale = np.max(np.abs(ref.z), axis=1, keepdims=True)
    z = zr + 1e-3 * scale * rng.standard_normal(zr.shape)
    z[2] += 2 * np.pi * rng.integers(-2, 3, t.size)
    grid, zz, zdot, lt, K = law_arrays(ref, law)
    data = _Law(params.M, params.m, params.I, grid, zz, zdot, lt, K, np.zeros(2, dtype=np.int64))
    got = np.empty_like(z)
    for j in range(t.size):
        _rhs(data, t[j], np.ascontiguousarray(z[:, j]), got[:, j])
    want = np.hstack([rhs(params, z[:, j:j + 1], *law.rates(t[j], z[:, j:j + 1])) for j in range(t.size)])
    dscale = np.max(np.abs(want), axis=1, keepdims=True)
    assert np.all(np.abs(got - want) <= 1e-10 * dscale)


def test_the_compiled_closed_loop_is_scipys(planned_arc):
    # the same DOP853 steps at rtol 1e-12: the two agree far below any physical effect and far above
    # the rounding in which they differ
    params, ref, law, z0, t = planned_arc
    states, rates, correction, ok = replay_law(ref, law, params, z0, t)
    s_states, s_rates, s_correction, s_ok = replay_law(ref, law, params, z0, t, engine="scipy")
    assert ok and s_ok
    scale = np.max(np.abs(ref.z), axis=1, keepdims=True)
    assert np.all(np.abs(states - s_states) <= 1e-8 * scale)
    rate_scale = np.max(np.abs(ref.zdot[5:7]))
    assert np.all(np.abs(rates - s_rates) <= 1e-8 * rate_scale)
    assert abs(correction - s_correction) <= 1e-8
    # and the closed loop holds the reference: the law hardly corrects
    assert np.all(np.abs(states - ref.state_at(t)[0]) <= 1e-8 * scale)
    assert correction <= 1e-6


@pytest.mark.parametrize("engine", ["compiled", "scipy"])
def test_an_exhausted_budget_is_a_failure_with_nan_states_after_it(planned_arc, engine):
    params, ref, law, z0, t = planned_arc
    states, rates, _, ok = replay_law(ref, law, params, z0, t, max_nfev=1000, engine=engine)
    assert not ok
    finite = np.all(np.isfinite(states), axis=0)
    assert not finite[-1]
    stop = int(np.argmin(finite))  # the first time not reached: none after it is
    assert not np.any(finite[stop:])
    assert np.all(np.isnan(rates[:, stop:]))
    # what was reached is the closed loop's own motion
    full, _, _, _ = replay_law(ref, law, params, z0, t, engine=engine)
    scale = np.max(np.abs(ref.z), axis=1, keepdims=True)
    assert np.all(np.abs(states[:, :stop] - full[:, :stop]) <= 1e-8 * scale)


def test_an_unknown_engine_is_refused(planned_arc):
    params, ref, law, z0, t = planned_arc
    with pytest.raises(ValueError, match="engine"):
        replay_law(ref, law, params, z0, t, engine="fortran")


def test_a_section_along_a_level_line_replays_under_its_law():
    """The heading of a line drawn level is zero all along: held to its own scale, its tolerance was a
    denormal (1e-314), DOP853's first step came out zero and the compiled replay raised
    ZeroDivisionError (simple-icons' orange logo crashed the command line's verification)."""
    from skatetrace.figures.patterns import pattern

    fig = pattern("line")
    trace = plan_figure(fig, options=st.TraceOptions(reach=1.0))
    assert trace.success, trace.message
    ref = section_reference(trace.sections[0], trace.params)
    assert np.max(np.abs(ref.z[2])) == 0.0 and np.max(np.abs(ref.zdot[2])) > 0.0  # a heading rate of round-off
    # the heading's interpolation error measured against a radian, not 1e-300: the reference is done at
    # its first sizes (it grew to its largest, 1,280,070 rows, and the orange logo's verification to 1.9 GB)
    assert ref.grid.size < 100_000
    law = design(ref, trace.params, default_gains(fig.size()))
    t = np.linspace(0.0, ref.duration, 50)
    states, _rates, correction, ok = replay_law(ref, law, trace.params, ref.state_at(0.0)[0][:, 0], t)
    assert ok and np.all(np.isfinite(states))
    assert correction < 1e-6  # on the trace the law barely corrects
    assert np.max(np.hypot(*(states[3:5] - ref.state_at(t)[0][3:5]))) < 1e-9 * fig.size()


def test_a_variable_at_zero_takes_the_scale_of_its_kind():
    from skatetrace.feedback.reference import variable_scales

    z = np.array([[2.0, -3.0], [90.0, 80.0], [0.0, 0.0], [0.0, 0.0], [-1.5, 4.0], [0.3, -0.2], [1e-12, 0.0]])
    np.testing.assert_array_equal(variable_scales(z), [3.0, 90.0, 1.0, 4.0, 4.0, 0.3, 0.3])
    z[2], z[3], z[6] = [0.0, 1e-3], [1e-8, 0.0], [0.0, 1e-6]
    np.testing.assert_array_equal(variable_scales(z), [3.0, 90.0, 1e-3, 1e-8, 4.0, 0.3, 1e-6])  # their own
    np.testing.assert_array_equal(variable_scales(np.zeros((7, 3))), [1e-300, 1e-300, 1.0] + [1e-300] * 4)
