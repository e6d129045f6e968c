"""The second verdict: could a skater make the controls?  (skatetrace.verification.feasibility)"""

from __future__ import annotations

import json
import math
from types import SimpleNamespace

import numpy as np
import pytest

import skatetrace as st
from skatetrace.cli import main
from skatetrace.dynamics.controls import ControlSchedule
from skatetrace.dynamics.presets import MOVING_FRACTION
from skatetrace.verification.feasibility import PAPER_FIGURE_SIZE, HumanLimits, assess_feasibility, exported_peaks
from skatetrace.outputs.results import read_controls


def _strict(text: str):
    """json.loads that refuses NaN and infinities, as every other JSON reader does."""
    def refuse(token):
        raise ValueError(f"non-standard JSON constant {token}")
    return json.loads(text, parse_constant=refuse)


@pytest.fixture(scope="module")
def flower():
    return st.trace_and_verify(st.pattern("double-flower"))


@pytest.fixture(scope="module")
def loop():
    fig = st.school_figure("loop", height=1.7)
    params, options = st.skater_params(height=1.7), st.TraceOptions(speed=2.0)
    raw = st.trace_figure(fig, params, options)
    done = st.trace_and_verify(fig, params, options, limits=HumanLimits.for_skater(1.7))
    return raw, done


# --------------------------------------------------------------------------------------------------
# limits
# --------------------------------------------------------------------------------------------------
def test_skater_limits_follow_height_and_weight():
    lim = HumanLimits.for_skater(1.7, 60.0)
    assert lim.unit == "m" and lim.reach == pytest.approx(0.85) and lim.mass_speed == 7.0
    # one body weight on the moving mass (34.2 % of the body): g / 0.342
    assert lim.mass_acceleration == pytest.approx(9.81 / MOVING_FRACTION)
    assert lim.cusp_jump == pytest.approx(0.085) and lim.singular_distance == pytest.approx(0.0085)
    tall = HumanLimits.for_skater(2.0, 90.0, moving_mass=30.0)
    assert tall.reach == pytest.approx(1.0) and tall.mass_acceleration == pytest.approx(90 * 9.81 / 30)
    assert "2 m tall" in tall.assumptions and "90 kg" in tall.assumptions


def test_model_limits_are_the_skater_limits_at_the_papers_scale():
    lim, si = HumanLimits.for_model(), HumanLimits.for_skater()
    height = PAPER_FIGURE_SIZE / 6
    metres, v = 1.7 / height, 2.0
    assert lim.unit == "model"
    assert lim.reach * metres == pytest.approx(si.reach)
    assert lim.cusp_jump * metres == pytest.approx(si.cusp_jump)
    assert lim.mass_speed * v == pytest.approx(si.mass_speed)
    assert lim.mass_acceleration * v * v / metres == pytest.approx(si.mass_acceleration)
    text = HumanLimits.for_model(params=st.SleighParams()).assumptions
    assert "double flower" in text and "radius of gyration" in text


def test_the_papers_scale_is_the_double_flowers_size(flower):
    assert flower.report.figure_size == pytest.approx(PAPER_FIGURE_SIZE, abs=0.005)


@pytest.mark.parametrize("kwargs, match", [
    ({"height": 0}, "height must be a positive"),
    ({"height": float("nan")}, "height must be a positive"),
    ({"height": -1.7}, "height must be a positive"),
    ({"body_mass": "60"}, "body_mass must be a positive"),
    ({"moving_mass": math.inf}, "moving_mass must be a positive"),
])
def test_bad_skater_limits_are_refused(kwargs, match):
    with pytest.raises(ValueError, match=match):
        HumanLimits.for_skater(**kwargs)


def test_bad_limits_are_refused():
    with pytest.raises(ValueError, match="reach must be a positive"):
        HumanLimits(reach=-1, mass_speed=1, mass_acceleration=1, cusp_jump=1, singular_distance=1)
    with pytest.raises(ValueError, match="unit must be 'm' or 'model'"):
        HumanLimits(reach=1, mass_speed=1, mass_acceleration=1, cusp_jump=1, singular_distance=1, unit="ft")


