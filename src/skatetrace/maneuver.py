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
Each is a small boundary-value problem in (alpha, duration) solved by Newton's method (MINPACK's
hybrid method), started from a bracket of the event-located stopping length.

The state integrated here is ``(p1, p2, a, b, s)``, ``s`` the arc length travelled.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Callable

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import root

from .model import SleighParams, curvature_coefficients, velocities

__all__ = ["Leg", "ManeuverSolution", "glide_state", "constrained_rates", "solve_stop"]


@dataclass(frozen=True, slots=True)
class Leg:
    """One stretch of constant curvature inside a manoeuvre: a dense solution on ``[t0, t1]``."""

    kappa: float
    t0: float
    t1: float
    sol: object  # scipy OdeSolution of (p1, p2, a, b, s)


@dataclass(frozen=True, slots=True, kw_only=True)
class ManeuverSolution:
    """Result of one manoeuvre solve.

    ``params`` are the free-control coefficients, ``duration`` the signed duration (negative for a
    launch, which is integrated backwards from its glide). ``residuals`` are the boundary
    conditions at the solution; ``min_singular_distance`` the closest approach of the mass to the
    singular point.
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
    c_a, c_b, c_0 = curvature_coefficients(params, kappa, p1, p2, a, b)
    n2 = c_a * c_a + c_b * c_b
    n = np.sqrt(n2)
    adot = -u * c_b / n - c_0 * c_a / n2
    bdot = u * c_a / n - c_0 * c_b / n2
    return adot, bdot, n


class _TooStiff(Exception):
    """The integration needed more right-hand-side evaluations than a manoeuvre can."""


_MAX_EVALUATIONS = 150_000


def _rhs_factory(params: SleighParams, kappa: float, ufun):
    M, m, I = params.M, params.m, params.I
    MI = M * m
    Mm = M + m
    calls = [0]

    # The model's formulas inlined with scalar math: this runs thousands of times per solve, and
    # numpy's per-call overhead would dominate. Tests compare it with model.rhs and
    # constrained_rates.
    def f(t, y):
        calls[0] += 1
        if calls[0] > _MAX_EVALUATIONS:
            # Only near the singular point or a blow-up does the step size collapse like this.
            raise _TooStiff
        p1, p2, a, b, _ = y
        u = ufun(t)
        c_a = m * (M * b + kappa * (I + m * a * a))
        c_b = m * a * (kappa * m * b - Mm)
        c_0 = (Mm - kappa * m * b) * p1 + (m * b - kappa * (I + m * (a * a + b * b))) * p2
        n2 = c_a * c_a + c_b * c_b
        if not n2 > 0.0:  # exactly at the singular point (or NaN): no rate holds the curvature
            raise _TooStiff
        n = math.sqrt(n2)
        ad = -u * c_b / n - c_0 * c_a / n2
        bd = u * c_a / n - c_0 * c_b / n2
        D = Mm * (I + m * a * a) + MI * b * b
        q = p1 - m * a * bd
        r = p2 + M * ad
        xi1 = (Mm * q + m * b * r) / D
        xi2 = (m * (b * q - (I + m * a * a) * ad) + (I + m * (a * a + b * b)) * p2) / D
        eta = ((MI * b * b + I * Mm) * bd + a * (Mm * p1 + m * b * r)) / D
        return [-m * eta * xi2, m * eta * xi1, ad, bd, xi2]

    return f


def _integrate(params, y0, legs_spec, ufun, t_end, *, rtol, atol, events=(), dense=True):
    """Integrate the constrained system through legs ``[(kappa, s_switch), ...]``.

    A leg ends when ``|s|`` reaches its ``s_switch`` (the last leg's is ``inf``) or at ``t_end``.
    Returns (legs, status, final_t, final_y, event_hit) where ``event_hit`` names a terminal event.
    """
    legs = []
    t0, y = 0.0, np.asarray(y0, dtype=float)
    for i, (kappa, s_switch) in enumerate(legs_spec):
        evs = []
        if math.isfinite(s_switch):

            def join(t, y, _s=s_switch):
                return abs(y[4]) - _s

            join.terminal = True
            evs.append(join)
        user = [ev(kappa, ufun) for ev in events]
        evs.extend(user)
        try:
            sol = solve_ivp(
                _rhs_factory(params, kappa, ufun), (t0, t_end), y, method="DOP853",
                rtol=rtol, atol=atol, dense_output=dense, events=evs or None,
            )
        except _TooStiff:
            return legs, -1, t0, y, "step size collapsed"
        if sol.status < 0:
            return legs, sol.status, sol.t[-1], sol.y[:, -1], sol.message
        legs.append(Leg(kappa, t0, float(sol.t[-1]), sol.sol))
        hit = None
        if sol.status == 1:
            offset = 1 if math.isfinite(s_switch) else 0
            for j, te in enumerate(sol.t_events[offset:]):
                if len(te):
                    hit = events[j].__name__
            if hit is None and i + 1 < len(legs_spec):
                t0, y = float(sol.t[-1]), sol.y[:, -1]
                continue
        return legs, 0, float(sol.t[-1]), sol.y[:, -1], hit
    return legs, 0, t0, y, None


def _singular_event(params, limit):
    def make(kappa, ufun):
        sa, sb = 0.0, -kappa * params.I / params.M

        def singular(t, y):
            return math.hypot(y[2] - sa, y[3] - sb) - limit

        singular.terminal = True
        return singular

    make.__name__ = "singular"
    return make


def _stop_event(params):
    def make(kappa, ufun):
        def stopped(t, y, _k=kappa):
            return _end_speed(params, _k, y, ufun(t))

        stopped.terminal = True
        return stopped

    make.__name__ = "stopped"
    return make


def _end_speed(params, kappa, y, u):
    p1, p2, a, b, _ = y
    ad, bd, _n = constrained_rates(params, kappa, p1, p2, a, b, u)
    return velocities(params, p1, p2, a, b, ad, bd)[1]


def _min_singular_distance(params, legs, n=400):
    best = math.inf
    for leg in legs:
        ts = np.linspace(leg.t0, leg.t1, n)
        y = leg.sol(ts)
        sb = -leg.kappa * params.I / params.M
        best = min(best, float(np.min(np.hypot(y[2], y[3] - sb))))
    return best


def solve_stop(
    params: SleighParams,
    legs: list[tuple[float, float]],
    glide_ab: tuple[float, float],
    speed: float,
    *,
    backward: bool = False,
    rtol: float = 1e-12,
    atol: float = 1e-13,
    singular_limit: float = 1e-3,
) -> ManeuverSolution:
    """Bring a glide to rest (or, with ``backward=True``, start it from rest).

    The free control is a ramp ``u = alpha t`` from the glide (``t = 0``). Unknowns ``alpha`` and
    the duration ``tau``; residuals ``xi2(tau) / speed`` and ``(s(tau) - length) / length``.
    A launch is integrated backwards in time from the glide, so its ``tau`` is negative.

    Parameters
    ----------
    legs : list of (kappa, length)
        The curve from the glide onwards (backwards for a launch): curvature (1/length) and arc
        length of each stretch, joined smoothly. The first curvature is the glide's.
    glide_ab : (float, float)
        Locked mass position during the glide.
    speed : float
        Glide speed (> 0).
    """
    kappa = legs[0][0]
    length = float(sum(ell for _, ell in legs))
    legs_spec = []
    acc = 0.0
    for i, (k, ell) in enumerate(legs):
        acc += ell
        legs_spec.append((float(k), acc if i + 1 < len(legs) else math.inf))
    kind = "launch" if backward else "stop"
    a0, b0 = glide_ab
    sa, sb = 0.0, -kappa * params.I / params.M
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
    sing = _singular_event(params, singular_limit * scale)
    stop = _stop_event(params)
    # Natural time and control scales: time ~ length / speed, u ~ speed^2 / length.
    t_nat = length / speed
    u_nat = speed * speed / length
    nfev = 0

    def event_length(alpha):
        nonlocal nfev
        nfev += 1
        legs, status, tf, yf, hit = _integrate(
            params, y0, legs_spec, lambda t: alpha * t, sign * 60.0 * t_nat,
            rtol=1e-9, atol=1e-11, events=(sing, stop), dense=False,
        )
        if status != 0 or hit != "stopped":
            return None, tf
        return abs(yf[4]), tf

    # Bracket alpha on a geometric grid of both signs; prefer the sign that keeps the mass
    # farther from the singular point.
    candidates = []
    for direction in (1.0, -1.0):
        # alpha scales like 1/length^2 on an arc and 1/length on a line: a wide grid covers both
        grid = direction * u_nat / t_nat * np.geomspace(1e-3, 2e3, 29)
        lengths = [event_length(a) for a in grid]
        for (a1, (l1, t1)), (a2, (l2, t2)) in zip(zip(grid, lengths), zip(grid[1:], lengths[1:])):
            if l1 is None or l2 is None:
                continue
            if (l1 - length) * (l2 - length) <= 0:
                w = (math.log(l1) - math.log(length)) / (math.log(l1) - math.log(l2)) if l1 != l2 else 0.5
                alpha = a1 * (a2 / a1) ** w
                tau = t1 + w * (t2 - t1)
                candidates.append((alpha, tau))
                break
    if not candidates:
        return ManeuverSolution(
            kind=kind, success=False, params=(math.nan,), duration=math.nan, legs=(), nfev=nfev,
            message=(f"no {kind} of length {length:.6g} found from a glide on curvature {kappa:.6g}: every ramp "
                     "either never stops the sleigh or drives the mass into the singular point"),
        )

    best = None
    for alpha0, tau0 in candidates:
        sol = _polish_stop(params, legs_spec, y0, sign, speed, length, alpha0, tau0, rtol, atol)
        nfev += sol[2]
        if sol[0] is None:
            continue
        (alpha, tau), res = sol[0], sol[1]
        legs, status, tf, yf, hit = _integrate(
            params, y0, legs_spec, lambda t, _a=alpha: _a * t, tau, rtol=rtol, atol=atol
        )
        dist = _min_singular_distance(params, legs)
        if best is None or dist > best[3]:
            best = (alpha, tau, legs, dist, res)
    if best is None:
        return ManeuverSolution(
            kind=kind, success=False, params=(math.nan,), duration=math.nan, legs=(), nfev=nfev,
            message=f"Newton's method did not converge for the {kind} of length {length:.6g}",
        )
    alpha, tau, legs, dist, res = best
    ok = dist > singular_limit * scale
    return ManeuverSolution(
        kind=kind, success=ok, params=(alpha,), duration=tau, legs=tuple(legs),
        residuals=res, min_singular_distance=dist, nfev=nfev,
        message="converged" if ok else f"mass came within {dist:.3g} of the singular point",
    )


def _polish_stop(params, legs_spec, y0, sign, speed, length, alpha0, tau0, rtol, atol):
    count = 0

    def residual(z):
        nonlocal count
        count += 1
        alpha, tau = z[0] * alpha0, z[1] * tau0
        legs, status, tf, yf, hit = _integrate(
            params, y0, legs_spec, lambda t: alpha * t, tau, rtol=rtol, atol=atol, dense=False
        )
        if status != 0 or len(legs) < len(legs_spec) or not np.all(np.isfinite(yf)):
            return np.array([1e3, 1e3])
        v = _end_speed(params, legs_spec[-1][0], yf, alpha * tau)
        return np.array([v / speed, (abs(yf[4]) - length) / length])

    out = root(residual, [1.0, 1.0], method="hybr", options={"xtol": 1e-14})
    if not out.x[1] > 0.0:
        # A duration of the other sign runs the manoeuvre the wrong way in time (a stop before its
        # glide, a launch after it): the residuals may vanish there, but it is no manoeuvre.
        return None, None, count
    res = residual(out.x)
    if not np.all(np.abs(res) < 1e-11):
        return None, None, count
    return (out.x[0] * alpha0, out.x[1] * tau0), {"end_speed": float(res[0] * speed),
                                                   "length": float(res[1] * length)}, count
