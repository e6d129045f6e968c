"""The tracking law's closed loop compiled: one sleigh under the law, integrated by the replays' DOP853 loop.

:func:`skatetrace.feedback.closed_loop.replay_law` integrates the model under a
:class:`~skatetrace.feedback.lqr.TrackingLaw` between the jumps of its rates, to verify an
ill-conditioned section. Through ``solve_ivp`` and the law in numpy an evaluation costs about
130 us, and a planned figure's section asks for tens of thousands. Here the same right-hand side
runs compiled:

- the reference's state and rates at ``t``: :meth:`Reference.state_at
  <skatetrace.feedback.reference.Reference.state_at>`'s cubic Hermite (the same polynomial, the same
  clamping to the section, read from the right at a jump: a zero-length interval gives the row's
  state and rates), its interval found by a short walk from the last one
  (:func:`skatetrace.dynamics.replayer.interval`);
- the gain ``K(t)``: linear between the law's rows, clamped, as :meth:`TrackingLaw.gain
  <skatetrace.feedback.lqr.TrackingLaw.gain>`;
- the rates ``u_r(t) - K(t) (z - z_r(t))``, the heading error wrapped as in :meth:`TrackingLaw.rates
  <skatetrace.feedback.lqr.TrackingLaw.rates>`;
- the seven derivatives: the sleigh's five (:func:`skatetrace.dynamics.replayer.sleigh_rhs`, the
  open-loop replay's), then the rates.

The step loop is :func:`skatetrace.dynamics.dop853.integrate`, the open-loop replay's: this module
only registers its right-hand side for it (:func:`skatetrace.dynamics.dop853.register`).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from ..dynamics import dop853 as rk
from ..dynamics.model import SleighParams
from ..dynamics.replayer import interval, sleigh_rhs
from .lqr import TrackingLaw
from .reference import Reference

__all__ = ["SpanRun", "law_arrays", "replay_span"]


class _Law(NamedTuple):
    """What the closed loop's right-hand side reads: the sleigh's parameters, the reference's rows
    (``grid`` (k,), ``z`` and ``zdot`` (7, k)), the law's rows (``t`` (j,), ``K`` (j, 2, 7)) and
    ``last``, its scratch: the intervals of ``grid`` and ``t`` last used."""

    M: float
    m: float
    I: float
    grid: np.ndarray
    z: np.ndarray
    zdot: np.ndarray
    t: np.ndarray
    K: np.ndarray
    last: np.ndarray


@njit(cache=True)
def _start(knots, t):
    """The interval of ``t`` among ``knots`` by bisection (:func:`interval`'s, for a first walk)."""
    return interval(knots, t, min(max(np.searchsorted(knots, t, side="right") - 1, 0), knots.size - 2))


@njit(cache=True)
def _locate(knots, t, last, which):
    """Where ``t``, clamped to the knots, falls: ``(k, h, u)``, the interval ``k`` (:func:`interval`, from
    the right at a repeated knot), its length ``h`` and the fraction ``u`` of it (0 if ``h`` is 0).

    ``last[which]`` holds the interval last used, the walk's start, and keeps this one.
    """
    tc = min(max(t, knots[0]), knots[-1])
    k = interval(knots, tc, last[which])
    last[which] = k
    h = knots[k + 1] - knots[k]
    return k, h, (tc - knots[k]) / h if h > 0.0 else 0.0


@njit(cache=True)
def _rates(grid, z, zdot, lt, K, last, t, y):
    """The law's rates ``(adot, bdot)`` at ``t`` for the state ``y``: :meth:`TrackingLaw.rates`."""
    # the reference at t: Reference.state_at (cubic Hermite), from the right at a jump
    k, h, u = _locate(grid, t, last, 0)
    u2 = u * u
    u3 = u2 * u
    c0, c1, c2, c3 = 2 * u3 - 3 * u2 + 1, u3 - 2 * u2 + u, -2 * u3 + 3 * u2, u3 - u2
    # the gain at t: TrackingLaw.gain, linear between the law's rows
    j, _, w = _locate(lt, t, last, 1)
    du0 = 0.0
    du1 = 0.0
    for i in range(7):
        # (in an interval of length zero: u = h = 0, the row's own state)
        dz = y[i] - (c0 * z[i, k] + c1 * (zdot[i, k] * h) + c2 * z[i, k + 1] + c3 * (zdot[i, k + 1] * h))
        if i == 2:
            dz = (dz + math.pi) % (2 * math.pi) - math.pi
        du0 += ((1 - w) * K[j, 0, i] + w * K[j + 1, 0, i]) * dz
        du1 += ((1 - w) * K[j, 1, i] + w * K[j + 1, 1, i]) * dz
    if h > 0.0:
        e0, e1, e2, e3 = 6 * u2 - 6 * u, 3 * u2 - 4 * u + 1, -6 * u2 + 6 * u, 3 * u2 - 2 * u
        ur0 = (e0 * z[5, k] + e1 * (zdot[5, k] * h) + e2 * z[5, k + 1] + e3 * (zdot[5, k + 1] * h)) / h
        ur1 = (e0 * z[6, k] + e1 * (zdot[6, k] * h) + e2 * z[6, k + 1] + e3 * (zdot[6, k + 1] * h)) / h
    else:
        ur0, ur1 = zdot[5, k], zdot[6, k]
    return ur0 - du0, ur1 - du1


@njit(cache=True, inline="always")
def _rhs(data, t, y, out):
    """The seven equations of ``y = (p1, p2, theta, x, y, a, b)`` under the law's rates at ``t``."""
    ad, bd = _rates(data.grid, data.z, data.zdot, data.t, data.K, data.last, t, y)
    sleigh_rhs(data.M, data.m, data.I, y, y[5], y[6], ad, bd, out)
    out[5] = ad
    out[6] = bd


rk.register(_Law, _rhs)


@njit(cache=True)
def _run(M, m, I, grid, z, zdot, law_t, K, y0, t0, t1, t_out, rtol, atol, max_nfev):
    """Integrate the closed loop from ``(t0, y0)`` to ``t1``; states at the sorted times ``t_out``.

    Returns :func:`skatetrace.dynamics.dop853.integrate`'s ``(status, t, y, out, nfev, nsteps)``.
    """
    last = np.empty(2, dtype=np.int64)
    last[0] = _start(grid, min(max(t0, grid[0]), grid[-1]))
    last[1] = _start(law_t, min(max(t0, law_t[0]), law_t[-1]))
    data = _Law(M, m, I, grid, z, zdot, law_t, K, last)
    return rk.integrate(data, y0, t0, t1, t_out, rtol, atol, max_nfev)


class SpanRun(NamedTuple):
    """Outcome of :func:`replay_span`: ``states`` (7, len(t_out)) NaN at the times not reached; ``y_end``
    the state where the integration got to; ``nfev`` the evaluations of the law it took."""

    success: bool
    y_end: np.ndarray
    states: np.ndarray
    nfev: int


def law_arrays(ref: Reference, law: TrackingLaw) -> tuple[np.ndarray, ...]:
    """The rows the compiled law reads, as contiguous float arrays: ``(grid, z, zdot, t, K)``."""
    return tuple(np.ascontiguousarray(a, dtype=float) for a in (ref.grid, ref.z, ref.zdot, law.t, law.K))


def replay_span(arrays: tuple[np.ndarray, ...], params: SleighParams, z0, span: tuple[float, float], t_out, *,
                rtol: float, atol, max_nfev: int) -> SpanRun:
    """One smooth span of the closed loop (between two jumps of the rates), compiled.

    Parameters
    ----------
    arrays : tuple of ndarray
        :func:`law_arrays` of the reference and the law.
    z0 : array_like, shape (7,)
        The state at the span's start.
    span : (t0, t1)
        Section times, ``t0 < t1``.
    t_out : array_like
        Non-decreasing times in ``[t0, t1]`` at which to report the state.
    rtol : float
    atol : float or array_like, shape (7,)
        DOP853's tolerances (an absolute one per variable, or one for all).
    max_nfev : int
        Budget of evaluations of the law; exceeding it fails the span.

    Returns
    -------
    SpanRun
    """
    grid, z, zdot, law_t, K = arrays
    tt = np.ascontiguousarray(t_out, dtype=float)
    tol = np.array(np.broadcast_to(np.asarray(atol, dtype=float), (7,)))  # a writable copy: one compiled type
    status, _, y, out, nfev, _ = _run(params.M, params.m, params.I, grid, z, zdot, law_t, K,
                                      np.array(z0, dtype=float), float(span[0]), float(span[1]), tt,
                                      float(rtol), tol, int(max_nfev))
    return SpanRun(success=int(status) == rk.REACHED, y_end=y, states=out, nfev=int(nfev))
