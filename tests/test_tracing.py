"""Exact tracing of sections, re-simulated through the full dynamics by the independent replay."""

import math

import numpy as np
import pytest

from skatetrace import Curve, Figure, Join, Segment, SleighParams, TraceOptions, trace_figure, verify
from skatetrace.figures.patterns import pattern
from skatetrace.tracing.sections import TraceStatus

P = SleighParams()


def _single(seg, join=None):
    return Figure("t", (Curve((seg,), name="t"),))


@pytest.mark.parametrize("seg", [Segment(1 / 1.2, 1.1 * math.pi * 1.2), Segment(-1 / 0.8, 0.2 * math.pi * 0.8),
                                 Segment(0.0, 2.0), Segment(1.0, math.pi)])
def test_single_piece_is_traced_exactly_and_replays_onto_it(seg):
    fig = _single(seg)
    tr = trace_figure(fig, P)
    assert tr.success, tr.message
    sec = tr.sections[0]
    assert max(sec.residuals.values()) <= 1e-10
    rep = verify(tr)
    assert rep.success, rep.message
    assert rep.max_deviation <= 1e-8 * max(1.0, fig.size())
    assert rep.max_cusp_speed <= 1e-8
    # invariants of the replay: p1 + r p2 on arcs, p2 on lines
    for d in rep.invariant_drift:
        assert d["drift"] <= 1e-8 * max(1.0, d["scale"]), d


def test_solver_curvature_condition_holds_along_the_section():
    tr = trace_figure(_single(Segment(1 / 1.2, 2.0)), P)
    sec = tr.sections[0]
    t = np.linspace(0, sec.duration, 301)[1:-1]
    v = sec.evaluate(t)
    assert np.max(np.abs(v["xi1"] - v["xi2"] / 1.2)) < 1e-9
    assert np.all(v["xi2"] > 0)  # the blade moves forwards inside the section
    assert abs(sec.evaluate(np.array([0.0]))["xi2"][0]) < 1e-12
    assert abs(sec.evaluate(np.array([sec.duration]))["xi2"][0]) < 1e-12


def test_launch_is_the_mirror_of_the_stop():
    """Time reversal with a -> -a maps a stop onto a launch (the sleigh's mass centre is on the blade)."""
    tr = trace_figure(_single(Segment(1.0, 2.0)), P)
    sec = tr.sections[0]
    T = sec.duration
    t = np.linspace(0, 0.3 * T, 50)
    early, late = sec.evaluate(t), sec.evaluate(T - t)
    np.testing.assert_allclose(early["a"], -late["a"], atol=1e-9)
    np.testing.assert_allclose(early["b"], late["b"], atol=1e-9)


def test_smooth_arc_arc_line_section():
    fig = pattern("s-bend")
    tr = trace_figure(fig, P)
    assert len(tr.sections) == 1 and tr.success, tr.message
    rep = verify(tr)
    assert rep.success, rep.message
    assert rep.max_deviation < 1e-8


def test_reversal_traces_backwards():
    rev = Join("cusp", 0.0, True)
    fig = Figure("rev", (Curve((Segment(1.0, 2.0), Segment(1.0, 2.0)), (rev,), name="rev"),))
    tr = trace_figure(fig, P)
    assert tr.success
    v = tr.sections[1].evaluate(np.linspace(0.1, tr.sections[1].duration - 0.1, 20))
    assert np.all(v["xi2"] < 0)
    rep = verify(tr)
    assert rep.success, rep.message


def test_time_scaling_changes_durations_not_paths():
    fig = _single(Segment(1.0, 2.0))
    slow = trace_figure(fig, P, TraceOptions(speed=1.0)).sections[0]
    fast = trace_figure(fig, P, TraceOptions(speed=2.0)).sections[0]
    assert fast.duration == pytest.approx(slow.duration / 2, rel=1e-12)
    a = slow.evaluate(np.linspace(0, slow.duration, 30))
    b = fast.evaluate(np.linspace(0, fast.duration, 30))
    np.testing.assert_allclose(a["a"], b["a"], atol=1e-12)
    np.testing.assert_allclose(2 * a["adot"], b["adot"], atol=1e-10)


def test_singular_set_is_detected():
    """With the mass gliding right at the singular point the tracer must refuse, not return garbage."""
    k = 1.0
    opts = TraceOptions(glide_lateral=-k * P.I / P.M)
    tr = trace_figure(_single(Segment(k, 2.0)), P, opts)
    assert not tr.success
    assert tr.sections[0].status.name in {"SINGULAR", "NO_STOP", "NO_LAUNCH"}
    assert tr.sections[0].message


def test_reported_singular_distance_matches_the_controls():
    k = 1 / 0.8
    tr = trace_figure(_single(Segment(k, 1.0)), P, TraceOptions(glide_lateral=-0.5))
    sec = tr.sections[0]
    assert sec.success
    v = sec.evaluate(np.linspace(0, sec.duration, 4001))
    independent = np.min(np.hypot(v["a"], v["b"] + k * P.I / P.M))
    assert sec.metrics["min_singular_distance"] == pytest.approx(independent, rel=1e-3)
    assert independent <= 1.375 + 1e-12  # never farther than the glide position


def test_failed_section_does_not_lose_the_others():
    opts = TraceOptions(glide_lateral=-P.I / P.M)  # singular for curvature 1, harmless on the line
    fig = Figure("mix", (Curve((Segment(0.0, 1.0), Segment(1.0, 2.0)), (Join("cusp"),), name="mix"),))
    tr = trace_figure(fig, P, opts)
    assert tr.sections[0].success and not tr.sections[1].success
    rep = verify(tr)
    assert not rep.success
    assert rep.sections[0]["traced"] and rep.sections[0]["max_deviation_replay_to_figure"] < 1e-8


