"""A launch that is a stop reversed in time, and the other way round: found without a solve of its own.

Time reversal ``t -> -t`` with ``(p1, p2, a, b, s) -> (p1, p2, -a, b, -s)`` and the same ramp slope
``alpha`` maps the constrained system of :mod:`~skatetrace.tracing.maneuver` onto itself (``c_a``,
``c_0`` and the speed ``xi2`` are even in ``a``, ``c_b`` odd; the rates ``(adot, bdot) -> (adot,
-bdot)`` then give ``(p1, p2)' -> -(p1, p2)'``), and the curvature depends on ``|s|`` only. IEEE
arithmetic is symmetric under negation, so this is exact in floating point too: a section whose
glide has the mass at ``a = 0`` and the same curve on both sides of its apex has for its launch the
mirror image of its stop (:func:`~skatetrace.tracing.sections.trace_section`).
"""

from __future__ import annotations

import numpy as np

from ..dynamics.integrator import DenseSolution
from .maneuver import Leg, ManeuverSolution, _coefficients

__all__ = ["mirrored_maneuver", "same_legs"]

_MIRROR = np.array([1.0, 1.0, -1.0, 1.0, -1.0])


def _mirrored_dense(sol: DenseSolution) -> DenseSolution:
    """``sol`` under the time reversal: the interpolant's variable ``(t - t_old) / h`` is unchanged."""
    return DenseSolution(-sol.t_old, -sol.h, sol.y_old * _MIRROR, sol.F * _MIRROR)


def same_legs(first, second) -> bool:
    """Whether two lists of legs ``[(kappa, length), ...]`` describe the same curve from the glide."""
    return len(first) == len(second) and all(
        _coefficients(k1) == _coefficients(k2) and float(l1) == float(l2)
        for (k1, l1), (k2, l2) in zip(first, second))


def mirrored_maneuver(solution: ManeuverSolution, legs=None) -> ManeuverSolution:
    """The launch (or stop) on the same legs that is the time reversal of a stop (or launch).

    A stop from a glide with the mass at ``(a, b)`` reversed in time is the launch onto the glide at
    ``(-a, b)`` over the same legs (integrated backwards from it), with the same ``alpha``, the
    duration negated and the same residuals and singular distance. So when a section's launch runs
    over the same curve as its stop and the mass glides at ``a = 0`` the launch is the stop's mirror
    image, exactly, and need not be solved again.

    ``legs`` (``[(kappa, length), ...]``, :func:`same_legs` as the solution's) gives the curvature
    coefficients to report on the mirror's legs as its own solve would (a launch's come from a
    polynomial expanded backwards: ``-0.0`` where the stop has ``0.0``).
    """
    kind = "launch" if solution.kind == "stop" else "stop"
    coeffs = [_coefficients(k) for k, _ in legs] if legs is not None else [leg.coefficients for leg in solution.legs]
    legs = tuple(Leg(c, -leg.t0, -leg.t1, _mirrored_dense(leg.sol), leg.s0) for c, leg in zip(coeffs, solution.legs))
    return ManeuverSolution(
        kind=kind, success=solution.success, message=solution.message, params=solution.params,
        duration=-solution.duration, legs=legs, residuals=dict(solution.residuals),
        min_singular_distance=solution.min_singular_distance, nfev=0, basis=solution.basis,
    )
