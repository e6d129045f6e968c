"""The paper's Tables 1-6 as data: one :class:`PaperRow` per arc and optimisation.

Every number is copied from the LaTeX source in ``shared/reference`` with the digits it is printed
with; ``published`` and ``published_error`` are the paper's claims, never our results.

- ``main``: Tables 1 and 2 (controls ``a = A cos wt, b = A sin wt``, length-based cost).
- ``point``: Tables 3 and 4 (appendix, ``a = a1 + a2 sin wt + a3 cos wt``, end-point cost).
- ``length``: Tables 5 and 6 (appendix controls, length-based cost).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

__all__ = ["PaperRow", "paper_rows", "paper_row", "METHODS"]

METHODS = ("main", "point", "length")


@dataclass(frozen=True, slots=True, kw_only=True)
class PaperRow:
    """One arc of one of the paper's optimisations, as printed.

    Attributes
    ----------
    method : {"main", "point", "length"}
    arc : int
        1, 2 or 3 (arc 1 is the inner arc of the double flower, arcs 2 and 3 the outer leaf).
    tables : str
        The tables the row comes from, e.g. ``"1-2"``.
    T : float
        The integration time ``T`` of the table.
    radius : float
        ``r``; the arcs turn left (counter-clockwise) for a positive speed.
    initial : tuple
        ``(p1, p2, theta, x, y)``, and ``b`` for the appendix methods.
    target_length : float or None
        ``L_opt`` for the length-based rows.
    target_point : tuple or None
        ``(X_opt, Y_opt)`` for the point-based rows.
    guess, published : tuple
        Control parameters: ``(A, omega)`` for ``main``, ``(a1, a2, a3, omega)`` otherwise.
    published_error : float or None
        The paper's "Error" column (Tables 2 and 6); Table 4 has none.
    """

    method: str
    arc: int
    tables: str
    T: float
    radius: float
    initial: tuple
    guess: tuple
    published: tuple
    target_length: float | None = None
    target_point: tuple | None = None
    published_error: float | None = None

    @property
    def key(self) -> str:
        """A short identifier, e.g. ``"main-arc1"``."""
        return f"{self.method}-arc{self.arc}"

    @property
    def centre(self) -> tuple[float, float]:
        """Centre of the circle through the initial point with the initial heading."""
        _, _, th, x, y = self.initial[:5]
        return x - self.radius * math.sin(th), y + self.radius * math.cos(th)

    @property
    def exact_length(self) -> float:
        """Length of the arc the exact engine is asked to trace.

        The length-based rows' ``L_opt``; for the point-based rows the counter-clockwise arc from
        the initial point to the target point (the forward arc the paper optimises).
        """
        if self.target_length is not None:
            return self.target_length
        cx, cy = self.centre
        _, _, _, x, y = self.initial[:5]
        a0 = math.atan2(y - cy, x - cx)
        a1 = math.atan2(self.target_point[1] - cy, self.target_point[0] - cx)
        return self.radius * ((a1 - a0) % (2 * math.pi))


def paper_rows() -> tuple[PaperRow, ...]:
    """All nine rows: Tables 1-2, 3-4 and 5-6, arcs 1-3 each."""
    pi = math.pi
    return (
        PaperRow(method="main", arc=1, tables="1-2", T=6.0, radius=1.2, target_length=1.1 * 1.2 * pi,
                 initial=(2.0, 3.0, 0.0, 0.0, -1.2), guess=(1.0, 1.0), published=(0.799, 3.283),
                 published_error=1.899e-7),
        PaperRow(method="main", arc=2, tables="1-2", T=4.1, radius=0.8, target_length=0.2 * 0.8 * pi,
                 initial=(0.15, 0.5, 0.0, 0.0, -0.8), guess=(0.1, 1.0), published=(-0.343, 1.369),
                 published_error=6.144e-4),
        PaperRow(method="main", arc=3, tables="1-2", T=4.1, radius=1.0, target_length=1.0 * pi,
                 initial=(2.0, 3.0, 0.0, 0.0, -1.0), guess=(1.0, 1.0), published=(-1.379, 2.352),
                 published_error=9.316e-8),
        PaperRow(method="point", arc=1, tables="3-4", T=8.0, radius=1.2,
                 target_point=(math.sqrt(27) / 5, 3 / 5), initial=(1.5, 2.5, 0.0, 0.0, -1.2, 1.1),
                 guess=(1.0, 1.0, 1.0, 1.0), published=(1.005, 1.013, 1.004, 1.018)),
        PaperRow(method="point", arc=2, tables="3-4", T=1.5, radius=1.0,
                 target_point=(1 / 5, -math.sqrt(24) / 5), initial=(0.015, 0.025, 0.0, 0.0, -1.0, 0.015),
                 guess=(0.1, 0.1, 0.1, 2.0), published=(0.139, -0.509, 0.323, 2.011)),
        PaperRow(method="point", arc=3, tables="3-4", T=8.0, radius=1.0, target_point=(1.0, 0.0),
                 initial=(1.5, 2.5, 0.0, 0.0, -1.0, 0.75), guess=(1.0, 1.0, 1.0, 1.0),
                 published=(1.028, 1.082, 0.954, 1.099)),
        PaperRow(method="length", arc=1, tables="5-6", T=6.0, radius=1.2, target_length=1.1 * 1.2 * pi,
                 initial=(2.5, 3.0, 0.0, 0.0, -1.2, 1.25), guess=(1.0, 1.0, 1.0, 1.0),
                 published=(1.000, 1.000, 1.000, 1.000), published_error=6.916e-4),
        PaperRow(method="length", arc=2, tables="5-6", T=2.1, radius=0.8, target_length=0.2 * 0.8 * pi,
                 initial=(0.0015, 0.0025, 0.0, 0.0, -0.8, 0.003), guess=(0.1, 0.1, 0.1, 1.0),
                 published=(0.658, -0.675, 0.428, 1.016), published_error=6.000e-14),
        PaperRow(method="length", arc=3, tables="5-6", T=8.0, radius=1.0, target_length=1.0 * pi,
                 initial=(1.5, 2.5, 0.0, 0.0, -1.0, 0.75), guess=(1.0, 1.0, 1.0, 1.0),
                 published=(1.024, 1.007, 0.996, 1.009), published_error=4.655e-11),
    )


def paper_row(method: str, arc: int) -> PaperRow:
    """The row of ``method`` (``"main"``, ``"point"``, ``"length"``) for ``arc`` (1-3)."""
    for row in paper_rows():
        if row.method == method and row.arc == arc:
            return row
    raise ValueError(f"no paper row for method {method!r} and arc {arc!r}: methods are {METHODS}, arcs 1, 2, 3")
