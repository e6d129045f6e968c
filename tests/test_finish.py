"""The exact finish's compiled shooting (skatetrace.planning.shooting) against its Python form, on a planned section."""

import math

import numpy as np
import pytest

import skatetrace as st
from skatetrace.figures.geometry import Spiral, shifted_polynomial
from skatetrace.planning import finish, planner
from skatetrace.planning.shooting import jacobian_columns, legs_from, segment_end, segment_ends


@pytest.fixture(scope="module")
def section():
    """The arguments of the first exact finish of a school three with two pieces (a long arc, then the cusp's turn)."""
    calls = []
    real = planner.finish_section

    def recording(*args, **kwargs):
        calls.append((args, kwargs))
        return real(*args, **kwargs)

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(planner, "finish_section", recording)
        fig = st.school_figure("three", height=1.7)
        st.plan_figure(fig, fig.params, st.TraceOptions(speed=2.0, reach=0.5))
    args, kwargs = next(c for c in calls if len(c[0][1]) >= 2)
    params, pieces, times, U, _start, _target, X = args
    ends, coeffs = finish._pieces(pieces)
    tot = params.M + params.m
    states = X[:5] * np.array([tot, tot, 1.0, 1.0, 1.0])[:, None]  # the plan's states, masses as the params'
    return params, ends, coeffs, np.ascontiguousarray(times, dtype=float), np.array(U, dtype=float), states, kwargs


def _python_segment(params, y_start, sig, times, U, i0, i1, ends, coeffs, rtol, atol, dense=False):
    """The segment by the Python loop of integrate_legs calls (finish._run), as finish_section's dense pass runs it."""
    y = y_start.copy()
    s_start = y[4]
    y[4] = 0.0
    yk, _u, out = finish._run(params, y, sig * times[i0:i1 + 1], U[i0:i1 + 1], ends - s_start, coeffs, rtol, atol,
                              dense)
    if yk is None:
        return None, out
    yk = yk.copy()
    yk[4] += s_start
    return yk, out


def test_the_legs_are_the_shifted_pieces():
    ends = np.array([1.0, 2.5, 4.0])
    coeffs = np.array([[0.5, 0.1, -0.2, 0.03], [0.0, 0.0, 0.0, 0.0], [-1.0, 0.4, 0.0, 0.0]])
    j, kap, sw = legs_from(ends, coeffs, 0.7)
    assert j == 0 and kap.shape == (3, 4)
    np.testing.assert_allclose(kap[0], shifted_polynomial(coeffs[0], 0.7, 1.0), rtol=1e-14)
    np.testing.assert_array_equal(kap[1:], coeffs[1:])
    np.testing.assert_allclose(sw, [0.3, 1.8, math.inf])
    j, kap, sw = legs_from(ends, coeffs, 5.0)  # beyond the end: the last piece, extrapolated
    assert j == 2 and kap.shape == (1, 4) and sw[0] == math.inf


def test_a_compiled_segment_across_a_join_is_the_python_one(section):
    params, ends, coeffs, times, U, states, kw = section
    # the nodes around the join of the first two pieces (as planned)
    n_join = int(np.searchsorted(states[4], ends[0]))
    i0, i1 = max(n_join - 3, 0), min(n_join + 3, times.size - 1)
    y_start = states[:, i0].copy()
    py, _ = _python_segment(params, y_start, 1.0, times, U, i0, i1, ends, coeffs, kw["rtol"], kw["atol"])
    _, dense = _python_segment(params, y_start, 1.0, times, U, i0, i1, ends, coeffs, kw["rtol"], kw["atol"], True)
    assert {j for *_, j in dense} == {0, 1}  # the segment crosses the join
    out = np.empty(5)
    assert segment_end(params.M, params.m, params.I, y_start, 1.0, times, U, i0, i1, ends, coeffs, kw["rtol"],
                       kw["atol"], out)
    assert py is not None
    np.testing.assert_allclose(out, py, rtol=1e-9, atol=1e-12)
    # and each segment of a stretched time scale, from the plan's states, as finish_section's residual runs them
    bounds = np.array(list(range(0, times.size - 1, kw["stride"])) + [times.size - 1], dtype=np.int64)
    ys = np.ascontiguousarray(states[:, bounds[:-1]].T)
    E = np.empty((bounds.size - 1, 5))
    ok, count = segment_ends(params.M, params.m, params.I, ys, 1.01, times, U, bounds, ends, coeffs, kw["rtol"],
                             kw["atol"], np.ones(bounds.size - 1, dtype=np.bool_), E)
    assert ok and count == bounds.size - 1
    for k in range(bounds.size - 1):
        py, _ = _python_segment(params, ys[k], 1.01, times, U, bounds[k], bounds[k + 1], ends, coeffs, kw["rtol"],
                                kw["atol"])
        np.testing.assert_allclose(E[k], py, rtol=1e-9, atol=1e-12)


