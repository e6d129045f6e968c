"""Exceptions raised by skatetrace."""

__all__ = ["SkatetraceError", "DrawingError", "FigureFormatError", "InfeasibleArcError", "FitError"]


class SkatetraceError(Exception):
    """Base class of skatetrace's own errors."""


class FigureFormatError(SkatetraceError, ValueError):
    """A figure (JSON or in code) is malformed; the message names the field and what is expected."""


class InfeasibleArcError(SkatetraceError, ValueError):
    """A piece cannot be traced with the requested options."""


class DrawingError(SkatetraceError, ValueError):
    """A drawing (SVG, point list, parametric curve) or a length cannot be read.

    The message names the input (file, element, line) and what would be accepted.
    """


class FitError(SkatetraceError, ValueError):
    """A curve cannot be fitted with arcs as asked (bad tolerance, gaps, zero length, non-finite points)."""
