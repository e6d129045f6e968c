"""Constrained dynamics of the sleigh on a curve, and the manoeuvres that start and stop it.

While the blade follows a curve of curvature ``kappa`` the control rates satisfy the curvature
condition ``c_a adot + c_b bdot + c_0 = 0`` (``model.curvature_coefficients``). We keep both rates
as unknowns and split them along the unit vectors of ``c = (c_a, c_b)``::

    (adot, bdot) = u * n - c_0 * c / |c|^2,     n = (-c_b, c_a) / |c|

``u(t)`` is the free control: the speed of the mass along the direction that leaves the curvature
unchanged. The split is singular only where ``c = 0``, the single point ``(0, -kappa I / M)``
(PHYSICS.md), unlike the paper's choice of ``bdot`` as the dependent rate (singular at ``a = 0``
and ``b = (M + m) / (kappa m)``).

A *glide* is the steady state of this system: the mass is locked at ``(0, b)`` on an arc (any
``(a, b)`` on a line) and the sleigh runs along the curve at constant speed. A *stop* starts in a
glide and ramps ``u = alpha t`` until the speed vanishes; a *launch* is the same integrated
backwards in time. Either may run through several smooth joins (a change of curvature with the
state continuous), so a smooth piece of several arcs and lines is a launch, one glide and a stop.
On a spiral (curvature varying along the piece) there is no steady glide; the apex is then an
instant with the mass momentarily at rest relative to the blade, and the legs carry the
curvature as a cubic of the distance travelled. Each manoeuvre is a small boundary-value problem
in (alpha, duration): the duration is where the speed first vanishes (an event of the
integration), so it is one equation in alpha, the stopping length. Its root is bracketed on a
geometric grid of alpha, found at a moderate accuracy by Brent's method and polished at full
accuracy by the secant method; should that fail, Brent's method at full accuracy and then Newton's
method on (alpha, duration) (MINPACK's hybrid method) take over. Those fallbacks serve the
ill-conditioned stops (the speed grazing zero before the end) and cost many integrations at full
accuracy, so a caller with other candidates may leave them out (``fallback=False``). A launch
over the same curve as its stop from a glide at ``a = 0`` is the stop reversed in time
(:func:`~skatetrace.tracing.mirror.mirrored_maneuver`).

The state integrated here is ``(p1, p2, a, b, s)``, ``s`` the arc length travelled.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Callable

import numpy as np
from scipy.optimize import brentq, root

from ..dynamics.integrator import final_state, integrate_legs
from ..dynamics.model import SleighParams, curvature_coefficients, holding_rates, singular_point, velocities
from ..figures.geometry import cubic_at

__all__ = ["Leg", "ManeuverSolution", "glide_state", "constrained_rates", "solve_stop"]


@dataclass(frozen=True, slots=True)
class Leg:
    """One stretch of the curve inside a manoeuvre: a dense solution on ``[t0, t1]``.

    The curvature on the leg is ``c0 + c1 sigma + c2 sigma^2 + c3 sigma^3`` with ``coefficients =
    (c0, c1, c2, c3)`` and ``sigma = |s| - s0`` the distance travelled since the leg began (from
    the glide, backwards for a launch); constant on an arc or a line.
    """

    coefficients: tuple[float, float, float, float]
    t0: float
    t1: float
    sol: object  # DenseSolution of (p1, p2, a, b, s), callable like scipy's OdeSolution
    s0: float = 0.0

    def kappa_at(self, s) -> np.ndarray:
        """Curvature at the manoeuvre's arc-length coordinate ``s`` (signed, as integrated)."""
        return cubic_at(self.coefficients, np.abs(np.asarray(s, dtype=float)) - self.s0)


@dataclass(frozen=True, slots=True, kw_only=True)
class ManeuverSolution:
    """Result of one manoeuvre solve.

    ``params`` are the free-control coefficients, ``duration`` the signed duration (negative for a
    launch, which is integrated backwards from its glide). ``residuals`` are the boundary
    conditions at the solution; ``min_singular_distance`` the closest approach of the mass to the
    singular point. ``deferred`` marks a failure solved with ``fallback=False`` where a bracket
    of the stopping length held a stop that only the full-accuracy fallbacks could have found.
    """

    kind: str
    success: bool
    message: str
    params: tuple[float, ...]
    duration: float
    legs: tuple[Leg, ...]
    residuals: dict[str, float] = field(default_factory=dict)
    min_singular_distance: float = math.inf
    nfev: int = 0
    basis: str = "ramp"
    deferred: bool = False

    @property
    def end(self) -> np.ndarray:
        """State ``(p1, p2, a, b, s)`` at the end of the manoeuvre."""
        leg = self.legs[-1]
        return leg.sol(leg.t1)

    def control(self, t):
        """Free control ``u(t)`` of this manoeuvre."""
        return _basis(self.basis, self.params, self.duration)(t)


