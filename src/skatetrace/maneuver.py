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
in (alpha, duration) solved by Newton's method (MINPACK's hybrid method), started from a bracket
of the event-located stopping length.

The state integrated here is ``(p1, p2, a, b, s)``, ``s`` the arc length travelled.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Callable

import numpy as np
from scipy.optimize import brentq, root

from .integrator import integrate_legs
from .model import SleighParams, curvature_coefficients, velocities

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
        sigma = np.abs(np.asarray(s, dtype=float)) - self.s0
        c0, c1, c2, c3 = self.coefficients
        return c0 + sigma * (c1 + sigma * (c2 + sigma * c3))


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


def _coefficients(kappa) -> tuple[float, float, float, float]:
    """A leg's curvature as cubic coefficients: a number (constant) or up to four coefficients."""
    if np.ndim(kappa) == 0:
        return (float(kappa), 0.0, 0.0, 0.0)
    c = [float(v) for v in kappa]
    return tuple(c + [0.0] * (4 - len(c)))


def _kappa_at(legs_spec, s: float) -> float:
    """Curvature at ``|s|`` on legs ``[(coefficients, s_switch), ...]``."""
    start = 0.0
    for coeffs, switch in legs_spec:
        if abs(s) <= switch:
            break
        start = switch
    c0, c1, c2, c3 = coeffs
    sigma = abs(s) - start
    return c0 + sigma * (c1 + sigma * (c2 + sigma * c3))


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


def _min_singular_distance(params, legs, n=400):
    best = math.inf
    for leg in legs:
        ts = np.linspace(leg.t0, leg.t1, n)
        y = leg.sol(ts)
        sb = -leg.kappa_at(y[4]) * params.I / params.M
        best = min(best, float(np.min(np.hypot(y[2], y[3] - sb))))
    return best


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
) -> ManeuverSolution:
    """Bring a glide to rest (or, with ``backward=True``, start it from rest).

    The free control is a ramp ``u = alpha t`` from the glide (``t = 0``). Unknowns ``alpha`` and
    the duration ``tau``; residuals ``xi2(tau) / speed`` and ``(s(tau) - length) / length``.
    A launch is integrated backwards in time from the glide, so its ``tau`` is negative.

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
    # Natural time and control scales: time ~ length / speed, u ~ speed^2 / length.
    t_nat = length / speed
    u_nat = speed * speed / length
    nfev = 0

    def event_length(alpha):
        nonlocal nfev
        nfev += 1
        legs, status, tf, yf, hit = _integrate(
            params, y0, legs_spec, alpha, sign * 60.0 * t_nat, rtol=1e-9, atol=1e-11,
            stop=True, singular_limit=singular_limit * scale, dense=False,
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
                candidates.append((alpha, tau, a1, a2))
                break
    if not candidates:
        return ManeuverSolution(
            kind=kind, success=False, params=(math.nan,), duration=math.nan, legs=(), nfev=nfev,
            message=(f"no {kind} of length {length:.6g} found from a glide on curvature {kappa:.6g}: every ramp "
                     "either never stops the sleigh or drives the mass into the singular point"),
        )

    best = None
    for alpha0, tau0, a1, a2 in candidates:
        # Root of the event-located stopping length on the bracket first (cannot diverge), then
        # Newton's method on (alpha, tau) from the interpolated guess.
        sol = _bracket_stop(params, legs_spec, y0, sign * 60.0 * t_nat, speed, length, a1, a2, rtol, atol,
                            singular_limit * scale)
        nfev += sol[2]
        if sol[0] is None:
            sol = _polish_stop(params, legs_spec, y0, sign, speed, length, alpha0, tau0, rtol, atol)
            nfev += sol[2]
        if sol[0] is None:
            continue
        (alpha, tau), res = sol[0], sol[1]
        legs, status, tf, yf, hit = _integrate(params, y0, legs_spec, alpha, tau, rtol=rtol, atol=atol)
        if status != 0 or len(legs) < len(legs_spec):
            continue  # the dense re-run did not get through: no usable solution from this bracket
        dist = _min_singular_distance(params, legs)
        if best is None or dist > best[3]:
            best = (alpha, tau, legs, dist, res)
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


def _bracket_stop(params, legs_spec, y0, t_max, speed, length, a1, a2, rtol, atol, singular_limit):
    """Brent's method for ``alpha`` in ``[a1, a2]``: the first stop of the speed falls at ``length``.

    Returns ``((alpha, tau), residuals, nfev)`` or ``(None, None, nfev)`` if the bracket does not
    hold at full accuracy or the stopping length jumps across it (the speed touching zero
    earlier), so that the root leaves a residual.
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
        alpha = brentq(excess, a1, a2, xtol=1e-300, rtol=4.0 * np.finfo(float).eps, maxiter=200)
        tau, yf = run(alpha)
    except (_NoStop, RuntimeError):
        return None, None, count
    res = {"end_speed": float(_end_speed(params, legs_spec, yf, alpha * tau)),
           "length": float(abs(yf[4]) - length)}
    if not (abs(res["end_speed"]) < 1e-11 * speed and abs(res["length"]) < 1e-11 * length):
        return None, None, count
    return (alpha, tau), res, count


def _polish_stop(params, legs_spec, y0, sign, speed, length, alpha0, tau0, rtol, atol):
    count = 0

    def residual(z):
        nonlocal count
        count += 1
        alpha, tau = z[0] * alpha0, z[1] * tau0
        legs, status, tf, yf, hit = _integrate(params, y0, legs_spec, alpha, tau, rtol=rtol, atol=atol, dense=False)
        if status != 0 or len(legs) < len(legs_spec) or not np.all(np.isfinite(yf)):
            return np.array([1e3, 1e3])
        v = _end_speed(params, legs_spec, yf, alpha * tau)
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
