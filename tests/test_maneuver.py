"""The manoeuvre solver: its compiled right-hand side against the model's formulas, and its solves."""

import math

import numpy as np
import pytest

from skatetrace.dynamics.integrator import _rhs
from skatetrace.tracing.maneuver import constrained_rates, solve_stop
from skatetrace.dynamics.model import SleighParams, curvature_coefficients, rhs, velocities


@pytest.mark.parametrize("params", [SleighParams(), SleighParams(M=2.3, m=1.7, I=0.9)])
def test_inlined_rhs_matches_model(params):
    rng = np.random.default_rng(3)
    for _ in range(20):
        p1, p2, a, b, kappa, u = rng.normal(size=6)
        out = np.empty(5)
        assert _rhs(params.M, params.m, params.I, kappa, u, 0.0, 1.0, np.array([p1, p2, a, b, 0.0]), out)  # u = alpha t + 0 at t = 1
        dp1, dp2, da, db, ds = out
        ad, bd, _ = constrained_rates(params, kappa, p1, p2, a, b, u)
        ref = rhs(params, np.array([p1, p2, 0.0, 0.0, 0.0]), a, b, ad, bd)
        xi1, xi2, _ = velocities(params, p1, p2, a, b, ad, bd)
        np.testing.assert_allclose([dp1, dp2, da, db, ds], [ref[0], ref[1], ad, bd, xi2], rtol=1e-12, atol=1e-12)
        # the rates hold the curvature: c . rates + c0 = 0, i.e. xi1 = kappa xi2
        c_a, c_b, c_0 = curvature_coefficients(params, kappa, p1, p2, a, b)
        assert abs(c_a * ad + c_b * bd + c_0) < 1e-10 * (1 + abs(c_0))
        assert abs(xi1 - kappa * xi2) < 1e-10 * (1 + abs(xi2))


def test_stop_and_launch_are_mirror_images():
    p = SleighParams()
    stop = solve_stop(p, [(1 / 1.2, 1.0)], (0.0, 0.0), 1.0)
    launch = solve_stop(p, [(1 / 1.2, 1.0)], (0.0, 0.0), 1.0, backward=True)
    assert stop.success and launch.success
    assert launch.duration == pytest.approx(-stop.duration, rel=1e-9)
    t = np.linspace(0, stop.duration, 7)
    ys, yl = stop.legs[0].sol(t), launch.legs[0].sol(-t)
    np.testing.assert_allclose(yl[2], -ys[2], atol=1e-9)  # a -> -a
    np.testing.assert_allclose(yl[3], ys[3], atol=1e-9)  # b -> b


def test_stop_reports_failure_as_data_at_the_singular_point():
    p = SleighParams()
    k = 1.0
    res = solve_stop(p, [(k, 1.0)], (0.0, -k * p.I / p.M), 1.0)
    assert not res.success and "singular" in res.message


def test_polish_rejects_a_duration_of_the_wrong_sign(monkeypatch):
    # Newton's method may land on a root whose duration has the other sign (the manoeuvre would run
    # backwards in time: a stop before its glide). Seen on the change-loop school figure, where it
    # gave a section of negative duration; such a root must be refused, not assembled. Here every
    # candidate meets the boundary conditions, so only the sign of the duration can reject it.
    from types import SimpleNamespace

    from skatetrace.tracing import maneuver
    from skatetrace.dynamics.model import SleighParams

    length = 1.0
    def lands_on(z):
        """MINPACK's iteration reduced to one iterate, ``z``, which it evaluates and returns."""
        def fake_root(fun, x0, **kw):
            fun(np.array(z))
            return SimpleNamespace(x=np.array(z))
        return fake_root

    monkeypatch.setattr(maneuver, "root", lands_on([1.0, -0.5]))
    monkeypatch.setattr(maneuver, "_integrate", lambda params, y0, legs_spec, u, tau, **kw: (
        [None] * len(legs_spec), 0, tau, np.array([0.0, 0.0, 0.0, 0.0, length]), None))
    monkeypatch.setattr(maneuver, "_end_speed", lambda *a: 0.0)
    params = SleighParams()
    y0 = np.zeros(5)
    sol, res, _ = maneuver._polish_stop(params, [(1.0, math.inf)], y0, 1.0, 1.0, length, 0.3, 2.0, 1e-10, 1e-12, 0.0)
    assert sol is None and res is None
    # the same root with a positive duration is accepted
    monkeypatch.setattr(maneuver, "root", lands_on([1.0, 0.5]))
    sol, res, _ = maneuver._polish_stop(params, [(1.0, math.inf)], y0, 1.0, 1.0, length, 0.3, 2.0, 1e-10, 1e-12, 0.0)
    assert sol == pytest.approx((0.3, 1.0)) and res == {"end_speed": 0.0, "length": 0.0}