def _basis(kind: str, params, duration) -> Callable[[float], float]:
    if kind == "ramp":
        (alpha,) = params
        return lambda t: alpha * t
    if kind == "affine":
        alpha, beta = params
        return lambda t: alpha * t + beta
    if kind == "sines":
        a1, a2 = params
        w = math.pi / duration
        return lambda t: a1 * np.sin(w * t) + a2 * np.sin(2.0 * w * t)
    raise ValueError(f"unknown control basis {kind!r}")


def glide_state(params: SleighParams, kappa: float, a: float, b: float, speed: float) -> np.ndarray:
    """Momenta of the steady glide with the mass locked at ``(a, b)``.

    Returns ``(p1, p2)`` such that ``xi2 = speed`` and ``xi1 = kappa * speed`` with
    ``adot = bdot = 0``. This is steady (``eta = 0``) only if ``kappa == 0`` or ``a == 0``.
    """
    M, m, I = params.M, params.m, params.I
    xi1, xi2 = kappa * speed, speed
    p1 = (I + m * (a * a + b * b)) * xi1 - m * b * xi2
    p2 = (M + m) * xi2 - m * b * xi1
    return np.array([p1, p2])


def constrained_rates(params: SleighParams, kappa, p1, p2, a, b, u):
    """Control rates ``(adot, bdot)`` that hold the curvature, for free control ``u``.

    Vectorised. Returns ``(adot, bdot, |c|)``; ``|c| = 0`` is the singular point.
    """
    return holding_rates(*curvature_coefficients(params, kappa, p1, p2, a, b), u)


def _coefficients(kappa) -> tuple[float, float, float, float]:
    """A leg's curvature as cubic coefficients: a number (constant) or up to four coefficients."""
    if np.ndim(kappa) == 0:
        return (float(kappa), 0.0, 0.0, 0.0)
    c = [float(v) for v in kappa]
    return tuple(c + [0.0] * (4 - len(c)))


def _continuous(legs_spec) -> bool:
    """Whether the curvature is continuous across every join of legs ``[(coefficients, s_switch), ...]``.

    True for a single leg and for a chain of spirals (exact mode's curvature splines); False where
    it jumps at a join (an arc into a line or an arc of another radius). Continuous means equal
    within ``1e-12`` of the largest curvature the legs start with: at an inflection both sides are
    rounding (``1e-16``), and of either sign.
    """
    scale = max(abs(coeffs[0]) for coeffs, _ in legs_spec)
    start = 0.0
    for (coeffs, switch), (following, _) in zip(legs_spec, legs_spec[1:]):
        end = cubic_at(coeffs, switch - start)
        if not abs(end - following[0]) <= 1e-12 * max(abs(end), abs(following[0]), scale, 1e-300):
            return False
        start = switch
    return True


def _kappa_at(legs_spec, s: float) -> float:
    """Curvature at ``|s|`` on legs ``[(coefficients, s_switch), ...]``."""
    start = 0.0
    for coeffs, switch in legs_spec:
        if abs(s) <= switch:
            break
        start = switch
    return cubic_at(coeffs, abs(s) - start)


def _integrate(params, y0, legs_spec, alpha, t_end, *, rtol, atol, stop=False, singular_limit=0.0, dense=True):
    """Integrate the constrained system under ``u = alpha t`` through legs ``[(coefficients, s_switch), ...]``.

    A leg ends when ``|s|`` reaches its ``s_switch`` (the last leg's is ``inf``) or at ``t_end``.
    ``stop`` and ``singular_limit`` arm the terminal events of :func:`integrate_legs`. Returns
    ``(legs, status, t, y, hit)``: the legs entered (``None`` each unless ``dense``), 0 or a
    negative failure code, the final time and state, and the name of the terminal event hit.
    """
    res = integrate_legs(params, y0, np.array([k for k, _ in legs_spec], dtype=float).reshape(-1, 4),
                         [s for _, s in legs_spec], alpha, t_end,
                         rtol=rtol, atol=atol, stop_event=stop, singular_limit=singular_limit,
                         max_nfev=_MAX_EVALUATIONS, dense=dense)
    bounds = res.leg_bounds
    legs = [Leg(legs_spec[i][0], float(bounds[i]), float(bounds[i + 1]), res.legs[i] if res.legs else None,
                float(legs_spec[i - 1][1]) if i else 0.0)
            for i in range(res.nlegs)]
    return legs, res.status, res.t, res.y, res.hit


_MAX_EVALUATIONS = 150_000 * 4  # per integration: only near a blow-up does the step size collapse like this


def _end_speed(params, legs_spec, y, u):
    p1, p2, a, b, s = y
    ad, bd, _n = constrained_rates(params, _kappa_at(legs_spec, s), p1, p2, a, b, u)
    return velocities(params, p1, p2, a, b, ad, bd)[1]


