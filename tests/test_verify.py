"""Measuring a replay against the figure: where the blade's speed jumps with the control rates."""

import importlib

import numpy as np
import pytest

from skatetrace.dynamics.model import SleighParams
from skatetrace.verification.distances import figure_to_replay

verify_module = importlib.import_module("skatetrace.verification.verify")  # the package exports the function as verify


def _circle_replay(params, times, speeds):
    """A replay on the unit circle whose speed jumps at the repeated time (both limits sampled)."""
    phi = np.empty(times.size)
    acc, last = 0.0, times[0]
    for i, (t, v) in enumerate(zip(times, speeds)):
        acc += v * (t - last)
        last = t
        phi[i] = acc
    I, Mm = params.I, params.M + params.m
    # mass at the contact point, at rest relative to the blade: xi1 = p1 / I, xi2 = p2 / (M + m)
    state = np.vstack([I * speeds, Mm * speeds, phi + np.pi / 2, np.cos(phi), np.sin(phi)])
    n = times.size
    return verify_module.Replay(t=times, state=state, controls=np.zeros((4, n)), section=np.zeros(n, int),
                                piece=np.zeros(n, int))


def test_figure_to_replay_uses_the_velocity_on_each_side_of_a_jump():
    params = SleighParams()
    left = np.linspace(0.0, 1.0, 11)
    right = np.linspace(1.0, 1.5, 16)
    times = np.concatenate([left, right])
    speeds = np.concatenate([np.full(left.size, 1.0), np.full(right.size, 3.0)])
    rep = _circle_replay(params, times, speeds)
    end = 1.0 + 3.0 * 0.5
    ang = np.linspace(0.0, end, 400)
    points = np.vstack([np.cos(ang), np.sin(ang)])
    d = figure_to_replay(points, rep, np.arange(times.size), params)
    # cubic Hermite interpolation of a circle in 0.1-radian steps is off by about 0.1**4 / 384 = 2.6e-7
    assert d.max() < 1e-6, d.max()
    # the same replay interpolated with the left-hand speed past the jump strays by far more
    bad = _circle_replay(params, np.delete(times, 11), np.delete(speeds, 11))
    assert figure_to_replay(points, bad, np.arange(times.size - 1), params).max() > 1e-4


def test_figure_to_replay_refuses_a_mask_for_its_row_indices():
    params = SleighParams()
    times = np.linspace(0.0, 1.0, 5)
    rep = _circle_replay(params, times, np.ones(times.size))
    with pytest.raises(TypeError, match="indices of the replay's rows"):
        figure_to_replay(np.array([[1.0], [0.0]]), rep, np.ones(times.size, bool), params)


def test_figure_to_replay_sees_past_a_run_of_repeated_rows():
    # a replay chunk of zero length (many rows at one instant) must not hide the intervals around it
    params = SleighParams()
    times = np.concatenate([np.linspace(0.0, 1.0, 11), np.full(20, 1.0), np.linspace(1.0, 2.0, 11)])
    speeds = np.ones(times.size)
    rep = _circle_replay(params, times, speeds)
    ang = np.linspace(0.0, 2.0, 400)
    d = figure_to_replay(np.vstack([np.cos(ang), np.sin(ang)]), rep, np.arange(times.size), params)
    assert d.max() < 1e-6, d.max()


