"""The compiled replay: the full five equations under sampled controls, integrated by DOP853.

Verification replays every chunk of a control schedule (a smooth stretch of ``controls.csv``)
through eqs. (p1_eq)-(y_eq). With scipy's ``solve_ivp`` and a Python right-hand side that costs
about 11 us a call, hundreds of thousands of calls per figure. Here the same integration runs
compiled:

- the controls are the schedule's cubic Hermite interpolants (:meth:`ControlSchedule.hermite`,
  the same coefficients :func:`skatetrace.dynamics.simulate.simulate` uses);
- the velocities are :func:`skatetrace.dynamics.model.body_velocities` itself, compiled, not a copy;
- the step is scipy's DOP853 (the arithmetic in :mod:`skatetrace.dynamics.dop853`), with the same error
  norm, step-size control, initial step and 7th-order dense output at the requested times.

The right-hand side knows nothing of curvatures, manoeuvres or how the controls were found: it is
the free motion of the sleigh and its mass under the given ``a(t), b(t)``. It shares only the
Runge-Kutta arithmetic with the manoeuvre integrator (:mod:`skatetrace.dynamics.integrator`), and a test
compares it with ``solve_ivp`` on the same schedules.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from . import dop853 as rk
from .controls import ControlSchedule
from .model import SleighParams, body_velocities

__all__ = ["ChunkReplay", "replay_chunk"]

_body_velocities = njit(cache=True)(body_velocities)

_REACHED, _EXHAUSTED, _SMALL_STEP, _NONFINITE = 0, -1, -2, -3
_MESSAGES = {
    _REACHED: "integrated to the end of the chunk",
    _EXHAUSTED: "step size collapsed: the evaluation budget ran out (the controls or the motion are singular)",
    _SMALL_STEP: "required step size is less than spacing between numbers",
    _NONFINITE: "the state became non-finite",
}


@njit(cache=True)
def _controls(knots, ca, cb, t, ctl):
    """``(a, b, adot, bdot)`` at ``t`` from the Hermite cubics (rows ``c3, c2, c1, c0`` per interval).

    They go to ``ctl[:4]``; ``ctl[4]`` holds the index of the interval last used.
    """
    # the interval of t: a short walk from the last one (the integration moves forwards)
    k = int(ctl[4])
    last = knots.size - 2
    while k < last and t >= knots[k + 1]:
        k += 1
    while k > 0 and t < knots[k]:
        k -= 1
    ctl[4] = k
    h = t - knots[k]
    ctl[0] = ((ca[k, 0] * h + ca[k, 1]) * h + ca[k, 2]) * h + ca[k, 3]
    ctl[1] = ((cb[k, 0] * h + cb[k, 1]) * h + cb[k, 2]) * h + cb[k, 3]
    ctl[2] = (3.0 * ca[k, 0] * h + 2.0 * ca[k, 1]) * h + ca[k, 2]
    ctl[3] = (3.0 * cb[k, 0] * h + 2.0 * cb[k, 1]) * h + cb[k, 2]


@njit(cache=True)
def _controls_at(knots, ca, cb, t_out):
    """``(a, b, adot, bdot)`` at the sorted times ``t_out``, shape ``(4, len(t_out))``."""
    out = np.empty((4, t_out.size))
    ctl = np.zeros(5)
    for j in range(t_out.size):
        _controls(knots, ca, cb, t_out[j], ctl)
        for r in range(4):
            out[r, j] = ctl[r]
    return out


@njit(cache=True)
def _rhs(M, m, I, knots, ca, cb, t, y, out, ctl):
    """Eqs. (p1_eq)-(y_eq) for the state ``(p1, p2, theta, x, y)``."""
    _controls(knots, ca, cb, t, ctl)
    xi1, xi2, eta = _body_velocities(M, m, I, y[0], y[1], ctl[0], ctl[1], ctl[2], ctl[3])
    out[0] = -m * eta * xi2
    out[1] = m * eta * xi1
    out[2] = xi1
    out[3] = xi2 * math.cos(y[2])
    out[4] = xi2 * math.sin(y[2])


@njit(cache=True)
def _run(M, m, I, y0, knots, ca, cb, t_out, rtol, atol, max_nfev):
    """Integrate from ``knots[0]`` to ``knots[-1]``; states at the sorted times ``t_out``.

    Returns ``(status, t, y, out, nfev, nsteps)``; ``out`` is NaN at the times not reached.
    """
    n = y0.size
    nout = t_out.size
    out = np.full((n, nout), np.nan)
    t = knots[0]
    t_end = knots[-1]
    y = y0.copy()
    ctl = np.zeros(5)
    j = 0
    while j < nout and t_out[j] <= t:
        for r in range(n):
            out[r, j] = y[r]
        j += 1
    f = np.empty(n)
    f_new = np.empty(n)
    ynew = np.empty(n)
    ytmp = np.empty(n)
    Kx = np.empty((16, n))
    F = np.empty((rk.POWER, n))
    _rhs(M, m, I, knots, ca, cb, t, y, f, ctl)
    h0, d1, scale = rk.initial_step_trial(y, f, t_end - t, rtol, atol)
    _rhs(M, m, I, knots, ca, cb, t + h0, y + h0 * f, f_new, ctl)
    h_abs = rk.initial_step(h0, d1, scale, f, f_new, t_end - t)
    nfev = 2
    nsteps = 0
    while t < t_end:
        min_step = 10.0 * abs(np.nextafter(t, np.inf) - t)
        h_abs = max(h_abs, min_step)
        rejected = False
        while True:
            if h_abs < min_step:
                return _SMALL_STEP, t, y, out, nfev, nsteps
            t_new = min(t + h_abs, t_end)
            h = t_new - t
            h_abs = h
            for i in range(n):
                Kx[0, i] = f[i]
            for s in range(1, rk.N_STAGES):
                for i in range(n):
                    acc = 0.0
                    for q in range(s):
                        acc += rk.A[s, q] * Kx[q, i]
                    ytmp[i] = y[i] + acc * h
                _rhs(M, m, I, knots, ca, cb, t + rk.C[s] * h, ytmp, Kx[s], ctl)
            for i in range(n):
                acc = 0.0
                for q in range(rk.N_STAGES):
                    acc += rk.B[q] * Kx[q, i]
                ynew[i] = y[i] + h * acc
            _rhs(M, m, I, knots, ca, cb, t_new, ynew, f_new, ctl)
            for i in range(n):
                Kx[rk.N_STAGES, i] = f_new[i]
            nfev += rk.N_STAGES
            if nfev > max_nfev:
                return _EXHAUSTED, t, y, out, nfev, nsteps
            err = rk.error_norm(Kx[:rk.N_STAGES + 1], y, ynew, h_abs, rtol, atol)
            h_abs *= rk.step_factor(err, rejected)
            if err < 1.0:
                break
            rejected = True
        if not math.isfinite(ynew[0] + ynew[1] + ynew[2] + ynew[3] + ynew[4]):
            return _NONFINITE, t, y, out, nfev, nsteps
        nsteps += 1
        if j < nout and t_out[j] <= t_new:
            # the three extra stages of the 7th-order interpolant, only on steps with output
            for s in range(rk.N_STAGES + 1, 16):
                for i in range(n):
                    acc = 0.0
                    for q in range(s):
                        acc += rk.A_EXTRA[s - rk.N_STAGES - 1, q] * Kx[q, i]
                    ytmp[i] = y[i] + acc * h
                _rhs(M, m, I, knots, ca, cb, t + rk.C_EXTRA[s - rk.N_STAGES - 1] * h, ytmp, Kx[s], ctl)
            nfev += 3
            rk.dense_coefficients(Kx, h, y, ynew, f_new, F)
            while j < nout and t_out[j] <= t_new:
                if t_out[j] == t_new:
                    for r in range(n):
                        out[r, j] = ynew[r]
                else:
                    rk.interpolate_into(t, h, y, F, t_out[j], out[:, j])
                j += 1
        t = t_new
        for i in range(n):
            y[i] = ynew[i]
            f[i] = f_new[i]
    return _REACHED, t, y, out, nfev, nsteps


@dataclass(frozen=True, slots=True, kw_only=True)
class ChunkReplay:
    """Outcome of :func:`replay_chunk`.

    ``states`` has shape ``(5, len(t_out))`` (p1, p2, theta, x, y) and is NaN at the requested
    times a failed integration did not reach; ``t_end`` and ``y_end`` are where it got to.
    ``controls`` has shape ``(4, len(t_out))``: the interpolated ``a, b, adot, bdot`` the
    integration used, at the same times.
    """

    success: bool
    status: int
    message: str
    t_end: float
    y_end: np.ndarray
    states: np.ndarray
    controls: np.ndarray
    nfev: int
    nsteps: int


def replay_chunk(params: SleighParams, state0, schedule: ControlSchedule, i0: int, i1: int, t_out, *,
                 rtol: float = 1e-13, atol: float = 1e-14, max_nfev: int = 2_000_000) -> ChunkReplay:
    """Integrate the full dynamics over one smooth chunk ``[i0, i1)`` of ``schedule``.

    Parameters
    ----------
    params : SleighParams
    state0 : array_like, shape (5,)
        ``(p1, p2, theta, x, y)`` at the chunk's first time.
    schedule : ControlSchedule
    i0, i1 : int
        Row range of a chunk (:meth:`ControlSchedule.chunks`): strictly increasing times.
    t_out : array_like
        Non-decreasing times inside the chunk at which to report the state.
    rtol, atol : float
        DOP853's tolerances.
    max_nfev : int
        Budget of right-hand-side evaluations; exhausting it ends the run with ``success=False``.

    Returns
    -------
    ChunkReplay
        Never raises for a numerical failure: it is reported as ``success=False``.

    Raises
    ------
    ValueError
        If the rows do not form a chunk, ``state0`` is not 5 finite numbers, or ``t_out`` is not
        sorted inside the chunk.
    """
    y0 = np.asarray(state0, dtype=float)
    if y0.shape != (5,) or not np.all(np.isfinite(y0)):
        raise ValueError(f"state0 must be 5 finite numbers (p1, p2, theta, x, y), got {state0!r}")
    knots, ca, cb = schedule.hermite(i0, i1)
    tt = np.ascontiguousarray(t_out, dtype=float)
    if tt.ndim != 1 or np.any(np.diff(tt) < 0) or (tt.size and (tt[0] < knots[0] or tt[-1] > knots[-1])):
        raise ValueError(f"t_out must be non-decreasing times within the chunk [{knots[0]:.17g}, {knots[-1]:.17g}]")
    status, t, y, out, nfev, nsteps = _run(params.M, params.m, params.I, y0.copy(), knots, ca, cb, tt,
                                           float(rtol), float(atol), int(max_nfev))
    status = int(status)
    message = _MESSAGES[status]
    if status:
        message = f"integration failed at t = {t:.6g}: {message}"
    return ChunkReplay(success=status == 0, status=status, message=message, t_end=float(t), y_end=y,
                       states=out, controls=_controls_at(knots, ca, cb, tt), nfev=int(nfev), nsteps=int(nsteps))
