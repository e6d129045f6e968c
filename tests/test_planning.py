"""The bounded-reach planner: its symbolic model, the exact finish, the reach bound and the replay."""

import dataclasses
import math
import os
from pathlib import Path

import numpy as np
import pytest

import skatetrace as st
from skatetrace.dynamics.integrator import _rhs
from skatetrace.figures.figure import figure_from_dict
from skatetrace.pipeline import DEFAULT_PLAN_BUDGET, DEFAULT_PLAN_UNKNOWNS, too_large_to_plan
from skatetrace.planning.planner import figure_unknowns as planner_figure_unknowns
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


def test_a_plan_is_sampled_coarsely_first_and_finely_where_its_replay_comes_close_to_a_limit(arc, monkeypatch):
    from skatetrace.verification.verify import VerificationReport, schedule_from_trace

    fig, trace = arc
    coarse, _ = schedule_from_trace(trace, fine=False)
    fine, _ = schedule_from_trace(trace)
    assert 3 * coarse.t.size < fine.t.size
    kept = st.trace_and_verify(fig, options=st.TraceOptions(reach=1.0))
    assert kept.success and kept.report.passed_within(0.5), kept.message
    assert kept.schedule.t.size == coarse.t.size
    # a replay that passes, but by less than half a limit: sampled thirty times more finely, and where
    # that comes close too, a thousand times; each verified again
    middle, _ = schedule_from_trace(trace, fine=30)
    assert coarse.t.size < middle.t.size < fine.t.size
    calls = []

    def passed_within(self, share):
        calls.append(share)
        return len(calls) > misses

    monkeypatch.setattr(VerificationReport, "passed_within", passed_within)
    for misses, rows in ((1, middle.t.size), (2, fine.t.size)):
        calls.clear()
        again = st.trace_and_verify(fig, options=st.TraceOptions(reach=1.0))
        assert again.success and again.schedule.t.size == rows
        assert calls == [0.5, 0.5]  # the coarse and the middle replays were asked, the fine one never


@pytest.mark.parametrize("fine", [0.5, -1, math.inf, math.nan, "fine", None])
def test_a_refinement_below_one_or_not_a_number_is_refused(arc, fine):
    from skatetrace.verification.verify import schedule_from_trace

    with pytest.raises(ValueError, match="fine must be True, False or a number >= 1"):
        schedule_from_trace(arc[1], fine=fine)


def test_passed_within_compares_every_measure_with_its_share_of_the_limit(arc):
    fig, _trace = arc
    report = st.trace_and_verify(fig, options=st.TraceOptions(reach=1.0)).report
    assert report.success
    tol = report.tolerance
    assert dataclasses.replace(report, max_deviation=0.6 * tol).passed_within(0.7)
    assert not dataclasses.replace(report, max_deviation=0.6 * tol).passed_within(0.5)
    sec = dict(report.sections[0], end_speed=0.6 * report.sections[0]["cusp_speed_limit"])
    assert not dataclasses.replace(report, sections=[sec, *report.sections[1:]]).passed_within(0.5)
    assert not dataclasses.replace(report, success=False).passed_within(1.0)


def _cusp_figure(join: dict, second: dict) -> dict:
    return {"schema": "skatetrace.figure/1", "name": "two arcs", "params": {"M": 2, "m": 1, "I": 3},
            "curves": [{"pieces": [{"type": "arc", "radius": 1.2, "sweep_deg": 150}, second], "joins": [join]}]}


#: A reversal (the blade runs back, a three turn's cusp) and a pivot of -40 degrees onto an arc the other way.
CUSPS = {
    "reversal": _cusp_figure({"type": "cusp", "pivot_deg": 0, "reverse": True},
                             {"type": "arc", "radius": 1.2, "sweep_deg": 150}),
    "pivot": _cusp_figure({"type": "cusp", "pivot_deg": -40}, {"type": "arc", "radius": 1.5, "sweep_deg": -120}),
}


@pytest.fixture(scope="module", params=sorted(CUSPS))
def through_a_cusp(request):
    fig = figure_from_dict(CUSPS[request.param])
    return fig, st.trace_and_verify(fig, options=st.TraceOptions(reach=1.0))


@pytest.fixture(scope="module")
def pivot_plan():
    fig = figure_from_dict(CUSPS["pivot"])
    return fig, plan_figure(fig, options=st.TraceOptions(reach=1.0))


def test_the_sections_that_come_close_to_a_limit_are_sampled_again_and_the_others_kept(pivot_plan, monkeypatch):
    import skatetrace.pipeline as pipeline
    from skatetrace.verification.verify import resampled, schedule_from_trace

    fig, trace = pivot_plan
    assert trace.success and len(trace.sections) == 2
    coarse, coarse_states = schedule_from_trace(trace, fine=False)
    middle, middle_states = schedule_from_trace(trace, fine=30)
    part, _ = schedule_from_trace(trace, fine=30, sections=[1])
    assert set(part.section) == {1}
    np.testing.assert_array_equal(part.t, middle.t[middle.section == 1])
    mixed, mixed_states = resampled(trace, coarse, coarse_states, [1], fine=30)
    assert coarse.t.size < mixed.t.size < middle.t.size and np.all(np.diff(mixed.t) >= 0)
    for rows, source, states in ((mixed.section == 0, (coarse, coarse.section == 0), coarse_states),
                                 (mixed.section == 1, (middle, middle.section == 1), middle_states)):
        sched, own = source
        for k in ("t", "a", "b", "adot", "bdot", "piece"):
            np.testing.assert_array_equal(getattr(mixed, k)[rows], getattr(sched, k)[own])
        for k in states:
            np.testing.assert_array_equal(mixed_states[k][rows], states[k][own])
    # the pipeline samples again only the sections its coarse replay names
    asked = []
    real = pipeline.verify_within

    def named_second(trace, schedule, share, rel_tol):
        asked.append(schedule.t.size)
        return (None, (1,)) if len(asked) == 1 else real(trace, schedule, share, rel_tol=rel_tol)

    monkeypatch.setattr(pipeline, "verify_within", named_second)
    kept = pipeline._sampled_and_verified(trace, 1e-6)
    assert asked == [coarse.t.size, mixed.t.size]
    assert kept[2].success
    np.testing.assert_array_equal(kept[0].t, mixed.t)


def test_a_planned_cusp_is_exact_verified_and_keeps_the_mass_in_place(through_a_cusp):
    fig, result = through_a_cusp
    assert result.success, result.message
    first, second = result.trace.sections
    for sec in (first, second):
        assert max(sec.residuals.values()) <= 1e-10
        assert sec.metrics["reach"] <= 1.0
    assert first.metrics["link"] == "start" and second.metrics["link"] == "impulse"
    checks = {c.name: c for c in result.feasibility.checks}
    size = result.report.figure_size
    # measured independently on the exported rows: the mass's position on the ice does not jump
    # at the cusp (the blade turns under it), and its velocity jumps by the impulse the planner reports
    assert checks["cusp_jump"].value <= 1e-9 * size
    assert checks["reach"].value <= 1.0
    info = result.feasibility.info
    assert info["max_cusp_impulse"] == pytest.approx(second.metrics["link_impulse"], rel=1e-6, abs=1e-9)
    # the one cusp's impulse as the effort of delivering it within IMPULSE_TIME, rows against plan
    from skatetrace.dynamics.presets import IMPULSE_TIME

    assert info["cusp_effort"] == pytest.approx(second.metrics["link_impulse"] ** 2 / IMPULSE_TIME, rel=1e-5, abs=1e-9)
    assert info["max_cusp_mass_speed"] > 0.0


