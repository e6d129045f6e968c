"""Rests at smooth joins: the same path, shorter sections, and the trace-and-verify loop."""

import math
from dataclasses import replace
from types import SimpleNamespace

import numpy as np
import pytest

from skatetrace import pipeline as rests_module
from skatetrace.errors import FigureFormatError
from skatetrace.figures.figure import REST, SMOOTH, Curve, Figure, Join
from skatetrace.figures.geometry import Pose, Segment
from skatetrace.dynamics.model import SleighParams
from skatetrace.dynamics.presets import skater_params
from skatetrace.pipeline import add_rests, middle_join, trace_and_verify
from skatetrace.tracing.sections import TraceOptions


def _s_curve():
    segs = (Segment(1.0, 1.0), Segment(-0.5, 2.0), Segment(0.0, 0.5), Segment(0.8, 1.5))
    return Curve(segs, (SMOOTH, SMOOTH, SMOOTH), start=Pose(0.3, -0.2, 0.4), name="s")


def test_a_rest_keeps_the_path_and_splits_the_section():
    c = _s_curve()
    r = c.with_rests([2])
    assert [p.start for p in r.layout()] == [p.start for p in c.layout()]
    assert [p.direction for p in r.layout()] == [p.direction for p in c.layout()]
    assert [len(s.pieces) for s in c.sections()] == [4]
    assert [[p.index for p in s.pieces] for s in r.sections()] == [[0, 1], [2, 3]]
    assert r.joins[1] == REST and REST.is_cusp and REST.pivot == 0.0 and not REST.reverse


def test_rests_only_at_smooth_joins():
    c = Curve((Segment(1.0, 1.0), Segment(1.0, 1.0)), (Join("cusp", 0.5),))
    for bad in ([1], [0], [5]):
        with pytest.raises(FigureFormatError, match="smooth join"):
            c.with_rests(bad)
    assert c.with_rests([]) is c


def test_a_repeated_curve_is_listed_out_with_its_closure():
    unit = Curve((Segment(1.0, math.pi / 2), Segment(-1.0, math.pi / 4)), (SMOOTH,), repeat=4,
                 closing=Join("cusp", math.radians(-45.0)))
    r = unit.with_rests([3])
    assert r.repeat == 1 and len(r.pieces) == 8
    assert [p.start for p in r.layout()] == [p.start for p in unit.layout()]
    assert r.closure() == pytest.approx(unit.closure())
    assert len(r.sections()) == len(unit.sections()) + 1


def test_middle_join_is_nearest_half_the_length():
    sec = _s_curve().sections()[0]  # lengths 1, 2, 0.5, 1.5: half is 2.5, joins at 1, 3, 3.5
    assert middle_join(sec) == 2
    single = Curve((Segment(1.0, 1.0),)).sections()[0]
    assert middle_join(single) is None


def test_a_section_that_fails_again_is_also_split_by_count_of_pieces():
    # four long pieces, then twelve short ones (a tight loop drawn as many small arcs)
    segs = (Segment(0.1, 4.0),) * 4 + tuple(Segment(5.0 * (-1) ** k, 0.05) for k in range(12))
    sec = Curve(segs, (SMOOTH,) * 15).sections()[0]
    assert middle_join(sec) == 2  # half of the length, 8.3, is nearest the join at 8 (before piece 2)
    assert rests_module._split_joins(sec, again=False) == [2]
    assert rests_module._split_joins(sec, again=True) == [2, 8]
    # where the two middles are a quarter of the pieces apart or nearer, only the one by length
    even = _s_curve().sections()[0]
    assert rests_module._split_joins(even, again=True) == [middle_join(even)] == [2]
    single = Curve((Segment(1.0, 1.0),)).sections()[0]
    assert rests_module._split_joins(single, again=True) == []


def _untraceable_stretch(monkeypatch, hard: int):
    """A stand-in tracer: a section of several pieces that holds piece ``hard`` is not traced, every
    other section is, and every traced one verifies."""
    def fake_trace(figure, params, options, **kw):
        sections = [SimpleNamespace(curve_index=ci, section=s, success=len(s.pieces) == 1
                                    or all(p.index != hard for p in s.pieces), message="no stop")
                    for ci, c in enumerate(figure.curves) for s in c.sections()]
        return SimpleNamespace(sections=sections, success=all(s.success for s in sections), options=options,
                               message="no stop")

    def fake_sampled(trace, rel_tol):
        report = SimpleNamespace(success=True, message="ok", sections=[{"passed": True} for _ in trace.sections])
        return None, {}, report

    monkeypatch.setattr(rests_module, "trace_figure", fake_trace)
    monkeypatch.setattr(rests_module, "_sampled_and_verified", fake_sampled)
    monkeypatch.setattr(rests_module, "_finish", lambda result, limits: result)