def test_polish_integrations_end_at_the_singular_limit(monkeypatch):
    # Newton's iterates can drive the mass into the singular point, where the step size collapses:
    # such an integration used to burn its whole evaluation budget (some 30 ms each, most of the
    # time of a drawing's failing polishes). It now ends at the singular limit, and a manoeuvre
    # that comes that close is no solution (solve_stop rejects it anyway).
    from types import SimpleNamespace

    from skatetrace.tracing import maneuver

    seen = []

    def integrate(params, y0, legs_spec, u, tau, **kw):
        seen.append(kw.get("singular_limit"))
        return [None] * len(legs_spec), 0, tau, np.array([0.0, 0.0, 0.0, 0.0, 1.0]), "singular"

    monkeypatch.setattr(maneuver, "root", lambda fun, x0, **k: SimpleNamespace(x=np.asarray(x0) if fun(x0)[0] else x0))
    monkeypatch.setattr(maneuver, "_integrate", integrate)
    monkeypatch.setattr(maneuver, "_end_speed", lambda *a: 0.0)
    sol, res, _ = maneuver._polish_stop(SleighParams(), [(1.0, math.inf)], np.zeros(5), 1.0, 1.0, 1.0, 0.3, 2.0,
                                        1e-10, 1e-12, 0.05)
    assert sol is None and res is None
    assert seen and all(v == 0.05 for v in seen)


def _linear_polish(monkeypatch, root_spy=None):
    """_polish_stop on residuals linear in (alpha / alpha0, tau / tau0), zero at (1.25, 0.8); the residuals of
    every evaluation in order."""
    from skatetrace.tracing import maneuver

    seen = []

    def integrate(params, y0, legs_spec, alpha, tau, **kw):
        z = np.array([alpha / 0.3, tau / 2.0])
        r = np.array([[2.0, 0.5], [-0.3, 1.0]]) @ (z - [1.25, 0.8])
        seen.append(r)
        return [None] * len(legs_spec), 0, tau, np.array([0.0, r[0], 0.0, 0.0, 1.0 + r[1]]), None

    monkeypatch.setattr(maneuver, "_integrate", integrate)
    monkeypatch.setattr(maneuver, "_end_speed", lambda params, legs_spec, yf, u: yf[1])
    if root_spy is not None:
        monkeypatch.setattr(maneuver, "root", root_spy)
    out = maneuver._polish_stop(SleighParams(), [(1.0, math.inf)], np.zeros(5), 1.0, 1.0, 1.0, 0.3, 2.0,
                                1e-10, 1e-12, 0.0)
    return out, seen


def test_polish_stops_at_its_first_iterate_that_passes(monkeypatch):
    # MINPACK went on towards an xtol of 1e-14 after the residuals had passed (up to 213 integrations
    # where 30 had done): the polish now takes the first iterate that passes, and integrates no more
    (sol, res, count), seen = _linear_polish(monkeypatch)
    assert sol == pytest.approx((0.375, 1.6), rel=1e-10)
    assert count == len(seen) < 20
    passed = [bool(np.all(np.abs(r) < 1e-11)) for r in seen]
    assert passed[-1] and not any(passed[:-1])
    assert res == {"end_speed": float(seen[-1][0]), "length": float(seen[-1][1])}


