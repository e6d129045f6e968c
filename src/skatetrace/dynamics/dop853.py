"""scipy's DOP853 compiled: its arithmetic, and one step loop for any right-hand side that registers itself.

Two compiled integrators use it: :mod:`skatetrace.dynamics.integrator` (the sleigh held on a curve, for the
manoeuvre solves) and the replays (:mod:`skatetrace.dynamics.replayer`, the full five equations under
sampled controls, and :mod:`skatetrace.feedback.law_replay`, the sleigh under the tracking law), for
verification. What they share here is the Butcher tableau and everything scipy's
:class:`scipy.integrate.DOP853` computes from the stages: the error norm, the step-size factor, the
initial step, and the 7th-order dense output. The manoeuvre integrator keeps its own stage loop (it
stops at events); the replays share :func:`integrate`, the whole loop to the end of a smooth stretch
with output at requested times.

:func:`integrate` calls :func:`rhs`, a name with no body of its own: each system gives it one for its
own data, a named tuple (:func:`register`, through numba's ``overload``). A compiled function cannot be
passed as an argument instead: numba then cannot cache the caller (the function object differs in
every process), and every run would compile the replay anew.
"""

from __future__ import annotations

import importlib.util
import math
from pathlib import Path

import numpy as np
from numba import njit, types
from numba.extending import overload

from .numba_cache import guard_saves

__all__ = ["N_STAGES", "A", "B", "C", "A_EXTRA", "C_EXTRA", "POWER", "REACHED", "EXHAUSTED", "SMALL_STEP",
           "NONFINITE", "combine", "integrate", "register", "rhs"]

guard_saves()  # this module's compiled functions share numba's cache with other processes

#: How :func:`integrate` ended: at the end of the stretch, or not (budget, step size, non-finite state).
REACHED, EXHAUSTED, SMALL_STEP, NONFINITE = 0, -1, -2, -3


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


def component(tol, i):
    """``tol[i]`` of a tolerance per component, or ``tol`` itself where one number serves all.

    Compiled code takes the overload below, chosen by ``tol``'s type; this body serves the plain
    Python run (``NUMBA_DISABLE_JIT=1``).
    """
    return tol[i] if np.ndim(tol) else tol


@overload(component)
def _component(tol, i):
    if isinstance(tol, types.Array):
        return lambda tol, i: tol[i]
    return lambda tol, i: tol


@njit(cache=True)
def error_norm(K, y, ynew, h_abs, rtol, atol):
    """scipy's DOP853 error estimate of a step from the stages ``K`` (13 x n, the last ``f(ynew)``).

    ``atol`` is one number, or one per component (as scipy accepts).
    """
    n = y.size
    e5n = 0.0
    e3n = 0.0
    for i in range(n):
        sc = component(atol, i) + max(abs(y[i]), abs(ynew[i])) * rtol
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
    """Second half of scipy's ``select_initial_step`` for an 8th-order method.

    A trial step of zero (a derivative beyond the floating-point range of its tolerance) gives
    ``d2 = inf`` as numpy's division does for scipy, and a first step of zero: the loop then starts
    from its smallest step. Compiled, the division would raise ``ZeroDivisionError`` instead.
    """
    d2 = rms((f1 - f0) / scale) / h0 if h0 != 0.0 else math.inf
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


@njit(cache=True)
def combine(coef, K, count, y, h, out):
    """``out = y + h * sum(coef[q] * K[q] for q < count)``: a stage's input, or the step's end.

    Component by component, the sum in the order of the stages (scipy's ``K[:s].T @ a[:s]``).
    """
    for i in range(y.size):
        acc = 0.0
        for q in range(count):
            acc += coef[q] * K[q, i]
        out[i] = y[i] + acc * h


def rhs(data, t, y, out):
    """The right-hand side :func:`integrate` calls: ``dy/dt`` at ``(t, y)`` into ``out``, for the system ``data``.

    Each system registers its own (:func:`register`) for its own type of ``data``, a named tuple
    of its numbers, arrays and scratch space; numba picks it by that type when it compiles
    :func:`integrate` for the system. The open-loop replay (:mod:`skatetrace.dynamics.replayer`)
    is one. Run as plain Python (``NUMBA_DISABLE_JIT=1``), this body calls the one registered on
    ``data``'s class.
    """
    try:
        own = type(data).__dict__["_dop853_rhs"]
    except KeyError:
        raise TypeError(f"no right-hand side is registered for {type(data).__name__} (see register)") from None
    return own(data, t, y, out)


