"""A manoeuvre leg's motion in one compiled call: the same bits as the vectorised formulas it replaces."""

import dataclasses

import numpy as np
import pytest

import skatetrace as st
from skatetrace.tracing.leg_motion import leg_motion
from skatetrace.tracing.maneuver import constrained_rates


def _formulas(params, man, leg, t):
    """The motion as the vectorised formulas give it: the dense output, then ``constrained_rates``."""
    y = leg.sol(t)
    adot, bdot, _ = constrained_rates(params, leg.kappa_at(y[4]), y[0], y[1], y[2], y[3], man.control(t))
    return y, adot, bdot


def _legs(trace):
    for sec in trace.sections:
        for ph in sec.phases:
            if ph.maneuver is not None:
                for leg in ph.maneuver.legs:
                    yield ph.maneuver, leg


def _same_bits(got, want):
    for g, w in zip(got, want):
        g, w = np.asarray(g), np.asarray(w)
        np.testing.assert_array_equal(g, w)
        np.testing.assert_array_equal(np.signbit(g), np.signbit(w))  # -0.0 stays -0.0


@pytest.fixture(scope="module")
def traced():
    """Ramps (a launch-glide-stop trace: arcs, lines, a spiral's cubic curvature, mirrored launches) and
    affine controls (a plan's exact finish)."""
    fig = st.figure_from_dict({"curves": [{"pieces": [
        {"type": "arc", "radius": 1.3, "sweep_deg": 140}, {"type": "line", "length": 0.8},
        {"type": "spiral", "curvature": [0.4, 0.8], "length": 1.5}],
        "joins": [{"type": "smooth"}, {"type": "cusp", "pivot_deg": 35}]}]})
    arc = st.figure_from_dict({"curves": [{"pieces": [{"type": "arc", "radius": 1.2, "sweep_deg": 198}]}]})
    return st.trace_figure(fig), st.plan_figure(arc, options=st.TraceOptions(reach=1.0))


def test_the_compiled_motion_is_the_formulas_bit_for_bit(traced):
    seen = set()
    for trace in traced:
        assert trace.success, trace.message
        for man, leg in _legs(trace):
            seen.add(man.basis)
            lo, hi = sorted((leg.t0, leg.t1))
            # inside the leg, at its ends, and a little past them (extrapolated from the nearest step)
            t = np.concatenate([np.linspace(lo, hi, 41), [lo - 1e-3 * (hi - lo), hi + 1e-3 * (hi - lo)]])
            _same_bits(leg_motion(trace.params, man, leg, t), _formulas(trace.params, man, leg, t))
    assert seen == {"ramp", "affine"}


def test_other_controls_take_the_formulas(traced):
    trace = traced[0]
    man, leg = next(_legs(trace))
    sines = dataclasses.replace(man, basis="sines", params=(0.3, -0.2))
    t = np.linspace(min(leg.t0, leg.t1), max(leg.t0, leg.t1), 9)
    _same_bits(leg_motion(trace.params, sines, leg, t), _formulas(trace.params, sines, leg, t))