def _singular_distances(params, legs, n=400):
    """Closest approach of the mass to the singular point on ``n`` samples per leg, and its distance at the start.

    The start (the glide, the first sample) is shared by every candidate solution of a manoeuvre,
    so no candidate can come out farther than that.
    """
    best = start = math.inf
    for i, leg in enumerate(legs):
        ts = np.linspace(leg.t0, leg.t1, n)
        y = leg.sol(ts)
        sb = -leg.kappa_at(y[4]) * params.I / params.M
        d = np.hypot(y[2], y[3] - sb)
        best = min(best, float(np.min(d)))
        if i == 0:
            start = float(d[0])
    return best, start


# The bracketing scan: multiples of the natural ramp slope ``speed^3 / length^2``. alpha scales
# like 1/length^2 on an arc and 1/length on a line: a wide grid covers both.
_GRID = np.geomspace(1e-3, 2e3, 29)
# Where the curvature is continuous along the legs (a single leg, or exact mode's chains of spirals:
# _continuous) the scan looks at every _COARSE-th grid point first (see _first_bracket); where it
# jumps at a join, at every point, since a stop that reaches such a join makes the stopping length
# jump too (plateaus at the join and spikes one grid point wide are seen). Exact mode's chains were
# scanned point by point before 2026-11-29: nanosvg-drawing's 344 scans of chains took 9,337
# integrations (3.2 s), and 4,730 (2.1 s) now.
_COARSE = 4
# Where neither sign of alpha has a bracket on the grid and its weakest ramp already stops the blade
# short of the length, the scan goes on below it, down to a millionth of it, at the grid's ratio
# (the last point is the grid's first; see _brackets). On a line the stopping length falls as
# 1 / alpha, and a ramp of alpha ~ speed^2 / length is needed: below the grid for a line shorter
# than about 1.3 mm (in model units, whatever the model's size).
_BELOW = _GRID[0] * (_GRID[1] / _GRID[0]) ** -np.arange(27, -1, -1)
# Accuracy of the integrations at the grid points (they only tell on which side of the length the
# stop falls, and whether there is one) and of Brent's method on the bracket found.
_GRID_RTOL, _GRID_ATOL = 1e-6, 1e-8
_SCAN_RTOL, _SCAN_ATOL = 1e-9, 1e-11
# That root is found to this relative precision in alpha, then polished at full accuracy by the
# secant method (at most _SECANT_STEPS further integrations). Brent's method at full accuracy to
# adjacent floating-point numbers took some fifteen integrations; this takes two or three.
_SCAN_XTOL = 1e-9
_SECANT_STEPS = 8
# Brent's method ends early at an iterate whose stop falls within this share of the length (in
# log): as close as the scan's accuracy tells. Its last steps only shrink the bracket to _SCAN_XTOL
# about a root it has already met, two or three integrations of some five to eight.
_SCAN_CLOSE = 1e-9
# A grid point's integration is given up once the blade has run this many times the length
# without stopping (a weak ramp glides on for most of the time allowed, some ten times the cost
# of a stop near the length); such a point stands for "farther, or never" (_FAR) where that
# settles the scan, and is integrated in full where it does not (see _first_bracket).
_FAR_LENGTHS = 8.0
_FAR = "far"


class _NoStop(Exception):
    """An integration that did not end with the speed vanishing (no stop, singular, failure)."""


class _Close(Exception):
    """Brent's iterate ``x`` (``args``) stops within :data:`_SCAN_CLOSE` of the length: the root, as the scan tells."""


class _Beyond(_NoStop):
    """An integration given up at an arc length (:meth:`_Stopper.run`): whether it stops beyond is not known."""


class _Stopper:
    """Event-located stops of one manoeuvre: ``run(alpha)`` integrates until the speed vanishes.

    Counts the integrations in ``nfev``.
    """

    def __init__(self, params, y0, legs_spec, t_max, singular_limit):
        self.params, self.y0 = params, y0
        # the legs as the compiled integrator takes them, made once for all the runs
        self.coef = np.array([k for k, _ in legs_spec], dtype=float).reshape(-1, 4)
        self.switches = np.array([s for _, s in legs_spec], dtype=float)
        self.t_max, self.singular_limit = t_max, singular_limit
        self.nfev = 0

    def run(self, alpha, rtol, atol, beyond=math.inf):
        """``(tau, y)`` at the first stop under ``u = alpha t``; raises :class:`_NoStop` otherwise.

        ``beyond``: an arc length at which to give up, raising :class:`_Beyond`: the stop, if
        there is one, is farther.
        """
        self.nfev += 1
        switches = self.switches
        if beyond < switches[-1]:
            switches = switches.copy()  # the last leg ends there, and with it the integration
            switches[-1] = max(beyond, switches[-2] if switches.size > 1 else 0.0)
        hit, tf, yf = final_state(self.params, self.y0, self.coef, switches, alpha, self.t_max, rtol=rtol,
                                  atol=atol, stop_event=True, singular_limit=self.singular_limit,
                                  max_nfev=_MAX_EVALUATIONS)
        if hit == "reached" and switches is not self.switches and abs(tf) < abs(self.t_max):
            raise _Beyond  # ended where the last leg does (to the event's rounding), before the time allowed
        if hit != "stopped":
            raise _NoStop
        return tf, yf


