"""Simulation of the full five equations under arbitrary controls, open loop or in feedback.

``simulate`` integrates eqs. (p1_eq)-(y_eq) for any mass motion: a callable returning
``(a, b, adot, bdot)`` at a time, a sampled :class:`~skatetrace.dynamics.controls.ControlSchedule`
(interpolated by cubic Hermite splines, restarted at every jump), or a :class:`Controller` that
maps the state (the mass position included) to the mass rates, closing the loop. Nothing here
knows how the controls were found; :mod:`skatetrace.verification.verify` uses it to replay
computed controls.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

import numpy as np

from .controls import ControlSchedule
from .model import SleighParams, velocities

__all__ = ["Controller", "Trajectory", "simulate"]

ControlFn = Callable[[float], tuple[float, float, float, float]]


@dataclass(frozen=True, slots=True)
class Controller:
    """State feedback: the mass rates as a function of time and the full state.

    ``rates(t, z) -> (adot, bdot)``, where ``z = (p1, p2, theta, x, y, a, b)`` is the sleigh's state
    with the mass position. With a controller, :func:`simulate` integrates all seven (the mass
    moves at the rates the controller returns). A
    :class:`~skatetrace.feedback.lqr.TrackingLaw`'s :meth:`~skatetrace.feedback.lqr.TrackingLaw.controller`
    is one; any callable of that signature is another.
    """

    rates: Callable[[float, np.ndarray], tuple[float, float]]


@dataclass(frozen=True, slots=True, kw_only=True)
class Trajectory:
    """Result of :func:`simulate`.

    ``t`` has shape ``(n,)`` and ``state`` shape ``(5, n)`` (p1, p2, theta, x, y) at the solver's
    steps, or ``(7, n)`` (with the mass position ``a, b``) under a :class:`Controller`;
    :meth:`__call__` evaluates the dense output anywhere in the span.
    """

    success: bool
    status: int
    message: str
    t: np.ndarray
    state: np.ndarray
    nfev: int
    pieces: tuple  # ((t0, t1, OdeSolution), ...)

    def __call__(self, t) -> np.ndarray:
        """State at times ``t`` (array), shape ``(5, len(t))`` (``(7, len(t))`` under a controller)."""
        t = np.atleast_1d(np.asarray(t, dtype=float))
        out = np.full((self.state.shape[0], t.size), np.nan)
        for t0, t1, sol in self.pieces:
            m = (t >= min(t0, t1)) & (t <= max(t0, t1))
            if np.any(m):
                out[:, m] = sol(t[m])
        return out


class _Exhausted(Exception):
    def __init__(self, t: float):
        self.t = t


def _rhs(params: SleighParams, controls: ControlFn | Controller, budget: list):
    """``f(t, y)`` for solve_ivp: the five equations under ``controls(t)``, or the seven (the mass
    moving at the rates a :class:`Controller` returns) under state feedback."""
    m = params.m
    feedback = isinstance(controls, Controller)

    def f(t, y):
        budget[0] -= 1
        if budget[0] < 0:
            raise _Exhausted(t)
        if feedback:
            a, b = y[5], y[6]
            ad, bd = controls.rates(t, y)
        else:
            a, b, ad, bd = controls(t)
        xi1, xi2, eta = velocities(params, y[0], y[1], a, b, ad, bd)
        dy = [-m * eta * xi2, m * eta * xi1, xi1, xi2 * math.cos(y[2]), xi2 * math.sin(y[2])]
        return dy + [ad, bd] if feedback else dy

    return f


def simulate(
    params: SleighParams,
    state0,
    controls: ControlFn | ControlSchedule | Controller,
    t_span: tuple[float, float] | None = None,
    *,
    rtol: float = 1e-12,
    atol: float = 1e-13,
    method: str = "DOP853",
    max_nfev: int = 2_000_000,
) -> Trajectory:
    """Integrate the full dynamics from ``state0 = (p1, p2, theta, x, y)``.

    Parameters
    ----------
    state0 : array_like
        ``(p1, p2, theta, x, y)``; with a :class:`Controller`, ``(p1, p2, theta, x, y, a, b)``.
    controls : callable, ControlSchedule or Controller
        ``controls(t) -> (a, b, adot, bdot)`` (floats), a sampled schedule, or state feedback. With a
        schedule the integration restarts at every repeated time (a jump of the rates), and
        ``t_span`` defaults to the schedule's span.
    t_span : (t0, t1)
        Required with a callable or a controller.
    max_nfev : int
        Budget of right-hand-side evaluations; exhausting it (step sizes collapsing at a
        singularity of the controls or the motion) ends the run with ``success=False``.

    Returns
    -------
    Trajectory
        With ``success=False`` and the integrator's message if it failed; never raises for a
        numerical failure.

    Examples
    --------
    >>> p = SleighParams()
    >>> tr = simulate(p, [0.0, 1.0, 0.0, 0.0, 0.0], lambda t: (0.5, 0.0, 0.0, 0.0), (0.0, 2.0))
    >>> bool(tr.success), round(float(tr.state[3, -1]), 6)  # mass locked on the blade: straight line
    (True, 0.666667)

    In feedback, the state includes the mass, and the controller returns its rates:

    >>> hold = Controller(lambda t, z: (-2.0 * z[5], -2.0 * z[6]))  # pull the mass onto the blade
    >>> tr = simulate(p, [0.0, 1.0, 0.0, 0.0, 0.0, 0.5, 0.0], hold, (0.0, 3.0))
    >>> bool(tr.success), tr.state.shape[0], abs(float(tr.state[5, -1])) < 0.5 * math.exp(-5)
    (True, 7, True)
    """
    feedback = isinstance(controls, Controller)
    n = 7 if feedback else 5
    y0 = np.asarray(state0, dtype=float)
    if y0.shape != (n,) or not np.all(np.isfinite(y0)):
        what = "(p1, p2, theta, x, y, a, b) with a controller" if feedback else "(p1, p2, theta, x, y)"
        raise ValueError(f"state0 must be {n} finite numbers {what}, got {state0!r}")
    if isinstance(controls, ControlSchedule):
        chunks = [(float(controls.t[i0]), float(controls.t[i1 - 1]), controls.scalar_interpolant(i0, i1))
                  for i0, i1 in controls.chunks()]
        if t_span is not None:
            lo, hi = t_span
            chunks = [(max(a, lo), min(b, hi), f) for a, b, f in chunks if b > lo and a < hi]
    else:
        if t_span is None:
            raise ValueError("t_span is required when controls is a callable or a controller")
        if not (np.all(np.isfinite(t_span)) and t_span[1] != t_span[0]):
            raise ValueError(f"t_span must be two different finite times, got {t_span!r}")
        chunks = [(float(t_span[0]), float(t_span[1]), controls)]
    from scipy.integrate import solve_ivp  # here, not at import: scipy.integrate takes 0.3-0.6 s to load

    ts, ys, pieces, nfev = [], [], [], 0
    y = y0
    budget = [int(max_nfev)]
    for t0, t1, fn in chunks:
        try:
            sol = solve_ivp(_rhs(params, fn, budget), (t0, t1), y, method=method, rtol=rtol, atol=atol,
                            dense_output=True)
        except _Exhausted as exc:
            return Trajectory(success=False, status=-2, message=(
                f"integration failed near t = {exc.t:.6g}: more than {max_nfev} evaluations (the controls "
                "or the motion are singular there)"), t=np.concatenate(ts) if ts else np.empty(0),
                state=np.hstack(ys) if ys else np.empty((n, 0)), nfev=int(max_nfev), pieces=tuple(pieces))
        nfev += sol.nfev
        if sol.status < 0 or not np.all(np.isfinite(sol.y[:, -1])):
            return Trajectory(success=False, status=-1, message=f"integration failed at t = {sol.t[-1]:.6g}: {sol.message}",
                              t=np.concatenate(ts + [sol.t]), state=np.hstack(ys + [sol.y]), nfev=nfev,
                              pieces=tuple(pieces))
        ts.append(sol.t)
        ys.append(sol.y)
        pieces.append((t0, t1, sol.sol))
        y = sol.y[:, -1]
    return Trajectory(success=True, status=0, message="integrated", t=np.concatenate(ts), state=np.hstack(ys),
                      nfev=nfev, pieces=tuple(pieces))