def test_a_stretch_that_fails_to_trace_is_cut_into_rather_than_peeled(monkeypatch):
    # Four long pieces and twelve short ones of unlike lengths (no ties of the middle), the tenth
    # piece untraceable in any section of several: halved by length alone, the short stretch is
    # only peeled of its neighbours, a round each. Where a part fails again it is also halved by count.
    segs = (Segment(0.1, 4.0),) * 4 + tuple(Segment(5.0 * (-1) ** k, 0.05 + 0.003 * k) for k in range(12))
    fig = Figure("loop", (Curve(segs, (SMOOTH,) * 15),))
    _untraceable_stretch(monkeypatch, hard=9)
    res = trace_and_verify(fig, rests="auto")
    # the first time a section fails it is halved by length only, as a replay that strays needs
    assert res.success and res.rests[0] == (0, middle_join(fig.curves[0].sections()[0])) == (0, 2)
    assert {(0, 9), (0, 10)} <= set(res.rests)  # the untraceable piece ends alone ...
    by_length = rests_module._split_joins
    monkeypatch.setattr(rests_module, "_split_joins", lambda section, again: by_length(section, False))
    peeled = trace_and_verify(fig, rests="auto")
    assert peeled.success
    assert res.rounds <= peeled.rounds - 2 and len(res.rests) <= len(peeled.rests)  # ... sooner, with no more rests


def test_auto_splits_failing_sections_and_those_before_them(monkeypatch):
    # A stand-in verification that fails every section of more than one piece: the loop must halve
    # sections (and the ones before a failing one) until each is a single piece, then pass.
    fig = Figure("s", (_s_curve(),))

    def fake_verify(trace, schedule, rel_tol):
        secs = [{"passed": len(s.section.pieces) == 1} for s in trace.sections]
        ok = all(s["passed"] for s in secs)
        return SimpleNamespace(success=ok, sections=secs, message="ok" if ok else "too far")

    monkeypatch.setattr(rests_module, "verify", fake_verify)
    monkeypatch.setattr(rests_module, "schedule_from_trace", lambda trace: (None, {}))
    monkeypatch.setattr(rests_module, "_finish", lambda result, limits: result)  # no rows to assess
    res = trace_and_verify(fig, rests="auto")
    assert res.success and res.rounds == 3
    assert sorted(res.rests) == [(0, 1), (0, 2), (0, 3)]
    assert [len(s.pieces) for s in res.figure.curves[0].sections()] == [1, 1, 1, 1]
    never = trace_and_verify(fig, rests="never")
    assert not never.success and never.rests == () and never.rounds == 1
    # With no round of rests in the middle, the last resort rests at every join of the failing section.
    capped = trace_and_verify(fig, rests="auto", max_rounds=0)
    assert capped.success and capped.rounds == 2 and sorted(capped.rests) == [(0, 1), (0, 2), (0, 3)]


def test_bad_policy_is_refused():
    fig = Figure("s", (_s_curve(),))
    with pytest.raises(ValueError, match="auto, never, joins"):
        trace_and_verify(fig, rests="sometimes")


