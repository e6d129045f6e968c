"""The motion on one leg of a manoeuvre at many times: the states, and the control rates that hold the curve.

A leg's dense output (:class:`~skatetrace.dynamics.integrator.DenseSolution`) gives the states
``(p1, p2, a, b, s)``; the curvature there (a cubic of the distance travelled) and the free control
``u`` (a ramp or an affine function of time) give the rates through the curvature condition
(:func:`~skatetrace.tracing.maneuver.constrained_rates`). Sampling a planned section asks this of
some forty legs at a time, a few hundred times, so for the ramps and affine controls of the
tracer and the planner it is one compiled call (:func:`_motion`): the integrator's own curvature
and the model's own arithmetic (:func:`~skatetrace.dynamics.model.curvature_terms`,
:func:`~skatetrace.dynamics.model.holding_rates`) compiled, hence the same bits as the vectorised
formulas; other controls take those formulas.
"""

from __future__ import annotations

import functools

import numpy as np
from numba import njit

from ..dynamics.integrator import DenseSolution, _curvature, _evaluate_steps, _rates, _terms, integrate_legs
from ..dynamics.model import SleighParams
from .maneuver import ManeuverSolution, constrained_rates

__all__ = ["leg_motion", "load"]


@njit(cache=True, error_model="numpy")
def _motion(M, m, I, t_old, h, y_old, F, ends, coefficients, s0, alpha, beta, affine, t):
    """Rows ``p1, p2, a, b, s, adot, bdot`` at times ``t``: the dense output, then the rates that hold the leg's
    curvature under ``u = alpha t`` (``+ beta`` where ``affine``), as :func:`constrained_rates` computes them."""
    y = _evaluate_steps(t_old, h, y_old, F, ends, t)
    out = np.empty((7, t.size))
    for p in range(t.size):
        p1, p2, a, b, s = y[p, 0], y[p, 1], y[p, 2], y[p, 3], y[p, 4]
        u = alpha * t[p] + beta if affine else alpha * t[p]
        c_a, c_b, c_0 = _terms(M, m, I, _curvature(coefficients, s0, s), p1, p2, a, b)
        out[0, p], out[1, p], out[2, p], out[3, p], out[4, p] = p1, p2, a, b, s
        out[5, p], out[6, p], _ = _rates(c_a, c_b, c_0, u)
    return out


def leg_motion(params: SleighParams, man: ManeuverSolution, leg, t: np.ndarray
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """On ``leg`` of manoeuvre ``man`` at its local times ``t`` (unit speed): the states ``(p1, p2, a, b, s)``
    (rows) and the control rates ``adot, bdot`` that hold the leg's curvature."""
    sol = leg.sol
    t = np.asarray(t, dtype=float)
    if man.basis in ("ramp", "affine") and isinstance(sol, DenseSolution) and t.ndim == 1:
        affine = man.basis == "affine"
        alpha, beta = (float(man.params[0]), float(man.params[1])) if affine else (float(man.params[0]), 0.0)
        out = _motion(params.M, params.m, params.I, sol.t_old, sol.h, sol.y_old, sol.F, sol.ends,
                      np.asarray(leg.coefficients, dtype=float), float(leg.s0), alpha, beta, affine, t)
        return out[:5], out[5], out[6]
    y = sol(t)
    adot, bdot, _ = constrained_rates(params, leg.kappa_at(y[4]), y[0], y[1], y[2], y[3], man.control(t))
    return y, adot, bdot


@functools.cache
def load() -> None:
    """Load :func:`_motion`'s machine code now, as :func:`skatetrace.dynamics.integrator.load` does the integrator's.

    Numba does it on the first call; workers forked after it share the code. Once a process.
    """
    sol = integrate_legs(SleighParams(), np.array([1.0, 0.0, 0.5, 0.5, 0.0]), [1.0], [np.inf], 0.0, 1e-3, rtol=1e-9,
                         atol=1e-12, dense=True).legs[0]
    _motion(1.0, 1.0, 1.0, sol.t_old, sol.h, sol.y_old, sol.F, sol.ends, np.zeros(4), 0.0, 1.0, 0.0, False,
            np.array([5e-4]))
