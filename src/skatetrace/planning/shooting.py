"""The exact finish's multiple shooting compiled: a segment's intervals, a residual's segments, a Jacobian's columns.

:func:`skatetrace.planning.finish.finish_section` integrates every shooting segment hundreds of
times per section (the residual, a forward difference per unknown, the backtracking). Each
segment is a few collocation intervals, each one call of the manoeuvre integrator's compiled
DOP853 (:func:`skatetrace.dynamics.integrator.integrate_legs`); driven from Python, the calls
cost more around the integration than in it. Here the loops run compiled and call the
integrator's core directly, with :func:`~skatetrace.dynamics.integrator.integrate_legs`'
arguments and semantics (no events, no dense output, its evaluation budget):

- :func:`legs_from`: the legs from an arc length on (the piece there, its curvature polynomial
  re-expanded about that arc length as :func:`skatetrace.figures.geometry.shifted_polynomial`
  does, then the pieces after it), also used by the finish's dense (Python) pass;
- :func:`segment_end`: one segment, interval by interval, each from its own start (local time
  and arc length 0), the arc length accumulated; a failure (a non-positive interval, the
  integrator's failure, a non-finite state) is ``False``;
- :func:`segment_ends`: the segments a residual needs;
- :func:`jacobian_columns`: every forward-difference column of the Jacobian at once, each
  re-integrating only the segments its unknown moves.

Every number is computed by the same operations in the same order as the Python loop they
replace, so that the iterations are the same.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ..dynamics.integrator import MAX_NFEV
from ..dynamics.integrator import _run as _integrate

__all__ = ["legs_from", "segment_end", "segment_ends", "jacobian_columns"]

#: Relative step of the forward differences (at least this absolute step). At 1e-7 the differences
#: were too far from the residual's derivative: they stalled the Gauss-Newton iterations of 12 of the 14
#: finishes of the circle eight at 1.85 m between 1e-8 and 5e-10 after 30 iterations, steps of 1e-6
#: and 1e-5 stalled them higher, and at 1e-9 all 14 finished within 2 to 5 iterations. Over 135
#: figures (school figures at 1.55 to 1.9 m, the examples, the corpus at 6 m) the finishes that
#: failed went from 113 of 473 to 36 of 402 (fewer failures, fewer meshes refined and programs again).
#: Central differences did worse at every step from 1e-9 to 1e-5 on octicons-git-branch-16's stalled
#: finishes, so the residual is not smooth on those scales (likely as the integrations' steps and the
#: joins' crossings move with the unknowns); a one-sided step this small sees the slope where the iterate is.
DIFF_STEP = 1e-9
#: Binomial coefficients ``C(j, k)`` of the cubic's re-expansion, row ``j``.
_BINOMIAL = np.array([[1.0, 0.0, 0.0, 0.0], [1.0, 1.0, 0.0, 0.0], [1.0, 2.0, 1.0, 0.0], [1.0, 3.0, 3.0, 1.0]])


@njit(cache=True)
def _shifted(c, origin, out):
    """Coefficients of the cubic ``q(x) = p(origin + x)`` into ``out``: ``shifted_polynomial(c, origin, 1.0)``."""
    for k in range(4):
        acc = 0.0
        for j in range(k, 4):
            acc += _BINOMIAL[j, k] * c[j] * origin ** float(j - k)
        out[k] = acc


@njit(cache=True)
def legs_from(ends, coef, s_cur):
    """Legs from arc length ``s_cur`` on, with lengths measured from there.

    Parameters
    ----------
    ends : ndarray, shape (n,)
        Cumulative arc length at the end of each piece (the same origin as ``s_cur``).
    coef : ndarray, shape (n, 4)
        Curvature coefficients ``c0..c3`` of each piece, in the distance from its start.
    s_cur : float
        Where the legs start.

    Returns
    -------
    j : int
        The piece at ``s_cur`` (the last one beyond the end).
    kappas : ndarray, shape (n - j, 4)
        The legs' coefficients: piece ``j``'s re-expanded about ``s_cur``, then the later pieces'.
    switches : ndarray, shape (n - j,)
        Where each leg ends, from ``s_cur``; ``inf`` for the last.
    """
    n = ends.size
    j = min(np.searchsorted(ends, s_cur, side="right"), n - 1)
    start_j = ends[j - 1] if j > 0 else 0.0
    origin = s_cur - start_j
    if 0.0 > origin:  # Python's max(origin, 0.0), -0.0 and NaN included
        origin = 0.0
    kappas = np.empty((n - j, 4))
    switches = np.empty(n - j)
    _shifted(coef[j], origin, kappas[0])
    switches[0] = ends[j] - s_cur
    for i in range(1, n - j):
        for c in range(4):
            kappas[i, c] = coef[j + i, c]
        switches[i] = ends[j + i] - s_cur
    switches[n - j - 1] = np.inf
    return j, kappas, switches


@njit(cache=True)
def segment_end(M, m, I, y_start, sig, times, uu, i0, i1, ends, coef, rtol, atol, out):
    """Integrate one shooting segment, intervals ``i0..i1`` of the time nodes, into ``out``.

    Parameters
    ----------
    M, m, I : float
        The sleigh's parameters.
    y_start : ndarray, shape (5,)
        The segment's initial state ``(p1, p2, a, b, s)``, ``s`` from the section's start.
    sig : float
        The scale of the time nodes.
    times, uu : ndarray, shape (N + 1,)
        The time nodes (unscaled) and the free control ``u`` there (linear in between).
    i0, i1 : int
        The segment's first and last node.
    ends, coef : ndarray
        The section's pieces, as :func:`legs_from` takes them (``ends`` from the section's start).
    rtol, atol : float
        The integrator's tolerances.
    out : ndarray, shape (5,)
        Written with the state at node ``i1`` (``s`` from the section's start), on success.

    Returns
    -------
    bool
        False for a non-positive interval, a failed integration or a non-finite state.
    """
    s_start = y_start[4]
    y = y_start.copy()
    ends_k = ends - s_start
    s_abs = 0.0
    for k in range(i0, i1):
        h = sig * times[k + 1] - sig * times[k]
        if not h > 0.0:
            return False
        alpha = (uu[k + 1] - uu[k]) / h
        _j, kappas, switches = legs_from(ends_k, coef, s_abs)
        y[4] = 0.0  # each interval from its own start
        # no events, no dense output, the usual budget: made at run time, not written as literals,
        # so that this is the trace's own compiled integrator, loaded from numba's cache (literal
        # arguments made numba compile a second one into the finish: 2 of its 6 s on a first plan)
        off = not rtol >= 0.0  # False
        res = _integrate(M, m, I, y, kappas, switches, alpha, uu[k], h, rtol, atol, off, 0.0, MAX_NFEV + 0 * i0, off)
        if res[0] < 0:
            return False
        yf = res[3]
        for c in range(5):
            if not np.isfinite(yf[c]):
                return False
            y[c] = yf[c]
        s_abs += y[4]
        y[4] = s_abs
    for c in range(5):
        out[c] = y[c]
    out[4] += s_start
    return True


@njit(cache=True)
def segment_ends(M, m, I, ys, sig, times, uu, bounds, ends, coef, rtol, atol, todo, E):
    """The segments ``k`` with ``todo[k]``, from ``ys[k]`` over nodes ``bounds[k]..bounds[k + 1]``, into ``E[k]``.

    In order, stopping at the first failure. Returns ``(ok, count)``: whether every one
    succeeded and how many were integrated (the failed one included). The other arguments are
    :func:`segment_end`'s.
    """
    count = 0
    for k in range(bounds.size - 1):
        if todo[k]:
            count += 1
            if not segment_end(M, m, I, ys[k], sig, times, uu, bounds[k], bounds[k + 1], ends, coef, rtol, atol, E[k]):
                return False, count
    return True, count


@njit(cache=True)
def jacobian_columns(M, m, I, z, uu, ys, yscale, times, bounds, ends, coef, rtol, atol, E, r, J, last, moved, steps):
    """Forward-difference columns of the finish's residual: all of ``J`` but its last six rows (the end conditions).

    Unknown ``i`` of ``z`` (the time scale, ``u`` at nodes ``1..N``, then the inner segment
    starts scaled by ``yscale``) is stepped by ``DIFF_STEP * max(1, |z[i]|)`` and only the
    segments it moves are integrated again (all for the time scale; those meeting the node for
    ``u``; the segment for its start). The continuity rows ``(E[k] - ys[k + 1]) / yscale`` of
    ``J`` are written; for the end conditions (computed in Python), ``moved[i]`` says whether the
    last segment moved, ``last[i]`` its end state and ``u`` there.

    Parameters
    ----------
    z : ndarray
        The unknowns; ``uu`` (N + 1,) and ``ys`` (K, 5) are their control and segment starts
        (restored on return).
    E : ndarray, shape (K, 5)
        The segments' ends at ``z``; ``r`` the residual there.
    J, last, moved, steps : ndarray
        Written: ``J`` (r.size, z.size) but its last six rows, ``last`` (z.size, 6), ``moved``
        (z.size,) and the steps (z.size,).

    Returns
    -------
    (bool, int)
        Whether every integration succeeded (stopping at the first column with a failure) and
        how many segments were integrated.
    """
    N = times.size - 1
    K = bounds.size - 1
    todo = np.empty(K, dtype=np.bool_)
    Ep = np.empty_like(E)
    count = 0
    for i in range(z.size):
        a = abs(z[i])
        h = DIFF_STEP * (a if a > 1.0 else 1.0)
        steps[i] = h
        zi = z[i] + h
        sig = z[0]
        seg, comp = -1, -1
        if i == 0:
            sig = zi
        elif i <= N:
            uu[i] = zi
        else:
            seg, comp = (i - N - 1) // 5 + 1, (i - N - 1) % 5
            ys[seg, comp] = zi * yscale[comp]
        for k in range(K):
            todo[k] = i == 0 or (i <= N and bounds[k] <= i <= bounds[k + 1]) or k == seg
            for c in range(5):
                Ep[k, c] = E[k, c]
        ok, n = segment_ends(M, m, I, ys, sig, times, uu, bounds, ends, coef, rtol, atol, todo, Ep)
        count += n
        if ok:
            for k in range(K - 1):
                for c in range(5):
                    J[5 * k + c, i] = ((Ep[k, c] - ys[k + 1, c]) / yscale[c] - r[5 * k + c]) / h
            moved[i] = todo[K - 1]
            for c in range(5):
                last[i, c] = Ep[K - 1, c]
            last[i, 5] = uu[N]
        if 1 <= i <= N:
            uu[i] = z[i]
        elif seg > 0:
            ys[seg, comp] = z[i] * yscale[comp]
        if not ok:
            return False, count
    return True, count
