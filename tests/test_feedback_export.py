"""The tracking law as data (feedback.json), its thinned gains, and what a controller sees of a sleigh that
is not its model."""

import json

import numpy as np
import pytest

import skatetrace as st
from skatetrace.dynamics.model import body_velocities, momenta
from skatetrace.feedback import Plant, design, robust_gains
from skatetrace.feedback.closed_loop import _Section
from skatetrace.feedback.export import FEEDBACK_SCHEMA, laws_from_dict, laws_to_dict
from skatetrace.feedback.reference import section_reference

PARAMS = st.SleighParams()


@pytest.fixture(scope="module")
def traced():
    fig = st.pattern("s-bend")
    trace = st.trace_figure(fig, PARAMS)
    assert trace.success
    refs = [section_reference(s, PARAMS, points=4000) for s in trace.sections]
    laws = [design(r, PARAMS, robust_gains(fig.size())) for r in refs]
    return fig, refs, laws


def test_thinned_gains_stay_within_their_bound_and_keep_every_jump(traced):
    _, refs, laws = traced
    for law in laws:
        thin = law.thinned(rel_tol=1e-3, start=32)
        assert thin.t.size < law.t.size
        # at every row of the full law, the thinned interpolant is within the bound of the largest gain
        got = thin.gain(law.t, law.t.size)
        err = np.max(np.abs(got - law.K))
        assert err <= 1e-3 * np.max(np.abs(law.K)) * (1 + 1e-9)
        jumps = law.t[1:][np.diff(law.t) == 0.0]
        assert np.all(np.isin(jumps, thin.t))
        assert thin.t[0] == law.t[0] and thin.t[-1] == law.t[-1]
        # a looser bound keeps fewer times
        assert law.thinned(rel_tol=1e-2, start=32).t.size <= thin.t.size


def test_a_law_that_is_already_small_is_kept(traced):
    law = traced[2][0]
    assert law.thinned(start=law.t.size) is law


def test_feedback_json_round_trips_to_the_bit(traced):
    fig, refs, laws = traced
    thin = [law.thinned() for law in laws]
    data = json.loads(json.dumps(laws_to_dict(thin, PARAMS, robust_gains(fig.size()), [0.0])))
    assert data["schema"] == FEEDBACK_SCHEMA and data["state"] == ["p1", "p2", "theta", "x", "y", "a", "b"]
    assert data["gains"]["rate_weight"] == 3000.0 and data["model"] == PARAMS.to_dict()
    back = laws_from_dict(data, refs, PARAMS)
    for got, want in zip(back, thin):
        assert np.array_equal(got.t, want.t) and np.array_equal(got.K, want.K) and got.params == PARAMS
    z, _ = refs[0].state_at(np.linspace(0, refs[0].duration, 7))
    z = z + 1e-3
    for tau in (0.0, 0.3 * refs[0].duration):
        assert np.array_equal(np.vstack(back[0].rates(tau, z)), np.vstack(thin[0].rates(tau, z)))


def test_feedback_json_that_is_not_this_law_is_refused(traced):
    fig, refs, laws = traced
    data = laws_to_dict(laws, PARAMS, robust_gains(fig.size()), [0.0])
    with pytest.raises(ValueError, match="expected schema 'skatetrace.feedback/1'"):
        laws_from_dict({**data, "schema": "skatetrace.robustness/1"}, refs, PARAMS)
    with pytest.raises(ValueError, match="designed for the model"):
        laws_from_dict(data, refs, st.SleighParams(M=2.1))
    with pytest.raises(ValueError, match="holds 1 sections, the figure has 2"):
        laws_from_dict(data, refs + refs, PARAMS)
    bad = json.loads(json.dumps(data))
    bad["sections"][0]["t"][-1] *= 0.5
    with pytest.raises(ValueError, match="section 0: its times must rise from 0 to the section's duration"):
        laws_from_dict(bad, refs, PARAMS)
    bad = json.loads(json.dumps(data))
    bad["sections"][0]["K"] = bad["sections"][0]["K"][:-1]
    with pytest.raises(ValueError, match=r"section 0: .* gains of shape"):
        laws_from_dict(bad, refs, PARAMS)


def _seen(law, plant, z, rates):
    sec = _Section(law.reference, plant, law, 0.01, np.zeros((7, 2, z.shape[1])))
    sec.last = rates
    return sec.sense(z)


def test_the_controller_sees_the_momenta_its_model_gives_to_the_motion(traced):
    """A sleigh 5 % heavier moving exactly as the reference moves (same velocities, same mass motion) has
    other momenta; the controller, which measures motion, sees the reference's own."""
    _, refs, laws = traced
    ref, law = refs[0], laws[0]
    zr, ur = ref.state_at(np.linspace(0.05, 0.95, 9) * ref.duration)
    xi1, xi2, _ = body_velocities(PARAMS.M, PARAMS.m, PARAMS.I, zr[0], zr[1], zr[5], zr[6], ur[0], ur[1])
    heavier = st.SleighParams(M=PARAMS.M, m=1.05 * PARAMS.m, I=PARAMS.I)
    p1, p2 = momenta(heavier, xi1, xi2, zr[5], zr[6], ur[0], ur[1])
    z = zr.copy()
    z[0], z[1] = p1, p2
    scale = np.max(np.abs(zr[:2]))
    assert np.max(np.abs(z[:2] - zr[:2])) > 1e-3 * scale  # the true momenta are not the reference's
    plant = Plant(M=np.full(9, heavier.M), m=np.full(9, heavier.m), I=np.full(9, heavier.I),
                  dx=np.zeros(9), dy=np.zeros(9), dtheta=np.zeros(9))
    seen = _seen(law, plant, z, (ur[0], ur[1]))
    assert np.max(np.abs(seen[:2] - zr[:2])) <= 1e-12 * scale
    assert np.array_equal(seen[2:], z[2:])
    # the sleigh that is the model is seen as it is
    nominal = Plant.nominal(PARAMS, 9)
    assert np.max(np.abs(_seen(law, nominal, zr, (ur[0], ur[1])) - zr)) <= 1e-12 * np.max(np.abs(zr))