# --------------------------------------------------------------------------------------------------
# the measurements, on controls made by hand
# --------------------------------------------------------------------------------------------------
def _fake(t, a, b, adot, bdot, x, y, theta, xi1, xi2, section, *, curves=(0,), speed=1.0, singular=(math.inf,)):
    n = len(t)
    schedule = ControlSchedule(t=np.asarray(t, float), a=np.asarray(a, float), b=np.asarray(b, float),
                               adot=np.asarray(adot, float), bdot=np.asarray(bdot, float),
                               section=np.asarray(section, int), piece=np.zeros(n, int))
    states = {k: np.asarray(v, float) for k, v in
              dict(x=x, y=y, theta=theta, xi1=xi1, xi2=xi2, p1=np.zeros(n), p2=np.zeros(n)).items()}
    sections = [SimpleNamespace(curve_index=c, metrics={"min_singular_distance": s}) for c, s in zip(curves, singular)]
    trace = SimpleNamespace(params=st.SleighParams(), options=SimpleNamespace(speed=speed), sections=sections,
                            start_times=tuple(0.0 for _ in sections))
    return trace, schedule, states


def _limits():
    return HumanLimits(reach=1.0, mass_speed=1.0, mass_acceleration=1.0, cusp_jump=0.1, singular_distance=0.01,
                       unit="m")


def test_a_glide_with_the_mass_held_still_is_feasible():
    t = np.linspace(0, 5, 51)
    z, one = np.zeros_like(t), np.ones_like(t)
    trace, schedule, states = _fake(t, z, 0.3 * one, z, z, t, z, z, z, one, z.astype(int))
    f = assess_feasibility(trace, schedule, states, _limits())
    assert f.feasible and f.success and f.status == "feasible"
    assert f.verdict(True) == "verified · humanly feasible"
    by = {c.name: c for c in f.checks}
    assert by["reach"].value == pytest.approx(0.3) and by["mass_speed"].value == 0.0
    assert by["mass_acceleration"].value == pytest.approx(0.0, abs=1e-12)  # uniform motion on a line
    assert by["blade_speed"].value == pytest.approx(1.0)


def test_a_mass_beyond_reach_moving_in_a_circle_fails_with_its_numbers():
    # The mass goes round the contact point at radius 2 with angular rate 1 while the sleigh stands
    # still: its speed relative to the body is 2, its acceleration on the ice 2 (centripetal).
    t = np.linspace(0, 2 * np.pi, 4001)
    z = np.zeros_like(t)
    trace, schedule, states = _fake(t, 2 * np.cos(t), 2 * np.sin(t), -2 * np.sin(t), 2 * np.cos(t), z, z, z, z, z,
                                    z.astype(int))
    f = assess_feasibility(trace, schedule, states, _limits())
    by = {c.name: c for c in f.checks}
    assert by["reach"].value == pytest.approx(2.0) and not by["reach"].passed
    assert by["mass_speed"].value == pytest.approx(2.0) and not by["mass_speed"].passed
    assert by["mass_acceleration"].value == pytest.approx(2.0, rel=1e-5)
    assert f.info["peak_force_on_mass"] == pytest.approx(2.0 * trace.params.m, rel=1e-5)
    assert not f.feasible and f.message.startswith("not humanly feasible: mass 2 m from the blade (limit 1 m)")
    assert f.verdict(True).startswith("verified · not humanly feasible: mass 2 m from the blade")
    assert [c.name for c in f.failed()][:3] == ["reach", "mass_speed", "mass_acceleration"]


