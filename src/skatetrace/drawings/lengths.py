"""Sizes in a drawing: lengths with units, a drawing's extent, when points coincide, how large coordinates may be.

A length the user writes (``"6m"``, ``"20ft"``, ``"0.5 mm"``, ``"6"`` in model units) becomes a number
and a unit with :func:`parse_length`; it scales a drawing to the ice (:meth:`Drawing.scaled_to`) or
sets a tolerance. The readers of drawings share the rest: :data:`CLOSE_TOL`, relative to a
drawing's :func:`extent`, decides when two points are the same point (a closed path, a repeated
point), and :data:`MAX_COORD` is the largest coordinate they accept.
"""

from __future__ import annotations

import math
import re

import numpy as np

from ..errors import DrawingError

__all__ = ["parse_length", "extent", "CLOSE_TOL", "MAX_COORD"]

CLOSE_TOL = 1e-9
"""Points closer than ``CLOSE_TOL`` times the drawing's size coincide (closure, repeated points)."""

MAX_COORD = 1e100
"""Largest coordinate accepted: beyond it, squares of lengths (curvature, areas) overflow."""

_UNITS = {"m": 1.0, "cm": 0.01, "mm": 0.001, "um": 1e-6, "\u00b5m": 1e-6, "\u03bcm": 1e-6, "ft": 0.3048,
          "in": 0.0254, "u": None, "": None}
_LENGTH = re.compile(r"\s*([+-]?(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][+-]?\d+)?)\s*([A-Za-z\u00b5\u03bc]*)\s*")
_LENGTH_FORMS = "'6m', '6 m', '600cm', '6000mm', '20ft', '240in', '6' or '6u' (model units)"


def parse_length(text: str) -> tuple[float, str]:
    """A length such as ``"6m"`` or ``"20ft"`` as ``(value, unit)``, physical lengths in metres.

    Parameters
    ----------
    text : str
        A positive number with an optional unit: ``m``, ``cm``, ``mm``, ``um`` (or ``µm``, micrometres,
        for exact mode's tolerances), ``ft``, ``in``; ``u`` or no unit for model units. Space between number and unit is allowed; case is ignored.

    Returns
    -------
    (float, str)
        ``(metres, "m")`` for a physical unit, ``(value, "model")`` otherwise.

    Raises
    ------
    DrawingError
        Not a number with a known unit, zero, negative or not finite; the message lists the
        accepted forms.

    Examples
    --------
    >>> parse_length("600cm"), parse_length("6 m"), parse_length("6")
    ((6.0, 'm'), (6.0, 'm'), (6.0, 'model'))
    """
    if not isinstance(text, str):
        raise DrawingError(f"a length must be text such as {_LENGTH_FORMS}; got {type(text).__name__}")
    match = _LENGTH.fullmatch(text)
    unit = match.group(2).lower() if match else None
    if match is None or unit not in _UNITS:
        raise DrawingError(f"cannot read the length {text!r}: expected a positive number with an optional unit, "
                           f"e.g. {_LENGTH_FORMS}")
    value = float(match.group(1))
    if not (value > 0 and math.isfinite(value)):
        raise DrawingError(f"a length must be positive and finite, got {text!r}; e.g. {_LENGTH_FORMS}")
    factor = _UNITS[unit]
    if factor is None:
        return value, "model"
    if not value * factor > 0:  # underflow, e.g. "5e-324mm"
        raise DrawingError(f"a length must be positive, got {text!r}, which is 0 in metres; e.g. {_LENGTH_FORMS}")
    return value * factor, "m"


def extent(points: np.ndarray) -> float:
    """Larger side of the bounding box of ``points``, shape ``(2, n)``: the size :data:`CLOSE_TOL` is relative to."""
    return float(max(np.ptp(points[0]), np.ptp(points[1])))