def test_distance_search_matches_a_brute_force_minimum():
    # points scattered around a replay whose blade speeds vary: the compiled search (golden section,
    # then Newton) must find each distance to the Hermite curve as a dense brute force does
    params = SleighParams()
    rng = np.random.default_rng(3)
    times = np.linspace(0.0, 1.0, 12)
    speeds = 1.0 + 0.5 * np.sin(3.0 * times)
    rep = _circle_replay(params, times, speeds)
    x, y, th = rep.state[3], rep.state[4], rep.state[2]
    v = speeds
    ang = rng.uniform(0.05, np.sum(np.diff(times) * speeds[:-1]) - 0.05, 300)
    rad = 1.0 + rng.uniform(-0.02, 0.02, 300)
    points = np.vstack([rad * np.cos(ang), rad * np.sin(ang)])
    d = figure_to_replay(points, rep, np.arange(times.size), params)
    hh = np.diff(times)
    vx, vy = v * np.cos(th), v * np.sin(th)

    def curve(j, u):
        h00, h10, h01, h11 = 2 * u**3 - 3 * u**2 + 1, u**3 - 2 * u**2 + u, -2 * u**3 + 3 * u**2, u**3 - u**2
        return (h00 * x[j] + h10 * hh[j] * vx[j] + h01 * x[j + 1] + h11 * hh[j] * vx[j + 1],
                h00 * y[j] + h10 * hh[j] * vy[j] + h01 * y[j + 1] + h11 * hh[j] * vy[j + 1])

    # brute force: a grid of 2000 steps per interval, then 20000 steps around the best of it
    coarse = np.linspace(0.0, 1.0, 2001)
    brute = np.empty(points.shape[1])
    for i, (qx, qy) in enumerate(points.T):
        best = min((float(np.min(np.hypot(*(np.array(curve(j, coarse)).T - (qx, qy)).T))), j) for j in range(hh.size))
        j = best[1]
        px, py = curve(j, coarse)
        u0 = coarse[np.argmin(np.hypot(px - qx, py - qy))]
        fine = np.linspace(max(u0 - 1e-3, 0.0), min(u0 + 1e-3, 1.0), 20001)
        px, py = curve(j, fine)
        brute[i] = np.min(np.hypot(px - qx, py - qy))
    # the fine grid (1e-7 of an interval) overestimates by far less than 1e-13 at these distances
    assert np.all(d <= brute + 1e-15)
    np.testing.assert_allclose(d, brute, rtol=0, atol=1e-13)


@pytest.mark.parametrize("rel_tol", [float("nan"), 0.0, -1e-6, 2.0, "1e-6", True])
def test_a_tolerance_that_would_pass_everything_is_refused(rel_tol):
    # deviation > NaN is False: a NaN tolerance would have verified anything
    import skatetrace as st

    fig = st.pattern("line")
    with pytest.raises(ValueError, match=r"rel_tol must be a number in \(0, 1\]"):
        st.trace_and_verify(fig, rel_tol=rel_tol)
    with pytest.raises(ValueError, match=r"rel_tol must be a number in \(0, 1\]"):
        st.verify(st.trace_figure(fig), rel_tol=rel_tol)


# --- bounded memory (issue 19): a long figure's replay and checks do not grow with its duration --------------

_PEAK = """
import json, resource, sys
from skatetrace.cli import main
code = main(["trace", sys.argv[1], "--out", sys.argv[2], "--no-plots", "--no-viewer"])
print(json.dumps({"code": code, "peak_kb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss}))
"""


def _peak_kb(tmp_path, length: float) -> int:
    import json
    import subprocess
    import sys

    figure = tmp_path / f"line{length:g}.json"
    figure.write_text(json.dumps({"curves": [{"pieces": [{"type": "line", "length": length}]}]}))
    run = subprocess.run([sys.executable, "-c", _PEAK, str(figure), str(tmp_path / f"out{length:g}")],
                         capture_output=True, text=True, timeout=600)
    out = json.loads(run.stdout.strip().splitlines()[-1])
    assert out["code"] == 0, run.stderr
    return out["peak_kb"]


def test_a_long_line_takes_little_more_memory_than_a_short_one(tmp_path):
    """A line 1e4 long used 1.95 GB (issue 19), 930 MB of it in verification; a line of length 1 about 200 MB.

    Measured against the short line in the same run (the imports' share differs between machines):
    at most 100 MB more (about 70 MB here, from the bounded replay and checks)."""
    short, long_ = _peak_kb(tmp_path, 1.0), _peak_kb(tmp_path, 1e4)
    assert long_ - short <= 100_000, (short, long_)


def test_the_replay_of_a_long_figure_is_bounded():
    import skatetrace as st

    figure = st.figure_from_dict({"curves": [{"pieces": [{"type": "line", "length": 1e5}]}]})
    done = st.trace_and_verify(figure, figure.params, st.TraceOptions())
    assert done.success
    rep = done.report.replay
    chunks = np.count_nonzero(np.diff(rep.t) == 0.0) + 1
    assert rep.t.size <= verify_module.MAX_REPLAY_SAMPLES + 50 * chunks