def test_a_jump_of_the_mass_at_a_cusp_is_measured_on_the_ice():
    # Two sections of one curve meet at rest at (1, 0); the blade pivots by 90 degrees and the mass
    # goes from (a, b) = (0, 0.2) to (0, 0.2) in the new frame: on the ice from (1, 0.2) to (0.8, 0).
    t = np.array([0.0, 0.5, 1.0, 1.0, 1.5, 2.0])
    a, b = np.zeros(6), np.full(6, 0.2)
    x = np.array([0.0, 0.5, 1.0, 1.0, 1.0, 1.0])
    y = np.array([0.0, 0.0, 0.0, 0.0, 0.5, 1.0])
    theta = np.array([0, 0, 0, 1, 1, 1]) * np.pi / 2
    xi2 = np.array([0.0, 1, 0, 0, 1, 0])
    sec = np.array([0, 0, 0, 1, 1, 1])
    trace, schedule, states = _fake(t, a, b, np.zeros(6), np.zeros(6), x, y, theta, np.zeros(6), xi2, sec,
                                    curves=(0, 0), singular=(math.inf, math.inf))
    f = assess_feasibility(trace, schedule, states, _limits())
    jump = {c.name: c for c in f.checks}["cusp_jump"]
    assert jump.value == pytest.approx(math.hypot(0.2, 0.2)) and not jump.passed
    assert jump.time == 1.0 and jump.section == 1
    # On two curves the blade itself moves between them: no cusp, nothing measured.
    trace2, schedule2, states2 = _fake(t, a, b, np.zeros(6), np.zeros(6), x, y, theta, np.zeros(6), xi2, sec,
                                       curves=(0, 1), singular=(math.inf, math.inf))
    assert {c.name: c for c in assess_feasibility(trace2, schedule2, states2, _limits()).checks}["cusp_jump"].value == 0


def test_nothing_traced_is_not_assessed():
    e = np.empty(0)
    trace, schedule, states = _fake(e, e, e, e, e, e, e, e, e, e, e.astype(int), curves=(), singular=())
    f = assess_feasibility(trace, schedule, states, _limits())
    assert not f.feasible and f.status == "not assessed"
    assert "feasibility not assessed" in f.verdict(False)
    assert f.checks == ()  # no motion measured: no check can say "ok"
    _strict(json.dumps({k: v for k, v in f.to_dict().items()}, allow_nan=False, default=str))


# --------------------------------------------------------------------------------------------------
# on real traces
# --------------------------------------------------------------------------------------------------
def test_the_mass_velocity_on_the_ice_is_the_rate_of_its_position(flower):
    # PHYSICS.md, Energies: the mass moves on the ice at (xi2 - xi1 b + a', xi1 a + b') in the body
    # frame; differentiating its position numerically along one smooth chunk must agree.
    from skatetrace.verification.feasibility import _mass_on_ice

    sch, stt = flower.schedule, flower.states
    i0, i1 = sch.chunks()[0]
    args = (sch.a, sch.b, stt["theta"], stt["x"], stt["y"], stt["xi1"], stt["xi2"], sch.adot, sch.bdot)
    X, Y, VX, VY = (v[i0:i1] for v in _mass_on_ice(*args))
    t = sch.t[i0:i1]
    scale = np.max(np.hypot(VX, VY))
    assert np.max(np.abs(np.gradient(X, t, edge_order=2) - VX)) < 1e-3 * scale
    assert np.max(np.abs(np.gradient(Y, t, edge_order=2) - VY)) < 1e-3 * scale


def test_the_double_flower_is_verified_but_not_feasible(flower):
    # issue 15's figures: the mass goes 5.0 units from the blade and jumps 7.1 units at a cusp
    f = flower.feasibility
    assert flower.success and not f.feasible and f.limits.unit == "model"
    by = {c.name: c for c in f.checks}
    assert by["reach"].value == pytest.approx(5.0, abs=0.05)
    assert by["cusp_jump"].value == pytest.approx(7.1, abs=0.05)
    assert by["blade_speed"].value == pytest.approx(1.0, abs=1e-6)  # the glide is the fastest
    assert by["blade_speed"].passed and by["singular_approach"].passed
    assert flower.verdict.startswith("verified · not humanly feasible: mass 5 model units from the blade")


def test_peaks_are_those_of_the_exported_rows(loop):
    raw, done = loop
    peaks = exported_peaks(done.schedule, done.states, done.trace.params, len(done.trace.sections))
    for k, (before, after) in enumerate(zip(raw.sections, done.trace.sections)):
        rows = done.schedule.section == k
        for key, col in (("peak_abs_adot", done.schedule.adot), ("peak_abs_bdot", done.schedule.bdot),
                         ("max_abs_a", done.schedule.a), ("max_abs_b", done.schedule.b)):
            assert after.metrics[key] >= before.metrics[key]
            assert after.metrics[key] >= np.max(np.abs(col[rows]))
            assert after.metrics[key] == max(before.metrics[key], peaks[k][key])


