"""Sections of one shape up to a rigid motion and round-off, found so that each shape is traced once.

:func:`~skatetrace.tracing.sections.trace_figure` traces every distinct section once and lays its
controls out again wherever the same shape recurs. Copies of one shape drawn at different places
(the nine dots of Adwaita's ``view-app-grid`` icon, a row of identical letters) do not have the
same pieces to the last digit: adding a copy's offset and fitting it again changes the curvatures
and lengths by about 1e-11 of themselves. Keys rounded to a fixed number of digits put such copies
on both sides of a rounding step (5 of the 9 dots were traced at 14 decimals, 3 at 11 significant
digits), so shapes are compared within a tolerance instead: two sections are one shape when they
have the same pieces in the same order, every length agreeing to :data:`SHAPE_TOL` of itself and
every turning term ``c_j L^(j+1)`` (the angle each coefficient of the curvature turns the blade
through) to :data:`SHAPE_TOL`. Controls traced for one then lay the other out within about
``SHAPE_TOL`` times its length, a thousand times below the replay's tolerance (1e-6 of the figure's
size); each section is still replayed and measured against its own pieces.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..dynamics.model import SleighParams
from ..figures.figure import Section

__all__ = ["SHAPE_TOL", "ShapeIndex", "exact_key"]

#: Relative agreement of two sections' lengths and turning terms for them to be one shape.
SHAPE_TOL = 1e-9


def exact_key(params: SleighParams, section: Section, options: Any) -> tuple:
    """The key of ``section`` as it is: parameters, options, and every piece's coefficients and length."""
    return (params, options, tuple((tuple(float(c) for c in s.coefficients), float(s.length)) for s in section.segments))


def _terms(key: tuple) -> np.ndarray:
    """Per piece of a key: its turning terms ``c_j L^(j+1)`` and its length, shape ``(n, 5)``."""
    rows = np.array([[*coef, length] for coef, length in key[2]], dtype=float).reshape(-1, 5)
    L = rows[:, 4:5]
    rows[:, :4] *= L ** np.arange(1, 5)
    return rows


#: Width, in the logarithm of a section's length, of the buckets :class:`ShapeIndex` keeps its keys
#: in: far wider than :data:`SHAPE_TOL`, so that a key's shape is in its own bucket or a neighbour.
_BUCKET = 1e-6


def _bucket(terms: np.ndarray) -> int | None:
    """The bucket of a key (its terms, :func:`_terms`): its section's length, on a log scale (None: not positive)."""
    total = float(np.sum(terms[:, 4]))
    return math.floor(math.log(total) / _BUCKET) if math.isfinite(total) and total > 0.0 else None


class ShapeIndex:
    """The keys of sections already known, found again by shape (see the module docstring).

    Keys are kept by parameters, options and number of pieces, and within those by their
    section's length (:data:`_BUCKET`): a key is compared with the few of about its length, not
    with every key known (1000 distinct arcs: 30 -> 11 ms), and the first known of its shape is
    found all the same.

    Parameters
    ----------
    keys : iterable of tuple, optional
        Keys known beforehand (a cache of solved sections, in the order they were solved).
    """

    def __init__(self, keys=()):
        # per (params, options, number of pieces), per bucket: the keys in the order they became
        # known, their order among all the keys, and their terms stacked in an array that doubles
        # when full (its first len(keys) rows are theirs)
        self._groups: dict[tuple, dict[int | None, tuple[list[tuple], list[int], np.ndarray]]] = {}
        self._count = 0
        for key in keys:
            self.find(key)

    def find(self, key: tuple) -> tuple:
        """The known key of ``key``'s shape, or ``key`` itself, known from now on, if it has none."""
        buckets = self._groups.setdefault((key[0], key[1], len(key[2])), {})
        terms = _terms(key)
        home = _bucket(terms)
        found = None  # (order, key) of the first known key of this shape
        for b in (home,) if home is None else (home - 1, home, home + 1):
            if b not in buckets:
                continue
            known, orders, stack = buckets[b]
            old = stack[:len(known)]
            lengths = np.maximum(old[:, :, 4], terms[None, :, 4])
            close = (np.abs(old[:, :, :4] - terms[None, :, :4]) <= SHAPE_TOL).all(axis=(1, 2)) & (
                np.abs(old[:, :, 4] - terms[None, :, 4]) <= SHAPE_TOL * lengths).all(axis=1)
            hit = np.flatnonzero(close)
            if hit.size and (found is None or orders[hit[0]] < found[0]):
                found = (orders[hit[0]], known[int(hit[0])])
        if found is not None:
            return found[1]
        known, orders, stack = buckets.get(home, ([], [], np.empty((0,) + terms.shape)))
        m = len(known)
        if m == stack.shape[0]:  # full: double it
            stack = np.concatenate([stack, np.empty((max(4, m),) + terms.shape)])
        stack[m] = terms
        known.append(key)
        orders.append(self._count)
        self._count += 1
        buckets[home] = (known, orders, stack)
        return key
