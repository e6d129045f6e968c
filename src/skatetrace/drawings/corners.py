"""Corners of a path: a turn of travel direction, wrapped to ``(-pi, pi]``, and the figure join it becomes.

Splitting (:mod:`.splitting`) measures each corner as a signed turn; a fitted run (arc spline or
exact) carries it as ``corner``; :func:`corner_join` says how the skater takes it in a
:class:`~skatetrace.figures.figure.Figure`: smoothly, by pivoting, or by reversing the blade (a cusp).
"""

from __future__ import annotations

import math

from ..figures.figure import SMOOTH, Join

__all__ = ["corner_join"]

_TWO_PI = 2.0 * math.pi


def _wrap(a: float) -> float:
    """Angle in ``(-pi, pi]``."""
    r = math.remainder(a, _TWO_PI)
    return math.pi if r <= -math.pi else r


def corner_join(corner: float | None, reverse_above_deg: float = 90.0) -> Join | None:
    """The figure join for a run's ``corner``; ``None`` if there is none.

    ``corner`` is as :attr:`~skatetrace.drawings.splitting.Run.corner`. ``0.0`` is a smooth join.
    Otherwise a cusp join: if ``|corner|`` exceeds ``reverse_above_deg`` the blade reverses (a true
    cusp) and pivots by ``remainder(corner - pi, 2 pi)``, else it pivots by ``corner``; either way the
    travel direction after the join has turned by ``corner``.

    Examples
    --------
    >>> corner_join(None) is None, corner_join(0.0) == SMOOTH
    (True, True)
    >>> j = corner_join(0.75 * math.pi)
    >>> j.kind, round(math.degrees(j.pivot), 9), j.reverse
    ('cusp', -45.0, True)
    """
    if corner is None:
        return None
    if corner == 0.0:
        return SMOOTH
    if abs(corner) > math.radians(reverse_above_deg):
        return Join("cusp", math.remainder(corner - math.pi, _TWO_PI), True)
    return Join("cusp", corner)