def _first_bracket(length_at, start, stop, length, coarse):
    """Grid indices ``(i, j)`` of the first bracket of ``length`` among points ``start..stop - 1``.

    ``length_at(i)`` is ``(stopping length, time)`` at grid point ``i``, or ``None`` where the ramp
    does not stop the sleigh. Brackets are looked for in ``|alpha|`` order between points ``coarse``
    apart (the fine grid's points in between are not integrated). Where the stop comes or goes
    between two such points the fine points there are all looked at, so that a root next to the
    edge of the stopping range is found as by the full scan; where both points stop on the same
    side of ``length``, or neither stops, there is taken to be no root in between. On a single leg
    the stopping length changes slowly and monotonically along the grid wherever the ramp stops the
    sleigh (a pair of roots, or an island of stops, within a factor ``1.68^coarse`` in alpha has not
    been seen), and so on a chain of legs whose curvature is continuous at the joins; across joins
    where the curvature jumps it does not, and there ``coarse`` is 1: every point, as the full scan.
    A point given up far beyond the length (:data:`_FAR`) is integrated in full (``length_at(i,
    True)``) only beside one that stops short of the length, or as the stronger of two points apart
    beside one that stops beyond it: beside one that does not stop the fine points are looked at.
    """
    i = start
    while i < stop - 1:
        j = min(i + coarse, stop - 1)
        li, lj = length_at(i), length_at(j)
        if li is _FAR or lj is _FAR:
            # A weak ramp given up far beyond the length stops there or never. Where the stronger
            # one is given up too, or stops beyond the length, there is no root between (the
            # stopping length falls as the ramp strengthens, as above); the other pairs are looked
            # at below, integrated in full only where that can tell a bracket.
            if li is _FAR and (lj is _FAR or (lj is not None and lj[0] > length)):
                i = j
                continue
            short = any(v is not None and v is not _FAR and v[0] <= length for v in (li, lj))
            if not short and (j - i == 1 or li is None or lj is None):
                # No bracket between the two (the far one stops beyond the length, or never). In full
                # it would tell whether the stop comes or goes between them: the fine points between
                # tell that too where one does not stop, and are looked at instead.
                fine = _first_bracket(length_at, i, j + 1, length, 1) if j - i > 1 else None
                if fine is not None:
                    return fine
                i = j
                continue
            li, lj = length_at(i, True), length_at(j, True)
        if li is not None and lj is not None:
            if (li[0] - length) * (lj[0] - length) <= 0.0:
                return i, j
        elif (li is None) != (lj is None) and j - i > 1:
            fine = _first_bracket(length_at, i, j + 1, length, 1)
            if fine is not None:
                return fine
        i = j
    return None


def _interpolated_guess(grid, i, j, li, lj, length):
    """``(alpha, tau)`` interpolated on a bracket, log-linearly in the stopping length."""
    (l1, t1), (l2, t2), a1, a2 = li, lj, grid[i], grid[j]
    w = (math.log(l1) - math.log(length)) / (math.log(l1) - math.log(l2)) if l1 != l2 else 0.5
    return a1 * (a2 / a1) ** w, t1 + w * (t2 - t1)


def _scan_root(stopper, grid, i, j, length_at, length):
    """Brent's method at the scan's accuracy for the root on ``grid[i..j]``, in ``log |alpha|``.

    It ends at its first iterate whose stop falls within :data:`_SCAN_CLOSE` of the length, or where
    its bracket is down to :data:`_SCAN_XTOL`. Returns ``(alpha, tau, slope)``: the root, the
    stopping time there and the slope of the stopping length in alpha (a secant over the nearest
    point tried at least ``1e-6`` away, where the scan's inaccuracy hardly shows; None if there is
    none). Raises :class:`_NoStop`.
    """
    direction = math.copysign(1.0, grid[i])
    seen = {math.log(abs(grid[k])): length_at(k) for k in (i, j)}

    def excess(x):
        if x not in seen:
            tau, yf = stopper.run(direction * math.exp(x), _SCAN_RTOL, _SCAN_ATOL)
            seen[x] = (abs(yf[4]), tau)
            if abs(math.log(max(seen[x][0], 1e-300) / length)) <= _SCAN_CLOSE:
                raise _Close(x)
        return math.log(max(seen[x][0], 1e-300) / length)

    xi, xj = math.log(abs(grid[i])), math.log(abs(grid[j]))
    try:
        x = brentq(excess, xi, xj, xtol=_SCAN_XTOL, rtol=4.0 * np.finfo(float).eps, maxiter=200)
    except _Close as close:
        (x,) = close.args
    excess(x)
    far = [u for u in seen if abs(u - x) >= 1e-6]
    slope = None
    if far:
        u = min(far, key=lambda v: abs(v - x))
        slope = (seen[u][0] - seen[x][0]) / (direction * (math.exp(u) - math.exp(x)))
    return direction * math.exp(x), seen[x][1], slope


