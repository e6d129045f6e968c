"""The exact finish: a planned section re-solved so that the full dynamics meets its end conditions to 1e-10.

The collocation answer (:mod:`skatetrace.planning.collocation`) satisfies the dynamics only to
its mesh's accuracy. Here its free control ``u`` (piecewise linear in time) is integrated by the
compiled DOP853 of the manoeuvres, one affine piece per call, so that the curvature condition
holds by construction to the integrator's tolerance, and the section is solved by multiple
shooting (:func:`finish_section`): the unknowns are a scale of the time nodes, ``u`` at the nodes
and the states at the inner segment starts; the residuals the continuity between segments and
the end state: the arc length, the mass's position ``(a, b)`` and rates ``(adot, bdot)`` as
planned, and the speed along the blade zero (rest). The next section then starts from that
position (and velocity, where the plan makes it continuous), exactly.

The residuals' and the Jacobian's integrations run compiled (:mod:`skatetrace.planning.shooting`);
the solution's phases (dense output) are integrated once more here, interval by interval.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..dynamics.integrator import integrate_legs
from ..dynamics.model import SleighParams, velocities
from ..tracing.maneuver import Leg, ManeuverSolution, constrained_rates
from .least_norm import least_norm_step
from .shooting import jacobian_columns, legs_from, segment_ends

__all__ = ["RestState", "FinishedSection", "finish_section", "rest_momenta"]

_RESIDUAL_TOL = 1e-10
_MODES = 5


@dataclass(frozen=True, slots=True)
class RestState:
    """The mass's position and rates relative to the blade at a rest, in the section's travel frame."""

    a: float
    b: float
    adot: float
    bdot: float

    def turned(self, angle: float) -> "RestState":
        """The same motion on the ice seen from a frame turned by ``-angle`` (a pivot of ``-angle``)."""
        c, s = math.cos(angle), math.sin(angle)
        return RestState(c * self.a - s * self.b, s * self.a + c * self.b,
                         c * self.adot - s * self.bdot, s * self.adot + c * self.bdot)


@dataclass(frozen=True, slots=True, kw_only=True)
class FinishedSection:
    """An exact section: its phases (one per affine piece of ``u``), end state and residuals."""

    success: bool
    message: str
    intervals: tuple[tuple[float, float, ManeuverSolution, float, int], ...]
    start: RestState
    end: RestState
    residuals: dict[str, float]
    nfev: int


def rest_momenta(params: SleighParams, a, b, adot, bdot) -> tuple[float, float]:
    """Momenta ``(p1, p2)`` of the sleigh at rest while the mass moves at ``(adot, bdot)``: the mass's own."""
    m = params.m
    return m * (a * bdot - b * adot), m * adot


def _pieces(pieces):
    """Cumulative ends and curvature coefficients (an array of shape (n, 4)) of the section's pieces."""
    ends = np.cumsum([p.length for p in pieces])
    return ends, np.array([tuple(p.coefficients) for p in pieces], dtype=float).reshape(-1, 4)


def _legs_from(ends, coeffs, s_cur):
    """Legs ``(coefficients, switch)`` from arc length ``s_cur`` on: :func:`~skatetrace.planning.shooting.legs_from`."""
    j, kap, sw = legs_from(ends, coeffs, s_cur)
    return int(j), kap, sw


def _run(params, y0, times, U, ends, coeffs, rtol, atol, dense):
    """Integrate under ``u`` linear between ``(times, U)``; returns the final state, ``u`` there and the intervals.

    Each interval is one call from its start (local time 0); the intervals keep the given
    ``times`` as their bounds, so that consecutive ones meet exactly. The Python form of
    :func:`skatetrace.planning.shooting.segment_end`, kept for the dense output of the phases.
    """
    y = np.array(y0, dtype=float)
    out = []
    s_abs = 0.0
    for k in range(times.size - 1):
        h = times[k + 1] - times[k]
        if not h > 0.0:
            return None, None, out
        alpha = (U[k + 1] - U[k]) / h
        j, kap, sw = _legs_from(ends, coeffs, s_abs)
        y_local = y.copy()
        y_local[4] = 0.0
        res = integrate_legs(params, y_local, kap, sw, alpha, h, rtol=rtol, atol=atol, dense=dense, beta=U[k])
        if res.status != 0 or not np.all(np.isfinite(res.y)):
            return None, None, out
        if dense:
            legs = []
            for i, sol in enumerate(res.legs):
                s0 = float(sw[i - 1]) if i else 0.0
                legs.append(Leg(tuple(float(c) for c in kap[i]), float(res.leg_bounds[i]),
                                float(res.leg_bounds[i + 1]), sol, s0))
            man = ManeuverSolution(kind="plan", success=True, message="planned", params=(float(alpha), float(U[k])),
                                   duration=float(h), legs=tuple(legs), basis="affine")
            out.append((float(times[k]), float(times[k + 1]), man, s_abs, j))
        y = np.array(res.y, dtype=float)
        s_abs += y[4]
        y[4] = s_abs
    return y, U[-1], out


