"""The paper's optimisation procedure (Section "Numerical Methods"), run as it was described.

Step 3: ``scipy.optimize.minimize`` with its default method (BFGS, finite-difference gradient)
over the control parameters, each cost evaluation integrating the reduced model with
``solve_ivp(method="BDF")`` at default tolerances, both ways in time and stopping where the speed
vanishes. Costs:

- length-based, eq. (eqn:CLengthandSpeed): ``|L_s - L_d|^p`` over the combined arc;
- point-based, eq. (eqn:Cpoint): ``[(X(t2) - X_opt)^2 + (Y(t2) - Y_opt)^2]^p`` over the forward
  half only (the backward half is generated afterwards).

The paper does not give ``p``; we use ``p = 2`` (selectable). The "zero speed at both ends" part
of the cost is enforced only by the termination event, as in the paper: a half that reaches ``T``
still moving is not penalised. :attr:`ProcedureResult.completed` says whether both ends stopped.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import minimize

from ..dynamics.model import SleighParams
from .controls import control_from_params
from .reduced import PAPER_SOLVER, ReducedArc, ReducedOptions, integrate_reduced
from .tables import PaperRow

__all__ = ["paper_cost", "run_procedure", "ProcedureResult", "RoundingStudy", "best_within_rounding"]


def _cost_of(row: PaperRow, arc: ReducedArc, p: float) -> float:
    if row.method == "point":
        x, y = arc.forward.state[2, -1], arc.forward.state[3, -1]
        d2 = (x - row.target_point[0]) ** 2 + (y - row.target_point[1]) ** 2
        val = float(d2) ** p
    else:
        val = abs(arc.length - row.target_length) ** p
    return val if math.isfinite(val) else math.inf


def paper_cost(row: PaperRow, values, params: SleighParams = SleighParams(),
               options: ReducedOptions = PAPER_SOLVER, p: float = 2.0) -> tuple[float, ReducedArc]:
    """The row's cost for control parameters ``values``, and the arc it was computed from.

    A non-finite cost (the integration broke down) is returned as ``inf``.
    """
    control = control_from_params(row.method, values)
    arc = integrate_reduced(params, row.radius, row.initial, control, row.T, options,
                            backward=row.method != "point")
    return _cost_of(row, arc, p), arc


@dataclass(frozen=True, slots=True, kw_only=True)
class ProcedureResult:
    """Outcome of :func:`run_procedure`: the optimiser's verdict and what it found.

    ``values`` are the optimised control parameters, ``cost`` the cost there as the procedure
    saw it, ``seconds`` the wall time, ``history`` the cost after each iteration.
    """

    success: bool
    status: int
    message: str
    values: tuple
    cost: float
    nit: int
    nfev: int
    seconds: float
    history: tuple = field(default=())


def run_procedure(row: PaperRow, *, guess=None, params: SleighParams = SleighParams(),
                  options: ReducedOptions = PAPER_SOLVER, p: float = 2.0, maxiter: int | None = None,
                  method: str = "BFGS") -> ProcedureResult:
    """Re-run the paper's procedure for ``row`` from its printed guess (or ``guess``).

    Parameters
    ----------
    maxiter : int, optional
        Iteration cap (scipy's default, ``200 * n``, when None).
    method : str
        ``scipy.optimize.minimize`` method; the paper used the default, BFGS.

    Returns
    -------
    ProcedureResult
        The optimiser's own ``success``/``status``/``message``; never raises for a failed
        optimisation.
    """
    x0 = np.asarray(row.guess if guess is None else guess, dtype=float)
    history: list[float] = []

    def f(x):
        return paper_cost(row, x, params, options, p)[0]

    t0 = time.perf_counter()
    opts = {} if maxiter is None else {"maxiter": int(maxiter)}
    with np.errstate(all="ignore"):
        res = minimize(f, x0, method=method, options=opts, callback=lambda xk: history.append(f(xk)))
    return ProcedureResult(success=bool(res.success), status=int(res.status), message=str(res.message),
                           values=tuple(float(v) for v in res.x), cost=float(res.fun), nit=int(res.nit),
                           nfev=int(res.nfev), seconds=time.perf_counter() - t0, history=tuple(history))


@dataclass(frozen=True, slots=True, kw_only=True)
class RoundingStudy:
    """The best a row can do with parameters that round to the published ones.

    ``values`` minimise the row's cost (accurate integration) over the box of half a unit in the
    last printed digit around the published parameters; ``cost`` is the cost there and
    ``published_cost`` at the printed values. If even ``cost`` is far above the printed error, the
    discrepancy is not a matter of rounding.
    """

    values: tuple
    cost: float
    published_cost: float
    half_width: float
    nfev: int
    message: str


def best_within_rounding(row: PaperRow, *, params: SleighParams = SleighParams(),
                         options: ReducedOptions | None = None, p: float = 2.0, digits: int = 3) -> RoundingStudy:
    """Minimise the row's cost over parameters that print as the published ones to ``digits`` decimals.

    Uses L-BFGS-B inside the box ``published +- 0.5 * 10**-digits`` with the accurate solver, so a
    failure to reach the printed error cannot be blamed on the printed rounding.
    """
    from .reduced import TIGHT_SOLVER

    opts = options or TIGHT_SOLVER
    x0 = np.asarray(row.published, dtype=float)
    h = 0.5 * 10.0 ** (-digits)

    def f(x):
        return paper_cost(row, x, params, opts, p)[0]

    c0 = f(x0)
    with np.errstate(all="ignore"):
        res = minimize(f, x0, method="L-BFGS-B", bounds=[(v - h, v + h) for v in x0])
    best_x, best = (res.x, float(res.fun)) if float(res.fun) < c0 else (x0, c0)
    return RoundingStudy(values=tuple(float(v) for v in best_x), cost=best, published_cost=c0, half_width=h,
                         nfev=int(res.nfev), message=str(res.message))
