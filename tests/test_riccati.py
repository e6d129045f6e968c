"""The tracking law's Riccati equation, compiled (skatetrace.feedback.riccati), against closed forms and scipy."""

import numpy as np
from scipy.integrate import solve_ivp

from skatetrace.feedback.riccati import solve_backwards


def _reference_solution(t, A, B, Rinv, times):
    """The same equation by scipy's Radau at tight tolerances, backwards in t, with A and B linear between
    the rows (right of a repeated row)."""
    last = t.size - 2

    def f(tt, pv):
        j = min(max(int(np.searchsorted(t, tt, side="right")) - 1, 0), last)
        h = t[j + 1] - t[j]
        w = (tt - t[j]) / h if h > 0 else 0.0
        Aj, Bj = (1 - w) * A[j] + w * A[j + 1], (1 - w) * B[j] + w * B[j + 1]
        P = pv.reshape(7, 7)
        PB = P @ Bj
        return -(Aj.T @ P + P @ Aj - (PB * Rinv) @ PB.T + np.eye(7)).ravel()

    sol = solve_ivp(f, (t[-1], t[0]), np.eye(7).ravel(), method="Radau", rtol=1e-11, atol=1e-13,
                    t_eval=times[::-1])
    assert sol.success
    return sol.y[:, ::-1]


def test_constant_coefficients_without_control_match_the_closed_form():
    # B = 0: dP/ds = 2 a P + I from P = I, so P = ((1 + 2a) exp(2 a s) - 1) / (2 a) I
    a, T = -0.7, 3.0
    t = np.array([0.0, 1.0, 2.0, T])
    A = np.repeat((a * np.eye(7))[None], t.size, axis=0)
    B = np.zeros((t.size, 7, 2))
    times = np.linspace(0.0, T, 31)
    P = solve_backwards(t, A, B, np.ones(2), times)
    s = T - times
    exact = ((1 + 2 * a) * np.exp(2 * a * s) - 1) / (2 * a)
    # DOP853 at rtol 1e-6 (design's): a global error of a few times that
    assert P.shape == (49, times.size)
    for r in range(7):
        for c in range(7):
            want = exact if r == c else np.zeros_like(exact)
            np.testing.assert_allclose(P[7 * r + c], want, rtol=1e-5, atol=1e-9)


def test_scalar_channel_reaches_the_algebraic_riccati_solution():
    # one controlled integrator, A = 0, B = e0, R^-1 = r: p' = 1 - r p^2 from 1 tends to 1 / sqrt(r) as
    # s grows, p(s) = tanh(sqrt(r) s + atanh(sqrt(r))) / sqrt(r) for r < 1; the other channels grow as s + 1
    r, T = 0.25, 20.0
    t = np.array([0.0, T])
    A = np.zeros((2, 7, 7))
    B = np.zeros((2, 7, 2))
    B[:, 0, 0] = 1.0
    times = np.array([0.0, 10.0, 19.0, T])
    P = solve_backwards(t, A, B, np.array([r, 0.0]), times)
    q = np.sqrt(r)
    np.testing.assert_allclose(P[0], np.tanh(q * (T - times) + np.arctanh(q)) / q, rtol=1e-5)
    np.testing.assert_allclose(P[0, 0], 1 / q, rtol=1e-5)  # ten time constants: at the limit
    np.testing.assert_allclose(P[8], T - times + 1, rtol=1e-9)


def test_varying_coefficients_with_a_jump_match_scipy():
    rng = np.random.default_rng(7)
    t = np.array([0.0, 0.4, 1.1, 1.1, 1.7, 2.5])  # a repeated row: the rates jump there
    A = rng.normal(scale=0.8, size=(t.size, 7, 7))
    B = rng.normal(size=(t.size, 7, 2))
    Rinv = np.array([0.5, 2.0])
    times = np.unique(np.concatenate([t, np.linspace(0.0, 2.5, 23)]))
    P = solve_backwards(t, A, B, Rinv, times)
    ref = _reference_solution(t, A, B, Rinv, times)
    assert np.max(np.abs(P - ref)) <= 1e-5 * np.max(np.abs(ref))
    # P stays symmetric (the equation keeps it so; the integration does to its tolerance)
    Ps = P.T.reshape(-1, 7, 7)
    assert np.max(np.abs(Ps - np.transpose(Ps, (0, 2, 1)))) <= 1e-6 * np.max(np.abs(Ps))


def test_no_duration_is_the_end_condition_and_failures_are_none():
    t = np.array([1.0, 1.0])
    A, B = np.zeros((2, 7, 7)), np.zeros((2, 7, 2))
    P = solve_backwards(t, A, B, np.ones(2), np.array([1.0]))
    np.testing.assert_array_equal(P[:, 0], np.eye(7).ravel())
    t = np.array([0.0, 5.0])
    assert solve_backwards(t, A, B, np.ones(2), np.array([0.0, 5.0]), max_nfev=1) is None  # out of budget
    # a solution that blows up: P' = 2 a P with a = 400 over 5 time units overflows
    huge = np.repeat((400.0 * np.eye(7))[None], 2, axis=0)
    assert solve_backwards(t, huge, B, np.ones(2), np.array([0.0, 5.0])) is None
