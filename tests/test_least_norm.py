"""The exact finish's least-norm step (skatetrace.planning.least_norm) against dense least norms."""

from pathlib import Path

import numpy as np
import pytest
import scipy.linalg
import scipy.sparse

from skatetrace.planning import least_norm
from skatetrace.planning.least_norm import least_norm_step


def _shooting_jacobian(segments: int, seed: int, near: float = 0.0, spread: float = 0.0):
    """A Jacobian shaped as the finish's: a dense first column (the time scale), then per segment 5 rows
    of continuity in its 3 controls, its start state's 5 columns and minus the next start state.

    The last block is 6 end conditions on the last segment. With ``near`` the last row is the
    sum of the two before it but for a change of that relative size: nearly dependent rows.
    ``spread`` scales the columns by ``10**U(-spread, spread)``, as the finish's differ.
    """
    rng = np.random.default_rng(seed)
    K = segments
    N = 3 * K
    cols = 1 + N + 5 * (K - 1)
    rows = 5 * (K - 1) + 6
    J = np.zeros((rows, cols))
    J[:, 0] = rng.normal(size=rows)
    for k in range(K):
        r0 = 5 * k
        nr = 5 if k < K - 1 else 6
        J[r0:r0 + nr, 1 + 3 * k:1 + 3 * k + 3] = rng.normal(size=(nr, 3))
        if k > 0:
            c0 = 1 + N + 5 * (k - 1)
            J[r0:r0 + nr, c0:c0 + 5] = rng.normal(size=(nr, 5))
        if k < K - 1:
            c1 = 1 + N + 5 * k
            J[r0:r0 + 5, c1:c1 + 5] = -np.eye(5)
    if near:
        J[-1] = (J[-2] + J[-3]) * (1.0 + near * rng.normal(size=cols))
    J *= 10.0 ** rng.uniform(-spread, spread, size=cols)
    return J, rng.normal(size=rows)


def _pinv_step(J, r):
    return -np.linalg.pinv(J, rcond=1e-15) @ r


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_the_sparse_step_is_the_least_norm_solution(seed):
    J, r = _shooting_jacobian(40, seed)  # 201 x 316
    assert J.shape[0] >= least_norm._SPARSE_ROWS
    dz = least_norm._augmented(J, r)
    assert dz is not None
    assert np.linalg.norm(J @ dz + r) <= 1e-12 * np.linalg.norm(r)
    ref = _pinv_step(J, r)
    assert np.linalg.norm(dz - ref) <= 1e-10 * np.linalg.norm(ref)
    assert np.array_equal(least_norm_step(J, r), dz)  # the sparse step is the one taken


def _gelsy_step(J, r):
    return scipy.linalg.lstsq(J, -r, lapack_driver="gelsy", check_finite=False)[0]


def _assert_sparse_step_is_gelsy_s(J, r, residual):
    """The sparse step is taken, solves ``J dz = -r`` to ``residual`` and is gelsy's to 1e-5 of its size."""
    dz = least_norm._augmented(J, r)
    assert dz is not None
    assert np.linalg.norm(J @ dz + r) <= residual * np.linalg.norm(r)
    ref = _gelsy_step(J, r)
    assert np.linalg.norm(dz - ref) <= 1e-5 * np.linalg.norm(ref)


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_an_ill_conditioned_step_is_gelsy_s_to_its_round_off(seed):
    """Two rows nearly dependent and columns of unlike scales: a condition number of 1e10 to 1e11, the finish's.

    The residuals are those of a moderate step, as in the finish. The steps agreed to 5e-7 of their
    size; with the augmented system's ``gamma`` at 0.1 they differed by 1e-2, or that step was refused.
    """
    J, _ = _shooting_jacobian(40, seed, near=1e-9, spread=1.0)
    assert np.linalg.cond(J) > 1e9
    r = -J @ np.random.default_rng(seed + 10).normal(size=J.shape[1])
    _assert_sparse_step_is_gelsy_s(J, r, residual=1e-9)


def test_the_circle_eight_s_jacobian_takes_the_sparse_step():
    """A Jacobian of the circle eight's exact finish at 1.85 m (551 x 656, 1.2 % nonzero, condition 1.2e10).

    Its step agreed with gelsy's to 1e-7 of its size; with ``gamma`` at 0.1 the sparse step was refused.
    """
    data = np.load(Path(__file__).parent / "data" / "finish-jacobian.npz")
    J = scipy.sparse.csr_matrix((data["data"], data["indices"], data["indptr"]), shape=tuple(data["shape"])).toarray()
    _assert_sparse_step_is_gelsy_s(J, data["r"], residual=1e-12)


def test_a_jacobian_of_deficient_rank_takes_gelsy_least_squares():
    J, r = _shooting_jacobian(40, 3)
    J[7] = J[3]  # two equal rows, unequal right-hand sides: no step solves both
    assert least_norm._augmented(J, r) is None
    dz = least_norm_step(J, r)
    assert np.array_equal(dz, _gelsy_step(J, r))


@pytest.mark.parametrize("spoil", ["nan", "zero row"])
def test_a_spoilt_jacobian_is_left_to_gelsy(spoil):
    J, r = _shooting_jacobian(40, 4)
    if spoil == "nan":
        J[-1, 0] = np.nan
    else:
        J[-1] = 0.0
    assert least_norm._augmented(J, r) is None


def test_a_small_jacobian_takes_gelsy():
    J, r = _shooting_jacobian(5, 5)  # 26 rows
    assert J.shape[0] < least_norm._SPARSE_ROWS
    dz = least_norm_step(J, r)
    assert np.array_equal(dz, _gelsy_step(J, r))
    assert np.linalg.norm(dz - _pinv_step(J, r)) <= 1e-10 * np.linalg.norm(dz)