def _scan(stopper, grid, length, coarse):
    """The first bracket of the stopping length along ``grid`` (one sign of alpha), or None.

    Returns ``(a1, a2, root, guess)``: neighbouring grid points ``a1, a2`` between which the
    stopping length crosses ``length``; the root ``(alpha, tau)`` there at the scan's accuracy, or
    None where a ramp inside the bracket does not stop; and ``guess()``, the root interpolated on
    the bracket (the start of Newton's method, should all else fail). ``coarse`` is the stride of
    the first look along the grid (see :func:`_first_bracket`).
    """
    cache = {}

    def length_at(k, full=False):
        if k not in cache or (full and cache[k] is _FAR):
            try:
                tau, yf = stopper.run(grid[k], _GRID_RTOL, _GRID_ATOL, math.inf if full else _FAR_LENGTHS * length)
                cache[k] = (abs(yf[4]), tau)
            except _Beyond:
                cache[k] = _FAR
            except _NoStop:
                cache[k] = None
        return cache[k]

    def root_on(i, j):
        try:
            return _scan_root(stopper, grid, i, j, length_at, length)
        except (_NoStop, RuntimeError, ValueError):
            return None

    start = 0
    while (bracket := _first_bracket(length_at, start, grid.size, length, coarse)) is not None:
        i, j = bracket
        root = root_on(i, j)
        if root is None and j - i > 1:
            # a ramp inside the coarse bracket does not stop: every grid point in it is looked at
            fine = _first_bracket(length_at, i, j + 1, length, 1)
            if fine is None:
                start = j
                continue
            i, j = fine
            root = root_on(i, j)
        if root is not None and j - i > 1:
            # the grid points next to the root (for Brent's method at full accuracy, should the
            # polish fail)
            k = i + int(np.searchsorted(np.abs(grid[i:j + 1]), abs(root[0]), side="right")) - 1
            i = min(max(k, i), j - 1)
            j = i + 1
        return grid[i], grid[j], root, lambda i=i, j=j, root=root: _guess(grid, i, j, length_at, length, root)
    return None


def _brackets(stopper, unit, length, coarse):
    """The first bracket (:func:`_scan`) of each sign of alpha on the grid, in multiples ``unit``.

    Where neither sign has one, each sign whose weakest ramp already stops the blade short of the
    length is scanned again below the grid (:data:`_BELOW`).
    """
    any_found = False
    for direction in (1.0, -1.0):
        cand = _scan(stopper, direction * unit * _GRID, length, coarse)
        if cand is not None:
            any_found = True
            yield cand
    if any_found:
        return
    for direction in (1.0, -1.0):
        if _stops_short(stopper, direction * unit * _GRID[0], length):
            cand = _scan(stopper, direction * unit * _BELOW, length, coarse)
            if cand is not None:
                yield cand


def _stops_short(stopper, alpha, length) -> bool:
    """Whether the ramp ``alpha`` stops the blade before ``length`` (at the grid's accuracy)."""
    try:
        return abs(stopper.run(alpha, _GRID_RTOL, _GRID_ATOL)[1][4]) < length
    except _NoStop:
        return False


def _guess(grid, i, j, length_at, length, root):
    """``(alpha, tau)`` interpolated on the bracket ``grid[i..j]`` or, where an end does not stop, ``root``'s."""
    li, lj = length_at(i, True), length_at(j, True)
    if li is None or lj is None:
        return root[:2]
    return _interpolated_guess(grid, i, j, li, lj, length)


def _secant_stop(stopper, alpha0, slope, a1, a2, length, rtol, atol):
    """The secant method at full accuracy on the event-located stopping length, from ``alpha0``.

    ``alpha0`` is the root at the scan's accuracy (about ``_SCAN_XTOL`` off) and ``slope`` the
    stopping length's slope there (or None). The first step is Newton's with that slope, which
    lands some thousand times closer; the secant step from there is within rounding of the root.
    Stops when the stop falls within a few ulps of ``length``, the step is down to a few ulps of
    alpha or the iterate leaves ``[a1, a2]``. Returns ``(alpha, tau, y)`` of the iterate with the
    least excess length, or raises :class:`_NoStop`.
    """
    lo, hi = min(a1, a2), max(a1, a2)
    tried = []

    def excess(alpha):
        tau, yf = stopper.run(alpha, rtol, atol)
        f = abs(yf[4]) - length
        tried.append((abs(f), alpha, tau, yf))
        return f

    ftol = 4.0 * np.finfo(float).eps * length  # a few ulps: the rounding of the stop's arc length
    x_prev, f_prev = alpha0, excess(alpha0)
    x = alpha0 - f_prev / slope if slope else math.nan
    if not (lo <= x <= hi and x != alpha0):
        x = alpha0 * (1.0 + 100.0 * _SCAN_XTOL)
    for _ in range(_SECANT_STEPS if abs(f_prev) > ftol else 0):
        f = excess(x)
        if abs(f) <= ftol or f == f_prev:
            break
        x_next = x - f * (x - x_prev) / (f - f_prev)
        if not lo <= x_next <= hi or abs(x_next - x) <= 4.0 * np.finfo(float).eps * abs(x):
            break
        x_prev, f_prev, x = x, f, x_next
    _f, alpha, tau, yf = min(tried, key=lambda r: r[0])
    return float(alpha), float(tau), yf


