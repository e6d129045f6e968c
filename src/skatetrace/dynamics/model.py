"""The Chaplygin sleigh steered by a moving point mass.

Symbols follow Rhodes & Putkaradze, "Trajectory tracing in figure skating" (the paper):

- ``p1``  angular momentum about the blade's contact point (eq. p1_eq),
- ``p2``  linear momentum along the blade (eq. p2_eq),
- ``theta`` heading of the blade, ``x, y`` contact point (eqs. theta_eq, x_eq, y_eq),
- ``a, b`` body-frame position of the moving mass (a along the blade, b to its left),
- ``xi1`` angular velocity, ``xi2`` speed along the blade, ``eta`` lateral body-frame velocity
  of the mass (eqs. xi1_eq, xi2_eq, eta_eq),
- ``kappa`` signed curvature of the traced curve (positive turns left).

The state vector is ``(p1, p2, theta, x, y)``. Every function here is vectorised: arrays broadcast.
The curvature condition and the corrected energy formulas follow ``shared/PHYSICS.md``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = [
    "SleighParams",
    "velocities",
    "body_velocities",
    "momenta",
    "rhs",
    "rhs_jacobian",
    "skate_energy",
    "mass_velocity",
    "mass_energy",
    "curvature_coefficients",
    "curvature_terms",
    "holding_rates",
    "singular_point",
]


@dataclass(frozen=True, slots=True, kw_only=True)
class SleighParams:
    """Masses and inertia of the sleigh and its moving mass (consistent units).

    Parameters
    ----------
    M : float
        Mass of the sleigh (skater's body without the moving mass).
    m : float
        Moving (control) mass: the skater's movable centre of mass.
    I : float
        Moment of inertia of the sleigh about the contact point. In this model the sleigh's own
        centre of mass sits at the contact point.

    The paper's values ``M = 2, m = 1, I = 3`` are the defaults.

    Examples
    --------
    >>> SleighParams()
    SleighParams(M=2.0, m=1.0, I=3.0)
    >>> SleighParams(M=-1.0)
    Traceback (most recent call last):
    ...
    ValueError: `M` (sleigh mass) must be a positive finite number, got -1.0
    """

    M: float = 2.0
    m: float = 1.0
    I: float = 3.0

    def __post_init__(self) -> None:
        labels = {"M": "sleigh mass", "m": "moving mass", "I": "sleigh moment of inertia"}
        for name, label in labels.items():
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float, np.floating, np.integer)):
                raise TypeError(f"`{name}` ({label}) must be a number, got {value!r}")
            if not (math.isfinite(value) and value > 0):
                raise ValueError(f"`{name}` ({label}) must be a positive finite number, got {value!r}")
            object.__setattr__(self, name, float(value))

    def to_dict(self) -> dict[str, float]:
        """Return ``{"M": ..., "m": ..., "I": ...}``."""
        return {"M": self.M, "m": self.m, "I": self.I}

    @property
    def length_scale(self) -> float:
        """Radius of gyration ``sqrt(I / (M + m))``: the model's natural length."""
        return math.sqrt(self.I / (self.M + self.m))


def velocities(params: SleighParams, p1, p2, a, b, adot, bdot):
    """Body velocities from momenta and controls: the paper's equations (xi1_eq), (xi2_eq), (eta_eq).

    Returns
    -------
    xi1, xi2, eta
        Angular velocity of the blade, speed along the blade, lateral body-frame velocity of the
        mass (``eta = a xi1 + bdot``).
    """
    return body_velocities(params.M, params.m, params.I, p1, p2, a, b, adot, bdot)


def body_velocities(M, m, I, p1, p2, a, b, adot, bdot):
    """:func:`velocities` with the parameters as plain numbers.

    Pure arithmetic, so that the compiled replay (:mod:`skatetrace.dynamics.replayer`) compiles this very
    function rather than a copy of its formulas.
    """
    D = (M + m) * (I + m * a * a) + M * m * b * b
    q = p1 - m * a * bdot
    r = p2 + M * adot
    xi1 = ((M + m) * q + m * b * r) / D
    xi2 = (m * (b * q - (I + m * a * a) * adot) + (I + m * (a * a + b * b)) * p2) / D
    eta = ((M * m * b * b + I * (M + m)) * bdot + a * ((M + m) * p1 + m * b * r)) / D
    return xi1, xi2, eta


def momenta(params: SleighParams, xi1, xi2, a, b, adot, bdot):
    """Momenta ``(p1, p2)`` for given body velocities: the inverse of :func:`velocities`.

    They are the derivatives of the kinetic energy (sleigh plus mass) with respect to ``xi1`` and
    ``xi2``. At rest (``xi1 = xi2 = 0``) they are the momenta of the mass's own motion.
    """
    M, m, I = params.M, params.m, params.I
    u, w = mass_velocity(xi1, xi2, a, b, adot, bdot)
    p1 = I * xi1 + m * (a * w - b * u)
    p2 = M * xi2 + m * u
    return p1, p2


def rhs(params: SleighParams, state, a, b, adot, bdot):
    """Time derivative of ``state = (p1, p2, theta, x, y)``: the paper's equations (p1_eq)-(y_eq).

    Parameters
    ----------
    state : array_like, shape (5,) or (5, n)
    a, b, adot, bdot : float or array_like, shape (n,)

    Returns
    -------
    ndarray, shape like ``state``
    """
    p1, p2, theta = state[0], state[1], state[2]
    xi1, xi2, eta = velocities(params, p1, p2, a, b, adot, bdot)
    m = params.m
    return np.array(
        [-m * eta * xi2, m * eta * xi1, xi1, xi2 * np.cos(theta), xi2 * np.sin(theta)]
    )


def skate_energy(params: SleighParams, xi1, xi2):
    """Kinetic energy of the sleigh, ``M xi2^2 / 2 + I xi1^2 / 2``.

    Notes
    -----
    On an arc of radius r this is ``xi2^2 (M + I / r^2) / 2``. The paper's final formula
    ``M xi2^2 (1 + M r / I) / 2`` is wrong (it assumes ``p1 = I Omega = M v r``); see PHYSICS.md.
    """
    return 0.5 * params.M * xi2 * xi2 + 0.5 * params.I * xi1 * xi1


def mass_velocity(xi1, xi2, a, b, adot, bdot):
    """Velocity of the moving mass on the ice, in the body frame: ``(xi2 - xi1 b + adot, xi1 a + bdot)``.

    The blade's velocity ``xi2 e1``, the rotation ``xi1`` carrying the mass at ``(a, b)``, and the
    mass's own motion ``(adot, bdot)`` relative to the body. The paper's eq. (vec_vm) writes ``e1``
    twice; the second component is along ``e2``.
    """
    return xi2 - xi1 * b + adot, xi1 * a + bdot


def mass_energy(params: SleighParams, xi1, xi2, a, b, adot, bdot):
    """Kinetic energy of the moving mass, ``m [(xi2 - xi1 b + adot)^2 + (xi1 a + bdot)^2] / 2``
    (:func:`mass_velocity`)."""
    u, w = mass_velocity(xi1, xi2, a, b, adot, bdot)
    return 0.5 * params.m * (u * u + w * w)


def curvature_coefficients(params: SleighParams, kappa, p1, p2, a, b):
    """Coefficients of the curvature condition ``c_a adot + c_b bdot + c_0 = 0``.

    The blade follows a curve of signed curvature ``kappa`` exactly iff ``xi1 = kappa xi2`` at
    every instant; multiplied by the denominator ``D`` this is linear in the control rates.

    Returns
    -------
    c_a, c_b, c_0
        ``c_a = m (M b + kappa (I + m a^2))``, ``c_b = m a (kappa m b - (M + m))``,
        ``c_0 = (M + m - kappa m b) p1 + (m b - kappa (I + m (a^2 + b^2))) p2``.
    """
    return curvature_terms(params.M, params.m, params.I, kappa, p1, p2, a, b)


def curvature_terms(M, m, I, kappa, p1, p2, a, b):
    """:func:`curvature_coefficients` with the parameters as plain numbers.

    Pure arithmetic, like :func:`body_velocities`, so that compiled code
    (:mod:`skatetrace.tracing.leg_motion`) compiles this very function rather than a copy of its formulas.
    """
    c_a = m * (M * b + kappa * (I + m * a * a))
    c_b = m * a * (kappa * m * b - (M + m))
    c_0 = (M + m - kappa * m * b) * p1 + (m * b - kappa * (I + m * (a * a + b * b))) * p2
    return c_a, c_b, c_0


def holding_rates(c_a, c_b, c_0, u):
    """Control rates ``(adot, bdot, |c|)`` that hold the curvature whose condition has coefficients
    ``c_a, c_b, c_0`` (:func:`curvature_coefficients`), for the free control ``u``.

    ``u`` is the speed of the mass along ``n = (-c_b, c_a) / |c|``, which leaves the curvature
    unchanged; the rest of the rates is along ``c``. Pure arithmetic, like :func:`curvature_terms`.
    ``|c| = 0`` is the singular point.
    """
    n2 = c_a * c_a + c_b * c_b
    n = np.sqrt(n2)
    adot = -u * c_b / n - c_0 * c_a / n2
    bdot = u * c_a / n - c_0 * c_b / n2
    return adot, bdot, n


def singular_point(params: SleighParams, kappa: float) -> tuple[float, float]:
    """The only mass position where both curvature coefficients vanish: ``(0, -kappa I / M)``.

    There neither control rate can hold the curvature, whichever is chosen as free.
    """
    return 0.0, -kappa * params.I / params.M


def rhs_jacobian(params: SleighParams, state, a, b, adot, bdot):
    """Partial derivatives of :func:`rhs` (same arguments), exact: the quotient rule on the fractions
    of :func:`body_velocities`.

    Returns an array of shape ``(5, 9)`` (or ``(5, 9, n)``): ``J[i, j]`` is the derivative of row
    ``i`` of :func:`rhs` with respect to variable ``j`` of ``(p1, p2, theta, x, y, a, b, adot, bdot)``.
    """
    M, m, I = params.M, params.m, params.I
    p1, p2, theta = (np.asarray(v, dtype=float) for v in (state[0], state[1], state[2]))
    a, b, adot, bdot = (np.asarray(v, dtype=float) for v in (a, b, adot, bdot))
    shape = np.broadcast_shapes(p1.shape, a.shape, b.shape, adot.shape, bdot.shape)
    zero = np.zeros(shape)
    Mm = M + m
    D = Mm * (I + m * a * a) + M * m * b * b
    q = p1 - m * a * bdot
    r = p2 + M * adot
    xi1, xi2, eta = body_velocities(M, m, I, p1, p2, a, b, adot, bdot)
    # each velocity's numerator N over D: d(N / D) = (dN - (N / D) dD) / D, by (p1, p2, a, b, adot, bdot)
    dD = (zero, zero, 2 * Mm * m * a + zero, 2 * M * m * b + zero, zero, zero)
    dN = {
        "xi1": (Mm + zero, m * b + zero, -Mm * m * bdot + zero, m * r + zero, M * m * b + zero, -Mm * m * a + zero),
        "xi2": (m * b + zero, I + m * (a * a + b * b) + zero, m * (2 * a * (p2 - m * adot) - m * b * bdot) + zero,
                m * (q + 2 * b * p2) + zero, -m * (I + m * a * a) + zero, -m * m * a * b + zero),
        "eta": (Mm * a + zero, m * a * b + zero, Mm * p1 + m * b * r + zero, m * (2 * M * b * bdot + a * r) + zero,
                M * m * a * b + zero, M * m * b * b + I * Mm + zero),
    }
    value = {"xi1": xi1, "xi2": xi2, "eta": eta}
    d = {k: [(dn - value[k] * dd) / D for dn, dd in zip(dN[k], dD)] for k in dN}
    c, s = np.cos(theta) + zero, np.sin(theta) + zero
    J = np.zeros((5, 9) + shape)
    cols = (0, 1, 5, 6, 7, 8)
    for j, col in enumerate(cols):
        J[0, col] = -m * (d["eta"][j] * xi2 + eta * d["xi2"][j])
        J[1, col] = m * (d["eta"][j] * xi1 + eta * d["xi1"][j])
        J[2, col] = d["xi1"][j]
        J[3, col] = d["xi2"][j] * c
        J[4, col] = d["xi2"][j] * s
    J[3, 2] = -xi2 * s
    J[4, 2] = xi2 * c
    return J