def _polish_on(monkeypatch, residuals):
    """_polish_stop under an iteration that evaluates up to 600 iterates, whose residuals are
    ``residuals(k)`` at the k-th; its answer and the iterates evaluated."""
    from types import SimpleNamespace

    from skatetrace.tracing import maneuver

    def endless(fun, x0, **kw):
        for k in range(600):
            fun(np.array([1.0, 1.0 + 1e-3 * k]))
        return SimpleNamespace(x=np.asarray(x0))

    def integrate(params, y0, legs_spec, alpha, tau, **kw):
        r = residuals(round((tau / 2.0 - 1.0) * 1e3))
        return [None] * len(legs_spec), 0, tau, np.array([0.0, r, 0.0, 0.0, 1.0]), None

    monkeypatch.setattr(maneuver, "root", endless)
    monkeypatch.setattr(maneuver, "_integrate", integrate)
    monkeypatch.setattr(maneuver, "_end_speed", lambda params, legs_spec, yf, u: yf[1])
    return maneuver._polish_stop(SleighParams(), [(1.0, math.inf)], np.zeros(5), 1.0, 1.0, 1.0, 0.3, 2.0,
                                 1e-10, 1e-12, 0.0)


def test_polish_gives_up_where_it_stalls(monkeypatch):
    from skatetrace.tracing import maneuver

    window = maneuver._POLISH_WINDOW
    # no progress at all: given up at the end of its second window, not at MINPACK's limit of 600
    sol, res, count = _polish_on(monkeypatch, lambda k: 0.1)
    assert sol is None and res is None and count == 2 * window
    # a factor 1.2 a window is too little: given up after the second window's
    sol, _res, count = _polish_on(monkeypatch, lambda k: 0.1 * 1.2 ** (-k / window))
    assert sol is None and count == 2 * window
    # slow but steady progress (a factor 1.7 a window, as the slowest polishes that succeeded) goes on
    # to the iterate that passes, past the second window
    passes = 3 * window + 7
    sol, res, count = _polish_on(monkeypatch, lambda k: 1e-12 if k >= passes else 0.1 * 1.7 ** (-k / window))
    assert sol is not None and count == passes + 1 and res["end_speed"] == 1e-12


# ---- issue 6: the faster solve finds the same manoeuvres ---------------------------------------


def _chain(coefficients, length, n):
    """A spiral's legs ``[(coefficients, length), ...]`` cut into ``n`` equal legs (its curvature continuous)."""
    from skatetrace.figures.geometry import shifted_polynomial

    h = length / n
    return [(shifted_polynomial(coefficients, i * h, 1.0), h) for i in range(n)]


def _full_scan_brackets(params, legs, glide_ab, backward=False):
    """The first bracket of each sign on the whole grid, every point integrated (the scan before issue 6)."""
    from skatetrace.tracing import maneuver

    length = sum(ell for _, ell in legs)
    spec, acc = [], 0.0
    for i, (k, ell) in enumerate(legs):
        acc += ell
        spec.append((maneuver._coefficients(k), acc if i + 1 < len(legs) else math.inf))
    p = maneuver.glide_state(params, spec[0][0][0], *glide_ab, 1.0)
    y0 = np.array([p[0], p[1], glide_ab[0], glide_ab[1], 0.0])
    sign = -1.0 if backward else 1.0
    out = {}
    for direction in (1.0, -1.0):
        grid = direction / length**2 * maneuver._GRID
        ends = []
        for a in grid:
            _legs, status, _t, y, hit = maneuver._integrate(params, y0, spec, a, sign * 60.0 * length, rtol=1e-9,
                                                            atol=1e-11, stop=True, singular_limit=1e-3, dense=False)
            ends.append(abs(y[4]) if status == 0 and hit == "stopped" else None)
        for k in range(grid.size - 1):
            if ends[k] is not None and ends[k + 1] is not None and (ends[k] - length) * (ends[k + 1] - length) <= 0:
                out[direction] = sorted((grid[k], grid[k + 1]))
                break
    return out