@pytest.mark.parametrize("name", sorted(CUSPS))
def test_the_planned_effort_is_below_the_launch_glide_stop_one(name):
    # the planner's objective, measured on the exported rows of both: the integral of the squared
    # force on the mass, and each cusp's impulse as the effort of delivering it within IMPULSE_TIME
    fig = figure_from_dict(CUSPS[name])
    planned = st.trace_and_verify(fig, options=st.TraceOptions(reach=1.0))
    today = st.trace_and_verify(fig)
    assert planned.success and today.success

    def effort(result):
        return result.feasibility.info["effort"] + result.feasibility.info["cusp_effort"]

    assert effort(planned) < effort(today)
    # and the reach it was asked for, where today's manoeuvres put the mass metres away
    reach = {c.name: c.value for c in today.feasibility.checks}["reach"]
    assert reach > 2.0


def test_the_launch_glide_stop_tracer_refuses_a_reach_instead_of_ignoring_it():
    fig = st.school_figure("three", height=1.7)
    with pytest.raises(ValueError, match="plan_figure"):
        st.trace_figure(fig, options=st.TraceOptions(reach=0.5))
    with pytest.raises(ValueError, match="plan_figure"):
        st.trace_section(fig.params, fig.curves[0].sections()[0], st.TraceOptions(reach=0.5))
    assert st.plan_figure is plan_figure  # the function the message names


def test_the_default_reach_is_the_trunk_length():
    from skatetrace.dynamics.presets import REACH_PER_HEIGHT, skater_reach

    assert skater_reach(1.7) == pytest.approx(REACH_PER_HEIGHT * 1.7)
    assert 0.45 < skater_reach(1.7) < 0.5  # inside the feasibility check's 0.5 x height
    for bad in (0.0, -1.7, math.nan, "tall"):
        with pytest.raises(ValueError, match="height"):
            skater_reach(bad)


def test_least_time_under_an_acceleration_bound_is_faster_and_keeps_the_bound():
    fig = figure_from_dict({"schema": "skatetrace.figure/1",
                            "curves": [{"pieces": [{"type": "arc", "radius": 1.2, "sweep_deg": 198}]}]})
    effort = st.trace_and_verify(fig, st.PAPER_PARAMS, st.TraceOptions(reach=1.0))
    fast = st.trace_and_verify(fig, st.PAPER_PARAMS, st.TraceOptions(reach=1.0, objective="time", max_accel=20.0))
    assert effort.success and fast.success, fast.message
    assert fast.trace.sections[0].duration < effort.trace.sections[0].duration
    measured = {c.name: c.value for c in fast.feasibility.checks}
    assert measured["mass_acceleration"] <= 20.0 and measured["reach"] <= 1.0  # on the exported rows


def test_the_warm_start_pins_the_mass_at_the_cusp_on_both_sides():
    # the chain the linked program starts from, and the plan where IPOPT cannot solve that program
    from skatetrace.planning.planner import _CUSP_AHEAD, _program_options, _warm_start, curve_specs

    fig = figure_from_dict(CUSPS["pivot"])
    popts = _program_options(fig.params, st.TraceOptions(reach=1.0))
    specs, _sections = curve_specs(fig.curves[0])
    guess, bad, continues = _warm_start(specs, popts)
    assert bad is None and continues == (False, True)
    end = guess.states[0][2:4, -1]
    c, s = math.cos(specs[1].turn), math.sin(specs[1].turn)
    start = guess.states[1][2:4, 0]
    np.testing.assert_allclose(start, [c * end[0] - s * end[1], s * end[0] + c * end[1]], atol=1e-9)
    np.testing.assert_allclose(start, [_CUSP_AHEAD * popts.reach, 0.0], atol=1e-9)


def test_a_mirrored_section_is_the_mirror_image_of_the_motion():
    # what lets the warm start share one solve between a section and its mirror image: with
    # every curvature reversed, (p1, p2, a, b, s, u) -> (-p1, p2, a, -b, s, u) maps the motion,
    # its speed, its rates and the mass's acceleration onto the mirrored ones
    from skatetrace.planning.planner import _mirrored, _shape_key
    from skatetrace.planning.collocation import PieceSpec, ProgramSolution, SectionSpec

    fn = sleigh_functions(0.658, 0.342, 0.0074)
    flip = np.array([-1.0, 1.0, 1.0, -1.0, 1.0, 1.0])
    rng = np.random.default_rng(5)
    cf = np.array([0.4, -0.2, 0.05, 0.01])
    for _ in range(5):
        x = rng.normal(size=6) * 0.3
        args, mirrored = (x, 0.7, cf, 0.1), (flip * x, 0.7, -cf, 0.1)
        np.testing.assert_allclose(fn["f"](*mirrored).full().ravel(), flip * fn["f"](*args).full().ravel(), rtol=1e-12,
                                   atol=1e-14)
        assert float(fn["xi2"](*mirrored)) == pytest.approx(float(fn["xi2"](*args)), rel=1e-12)
        rates, rates_m = fn["rates"](*args).full().ravel(), fn["rates"](*mirrored).full().ravel()
        np.testing.assert_allclose(rates_m, [rates[0], -rates[1]], rtol=1e-12, atol=1e-14)
        acc, acc_m = fn["accel"](*args).full().ravel(), fn["accel"](*mirrored).full().ravel()
        np.testing.assert_allclose(acc_m, [acc[0], -acc[1]], rtol=1e-10, atol=1e-12)
    one = SectionSpec((PieceSpec(tuple(cf), 2.0), PieceSpec((0.0, 0.0, 0.0, 0.0), 1.0)))
    other = SectionSpec((PieceSpec(tuple(-cf), 2.0), PieceSpec((-0.0, 0.0, 0.0, 0.0), 1.0)))
    (key, sign), (key_m, sign_m) = _shape_key(one), _shape_key(other)
    assert key == key_m and sign == -sign_m
    states = rng.normal(size=(6, 4))
    plan = ProgramSolution(success=True, status="s", message="s", times=(np.arange(4.0),), states=(states,),
                           controls=(np.ones(3),))
    np.testing.assert_array_equal(_mirrored(plan).states[0], flip[:, None] * states)


def test_the_mesh_of_a_symmetric_section_has_no_interval_of_round_off():
    # A bracket's section is symmetric about its middle join, where a node of the section's mesh
    # falls within round-off of the join: left in, its interval of 1e-16 made IPOPT's Hessian NaN.
    from skatetrace.planning.collocation import PieceSpec, SectionSpec, _mesh

    for n in (36, 40, 54, 80):
        pieces = (PieceSpec((7.1429, 0.0, 0.0, 0.0), 0.2126), PieceSpec((-0.3922, 0.0, 0.0, 0.0), 7.8783),
                  PieceSpec((0.3922, 0.0, 0.0, 0.0), 7.8783), PieceSpec((-7.1429, 0.0, 0.0, 0.0), 0.2126))
        spec = SectionSpec(pieces, 0.0, 20.0)
        meshes, _ = _mesh(spec, spec.duration, n)
        # the pieces' meshes meet at their joins, and no interval is far shorter than the grading's
        assert all(a[-1] == b[0] for a, b in zip(meshes[:-1], meshes[1:]))
        smallest = min(np.min(np.diff(m)) for m in meshes)
        assert smallest > 0.1 * (1.0 - math.cos(math.pi / n)) * 0.5 * spec.duration


def test_a_plan_restarted_from_itself_is_found_again_at_once():
    # The guess's states at the collocation points are interpolated between its nodes: a start
    # whose collocation defects are small. (Copies of the next node took twice the iterations on
    # this arc, and the school three's linked program 140 against 27.)
    from skatetrace.planning.collocation import solve_program
    from skatetrace.planning.planner import _program_options, curve_specs

    fig = figure_from_dict({"schema": "skatetrace.figure/1",
                            "curves": [{"pieces": [{"type": "arc", "radius": 1.2, "sweep_deg": 198}]}]})
    popts = _program_options(st.PAPER_PARAMS, st.TraceOptions(reach=1.0))
    specs, _ = curve_specs(fig.curves[0])
    first = solve_program(specs, popts)
    again = solve_program(specs, popts, guess=first, meshes=first.meshes)
    assert first.success and again.success
    # a handful of iterations back to the optimum (9 of 17 measured; IPOPT's path depends on the ordering)
    assert again.iterations < first.iterations and again.iterations <= 12
    assert again.objective == pytest.approx(first.objective, rel=1e-6)


