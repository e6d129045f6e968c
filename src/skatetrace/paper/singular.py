"""How an appendix arc meets ``a = 0``, measured where the measurement does not depend on round-off.

The appendix controls prescribe ``a(t) = a1 + a2 sin wt + a3 cos wt`` and take ``bdot`` from the
curvature condition, eq. (b_diff_eq): ``bdot = F / (a g)`` with (at ``kappa = 1 / r``)

    g = m (kappa m b - (M + m)),        F = -(c_a adot + c_0)

(``c_a, c_0`` of :func:`skatetrace.dynamics.model.curvature_coefficients`). Where ``a(t)`` has a simple zero
``t*`` the equation is singular. Whether an integrator "breaks down" there, steps across, or
continues on some branch depends on its step sizes and on round-off, so none of that is a fact
about the paper's optimum. What is a fact is what happens *on the way in*, which is a regular ODE
up to any ``t* - tau``:

- Near ``a = 0`` the lateral velocity of the mass is ``eta ~ bdot``, so the momenta move with
  ``b``: ``dp1/db = -m xi2``, ``dp2/db = kappa m xi2``. Along the motion
  ``dF/dt = F_b bdot = (F_b / (g a)) F`` with
  ``F_b = dF/db - m xi2 dF/dp1 + kappa m xi2 dF/dp2``, and ``a = adot* (t - t*)``. Hence::

      F ~ |t - t*|^mu,   mu = F_b / (g adot*),
      bdot ~ |t - t*|^(mu - 1),   KE_m ~ m bdot^2 / 2 ~ |t - t*|^(2 (mu - 1)),

  plus a bounded part from the explicit time dependence. Stopping at ``|a| = eps`` instead of at
  ``t* - tau`` gives the same exponents, since ``eps = |adot*| tau`` to first order.
- ``0 < mu < 1``: ``bdot`` and the mass's kinetic energy grow without bound: there is no
  continuation with bounded rates. ``mu > 1``: ``bdot`` stays bounded but the continuation past
  ``t*`` is not unique (any ``C |t - t*|^mu`` may be added on the far side), so everything computed
  after the crossing depends on how the integrator stepped across it.

PHYSICS.md's "``bdot ~ (t* - t)^(-1/2)``, ``KE ~ 1 / (t* - t)``" is the case ``mu = 1/2``, not a law:
the published optima give ``mu`` of 0.53-0.62 on the forward crossings of arcs 1 and 3 (fitted
slopes of ``bdot`` -0.39 to -0.49, checked against ``mu - 1`` in the tests) and 0.9-1.3 on the other
crossings, where ``bdot`` stays bounded or grows too slowly to see (``tau^-0.1``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

from ..dynamics.model import SleighParams, mass_energy
from .controls import HarmonicControl, control_from_params
from .reduced import TIGHT_SOLVER, ReducedOptions, integrate_reduced
from .tables import PaperRow

__all__ = ["Crossing", "approach_a_zero", "crossing_exponent", "first_zero_of_a"]

#: Distances ``t* - t`` at which the approach is sampled (decades, so the fit is in log-log).
TAUS = (1e-2, 1e-3, 1e-4, 1e-5, 1e-6)


@dataclass(frozen=True, slots=True, kw_only=True)
class Crossing:
    """The approach of one half-arc to the first zero of ``a(t)`` in its direction.

    Attributes
    ----------
    direction : int
        ``+1`` (forward from ``t = 0``) or ``-1`` (backward).
    t_star : float or None
        The zero of ``a`` (None: ``a`` has no zero within ``T`` in this direction).
    adot_star : float
        ``da/dt`` at ``t_star``.
    reaches : bool
        The reduced model is still moving at ``t* - tau`` for every ``tau`` (its speed did not
        vanish first): the arc must cross ``a = 0``.
    speed_at_crossing : float
        The reduced speed at the smallest ``tau``.
    taus, bdot, mass_energy : tuple of float
        ``|t - t*|``, ``|bdot|`` and the mass's kinetic energy there.
    bdot_exponent, energy_exponent : float
        Least-squares slopes of ``log |bdot|`` and ``log KE_m`` against ``log tau``.
    mu : float
        The exponent of ``F`` from the state at the smallest ``tau`` (module docstring); the
        theory predicts slopes ``min(mu - 1, 0)`` and ``2 min(mu - 1, 0)``.
    """

    direction: int
    t_star: float | None
    adot_star: float
    reaches: bool
    speed_at_crossing: float
    taus: tuple
    bdot: tuple
    mass_energy: tuple
    bdot_exponent: float
    energy_exponent: float
    mu: float

    @property
    def blows_up(self) -> bool:
        """``bdot`` and the mass energy visibly diverge at the crossing (``0 < mu < 0.8``).

        The margin below 1 keeps the verdict off the borderline: at ``mu = 0.9`` the growth
        ``tau^-0.1`` is real but does not show over the sampled decades.
        """
        return bool(self.reaches and 0.0 < self.mu < 0.8)

    def to_dict(self) -> dict:
        return {k: getattr(self, k) for k in ("direction", "t_star", "adot_star", "reaches", "speed_at_crossing",
                                              "taus", "bdot", "mass_energy", "bdot_exponent", "energy_exponent",
                                              "mu")} | {"blows_up": self.blows_up}


def first_zero_of_a(control: HarmonicControl, direction: int, t_max: float, n: int = 20_001) -> float | None:
    """The first zero of ``a(t)`` from ``t = 0`` towards ``direction * t_max`` (None if there is none)."""
    ts = np.linspace(0.0, direction * t_max, n)
    a = np.array([control.a(float(t))[0] for t in ts])
    k = np.nonzero(a[:-1] * a[1:] <= 0)[0]
    if not k.size:
        return None
    i = int(k[0])
    if a[i] == 0.0:
        return float(ts[i])
    return float(brentq(lambda t: control.a(t)[0], ts[i], ts[i + 1], xtol=1e-15, rtol=4 * np.finfo(float).eps))


def crossing_exponent(params: SleighParams, kappa: float, p1: float, p2: float, b: float, adot: float) -> float:
    """``mu = F_b / (g adot)`` at ``a = 0`` (module docstring): ``F ~ |t - t*|^mu`` near the zero."""
    M, m, I = params.M, params.m, params.I
    g = m * (kappa * m * b - (M + m))
    dF_db = -(m * M * adot - kappa * m * p1 + (m - 2 * kappa * m * b) * p2)
    dF_dp1 = -(M + m - kappa * m * b)
    dF_dp2 = -(m * b - kappa * (I + m * b * b))
    D0 = (M + m) * I + M * m * b * b
    xi2 = (m * (b * p1 - I * adot) + (I + m * b * b) * p2) / D0
    return float((dF_db - m * xi2 * dF_dp1 + kappa * m * xi2 * dF_dp2) / (g * adot))


def approach_a_zero(row: PaperRow, values=None, direction: int = 1, *, params: SleighParams = SleighParams(),
                    options: ReducedOptions = TIGHT_SOLVER, taus=TAUS, initial=None) -> Crossing:
    """Integrate ``row``'s reduced model towards the first zero of ``a`` and measure the approach.

    Parameters
    ----------
    values : sequence, optional
        ``(a1, a2, a3, omega)``; the published optimum by default.
    direction : {1, -1}
        Forward or backward from the table's initial condition.
    taus : sequence of float
        Distances ``t* - t`` at which to stop (decreasing); each is a separate regular integration.
    initial : sequence, optional
        Initial state instead of the table's.

    Returns
    -------
    Crossing
        ``t_star`` None if ``a`` does not vanish within ``T``; ``reaches`` False if the speed
        vanishes first (then the growth fields are empty).
    """
    if row.method == "main":
        raise ValueError("approach_a_zero is for the appendix rows (b from eq. (b_diff_eq)); got a main-method row")
    if direction not in (1, -1):
        raise ValueError(f"direction must be 1 or -1, got {direction!r}")
    control = control_from_params(row.method, row.published if values is None else values)
    initial = row.initial if initial is None else tuple(initial)
    t_star = first_zero_of_a(control, direction, row.T)
    empty = dict(taus=(), bdot=(), mass_energy=(), bdot_exponent=math.nan, energy_exponent=math.nan, mu=math.nan)
    if t_star is None:
        return Crossing(direction=direction, t_star=None, adot_star=math.nan, reaches=False,
                        speed_at_crossing=math.nan, **empty)
    adot_star = control.a(t_star)[1]
    taus = tuple(float(t) for t in taus)
    bd, ke, last = [], [], None
    for tau in taus:
        span = abs(t_star) - tau
        if span <= 0:
            raise ValueError(f"tau = {tau:g} reaches past t = 0 (t* = {t_star:g})")
        arc = integrate_reduced(params, row.radius, initial, control, span, options, backward=direction < 0)
        half = arc.forward if direction > 0 else arc.backward
        if half.status != "time":
            return Crossing(direction=direction, t_star=t_star, adot_star=adot_star, reaches=False,
                            speed_at_crossing=math.nan, **empty)
        last = arc.series([half.t_end])
        bd.append(abs(float(last["bdot"][0])))
        ke.append(float(mass_energy(params, last["xi1"], last["xi2"], last["a"], last["b"], last["adot"],
                                    last["bdot"])[0]))
    lt = np.log(taus)
    with np.errstate(all="ignore"):
        slope_b = float(np.polyfit(lt, np.log(bd), 1)[0]) if len(taus) > 1 else math.nan
        slope_e = float(np.polyfit(lt, np.log(ke), 1)[0]) if len(taus) > 1 else math.nan
    mu = crossing_exponent(params, 1.0 / row.radius, float(last["p1"][0]), float(last["p2"][0]),
                           float(last["b"][0]), adot_star)
    return Crossing(direction=direction, t_star=t_star, adot_star=float(adot_star), reaches=True,
                    speed_at_crossing=float(last["speed"][0]), taus=taus, bdot=tuple(bd), mass_energy=tuple(ke),
                    bdot_exponent=slope_b, energy_exponent=slope_e, mu=mu)
