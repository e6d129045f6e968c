"""The paper's two families of mass motions.

- :class:`CircularControl`: eq. (eqn: controls), ``a = A cos wt, b = A sin wt``; both coordinates
  are prescribed, so nothing is left to enforce the curvature condition.
- :class:`HarmonicControl`: eq. (eqn: general control function), ``a = a1 + a2 sin wt + a3 cos wt``;
  ``b`` follows from the curvature condition through eq. (b_diff_eq), see :func:`b_rate_printed`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from ..dynamics.model import SleighParams

__all__ = ["CircularControl", "HarmonicControl", "control_from_params", "b_rate_printed"]


@dataclass(frozen=True, slots=True)
class CircularControl:
    """``a = A cos(omega t)``, ``b = A sin(omega t)``: the mass circles the contact point."""

    A: float
    omega: float

    @property
    def values(self) -> tuple[float, float]:
        return (self.A, self.omega)

    def a(self, t: float) -> tuple[float, float]:
        """``(a, adot)`` at time ``t``."""
        c, s = math.cos(self.omega * t), math.sin(self.omega * t)
        return self.A * c, -self.A * self.omega * s

    def b(self, t: float) -> tuple[float, float]:
        """``(b, bdot)`` at time ``t``."""
        c, s = math.cos(self.omega * t), math.sin(self.omega * t)
        return self.A * s, self.A * self.omega * c

    def regularity_margin(self) -> float:
        """``a1^2 - a2^2 - a3^2`` for ``a = 0 + 0 sin + A cos``: ``-A^2`` (never regular)."""
        return -self.A * self.A


@dataclass(frozen=True, slots=True)
class HarmonicControl:
    """``a = a1 + a2 sin(omega t) + a3 cos(omega t)``; ``b`` comes from eq. (b_diff_eq)."""

    a1: float
    a2: float
    a3: float
    omega: float

    @property
    def values(self) -> tuple[float, float, float, float]:
        return (self.a1, self.a2, self.a3, self.omega)

    def a(self, t: float) -> tuple[float, float]:
        """``(a, adot)`` at time ``t``."""
        c, s = math.cos(self.omega * t), math.sin(self.omega * t)
        return self.a1 + self.a2 * s + self.a3 * c, self.omega * (self.a2 * c - self.a3 * s)

    def regularity_margin(self) -> float:
        """``a1^2 - (a2^2 + a3^2)``; the paper's condition (sing_cond) asks for it to be positive.

        Positive means ``a(t)`` never reaches 0, where eq. (b_diff_eq) is singular.
        """
        return self.a1 ** 2 - (self.a2 ** 2 + self.a3 ** 2)


def control_from_params(method: str, values) -> CircularControl | HarmonicControl:
    """The control family of ``method`` (``"main"`` or an appendix method) with ``values``."""
    values = tuple(float(v) for v in values)
    if method == "main":
        if len(values) != 2:
            raise ValueError(f"the main method takes (A, omega), got {values!r}")
        return CircularControl(*values)
    if len(values) != 4:
        raise ValueError(f"the appendix methods take (a1, a2, a3, omega), got {values!r}")
    return HarmonicControl(*values)


def b_rate_printed(params: SleighParams, r: float, p1: float, p2: float, a: float, adot: float, b: float) -> float:
    """``bdot`` from the curvature condition ``xi2 = r xi1``, exactly as printed in eq. (b_diff_eq).

    Singular where ``a = 0`` and, as the paper does not say, where ``b = (M + m) r / m``. Agrees
    with ``-(c_a adot + c_0) / c_b`` of :func:`skatetrace.dynamics.model.curvature_coefficients` at
    ``kappa = 1 / r`` (a test checks it).
    """
    M, m, I = params.M, params.m, params.I
    num = (m * b * p1 - m * adot * (I + m * a * a) + p2 * (I + m * (a * a + b * b))
           - r * (M + m) * p1 - r * m * b * (p2 + M * adot))
    den = m * m * a * b - r * (M + m) * m * a
    if den == 0.0:
        return math.nan  # the integrators report the failure where the motion reaches the singular set
    return num / den