def test_a_curve_that_repeats_a_unit_of_sections_is_planned_as_that_unit():
    import dataclasses

    from skatetrace.planning.planner import _period, _program_options, _closing_turn, curve_specs

    def period(name, bent=None):
        fig = st.school_figure(name, height=1.7)
        specs, sections = curve_specs(fig.curves[0])
        if bent is not None:  # one cusp turned a little more
            specs[bent] = dataclasses.replace(specs[bent], turn=specs[bent].turn + 1e-3)
        popts = _program_options(fig.params, st.TraceOptions(reach=0.5, speed=2.0))
        return _period(specs, dataclasses.replace(popts, closing_turn=_closing_turn(fig.curves[0], sections)))

    # the other foot skates the same sections mirrored (paragraph figures) or as they are (change figures)
    assert period("paragraph-double-three") == (5, -1)
    assert period("change-double-three") == (3, 1)
    assert period("circle-eight") == (1, -1)
    assert period("paragraph-double-three", bent=7) is None
    # an open curve has ends that no unit repeats; so has a curve whose sections differ
    assert _period(curve_specs(figure_from_dict(CUSPS["pivot"]).curves[0])[0],
                   _program_options(st.PAPER_PARAMS, st.TraceOptions(reach=1.0))) is None


def test_the_units_plan_is_a_stationary_point_of_the_whole_curves_program():
    # By the curve's symmetry the unit's optimum, repeated, is one of the whole program's: solved
    # as a whole from it, IPOPT stays where it is, with twice the unit's effort.
    import dataclasses

    from skatetrace.planning.collocation import solve_program
    from skatetrace.planning.planner import (_closing_turn, _linked_job, _linked_options, _program_options,
                                             _warm_start, curve_specs)

    fig = st.school_figure("loop", height=1.7)
    specs, sections = curve_specs(fig.curves[0])
    popts = _program_options(fig.params, st.TraceOptions(reach=0.5, speed=2.0))
    popts = _linked_options(dataclasses.replace(popts, closing_turn=_closing_turn(fig.curves[0], sections)))
    guess, _bad, _continues = _warm_start(specs, popts)
    job, whole = _linked_job(specs, popts, guess, guess.meshes)
    assert len(job[0]) == 1 and job[1].closing_mirror  # the loop's two halves are mirror images
    unit = solve_program(job[0], job[1], guess=job[2], meshes=job[3])
    plan = whole(unit)
    assert unit.success and len(plan.states) == 2
    np.testing.assert_allclose(plan.states[1][[0, 3]], -plan.states[0][[0, 3]])
    again = solve_program(specs, popts, guess=plan, meshes=plan.meshes)
    # IPOPT's barrier takes its iterations to settle, within its tolerance (1e-6 on the optimality
    # conditions): the effort moves by 3e-8, the mass by 4e-6 of the reach (the paragraph loop's by
    # 7e-7; 5e-9 and 8e-7 before the collocation's end states were merged with its nodes, when the
    # unit found another optimum: 1.2 times the reach from this one, where they are farthest apart).
    assert again.success and again.objective == pytest.approx(2.0 * unit.objective, rel=1e-6)
    moved = max(float(np.max(np.abs(a[2:4] - b[2:4]))) for a, b in zip(again.states, plan.states))
    assert moved <= 1e-4 * popts.reach


def test_a_linked_program_out_of_iterations_is_finished_from_its_last_iterate(monkeypatch):
    # The iterate may be crawling towards a plan far better than the chain's; the exact finish
    # decides whether it is a plan: where every section finishes within the reach it is kept.
    from skatetrace.planning import planner

    kept = []
    real = planner._unconverged

    def spy(candidate, *args, **kwargs):
        assert candidate.status == "Maximum_Iterations_Exceeded"
        kept.append(real(candidate, *args, **kwargs))
        return kept[-1]

    monkeypatch.setattr(planner, "_unconverged", spy)
    monkeypatch.setattr(planner, "_LINKED_ITER", 15)  # the loop's unit converges in about 20
    fig = st.school_figure("loop", height=1.7)
    trace = plan_figure(fig, options=st.TraceOptions(reach=0.5, speed=2.0))
    assert len(kept) == 1 and kept[0] is not None and list(trace.sections) == kept[0]
    for sec in trace.sections:
        assert sec.success and max(sec.residuals.values()) <= 1e-10 and sec.metrics["reach"] <= 0.5
    assert [sec.metrics["link"] for sec in trace.sections] == ["start", "impulse"]

    # three iterations into the pivot's linked program its iterate no longer finishes (residuals
    # of 1e-2): the chain is the plan, finished and mended as before
    monkeypatch.setattr(planner, "_LINKED_ITER", 3)
    chain = plan_figure(figure_from_dict(CUSPS["pivot"]), options=st.TraceOptions(reach=1.0))
    assert len(kept) == 2 and kept[1] is None
    assert chain.success and all(max(sec.residuals.values()) <= 1e-10 for sec in chain.sections)


def test_a_last_iterate_is_finished_no_further_than_its_first_failed_section(monkeypatch):
    # The last iterate is kept only whole: once a section fails, the sections after it are not
    # finished (on heroicons' paper airplane the first failed, and the four after it cost 0.6 s).
    from skatetrace.planning import planner

    real_finish, real_unconverged = planner.finish_section, planner._unconverged
    inside, strides = [False], []

    def failing(*args, **kwargs):
        fin = real_finish(*args, **kwargs)
        if inside[0]:
            strides.append(kwargs["stride"])
            return dataclasses.replace(fin, success=False, residuals=dict(fin.residuals, continuity=1e-3))
        return fin

    def spy(*args, **kwargs):
        inside[0] = True
        try:
            return real_unconverged(*args, **kwargs)
        finally:
            inside[0] = False

    monkeypatch.setattr(planner, "finish_section", failing)
    monkeypatch.setattr(planner, "_unconverged", spy)
    monkeypatch.setattr(planner, "_LINKED_ITER", 15)  # out of iterations, as in the test above
    trace = plan_figure(st.school_figure("loop", height=1.7), options=st.TraceOptions(reach=0.5, speed=2.0))
    assert strides == list(planner._STRIDES)  # the first section, at every stride; not the second
    assert len(trace.sections) == 2 and all(sec.success for sec in trace.sections)  # the chain, mended


@pytest.mark.parametrize("miss", [3e-10, 3e-6])
def test_a_finish_that_misses_its_tolerance_narrowly_is_solved_again_at_other_integration_tolerances(monkeypatch, miss):
    # Within ten times the tolerance the miss is round-off (phosphor-infinity's 1.5e-10 cost a
    # refined mesh and a program again, 2.6 s): the finish is solved again at twice and a quarter
    # of the integrations' tolerances before that. A wide miss is not.
    from skatetrace.planning import planner

    real, calls = planner.finish_section, []

    def missing(*args, **kwargs):
        calls.append((kwargs["stride"], kwargs["rtol"], kwargs["atol"]))
        fin = real(*args, **kwargs)
        if len(calls) <= 2:  # the first section at both strides
            return dataclasses.replace(fin, success=False, residuals=dict(fin.residuals, continuity=miss))
        return fin

    monkeypatch.setattr(planner, "finish_section", missing)
    options = st.TraceOptions(reach=0.5, speed=2.0)
    trace = plan_figure(st.school_figure("loop", height=1.7), options=options)
    assert calls[:2] == [(2, options.rtol, options.atol), (1, options.rtol, options.atol)]
    rerolled = [c for c in calls if c[1] != options.rtol]
    if miss < 10 * 1e-10:
        assert calls[2] == (1, 2.0 * options.rtol, 2.0 * options.atol) and rerolled == [calls[2]]
        assert trace.success and len(calls) == 2 + 1 + 1  # the second section as before, nothing planned again
    else:
        assert rerolled == []