@pytest.mark.slow
@pytest.mark.parametrize("name", ["double-flower", "double-flower-cusps"])
def test_double_flower_end_to_end(name):
    fig = pattern(name)
    tr = trace_figure(fig)
    assert tr.success
    assert max(max(s.residuals.values()) for s in tr.sections) <= 1e-10
    rep = verify(tr)
    assert rep.success, rep.message
    assert rep.max_deviation <= 1e-6 * fig.size()
    assert rep.max_cusp_speed <= 1e-8
    for c in fig.curves:
        assert c.closure()["closed"]


def test_smooth_inflection_s_curve():
    """Arc into an arc of the opposite turn, joined smoothly: needs the glide on the accelerating side."""
    fig = Figure("s", (Curve((Segment(1.0, 1.0), Segment(-1.0, 1.0)), (Join("smooth"),), name="s"),))
    tr = trace_figure(fig, P)
    assert tr.success, tr.message
    rep = verify(tr)
    assert rep.success, rep.message
    assert rep.max_deviation < 1e-6


def test_implausible_solutions_are_refused():
    """A solve whose mass would wander off is reported as a failure, never returned as a success."""
    fig = Figure("s3", (Curve((Segment(1.0, 1.5), Segment(-1.0, 1.5), Segment(1.0, 1.5)),
                              (Join("smooth"), Join("smooth")), name="s3"),))
    tr = trace_figure(fig, P)
    sec = tr.sections[0]
    if sec.success:  # if a solution is found it must be a real one
        rep = verify(tr)
        assert rep.success, rep.message
    else:
        assert sec.status.name in {"EXCURSION", "NO_STOP", "NO_LAUNCH", "SINGULAR", "RESIDUAL"}
        assert sec.message


def test_one_sided_limits_at_a_smooth_join():
    """At a smooth join the state is continuous and the curvature held jumps from one side to the other."""
    tr = trace_figure(pattern("s-bend"), P)
    sec = tr.sections[0]
    k0, k1 = (p.segment.curvature for p in sec.section.pieces[:2])
    tj = sec.time_at_length(sec.section.pieces[0].segment.length)
    left, right = sec.evaluate([tj], side="left"), sec.evaluate([tj], side="right")
    for key in ("p1", "p2", "a", "b", "x", "y", "theta"):
        assert left[key][0] == pytest.approx(right[key][0], abs=1e-9)
    assert left["xi1"][0] == pytest.approx(k0 * left["xi2"][0], abs=1e-9)
    assert right["xi1"][0] == pytest.approx(k1 * right["xi2"][0], abs=1e-9)
    assert abs(right["adot"][0] - left["adot"][0]) + abs(right["bdot"][0] - left["bdot"][0]) > 1e-3
    assert (left["segment"][0], right["segment"][0]) == (0, 1)
    with pytest.raises(ValueError, match="side"):
        sec.evaluate([tj], side="middle")


def test_time_at_length_at_joins_and_in_between():
    # joins are breakpoints and come back exactly; other lengths by bisection, to the time's rounding
    tr = trace_figure(pattern("s-bend"), P)
    sec = tr.sections[0]
    ends = np.cumsum([p.segment.length for p in sec.section.pieces])
    joins = sec.time_at_length(ends[:-1])
    assert set(joins.tolist()) <= set(sec.breakpoints().tolist())
    lengths = np.array([0.0, 0.137, 0.5 * ends[0], ends[0] + 0.25, 0.999 * ends[-1]])
    times = sec.time_at_length(lengths)
    assert times[0] == 0.0 and np.all(np.diff(times) > 0)
    np.testing.assert_allclose(sec.evaluate(times, geometry=False)["s"], lengths, rtol=0, atol=1e-12)
    assert sec.time_at_length(0.137) == times[1]  # a scalar in, a scalar out


def test_sections_after_a_failed_one_are_still_verified():
    opts = TraceOptions(glide_lateral=-P.I / P.M)  # the arc glides at its singular point: refused
    fig = Figure("mix2", (Curve((Segment(1.0, 2.0), Segment(0.0, 1.0)), (Join("cusp", 0.5),), name="mix2"),))
    tr = trace_figure(fig, P, opts)
    assert not tr.sections[0].success and tr.sections[1].success
    assert not tr.sections[0].phases  # failed controls are not handed on
    rep = verify(tr)
    assert not rep.success and not rep.sections[0]["traced"]
    assert rep.sections[1]["max_deviation_replay_to_figure"] < 1e-8
    assert rep.sections[1]["max_deviation_figure_to_replay"] < 1e-8


def test_evaluate_refuses_times_outside_the_section():
    sec = trace_figure(_single(Segment(1.0, 1.0)), P).sections[0]
    with pytest.raises(ValueError, match="span"):
        sec.evaluate([sec.duration * 1.01])
    with pytest.raises(ValueError, match="span"):
        sec.evaluate([-1e-3])
    assert sec.evaluate([sec.duration])["xi2"][0] == pytest.approx(0.0, abs=1e-12)


def test_evaluate_gives_each_time_its_state_whatever_the_order_of_the_times():
    # Times in order are shared out to the phases by bisection, others through their
    # order: every time gets, bit for bit, what it gets alone, on either side of the breakpoints.
    fig = Figure("s", (Curve((Segment(1 / 1.5, 2.0), Segment(0.0, 1.0), Segment(-1 / 2.5, 2.5)),
                             (Join("smooth"), Join("smooth")), name="s"),))
    sec = trace_figure(fig, P, TraceOptions(workers=1)).sections[0]
    assert len(sec.phases) == 3 and sum(len(ph.maneuver.legs) for ph in sec.phases if ph.maneuver) >= 3
    t = np.concatenate([np.linspace(0.0, sec.duration, 201), sec.breakpoints()])
    order = np.random.default_rng(5).permutation(t.size)
    for side in ("left", "right"):
        alone = [sec.evaluate([ti], side=side) for ti in t]
        for pick in (np.argsort(t, kind="stable"), np.arange(t.size), order, order[::-1]):
            got = sec.evaluate(t[pick], side=side)
            for key, values in got.items():
                np.testing.assert_array_equal(values, np.array([alone[i][key][0] for i in pick]), err_msg=key)


