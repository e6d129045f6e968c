"""The bounded-reach planner: its symbolic model, the exact finish, the reach bound and the replay."""

import math

import numpy as np
import pytest

import skatetrace as st
from skatetrace.dynamics.integrator import _rhs
from skatetrace.figures.figure import figure_from_dict
from skatetrace.planning.planner import plan_figure
from skatetrace.planning.symbolic import sleigh_functions


@pytest.mark.parametrize("kappa", [0.0, -0.39, 7.1])
def test_symbolic_model_is_the_compiled_one(kappa):
    M, m, I = 0.658, 0.342, 0.0074
    fn = sleigh_functions(M, m, I)
    rng = np.random.default_rng(3)
    for _ in range(5):
        x = rng.normal(size=6) * 0.3
        out = np.empty(5)
        assert _rhs.py_func(M, m, I, kappa, 0.0, x[5], 0.0, x[:5].copy(), out)
        got = np.array(fn["f"](x, 0.7, [kappa, 0.0, 0.0, 0.0], 0.0)).ravel()
        np.testing.assert_allclose(got[:5], out, rtol=1e-12, atol=1e-12)
        assert got[5] == 0.7


def test_options_check_the_planner_fields():
    with pytest.raises(ValueError, match="reach"):
        st.TraceOptions(reach=-1.0)
    with pytest.raises(ValueError, match="max_accel"):
        st.TraceOptions(reach=1.0, objective="time")
    with pytest.raises(ValueError, match="objective"):
        st.TraceOptions(reach=1.0, objective="fast")


@pytest.fixture(scope="module")
def arc():
    fig = figure_from_dict({"schema": "skatetrace.figure/1",
                            "curves": [{"pieces": [{"type": "arc", "radius": 1.2, "sweep_deg": 198}]}]})
    return fig, plan_figure(fig, options=st.TraceOptions(reach=1.0))


def test_a_planned_arc_is_exact_and_within_reach(arc):
    _fig, trace = arc
    sec = trace.sections[0]
    assert trace.success, trace.message
    assert max(sec.residuals.values()) <= 1e-10
    assert sec.metrics["reach"] <= 1.0
    # between the certified samples too: a finer look never finds the mass farther out
    t = np.linspace(0.0, sec.duration, 200_001)
    v = sec.evaluate(t, geometry=False)
    assert np.max(np.hypot(v["a"], v["b"])) <= sec.metrics["reach"]
    # rests at both ends
    assert abs(v["xi2"][0]) <= 1e-10 and abs(v["xi2"][-1]) <= 1e-10


def test_a_planned_arc_is_verified_by_the_replay(arc):
    fig, _trace = arc
    result = st.trace_and_verify(fig, options=st.TraceOptions(reach=1.0))
    assert result.success, result.message
