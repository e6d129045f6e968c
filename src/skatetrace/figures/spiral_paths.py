"""Positions along a spiral, compiled: the quadrature behind :func:`~skatetrace.figures.geometry.travel`.

A :class:`~skatetrace.figures.geometry.Spiral`'s heading is a quartic of arc length and its
position the integral of the heading's cosine and sine. That integral is taken by ten-point
Gauss-Legendre quadrature on ``n`` equal cells of the spiral (the heading turns by at most 0.2 rad
over one, so the rule is accurate to rounding): :func:`cell_nodes` integrates the cells once, and
:func:`positions` then reaches any arc length from the nearest cell boundary (half a cell at
most). :func:`foot_points` runs Newton's method on the foot points of many points at once, the
distance search of :func:`~skatetrace.figures.geometry.distance_to_segment`.

In numpy, each call paid some 50 us of array set-up whatever its size; the exact mode lays out,
samples and measures hundreds of spirals a figure, many times each (a 596-spiral figure made
10,000 such calls). Compiled by numba with ``cache=True``, like the integrators
(:mod:`skatetrace.cli.compiled` names it "the spirals' geometry").
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..dynamics.numba_cache import guard_saves

__all__ = ["cell_nodes", "foot_points", "positions"]

guard_saves()  # this module's compiled functions share numba's cache with other processes

# The quadrature rule, frozen into the compiled code as constants.
_NODES, _WEIGHTS = np.polynomial.legendre.leggauss(10)


@njit(cache=True, inline="always")
def _heading_change(c, s):
    return s * (c[0] + s * (c[1] / 2.0 + s * (c[2] / 3.0 + s * c[3] / 4.0)))


@njit(cache=True, inline="always")
def _offset(c, heading, a, b):
    """Displacement along the spiral from arc length ``a`` to ``b`` (within a cell of each other)."""
    mid, half = 0.5 * (a + b), 0.5 * (b - a)
    dx = dy = 0.0
    for k in range(_NODES.size):
        th = heading + _heading_change(c, mid + half * _NODES[k])
        dx += _WEIGHTS[k] * math.cos(th)
        dy += _WEIGHTS[k] * math.sin(th)
    return half * dx, half * dy


@njit(cache=True, inline="always")
def _boundary(length, n, j):
    """Arc length of cell boundary ``j`` of ``n`` equal cells (the last one exactly ``length``)."""
    return length if j == n else j * (length / n)


@njit(cache=True)
def cell_nodes(c, length, n, x0, y0, heading):
    """Positions ``(x, y)`` of the ``n + 1`` cell boundaries of a spiral laid out from ``(x0, y0, heading)``.

    Parameters
    ----------
    c : ndarray, shape (4,)
        Curvature coefficients ``(c0, c1, c2, c3)`` in arc length.
    length : float
        The spiral's length.
    n : int
        Number of equal cells (at least 1).
    x0, y0, heading : float
        The pose at the spiral's start.
    """
    node_x, node_y = np.empty(n + 1), np.empty(n + 1)
    node_x[0], node_y[0] = x0, y0
    sx = sy = 0.0
    for j in range(n):
        dx, dy = _offset(c, heading, _boundary(length, n, j), _boundary(length, n, j + 1))
        sx += dx
        sy += dy
        node_x[j + 1], node_y[j + 1] = x0 + sx, y0 + sy
    return node_x, node_y


@njit(cache=True, inline="always")
def _at(c, length, n, heading, node_x, node_y, s):
    j = min(max(int(np.rint(s / length * n)), 0), n) if length > 0.0 else 0
    dx, dy = _offset(c, heading, _boundary(length, n, j), s)
    return node_x[j] + dx, node_y[j] + dy, heading + _heading_change(c, s)


@njit(cache=True)
def positions(c, length, n, heading, node_x, node_y, s):
    """Pose ``(x, y, heading)`` at each arc length of ``s`` (1-D) on the spiral of :func:`cell_nodes`."""
    x, y, th = np.empty(s.size), np.empty(s.size), np.empty(s.size)
    for i in range(s.size):
        x[i], y[i], th[i] = _at(c, length, n, heading, node_x, node_y, s[i])
    return x, y, th


@njit(cache=True)
def foot_points(c, length, n, heading, node_x, node_y, px, py, t, max_step, iterations):
    """Arc lengths of the foot points of ``(px, py)`` on the spiral, by Newton's method from ``t``.

    Newton's method on half the squared distance, its step held within ``max_step`` (a spacing of
    the samples that ``t`` was picked from, so that it stays in the basin of their nearest) and to
    the spiral; a step where the distance's second derivative is below 0.1 is a gradient step.
    """
    out = t.copy()
    for i in range(out.size):
        u = out[i]
        for _ in range(iterations):
            fx, fy, th = _at(c, length, n, heading, node_x, node_y, u)
            dx, dy = fx - px[i], fy - py[i]
            cs, sn = math.cos(th), math.sin(th)
            g = dx * cs + dy * sn  # derivative of half the squared distance
            dg = 1.0 + (c[0] + u * (c[1] + u * (c[2] + u * c[3]))) * (-dx * sn + dy * cs)
            step = g / dg if dg > 0.1 else g
            u = min(max(u - min(max(step, -max_step), max_step), 0.0), length)
        out[i] = u
    return out