@pytest.mark.parametrize("seg", [Segment(0.1, 0.349), Segment(0.0, 0.01)])
def test_gentle_arcs_and_tiny_lines(seg):
    """A gently curved short arc (a stop from a = 0 would need the mass ~2/k away) and a 1 cm line."""
    tr = trace_figure(_single(seg), P)
    assert tr.success, tr.message
    sec = tr.sections[0]
    assert max(sec.metrics["max_abs_a"], sec.metrics["max_abs_b"]) < 5.0
    rep = verify(tr)
    assert rep.success, rep.message


# --------------------------------------------------------------------------------------------------
# spirals: curvature varying along the piece (exact mode)
# --------------------------------------------------------------------------------------------------
from skatetrace.figures.figure import SMOOTH  # noqa: E402
from skatetrace.figures.geometry import Spiral  # noqa: E402

_SPIRAL_SECTIONS = {
    "clothoid": (Spiral((0.2, 0.3, 0.0, 0.0), 2.0),),
    "clothoid-arc-cubic": (Spiral((0.2, 0.3, 0.0, 0.0), 2.0), Segment(0.8, 1.5),
                           Spiral((0.8, -0.4, 0.05, 0.01), 3.0)),
    "inflection": (Spiral((0.6, -0.5, 0.0, 0.0), 2.4),),
    "line-into-clothoid": (Segment(0.0, 1.0), Spiral((0.0, 0.5, 0.0, 0.0), 2.0)),
}


@pytest.mark.parametrize("name", sorted(_SPIRAL_SECTIONS))
def test_spiral_sections_are_traced_exactly(name):
    pieces = _SPIRAL_SECTIONS[name]
    fig = Figure(name, (Curve(pieces, (SMOOTH,) * (len(pieces) - 1), name=name),))
    tr = trace_figure(fig, P)
    assert tr.success, tr.message
    sec = tr.sections[0]
    assert max(sec.residuals.values()) <= 1e-10
    # the solver's own state obeys xi1 = kappa(s) xi2 with kappa read off the figure's pieces
    t = np.linspace(0.0, sec.duration, 2001)[1:-1]
    v = sec.evaluate(t)
    ends = np.cumsum([p.length for p in pieces])
    starts = ends - [p.length for p in pieces]
    kappa = np.array([float(pieces[i].curvature_at(s - starts[i])) for i, s in zip(v["segment"], v["s"])])
    assert np.max(np.abs(v["xi1"] - kappa * v["xi2"])) <= 1e-9 * np.max(np.abs(v["xi2"]))
    assert np.all(v["xi2"] > 0)
    # and the independent replay stays on the spiral
    rep = verify(tr)
    assert rep.success, rep.message
    assert rep.max_deviation <= 1e-7 * fig.size()
    assert rep.max_cusp_speed <= 1e-8
    assert all(d["piece"] in [p.index for p in fig.curves[0].layout() if p.segment.constant]
               for d in rep.invariant_drift)


def test_spiral_sections_are_cached_by_shape_not_confused_with_arcs():
    a = Curve((Spiral((0.5, 0.1, 0.0, 0.0), 1.0),), name="a")
    b = Curve((Segment(0.5, 1.0),), name="b")
    tr = trace_figure(Figure("ab", (a, b)), P)
    assert tr.success, tr.message
    assert tr.sections[0].phases != tr.sections[1].phases


def test_copies_of_a_shape_that_differ_by_round_off_are_traced_once():
    # nine dots of an icon differ in the last digits of their pieces (about 1e-11 of them): one
    # shape, traced once, each copy still laid out from its own pieces and verified against them
    from skatetrace.tracing.shapes import SHAPE_TOL

    rng = np.random.default_rng(3)
    base = [(1.6661106953181, 1.6517321274890), (1.6650919230777, 1.6490492460729)]
    curves = []
    for i in range(5):
        jitter = 1.0 + 2e-11 * rng.standard_normal((2, 2))
        segs = tuple(Segment(k * j0, L * j1) for (k, L), (j0, j1) in zip(base, jitter))
        curves.append(Curve(segs, (Join("smooth"),), name=f"dot{i}"))
    # and one whose curvature is 1e-6 of itself off: another shape
    curves.append(Curve((Segment(base[0][0] * (1 + 1e-6), base[0][1]), Segment(*base[1])), (Join("smooth"),),
                        name="other"))
    fig = Figure("dots", tuple(curves))
    tr = trace_figure(fig, P)
    assert tr.success, tr.message
    assert len({id(s.phases) for s in tr.sections[:5]}) == 1
    assert tr.sections[5].phases is not tr.sections[0].phases
    assert 2e-11 * 10 < SHAPE_TOL  # the jitter is well inside the tolerance
    rep = verify(tr)
    assert rep.success, rep.message


def test_the_shape_index_compares_lengths_and_turning_within_its_tolerance():
    from skatetrace.tracing.shapes import SHAPE_TOL, ShapeIndex, exact_key

    def key(*segs, params=P):
        fig = Figure("k", (Curve(tuple(Segment(k, L) for k, L in segs), (Join("smooth"),) * (len(segs) - 1)),))
        return exact_key(params, fig.curves[0].sections()[0], TraceOptions())

    index = ShapeIndex()
    first = key((0.5, 2.0), (0.0, 1.0))
    assert index.find(first) is first
    assert index.find(key((0.5 * (1 + 0.4 * SHAPE_TOL), 2.0 * (1 - 0.4 * SHAPE_TOL)), (0.0, 1.0 + 4e-10))) is first
    # beyond the tolerance in a length, in a turning (curvature times length), or in the pieces
    for other in (key((0.5, 2.0 * (1 + 3 * SHAPE_TOL)), (0.0, 1.0)),
                  key((0.5 + 3 * SHAPE_TOL / 2.0, 2.0), (0.0, 1.0)),
                  key((0.5, 2.0), (0.0, 1.0), (0.0, 1.0)),
                  key((0.5, 2.0), (0.0, 1.0), params=SleighParams(M=3.0, m=1.0, I=3.0))):
        assert index.find(other) is other
    # keys known beforehand (a cache of solved sections) are found again
    assert ShapeIndex([first]).find(key((0.5, 2.0), (0.0, 1.0 + 1e-13))) is first