def test_a_chains_replan_solves_each_distinct_program_once_side_by_side(monkeypatch):
    # feather-settings' chain of 39 sections was planned again section by section, one after
    # another, 114 programs; the same program (pieces, pins, guess, mesh) is now solved once
    from skatetrace.planning import planner
    from skatetrace.planning.collocation import solve_program

    fig = figure_from_dict({"schema": "skatetrace.figure/1",
                            "curves": [{"pieces": [{"type": "arc", "radius": 1.2, "sweep_deg": 198}]}]})
    popts = planner._program_options(st.PAPER_PARAMS, st.TraceOptions(reach=1.0))
    (spec,), _ = planner.curve_specs(fig.curves[0])
    one = solve_program([spec], popts)
    other = solve_program([spec], dataclasses.replace(popts, reach=0.9))
    plan = planner._chain([one, other, one], "warm start")
    batches = []
    real = planner.solve_programs
    monkeypatch.setattr(planner, "solve_programs", lambda jobs, workers=None, stage="": batches.append(
        (len(jobs), workers, stage)) or real(jobs, workers))
    again = planner._replan(plan, [spec] * 3, popts, ("start", "jump", "jump"), False, workers=2)
    assert batches == [(2, 2, "programs again")] and again.success and len(again.states) == 3
    np.testing.assert_array_equal(again.states[0], again.states[2])
    alone = solve_program([spec], dataclasses.replace(popts, mu_init=planner._LINKED_MU), guess=planner._section_of(plan, 1),
                          meshes=plan.meshes[1:2])
    np.testing.assert_array_equal(again.states[1], alone.states[0])  # the same program as solved on its own


def test_every_program_solved_is_reported_batch_by_batch():
    # issue 19: a drawing's planning ran for minutes without a word; the command line now shows
    # each batch of programs as it is solved
    from skatetrace.planning.pool import reporting

    seen = []
    with reporting(lambda stage, done, total: seen.append((stage, done, total))):
        trace = plan_figure(st.school_figure("loop", height=1.7), options=st.TraceOptions(reach=0.5, speed=2.0))
    assert trace.success
    stages = [s for s, _d, _t in seen]
    assert stages[0] == "warm starts" and "linked programs" in stages
    for stage in set(stages):
        counts = [(d, t) for s, d, t in seen if s == stage]
        assert counts[-1][0] == counts[-1][1] and all(1 <= d <= t for d, t in counts)
    plan_figure(st.school_figure("loop", height=1.7), options=st.TraceOptions(reach=0.5, speed=2.0))
    assert len(seen) == len(stages)  # outside the block, nothing is reported