def test_the_compiled_jacobian_columns_are_forward_differences_of_the_segments(section):
    params, ends, coeffs, times, U, states, kw = section
    N, stride = 12, 4  # the section's first twelve intervals, three segments
    times, U = times[:N + 1].copy(), U[:N + 1].copy()
    bounds = np.arange(0, N + 1, stride, dtype=np.int64)  # [0, 4, 8, 12]
    tot = params.M + params.m
    yscale = np.array([tot, tot, 1.0, 1.0, ends[-1]])
    ys = np.ascontiguousarray(states[:, bounds[:-1]].T)
    z = np.concatenate([[1.0], U[1:]] + [ys[k] / yscale for k in (1, 2)])
    ys = np.concatenate([ys[:1], z[N + 1:].reshape(2, 5) * yscale])  # as finish_section unpacks z
    uu = U.copy()
    rtol, atol = kw["rtol"], kw["atol"]

    def ends_at(sig, uu, ys):
        return np.array([_python_segment(params, ys[k], sig, times, uu, bounds[k], bounds[k + 1], ends, coeffs, rtol,
                                         atol)[0] for k in range(3)])

    E = ends_at(1.0, uu, ys)
    r = np.concatenate([((E[:-1] - ys[1:]) / yscale).ravel(), np.zeros(6)])
    J, last = np.full((r.size, z.size), np.nan), np.empty((z.size, 6))
    moved, steps = np.zeros(z.size, dtype=np.bool_), np.empty(z.size)
    ok, count = jacobian_columns(params.M, params.m, params.I, z, uu, ys, yscale, times, bounds, ends, coeffs, rtol,
                                 atol, E, r, J, last, moved, steps)
    assert ok and count == 3 + (N + 2) + 10  # all for the time scale, two at an inner node, one for a state
    np.testing.assert_array_equal(uu, U)  # restored
    for i in (0, 4, 5, N + 1 + 7):  # the time scale, u at a segment's end and inside one, b at the third's start
        sig, uu_p, ys_p = 1.0, uu.copy(), ys.copy()
        zi = z[i] + steps[i]
        if i == 0:
            sig = zi
        elif i <= N:
            uu_p[i] = zi
        else:
            ys_p[(i - N - 1) // 5 + 1, (i - N - 1) % 5] = zi * yscale[(i - N - 1) % 5]
        Ep = ends_at(sig, uu_p, ys_p)
        col = ((Ep[:-1] - ys_p[1:]) / yscale).ravel() - r[:-6]
        np.testing.assert_allclose(J[:-6, i] * steps[i], col, rtol=1e-6, atol=1e-9 * max(np.max(np.abs(col)), 1e-6))
        assert moved[i] == (i == 0 or 8 <= i <= N or i >= N + 6)  # the last segment moved
        if moved[i]:
            np.testing.assert_allclose(last[i, :5], Ep[-1], rtol=1e-9, atol=1e-12)
            assert last[i, 5] == uu_p[N]
    assert moved.tolist() == [True] + [i >= 8 for i in range(1, N + 1)] + [False] * 5 + [True] * 5


def test_failures_come_back_as_none(section):
    params, ends, coeffs, times, U, states, kw = section
    rtol, atol = kw["rtol"], kw["atol"]
    kappa = coeffs[0, 0]
    assert kappa != 0.0
    singular = np.array([0.0, 0.0, 0.0, -kappa * params.I / params.M, 0.0])  # the integrator fails at once
    bad_times = times.copy()
    bad_times[2] = bad_times[1]  # an interval of zero length
    nan_start = states[:, 0].copy()
    nan_start[2] = np.nan
    out = np.empty(5)
    for y, tt, sig in ((singular, times, 1.0), (states[:, 0], bad_times, 1.0), (states[:, 0], times, -1.0),
                       (nan_start, times, 1.0)):
        py, _ = _python_segment(params, y, sig, tt, U, 0, 3, ends, coeffs, rtol, atol)
        assert py is None
        assert not segment_end(params.M, params.m, params.I, y, sig, tt, U, 0, 3, ends, coeffs, rtol, atol, out)
    # a residual stops at the failing segment; a Jacobian at the first column that fails
    ys = np.array([states[:, 0], singular, states[:, 6]])
    bounds = np.array([0, 3, 6, 9], dtype=np.int64)
    E = np.empty((3, 5))
    ok, count = segment_ends(params.M, params.m, params.I, ys, 1.0, times, U, bounds, ends, coeffs, rtol, atol,
                             np.ones(3, dtype=np.bool_), E)
    assert not ok and count == 2
    z = np.concatenate([[1.0], U[1:10]] + [ys[1], ys[2]])
    J, last = np.zeros((16, z.size)), np.zeros((z.size, 6))
    ok, count = jacobian_columns(params.M, params.m, params.I, z, U[:10].copy(), ys, np.ones(5), times[:10], bounds,
                                 ends, coeffs, rtol, atol, E, np.zeros(16), J, last, np.zeros(z.size, dtype=np.bool_),
                                 np.empty(z.size))
    assert not ok and count == 2
    # and a finish whose integrations fail says so without raising
    pieces = [Spiral(tuple(c), float(length)) for c, length in zip(coeffs, np.diff(ends, prepend=0.0))]
    rest = finish.RestState(float(states[2, 0]), float(states[3, 0]), 0.0, 0.0)
    fin = finish.finish_section(params, pieces, bad_times, U, rest, rest)
    assert not fin.success and fin.residuals == {} and fin.intervals == () and fin.nfev == 1


def test_the_circle_eight_of_a_1_85_m_skater_finishes_every_section_from_its_first_plan(monkeypatch, tmp_path):
    """The forward differences' step: at 1e-7 12 of this figure's 14 finishes stalled between 1e-8 and 5e-10
    after 30 iterations (each then cost a refined mesh and a program again); at 1e-9 its first plan's finish."""
    from skatetrace.cli.entry import script

    finished = []
    real = planner.finish_section

    def recording(*args, **kwargs):
        finished.append(real(*args, **kwargs))
        return finished[-1]

    monkeypatch.setattr(planner, "finish_section", recording)
    code = script(["trace", "school:circle-eight", "--height", "1.85", "--no-plots", "--no-viewer", "--workers", "1",
                   "--out", str(tmp_path / "out")])
    assert code == 0
    assert finished and all(fin.success for fin in finished)
    assert all(max(fin.residuals.values()) <= 1e-10 for fin in finished)