def test_the_shape_index_finds_a_shape_across_the_edge_of_its_length_buckets():
    # Keys are kept in buckets of their section's length: two lengths within the tolerance on both
    # sides of a bucket's edge are one shape, and the first known is found, whichever bucket it is in.
    from skatetrace.tracing import shapes

    def key(length, kappa=0.0):
        fig = Figure("k", (Curve((Segment(kappa, length),), ()),))
        return shapes.exact_key(P, fig.curves[0].sections()[0], TraceOptions())

    edge = math.exp(123457 * shapes._BUCKET)
    below, above = key(edge * (1 - 2e-10)), key(edge * (1 + 2e-10))
    assert shapes._bucket(shapes._terms(below)) != shapes._bucket(shapes._terms(above))
    for first, second in ((below, above), (above, below)):
        index = shapes.ShapeIndex()
        other = key(edge * (1 - 2e-10), kappa=1.0)  # the same length, another shape
        assert index.find(other) is other and index.find(first) is first
        assert index.find(second) is first
    known = key(edge * (1 + 2e-10))  # known beforehand, then found from the bucket below
    assert shapes.ShapeIndex([known]).find(key(edge * (1 - 3e-10))) is known
    # two known shapes (1.2e-9 apart) on either side of the edge, both within the tolerance of a
    # third: the one known first is its shape, not the one in the bucket looked at first
    later, earlier = key(edge * (1 - 6e-10)), key(edge * (1 + 6e-10))
    assert shapes._bucket(shapes._terms(later)) < shapes._bucket(shapes._terms(earlier))
    assert shapes.ShapeIndex([earlier, later]).find(key(edge)) is earlier


# --------------------------------------------------------------------------------------------------
# issue 6: the shortcuts of the placement search change no choice
# --------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("seg", [Segment(1.25, 0.5026548245743669), Segment(1.0, math.pi)])
def test_pruned_search_and_mirrored_launches_choose_as_the_full_search(seg, monkeypatch):
    # the paper's second arc (three placements trace it, the last cannot beat the second) and
    # third (one glide at a = 0, whose launch is its stop reversed; the apexes on the axis lie
    # farther out than that glide's whole reach)
    from skatetrace.tracing import search
    from skatetrace.tracing import sections as tracing

    sec = _single(seg).curves[0].sections()[0]
    fast = tracing.trace_section(P, sec)
    monkeypatch.setattr(search, "_cannot_win", lambda *a: False)
    monkeypatch.setattr(tracing, "same_legs", lambda *a: False)
    full = tracing.trace_section(P, sec)
    assert fast.success and full.success
    assert fast.glide == full.glide and fast.metrics == full.metrics and fast.residuals == full.residuals
    for a, b in zip(fast.phases, full.phases, strict=True):
        assert (a.kind, a.t0, a.t1) == (b.kind, b.t0, b.t1)
    assert fast.nfev < full.nfev


def test_a_placement_search_in_batches_side_by_side_chooses_as_one_after_another(monkeypatch):
    # every placement of a long search solved in forked batches from the first on: the same choice,
    # the same integrations counted, as one after another
    import functools

    from skatetrace import processes
    from skatetrace.tracing import search
    from skatetrace.tracing import sections as tracing

    if not processes.can_fork() or processes.available_workers() < 2:
        pytest.skip("this test process may not fork, or has one core")
    fig = Figure("s", (Curve((Segment(1 / 1.5, 2.0), Segment(0.0, 1.0), Segment(-1 / 2.5, 2.5)),
                             (Join("smooth"), Join("smooth")), name="s"),))
    sec = fig.curves[0].sections()[0]
    here = tracing.trace_section(P, sec, TraceOptions(workers=1))
    made, real = [], processes.map_forked

    def forked(fn, items, workers=None):
        made.append(len(items))
        return real(fn, items, workers)

    monkeypatch.setattr(processes, "map_forked", forked)
    monkeypatch.setattr(search, "evaluated_ahead", functools.partial(processes.evaluated_ahead, alone_for=0.0,
                                                                     batch=2))
    batched = tracing.trace_section(P, sec, TraceOptions(workers=2))
    assert made and max(made) > 1  # batches were shared out
    assert here.success and batched.success
    assert (batched.glide, batched.metrics, batched.residuals, batched.nfev) == (here.glide, here.metrics,
                                                                                 here.residuals, here.nfev)
    t = np.linspace(0.0, here.duration, 101)
    for key in ("a", "b", "xi2"):
        np.testing.assert_array_equal(batched.evaluate(t, geometry=False)[key], here.evaluate(t, geometry=False)[key])


def test_placement_keys_within_rounding_are_a_tie_kept_by_the_first():
    from skatetrace.tracing.search import _improves

    assert _improves((0.9, 5.0), (1.0, 1.0))
    assert not _improves((1.1, 0.5), (1.0, 1.0))
    assert _improves((1.0 + 1e-14, 2.0), (1.0, 3.0))  # same reach: less energy wins
    assert not _improves((1.0 - 1e-14, 3.0 - 1e-13), (1.0, 3.0))  # a tie
    # the inflection spiral is symmetric under b -> -b about its middle: the apexes at b = +-2.5 are
    # mirror images and the first tried is kept, whatever the rounding of their solves
    fig = Figure("i", (Curve((Spiral((0.6, -0.5, 0.0, 0.0), 2.4),), name="i"),))
    assert trace_figure(fig, P).sections[0].glide["b"] == 2.5