def test_a_launch_back_through_a_whole_circle_is_ill_conditioned_and_a_rest_at_the_waist_fixes_it(monkeypatch):
    # A figure eight of two 1.5 m circles for a real skater (SI units), the second circle longer by
    # 1e-9 so that the glide lies on it: the launch then runs back through the whole first circle,
    # a long open-loop manoeuvre whose replay amplifies any error of the controls. With a rest at
    # the waist both circles are launched and stopped within themselves.
    #
    # How far the unrested replay strays is round-off's doing, not the physics': perturbing the
    # sampled controls by 1e-15..1e-12 (relative) spreads it over 2.3e-7..6e-5 m (30 draws), on
    # both sides of a 1e-7 x size tolerance (6e-7 m). So the outcome is not asserted from round-off:
    # the controls are perturbed by a seeded 1e-9 (relative), a million times round-off, and the
    # robust fact is asserted, the conditioning: over 16 seeds the single section strays by
    # 1.2e-4..4.2e-3 m (median 8.4e-4), the two rested ones by 4.6e-7..7.6e-6 m (median 1.9e-6),
    # amplification factors of about 3e6 and 3e3. Seed 0 gives 7.8e-4 and 2.2e-6 m; the tolerance,
    # 5e-6 x size = 3e-5 m, sits geometrically between them (26x and 14x away).
    R = 1.5
    segs = (Segment(1 / R, 2 * math.pi * R), Segment(-1 / R, 2 * math.pi * R * (1 + 1e-9)))
    fig = Figure("eight", (Curve(segs, (SMOOTH,)),), skater_params())
    opts = TraceOptions(speed=2.0, placement="first")  # the default picks a placement that needs no rest
    # Unperturbed, with a rest at the waist the replay stays within 1e-7 x size: 7e-9..8e-8 m over
    # the same 30 draws of round-off-sized perturbations, at least 7x inside.
    joins = trace_and_verify(fig, options=opts, rests="joins", rel_tol=1e-7)
    assert joins.rests == ((0, 1),) and joins.rounds == 1 and joins.success, joins.message

    real_verify = rests_module.verify

    def perturbed_verify(trace, schedule, rel_tol):
        rng = np.random.default_rng(0)
        noisy = {c: getattr(schedule, c) * (1.0 + 1e-9 * rng.standard_normal(schedule.t.size))
                 for c in ("a", "b", "adot", "bdot")}
        return real_verify(trace, replace(schedule, **noisy), rel_tol=rel_tol)

    monkeypatch.setattr(rests_module, "verify", perturbed_verify)
    never = trace_and_verify(fig, options=opts, rests="never", rel_tol=5e-6)
    assert never.trace.success and not never.report.success
    assert never.report.max_deviation > 3.0 * never.report.tolerance  # measured 26x
    auto = trace_and_verify(fig, options=opts, rests="auto", rel_tol=5e-6)
    assert auto.success and auto.rests == ((0, 1),) and auto.rounds == 2, auto.message
    assert auto.report.max_deviation < 0.3 * auto.report.tolerance  # measured 0.07
    # orders of magnitude better conditioned: measured 2.2e-6 / 7.8e-4 = 0.003
    assert auto.report.max_deviation < 0.03 * never.report.max_deviation
    # "at rest" is judged against the fastest motion in each section: here the mass, relative to
    # the ice, moving several times faster than the 2 m/s glide
    for checks, sec in zip(auto.report.sections, auto.trace.sections):
        mass_peak = math.sqrt(2.0 * sec.metrics["peak_mass_kinetic_energy"] / sec.params.m)
        assert checks["speed_scale"] >= 0.99 * mass_peak > 2.0 * opts.speed
        assert checks["cusp_speed_limit"] == pytest.approx(1e-8 * checks["speed_scale"])
        assert max(checks["start_speed"], checks["end_speed"]) < 0.3 * checks["cusp_speed_limit"]  # measured < 0.11


def test_least_reach_placement_keeps_the_mass_closer_than_the_first_that_works():
    # the school change three's first section (an arc, the change of edge, the next arc) for a 1.7 m
    # skater: the first placement that works glides with the mass 21 m from the blade; another
    # keeps it within 0.2 m
    from skatetrace.figures.school import school_figure
    from skatetrace.tracing.sections import trace_section

    sec = school_figure("change-three", height=1.7).curves[0].sections()[0]
    params = skater_params(height=1.7)
    first = trace_section(params, sec, TraceOptions(speed=2.0, placement="first"))
    least = trace_section(params, sec, TraceOptions(speed=2.0))
    reach = [max(t.metrics["max_abs_a"], t.metrics["max_abs_b"]) for t in (first, least)]
    assert first.success and least.success
    assert reach[1] < 0.1 * reach[0], reach  # measured 21.1 m and 0.196 m
    assert least.nfev > first.nfev  # every placement was tried
    with pytest.raises(ValueError, match="placement"):
        TraceOptions(placement="best")


def test_search_bounds_the_placements_tried_after_the_first_that_works():
    from skatetrace.figures.school import school_figure
    from skatetrace.tracing.sections import trace_section

    sec = school_figure("three", height=1.7).curves[0].sections()[1]
    params = skater_params(height=1.7)
    first = trace_section(params, sec, TraceOptions(speed=2.0, placement="first"))
    none_more = trace_section(params, sec, TraceOptions(speed=2.0, search=0))
    assert none_more.glide == first.glide and none_more.nfev == first.nfev
    with pytest.raises(ValueError, match="search"):
        TraceOptions(search=-1)


