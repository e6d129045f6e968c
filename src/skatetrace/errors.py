"""Exceptions raised by skatetrace."""

__all__ = ["SkatetraceError", "FigureFormatError", "InfeasibleArcError"]


class SkatetraceError(Exception):
    """Base class of skatetrace's own errors."""


class FigureFormatError(SkatetraceError, ValueError):
    """A figure (JSON or in code) is malformed; the message names the field and what is expected."""


class InfeasibleArcError(SkatetraceError, ValueError):
    """A piece cannot be traced with the requested options."""
