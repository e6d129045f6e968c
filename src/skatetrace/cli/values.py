"""Values the user writes with units: lengths in the figure's units, fractions, angles and times.

Each parser takes the text of one option and the option's name, and returns a number in the
figure's units (radians for an angle), or raises :class:`~skatetrace.errors.SkatetraceError` naming
the option, what it got and what would be right. A physical unit (``mm``, ``ms``) is refused for a
figure in model units, where it would mean nothing: there a plain number is in model units.
"""

from __future__ import annotations

import math
import re

from ..errors import DrawingError, SkatetraceError

__all__ = ["figure_length", "length_or_zero", "fraction", "angle", "duration"]

_QUANTITY = re.compile(r"\s*([+-]?(?:(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][+-]?\d+)?|nan|inf(?:inity)?))\s*"
                       r"([a-z%\u00b0\u00b5\u03bc]*)\s*", re.IGNORECASE)


def _quantity(text: str, flag: str, units: dict[str, float | None], forms: str) -> tuple[float, str]:
    """``text`` as ``(number, unit)``: a finite number >= 0 and one of ``units`` (lower case)."""
    match = _QUANTITY.fullmatch(text) if isinstance(text, str) else None
    unit = match.group(2).lower() if match else None
    if match is None or unit not in units:
        raise SkatetraceError(f"{flag}: cannot read {text!r}: expected a number >= 0 with one of the units "
                              f"{forms}")
    value = float(match.group(1))
    if not (math.isfinite(value) and value >= 0):
        raise SkatetraceError(f"{flag} must be a finite number >= 0, got {text!r}; e.g. {forms}")
    return value, unit


def figure_length(text: str, unit: str, flag: str) -> float:
    """A positive length in the figure's units: a physical length (``0.5m``) only for a figure in metres."""
    from ..drawings.lengths import parse_length

    value, given = parse_length(text)
    if given == "m" and unit != "m":
        raise SkatetraceError(f"{flag} {text!r} is a physical length but the figure is in model units: give "
                              "a plain number (model units)")
    return value


def length_or_zero(text: str, unit: str, flag: str) -> float:
    """:func:`figure_length`, or zero (``0``, ``0mm``): an error that is not there."""
    from ..drawings.lengths import parse_length

    match = _QUANTITY.fullmatch(text) if isinstance(text, str) else None
    zero = match is not None and float(match.group(1)) == 0.0
    try:
        if zero:
            parse_length("1" + match.group(2))  # the unit must still be one
            return 0.0
        return figure_length(text, unit, flag)
    except DrawingError as exc:
        raise SkatetraceError(f"{flag}: {exc}") from None


def fraction(text: str, flag: str) -> float:
    """A fraction in [0, 1): ``5%`` or ``0.05``."""
    value, unit = _quantity(text, flag, {"%": 0.01, "": 1.0}, "'5%' or '0.05'")
    value *= 0.01 if unit == "%" else 1.0
    if not value < 1.0:
        raise SkatetraceError(f"{flag} must be below 100 %, got {text!r}; e.g. '5%' or '0.05'")
    return value


def angle(text: str, flag: str) -> float:
    """An angle >= 0 in radians from ``0.5deg`` (or ``0.5°``) or ``0.01rad``; a plain ``0`` needs no unit."""
    value, unit = _quantity(text, flag, {"deg": math.pi / 180, "\u00b0": math.pi / 180, "rad": 1.0, "": None},
                            "'0.5deg', '0.5°' or '0.01rad'")
    if unit == "":
        if value != 0.0:
            raise SkatetraceError(f"{flag}: the angle {text!r} needs a unit: '{text.strip()}deg' or "
                                  f"'{text.strip()}rad'")
        return 0.0
    return value * (math.pi / 180 if unit in ("deg", "\u00b0") else 1.0)


def duration(text: str, unit: str, flag: str) -> float:
    """A time >= 0 in the figure's time unit: ``10ms``, ``0.01s`` or ``0.01`` (seconds only for a figure in metres)."""
    scale = {"s": 1.0, "ms": 1e-3, "us": 1e-6, "\u00b5s": 1e-6, "\u03bcs": 1e-6, "": 1.0}
    value, given = _quantity(text, flag, scale, "'10ms', '0.01s' or '0.01'")
    if given and unit != "m" and value != 0.0:
        raise SkatetraceError(f"{flag} {text!r} is a physical time but the figure is in model units: give a "
                              "plain number (model time units)")
    return value * scale[given]