def _refined_stop(params, stopper, legs_spec, speed, length, root, a1, a2, rtol, atol):
    """:func:`_secant_stop` with the acceptance test of :func:`_bracket_stop`.

    Returns ``((alpha, tau), residuals)`` or ``(None, None)``.
    """
    try:
        alpha, tau, yf = _secant_stop(stopper, root[0], root[2], a1, a2, length, rtol, atol)
    except _NoStop:
        return None, None
    res = {"end_speed": float(_end_speed(params, legs_spec, yf, alpha * tau)),
           "length": float(abs(yf[4]) - length)}
    if not (abs(res["end_speed"]) < 1e-11 * speed and abs(res["length"]) < 1e-11 * length):
        return None, None
    return (alpha, tau), res


def solve_stop(
    params: SleighParams,
    legs: list[tuple[float, float]],
    glide_ab: tuple[float, float],
    speed: float,
    *,
    backward: bool = False,
    rtol: float = 1e-13,
    atol: float = 1e-14,
    singular_limit: float = 1e-3,
    fallback: bool = True,
) -> ManeuverSolution:
    """Bring a glide to rest (or, with ``backward=True``, start it from rest).

    The free control is a ramp ``u = alpha t`` from the glide (``t = 0``). Unknowns ``alpha`` and
    the duration ``tau``; residuals ``xi2(tau) / speed`` and ``(s(tau) - length) / length``.
    A launch is integrated backwards in time from the glide, so its ``tau`` is negative.

    For each sign of ``alpha`` the first ramp (in ``|alpha|`` order on a geometric grid) whose
    event-located stop falls at ``length`` is found at a moderate accuracy, then polished at full
    accuracy; of the two signs the solution whose mass stays farther from the singular point
    wins (the positive sign on a tie).

    Parameters
    ----------
    legs : list of (kappa, length)
        The curve from the glide onwards (backwards for a launch): curvature (1/length) and arc
        length of each stretch, joined smoothly. ``kappa`` is a number (an arc or a line) or up to
        four coefficients of a cubic in the distance travelled on the leg (a spiral; for a launch
        that distance runs backwards along the curve). The curvature where the first leg begins is
        the glide's (or the instant apex's).
    glide_ab : (float, float)
        Locked mass position during the glide.
    speed : float
        Glide speed (> 0).
    fallback : bool
        Where the secant polish of a bracket's root fails, go on with Brent's method on the
        bracket at full accuracy and then Newton's method (the default). False gives that bracket
        up instead; a stop that needed them is then a failure with ``deferred=True``.
    """
    length = float(sum(ell for _, ell in legs))
    legs_spec = []
    acc = 0.0
    for i, (k, ell) in enumerate(legs):
        acc += ell
        legs_spec.append((_coefficients(k), acc if i + 1 < len(legs) else math.inf))
    kappa = legs_spec[0][0][0]
    kind = "launch" if backward else "stop"
    a0, b0 = glide_ab
    sa, sb = singular_point(params, kappa)
    if math.hypot(a0 - sa, b0 - sb) <= singular_limit * params.length_scale:
        return ManeuverSolution(
            kind=kind, success=False, params=(math.nan,), duration=math.nan, legs=(), nfev=0,
            message=(f"the glide's mass position ({a0:.6g}, {b0:.6g}) is at the singular point "
                     f"(0, -kappa I / M) = ({sa:.6g}, {sb:.6g}) of curvature {kappa:.6g}"),
        )
    p = glide_state(params, kappa, a0, b0, speed)
    y0 = np.array([p[0], p[1], a0, b0, 0.0])
    sign = -1.0 if backward else 1.0
    scale = params.length_scale
    # Natural time and control scales: time ~ length / speed, u ~ speed^2 / length.
    t_nat = length / speed
    u_nat = speed * speed / length
    stopper = _Stopper(params, y0, legs_spec, sign * 60.0 * t_nat, singular_limit * scale)
    nfev = 0
    found = deferred = False
    best = None
    # One bracket per sign of alpha; prefer the sign that keeps the mass farther from the singular point.
    for cand in _brackets(stopper, u_nat / t_nat, length, _COARSE if _continuous(legs_spec) else 1):
        found = True
        a1, a2, root, guess = cand
        sol = (None, None)
        if root is not None:
            sol = _refined_stop(params, stopper, legs_spec, speed, length, root, a1, a2, rtol, atol)
        if sol[0] is None and not fallback:
            deferred = True
            continue
        if sol[0] is None:
            # Brent's method at full accuracy on the bracket (cannot diverge), then Newton's method
            # on (alpha, tau) from the guess. The scan's accuracy can mislead where the stop is
            # ill-conditioned (the speed creeping to zero): its root was seen 0.2% off the true one.
            # Where the scan's root is a jump of the stopping length, Brent searches only beside it.
            jump = _jump_at(stopper, root[0], length, rtol, atol) if root is not None else None
            sol = _bracket_stop(params, legs_spec, y0, sign * 60.0 * t_nat, speed, length, a1, a2, rtol, atol,
                                singular_limit * scale, jump)
            nfev += sol[2]
        if sol[0] is None:
            alpha0, tau0 = guess()
            sol = _polish_stop(params, legs_spec, y0, sign, speed, length, alpha0, tau0, rtol, atol,
                               singular_limit * scale)
            nfev += sol[2]
        if sol[0] is None:
            continue
        (alpha, tau), res = sol[0], sol[1]
        nfev += 1
        legs, status, tf, yf, hit = _integrate(params, y0, legs_spec, alpha, tau, rtol=rtol, atol=atol)
        if status != 0 or len(legs) < len(legs_spec):
            continue  # the dense re-run did not get through: no usable solution from this bracket
        dist, start = _singular_distances(params, legs)
        if best is None or dist > best[3]:
            best = (alpha, tau, legs, dist, res)
        if best[3] >= start:
            break  # the mass is nowhere nearer than at the glide: the other sign could only tie
    nfev += stopper.nfev
    if not found:
        return ManeuverSolution(
            kind=kind, success=False, params=(math.nan,), duration=math.nan, legs=(), nfev=nfev,
            message=(f"no {kind} of length {length:.6g} found from a glide on curvature {kappa:.6g}: every ramp "
                     "either never stops the sleigh or drives the mass into the singular point"),
        )
    if best is None and deferred:
        return ManeuverSolution(
            kind=kind, success=False, params=(math.nan,), duration=math.nan, legs=(), nfev=nfev, deferred=True,
            message=(f"the {kind} of length {length:.6g} is ill-conditioned: its bracketed root did not polish, "
                     "and the full-accuracy fallbacks were not run (fallback=False)"),
        )
    if best is None:
        return ManeuverSolution(
            kind=kind, success=False, params=(math.nan,), duration=math.nan, legs=(), nfev=nfev,
            message=(f"neither the bracketed root nor Newton's method converged for the {kind} of length "
                     f"{length:.6g}"),
        )
    alpha, tau, legs, dist, res = best
    ok = dist > singular_limit * scale
    return ManeuverSolution(
        kind=kind, success=ok, params=(alpha,), duration=tau, legs=tuple(legs),
        residuals=res, min_singular_distance=dist, nfev=nfev,
        message="converged" if ok else f"mass came within {dist:.3g} of the singular point",
    )