def test_sections_traced_in_worker_processes_are_the_ones_traced_here(monkeypatch, pools_made):
    """Four distinct sections (and one repeated) in a pool of two: the same traces, in skating
    order, as one after another; the repeated section is still solved once."""
    from skatetrace.tracing import sections

    segs = [Segment(1.0 / r, 1.0 + 0.3 * i) for i, r in enumerate((1.5, 2.0, -2.5, 3.0))]
    pieces = tuple(segs + [segs[0]])
    fig = Figure("five", (Curve(pieces, tuple(Join("cusp") for _ in pieces[1:]), name="five"),))
    here = trace_figure(fig, P, TraceOptions(workers=1))
    progress = []
    monkeypatch.setattr(sections, "_POOL_WORTH", 0.0)  # the pool from the second section on
    pooled = trace_figure(fig, P, TraceOptions(workers=2), progress=lambda d, n: progress.append((d, n)))
    assert pools_made == [2]
    assert progress == [(i, 5) for i in range(1, 6)]
    assert here.success and pooled.success
    assert pooled.start_times == here.start_times
    for a, b in zip(here.sections, pooled.sections):
        assert a.residuals == b.residuals and a.glide == b.glide and a.duration == b.duration
        t = np.linspace(0.0, a.duration, 51)
        va, vb = a.evaluate(t, geometry=False), b.evaluate(t, geometry=False)
        for key in ("a", "b", "xi2"):
            np.testing.assert_array_equal(va[key], vb[key])
    assert pooled.sections[4].glide == pooled.sections[0].glide


def _pool_recorded(monkeypatch, wait):
    """The sections traced here and those handed to the pool (in order), a pool costing 0.2 s.

    ``wait(here)`` runs before each section traced here (``here``: those traced so far).
    """
    from skatetrace.tracing import sections

    here, pooled = [], []
    real_job = sections._trace_job

    def job(j):
        wait(here)
        here.append(j[1])
        return real_job(j)

    def run_jobs(fn, jobs, workers, chunk=1):
        pooled.extend(j[1] for j in jobs)
        return (real_job(j) for j in jobs)

    monkeypatch.setattr(sections, "_POOL_WORTH", 0.2)
    monkeypatch.setattr(sections, "_trace_job", job)
    monkeypatch.setattr(sections, "run_jobs", run_jobs)
    return here, pooled


@pytest.mark.parametrize("slow", ["first section", "loading the integrator"])
def test_after_a_long_first_section_the_others_go_to_the_pool(monkeypatch, slow):
    """The pool's threshold counts the sections' own time: a first section that takes longer sends
    every other section to the pool (not the next one here too, as when its time was taken for
    the integrator's loading); loading the integrator, however long, does not count."""
    import time

    from skatetrace.tracing import sections

    segs = [Segment(1.0 / r, 1.0 + 0.3 * i) for i, r in enumerate((1.5, 2.0, -2.5, 3.0))]
    fig = Figure("four", (Curve(tuple(segs), tuple(Join("cusp") for _ in segs[1:]), name="four"),))
    real_load = sections.load_integrator

    def load():
        if slow == "loading the integrator":
            time.sleep(0.3)
        real_load()

    here, pooled = _pool_recorded(monkeypatch, lambda done: time.sleep(0.3 if not done and slow == "first section"
                                                                         else 0.0))
    monkeypatch.setattr(sections, "load_integrator", load)
    tr = trace_figure(fig, P, TraceOptions(workers=2))
    assert tr.success
    sections_in_order = [s.section for s in tr.sections]
    if slow == "first section":
        assert here == sections_in_order[:1] and pooled == sections_in_order[1:]
    else:
        assert here == sections_in_order and pooled == []


def test_sections_go_to_the_pool_after_the_first_where_the_rest_would_take_longer_than_a_pool_costs(monkeypatch):
    """Twelve sections of 0.03 s or more each: after the first, the other eleven would take 0.33 s
    here, more than a pool costs (0.2 s here), and they go to the pool at once, not after 0.2 s."""
    import time

    segs = [Segment(1.0 / (1.5 + 0.1 * i), 1.0 + 0.1 * i) for i in range(12)]
    fig = Figure("twelve", (Curve(tuple(segs), tuple(Join("cusp") for _ in segs[1:]), name="twelve"),))
    here, pooled = _pool_recorded(monkeypatch, lambda done: time.sleep(0.03))
    tr = trace_figure(fig, P, TraceOptions(workers=2))
    assert tr.success
    sections_in_order = [s.section for s in tr.sections]
    assert here == sections_in_order[:1] and pooled == sections_in_order[1:]


@pytest.mark.parametrize("pieces, here, pooled", [
    ((1, 5, 1, 9, 3), [], [3, 1, 4, 0, 2]),  # several of many pieces: the pool, most pieces first
    ((1, 20, 1, 9, 3), [1], [3, 4, 0, 2]),  # one of more than all the others: here, first
    ((1, 1, 4, 1), [0, 1, 2, 3], []),  # one of several pieces: here, while they take little time
])
def test_sections_of_many_pieces_go_to_the_pool_longest_first(monkeypatch, pieces, here, pooled):
    """A section of several pieces takes 0.03 to 8 s, one of one piece milliseconds: where two or
    more have several, the longest-looking start first (in the pool, or here if it outweighs
    all the others), and the traces still come back in skating order."""
    from types import SimpleNamespace

    from skatetrace.tracing import sections

    ran_here, ran_pooled = [], []

    def job(j):
        ran_here.append(j[3])
        return f"trace {j[3]}"

    def run_jobs(fn, jobs, workers, chunk=1):
        ran_pooled.extend(j[3] for j in jobs)
        return (f"trace {j[3]}" for j in jobs)

    monkeypatch.setattr(sections, "_trace_job", job)
    monkeypatch.setattr(sections, "run_jobs", run_jobs)
    jobs = [(P, SimpleNamespace(pieces=(None,) * n), None, k) for k, n in enumerate(pieces)]
    assert list(sections._solve_sections(jobs, 2)) == [f"trace {k}" for k in range(len(pieces))]
    assert ran_here == here and ran_pooled == pooled


