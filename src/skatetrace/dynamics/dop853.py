"""The arithmetic of scipy's DOP853 that does not involve the right-hand side, compiled.

Two compiled integrators use it: :mod:`skatetrace.dynamics.integrator` (the sleigh held on a curve, for the
manoeuvre solves) and :mod:`skatetrace.dynamics.replayer` (the full five equations under sampled controls,
for verification). Each keeps its own right-hand side and stage loop; what they share here is the
Butcher tableau and everything scipy's :class:`scipy.integrate.DOP853` computes from the stages:
the error norm, the step-size factor, the initial step, and the 7th-order dense output.
"""

from __future__ import annotations

import importlib.util
import math
from pathlib import Path

import numpy as np
from numba import njit

__all__ = ["N_STAGES", "A", "B", "C", "A_EXTRA", "C_EXTRA", "POWER"]



def _scipy_coefficients():
    """scipy's ``dop853_coefficients`` module (numbers only, it imports nothing but numpy).

    It is read from its file, so that the package ``scipy.integrate`` (0.3-0.6 s to import, for
    solve_ivp, quadrature and more) is not loaded by every run; if the file is not where scipy
    keeps it, the module is imported the ordinary way.
    """
    spec = importlib.util.find_spec("scipy")
    path = Path(spec.origin).parent / "integrate" / "_ivp" / "dop853_coefficients.py" if spec and spec.origin else None
    if path is None or not path.is_file():
        from scipy.integrate._ivp import dop853_coefficients

        return dop853_coefficients
    file_spec = importlib.util.spec_from_file_location("skatetrace._dop853_coefficients", path)
    module = importlib.util.module_from_spec(file_spec)
    file_spec.loader.exec_module(module)
    return module


_dop = _scipy_coefficients()
N_STAGES = _dop.N_STAGES  # 12
A = np.ascontiguousarray(_dop.A[:N_STAGES, :N_STAGES])
B = np.ascontiguousarray(_dop.B)
C = np.ascontiguousarray(_dop.C[:N_STAGES])
E3 = np.ascontiguousarray(_dop.E3)
E5 = np.ascontiguousarray(_dop.E5)
D = np.ascontiguousarray(_dop.D)
A_EXTRA = np.ascontiguousarray(_dop.A[N_STAGES + 1:])
C_EXTRA = np.ascontiguousarray(_dop.C[N_STAGES + 1:])
POWER = _dop.INTERPOLATOR_POWER  # 7


@njit(cache=True)
def rms(x):
    """Root mean square of a vector."""
    return math.sqrt(np.sum(x * x) / x.size)


@njit(cache=True)
def error_norm(K, y, ynew, h_abs, rtol, atol):
    """scipy's DOP853 error estimate of a step from the stages ``K`` (13 x n, the last ``f(ynew)``)."""
    n = y.size
    e5n = 0.0
    e3n = 0.0
    for i in range(n):
        sc = atol + max(abs(y[i]), abs(ynew[i])) * rtol
        e5 = 0.0
        e3 = 0.0
        for j in range(N_STAGES + 1):
            e5 += E5[j] * K[j, i]
            e3 += E3[j] * K[j, i]
        e5n += (e5 / sc) ** 2
        e3n += (e3 / sc) ** 2
    if e5n == 0.0 and e3n == 0.0:
        return 0.0
    return h_abs * e5n / math.sqrt((e5n + 0.01 * e3n) * n)


@njit(cache=True)
def step_factor(err, rejected):
    """Factor scipy applies to the step size after a step with error ``err``.

    An accepted step (``err < 1``) may grow the step by up to 10, or not at all right after a
    rejection; a rejected one shrinks it by at least 5 (by 5 on a NaN error).
    """
    if err < 1.0:
        factor = 10.0 if err == 0.0 else min(10.0, 0.9 * err ** (-1.0 / 8.0))
        return min(1.0, factor) if rejected else factor
    if err != err:
        return 0.2
    return max(0.2, 0.9 * err ** (-1.0 / 8.0))


@njit(cache=True)
def initial_step_trial(y0, f0, interval, rtol, atol):
    """First half of scipy's ``select_initial_step``: the trial step ``h0`` and ``(d1, scale)``.

    The caller evaluates the right-hand side at ``y0 + h0 direction f0`` and finishes with
    :func:`initial_step`.
    """
    scale = atol + np.abs(y0) * rtol
    d0 = rms(y0 / scale)
    d1 = rms(f0 / scale)
    if d0 < 1e-5 or d1 < 1e-5:
        h0 = 1e-6
    else:
        h0 = 0.01 * d0 / d1
    return min(h0, interval), d1, scale


@njit(cache=True)
def initial_step(h0, d1, scale, f0, f1, interval):
    """Second half of scipy's ``select_initial_step`` for an 8th-order method."""
    d2 = rms((f1 - f0) / scale) / h0
    if d1 <= 1e-15 and d2 <= 1e-15:
        h1 = max(1e-6, h0 * 1e-3)
    else:
        h1 = (0.01 / max(d1, d2)) ** (1.0 / 8.0)
    return min(100.0 * h0, h1, interval)


@njit(cache=True)
def dense_coefficients(Kx, h, y_old, y_new, f_new, F):
    """Write the interpolant's coefficients (7 x n) for a step with all 16 stages ``Kx`` into ``F``."""
    for i in range(y_old.size):
        dy = y_new[i] - y_old[i]
        F[0, i] = dy
        F[1, i] = h * Kx[0, i] - dy
        F[2, i] = 2.0 * dy - h * (f_new[i] + Kx[0, i])
        for r in range(4):
            acc = 0.0
            for j in range(16):
                acc += D[r, j] * Kx[j, i]
            F[3 + r, i] = h * acc


@njit(cache=True)
def interpolate_into(t_old, h, y_old, F, t, out):
    """DOP853's dense output on one step (scipy's ``Dop853DenseOutput``) at ``t``, into ``out``.

    Scalar loops into a buffer: for each component the same operations in the same order as
    scipy's array form, so the same bits.
    """
    x = (t - t_old) / h
    npow = F.shape[0]
    n = y_old.size
    for k in range(n):
        out[k] = 0.0
    for i in range(npow - 1, -1, -1):
        w = x if (npow - 1 - i) % 2 == 0 else 1.0 - x
        for k in range(n):
            out[k] = (out[k] + F[i, k]) * w
    for k in range(n):
        out[k] += y_old[k]
    return out
