"""A compiled DOP853 integrator for the sleigh held on a curve (the manoeuvre solves).

A manoeuvre solve integrates many times (a bracketing scan, then the root's refinement), so the
integration dominates the time of a trace. This module is scipy's DOP853
(:class:`scipy.integrate.DOP853`) step for step (the same coefficients, error norm, step-size
control, initial step, event rule and 7th-order dense output), specialised to the
constrained system of :mod:`skatetrace.tracing.maneuver` and compiled with numba. A test compares it with
``solve_ivp(method="DOP853")`` on the same problem.

The system integrated is ``y = (p1, p2, a, b, s)`` under the control ``u = alpha t + beta`` (a
ramp, ``beta = 0``, for the manoeuvres; one affine piece of the planner's controls) through
*legs*: a leg ends where ``|s|`` reaches its switch length and the next one starts from that
state (a smooth join). On each leg the curvature is a cubic polynomial of the distance travelled since
the leg started::

    kappa(sigma) = c0 + c1 sigma + c2 sigma^2 + c3 sigma^3,    sigma = |s| - s_start,

with ``s_start`` the previous leg's switch length (0 for the first leg); a leg of constant
curvature is ``c1 = c2 = c3 = 0``. A leg that begins where the curvature jumps starts with scipy's
initial step, as a new ``solve_ivp`` call would; one that continues the curvature (a chain of
spirals) keeps the step size the previous leg proposed, which saves most of a restart per join. The curvature condition ``xi1 = kappa(s) xi2`` is algebraic, so
only ``kappa(s)`` (not its derivative) enters the right-hand side, the events and the step control.
Two terminal events may be armed: the speed along the blade vanishing (``"stopped"``) and the mass
coming within a distance of the singular point ``(0, -kappa(s) I / M)`` (``"singular"``).
An event (or a join) is located on its step's dense output to adjacent floating-point numbers,
as a bisection would, by the false position (:func:`_event_time`): some seven evaluations of the
event function where a bisection takes fifty (which was a third of the time of a manoeuvre solve's
integrations). Only the event being located is evaluated there (a join's needs no right-hand side),
and at a step's end the speed is the last stage's, not computed again.

Set the environment variable ``NUMBA_DISABLE_JIT=1`` to run the same code as plain Python.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from . import dop853 as rk
from .model import SleighParams, body_velocities, curvature_terms, holding_rates

__all__ = ["DenseSolution", "IntegrationResult", "MAX_NFEV", "integrate_legs", "load"]

#: Default budget of right-hand-side evaluations of one integration (:func:`integrate_legs`).
MAX_NFEV = 150_000

# scipy's DOP853 tableau (:mod:`skatetrace.dynamics.dop853`, shared with the compiled replay)
_NS, _A, _B, _C = rk.N_STAGES, rk.A, rk.B, rk.C
_A_EXTRA, _C_EXTRA, _POWER = rk.A_EXTRA, rk.C_EXTRA, rk.POWER

# Status codes of the compiled loop
_REACHED, _STOPPED, _SINGULAR = 0, 1, 2
_EXHAUSTED, _SMALL_STEP, _NONFINITE = -1, -2, -3
_MESSAGES = {
    _REACHED: "reached the end of the interval",
    _STOPPED: "the speed along the blade vanished",
    _SINGULAR: "the mass reached the singular point's neighbourhood",
    _EXHAUSTED: "step size collapsed (evaluation budget exhausted or the control law is singular)",
    _SMALL_STEP: "required step size is less than spacing between numbers",
    _NONFINITE: "the state became non-finite",
}


#: The model's arithmetic itself, compiled into the right-hand side and into
#: :mod:`skatetrace.tracing.leg_motion`'s loop; inlined by numba (called, the integrations took 11 %
#: longer), so each caller's error model holds: leg_motion's gives NaN at the singular point as numpy does.
_terms = njit(cache=True, inline="always")(curvature_terms)
_rates = njit(cache=True, inline="always", error_model="numpy")(holding_rates)
_body_velocities = njit(cache=True, inline="always")(body_velocities)


@njit(cache=True)
def _curvature(coef, s0, s):
    """The leg's curvature at arc length ``s``: Horner's rule in ``sigma = |s| - s0``.

    ``coef`` holds ``(c0, c1, c2, c3)``; with ``c1 = c2 = c3 = 0`` the result is ``c0`` exactly.
    """
    sigma = abs(s) - s0
    return coef[0] + sigma * (coef[1] + sigma * (coef[2] + sigma * coef[3]))


@njit(cache=True)
def _rhs(M, m, I, kappa, alpha, beta, t, y, out):
    """Right-hand side of ``(p1, p2, a, b, s)`` for the curvature ``kappa`` given at ``y``.

    The model's own arithmetic compiled (:func:`~skatetrace.dynamics.model.curvature_terms`,
    :func:`~skatetrace.dynamics.model.holding_rates`, :func:`~skatetrace.dynamics.model.body_velocities`),
    not a copy of its formulas. Returns False at the singular point itself.
    """
    p1, p2, a, b = y[0], y[1], y[2], y[3]
    u = alpha * t + beta
    c_a, c_b, c_0 = _terms(M, m, I, kappa, p1, p2, a, b)
    if not c_a * c_a + c_b * c_b > 0.0:
        return False
    ad, bd, _n = _rates(c_a, c_b, c_0, u)
    xi1, xi2, eta = _body_velocities(M, m, I, p1, p2, a, b, ad, bd)
    out[0] = -m * eta * xi2
    out[1] = m * eta * xi1
    out[2] = ad
    out[3] = bd
    out[4] = xi2
    return True


@njit(cache=True)
def _rhs_leg(M, m, I, coef, s0, alpha, beta, t, y, out):
    """:func:`_rhs` on a leg with curvature coefficients ``coef`` starting at ``|s| = s0``."""
    return _rhs(M, m, I, _curvature(coef, s0, y[4]), alpha, beta, t, y, out)


@njit(cache=True)
def _speed(M, m, I, coef, s0, alpha, beta, t, y, work):
    """Speed along the blade ``xi2`` (the ``"stopped"`` event); NaN at the singular point.

    ``work`` is a scratch array of 5 (the event is evaluated in tight loops: no allocation).
    """
    if not _rhs_leg(M, m, I, coef, s0, alpha, beta, t, y, work):
        return np.nan
    return work[4]


@njit(cache=True)
def _event_value(M, m, I, coef, s0, alpha, beta, t, y, switch, stop_event, sing_limit, e, work):
    """Event function ``e`` at ``(t, y)``: 0 the join ``|s| - switch``, 1 the speed, 2 the singular distance - limit.

    The singular point ``(0, -kappa I / M)`` moves with the curvature at ``y``'s ``|s|``. Only the
    speed needs the right-hand side. ``work`` is a scratch array of 5.
    """
    if e == 0:
        return abs(y[4]) - switch
    if e == 1:
        return _speed(M, m, I, coef, s0, alpha, beta, t, y, work) if stop_event else 1.0
    if sing_limit > 0.0:
        sing_b = -_curvature(coef, s0, y[4]) * I / M
        return math.hypot(y[2], y[3] - sing_b) - sing_limit
    return 1.0


@njit(cache=True)
def _event_values(M, m, I, coef, s0, alpha, beta, t, y, switch, stop_event, sing_limit, g, work, speed):
    """The three event functions at ``(t, y)`` (:func:`_event_value`) into ``g``.

    ``speed`` is the right-hand side's speed ``f[4]`` at the same ``(t, y)`` where the caller has
    it (the step's last stage, or a leg's first evaluation): the same number, not computed again.
    NaN computes it.
    """
    g[0] = _event_value(M, m, I, coef, s0, alpha, beta, t, y, switch, stop_event, sing_limit, 0, work)
    if stop_event and speed == speed:
        g[1] = speed
    else:
        g[1] = _event_value(M, m, I, coef, s0, alpha, beta, t, y, switch, stop_event, sing_limit, 1, work)
    g[2] = _event_value(M, m, I, coef, s0, alpha, beta, t, y, switch, stop_event, sing_limit, 2, work)


#: Evaluations of the event functions by the false position (:func:`_event_time`) before it gives way to bisection.
_FALSE_POSITION_STEPS = 12


@njit(cache=True)
def _event_time(M, m, I, coef, s0, alpha, beta, t, h, y, F, t_new, switch, stop_event, sing_limit, e, g_start, g_end,
                work, yint):
    """Where event ``e`` changes sign on the step ``[t, t_new]``, to adjacent floating-point numbers.

    The bracket ``[lo, hi]`` keeps ``g[e](lo)`` on the side of ``g_start`` (and nonzero, unless
    ``lo`` is the step's start with ``g_start = 0``) and ``hi`` past it, as a bisection would, and
    ends, as one does, where ``lo`` and ``hi`` are adjacent. Where the event function is monotone
    on the step that is the bisection's answer, bit for bit; where rounding makes it change sign
    more than once within a few ulps, either answer is such a pair. The points are the Illinois
    variant of the false position on the dense output: some seven evaluations of the event
    functions where a bisection takes fifty. Where the line meets zero at an end of the bracket
    (to rounding) the point is the float beside that end, inside it; after
    :data:`_FALSE_POSITION_STEPS` evaluations the rest is bisection.

    Returns ``(time, evaluations)``: ``hi`` (``lo`` where ``g_start = 0``), and how many times the
    event functions were evaluated.
    """
    lo, hi = t, t_new
    glo = g_start
    f_lo, f_hi = g_start, g_end  # the values the false position draws its line through
    side = 0  # which end moved last: -1 lo, 1 hi (Illinois halves the other's value when one moves twice)
    count = 0
    for _ in range(4096):
        mid = 0.5 * (lo + hi)
        if mid == lo or mid == hi:
            break
        if count < _FALSE_POSITION_STEPS and f_lo * f_hi <= 0.0 and f_lo != f_hi:
            x = lo + (hi - lo) * (f_lo / (f_lo - f_hi))
            if not ((lo < x < hi) or (hi < x < lo)):
                end, other = (lo, hi) if abs(x - lo) <= abs(x - hi) else (hi, lo)
                x = np.nextafter(end, other)
            mid = x
        value = _event_value(M, m, I, coef, s0, alpha, beta, mid, rk.interpolate_into(t, h, y, F, mid, yint), switch,
                             stop_event, sing_limit, e, work)
        count += 1
        if (value <= 0.0) == (glo <= 0.0) and value != 0.0:
            lo, glo, f_lo = mid, value, value
            if side == -1:
                f_hi *= 0.5
            side = -1
        else:
            hi, f_hi = mid, value
            if side == 1:
                f_lo *= 0.5
            side = 1
    return (hi if glo != 0.0 else lo), count


@njit(cache=True)
def _dense_coefficients(M, m, I, coef, s0, alpha, beta, t_old, h, y_old, y_new, f_new, K, Kx, ytmp, F):
    """The interpolant's coefficients ``F`` (7 x n) for the step just taken (3 extra stages).

    ``Kx`` (16 x n) and ``ytmp`` (n) are scratch arrays and ``F`` is written in place. Scalar
    loops, no temporaries (this runs on every step of a dense integration): the same operations
    in the same order as the array form of scipy's ``_dense_output_impl``.
    """
    n = y_old.size
    for s in range(_NS + 1):
        for i in range(n):
            Kx[s, i] = K[s, i]
    for s in range(_NS + 1, 16):
        row = s - _NS - 1
        for i in range(n):
            dy = 0.0
            for j in range(s):
                dy += _A_EXTRA[row, j] * Kx[j, i]
            ytmp[i] = y_old[i] + dy * h
        _rhs_leg(M, m, I, coef, s0, alpha, beta, t_old + _C_EXTRA[row] * h, ytmp, Kx[s])
    rk.dense_coefficients(Kx, h, y_old, y_new, f_new, F)
    return F


@njit(cache=True)
def _initial_step(M, m, I, coef, s0, alpha, beta, t0, y0, f0, t_bound, direction, rtol, atol):
    """scipy's ``select_initial_step`` for an 8th-order method (error estimator order 7)."""
    interval = abs(t_bound - t0)
    if interval == 0.0:
        return 0.0
    h0, d1, scale = rk.initial_step_trial(y0, f0, interval, rtol, atol)
    y1 = y0 + h0 * direction * f0
    f1 = np.empty(y0.size)
    _rhs_leg(M, m, I, coef, s0, alpha, beta, t0 + h0 * direction, y1, f1)
    return rk.initial_step(h0, d1, scale, f0, f1, interval)


@njit(cache=True)
def _grow(arr, n):
    # Element by element, here and wherever compiled code copies arrays: numba compiles an array-to-slice
    # assignment with its broadcasting and shape-mismatch error formatting (string code), seconds of a
    # first run's compilation for nothing (a copy is a copy).
    out = np.empty((2 * arr.shape[0],) + arr.shape[1:])
    flat_out = out.reshape(-1)
    flat_in = arr.reshape(-1)
    for i in range(n * (flat_in.size // max(arr.shape[0], 1))):
        flat_out[i] = flat_in[i]
    return out


@njit(cache=True)
def _run(M, m, I, y0, kappas, switches, alpha, beta, t_end, rtol, atol, stop_event, sing_limit, max_nfev, dense):
    """Integrate through the legs; see :func:`integrate_legs`.

    ``kappas`` is the (nlegs, 4) array of curvature coefficients ``c0..c3`` of the legs.
    Returns ``(status, leg, t, y, leg_bounds, steps, nsteps)``: with ``dense``, the first ``nsteps``
    rows of ``steps`` are the steps taken, one row each (:func:`_step_rows` reads them). One array,
    not five: each array returned is boxed for Python, some 0.3 us of every call.
    """
    n = y0.size
    nlegs = kappas.shape[0]
    direction = 1.0 if t_end >= 0.0 else -1.0
    t = 0.0
    y = y0.copy()
    leg_bounds = np.empty(nlegs + 1)
    leg_bounds[0] = 0.0
    cap = 64 if dense else 1
    steps = np.empty((cap, 3 + n * (1 + _POWER)))  # one row a step: see _step_rows
    nsteps = np.int64(0)  # not the literal 0: numba would compile _grow for Literal[int](0) as well as int64
    nfev = 0
    K = np.empty((_NS + 1, n))
    ytmp = np.empty(n)
    ynew = np.empty(n)
    kstage = np.empty(n)
    f = np.empty(n)
    f_new = np.empty(n)
    g_old = np.empty(3)
    g_new = np.empty(3)
    work = np.empty(n)  # scratch of the event functions
    yint = np.empty(n)  # the dense output where an event is looked for
    Kx = np.empty((16, n))  # scratch of the dense output's extra stages
    F_step = np.zeros((_POWER, n))  # the dense output of the current step, when it has one
    F_none = np.zeros((_POWER, n))  # stands for "no dense output" on steps that need none
    h_abs = 0.0
    for leg in range(nlegs):
        coef = kappas[leg]  # a view: (c0, c1, c2, c3) of this leg
        s0 = switches[leg - 1] if leg > 0 else 0.0  # |s| where this leg starts
        switch = switches[leg]
        if not _rhs_leg(M, m, I, coef, s0, alpha, beta, t, y, f):
            return _EXHAUSTED, leg, t, y, leg_bounds, steps, nsteps
        nfev += 1
        _event_values(M, m, I, coef, s0, alpha, beta, t, y, switch, stop_event, sing_limit, g_old, work, f[4])
        # Where the curvature is continuous across the join (a chain of spirals) the right-hand side
        # is too, and the step size the last leg proposed carries over; where it jumps the control
        # rates jump, and the step is chosen afresh as scipy would for a new solve_ivp call.
        smooth = False
        if leg > 0:
            s_prev = switches[leg - 2] if leg > 1 else 0.0
            k_end = _curvature(kappas[leg - 1], s_prev, s0)
            smooth = abs(k_end - coef[0]) <= 1e-12 * max(abs(k_end), abs(coef[0]), 1e-300)
        if not smooth:
            h_abs = _initial_step(M, m, I, coef, s0, alpha, beta, t, y, f, t_end, direction, rtol, atol)
            nfev += 1
        while True:
            if direction * (t_end - t) <= 0.0:
                leg_bounds[leg + 1] = t
                return _REACHED, leg, t, y, leg_bounds, steps, nsteps
            min_step = 10.0 * abs(np.nextafter(t, direction * np.inf) - t)
            if h_abs < min_step:
                h_abs = min_step
            accepted = False
            rejected = False
            while not accepted:
                if h_abs < min_step:
                    return _SMALL_STEP, leg, t, y, leg_bounds, steps, nsteps
                h = h_abs * direction
                t_new = t + h
                if direction * (t_new - t_end) > 0.0:
                    t_new = t_end
                h = t_new - t
                h_abs = abs(h)
                # one Runge-Kutta step (scipy's rk_step), written out without temporaries
                for i in range(n):
                    K[0, i] = f[i]
                ok = True
                for s in range(1, _NS):
                    for i in range(n):
                        acc = 0.0
                        for j in range(s):
                            acc += _A[s, j] * K[j, i]
                        ytmp[i] = y[i] + acc * h
                    if not _rhs_leg(M, m, I, coef, s0, alpha, beta, t + _C[s] * h, ytmp, kstage):
                        ok = False
                    for i in range(n):
                        K[s, i] = kstage[i]
                nfev += _NS
                for i in range(n):
                    acc = 0.0
                    for j in range(_NS):
                        acc += _B[j] * K[j, i]
                    ynew[i] = y[i] + h * acc
                if not _rhs_leg(M, m, I, coef, s0, alpha, beta, t + h, ynew, f_new):
                    ok = False
                nfev += 1
                if not ok or nfev > max_nfev:
                    return _EXHAUSTED, leg, t, y, leg_bounds, steps, nsteps
                for i in range(n):
                    K[_NS, i] = f_new[i]
                err = rk.error_norm(K, y, ynew, h_abs, rtol, atol)
                h_abs *= rk.step_factor(err, rejected)
                accepted = err < 1.0
                rejected = not accepted
            finite = True
            for i in range(n):
                if not math.isfinite(ynew[i]):
                    finite = False
            if not finite:
                return _NONFINITE, leg, t, y, leg_bounds, steps, nsteps
            # events: a sign change (or touch of zero) between the step's ends, as in solve_ivp
            # f_new is the right-hand side at t + h: the speed there is the event's where that is t_new
            _event_values(M, m, I, coef, s0, alpha, beta, t_new, ynew, switch, stop_event, sing_limit, g_new, work,
                          f_new[4] if t + h == t_new else np.nan)
            active = False
            for e in range(3):
                if (g_old[e] <= 0.0 and g_new[e] >= 0.0) or (g_old[e] >= 0.0 and g_new[e] <= 0.0):
                    active = True
            F = F_none
            if dense or active:
                F = _dense_coefficients(M, m, I, coef, s0, alpha, beta, t, h, y, ynew, f_new, K, Kx, ytmp, F_step)
                nfev += 3
            hit = -1
            t_hit = t_new
            if active:
                for e in range(3):
                    if not ((g_old[e] <= 0.0 and g_new[e] >= 0.0) or (g_old[e] >= 0.0 and g_new[e] <= 0.0)):
                        continue
                    root, _count = _event_time(M, m, I, coef, s0, alpha, beta, t, h, y, F, t_new, switch,
                                               stop_event, sing_limit, e, g_old[e], g_new[e], work, yint)
                    if hit < 0 or direction * (root - t_hit) < 0.0:
                        hit, t_hit = e, root
            if dense:
                if nsteps == steps.shape[0]:
                    steps = _grow(steps, nsteps)
                steps[nsteps, 0] = t
                steps[nsteps, 1] = h
                steps[nsteps, 2] = leg
                for i in range(n):
                    steps[nsteps, 3 + i] = y[i]
                for r in range(_POWER):
                    for i in range(n):
                        steps[nsteps, 3 + n + r * n + i] = F[r, i]
                nsteps += 1
            if hit >= 0:
                yh = rk.interpolate_into(t, h, y, F, t_hit, np.empty(n))
                if hit == 0 and leg + 1 < nlegs:
                    t, y = t_hit, yh
                    leg_bounds[leg + 1] = t
                    break  # next leg, from the join
                leg_bounds[leg + 1] = t_hit
                status = _REACHED if hit == 0 else (_STOPPED if hit == 1 else _SINGULAR)
                return status, leg, t_hit, yh, leg_bounds, steps, nsteps
            t = t_new
            for i in range(n):
                y[i] = ynew[i]
                f[i] = f_new[i]
            for e in range(3):
                g_old[e] = g_new[e]
    return _REACHED, nlegs - 1, t, y, leg_bounds, steps, nsteps


def _step_rows(steps: np.ndarray, nsteps: int, n: int):
    """The dense steps packed by :func:`_run`, as views ``(t_old, h, leg, y_old, F)``; ``F`` is ``(nsteps, 7, n)``.

    A row holds the step's start time, its signed size, its leg, the state at its start and the
    interpolant's coefficients, in that order.
    """
    rows = steps[:nsteps]
    return rows[:, 0], rows[:, 1], rows[:, 2], rows[:, 3:3 + n], rows[:, 3 + n:].reshape(nsteps, _POWER, n)


@njit(cache=True)
def _evaluate_steps(t_old, h, y_old, F, ends, t):
    """The dense output at times ``t``: shape ``(t.size, n)``.

    Each time is taken on the last step whose left end (``ends``, in increasing order) is at or
    before it, or on the first step where it is before them all: ``np.searchsorted(ends, t,
    "right") - 1`` kept within the steps, so that a time outside them is extrapolated from the
    nearest, as scipy does. There :func:`skatetrace.dynamics.dop853.interpolate_into` is written
    out: for each component the same operations in the same order (scipy's vectorised form), so
    the same bits, each component's sum kept in a register instead of a view of the output. This
    samples thousands of points per section: the 270 points of an arc's stop, their steps found
    too, in 12 us against 28 us.
    """
    n = y_old.shape[1]
    npow = F.shape[1]
    last = ends.size - 1
    out = np.empty((t.size, n))
    for p in range(t.size):
        i = min(max(np.searchsorted(ends, t[p], side="right") - 1, 0), last)
        x = (t[p] - t_old[i]) / h[i]
        for k in range(n):
            acc = 0.0
            for q in range(npow - 1, -1, -1):
                w = x if (npow - 1 - q) % 2 == 0 else 1.0 - x
                acc = (acc + F[i, q, k]) * w
            out[p, k] = acc + y_old[i, k]
    return out


class DenseSolution:
    """Piecewise DOP853 interpolant of one leg, callable like scipy's ``OdeSolution``.

    ``sol(t)`` returns shape ``(5,)`` for a scalar ``t`` and ``(5, n)`` for an array; times
    outside the steps are extrapolated from the nearest step (as scipy does).
    """

    __slots__ = ("t_old", "h", "y_old", "F", "_ends")

    def __init__(self, t_old: np.ndarray, h: np.ndarray, y_old: np.ndarray, F: np.ndarray):
        order = np.argsort(t_old) if h.size and h[0] < 0 else np.arange(t_old.size)
        self.t_old, self.h, self.y_old, self.F = t_old[order], h[order], y_old[order], F[order]
        self._ends = np.minimum(self.t_old, self.t_old + self.h)  # left end of each step

    @property
    def ends(self) -> np.ndarray:
        """The left end of each step, in increasing order (where :meth:`__call__` looks a time up)."""
        return self._ends

    def __getstate__(self):
        return (self.t_old, self.h, self.y_old, self.F)

    def __setstate__(self, state):
        self.__init__(*state)

    def __call__(self, t):
        t = np.asarray(t, dtype=float)
        scalar = t.ndim == 0
        tt = np.atleast_1d(t)
        y = _evaluate_steps(self.t_old, self.h, self.y_old, self.F, self._ends, tt)
        return y[0] if scalar else y.T


@dataclass(frozen=True, slots=True)
class IntegrationResult:
    """Outcome of :func:`integrate_legs`.

    ``status`` is 0 (reached ``t_end``, or the last join with no leg after it), ``"stopped"`` or
    ``"singular"`` for a terminal event, or a negative code for a failure (see ``message``).
    ``leg_bounds`` are the times at which each leg started and the last one ended; ``legs`` the
    dense solutions (``dense=True`` and no failure only), one per leg entered.
    """

    status: int
    hit: str | None
    message: str
    t: float
    y: np.ndarray
    leg_bounds: np.ndarray
    legs: tuple[DenseSolution, ...]

    @property
    def nlegs(self) -> int:
        return self.leg_bounds.size - 1


def integrate_legs(params: SleighParams, y0, kappas, switches, alpha: float, t_end: float, *,
                   rtol: float, atol: float, stop_event: bool = False, singular_limit: float = 0.0,
                   max_nfev: int = MAX_NFEV, dense: bool = False, beta: float = 0.0) -> IntegrationResult:
    """Integrate ``(p1, p2, a, b, s)`` from ``t = 0`` under ``u = alpha t + beta`` through legs.

    Leg ``k`` runs from ``|s| = s_start`` (``switches[k - 1]``, or 0 for the first leg) to
    ``|s| = switches[k]`` and holds the curvature::

        kappa(sigma) = c0 + c1 sigma + c2 sigma^2 + c3 sigma^3,    sigma = |s| - s_start,

    evaluated at the current state's ``|s|`` (``s`` runs negative backwards in time, hence the
    absolute value).

    Parameters
    ----------
    params : SleighParams
    y0 : array_like, shape (5,)
        Initial state ``(p1, p2, a, b, s)``.
    kappas : array_like, shape (n,) or (n, 4)
        Curvature of each leg: shape ``(n,)`` gives a constant curvature per leg (the same as
        ``c0`` with ``c1 = c2 = c3 = 0``); shape ``(n, 4)`` gives the polynomial coefficients
        ``(c0, c1, c2, c3)`` of each leg.
    switches : array_like, shape (n,)
        The cumulative ``|s|`` at which each leg ends (``inf`` for the last).
    alpha : float
        Slope of the ramp control ``u = alpha t + beta``.
    t_end : float
        Final time; negative integrates backwards.
    rtol, atol : float
        Tolerances of the step-size control.
    stop_event : bool
        End where the speed along the blade vanishes.
    singular_limit : float
        If positive, end where the mass comes within this distance of the singular point
        ``(0, -kappa I / M)``, with ``kappa`` the curvature at the current ``|s|``.
    max_nfev : int
        Budget of right-hand-side evaluations; running out means the step size collapsed.
    dense : bool
        Keep the dense output of every step.
    beta : float
        Value of the control at ``t = 0`` (0 for the manoeuvres' ramps; the planner's controls are
        piecewise linear in time, one affine piece per call).

    Returns
    -------
    IntegrationResult

    Raises
    ------
    ValueError
        If ``kappas`` is neither of shape ``(n,)`` nor ``(n, 4)``, if ``switches`` is not of
        shape ``(n,)`` with the same ``n``, or if there is no leg.
    """
    kap = np.asarray(kappas, dtype=float)
    sw = np.ascontiguousarray(switches, dtype=float)
    if kap.ndim == 1:
        coef = np.zeros((kap.shape[0], 4))
        coef[:, 0] = kap
    elif kap.ndim == 2 and kap.shape[1] == 4:
        coef = np.ascontiguousarray(kap)
    else:
        raise ValueError(f"kappas must have shape (n,) (constant curvature per leg) or (n, 4) "
                         f"(cubic coefficients c0..c3 per leg), got shape {kap.shape}")
    if sw.ndim != 1 or sw.shape[0] != coef.shape[0]:
        raise ValueError(f"switches must have shape ({coef.shape[0]},) to match the {coef.shape[0]} legs of "
                         f"kappas, got shape {sw.shape}")
    if coef.shape[0] == 0:
        raise ValueError("at least one leg is required")
    y = np.asarray(y0, dtype=float).copy()
    out = _run(params.M, params.m, params.I, y, coef, sw, float(alpha), float(beta), float(t_end), float(rtol), float(atol),
               bool(stop_event), float(singular_limit), int(max_nfev), bool(dense))
    status, leg, t, yf, bounds, steps, ns = out
    nlegs = int(leg) + 1
    legs = ()
    if dense and status >= 0:
        st, sh, sleg, sy, sF = _step_rows(steps, ns, y.size)
        legs = tuple(DenseSolution(st[sel], sh[sel], sy[sel], sF[sel]) for sel in (sleg == k for k in range(nlegs)))
    bounds = np.array(bounds[:nlegs + 1])
    bounds[-1] = t  # where the last leg entered ended (unset by a failure)
    hit = {_STOPPED: "stopped", _SINGULAR: "singular"}.get(int(status))
    code = 0 if status >= 0 else int(status)
    return IntegrationResult(status=code, hit=hit, message=_MESSAGES[int(status)], t=float(t), y=np.asarray(yf),
                             leg_bounds=bounds, legs=legs)


@functools.cache
def load() -> None:
    """Load the integrator's machine code now (compiled the first time after install, else from numba's cache).

    Numba does it on the first call; a caller that times its work, or forks workers that should
    share the code, calls this first. About 0.2 s from the cache; nothing once loaded (the call is
    remembered for the process: its integration took some 30 us of every ``trace_figure``).
    """
    res = integrate_legs(SleighParams(), np.array([1.0, 0.0, 0.5, 0.5, 0.0]), [1.0], [np.inf], 0.0, 1e-3,
                         rtol=1e-9, atol=1e-12, dense=True)
    res.legs[0](np.array([5e-4]))


def final_state(params: SleighParams, y0: np.ndarray, coef: np.ndarray, switches: np.ndarray, alpha: float,
                t_end: float, *, rtol: float, atol: float, stop_event: bool = False, singular_limit: float = 0.0,
                max_nfev: int = MAX_NFEV, beta: float = 0.0) -> tuple[str | None, float, np.ndarray]:
    """Where :func:`integrate_legs` ends, without its checks and bookkeeping (no dense output).

    For the many short integrations of a manoeuvre solve. ``coef`` must be a float array of shape
    ``(n, 4)`` and ``switches`` one of shape ``(n,)``, as :func:`integrate_legs` makes them.
    Returns ``(outcome, t, y)``: ``outcome`` is ``"stopped"`` or ``"singular"`` for a terminal
    event, ``"reached"`` for the end of the interval (or of the last leg) and ``None`` for a failure.
    """
    out = _run(params.M, params.m, params.I, y0, coef, switches, float(alpha), float(beta), float(t_end), float(rtol),
               float(atol), bool(stop_event), float(singular_limit), int(max_nfev), False)
    status = int(out[0])
    outcome = {_REACHED: "reached", _STOPPED: "stopped", _SINGULAR: "singular"}.get(status)
    return outcome, float(out[2]), np.asarray(out[3])