def test_a_small_figure_never_starts_a_pool(monkeypatch):
    from skatetrace import processes

    def refuse(*args, **kwargs):
        raise AssertionError("a pool for a figure traced in milliseconds")

    monkeypatch.setattr(processes, "ProcessPoolExecutor", refuse)
    tr = trace_figure(pattern("double-flower"), None, TraceOptions(workers=2))
    assert tr.success


# --------------------------------------------------------------------------------------------------
# issues 17 and 18: the search prefers stops found without the full-accuracy fallbacks
# --------------------------------------------------------------------------------------------------
def _counting_fallbacks(monkeypatch):
    """Count the calls of the stop's full-accuracy fallbacks (Brent on the bracket, Newton)."""
    from skatetrace.tracing import maneuver

    calls = []
    for name in ("_bracket_stop", "_polish_stop"):
        real = getattr(maneuver, name)
        monkeypatch.setattr(maneuver, name, lambda *a, _real=real, **k: calls.append(1) or _real(*a, **k))
    return calls


def test_a_placement_whose_stop_needs_the_fallbacks_gives_way_to_one_that_does_not(monkeypatch):
    # A section of an icon (feather-settings, a 1.7 m skater): a short line, an arc of radius 0.55 m
    # over 1.7 m, a shorter line. The glide at b = -0.129 (the line's singular point, one model
    # length off) has a stop that only the fallbacks find (its speed grazes zero before the end):
    # searched with them from the start, that placement was kept, with the fallbacks run on several
    # others. Without them, a placement nearer the blade (b = -0.086) is kept and they never run.
    from skatetrace.dynamics.presets import skater_params

    params = skater_params(height=1.7)
    curve = Curve((Segment(0.0, 0.04636363636363505), Segment(-1.833333333333332, 1.7135959928671607),
                   Segment(0.0, 0.024545454545454426)), (Join("smooth"), Join("smooth")), name="f")
    calls = _counting_fallbacks(monkeypatch)
    tr = trace_figure(Figure("f", (curve,)), params, TraceOptions(speed=2.0, workers=1))
    assert tr.success and not calls
    assert len(tr.sections) == 1 and len(tr.sections[0].section.pieces) == 3
    glide = tr.sections[0].glide
    assert glide["segment"] == 1 and glide["a"] == 0.0 and abs(glide["b"] + 0.0860) < 1e-3
    # the placement kept with the fallbacks reached 0.129 (its apex alone)
    assert max(tr.sections[0].metrics["max_abs_a"], tr.sections[0].metrics["max_abs_b"]) < 0.1
    report = verify(tr)
    assert report.success, report.message


def _recording_solves(monkeypatch):
    """Record each placement's manoeuvres: (its stop's legs and apex, fallback, stop found, deferred)."""
    from skatetrace.tracing import sections

    solves = []
    real = sections.solve_stop

    def recorded(params, legs, glide_ab, speed, **kw):
        sol = real(params, legs, glide_ab, speed, **kw)
        if kw.get("backward"):  # the launch of the placement whose stop was found last
            place, fallback, found, deferred = solves[-1]
            solves[-1] = (place, fallback, found, deferred or sol.deferred)
        else:
            solves.append(((tuple(legs), tuple(glide_ab)), kw["fallback"], sol.success, sol.deferred))
        return sol

    monkeypatch.setattr(sections, "solve_stop", recorded)
    return solves


def test_a_section_only_the_fallbacks_trace_is_searched_again_with_them(monkeypatch):
    # With the secant polish made to fail everywhere, every stop that a scan brackets needs the
    # fallbacks: the first search keeps nothing and the second traces the paper's second arc.
    from skatetrace.tracing import maneuver, sections

    monkeypatch.setattr(maneuver, "_refined_stop", lambda *a: (None, None))
    solves = _recording_solves(monkeypatch)
    tr = sections.trace_section(P, _single(Segment(1.25, 0.5026548245743669)).curves[0].sections()[0])
    assert tr.success and max(abs(v) for v in tr.residuals.values()) < 1e-10
    quick = [s for s in solves if not s[1]]
    assert quick and all(deferred and not found for _, _, found, deferred in quick)
    full = [s[0] for s in solves if s[1]]
    assert full and full == [s[0] for s in quick][:len(full)]  # the same placements, in the same order


def test_a_section_nothing_traces_solves_each_placement_once_with_the_fallbacks(monkeypatch):
    # A line into a tight arc (a line of 1, an arc of radius 0.5): no placement traces it, with or
    # without the fallbacks. The glides on the line fail for want of any stop (no bracket), so the
    # second search takes them from the first; only the placements that wanted the fallbacks are
    # solved again, and the failure keeps the first one's reason.
    from skatetrace.tracing import sections

    solves = _recording_solves(monkeypatch)
    fig = Figure("s", (Curve((Segment(0.0, 1.0), Segment(2.0, 1.0)), (Join("smooth"),), name="s"),))
    tr = sections.trace_section(P, fig.curves[0].sections()[0])
    assert not tr.success and tr.status is TraceStatus.NO_STOP
    assert "no stop of length 1.5 found" in tr.message and "tried 9 glide placements" in tr.message
    quick = [s for s in solves if not s[1]]
    full = [s for s in solves if s[1]]
    assert len(quick) == 9
    settled = [s[0] for s in quick if not s[3]]
    assert settled and not set(settled) & {s[0] for s in full}
    assert [s[0] for s in full] == [s[0] for s in quick if s[3]]
    assert tr.nfev > 0