#: Relative step in alpha on either side of the scan's root at which :func:`_jump_at` looks, and the
#: share of the length by which the stop must miss on both sides for a jump.
_JUMP_STEP = 1e-7
_JUMP_MISS = 1e-3


def _jump_at(stopper, alpha, length, rtol, atol):
    """Where the stopping length jumps across ``length`` at ``alpha`` (the scan's root) at full accuracy.

    Where the speed grazes zero before the stop, the first stop comes or goes with a small change
    of the ramp, and the stopping length jumps: the scan's root is then that jump, not a root, and
    full-accuracy Brent on the whole bracket converges on it in some sixty integrations, to be
    refused. At ``alpha (1 -+ _JUMP_STEP)`` the stop falls on both sides of ``length`` and misses it
    by more than ``_JUMP_MISS`` of it on both (a continuous stopping length would need a slope of
    1e4 in ``log alpha``). Returns ``((alpha_lo, miss_lo), (alpha_hi, miss_hi))``, the misses
    signed shares of ``length``, or None where there is no such jump.
    """
    out = []
    for f in (1.0 - _JUMP_STEP, 1.0 + _JUMP_STEP):
        try:
            out.append((alpha * f, abs(stopper.run(alpha * f, rtol, atol)[1][4]) / length - 1.0))
        except _NoStop:
            return None
    (_, m1), (_, m2) = out
    return tuple(out) if m1 * m2 < 0.0 and min(abs(m1), abs(m2)) > _JUMP_MISS else None