def test_a_school_loop_passes_close_to_the_singular_point(loop):
    _, done = loop
    by = {c.name: c for c in done.feasibility.checks}
    assert by["reach"].passed  # loops are small: the mass stays within 0.2 m
    assert not by["singular_approach"].passed and by["singular_approach"].value < 1e-3
    assert not by["mass_acceleration"].passed  # the rates spike there


# --------------------------------------------------------------------------------------------------
# what a user sees
# --------------------------------------------------------------------------------------------------
def test_cli_warns_and_writes_both_verdicts(tmp_path, capsys):
    out = tmp_path / "three"
    assert main(["trace", "school:three", "--height", "1.7", "--reach", "none", "--out", str(out), "--no-plots"]) == 0
    cap = capsys.readouterr()
    assert "skatetrace: warning: verified · not humanly feasible: mass" in cap.err
    assert "m from the blade (limit 0.85 m)" in cap.err
    assert "feasibility: not feasible" in cap.out and "BEYOND" in cap.out
    report = _strict((out / "report.json").read_text())
    feas = report["feasibility"]
    assert report["status"] == "passed" and feas["feasible"] is False
    assert report["verdict"].startswith("verified · not humanly feasible: mass")
    reach = next(c for c in feas["checks"] if c["name"] == "reach")
    rows = read_controls(out / "controls.csv")
    assert reach["value"] == pytest.approx(np.max(np.hypot(rows["a"], rows["b"])), rel=1e-12)
    assert reach["value"] > 10 and reach["limit"] == pytest.approx(0.85)
    html = (out / "viewer.html").read_text()
    assert 'class="badge warn"' in html and "not humanly feasible" in html
    assert "⚠ beyond" in html and "feasible: reach" in html



def test_effort_integrates_the_squared_force_between_jumps():
    from skatetrace.verification.feasibility import _effort

    t = np.concatenate([np.linspace(0.0, 1.0, 101), np.linspace(1.0, 3.0, 201)])  # a jump at t = 1
    acc = np.where(np.arange(t.size) < 101, 3.0, 0.5)
    cut = np.flatnonzero(np.diff(t) <= 0.0) + 1
    # (2 * 3)^2 over one second, (2 * 0.5)^2 over two: the jump itself adds nothing
    assert _effort(2.0, t, acc, cut) == pytest.approx(36.0 + 2.0, rel=1e-12)


def test_rows_apart_by_round_off_are_a_jump_not_an_acceleration():
    # The mass circles at radius 0.3 (acceleration 0.3); at t = 1 its rates jump (a piece's end),
    # sampled on both sides at times 4e-13 apart instead of at one time. The difference quotient
    # across them would read 1e12; the jump is measured as one, the acceleration stays 0.3.
    t = np.concatenate([np.linspace(0.0, 1.0, 401), 1.0 + 4e-13 + np.linspace(0.0, 1.0, 401)])
    w = np.where(t <= 1.0, 1.0, -1.0)  # the sense of rotation reverses at the jump
    a, b = 0.3 * np.cos(w * t), 0.3 * np.sin(w * t)
    adot, bdot = -0.3 * w * np.sin(w * t), 0.3 * w * np.cos(w * t)
    z = np.zeros_like(t)
    trace, schedule, states = _fake(t, a, b, adot, bdot, z, z, z, z, z, z.astype(int))
    f = assess_feasibility(trace, schedule, states, _limits())
    assert {c.name: c for c in f.checks}["mass_acceleration"].value == pytest.approx(0.3, rel=1e-4)
    # the velocity jumps from (-0.3 sin 1, 0.3 cos 1) to (-0.3 sin 1, -0.3 cos 1)
    assert f.info["max_mass_velocity_jump_at_join"] == pytest.approx(0.6 * math.cos(1.0), rel=1e-9)