def test_max_placements_gives_up_on_a_section_after_that_many_placements_none_of_which_worked(monkeypatch):
    # issue 19: a zigzag read as one smooth section of 585 arcs has some 3,000 placements, which all
    # fail there (minutes); a section gives up after max_placements of them
    from skatetrace.figures.school import school_figure
    from skatetrace.tracing import sections as tracing

    sec = school_figure("three", height=1.7).curves[0].sections()[1]
    params = skater_params(height=1.7)
    tried = []
    assemble = tracing._assemble
    monkeypatch.setattr(tracing, "_assemble", lambda *a: tried.append(r := assemble(*a)) or r)
    # one placement at a time, here (a long search goes on in batches side by side: some are then
    # solved ahead, in children, that the search never uses)
    first = tracing.trace_section(params, sec, TraceOptions(speed=2.0, placement="first", workers=1))
    k = len(tried)
    assert first.success and k > 1 and not any(t.success for t in tried[:-1])
    assert tracing.trace_section(params, sec, TraceOptions(speed=2.0, placement="first", max_placements=k)).glide \
        == first.glide
    # Of the first three placements none works: one only for want of the stop's full-accuracy
    # fallbacks (a first search goes without them), the others with them too; the second search,
    # with them, solves that one again and gives up after as many placements. The seventh works
    # only with the fallbacks, so a search of seven finds it in its second round.
    tried.clear()
    short = tracing.trace_section(params, sec, TraceOptions(speed=2.0, max_placements=3, workers=1))
    deferred = sum("fallback" in t.message for t in tried[:3])
    assert not short.success and not short.phases and deferred and len(tried) == 3 + deferred
    total = len(tracing.glide_candidates(params, sec.segments, 0, 0.1, TraceOptions())) \
        + len(tracing.glide_candidates(params, sec.segments, 1, 0.1, TraceOptions()))
    assert f"gave up after 3 of its {total} glide placements" in short.message
    tried.clear()
    seven = tracing.trace_section(params, sec, TraceOptions(speed=2.0, max_placements=7, workers=1))
    assert seven.success and not any(t.success for t in tried[:7]) and any(t.success for t in tried[7:])
    for bad in (0, -1, 2.0, True):
        with pytest.raises(ValueError, match="max_placements"):
            TraceOptions(max_placements=bad)


def test_auto_stops_adding_rests_when_two_rounds_in_a_row_verify_no_more_of_the_figure(monkeypatch):
    # issue 19: every round doubles the sections to trace; where halving stops helping (a zigzag:
    # no piece of it traced in 10, 16, 42 s rounds) the loop ends with a note
    segs = tuple(Segment(0.3 * (-1) ** k, 1.0) for k in range(8))
    fig = Figure("z", (Curve(segs, (SMOOTH,) * 7, name="z"),))
    monkeypatch.setattr(rests_module, "schedule_from_trace", lambda trace: (None, {}))
    monkeypatch.setattr(rests_module, "_finish", lambda result, limits: result)

    def verifier(passes):
        def fake_verify(trace, schedule, rel_tol):
            secs = [{"passed": passes(s.section)} for s in trace.sections]
            ok = all(s["passed"] for s in secs)
            return SimpleNamespace(success=ok, sections=secs, message="ok" if ok else "too far")
        return fake_verify

    monkeypatch.setattr(rests_module, "verify", verifier(lambda sec: False))
    res = trace_and_verify(fig, rests="auto")
    # rounds 2 and 3 (2 and 4 sections) verified nothing more than round 1; the last resort, a rest
    # at every join of the failing sections (8 sections of a piece each), verified no more, and the
    # third round's result is kept, the round counted
    assert not res.success and res.rounds == 4 and len(res.trace.sections) == 4
    assert "stopped adding rests in the middle of failing sections after 3 rounds" in res.message
    assert "a rest at each of the 4 smooth joins of the sections left failing verified no more" in res.message
    # a round that verifies more keeps the loop going: the last quarter verifies in round 3, and
    # round 4 splits the sections before it into single pieces
    monkeypatch.setattr(rests_module, "verify", verifier(lambda sec: [p.index for p in sec.pieces] in ([6, 7], [7])))
    res = trace_and_verify(fig, rests="auto")
    assert res.rounds == 4 and len(res.trace.sections) == 7 and not res.success and not res.note  # [6, 7] kept
    never = trace_and_verify(fig, rests="never")
    assert never.note == ""


