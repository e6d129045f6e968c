"""The tracking law's Riccati equation compiled: integrated backwards by the replays' DOP853 loop.

:func:`skatetrace.feedback.lqr.design` solves ``-dP/dt = A^T P + P A - P B R^-1 B^T P + Q`` backwards
over a section, ``A`` and ``B`` linear between the reference's rows. Verification designs a law for
every ill-conditioned section, and through ``solve_ivp`` (LSODA) and a right-hand side in numpy an
evaluation cost about 20 us: 0.12 to 0.26 s a section of the paragraph double three (5,000 to 14,000
evaluations), most of the closed loop's time. Here the same equation runs compiled:

- in the time left to the section's end, ``s = T - t``, so that it runs forwards:
  ``dP/ds = A^T P + P A - P B R^-1 B^T P + Q`` from ``P = Q`` at ``s = 0`` (the scaled coordinates of
  :func:`~skatetrace.feedback.lqr.design`, where ``Q`` is the identity);
- ``A`` and ``B`` at ``t`` linear between the rows, as before: the interval found by a short walk from
  the last one (:func:`skatetrace.dynamics.replayer.interval`, right of a repeated row);
- the step is scipy's DOP853 (:func:`skatetrace.dynamics.dop853.integrate`, the replays' loop), at
  the tolerances LSODA had. The gains differ from LSODA's by the tolerances (1e-5 of the largest
  gain on the paragraph double three's sections, as scipy's own DOP853 and RK45 differ from LSODA).
  On the trace the law's correction ``K (z - z_r)`` is of round-off, so the closed loops of the
  paragraph double three and the change double three moved by 1e-10 of their cusp-speed limits,
  both ways, with the same verdicts.

The equation is not stiff on these sections (``solve_ivp``'s RK45 took fewer evaluations than LSODA).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

from ..dynamics import dop853 as rk
from ..dynamics.replayer import interval

__all__ = ["solve_backwards"]


class _Riccati(NamedTuple):
    """What the right-hand side reads: the section's end ``T``, the rows ``t`` (k,), ``A`` (k, 7, 7) and
    ``B`` (k, 7, 2) in scaled coordinates, the diagonal of ``R^-1`` (2,), and its scratch: ``last``
    (the interval last used), ``Aj`` (7, 7) and ``PB`` (7, 2)."""

    T: float
    t: np.ndarray
    A: np.ndarray
    B: np.ndarray
    Rinv: np.ndarray
    last: np.ndarray
    Aj: np.ndarray
    PB: np.ndarray


@njit(cache=True)
def _derivative(T, t, A, B, Rinv, last, Aj, PB, s, y, out):
    """``dP/ds`` at ``s = T - t`` for ``P`` = ``y`` (49, row by row), into ``out``."""
    tt = T - s
    j = interval(t, tt, last[0])
    last[0] = j
    h = t[j + 1] - t[j]
    w = (tt - t[j]) / h if h > 0.0 else 0.0
    for r in range(7):
        for c in range(7):
            Aj[r, c] = (1.0 - w) * A[j, r, c] + w * A[j + 1, r, c]
        for q in range(2):
            acc = 0.0
            for c in range(7):
                acc += y[7 * r + c] * ((1.0 - w) * B[j, c, q] + w * B[j + 1, c, q])
            PB[r, q] = acc
    for r in range(7):
        for c in range(7):
            acc = 0.0
            for k in range(7):
                acc += Aj[k, r] * y[7 * k + c] + y[7 * r + k] * Aj[k, c]
            acc -= PB[r, 0] * Rinv[0] * PB[c, 0] + PB[r, 1] * Rinv[1] * PB[c, 1]
            if r == c:
                acc += 1.0
            out[7 * r + c] = acc


@njit(cache=True, inline="always")
def _rhs(data, s, y, out):
    _derivative(data.T, data.t, data.A, data.B, data.Rinv, data.last, data.Aj, data.PB, s, y, out)


rk.register(_Riccati, _rhs)


@njit(cache=True)
def _run(T, t, A, B, Rinv, s_end, s_out, rtol, atol, max_nfev):
    """Integrate from ``P = I`` at ``s = 0`` to ``s_end``; ``P`` at the sorted ``s_out``.

    Returns :func:`skatetrace.dynamics.dop853.integrate`'s ``(status, s, y, out, nfev, nsteps)``.
    """
    last = np.empty(1, dtype=np.int64)
    last[0] = t.size - 2
    data = _Riccati(T, t, A, B, Rinv, last, np.empty((7, 7)), np.empty((7, 2)))
    return rk.integrate(data, np.eye(7).ravel(), 0.0, s_end, s_out, rtol, atol, max_nfev)


def solve_backwards(t: np.ndarray, A: np.ndarray, B: np.ndarray, Rinv: np.ndarray, times: np.ndarray, *,
                    rtol: float = 1e-6, atol: float = 1e-9, max_nfev: int = 200_000) -> np.ndarray | None:
    """The Riccati solution ``P`` (scaled coordinates, ``Q = I``, ``P = I`` at the end) at ``times``.

    Parameters
    ----------
    t : ndarray, shape (k,)
        The reference's rows, non-decreasing (a repeated time is a jump of the rates), ``k >= 2``.
    A, B : ndarray, shapes (k, 7, 7) and (k, 7, 2)
        The linearisation at the rows, linear between them.
    Rinv : ndarray, shape (2,)
        The diagonal of ``R^-1``.
    times : ndarray
        Increasing times in ``[t[0], t[-1]]``.
    rtol, atol : float
        DOP853's tolerances.
    max_nfev : int
        Budget of evaluations; beyond it the solve fails.

    Returns
    -------
    ndarray, shape (49, len(times)), or None
        ``P`` row by row at each time, or None where the integration failed (its budget, or a
        solution that left the finite numbers).
    """
    t = np.ascontiguousarray(t, dtype=float)
    T = float(t[-1])
    s_out = np.ascontiguousarray(T - np.asarray(times, dtype=float)[::-1])
    s_end = T - float(t[0])
    if not s_end > 0.0:  # a section of no duration: P is Q throughout
        return np.repeat(np.eye(7).reshape(49, 1), len(times), axis=1)
    status, _, _, out, _, _ = _run(T, t, np.ascontiguousarray(A, dtype=float), np.ascontiguousarray(B, dtype=float),
                                   np.ascontiguousarray(Rinv, dtype=float), s_end, s_out, float(rtol), float(atol),
                                   int(max_nfev))
    if int(status) != rk.REACHED or not np.all(np.isfinite(out)):
        return None
    return out[:, ::-1]