def test_a_larger_linked_program_gets_fewer_iterations(monkeypatch):
    # issues 17 and 18: IPOPT's time an iteration grows with the program, and a drawing's big
    # linked program crawls; its iterations are budgeted by its size
    from skatetrace.planning import collocation, nlp, planner

    base = collocation.ProgramOptions(M=0.6, m=0.4, I=0.5, reach=0.5)
    assert base.iterations_for(10**6) == base.max_iter  # no budget: IPOPT's cap as given
    linked = planner._linked_options(base)
    assert linked.iterations_for(2300) == linked.iterations_for(3830) == planner._LINKED_ITER
    # fontawesome-feather's curve: 16,190 unknowns before the end states were merged with the nodes, some 12,400 now
    assert linked.iterations_for(12400) == 46 and linked.iterations_for(10**6) == planner._LINKED_ITER // 4
    section = planner._program_options(st.PAPER_PARAMS, st.TraceOptions(reach=0.5))
    assert section.iterations_for(2560) == 500 and section.iterations_for(9200) == 166  # a section on its own

    seen = []
    solve = nlp.SparseProgram.solve

    def spy(self, options, give_up=None):
        seen.append((options["ipopt.mu_init"], options["ipopt.max_iter"], self.n))
        return solve(self, options, give_up)

    monkeypatch.setattr(nlp.SparseProgram, "solve", spy)
    monkeypatch.setattr(planner, "_LINKED_BUDGET", 40 * 1000)
    plan_figure(st.school_figure("loop", height=1.7), options=st.TraceOptions(reach=0.5, speed=2.0, workers=1))
    caps = [(cap, n) for mu, cap, n in seen if mu == planner._LINKED_MU]
    assert caps and all(cap == min(150, max(37, 40_000 // n)) for cap, n in caps), caps
    assert any(cap < 150 for cap, _n in caps)
    assert all(cap == 500 for mu, cap, _n in seen if mu != planner._LINKED_MU)  # single sections: as before


def test_an_intervals_last_collocation_point_is_the_next_node_not_a_copy_of_it():
    # Radau's last point is the interval's end: its state is the next node's, one unknown (19 an
    # interval: the node, two inner points, the control), where a copy tied to the node by a
    # constraint made 25 and IPOPT's linear systems a fifth larger, for the same optimum
    from skatetrace.planning import collocation

    spec = collocation.SectionSpec((collocation.PieceSpec((1.2, 0.0, 0.0, 0.0), 2.0),
                                    collocation.PieceSpec((0.0, 0.0, 0.0, 0.0), 1.5)))
    opts = collocation.ProgramOptions(M=0.6, m=0.4, I=0.5, reach=0.5)
    layout, n = collocation._layout([spec], opts, None)
    lays = layout[0][3]
    assert n == collocation.program_unknowns([spec], opts) == sum(7 + 19 * lay.N for lay in lays)
    used = {lay.T for lay in lays}
    for lay in lays:
        index, _scale = lay.interval_index()
        assert np.array_equal(index[18:24], index[0:6] + 6)  # the last point of interval k is node k + 1
        used.update(index.ravel().tolist())
    assert used == set(range(n))  # every unknown is an interval's (or a piece's duration), none a copy

def test_a_program_too_large_to_build_is_refused_as_data(monkeypatch):
    """Issue 19: a line 1000 km long at --reach asked CasADi for 10^8 unknowns and died of bad_alloc
    after taking 5 GB; the program's size is now checked before anything is built."""
    from skatetrace.planning import collocation

    def no_build(*args, **kwargs):
        raise AssertionError("a program too large must not be built")

    monkeypatch.setattr(collocation, "SparseProgram", no_build)
    figure = figure_from_dict({"curves": [{"pieces": [{"type": "line", "length": 1e6}]}]})
    trace = plan_figure(figure, figure.params, st.TraceOptions(reach=0.5, workers=1))
    (sec,) = trace.sections
    assert not sec.success and sec.status is st.TraceStatus.NOT_PLANNED
    assert f"more than the {collocation.MAX_UNKNOWNS:,} allowed" in sec.message and "--reach none" in sec.message


def test_a_section_of_hundreds_of_pieces_is_refused_for_its_pieces_before_anything_is_built():
    # the serpentine in exact mode (313 spirals in one section, 33,691 unknowns) ran 500 IPOPT
    # iterations in 6 minutes and failed; a program that large is refused at once, saying why
    from skatetrace.planning import collocation, planner

    popts = planner._program_options(st.PAPER_PARAMS, st.TraceOptions(reach=1.0))
    pieces = tuple(collocation.PieceSpec((0.5 * (-1) ** k, 0.0, 0.0, 0.0), 0.01) for k in range(400))
    spec = collocation.SectionSpec(pieces, 0.0, 1.25 * 4.0)
    why = collocation.program_too_large([spec], popts)
    assert why is not None and "its 400 pieces have at least 3 intervals each" in why and "--reach none" in why
    assert collocation.program_too_large([collocation.SectionSpec(pieces[:100], 0.0, 1.25)], popts) is None


def test_a_curve_with_a_section_too_large_to_plan_solves_no_program_at_all(monkeypatch):
    # the three turn in exact mode spent 88 s on the warm starts of four sections beside its fifth,
    # too large to plan, which made the curve unplannable anyway (398 s in all, now 8 s)
    from skatetrace.planning import collocation

    def no_solve(self, options, give_up=None):
        raise AssertionError("no program of a curve that cannot be planned is solved")

    monkeypatch.setattr(collocation.SparseProgram, "solve", no_solve)
    figure = figure_from_dict(_cusp_figure({"type": "cusp", "pivot_deg": 30}, {"type": "line", "length": 1e6}))
    trace = plan_figure(figure, figure.params, st.TraceOptions(reach=0.5, workers=1))
    assert [sec.status for sec in trace.sections] == [st.TraceStatus.NOT_PLANNED] * 2
    assert "section 1 of this curve cannot be planned" in trace.sections[0].message
    assert "more than the 9,200 allowed" in trace.sections[1].message


def test_a_solver_that_stops_with_an_error_is_a_failed_program_not_a_crash(monkeypatch):
    """Issue 19: IPOPT out of memory (std::bad_alloc, raised by CasADi as RuntimeError) on a
    2,000-point zigzag drawing was a traceback after 12 s; it is a failed program, and the default
    reach then falls back to the launch-glide-stop manoeuvres."""
    from skatetrace.planning import collocation, nlp

    def bad_alloc(self, options, give_up=None):
        raise RuntimeError("Error in Function::call for 'plan' [IpoptInterface] at .../function.cpp:514:\n"
                           "std::bad_alloc")

    monkeypatch.setattr(nlp.SparseProgram, "solve", bad_alloc)
    figure = figure_from_dict({"curves": [{"pieces": [{"type": "arc", "radius": 1, "sweep_deg": 90}]}]})
    trace = plan_figure(figure, figure.params, st.TraceOptions(reach=0.5, workers=1))
    (sec,) = trace.sections
    assert not sec.success and sec.message
    from skatetrace.planning.planner import _program_options, curve_specs
    specs, _ = curve_specs(figure.curves[0])
    sol = collocation.solve_program(specs, _program_options(st.SleighParams(), st.TraceOptions(reach=0.5)))
    assert not sol.success and sol.status == "solver_error" and sol.message == "the solver stopped: out of memory"


def test_the_size_check_passes_every_school_figure():
    from skatetrace.planning.collocation import program_too_large
    from skatetrace.planning.planner import _program_options, curve_specs

    options = st.TraceOptions(reach=0.5)
    for name in ("paragraph-double-three", "change-double-three", "serpentine"):
        figure = st.school_figure(name, height=1.7)
        popts = _program_options(figure.params, options)
        for curve in figure.curves:
            specs, _ = curve_specs(curve)
            assert program_too_large(specs, popts) is None


def test_an_interval_whose_integration_diverged_is_split_the_most_not_a_crash():
    # found by the corpus under the default reach (vivus-hi-there): an infinite defect raised
    # OverflowError in the mesh refinement (ceil of infinity)
    from skatetrace.planning.collocation import ProgramSolution
    from skatetrace.planning.mesh import _MAX_PARTS, refined

    nodes = np.array([0.0, 0.5, 1.0])
    sol = ProgramSolution(success=True, status="x", message="x", times=(nodes.copy(),),
                          states=(np.vstack([nodes] * 6),), controls=(np.zeros(2),), meshes=((nodes,),))
    meshes, guess, n_split = refined(sol, [np.array([math.inf, 1e-12])], 1e-5)
    assert n_split == 1 and meshes[0][0].size == 3 + _MAX_PARTS - 1
    assert np.all(np.isfinite(guess.states[0])) and guess.times[0].size == meshes[0][0].size


def test_an_error_in_finishing_a_curve_is_that_curves_failure_not_the_runs(monkeypatch):
    # a corpus drawing crashed the whole run from inside the planner (an infinite defect in the mesh
    # refinement); whatever arithmetic error a curve's finish meets is reported on its sections
    from skatetrace.planning import planner

    real = planner._mended
    calls = []

    def broken_first(plan, links, linked, specs, sections, ci, *args):
        calls.append(ci)
        if ci == 0:
            raise OverflowError("cannot convert float infinity to integer")
        return real(plan, links, linked, specs, sections, ci, *args)

    monkeypatch.setattr(planner, "_mended", broken_first)
    arc = {"pieces": [{"type": "arc", "radius": 1.2, "sweep_deg": 90}]}
    figure = figure_from_dict({"curves": [arc, arc], "params": {"M": 2, "m": 1, "I": 3}})
    trace = plan_figure(figure, figure.params, st.TraceOptions(reach=1.0, workers=1))
    first, second = trace.sections
    assert calls == [0, 1] and first.status is st.TraceStatus.NOT_PLANNED and not first.phases
    assert "the planner failed on this curve (OverflowError: cannot convert" in first.message
    assert second.success and max(second.residuals.values()) <= 1e-10


def test_a_section_without_a_plan_searches_larger_reaches_only_when_asked(monkeypatch):
    # the command line's default reach falls back to the launch-glide-stop manoeuvres, and the
    # search of larger reaches (one program each: 65 s on a spiral of 60 arcs) only delayed that
    from skatetrace.planning import planner

    fig = figure_from_dict({"schema": "skatetrace.figure/1", "params": {"M": 2, "m": 1, "I": 3},
                            "curves": [{"pieces": [{"type": "arc", "radius": 1.2, "sweep_deg": 198}]}]})
    searched = []
    real = planner.smallest_reach
    monkeypatch.setattr(planner, "smallest_reach", lambda *a: searched.append(1) or real(*a))
    hinted = plan_figure(fig, options=st.TraceOptions(reach=0.02))
    (sec,) = hinted.sections
    assert searched and sec.status.name == "INFEASIBLE" and "on its own it plans within" in sec.message
    assert 0.02 < sec.metrics["smallest_feasible_reach"] <= 0.1
    searched.clear()
    (bare,) = plan_figure(fig, options=st.TraceOptions(reach=0.02, reach_hint=False)).sections
    assert not searched and bare.status.name == "INFEASIBLE" and "on its own" not in bare.message
    assert "smallest_feasible_reach" not in (bare.metrics or {})
    with pytest.raises(ValueError, match="reach_hint must be True or False"):
        st.TraceOptions(reach=1.0, reach_hint="no")


def test_curves_drawn_alike_share_one_linked_program():
    # a row of identical strokes (an SVG's, scaled: equal up to round-off) was one linked program
    # each; each distinct one is now solved once, and every curve is still finished exactly
    import copy

    from skatetrace.planning.pool import reporting

    data = copy.deepcopy(CUSPS["pivot"])
    twin = copy.deepcopy(data["curves"][0])
    twin["pieces"][0]["radius"] *= 1 + 4e-16  # the round-off of a translated, scaled copy
    other = copy.deepcopy(data["curves"][0])
    other["pieces"][1]["radius"] = 1.4  # a stroke drawn differently
    data["curves"] += [twin, other]
    seen = []
    with reporting(lambda stage, done, total: seen.append((stage, total))):
        trace = plan_figure(figure_from_dict(data), options=st.TraceOptions(reach=1.0))
    assert ("linked programs", 2) in seen and all(t == 2 for s, t in seen if s == "linked programs")
    assert trace.success and len(trace.sections) == 6
    assert all(max(sec.residuals.values()) <= 1e-10 and sec.metrics["reach"] <= 1.0 for sec in trace.sections)
    assert [sec.metrics["link"] for sec in trace.sections] == ["start", "impulse"] * 3


def test_sections_without_a_pinned_plan_are_planned_again_side_by_side(monkeypatch):
    # a section whose pinned warm start fails is planned with free ends, then pinned again from
    # that plan: one after another (octicons-infinity: two such sections, 14 s) these programs are
    # now batches of their own, and the warm start is the one the sequential search found
    from skatetrace.planning import planner
    from skatetrace.planning.collocation import ProgramSolution

    fig = figure_from_dict(CUSPS["pivot"])
    popts = planner._program_options(fig.params, st.TraceOptions(reach=1.0))
    specs, _sections = planner.curve_specs(fig.curves[0])
    real = planner.solve_programs
    batches = []

    def pinned_fail(jobs, workers=None, stage=""):
        # every program pinned at its start, from the default guess, "fails" (IPOPT out of iterations)
        batches.append((stage, len(jobs)))
        sols = real(jobs, workers, stage)
        return [ProgramSolution(success=False, status="Maximum_Iterations_Exceeded", message="mocked")
                if job[1].start_position is not None and job[2] is None else sol for job, sol in zip(jobs, sols)]

    monkeypatch.setattr(planner, "solve_programs", pinned_fail)
    solved = planner._presolved([(specs, popts)], 2)
    assert [stage for stage, _n in batches] == ["warm starts", "warm starts with free ends",
                                                 "warm starts pinned again"]
    assert batches[1][1] == 2  # both sections, with free ends
    batched, _bad, links = planner._warm_start(specs, popts, solved)
    assert len(batches) == 3  # every program came from the batches: none was solved again
    alone, _bad, links_alone = planner._warm_start(specs, popts, {})  # one after another, as before
    assert [n for _stage, n in batches[3:]] == [1] * (len(batches) - 3)
    assert links == links_alone
    for a, b in zip(batched.states, alone.states):
        np.testing.assert_array_equal(a, b)


def test_all_or_nothing_plans_no_curve_further_once_a_section_has_no_plan(monkeypatch):
    # the command line's default reach uses a plan only if every section has one: a drawing of 22
    # sections planned and finished its other curves for 30 s before falling back all the same.
    # The warm start of curve 1 is made to find no plan (a real one takes 50 s to say so)
    import copy

    from skatetrace.planning import planner
    from skatetrace.planning.pool import reporting

    real = planner._warm_start

    def none_for_the_arc(specs, popts, solved):
        guess, bad, continues = real(specs, popts, solved)
        return (None, 0, continues) if len(specs) == 1 else (guess, bad, continues)

    monkeypatch.setattr(planner, "_warm_start", none_for_the_arc)
    data = copy.deepcopy(CUSPS["pivot"])
    data["curves"].append({"pieces": [{"type": "arc", "radius": 1.2, "sweep_deg": 90}]})
    fig = figure_from_dict(data)
    for aon in (False, True):
        stages = []
        with reporting(lambda stage, done, total: stages.append(stage)):
            trace = plan_figure(fig, options=st.TraceOptions(reach=1.0, reach_hint=False, all_or_nothing=aon))
        first, second, arc = trace.sections
        assert arc.status is st.TraceStatus.INFEASIBLE
        if not aon:
            assert first.success and second.success and "linked programs" in stages
        else:
            assert "linked programs" not in stages and "programs again" not in stages
            for sec in (first, second):
                assert sec.status is st.TraceStatus.NOT_PLANNED and not sec.phases
                assert "section 0 of curve 1 has no motion within the reach (all or nothing)" in sec.message
    with pytest.raises(ValueError, match="all_or_nothing must be True or False"):
        st.TraceOptions(reach=1.0, all_or_nothing=1)


def _pivot_and_arc():
    import copy

    data = copy.deepcopy(CUSPS["pivot"])
    data["curves"].append({"pieces": [{"type": "arc", "radius": 1.2, "sweep_deg": 90}]})
    return figure_from_dict(data)


def test_a_plan_that_spends_its_budget_reports_every_section_not_planned_as_data(monkeypatch):
    from skatetrace.planning import planner
    from skatetrace.planning.pool import spending

    monkeypatch.setattr(planner, "_LINKED_SHARE", 1.0)  # the linked program may spend all that is left (next test)
    fig = _pivot_and_arc()
    options = st.TraceOptions(reach=1.0, reach_hint=False)
    with spending(10**12) as counted:  # a plan without a budget of its own counts against the caller's
        free = plan_figure(fig, options=options)
    assert free.success and counted.spent > 0
    within = plan_figure(fig, options=dataclasses.replace(options, plan_budget=counted.spent))
    assert within.success
    for a, b in zip(free.sections, within.sections):
        assert a.residuals == b.residuals and a.duration == b.duration
    for budget in (counted.spent - 1, 0):
        short = plan_figure(fig, options=dataclasses.replace(options, plan_budget=budget))
        assert not short.success and len(short.sections) == len(free.sections)
        for sec in short.sections:
            assert sec.status is st.TraceStatus.OVER_BUDGET and not sec.phases
            assert f"reach 1: not planned: the planning budget of {budget:,} (IPOPT iterations x unknowns)" \
                in sec.message


def test_a_linked_program_under_a_budget_leaves_the_rest_to_finish_the_chain(monkeypatch):
    # The linked program only improves the chain of warm starts: given all that is left (share 1),
    # one that would need a unit more spends the budget and nothing is planned (test above); at
    # its share it stops short, and the chain (or its last iterate, finished) is the plan
    from skatetrace.planning import planner, pool
    from skatetrace.planning.pool import spending

    batches = []
    real = pool.solve_programs

    def recorded(jobs, workers=None, stage="programs", share=1.0):
        sols = real(jobs, workers, stage, share)
        batches.append((stage, share, [s.iterations * s.unknowns for s in sols], [(s.status, s.unknowns) for s in sols]))
        return sols

    monkeypatch.setattr(planner, "solve_programs", recorded)
    fig = _pivot_and_arc()
    options = st.TraceOptions(reach=1.0, reach_hint=False)
    with spending(10**12) as counted:
        plan_figure(fig, options=options)
    (warm, _s, warm_work, _st), (linked, share, linked_work, linked_status) = batches[:2]
    assert (warm, linked, share) == ("warm starts", "linked programs", planner._LINKED_SHARE)
    assert linked_status[0][0] == "Solve_Succeeded"
    budget = counted.spent - 1
    left = budget - sum(warm_work)
    # a share of half what the linked program needs: it stops short, and what is left after it (half
    # of it and all that the programs after it took, mending a finish) is kept for the rest
    monkeypatch.setattr(planner, "_LINKED_SHARE", 0.5 * linked_work[0] / left)
    batches.clear()
    with spending(10**12) as spent:
        trace = plan_figure(fig, options=dataclasses.replace(options, plan_budget=budget))
    assert trace.success and all(sec.status is st.TraceStatus.SUCCESS for sec in trace.sections)
    (_w, _s, again, _st), (_l, share, capped, status) = batches[:2]
    assert again == warm_work and share == planner._LINKED_SHARE and status[0][0] == "Maximum_Iterations_Exceeded"
    assert capped[0] <= share * left + status[0][1]  # one iteration past its part, at most
    assert spent.spent <= budget


def test_a_budget_spent_while_a_later_curve_is_mended_keeps_the_curves_finished_before(monkeypatch):
    from skatetrace.planning import planner
    from skatetrace.planning.pool import BudgetSpent

    real, calls = planner._mended, []

    def spent_on_the_second_curve(*args):
        calls.append(args[5])  # the curve's index
        if len(calls) == 2:
            raise BudgetSpent("the planning budget of 7 (IPOPT iterations x unknowns) was spent after 9 programs (8)")
        return real(*args)

    monkeypatch.setattr(planner, "_mended", spent_on_the_second_curve)
    # one after another (side by side, the curves' programs are charged in the same order: test_pool)
    options = st.TraceOptions(reach=1.0, reach_hint=False, plan_budget=10**12, workers=1)
    trace = plan_figure(_pivot_and_arc(), options=options)
    assert calls == [0, 1]
    first, second, arc = trace.sections
    assert first.success and second.success
    assert arc.status is st.TraceStatus.OVER_BUDGET and "was spent after 9 programs" in arc.message


def test_curves_finished_side_by_side_are_the_ones_finished_one_after_another(monkeypatch):
    # each curve's finish and mending run in a process of its own, the same bits as one after another
    from skatetrace.planning import pool

    forked = []
    real = pool.map_forked

    def spy(fn, items, workers=None):
        forked.append(len(items))
        return real(fn, items, workers)

    monkeypatch.setattr(pool, "map_forked", spy)
    monkeypatch.setattr(pool, "can_fork", lambda: True)
    fig = _pivot_and_arc()
    one, two = (plan_figure(fig, options=st.TraceOptions(reach=1.0, reach_hint=False, plan_budget=10**12,
                                                          workers=w)) for w in (1, 2))
    assert forked == [2] and one.success and two.success and len(one.sections) == len(two.sections) == 3
    for a, b in zip(one.sections, two.sections):
        assert a.residuals == b.residuals and a.metrics == b.metrics
        t = np.linspace(0.0, a.duration, 51)
        va, vb = a.evaluate(t, geometry=False), b.evaluate(t, geometry=False)
        for key in ("a", "b", "xi2"):
            np.testing.assert_array_equal(va[key], vb[key])


def test_the_default_reach_keeps_the_launch_glide_stop_trace_where_the_plan_spends_its_budget():
    fig = figure_from_dict(CUSPS["pivot"])
    options = st.TraceOptions(reach=1.0, reach_hint=False, all_or_nothing=True)
    kept = st.trace_within_default_reach(fig, None, options, rests="never", max_work=0)
    assert kept.fell_back == "over budget" and "the planning budget of 0 (IPOPT iterations x unknowns)" in kept.reason
    assert kept.result.success and kept.options.reach is None and kept.result.trace.options.reach is None
    # the budget the options carry is the one spent, and without a bound the plan is kept
    for opts, work in ((dataclasses.replace(options, plan_budget=10**12), 0), (options, None)):
        kept = st.trace_within_default_reach(fig, None, opts, rests="never", max_work=work)
        assert kept.result.success and kept.fell_back == "" and kept.options.reach == 1.0


def _given_up_beside(monkeypatch, background):
    """A plan given up at once (no budget) with ``background`` as the pipeline's Background: the
    result, and the reach of every ``trace_and_verify`` made in this process (None: launch-glide-stop)."""
    import skatetrace.pipeline as pipeline
    from skatetrace import processes

    monkeypatch.setattr(processes, "can_fork", lambda: True)
    monkeypatch.setattr(pipeline, "Background", background)
    made_here = []
    real = pipeline.trace_and_verify
    monkeypatch.setattr(pipeline, "trace_and_verify", lambda *a, **k: made_here.append(a[2].reach) or real(*a, **k))
    fig = figure_from_dict(CUSPS["pivot"])
    options = st.TraceOptions(reach=1.0, reach_hint=False, all_or_nothing=True, workers=2)
    kept = st.trace_within_default_reach(fig, None, options, rests="never", max_work=0)
    assert kept.fell_back == "over budget" and kept.result.success and kept.options.reach is None
    direct = real(fig, None, kept.options, rests="never")
    return kept, made_here, direct


def test_the_launch_glide_stop_trace_made_beside_the_plan_is_the_one_kept(monkeypatch):
    # it is made in a child on what the planner leaves idle; here the child is waited for, as when
    # the planning took long enough, and its answer is the one made here without it
    from skatetrace import processes

    class Waited(processes.Background):
        def ready(self):
            return self._child is not None and self._child.wait(300)

    kept, made_here, direct = _given_up_beside(monkeypatch, Waited)
    assert made_here == [1.0]  # the plan; the launch-glide-stop trace came from the child
    for name in ("t", "a", "b", "adot", "bdot"):
        np.testing.assert_array_equal(getattr(kept.result.schedule, name), getattr(direct.schedule, name))
    assert kept.result.report.max_deviation == direct.report.max_deviation


@pytest.mark.skipif(not os.path.exists("/proc/self/stat"), reason="a child's processor time is read from /proc")
def test_a_launch_glide_stop_trace_not_done_when_the_plan_is_given_up_is_waited_for(monkeypatch):
    # the child is not done when the plan is given up: it is waited for while it runs (here asked
    # for no share of a core, so that a busy test machine cannot starve it), not made afresh here
    from skatetrace import processes

    class NotYet(processes.Background):
        def ready(self):
            return False

        def awaited(self, share=0.5, window=0.25):
            return super().awaited(share=0.0, window=window)

    kept, made_here, direct = _given_up_beside(monkeypatch, NotYet)
    assert made_here == [1.0]  # the plan here; the launch-glide-stop trace came from the child
    np.testing.assert_array_equal(kept.result.schedule.a, direct.schedule.a)


def test_the_largest_school_figure_is_planned_well_within_the_default_budget():
    # DEFAULT_PLAN_BUDGET bounds a plan the user did not ask for; the school figures (planned by
    # default) spend 69,000 to 527,000 units, the paragraph double three the most
    from skatetrace.planning.pool import spending

    options = st.TraceOptions(speed=2.0, reach=0.288 * 1.7, reach_hint=False, all_or_nothing=True)
    with spending(10**12) as counted:
        trace = plan_figure(st.school_figure("paragraph-double-three", height=1.7), st.skater_params(height=1.7),
                            options)
    assert trace.success, trace.message
    assert 0 < counted.spent < 0.9 * DEFAULT_PLAN_BUDGET, counted.spent


def test_the_default_reach_gives_up_a_plan_whose_replay_fails_for_the_launch_glide_stop_trace(mocked_plans):
    # a plan is exact to its finish's residuals (1e-10 at the shooting joins): on a 6 m line with the
    # mass behind the blade the open loop grew them to 8e-6 at a tolerance of 6e-6 (w3c-styling-css-01-b)
    fig = figure_from_dict(CUSPS["pivot"])
    options = st.TraceOptions(reach=1.0, reach_hint=False, all_or_nothing=True)
    made = mocked_plans(plan_verifies=False)
    kept = st.trace_within_default_reach(fig, None, options, rests="never")
    assert kept.fell_back == "unverified" and "deviation 8e-06 exceeds 6e-06" in kept.reason
    assert kept.result.success and kept.options.reach is None and kept.result.trace.options.reach is None
    assert [o.reach for o in made] == [1.0, None]
    # where the launch-glide-stop trace fails too, the plan and its failure are kept
    made = mocked_plans(plan_verifies=False, unbounded_verifies=False)
    kept = st.trace_within_default_reach(fig, None, options, rests="never")
    # made with the options given and the default reach's budget
    assert (kept.fell_back, kept.reason) == ("", "")
    assert kept.options == dataclasses.replace(options, plan_budget=DEFAULT_PLAN_BUDGET)
    assert not kept.result.success and kept.result.trace.options.reach == 1.0
    # a plan that verifies is kept without tracing anything else
    made = mocked_plans(plan_verifies=True)
    kept = st.trace_within_default_reach(fig, None, options, rests="never")
    assert kept.result.success and kept.fell_back == "" and [o.reach for o in made] == [1.0]
    with pytest.raises(ValueError, match="planning needs options.reach"):
        st.trace_within_default_reach(fig, None, st.TraceOptions(), rests="never")


def test_the_default_reach_traces_a_figure_too_large_to_plan_with_the_launch_glide_stop_manoeuvres(mocked_plans,
                                                                                                    monkeypatch):
    fig = figure_from_dict(CUSPS["pivot"])
    options = st.TraceOptions(reach=1.0, reach_hint=False, all_or_nothing=True)
    size = planner_figure_unknowns(fig, None, options)
    made = mocked_plans(plan_verifies=True)
    kept = st.trace_within_default_reach(fig, None, options, rests="never", max_unknowns=size - 1)
    assert kept.fell_back == "too large" and kept.unknowns == size and [o.reach for o in made] == [None]
    assert kept.reason == f"{size:,} unknowns in its programs, more than {size - 1:,}: larger than a school figure"
    assert kept.result.success and kept.options.reach is None
    made = mocked_plans(plan_verifies=True)
    kept = st.trace_within_default_reach(fig, None, options, rests="never", max_unknowns=size)
    assert kept.fell_back == "" and [o.reach for o in made] == [1.0]  # at the bound: planned
    # the launch-glide-stop trace is kept whatever its outcome: no plan of minutes is made
    import skatetrace.pipeline as pipeline
    from skatetrace.tracing.sections import trace_figure

    made = mocked_plans(plan_verifies=True)

    def failing(figure, params, options, progress=None, cache=None):
        made.append(options)
        tr = trace_figure(figure, params, options, progress=progress, cache=cache)
        bad = dataclasses.replace(tr.sections[0], success=False, status=st.TraceStatus.INFEASIBLE, message="no")
        return dataclasses.replace(tr, sections=(bad,) + tr.sections[1:])

    monkeypatch.setattr(pipeline, "trace_figure", failing)
    kept = st.trace_within_default_reach(fig, None, options, rests="never", max_unknowns=0)
    assert kept.fell_back == "too large" and not kept.result.success and [o.reach for o in made] == [None]
    for bad in (-1, 1.5, True, "12000"):
        with pytest.raises(ValueError, match="max_unknowns must be a whole number"):
            st.trace_within_default_reach(fig, None, options, max_unknowns=bad)
        with pytest.raises(ValueError, match="max_pieces must be a whole number"):
            st.trace_within_default_reach(fig, None, options, max_pieces=bad)
    # too many pieces, whatever the unknowns: a drawing's IPOPT iterations grow with its pieces
    pieces = sum(len(c.pieces) for c in fig.curves)
    reason = too_large_to_plan(fig, None, options, max_pieces=pieces - 1, max_unknowns=None)
    assert reason == f"{pieces} pieces, more than {pieces - 1}: larger than a school figure"
    assert too_large_to_plan(fig, None, options, max_pieces=pieces - 1, max_unknowns=size - 1) == (
        f"{size:,} unknowns in its programs, more than {size - 1:,} and {pieces} pieces, more than {pieces - 1}: "
        "larger than a school figure")
    assert too_large_to_plan(fig, None, options, max_pieces=pieces, max_unknowns=size) == ""


DATA = Path(__file__).parent / "data"


def test_every_school_figure_is_small_enough_for_the_default_reach_to_plan():
    # issue 15: a skater's figure is planned by default; the bounds are what keep drawings of
    # tens of thousands of unknowns (minutes of IPOPT) to the launch-glide-stop manoeuvres
    options = st.TraceOptions(speed=2.0, reach=0.288 * 1.7)
    sizes = {name: planner_figure_unknowns(st.school_figure(name, height=1.7), st.skater_params(height=1.7), options)
             for name in st.school_names()}
    assert max(sizes.values()) <= DEFAULT_PLAN_UNKNOWNS, sizes
    assert min(sizes.values()) > 1000  # a real count: 36 intervals or more a section
    for name in st.school_names():
        assert too_large_to_plan(st.school_figure(name, height=1.7), st.skater_params(height=1.7), options) == ""
    drawing = st.resolve(DATA / "svg-corpus" / "vivus-hi-there.svg", size="6m", tol="1mm").figure
    assert planner_figure_unknowns(drawing, None, options) > 5 * DEFAULT_PLAN_UNKNOWNS
    assert "pieces, more than 32: larger than a school figure" in too_large_to_plan(drawing, None, options)


def test_a_warm_start_that_goes_nowhere_is_given_up_for_its_fallbacks(monkeypatch):
    # svgpathtools-negative-scale at 6 m: one section's warm start, pinned at the cusps from the
    # launch-glide-stop guess, stays some 1e-2 off its constraints and ran on to its 500 iterations
    # (3.5 s) before it failed; the section then has a plan with free ends and is pinned again
    # from it. Only that first warm start is watched: the programs from a plan are not.
    from skatetrace.planning import planner
    from skatetrace.planning.nlp import GiveUp

    rule = planner._WARM_GIVE_UP
    assert isinstance(rule, GiveUp) and rule.iterations >= 200 and rule.violation <= 1e-3
    drawing = st.resolve(DATA / "svg-corpus" / "svgpathtools-negative-scale.svg", size="6m", tol="1mm").figure
    seen = []

    class Enough(Exception):
        pass

    def first_batch(jobs, workers, stage, **kw):
        sols = solve(jobs, workers, stage, **kw)
        seen.extend(zip(jobs, sols))
        raise Enough  # the warm starts are all this test looks at

    solve = planner.solve_programs
    monkeypatch.setattr(planner, "solve_programs", first_batch)
    with pytest.raises(Enough):
        plan_figure(drawing, options=st.TraceOptions(speed=2.0, reach=0.288 * 1.7, workers=1))
    assert len(seen) == 4 and all(job[1].give_up == rule and job[2] is None for job, _sol in seen)
    given_up = [sol for _job, sol in seen if sol.status == "Given_Up"]
    assert len(given_up) == 1 and not given_up[0].success
    assert given_up[0].iterations <= rule.iterations and "given up after" in given_up[0].message
    assert all(sol.success for _job, sol in seen if sol is not given_up[0])
    # from a plan (pinned again), the linked options: no rule
    spec, popts = seen[0][0][0][0], seen[0][0][1]
    again = planner._warm_job(spec, popts, (0.1, 0.0), (0.1, 0.0), guess=given_up[0])
    assert again[1].give_up is None and again[1].max_iter == planner._LINKED_ITER
    # a budget counts the given-up program as run on to its cap
    assert given_up[0].allowed == 500 and given_up[0].work == 500 * given_up[0].unknowns


def test_a_warm_start_that_crawls_along_a_feasible_valley_stalls_and_keeps_its_iterate(monkeypatch):
    # feather-aperture at 6 m: its circle's warm start (1,508 unknowns) meets its constraints within
    # 1e-7 from its 50th iteration on, its barrier at the least, while the objective creeps down
    # some 1 % in 50 iterations; it ran on to its 500 iterations (3.9 s) and failed, and the plan's
    # budget ran out before the figure was planned. Stalled, its last iterate is a feasible warm start.
    from skatetrace.planning import planner

    rule = planner._WARM_GIVE_UP
    assert rule.window >= 20 and 0.0 < rule.decrease <= 0.05 and rule.feasible <= 1e-5
    drawing = st.resolve(DATA / "svg-corpus" / "feather-aperture.svg", size="6m", tol="1mm").figure
    seen = []

    class Enough(Exception):
        pass

    def first_batch(jobs, workers, stage, **kw):
        seen.extend(zip(jobs, solve(jobs, workers, stage, **kw)))
        raise Enough  # the warm starts are all this test looks at

    solve = planner.solve_programs
    monkeypatch.setattr(planner, "solve_programs", first_batch)
    with pytest.raises(Enough):
        plan_figure(drawing, options=st.TraceOptions(speed=2.0, reach=0.288 * 1.7, workers=1))
    stalled = [sol for _job, sol in seen if sol.status == "Stalled"]
    assert len(stalled) == 1 and stalled[0].unknowns > 1000
    assert rule.iterations <= stalled[0].iterations + 1 < 500  # (IPOPT counts from its iteration 0)
    assert stalled[0].success and "stalled after" in stalled[0].message  # feasible: kept
    assert all(sol.success for _job, sol in seen)