def _end_conditions(params, y, u_end, ends, coeffs, target, L, scale_r, scale_v):
    kap = coeffs[-1].tolist()
    sig = y[4] - (ends[-2] if len(ends) > 1 else 0.0)
    k_end = kap[0] + sig * (kap[1] + sig * (kap[2] + sig * kap[3]))
    ad, bd, _ = constrained_rates(params, k_end, y[0], y[1], y[2], y[3], u_end)
    xi2 = velocities(params, y[0], y[1], y[2], y[3], ad, bd)[1]
    r = np.array([(y[4] - L) / L, (y[2] - target.a) / scale_r, (y[3] - target.b) / scale_r,
                  (ad - target.adot) / scale_v, (bd - target.bdot) / scale_v, xi2])
    return r, RestState(float(y[2]), float(y[3]), float(ad), float(bd))


def finish_section(params: SleighParams, pieces, times, U, start: RestState, target: RestState, states=None, *,
                   stride: int = 3, rtol: float = 1e-13, atol: float = 1e-14,
                   residual_tol: float = _RESIDUAL_TOL, max_iter: int = 30) -> FinishedSection:
    """Solve the planned section exactly from ``start`` to rest at ``target``, by multiple shooting.

    ``times`` and ``U`` are the plan's time nodes (normalised, top speed 1) and the free control
    there; ``pieces`` carry ``coefficients`` and ``length``; ``states`` the plan's states at the
    nodes (masses normalised to ``M + m = 1``), the start of each shooting segment of ``stride``
    intervals. Unknowns: a scale of the times, ``u`` at every node but the first, and the state
    at every inner segment start; residuals: continuity between segments and the six end
    conditions. The system is underdetermined: Gauss-Newton with least-norm steps. Never raises.
    """
    ends, coeffs = _pieces(pieces)
    L = float(ends[-1])
    tot = params.M + params.m
    p1, p2 = rest_momenta(params, start.a, start.b, start.adot, start.bdot)
    kap0 = float(coeffs[0, 0])
    from ..dynamics.model import curvature_coefficients
    c_a, c_b, _c0 = curvature_coefficients(params, kap0, p1, p2, start.a, start.b)
    u0 = (-c_b * start.adot + c_a * start.bdot) / math.hypot(c_a, c_b)
    times = np.ascontiguousarray(times, dtype=float)
    N = times.size - 1
    bounds = list(range(0, N, stride)) + [N]
    K = len(bounds) - 1
    y0 = np.array([p1, p2, start.a, start.b, 0.0])
    yscale = np.array([tot, tot, 1.0, 1.0, L])
    Uv = np.array(U, dtype=float)
    Uv[0] = u0
    if states is None:
        states = np.zeros((6, N + 1))
    Y = [np.asarray(states[:5, bounds[k]], dtype=float) * np.array([1.0, 1.0, 1.0, 1.0, 1.0 / L]) for k in range(1, K)]
    z = np.concatenate([[1.0], Uv[1:]] + Y)
    scale_r = max(math.hypot(target.a, target.b), params.length_scale)
    scale_v = max(math.hypot(target.adot, target.bdot), 1.0)
    count = 0
    bounds_a = np.array(bounds, dtype=np.int64)
    every = np.ones(K, dtype=np.bool_)
    M, m, I, rtol, atol = float(params.M), float(params.m), float(params.I), float(rtol), float(atol)

    def unpack(z):
        uu = np.concatenate([[u0], z[1:N + 1]])
        ys = np.concatenate([y0[None, :], z[N + 1:].reshape(K - 1, 5) * yscale])
        return z[0], uu, ys

    def segment(k, z):
        """The dense integration of segment ``k`` (Python: it builds the phases)."""
        nonlocal count
        count += 1
        sig, uu, ys = unpack(z)
        i0, i1 = bounds[k], bounds[k + 1]
        tt = sig * times[i0:i1 + 1]
        y = ys[k].copy()
        s_start = y[4]
        y[4] = 0.0
        yk, u_end, out = _run(params, y, tt, uu[i0:i1 + 1], ends - s_start, coeffs, rtol, atol, True)
        if yk is None:
            return None, None, out
        yk = yk.copy()
        yk[4] += s_start
        out = [(t0, t1, man, s0 + s_start, j) for t0, t1, man, s0, j in out]
        return yk, u_end, out

    def end_conditions(y, u_end):
        return _end_conditions(params, y, u_end, ends, coeffs, target, L, scale_r, scale_v)[0]

    def residual(z):
        """The residuals at ``z`` and the segments' ends (compiled), or ``(None, None)`` on a failure."""
        nonlocal count
        sig, uu, ys = unpack(z)
        E = np.empty((K, 5))
        ok, n = segment_ends(M, m, I, ys, sig, times, uu, bounds_a, ends, coeffs, rtol, atol, every, E)
        count += n
        if not ok:
            return None, None
        return np.concatenate([((E[:-1] - ys[1:]) / yscale).ravel(), end_conditions(E[-1], uu[-1])]), E

    def jacobian(z, r, E):
        """Forward differences, one column per unknown (compiled); None on a failure."""
        nonlocal count
        sig, uu, ys = unpack(z)
        J = np.empty((r.size, z.size))
        last, moved, steps = np.empty((z.size, 6)), np.zeros(z.size, dtype=np.bool_), np.empty(z.size)
        ok, n = jacobian_columns(M, m, I, z, uu, ys, yscale, times, bounds_a, ends, coeffs, rtol, atol, E, r, J, last,
                                 moved, steps)
        count += n
        if not ok:
            return None
        # the end conditions: the forward difference of an unchanged residual (zero, NaN where it is
        # NaN, as the columns were before) unless the last segment moved
        J[-6:] = (r[-6:] - r[-6:])[:, None] / steps
        for i in np.flatnonzero(moved):
            J[-6:, i] = (end_conditions(last[i, :5], last[i, 5]) - r[-6:]) / steps[i]
        return J

    with np.errstate(all="ignore"):
        r, E = residual(z)
        ok = r is not None
        previous = math.inf
        for _ in range(max_iter if ok else 0):
            # a tenth of the tolerance to spare; but once within it, an iteration that did not
            # halve the residual is at the round-off floor, and more of them (a Jacobian of
            # hundreds of integrations each) only wander there (circle eight: eight more at 2e-11)
            worst = np.max(np.abs(r))
            if worst <= 0.1 * residual_tol or (worst <= residual_tol and worst > 0.5 * previous):
                break
            previous = worst
            J = jacobian(z, r, E)
            if J is None:
                break
            dz = least_norm_step(J, r)
            step = 1.0
            while step > 1e-3:
                rn, En = residual(z + step * dz)
                if rn is not None and np.linalg.norm(rn) < np.linalg.norm(r):
                    break
                step *= 0.5
            if rn is None or step <= 1e-3:
                break
            z, r, E = z + step * dz, rn, En
    worst = float(np.max(np.abs(r))) if r is not None else math.inf
    names = ("length", "end_a", "end_b", "end_adot", "end_bdot", "end_speed")
    res = {k: float(v) for k, v in zip(names, r[-6:])} if r is not None else {}
    if r is not None:
        res["continuity"] = float(np.max(np.abs(r[:-6]))) if r.size > 6 else 0.0
    if not worst <= residual_tol:
        return FinishedSection(success=False, message=f"the exact finish did not converge (largest residual {worst:.3g})",
                               intervals=(), start=start, end=target, residuals=res, nfev=count)
    out = []
    for k in range(K):
        yk, u_end, seg_out = segment(k, z)
        out += seg_out
    _fin, end = _end_conditions(params, yk, u_end, ends, coeffs, target, L, scale_r, scale_v)
    return FinishedSection(success=True, message="finished exactly", intervals=tuple(out), start=start, end=end,
                           residuals=res, nfev=count)
