"""The sleigh held on a curve, written symbolically for CasADi: rates, velocities and the mass's acceleration.

The same equations as :mod:`skatetrace.dynamics.model` and the constrained split of
:mod:`skatetrace.tracing.maneuver`, on the state ``x = (p1, p2, a, b, s, u)``: the five states of
the manoeuvres and the free control ``u`` (the speed of the mass along the direction that leaves
the curvature unchanged), whose rate ``w = du/dt`` is the planner's control. The curvature is a
cubic of the distance ``s - s0`` travelled on the piece. :func:`sleigh_functions` returns CasADi
functions of ``(x, w, coefficients, s0)``:

- ``f``: the time derivative of ``x``;
- ``accel``: the acceleration of the mass on the ice, in the blade's frame (``d/dt`` of its
  velocity ``(xi2 - xi1 b + adot, xi1 a + bdot)`` plus the frame's rotation ``xi1``);
- ``velocity``: the mass's velocity on the ice in the blade's frame, and ``xi1``;
- ``xi2``: the speed along the blade; ``rates``: ``(adot, bdot)``; ``gap``: the squared norm
  ``|c|^2`` of the curvature condition's coefficients, zero only at the singular point.
"""

from __future__ import annotations

import casadi as ca

__all__ = ["sleigh_functions"]


def sleigh_functions(M: float, m: float, I: float) -> dict[str, ca.Function]:
    """CasADi functions of the constrained sleigh for masses ``M, m`` and inertia ``I``."""
    x = ca.SX.sym("x", 6)
    w = ca.SX.sym("w")
    cf = ca.SX.sym("coefficients", 4)
    s0 = ca.SX.sym("s0")
    p1, p2, a, b, s, u = (x[i] for i in range(6))
    sigma = s - s0
    kappa = cf[0] + sigma * (cf[1] + sigma * (cf[2] + sigma * cf[3]))
    Mm = M + m
    c_a = m * (M * b + kappa * (I + m * a * a))
    c_b = m * a * (kappa * m * b - Mm)
    c_0 = (Mm - kappa * m * b) * p1 + (m * b - kappa * (I + m * (a * a + b * b))) * p2
    n2 = c_a * c_a + c_b * c_b
    n = ca.sqrt(n2)
    ad = -u * c_b / n - c_0 * c_a / n2
    bd = u * c_a / n - c_0 * c_b / n2
    D = Mm * (I + m * a * a) + M * m * b * b
    xi1 = (Mm * (p1 - m * a * bd) + m * b * (p2 + M * ad)) / D
    xi2 = (m * (b * (p1 - m * a * bd) - (I + m * a * a) * ad) + (I + m * (a * a + b * b)) * p2) / D
    eta = ((M * m * b * b + I * Mm) * bd + a * (Mm * p1 + m * b * (p2 + M * ad))) / D
    f = ca.vertcat(-m * eta * xi2, m * eta * xi1, ad, bd, xi2, w)
    v = ca.vertcat(xi2 - xi1 * b + ad, xi1 * a + bd)
    vdot = ca.jtimes(v, x, f)
    accel = ca.vertcat(vdot[0] - xi1 * v[1], vdot[1] + xi1 * v[0])
    args = [x, w, cf, s0]
    names = ["x", "w", "coefficients", "s0"]
    return {
        "f": ca.Function("f", args, [f], names, ["xdot"]),
        "accel": ca.Function("accel", args, [accel], names, ["accel"]),
        "xi2": ca.Function("xi2", args, [xi2], names, ["xi2"]),
        "rates": ca.Function("rates", args, [ca.vertcat(ad, bd)], names, ["rates"]),
        "gap": ca.Function("gap", args, [n2], names, ["gap"]),
        "velocity": ca.Function("velocity", args, [v, xi1], names, ["velocity", "xi1"]),
    }