def test_add_rests_keeps_the_path_and_only_touches_the_named_curve():
    a = Curve((Segment(1.0, 1.0), Segment(-1.0, 1.0), Segment(0.0, 1.0)), (SMOOTH, SMOOTH), name="a")
    b = Curve((Segment(0.5, 1.0), Segment(0.0, 1.0)), (SMOOTH,), name="b")
    fig = Figure("two", (a, b))
    out = add_rests(fig, [(0, 2)])
    assert out.curves[0].joins == (SMOOTH, REST) and out.curves[1] == b
    for p, q in zip(fig.curves[0].layout(), out.curves[0].layout()):
        assert tuple(p.start) == pytest.approx(tuple(q.start), abs=1e-14)
    assert add_rests(fig, []) is fig
    with pytest.raises(FigureFormatError, match="does not follow a smooth join"):
        add_rests(fig, [(1, 0)])


def _wiggle(n: int, curvature: float = 1.0, length: float = 0.8) -> Figure:
    """One smooth curve of ``n`` arcs, two to the left, two to the right, and so on."""
    segs = tuple(Segment(curvature * (-1) ** (k // 2), length) for k in range(n))
    return Figure("wiggle", (Curve(segs, (SMOOTH,) * (n - 1), name="wiggle"),))


def test_a_section_that_will_be_split_is_searched_less(monkeypatch):
    # split_on_failure: more than SHORT_SECTION pieces, no search with the stops' fallbacks; more
    # than LONG_SECTION, at most BRIEF_PLACEMENTS placements before one works
    from skatetrace.tracing import options as opts
    from skatetrace.tracing import sections as tracing
    from skatetrace.tracing.search import Searched

    searches = []

    def failing(placements, solve, options, settled):
        searches.append(options.max_placements)
        failed = tracing.SectionTrace(success=False, status=tracing.TraceStatus.NO_STOP, message="no stop",
                                      curve_index=0, section=sec, params=params, speed=1.0, glide={})
        return Searched(best=None, first_failure=failed, attempts=1, nfev=3, deferred=True, settled={})

    monkeypatch.setattr(tracing, "search_placements", failing)
    params = SleighParams()
    for pieces, split, wanted in ((opts.SHORT_SECTION, True, [256, 256]), (opts.SHORT_SECTION + 1, True, [256]),
                                  (opts.LONG_SECTION, True, [256]), (opts.LONG_SECTION + 1, True, [opts.BRIEF_PLACEMENTS]),
                                  (opts.LONG_SECTION + 1, False, [256, 256])):
        searches.clear()
        sec = _wiggle(pieces).curves[0].sections()[0]
        out = tracing.trace_section(params, sec, TraceOptions(split_on_failure=split))
        assert searches == wanted, (pieces, split)
        assert not out.success and out.nfev == 3 * len(wanted)
        assert ("to be split by a rest" in out.message) == (len(wanted) == 1)
    with pytest.raises(ValueError, match="split_on_failure"):
        TraceOptions(split_on_failure="yes")


def test_a_section_searched_less_is_traced_the_same_where_it_is_traced():
    from skatetrace.tracing import sections as tracing

    sec = _wiggle(40).curves[0].sections()[0]
    params = SleighParams()
    full, brief = (tracing.trace_section(params, sec, TraceOptions(split_on_failure=split, workers=1))
                   for split in (False, True))
    assert full.success and brief.success and brief.nfev == full.nfev and brief.glide == full.glide
    assert [ph.t1 for ph in brief.phases] == [ph.t1 for ph in full.phases]


def test_only_a_section_whose_replay_strayed_splits_the_sections_before_it():
    def sec(curve, traced=True, passed=True):
        return SimpleNamespace(curve_index=curve, success=traced), {"passed": traced and passed}

    def split(*rows):
        sections = [r[0] for r in rows]
        passed = [r[0].success and r[1]["passed"] for r in rows]
        chosen = [id(s) for s in rests_module._to_split(sections, passed)]
        return [k for k, s in enumerate(sections) if id(s) in chosen]

    # an untraced section has no replay: the next starts afresh, and those before it passed
    assert split(sec(0), sec(0), sec(0, traced=False), sec(0)) == [2]
    # a replay that strays may carry an error from before it: its curve is split up to it
    assert split(sec(0), sec(0, passed=False), sec(0), sec(0, traced=False)) == [0, 1, 3]
    # ... and only its own curve
    assert split(sec(0), sec(1), sec(1, passed=False)) == [1, 2]
    assert split(sec(0), sec(1)) == []


def test_a_section_left_failed_by_a_short_search_is_searched_in_full_when_the_rests_end(monkeypatch):
    # Every section of several pieces fails its short search here; when rests are no longer added
    # (max_rounds, or rounds that verify nothing more), those left failed are searched in full once.
    fig = _wiggle(6)
    flags = []
    real = rests_module.trace_figure

    def short_searches_fail(figure, params, options, **kw):
        flags.append(options.split_on_failure)
        trace = real(figure, params, options, **kw)
        if not options.split_on_failure:
            return trace
        failed = [replace(s, success=False, status=s.status.NO_STOP, message="given up", phases=())
                  if len(s.section.pieces) > 1 else s for s in trace.sections]
        return replace(trace, sections=tuple(failed))

    monkeypatch.setattr(rests_module, "trace_figure", short_searches_fail)
    res = trace_and_verify(fig, rests="auto", max_rounds=0)
    assert flags == [True, False] and res.success and res.rounds == 2 and res.rests == ()
    assert not res.trace.options.split_on_failure
    flags.clear()
    res = trace_and_verify(fig, rests="auto", max_rounds=1)  # one rest, then its two halves in full
    assert flags == [True, True, False] and res.success and res.rounds == 3 and res.rests == ((0, 3),)
    assert [len(s.section.pieces) for s in res.trace.sections] == [3, 3]
    flags.clear()
    assert trace_and_verify(fig, rests="never").success and flags == [False]


def test_a_round_that_leaves_a_long_section_failed_is_not_counted_against_the_rests():
    # A wiggle of 80 arcs: its sections of 80, 40 and 20 pieces have no stop, those of 10 trace.
    # Two rounds in a row that verify nothing more end the rests, but not while a failed section
    # has more than LONG_SECTION pieces (given up soon, and splitting is what traces it).
    from skatetrace.tracing.options import LONG_SECTION

    fig = _wiggle(80, curvature=2.0, length=0.5)
    res = trace_and_verify(fig, rests="auto")
    assert res.success and not res.note and res.rounds >= 4
    assert max(len(s.section.pieces) for s in res.trace.sections) < LONG_SECTION
    capped = trace_and_verify(fig, rests="auto", max_rounds=2)  # the rounds still end at max_rounds
    # three rounds, the search in full, then the last resort: a rest at every join of what still fails
    assert capped.success and capped.rounds == 5
    assert max(len(s.section.pieces) for s in capped.trace.sections) == 1 < len(capped.trace.sections)


def test_sections_still_failing_when_the_rounds_end_are_rested_at_every_join():
    """Three arcs of a few millimetres from a random drawing of Béziers at 6 m (radius 1.5 mm, then 6.7 mm,
    then a line). In that drawing their section, with four more pieces, had no stop; halving it in
    the middle found nothing in ten rounds (19 s) and left the drawing failed. Alone, the three are
    traced as one section, but its replay strays 1.3e-8 from them, beyond 1e-6 of their 8.7 mm
    (the same 1.3e-8 with the curvatures moved by 1e-9 or 1e-6 of themselves: not round-off). With
    no round of rests (``max_rounds=0``) the last resort rests at both joins, and each arc is traced
    and verified on its own. Before 2026-11-29 the figure was left failed."""
    pieces = (Segment(-657.7214395732998, 0.0026560329736021616), Segment(150.37451415725394, 0.0023430528604097465),
              Segment(0.0, 0.004692937739051344))
    fig = Figure("tiny-arcs", (Curve(pieces, (SMOOTH, SMOOTH), name="tiny"),), skater_params(height=1.7))
    options = TraceOptions(speed=2.0)
    assert not trace_and_verify(fig, options=options, rests="never").success
    res = trace_and_verify(fig, options=options, rests="auto", max_rounds=0)
    assert res.success and res.rounds == 2 and sorted(res.rests) == [(0, 1), (0, 2)]
    assert [len(s.section.pieces) for s in res.trace.sections] == [1, 1, 1]
