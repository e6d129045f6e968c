"""A parametric curve ``u -> (x, y)``, a Python function, as a one-piece drawing.

The curve becomes a :class:`~skatetrace.drawings.curves.FunctionPiece`: exact derivatives when
they are given, central differences otherwise. It is checked once on a grid so that a function
that fails, returns the wrong shape or non-finite values is a :class:`DrawingError` here and not
a traceback during fitting.
"""

from __future__ import annotations

import math
from typing import Callable

import numpy as np

from .curves import Drawing, FunctionPiece, Path
from .lengths import CLOSE_TOL, MAX_COORD, extent
from ..errors import DrawingError

__all__ = ["from_function"]


def from_function(fn: Callable, u0: float, u1: float, *, closed: bool = False, dfn: Callable | None = None,
                  d2fn: Callable | None = None, name: str = "function") -> Drawing:
    """A parametric curve ``u -> (x, y)`` on ``[u0, u1]`` as a one-piece drawing.

    Parameters
    ----------
    fn : callable
        ``fn(u) -> (x, y)`` for a numpy array ``u``; returns two arrays or one of shape ``(2, n)``.
    u0, u1 : float
        Parameter interval (``u1 < u0`` runs the curve backwards).
    closed : bool
        Whether the curve is closed; then ``fn(u1)`` must equal ``fn(u0)`` within ``CLOSE_TOL``
        of the curve's size.
    dfn, d2fn : callable, optional
        Exact first and second derivatives with respect to ``u`` (same shapes); otherwise central
        differences, which evaluate ``fn`` slightly outside ``[u0, u1]``.
    name : str
        Name of the drawing and of its path.

    Returns
    -------
    Drawing
        One :class:`Path` with one :class:`FunctionPiece`, ``unit="model"``.

    Raises
    ------
    DrawingError
        ``fn`` (or a derivative) fails, does not accept arrays, returns the wrong shape or
        non-finite values on a test grid; an empty interval; a curve with no extent; ``closed``
        but not closing.

    Examples
    --------
    >>> import numpy as np
    >>> circle = from_function(lambda u: (np.cos(u), np.sin(u)), 0.0, 2 * np.pi, closed=True,
    ...                        dfn=lambda u: (-np.sin(u), np.cos(u)), name="circle")
    >>> round(circle.paths[0].length(), 9)
    6.283185307
    """
    if not callable(fn):
        raise DrawingError(f"{name}: fn must be a function u -> (x, y), got {type(fn).__name__}")
    for label, f in (("dfn", dfn), ("d2fn", d2fn)):
        if f is not None and not callable(f):
            raise DrawingError(f"{name}: {label} must be a function u -> (x', y') or None, got {type(f).__name__}")
    try:
        u0, u1 = float(u0), float(u1)
    except (TypeError, ValueError):
        raise DrawingError(f"{name}: u0 and u1 must be numbers, got {u0!r} and {u1!r}") from None
    if not (math.isfinite(u0) and math.isfinite(u1) and u0 != u1):
        raise DrawingError(f"{name}: the parameter interval [u0, u1] must be finite and not empty, "
                           f"got [{u0!r}, {u1!r}]")
    piece = FunctionPiece(fn, u0, u1, dfn, d2fn)
    grid = np.linspace(0.0, 1.0, 33)
    for what, method in (("fn", piece.point), ("its derivative", piece.d1), ("its second derivative", piece.d2)):
        try:
            with np.errstate(all="ignore"):
                values = method(grid)
        except Exception as exc:  # the user's own function may raise anything; say which and where
            raise DrawingError(f"{name}: evaluating {what} on u in [{u0:g}, {u1:g}] failed ({exc}); fn must "
                               "accept a numpy array u and return x and y arrays, shape (2, len(u))") from exc
        if not np.all(np.isfinite(values)):
            hint = "" if what == "fn" else " (give dfn/d2fn if fn is undefined just outside [u0, u1])"
            raise DrawingError(f"{name}: {what} is not finite somewhere on u in [{u0:g}, {u1:g}]{hint}")
        if what == "fn":
            largest = float(np.abs(values).max())
            if largest > MAX_COORD:
                raise DrawingError(f"{name}: coordinates reach {largest:.3g}, beyond the supported "
                                   f"{MAX_COORD:.0e}: rescale the curve")
            size = extent(values)
    if not size > 0:
        raise DrawingError(f"{name}: fn is constant on [{u0:g}, {u1:g}]: the curve is a single point")
    gap = float(np.hypot(*(piece.end - piece.start)))
    if closed and gap > CLOSE_TOL * size:
        raise DrawingError(f"{name}: closed=True but fn(u1) = {tuple(piece.end.round(12))} differs from "
                           f"fn(u0) = {tuple(piece.start.round(12))} by {gap:.3g}; fix the interval or pass closed=False")
    return Drawing((Path((piece,), closed=bool(closed), name=name),), name=name, source="function", unit="model")