@pytest.mark.parametrize("legs,glide_ab,backward", [
    ([(1.0, 1.0)], (0.0, 0.0), False),  # the paper's third arc
    ([(1.0, 0.5 * math.pi)], (10.42477796076938, 0.0), False),  # its apex on the blade's axis
    ([(1.25, 0.25)], (2.507964473723101, 0.0), True),  # the paper's second arc: a launch
    ([(0.0, 1.0)], (3.0, 0.0), False),  # a line
    ([((0.2, 0.3, 0.0, 0.0), 1.0)], (0.0, 1.0), False),  # a clothoid
    (_chain((0.2, 0.3, 0.0, 0.0), 1.0, 4), (0.0, 1.0), False),  # the clothoid cut into four legs
    (_chain((0.8, -1.6, 0.0, 0.4), 1.0, 8), (0.0, 1.0), True),  # a cubic through an inflection, in eight
])
def test_stop_is_the_first_root_of_the_full_scan_polished_to_rounding(legs, glide_ab, backward):
    p = SleighParams()
    sol = solve_stop(p, legs, glide_ab, 1.0, backward=backward)
    assert sol.success, sol.message
    brackets = _full_scan_brackets(p, legs, glide_ab, backward)
    alpha = sol.params[0]
    assert any(lo <= alpha <= hi for lo, hi in brackets.values()), (alpha, brackets)
    length = sum(ell for _, ell in legs)
    # "to rounding" of the integration that places the stop, which is not the rounding of the
    # length itself: with the glide and speed perturbed by 1e-15..1e-11 the residual reaches
    # 38 ulps of the length on the apex case (4 to 5 on the others), the end speed 9e-16. The
    # solver itself accepts 1e-11 x length; Brent's scan alone stops at 1e-9 in alpha.
    assert abs(sol.residuals["length"]) <= 1e-12 * length
    assert abs(sol.residuals["end_speed"]) <= 1e-13
    # a coarse scan, Brent's method at moderate accuracy, two or three polishing runs: 12 to 28
    # evaluations over the same perturbed draws
    assert sol.nfev <= 40


def test_mirrored_stop_is_the_launch_bit_for_bit():
    from skatetrace.tracing.mirror import mirrored_maneuver

    p = SleighParams()
    for legs, (a, b) in [([(1.0, 1.0)], (0.0, 0.3)), ([(1.25, 0.25)], (2.507964473723101, 0.0)),
                         ([(0.0, 1.0), ((0.0, 0.5, 0.0, 0.0), 2.0)], (0.0, 0.5))]:
        launch = solve_stop(p, legs, (a, b), 1.0, backward=True)
        mirror = mirrored_maneuver(solve_stop(p, legs, (-a, b), 1.0), legs)
        assert launch.success and mirror.success and mirror.kind == "launch"
        assert mirror.params == launch.params and mirror.duration == launch.duration
        assert mirror.residuals == launch.residuals
        assert mirror.min_singular_distance == launch.min_singular_distance
        for ml, ll in zip(mirror.legs, launch.legs, strict=True):
            assert (ml.coefficients, ml.t0, ml.t1, ml.s0) == (ll.coefficients, ll.t0, ll.t1, ll.s0)
            t = np.linspace(ll.t0, ll.t1, 101)
            assert np.array_equal(ml.sol(t), ll.sol(t))


def test_same_legs_compares_curvature_polynomials_and_lengths():
    from skatetrace.tracing.mirror import same_legs

    assert same_legs([(1.0, 2.0)], [((1.0, -0.0, 0.0, -0.0), 2.0)])
    assert not same_legs([(1.0, 2.0)], [(1.0, 2.5)])
    assert not same_legs([(1.0, 2.0)], [((1.0, 0.1), 2.0)])
    assert not same_legs([(1.0, 2.0)], [(1.0, 1.0), (0.5, 1.0)])


def test_a_jump_of_the_stopping_length_is_not_searched_as_a_root(monkeypatch):
    # A launch of a school figure for a 1.7 m skater over two legs (an arc, then the opposite arc):
    # for positive ramps the scan's root is where the stopping length jumps (the speed grazing zero
    # before the stop), not a root. Brent's method at full accuracy on the whole bracket converged
    # on the jump and was refused; now only a side of it that still crosses the length is searched.
    from skatetrace.dynamics.presets import skater_params
    from skatetrace.tracing import maneuver

    params = skater_params(height=1.7)
    legs = [(0.3921568627450981, 2.55), (-0.3921568627450981, 8.011061266653972)]
    kw = dict(backward=True)
    seen = []
    real = maneuver._jump_at
    monkeypatch.setattr(maneuver, "_jump_at", lambda *a: seen.append(real(*a)) or seen[-1])
    fast = solve_stop(params, legs, (0.0, 0.09044954710408228), 1.0, **kw)
    assert any(j is not None for j in seen)
    (lo, miss_lo), (hi, miss_hi) = next(j for j in seen if j is not None)
    assert lo < hi and miss_lo * miss_hi < 0 and min(abs(miss_lo), abs(miss_hi)) > maneuver._JUMP_MISS
    monkeypatch.setattr(maneuver, "_jump_at", lambda *a: None)
    full = solve_stop(params, legs, (0.0, 0.09044954710408228), 1.0, **kw)
    assert fast.success and full.success
    assert fast.params == full.params and fast.duration == full.duration and fast.residuals == full.residuals
    assert fast.nfev < full.nfev - 20