def register(system: type, fn) -> None:
    """Make the compiled ``fn(data, t, y, out)`` :func:`rhs` for ``data`` of the named tuple class ``system``.

    Call it once, at the import of the module that defines both. Compile ``fn`` with
    ``inline="always"`` and let it only read the tuple's fields and pass them on to compiled
    functions (numba's inliner warns on loops): :func:`integrate` then reads the fields where it
    stands. A call that passes the whole tuple instead made an evaluation of the open loop 30-40 %
    slower (measured: 80 ns against 105-117 ns).
    """
    system._dop853_rhs = staticmethod(fn)  # for the plain Python run (see rhs)

    @overload(rhs, inline="always")
    def _rhs_of_system(data, t, y, out):
        if getattr(data, "instance_class", None) is system:
            return lambda data, t, y, out: fn(data, t, y, out)
        return None


@njit
def integrate(data, y0, t0, t_end, t_out, rtol, atol, max_nfev):
    """scipy's DOP853 from ``(t0, y0)`` to ``t_end`` on :func:`rhs` of ``data``; states at the sorted ``t_out``.

    The same steps as ``solve_ivp(method="DOP853")``: initial step, error norm, step-size control,
    and its 7th-order dense output at the requested times (a time at or before ``t0`` gets ``y0``).

    Parameters
    ----------
    data : named tuple
        The system: whatever its :func:`rhs` reads.
    y0 : ndarray, shape (n,)
    t0, t_end : float
        ``t0 < t_end``.
    t_out : ndarray
        Non-decreasing times at which to report the state.
    rtol : float
    atol : float or ndarray, shape (n,)
        One absolute tolerance, or one per component.
    max_nfev : int
        Budget of evaluations of the right-hand side; exceeding it ends the run with ``EXHAUSTED``.

    Returns
    -------
    status, t, y, out, nfev, nsteps
        ``status`` is :data:`REACHED` or how it failed, ``(t, y)`` where it got to, ``out`` the
        states ``(n, len(t_out))`` (NaN at the times not reached).

    Notes
    -----
    Compiled without numba's cache on purpose: it is compiled into each caller (each system's
    entry point, cached in its own module), so that a change to that system's right-hand side
    recompiles it; a cache of this loop's own would keep the old right-hand side.
    """
    n = y0.size
    nout = t_out.size
    out = np.full((n, nout), np.nan)
    t = t0
    y = y0.copy()
    j = 0
    while j < nout and t_out[j] <= t:
        for r in range(n):
            out[r, j] = y[r]
        j += 1
    f = np.empty(n)
    f_new = np.empty(n)
    ynew = np.empty(n)
    ytmp = np.empty(n)
    Kx = np.empty((16, n))
    F = np.empty((POWER, n))
    rhs(data, t, y, f)
    h0, d1, scale = initial_step_trial(y, f, t_end - t, rtol, atol)
    rhs(data, t + h0, y + h0 * f, f_new)
    h_abs = initial_step(h0, d1, scale, f, f_new, t_end - t)
    nfev = 2
    nsteps = 0
    while t < t_end:
        min_step = 10.0 * abs(np.nextafter(t, np.inf) - t)
        h_abs = max(h_abs, min_step)
        rejected = False
        while True:
            if h_abs < min_step:
                return SMALL_STEP, t, y, out, nfev, nsteps
            t_new = min(t + h_abs, t_end)
            h = t_new - t
            h_abs = h
            for i in range(n):
                Kx[0, i] = f[i]
            for s in range(1, N_STAGES):
                combine(A[s], Kx, s, y, h, ytmp)
                rhs(data, t + C[s] * h, ytmp, Kx[s])
            combine(B, Kx, N_STAGES, y, h, ynew)
            rhs(data, t_new, ynew, f_new)
            for i in range(n):
                Kx[N_STAGES, i] = f_new[i]
            nfev += N_STAGES
            if nfev > max_nfev:
                return EXHAUSTED, t, y, out, nfev, nsteps
            err = error_norm(Kx[:N_STAGES + 1], y, ynew, h_abs, rtol, atol)
            h_abs *= step_factor(err, rejected)
            if err < 1.0:
                break
            rejected = True
        total = 0.0
        for i in range(n):
            total += ynew[i]
        if not math.isfinite(total):
            return NONFINITE, t, y, out, nfev, nsteps
        nsteps += 1
        if j < nout and t_out[j] <= t_new:
            # the three extra stages of the 7th-order interpolant, only on steps with output
            for s in range(N_STAGES + 1, 16):
                combine(A_EXTRA[s - N_STAGES - 1], Kx, s, y, h, ytmp)
                rhs(data, t + C_EXTRA[s - N_STAGES - 1] * h, ytmp, Kx[s])
            nfev += 3
            dense_coefficients(Kx, h, y, ynew, f_new, F)
            while j < nout and t_out[j] <= t_new:
                if t_out[j] == t_new:
                    for r in range(n):
                        out[r, j] = ynew[r]
                else:
                    interpolate_into(t, h, y, F, t_out[j], out[:, j])
                j += 1
        t = t_new
        for i in range(n):
            y[i] = ynew[i]
            f[i] = f_new[i]
    return REACHED, t, y, out, nfev, nsteps
