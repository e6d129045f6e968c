"""Built-in figures, each with its provenance.

- ``double-flower``: the paper's Table 1 arcs (r = 1.2, 0.8, 1.0; L = 1.1 pi r, 0.2 pi r, pi r;
  m = 1, M = 2, I = 3), inner curve of 8 arcs and outer curve of 8 three-arc leaves, closed 8-fold
  with finite pivots at the cusps (PHYSICS.md "Closing a symmetric figure").
- ``double-flower-cusps``: the variant with true cusps (reversals, no pivot), lengths that close:
  1.25 pi r1 for the inner arc and 0.75 pi r2 for arc 2 between two semicircles (PHYSICS.md).
- ``circle``, ``line``, ``s-bend``: small figures for tests and teaching.
"""

from __future__ import annotations

import math

from scipy.optimize import brentq

from ..dynamics.model import SleighParams
from ..errors import FigureFormatError
from .figure import SMOOTH, Curve, Figure, Join
from .geometry import Segment

__all__ = ["pattern", "pattern_names"]

_PAPER = "Rhodes & Putkaradze, Trajectory tracing in figure skating, Table 1; shared/PHYSICS.md"


def _arc(radius: float, sweep_deg: float) -> Segment:
    return Segment(math.copysign(1.0 / radius, sweep_deg), radius * math.radians(abs(sweep_deg)))


def _outer_leaf_pivots() -> tuple[float, float]:
    """Pivots (p_a, p_b) of the outer leaf with all four junctions on one circle.

    The leaf is arc 3, arc 2, arc 3 with pivots p_a, p_a and p_b at the leaf's end;
    ``2 p_a + p_b = 45 deg - (180 + 36 + 180) deg`` closes the curve 8-fold.
    """
    leaf = (_arc(1.0, 180.0), _arc(0.8, 36.0), _arc(1.0, 180.0))
    total = math.radians(45.0) - sum(s.turn for s in leaf)

    def spread(pa: float) -> float:
        pb = total - 2 * pa
        c = Curve(leaf, (Join("cusp", pa), Join("cusp", pa)), 8, Join("cusp", pb))
        cx, cy = c.unit_centre()
        placed = c.layout()
        r0 = math.hypot(placed[0].start.x - cx, placed[0].start.y - cy)
        r1 = math.hypot(placed[1].start.x - cx, placed[1].start.y - cy)
        return r1 - r0

    pa = brentq(spread, math.radians(-120.0), math.radians(-80.0), xtol=1e-15)
    return pa, total - 2 * pa


def _double_flower() -> Figure:
    inner = Curve((_arc(1.2, 198.0),), (), 8, Join("cusp", math.radians(-153.0)), name="inner").centred_at(0, 0)
    pa, pb = _outer_leaf_pivots()
    outer = Curve((_arc(1.0, 180.0), _arc(0.8, 36.0), _arc(1.0, 180.0)), (Join("cusp", pa), Join("cusp", pa)),
                  8, Join("cusp", pb), name="outer").centred_at(0, 0)
    return Figure("double-flower", (inner, outer), SleighParams(),
                  "The paper's double flower: 8 inner arcs and 8 three-arc outer leaves, pivots at cusps.",
                  _PAPER + f"; outer pivots {math.degrees(pa):.4f}, {math.degrees(pa):.4f}, "
                  f"{math.degrees(pb):.4f} deg put all leaf junctions on one circle")


def _double_flower_cusps() -> Figure:
    rev = Join("cusp", 0.0, True)
    inner = Curve((_arc(1.2, 225.0),), (), 8, rev, name="inner").centred_at(0, 0)
    outer = Curve((_arc(1.0, 180.0), _arc(0.8, 135.0), _arc(1.0, 180.0)), (rev, rev), 8, rev,
                  name="outer").centred_at(0, 0)
    return Figure("double-flower-cusps", (inner, outer), SleighParams(),
                  "Double flower with true cusps (reversals, no pivots) and lengths that close 8-fold.",
                  "shared/PHYSICS.md, 'Closing a symmetric figure': inner arc 1.25 pi r1, arc 2 0.75 pi r2")


def _builtins() -> dict:
    return {
        "double-flower": _double_flower,
        "double-flower-cusps": _double_flower_cusps,
        "circle": lambda: Figure("circle", (Curve((_arc(1.0, 360.0),), name="circle"),), None,
                                 "One full circle of radius 1 from rest to rest.", "test figure"),
        "line": lambda: Figure("line", (Curve((Segment(0.0, 3.0),), name="line"),), None,
                               "A straight line of length 3 from rest to rest.", "test figure"),
        "s-bend": lambda: Figure(
            "s-bend", (Curve((_arc(2.0, 30.0), _arc(1.0, 30.0), Segment(0.0, 0.5)), (SMOOTH, SMOOTH), name="s-bend"),),
            None, "Arc, tighter arc and line joined smoothly: one section from rest to rest.", "test figure"),
    }


def pattern_names() -> list[str]:
    """Names of the built-in figures."""
    return sorted(_builtins())


def pattern(name: str) -> Figure:
    """A built-in figure by name (see :func:`pattern_names`)."""
    table = _builtins()
    if not isinstance(name, str) or name not in table:
        raise FigureFormatError(f"unknown figure {name!r}; built-in figures are {', '.join(sorted(table))}")
    return table[name]()