def test_the_search_keeps_the_failures_it_need_not_solve_again_without_their_controls():
    # search_placements on stand-in traces: the deferred failures are said and not kept, the others
    # kept (without their controls) and taken from there by a second search, which solves the rest
    from skatetrace.tracing.search import Attempt, search_placements
    from skatetrace.tracing.sections import SectionTrace

    sec = _single(Segment(1.0, 1.0)).curves[0].sections()[0]

    def trace(ok, reach=1.0):
        return SectionTrace(success=ok, status=TraceStatus.SUCCESS if ok else TraceStatus.NO_STOP,
                            message="ok" if ok else "no stop", curve_index=0, section=sec, params=P, speed=1.0,
                            glide={}, phases=("controls",), metrics={"max_abs_a": reach, "max_abs_b": 0.0,
                                                                     "peak_mass_kinetic_energy": 1.0})

    placements = [(0, 0.0, 1.0, 0.1, (0.0, float(k)), True) for k in range(4)]
    outcome = {0: (False, True), 1: (False, False), 2: (False, True), 3: (False, False)}  # (works, deferred)
    solved = []

    def solve(p, bound):
        solved.append(p[4][1])
        works, deferred = outcome[int(p[4][1])]
        return Attempt(trace(works, reach=5.0), 10, deferred)  # farther than every apex: none is pruned

    opts = TraceOptions(workers=1)
    first = search_placements(iter(placements), solve, opts, {})
    assert first.best is None and first.deferred and first.attempts == 4 and first.nfev == 40
    assert sorted(first.settled) == [1, 3] and all(t.phases == () for t in first.settled.values())
    assert first.first_failure.phases == ("controls",)
    outcome.update({0: (True, False), 2: (True, False)})  # with the fallbacks, 0 and 2 work
    solved.clear()
    again = search_placements(iter(placements), solve, opts, first.settled)
    assert solved == [0.0, 2.0] and again.best is not None and again.nfev == 20 and not again.deferred


def test_section_peaks_resolve_the_spikes_where_the_blade_comes_to_rest():
    """The peaks come from every integration step of the manoeuvres: near a section's ends, where
    the blade comes to rest, the rates rise and fall within a fraction of the spacing of 4001
    times evenly spread, which missed up to 20 % of them on this drawing."""
    from pathlib import Path

    from skatetrace import resolve

    svg = Path(__file__).parent / "data" / "svg-corpus" / "ionicons-bicycle-outline.svg"
    tr = trace_figure(resolve(svg, size="6m", tol="1mm", height=1.7).figure)
    assert tr.success
    for sec in tr.sections:
        T = sec.duration
        near_ends = T * np.geomspace(1e-9, 1e-2, 3000)
        t = np.unique(np.concatenate([np.linspace(0.0, T, 40001), near_ends, T - near_ends, sec.breakpoints()]))
        v = sec.evaluate(np.clip(t, 0.0, T), geometry=False)
        for metric, key in (("peak_abs_adot", "adot"), ("peak_abs_bdot", "bdot"), ("max_abs_a", "a"),
                            ("max_abs_b", "b")):
            assert sec.metrics[metric] == pytest.approx(np.max(np.abs(v[key])), rel=1e-3), metric
        assert 0.0 < sec.metrics["min_speed_inside"]


def test_a_placement_whose_stop_reaches_farther_than_the_best_is_not_launched(monkeypatch):
    # An arc of bench/_common.py's distinct_arcs(40) (number 14): its first placement, the glide at
    # (0, 0), works; the next, an instant apex at (a, 0), stops with the mass 5.7 from the blade,
    # farther than the first's whole section (3.5). Its launch is not solved: the same trace, with
    # fewer integrations (measured 33 against 58).
    from skatetrace.tracing import maneuver
    from skatetrace.tracing import sections as tracing

    sec = _single(Segment(-1.698759465776116, 0.7263077763314891)).curves[0].sections()[0]
    real, launches = maneuver.solve_stop, []

    def counted(*args, **kw):
        launches.append(kw.get("backward", False))
        return real(*args, **kw)

    monkeypatch.setattr(tracing, "solve_stop", counted)
    pruned = tracing.trace_section(P, sec, TraceOptions(workers=1))
    pruned_launches, launches[:] = sum(launches), []
    monkeypatch.setattr(tracing, "_stop_reach", lambda stop: math.nan)  # no stop tells: every placement launched
    full = tracing.trace_section(P, sec, TraceOptions(workers=1))
    assert pruned.success and full.success
    assert (pruned.glide, pruned.metrics, pruned.residuals) == (full.glide, full.metrics, full.residuals)
    assert pruned_launches < sum(launches) and pruned.nfev < full.nfev
    t = np.linspace(0.0, full.duration, 101)
    for key in ("a", "b", "xi2"):
        np.testing.assert_array_equal(pruned.evaluate(t, geometry=False)[key], full.evaluate(t, geometry=False)[key])