def test_a_replay_that_turns_nan_fails_its_section_instead_of_crashing_the_measurement(monkeypatch):
    # Issue 19, item 4, found again on a planned drawing (lucide-safari-pinned-tab at 6 m under the
    # default reach): the distance search (cKDTree) refused the NaN rows with "'x' must be finite"
    # before the verification's own check; such a section is measured as infinitely far, and fails
    import skatetrace as st

    trace = st.trace_figure(st.pattern("double-flower"), st.PAPER_PARAMS)
    real = verify_module.replay

    def nan_in_section_1(trace, schedule):
        rep = real(trace, schedule)
        rows = np.flatnonzero(rep.section == 1)
        state = rep.state.copy()
        state[:, rows[rows.size // 2:]] = np.nan
        return verify_module.Replay(t=rep.t, state=state, controls=rep.controls, section=rep.section, piece=rep.piece)

    monkeypatch.setattr(verify_module, "replay", nan_in_section_1)
    report = verify_module.verify(trace)
    assert not report.success
    bad = [s for s in report.sections if not s["passed"]]
    assert bad and bad[0]["section"] == 1 and bad[0]["max_deviation_replay_to_figure"] == float("inf")
    assert report.sections[0]["passed"]


def test_many_sections_are_sampled_side_by_side_as_one_by_one_and_the_verification_reports_its_stages(
        monkeypatch, pools_made):
    # Issue 19 item 7: a zigzag of 2,000 lines spent a silent minute sampling, replaying and
    # measuring its sections after they were traced; the sampling now runs in rounds shared out
    # between processes, and every stage reports how far it is
    import skatetrace as st

    pieces = [{"type": "line", "length": 1.0 + 0.05 * k} for k in range(20)]  # 20 distinct sections
    joins = [{"type": "cusp", "pivot_deg": 40.0 * (-1) ** k} for k in range(19)]
    figure = st.figure_from_dict({"curves": [{"pieces": pieces, "joins": joins}]})
    trace = st.trace_figure(figure, figure.params)
    assert len(trace.sections) == 20 and all(s.success for s in trace.sections)
    monkeypatch.setattr(verify_module, "_FORK_SECTIONS", 10**9)
    monkeypatch.setattr(verify_module, "_FORK_LEGS", 10**9)
    alone, alone_states = verify_module.schedule_from_trace(trace)
    monkeypatch.setattr(verify_module, "_FORK_SECTIONS", 2)
    monkeypatch.setattr(verify_module, "_SAMPLE_ROUND", 3)
    seen = []
    with verify_module.reporting(lambda *args: seen.append(args)):
        shared, shared_states = verify_module.schedule_from_trace(trace)
        report = verify_module.verify(trace, shared)
    for k in ("t", "a", "b", "adot", "bdot", "section", "piece"):
        np.testing.assert_array_equal(getattr(shared, k), getattr(alone, k))
    for k in alone_states:
        np.testing.assert_array_equal(shared_states[k], alone_states[k])
    assert report.success
    for stage in ("sampling the controls", "replaying", "measuring"):
        done = [d for s, d, total in seen if s == stage]
        assert done == sorted(done) and done[-1] == 20 and len(done) > 5, (stage, done)
        assert {total for s, _, total in seen if s == stage} == {20}
    assert [s for s, _, _ in seen] == sorted((s for s, _, _ in seen), key=["sampling the controls", "replaying",
                                                                          "measuring"].index)


def test_few_sections_of_many_legs_are_sampled_side_by_side(monkeypatch):
    # a planned section has some forty manoeuvre legs, each about as costly to sample as a
    # launch-glide-stop section's few: the legs, not only the sections, decide
    import skatetrace as st

    pieces = [{"type": "line", "length": 1.0 + 0.05 * k} for k in range(4)]
    joins = [{"type": "cusp", "pivot_deg": 40.0 * (-1) ** k} for k in range(3)]
    trace = st.trace_figure(st.figure_from_dict({"curves": [{"pieces": pieces, "joins": joins}]}))
    legs = sum(len(ph.maneuver.legs) for sec in trace.sections for ph in sec.phases if ph.maneuver is not None)
    batches = []
    forked = verify_module.map_forked

    def counted(fn, items, workers=None):
        batches.append(len(items))
        return forked(fn, items, workers)

    monkeypatch.setattr(verify_module, "map_forked", counted)
    monkeypatch.setattr(verify_module, "_FORK_SECTIONS", 10**9)
    for threshold, sizes in ((legs + 1, [1, 1, 1, 1]), (legs, [4])):
        monkeypatch.setattr(verify_module, "_FORK_LEGS", threshold)
        batches.clear()
        verify_module.schedule_from_trace(trace)
        assert batches == sizes


def test_a_section_through_the_contact_point_is_not_sampled_to_round_off(monkeypatch, tmp_path):
    # A dot of Adwaita's view-app-grid icon (a circle of four cubics, 1.2 m across at 1 mm) fitted
    # by 25 arcs: its launch-glide-stop manoeuvre passes the mass through the blade's contact
    # point, where two pieces' values are all tiny. Held each to its own scale, they took 322,000
    # rows each (873,000 for the dot); held to SCALE_FLOOR of the section's, the replay is as close.
    import skatetrace as st
    from skatetrace.drawings import fitting
    from skatetrace.pipeline import trace_and_verify

    svg = ('<svg viewBox="0 0 16 16" xmlns="http://www.w3.org/2000/svg"><path d="m 4 3 c -0.554688 0 -1 '
           '0.445312 -1 1 s 0.445312 1 1 1 s 1 -0.445312 1 -1 s -0.445312 -1 -1 -1 z"/></svg>')
    (tmp_path / "dot.svg").write_text(svg)
    # fitted as before a smooth closed path was merged: 32 arcs, traced as one section of 25 pieces
    with monkeypatch.context() as m:
        m.setattr(fitting._Fitter, "merged", lambda self, geom, intervals, least=None: intervals)
        fig = st.resolve(tmp_path / "dot.svg", size="1.2m", tol="1mm", height=1.7).figure
    assert len(fig.curves[0].pieces) > 20
    options = st.TraceOptions(speed=2.0)
    done = trace_and_verify(fig, fig.params, options)
    assert done.success
    reach = np.hypot(done.schedule.a, done.schedule.b)
    assert reach.min() < 1e-6 * reach.max()  # the mass passes through the contact point
    assert done.schedule.t.size < 400_000
    monkeypatch.setattr(verify_module, "SCALE_FLOOR", 0.0)
    each = trace_and_verify(fig, fig.params, options)
    assert each.schedule.t.size > 2 * done.schedule.t.size
    # the same deviation within the replay's spread (the sampling is not what bounds it)
    assert done.report.max_deviation <= 1.2 * each.report.max_deviation


def _spiral_chain(n=120, seed=3):
    """A smooth chain of ``n`` short spirals (curvature continuous, about 2 mm each), placed on the ice."""
    from skatetrace.figures.figure import SMOOTH, Curve
    from skatetrace.figures.geometry import Spiral

    rng = np.random.default_rng(seed)
    pieces, k = [], 0.8
    for _ in range(n):
        slope = rng.uniform(-40.0, 40.0)
        length = rng.uniform(1e-3, 3e-3)
        pieces.append(Spiral((k, slope, 0.0, 0.0), length))
        k += slope * length
    return Curve(tuple(pieces), (SMOOTH,) * (n - 1)).layout()


def test_nearer_pieces_is_the_test_of_every_point_piece_after_piece():
    """The k-d tree only leaves out points that no piece's disc test can take: the same distances, bit for bit."""
    from scipy.spatial import cKDTree

    from skatetrace.figures.geometry import distance_to_segment, segment_points
    from skatetrace.verification.distances import nearer_pieces

    placed = _spiral_chain()
    samples = [segment_points(p.start, p.segment, 65) for p in placed]
    curve = np.hstack(samples)
    rng = np.random.default_rng(7)
    # replayed points beside the chain, a few millimetres off: many lie outside every piece's disc
    # (whose radius is about a millimetre) yet nearer a spiral than to any of its samples
    base = curve[:, rng.integers(0, curve.shape[1], 3000)]
    pts = base + rng.normal(scale=2e-3, size=base.shape)
    d0 = cKDTree(curve.T).query(pts.T)[0]
    want = d0.copy()
    for p, xy in zip(placed, samples):  # every point tested against every piece's disc, as before the tree
        seg = p.segment
        centre = xy.mean(axis=1)
        radius = float(np.max(np.hypot(xy[0] - centre[0], xy[1] - centre[1])))
        radius += seg.length**2 * seg.max_abs_curvature() / (8 * 64**2) + 1e-12 * seg.length
        near = np.hypot(pts[0] - centre[0], pts[1] - centre[1]) - radius < want
        want[near] = np.minimum(want[near], distance_to_segment(pts[:, near], p.start, seg))
    got = nearer_pieces(d0, pts, placed, samples)
    assert np.array_equal(got, want)
    assert np.count_nonzero(got < d0) > 100  # the spirals' own distances did lower many
    assert np.array_equal(d0, cKDTree(curve.T).query(pts.T)[0])  # and the input is left as it was


def test_rows_by_piece_are_each_pieces_rows_in_order():
    piece = np.array([3, 3, 0, 0, 1, 3, 7, 7, 1, 0])
    rows = verify_module._rows_by_piece(piece)
    assert sorted(rows) == [0, 1, 3, 7]
    for k, idx in rows.items():
        assert np.array_equal(idx, np.flatnonzero(piece == k))