def test_jump_at_tells_a_jump_from_a_steep_or_missing_stop():
    from skatetrace.tracing import maneuver

    class Fake:
        def __init__(self, stop):
            self.stop = stop

        def run(self, alpha, rtol, atol):
            s = self.stop(alpha)
            if s is None:
                raise maneuver._NoStop
            return 1.0, np.array([0.0, 0.0, 0.0, 0.0, s])

    root = 0.02
    assert maneuver._jump_at(Fake(lambda a: 2.0 if a > root else 0.5), root, 1.0, 1e-13, 1e-14) is not None
    # a continuous stopping length, however steep in alpha near the root (slope 1e3 in log alpha)
    assert maneuver._jump_at(Fake(lambda a: (a / root) ** 1000), root, 1.0, 1e-13, 1e-14) is None
    # the stop falls on one side only, or a probe does not stop
    assert maneuver._jump_at(Fake(lambda a: 2.0 if a > root else 1.5), root, 1.0, 1e-13, 1e-14) is None
    assert maneuver._jump_at(Fake(lambda a: 2.0 if a > root else None), root, 1.0, 1e-13, 1e-14) is None


def test_without_the_fallbacks_a_stop_that_needs_them_is_deferred(monkeypatch):
    # The paper's second arc from the glide at (0, 0): with the secant polish made to fail, the
    # stop needs Brent's method and Newton's; without them it is a failure marked deferred, found
    # in a few integrations, and with them it is the stop found as usual.
    from skatetrace.tracing import maneuver

    params = SleighParams()
    legs = [(1.25, 0.25132741228718345)]
    usual = solve_stop(params, legs, (0.0, 0.0), 1.0)
    monkeypatch.setattr(maneuver, "_refined_stop", lambda *a: (None, None))
    quick = solve_stop(params, legs, (0.0, 0.0), 1.0, fallback=False)
    assert not quick.success and quick.deferred and "fallback" in quick.message
    slow = solve_stop(params, legs, (0.0, 0.0), 1.0)
    assert usual.success and slow.success and not slow.deferred and not usual.deferred
    assert slow.params[0] == pytest.approx(usual.params[0], rel=1e-9)
    assert quick.nfev < slow.nfev
    # a stop that no ramp brackets is no deferral: the fallbacks would have nothing to search
    # (half a line into a tight arc, from a glide on the line)
    monkeypatch.undo()
    line = solve_stop(params, [(0.0, 0.5), (2.0, 1.0)], (4.0, 0.0), 1.0, fallback=False)
    assert not line.success and not line.deferred and "no stop" in line.message


# ---- issue 18: weak ramps given up far beyond the length -----------------------------------------


def test_a_weak_ramp_is_given_up_beyond_the_arc_length_asked():
    from skatetrace.tracing import maneuver

    p = SleighParams()
    glide = maneuver.glide_state(p, 1.0, 0.0, 0.4, 1.0)
    stopper = maneuver._Stopper(p, np.array([glide[0], glide[1], 0.0, 0.4, 0.0]),
                                [((1.0, 0.0, 0.0, 0.0), math.inf)], 20.0, 1e-3)
    weak = 1e-6  # glides on past a length of 12 without stopping
    with pytest.raises(maneuver._Beyond):
        stopper.run(weak, 1e-6, 1e-8, beyond=8.0)
    with pytest.raises(maneuver._NoStop) as full:
        stopper.run(weak, 1e-6, 1e-8)
    assert not isinstance(full.value, maneuver._Beyond)  # integrated in full, it never stops
    # a stop before the arc length given is the same stop, to the bit
    tau, y = stopper.run(1.0, 1e-9, 1e-11)
    tau_capped, y_capped = stopper.run(1.0, 1e-9, 1e-11, beyond=8.0 * abs(y[4]))
    assert (tau_capped, list(y_capped)) == (tau, list(y))