def test_the_search_counts_a_stop_that_outreaches_the_best_alike_in_a_batch_and_one_by_one():
    # Stand-in attempts: placement 1 beats 0; placement 2's stop reaches farther than 1's section but
    # not than 0's. One by one, 2 is given up after its stop (bound 1's reach); solved in a batch
    # beside 1 (bound 0's reach), it is launched, and counted as its stop alone all the same.
    from skatetrace.tracing.search import Attempt, search_placements
    from skatetrace.tracing.sections import SectionTrace

    sec = _single(Segment(1.0, 1.0)).curves[0].sections()[0]

    def trace(reach):
        return SectionTrace(success=True, status=TraceStatus.SUCCESS, message="ok", curve_index=0, section=sec,
                            params=P, speed=1.0, glide={}, phases=("controls",),
                            metrics={"max_abs_a": reach, "max_abs_b": 0.0, "peak_mass_kinetic_energy": 1.0})

    placements = [(0, 0.0, 1.0, 0.1, (0.0, 0.0), True) for _ in range(4)]
    stops, reaches = [2.0, 1.0, 3.0, 1.5], [5.0, 2.0, 3.5, 2.5]  # the stops' reaches, the sections'
    bounds = []

    def solve(bounded, p, bound):
        k = len(bounds)
        bounds.append(bound)
        if bounded and stops[k] > bound * (1.0 + 1e-9):
            return Attempt(None, 4, False, stops[k], 4)
        return Attempt(trace(reaches[k]), 10, False, stops[k], 4)

    opts = TraceOptions(workers=1)
    one_by_one = search_placements(iter(placements), lambda p, bound: solve(True, p, bound), opts, {})
    assert bounds == [math.inf, 5.0, 2.0, 2.0]
    bounds.clear()
    batched = search_placements(iter(placements), lambda p, bound: solve(False, p, bound), opts, {})
    for done in (one_by_one, batched):
        assert done.best.metrics["max_abs_a"] == 2.0 and done.attempts == 4
        assert done.nfev == 10 + 10 + 4 + 10  # placement 2 counted as its stop alone


# ---- an apex beside its curvature's singular point is not solved ---------------------------------


def _apex_calls(monkeypatch):
    """solve_stop's glide positions, recorded as trace_section calls it."""
    from skatetrace.tracing import maneuver
    from skatetrace.tracing import sections as tracing

    real, seen = maneuver.solve_stop, []

    def recorded(params, legs, glide_ab, speed, **kw):
        seen.append(tuple(glide_ab))
        return real(params, legs, glide_ab, speed, **kw)

    monkeypatch.setattr(tracing, "solve_stop", recorded)
    return seen


def test_an_apex_beside_its_curvatures_singular_point_counts_as_tried_and_is_not_solved(monkeypatch):
    """A gently curved arc (radius 500 in the paper's model): the apex (0, 0) is 1.5 |kappa| = 3e-3 from the
    singular point (0, -kappa I / M), three singular limits. It is not solved; the trace is the one the
    search kept when it was (the instant apex on the arc's axis), with fewer integrations."""
    from skatetrace.tracing import placements
    from skatetrace.tracing import sections as tracing

    kappa = 0.002
    sec = _single(Segment(kappa, 2.0)).curves[0].sections()[0]
    limit = TraceOptions().singular_limit * P.length_scale
    assert placements.apex_singular_distance(P, kappa, (0.0, 0.0)) == pytest.approx(3.0 * limit)
    seen = _apex_calls(monkeypatch)
    kept = tracing.trace_section(P, sec, TraceOptions(workers=1))
    assert kept.success, kept.message
    assert all(placements.apex_singular_distance(P, kappa, ab) > placements.APEX_CLEARANCE * limit for ab in seen)
    assert kept.glide["a"] > 0.0 and kept.glide["b"] == 0.0
    seen.clear()
    monkeypatch.setattr(tracing, "APEX_CLEARANCE", 0.0)
    solved = tracing.trace_section(P, sec, TraceOptions(workers=1))
    assert (0.0, 0.0) in seen  # solved when nothing keeps it out
    assert (kept.glide, kept.metrics, kept.residuals) == (solved.glide, solved.metrics, solved.residuals)
    assert kept.nfev < solved.nfev


def test_an_apex_beyond_the_clearance_is_solved_and_a_section_only_such_apexes_could_trace_says_why(monkeypatch):
    from skatetrace.tracing import placements
    from skatetrace.tracing import sections as tracing

    limit = TraceOptions().singular_limit * P.length_scale
    kappa = 12.0 * limit / 1.5  # the apex (0, 0) twelve limits from the singular point
    seen = _apex_calls(monkeypatch)
    tracing.trace_section(P, _single(Segment(kappa, 2.0)).curves[0].sections()[0], TraceOptions(workers=1))
    assert (0.0, 0.0) in seen
    # the only placement asked for is within the clearance: the section fails with its reason, unsolved
    seen.clear()
    near = 3.0 * limit / 1.5
    failed = tracing.trace_section(P, _single(Segment(near, 2.0)).curves[0].sections()[0],
                                   TraceOptions(workers=1, glide_lateral=0.0))
    assert not failed.success and failed.status is TraceStatus.SINGULAR and seen == []
    assert "within 10 singular limits" in failed.message and "(0, -0.003)" in failed.message
    assert placements.APEX_CLEARANCE == 10.0


def test_nearest_breakpoint_is_argmins_first_nearest_without_the_matrix():
    """The nearest of increasing values (repeated ones, exact ties between two) and of values in any order."""
    from skatetrace.tracing.sections import _nearest

    rng = np.random.default_rng(11)
    for _ in range(300):
        v = np.sort(np.round(rng.uniform(0.0, 10.0, int(rng.integers(1, 30))), int(rng.integers(0, 3))))
        x = np.concatenate([rng.uniform(-1.0, 11.0, 20), v, 0.5 * (v[:-1] + v[1:])])  # midpoints: exact ties
        assert np.array_equal(_nearest(v, x), np.argmin(np.abs(v[:, None] - x[None, :]), axis=0))
        w = rng.permutation(v)
        assert np.array_equal(_nearest(w, x), np.argmin(np.abs(w[:, None] - x[None, :]), axis=0))


def test_a_failed_sections_pieces_are_named_in_short():
    from types import SimpleNamespace

    from skatetrace.tracing.sections import _indices

    def pieces(*idx):
        return [SimpleNamespace(index=i) for i in idx]

    assert _indices(pieces(3, 4, 5)) == "[3, 4, 5]"
    assert _indices(pieces(*range(1824, 5357))) == "[1824..5356]"
    assert _indices(pieces(1, 2, 3, 4, 9)) == "[1, 2, 3, 4, 9]"
