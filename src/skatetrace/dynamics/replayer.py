"""The compiled replay: the full five equations under sampled controls, integrated by DOP853.

Verification replays every chunk of a control schedule (a smooth stretch of ``controls.csv``)
through eqs. (p1_eq)-(y_eq). With scipy's ``solve_ivp`` and a Python right-hand side that costs
about 11 us a call, hundreds of thousands of calls per figure. Here the same integration runs
compiled:

- the controls are the schedule's cubic Hermite interpolants (:meth:`ControlSchedule.hermite`,
  the same coefficients :func:`skatetrace.dynamics.simulate.simulate` uses);
- the velocities are :func:`skatetrace.dynamics.model.body_velocities` itself, compiled, not a copy;
- the step is scipy's DOP853 (the loop :func:`skatetrace.dynamics.dop853.integrate`, which the
  tracking law's replay shares), with the same error norm, step-size control, initial step and
  7th-order dense output at the requested times.

The right-hand side knows nothing of curvatures, manoeuvres or how the controls were found: it is
the free motion of the sleigh and its mass under the given ``a(t), b(t)``. It shares only the
Runge-Kutta arithmetic with the manoeuvre integrator (:mod:`skatetrace.dynamics.integrator`), and a test
compares it with ``solve_ivp`` on the same schedules.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from numba import njit

from . import dop853 as rk
from .controls import ControlSchedule
from .model import SleighParams, body_velocities

__all__ = ["ChunkReplay", "interval", "replay_chunk", "sleigh_rhs"]

_body_velocities = njit(cache=True)(body_velocities)

_MESSAGES = {
    rk.REACHED: "integrated to the end of the chunk",
    rk.EXHAUSTED: "step size collapsed: the evaluation budget ran out (the controls or the motion are singular)",
    rk.SMALL_STEP: "required step size is less than spacing between numbers",
    rk.NONFINITE: "the state became non-finite",
}


class _Schedule(NamedTuple):
    """What the open-loop right-hand side reads (:func:`skatetrace.dynamics.dop853.rhs`): the parameters,
    the controls' Hermite cubics and ``ctl``, its scratch (see :func:`_controls`)."""

    M: float
    m: float
    I: float
    knots: np.ndarray
    ca: np.ndarray
    cb: np.ndarray
    ctl: np.ndarray


@njit(cache=True)
def interval(knots, t, k):
    """The interval of ``t`` among the sorted ``knots``: the last ``k`` with ``knots[k] <= t``, at most
    ``knots.size - 2`` and at least 0 (``np.searchsorted(knots, t, side="right") - 1``, clipped).

    A short walk from ``k``, the interval last used: integration moves forwards. Right of a repeated
    knot (a jump), so a time at a jump is in the interval that starts there.
    """
    last = knots.size - 2
    while k < last and t >= knots[k + 1]:
        k += 1
    while k > 0 and t < knots[k]:
        k -= 1
    return k


@njit(cache=True)
def _controls(knots, ca, cb, t, ctl):
    """``(a, b, adot, bdot)`` at ``t`` from the Hermite cubics (rows ``c3, c2, c1, c0`` per interval).

    They go to ``ctl[:4]``; ``ctl[4]`` holds the index of the interval last used.
    """
    k = interval(knots, t, int(ctl[4]))
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
def sleigh_rhs(M, m, I, y, a, b, adot, bdot, out):
    """Eqs. (p1_eq)-(y_eq): ``d(p1, p2, theta, x, y)/dt`` into ``out[:5]`` for the state ``y[:5]``
    under the mass motion ``(a, b, adot, bdot)``."""
    xi1, xi2, eta = _body_velocities(M, m, I, y[0], y[1], a, b, adot, bdot)
    out[0] = -m * eta * xi2
    out[1] = m * eta * xi1
    out[2] = xi1
    out[3] = xi2 * math.cos(y[2])
    out[4] = xi2 * math.sin(y[2])


@njit(cache=True, inline="always")
def _rhs(data, t, y, out):
    """The five equations under the schedule's controls at ``t``."""
    ctl = data.ctl
    _controls(data.knots, data.ca, data.cb, t, ctl)
    sleigh_rhs(data.M, data.m, data.I, y, ctl[0], ctl[1], ctl[2], ctl[3], out)


rk.register(_Schedule, _rhs)


@njit(cache=True)
def _run(M, m, I, y0, knots, ca, cb, t_out, rtol, atol, max_nfev):
    """Integrate from ``knots[0]`` to ``knots[-1]``; states at the sorted times ``t_out``.

    Returns ``(status, t, y, out, nfev, nsteps)``; ``out`` is NaN at the times not reached
    (:func:`skatetrace.dynamics.dop853.integrate`).
    """
    data = _Schedule(M, m, I, knots, ca, cb, np.zeros(5))
    return rk.integrate(data, y0, knots[0], knots[-1], t_out, rtol, atol, max_nfev)


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