@pytest.mark.parametrize("ends,apart,side_by_side", [
    (("far", "far"), [], []),                   # both weak ramps given up: no root between
    (("far", (2.0, 1.0)), [], []),              # the stronger stops beyond the length: none either
    (("far", (0.5, 1.0)), [0, 4], [0, 1]),      # it stops short of it: both looked at in full
    (("far", None), [], []),                    # it does not stop (the singular point, say): the fine
    ((None, "far"), [], []),                    # points between are looked at instead, either way round
    (((2.0, 1.0), "far"), [0, 4], []),          # a weaker ramp stops beyond, a stronger runs on: in full
])                                              # where the stop may go between them
@pytest.mark.parametrize("coarse", [4, 1])
def test_first_bracket_integrates_a_far_point_in_full_only_where_it_decides(ends, apart, side_by_side, coarse):
    """A point given up far beyond the length is integrated in full only where that can tell a bracket.

    Beside a point that does not stop, or next to one that stops beyond the length, it cannot: until
    2026-11-29 it was (some 20 us each, four times in a single arc's trace). Where the stop comes or
    goes between two points apart, the fine points are looked at without it.
    """
    from skatetrace.tracing import maneuver

    far, full, looked = maneuver._FAR, [], []
    values = {0: ends[0], coarse: ends[1]}
    in_full = {k: v if v != far else (3.0, 1.0) for k, v in values.items()}

    def length_at(k, exact=False):
        if exact:
            full.append(k)
            return in_full[k]
        looked.append(k)
        return values.get(k, (3.0, 1.0))  # the fine points between stop beyond the length

    found = maneuver._first_bracket(length_at, 0, coarse + 1, 1.0, coarse)
    assert found is None or (ends[1] == (0.5, 1.0) and found == (0, coarse))
    assert sorted(set(full)) == (apart if coarse == 4 else side_by_side)
    if None in ends:
        assert sorted(set(looked)) == list(range(coarse + 1))  # the fine points, where there are any


def test_the_scan_gives_up_weak_ramps_and_finds_the_same_stop(monkeypatch):
    from skatetrace.tracing import maneuver

    p, legs, glide_ab = SleighParams(), [(0.8, 1.5)], (0.0, 0.4)
    real = maneuver.final_state
    ran = []

    def recorded(*args, **kw):
        out = real(*args, **kw)
        if kw["rtol"] == maneuver._GRID_RTOL:
            ran.append(abs(out[2][4]))
        return out

    monkeypatch.setattr(maneuver, "final_state", recorded)
    capped = solve_stop(p, legs, glide_ab, 1.0)
    far_capped = max(ran)
    ran.clear()
    monkeypatch.setattr(maneuver, "_FAR_LENGTHS", math.inf)
    full = solve_stop(p, legs, glide_ab, 1.0)
    assert capped.success and full.success
    assert capped.params[0] == pytest.approx(full.params[0], rel=1e-14)
    assert capped.duration == pytest.approx(full.duration, rel=1e-14)
    # the weak ramps glide on for tens of lengths when integrated in full
    assert far_capped <= 8.0 * 1.5 * (1 + 1e-12) < max(ran)


# ---- issue 17: short lines, whose stop needs a ramp weaker than the grid's weakest ----------------


@pytest.mark.parametrize("length", [5e-4, 1e-3, 1.3e-3])
@pytest.mark.parametrize("skater", [False, True])
def test_a_line_shorter_than_the_grid_reaches_is_traced_and_verified(length, skater):
    """A line of 1.3 mm or less (the paper's model, or a 1.7 m skater's at 2 m/s) failed "no stop of
    length ... found": its stopping length falls as 1 / alpha, and even the grid's weakest ramp
    stopped the blade short of it. The ramps below the grid bracket its stop."""
    from skatetrace import Curve, Figure, Segment, TraceOptions, schedule_from_trace, skater_params, trace_figure, verify

    params = skater_params(height=1.7) if skater else SleighParams()
    speed = 2.0 if skater else 1.0
    fig = Figure("short", (Curve((Segment(0.0, length),), (), name="short"),), params)
    tr = trace_figure(fig, options=TraceOptions(speed=speed, workers=1))
    assert tr.success, tr.message
    schedule, _ = schedule_from_trace(tr)
    assert verify(tr, schedule).success