def _bracket_stop(params, legs_spec, y0, t_max, speed, length, a1, a2, rtol, atol, singular_limit, jump=None):
    """Brent's method for ``alpha`` in ``[a1, a2]``: the first stop of the speed falls at ``length``.

    Returns ``((alpha, tau), residuals, nfev)`` or ``(None, None, nfev)`` if the bracket does not
    hold at full accuracy or the stopping length jumps across it (the speed touching zero
    earlier), so that the root leaves a residual. ``jump`` is :func:`_jump_at`'s answer, a jump
    inside the bracket: then only the side of it where the stop still crosses ``length`` is
    searched, and there is none where both sides' ends miss it the same way as the jump's.
    """
    count = 0

    class _NoStop(Exception):
        pass

    def run(alpha):
        nonlocal count
        count += 1
        legs, status, tf, yf, hit = _integrate(params, y0, legs_spec, alpha, t_max, rtol=rtol, atol=atol, stop=True,
                                               singular_limit=singular_limit, dense=False)
        if status != 0 or hit != "stopped":
            raise _NoStop
        return tf, yf

    def excess(alpha):
        return abs(run(alpha)[1][4]) - length

    try:
        f1, f2 = excess(a1), excess(a2)
        if not f1 * f2 <= 0.0:
            return None, None, count
        if jump is not None:
            (lo, f_lo), (hi, f_hi) = jump
            if f1 * f_lo <= 0.0:
                a2 = lo
            elif f_hi * f2 <= 0.0:
                a1 = hi
            else:
                return None, None, count
        alpha = brentq(excess, a1, a2, xtol=1e-300, rtol=4.0 * np.finfo(float).eps, maxiter=200)
        tau, yf = run(alpha)
    except (_NoStop, RuntimeError):
        return None, None, count
    res = {"end_speed": float(_end_speed(params, legs_spec, yf, alpha * tau)),
           "length": float(abs(yf[4]) - length)}
    if not (abs(res["end_speed"]) < 1e-11 * speed and abs(res["length"]) < 1e-11 * length):
        return None, None, count
    return (alpha, tau), res, count


#: Newton's method on ``(alpha, tau)`` (:func:`_polish_stop`) is given up where it stalls: from its
#: 100th integration, whenever the last 50 have not brought its least residual down by a factor 1.3.
#: Over 189 drawings and school figures at 6 m / 1 mm (632 polishes), the 9 of 130 that succeeded
#: after 100 integrations (up to 211) gained 1.7 or more a window; the failures that ran to MINPACK's
#: limit of 600 (36 s in all), 1.08 or less.
_POLISH_WINDOW = 50
_POLISH_PROGRESS = 1.3


class _Polished(Exception):
    """Raised inside MINPACK's iteration at the first iterate whose residuals pass: ``args`` are ``(z, residuals)``."""


class _Stalled(Exception):
    """Raised inside MINPACK's iteration where it has stopped making progress (see :data:`_POLISH_WINDOW`)."""


def _polish_stop(params, legs_spec, y0, sign, speed, length, alpha0, tau0, rtol, atol, singular_limit):
    """Newton's method (MINPACK's hybrid method) on ``(alpha, tau)`` from ``(alpha0, tau0)``.

    Stops at the first iterate whose residuals pass (below 1e-11, with a duration of the right sign;
    MINPACK went on towards an ``xtol`` of 1e-14), and gives up where it stalls (:data:`_POLISH_WINDOW`).
    Returns ``((alpha, tau), residuals, nfev)`` or ``(None, None, nfev)``.
    """
    count = 0
    least = [math.inf]  # the least residual after each integration

    def residual(z):
        nonlocal count
        count += 1
        alpha, tau = z[0] * alpha0, z[1] * tau0
        legs, status, tf, yf, hit = _integrate(params, y0, legs_spec, alpha, tau, rtol=rtol, atol=atol, dense=False,
                                               singular_limit=singular_limit)
        if status != 0 or hit is not None or len(legs) < len(legs_spec) or not np.all(np.isfinite(yf)):
            res = np.array([1e3, 1e3])
        else:
            v = _end_speed(params, legs_spec, yf, alpha * tau)
            res = np.array([v / speed, (abs(yf[4]) - length) / length])
        # A duration of the other sign runs the manoeuvre the wrong way in time (a stop before its
        # glide, a launch after it): the residuals may vanish there, but it is no manoeuvre.
        if z[1] > 0.0 and np.all(np.abs(res) < 1e-11):
            raise _Polished(np.array(z, dtype=float), res)
        least.append(min(least[-1], float(np.max(np.abs(res)))))
        if count >= 2 * _POLISH_WINDOW and count % _POLISH_WINDOW == 0 \
                and least[-1] * _POLISH_PROGRESS > least[-1 - _POLISH_WINDOW]:
            raise _Stalled
        return res

    try:
        root(residual, [1.0, 1.0], method="hybr", options={"xtol": 1e-14})
    except _Stalled:
        pass
    except _Polished as done:
        z, res = done.args
        return (z[0] * alpha0, z[1] * tau0), {"end_speed": float(res[0] * speed),
                                              "length": float(res[1] * length)}, count
    return None, None, count
