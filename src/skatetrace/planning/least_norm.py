"""The least-norm step of the exact finish's Gauss-Newton: sparse, through the augmented system.

The finish's Jacobian (:func:`~skatetrace.planning.finish.finish_section`) is wide, some 550 x 660
on a long section, and sparse: each shooting segment's continuity depends on its own controls and
start state, and every row on the one scale of the times, so 1 to 3 % of it is nonzero. The
least-norm solution of ``J dz = -r`` solves the augmented system ::

    [ gamma I   J^T ] [ dz ]   [  0 ]
    [   J        0  ] [ -w ] = [ -r ]          (dz = J^T w / gamma)

whose sparse LU (SuperLU, :func:`scipy.sparse.linalg.splu`) takes a fifth of the time of the
dense complete orthogonal factorisation (LAPACK's gelsy) on those shapes. The rows are scaled to
unit norm first (the least-norm solution does not change) and ``gamma`` is small against them:
with ``gamma`` from 1e-4 to 1e-8 the step agreed with gelsy's to 1e-7 of its norm on the circle
eight's 1.85 m finish (Jacobians of condition 1e10), as gelsy's and numpy's SVD-based least norm
agree with each other; the residual ``J dz + r`` was 1e-16 to 1e-10 of ``r`` (rows scaled), where
iterative refinement did not lower it. Where the factorisation fails or the residual is above 1e-6
of ``r`` (a Jacobian of deficient rank, NaN entries), the step is gelsy's, as before.

A step that differs from gelsy's by round-off moves the finished section within what the finish's
tolerance allows: the same end conditions to 1e-10, controls that differ in digits the tolerance
does not fix (and replays that stray by other amounts within theirs).
"""

from __future__ import annotations

import numpy as np
import scipy.linalg
import scipy.sparse
import scipy.sparse.linalg

__all__ = ["least_norm_step"]

#: The augmented system's ``gamma`` against rows of unit norm (see the module's docstring).
_GAMMA = 1e-6
#: The largest residual ``|J dz + r| / |r|`` (the rows scaled) a sparse step is kept with; else gelsy's is
#: taken. The circle eight's steps left 1e-16 to 1e-10 (gelsy's 1e-15). An inexact Newton step that solves
#: its linear system to 1e-6 of ``r`` changes the next residual by that fraction of this one, far below
#: the contraction of the finish's iterations (1e-2 to 1e-5 an iteration in the circle eight's).
_RESIDUAL = 1e-6
#: Below this many rows gelsy's dense factorisation is the quicker: on blocks of the circle eight's
#: Jacobians, 0.1 against 0.5 ms at 60 rows, 0.6 against 0.7 at 100, 1.7 against 1.3 at 150.
_SPARSE_ROWS = 120


def least_norm_step(J: np.ndarray, r: np.ndarray) -> np.ndarray:
    """The least-norm ``dz`` with ``J dz = -r`` for a wide ``J`` (the least-squares one where none solves it).

    Sparse through the augmented system where ``J`` has at least ``_SPARSE_ROWS`` rows and that
    solves it to ``_RESIDUAL``; otherwise LAPACK's gelsy (a complete orthogonal factorisation).
    """
    J = np.asarray(J, dtype=float)
    r = np.asarray(r, dtype=float)
    rows, cols = J.shape
    if rows >= _SPARSE_ROWS and rows < cols:
        dz = _augmented(J, r)
        if dz is not None:
            return dz
    return scipy.linalg.lstsq(J, -r, lapack_driver="gelsy", check_finite=False)[0]


def _augmented(J: np.ndarray, r: np.ndarray) -> np.ndarray | None:
    """The least-norm step by the sparse augmented system, or None where it does not solve ``J dz = -r``."""
    if not (np.all(np.isfinite(J)) and np.all(np.isfinite(r))):
        return None
    norms = np.linalg.norm(J, axis=1)
    if not np.all(norms > 0.0):
        return None
    cols = J.shape[1]
    scaled = scipy.sparse.csc_matrix(J / norms[:, None])
    K = scipy.sparse.bmat([[scipy.sparse.identity(cols, format="csc") * _GAMMA, scaled.T], [scaled, None]],
                          format="csc")
    b = -r / norms
    rhs = np.concatenate([np.zeros(cols), b])
    try:
        lu = scipy.sparse.linalg.splu(K)
    except RuntimeError:  # exactly singular: J's rank is deficient
        return None
    dz = lu.solve(rhs)[:cols]
    if not np.linalg.norm(scaled @ dz - b) <= _RESIDUAL * np.linalg.norm(b):
        return None
    return dz