def test_the_ramps_below_the_grid_are_scanned_only_where_the_grid_has_no_bracket(monkeypatch):
    from skatetrace.tracing import maneuver

    scanned = []
    real = maneuver._scan

    def recorded(stopper, grid, length, coarse):
        scanned.append(abs(grid[0]) * length**2)  # in natural units (speed 1)
        return real(stopper, grid, length, coarse)

    monkeypatch.setattr(maneuver, "_scan", recorded)
    p = SleighParams()
    a0 = 2.0 * (p.M + p.m) / p.m * 1e-3 + p.length_scale  # the line's apex before a 1 mm leg
    assert solve_stop(p, [(0.0, 1e-3)], (a0, 0.0), 1.0).success  # a line of 2 mm: its half
    assert all(g == pytest.approx(maneuver._GRID[0]) for g in scanned)
    scanned.clear()
    a0 = 2.0 * (p.M + p.m) / p.m * 2.5e-4 + p.length_scale
    assert solve_stop(p, [(0.0, 2.5e-4)], (a0, 0.0), 1.0).success  # half a line of 0.5 mm
    assert any(g < maneuver._GRID[0] * 1e-3 for g in scanned)


def test_the_scan_is_coarse_where_the_curvature_is_continuous_at_every_join(monkeypatch):
    from skatetrace.tracing import maneuver

    assert maneuver._continuous([((1.0, 0.0, 0.0, 0.0), math.inf)])
    clothoid = [(maneuver._coefficients(k), ell) for k, ell in _chain((0.2, 0.3, 0.0, 0.0), 1.0, 4)]
    spec = [(k, 0.25 * (i + 1) if i < 3 else math.inf) for i, (k, _ell) in enumerate(clothoid)]
    assert maneuver._continuous(spec)
    # an inflection at a join: both sides are rounding, of either sign
    assert maneuver._continuous([((1.0, -2.0, 0.0, 0.0), 0.5), ((-1.4e-16, -2.0, 0.0, 0.0), math.inf)])
    assert not maneuver._continuous([((1.0, 0.0, 0.0, 0.0), 0.5), ((0.0, 0.0, 0.0, 0.0), math.inf)])  # arc, line
    assert not maneuver._continuous([((1.0, 0.0, 0.0, 0.0), 0.5), ((1.0 + 1e-9, 0.0, 0.0, 0.0), math.inf)])

    strides = []
    real = maneuver._scan

    def recorded(stopper, grid, length, coarse):
        strides.append(coarse)
        return real(stopper, grid, length, coarse)

    monkeypatch.setattr(maneuver, "_scan", recorded)
    p = SleighParams()
    assert solve_stop(p, _chain((0.2, 0.3, 0.0, 0.0), 1.0, 4), (0.0, 1.0), 1.0).success
    assert strides and set(strides) == {maneuver._COARSE}
    strides.clear()
    assert solve_stop(p, [(0.5, 0.5), (0.25, 0.5)], (0.0, 1.0), 1.0).success  # an arc into a wider one
    assert strides and set(strides) == {1}


def test_brent_ends_at_its_first_iterate_that_stops_within_the_scan_accuracy():
    from skatetrace.tracing import maneuver

    root, length = 3.7, 0.8
    runs = []

    def stopping_length(alpha):  # smooth and monotone, not linear in log alpha (Brent needs several steps)
        x = math.log(alpha / root)
        return length * math.exp(-x - 0.3 * x * x)

    class Fake:
        def run(self, alpha, rtol, atol):
            runs.append(alpha)
            return 1.0, np.array([0.0, 0.0, 0.0, 0.0, stopping_length(alpha)])

    grid = np.array([1.0, 10.0])
    alpha, _tau, slope = maneuver._scan_root(Fake(), grid, 0, 1, lambda k: (stopping_length(grid[k]), 1.0), length)
    close = [abs(math.log(stopping_length(a) / length)) <= maneuver._SCAN_CLOSE for a in runs]
    assert close[-1] and not any(close[:-1]) and alpha == runs[-1]
    assert abs(alpha / root - 1.0) < 1e-8 and slope < 0.0
