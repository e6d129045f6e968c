"""A fit turned into a :class:`~skatetrace.figures.figure.Figure`: one curve per path, joined at its corners.

:func:`figure_from_fit` makes a figure from an arc-spline fit: segments of a run join smoothly, and
each corner becomes a cusp join that pivots the blade, or reverses it (a true cusp) when the travel
direction turns by more than ``reverse_above_deg`` (:func:`~skatetrace.drawings.corners.corner_join`).
Exact fits (:mod:`.exact`) are laid into curves the same way, by :func:`_figure_curves`.
"""

from __future__ import annotations

from .corners import corner_join
from .fit_results import DrawingFit, PathFit
from ..errors import FitError
from ..figures.figure import SMOOTH, Curve, Figure, Join

__all__ = ["figure_from_fit"]


def figure_from_fit(fit: PathFit | DrawingFit, *, name: str, params=None, reverse_above_deg: float = 90.0) -> Figure:
    """A :class:`~skatetrace.figures.figure.Figure` from a fit: one curve per path.

    Parameters
    ----------
    fit : PathFit or DrawingFit
        A successful fit.
    name : str
    params : SleighParams, optional
    reverse_above_deg : float
        At a corner whose travel direction turns by ``delta`` (in ``(-pi, pi]``), a cusp join: if
        ``|delta|`` exceeds this, the blade reverses (a true cusp) and pivots by
        ``remainder(delta - pi, 2 pi)``; otherwise it pivots by ``delta``. Either way the travel
        direction after the join is the curve's.

    Returns
    -------
    Figure
        Segments of a run joined smoothly; a closed path's curve gets the closing join (smooth, or the
        corner where it closes). Laid out with :meth:`Curve.layout`, the pieces reproduce the fit.

    Raises
    ------
    FitError
        If the fit did not succeed.

    Examples
    --------
    >>> import math
    >>> from skatetrace.drawings.curves import LinePiece, Path
    >>> from skatetrace.drawings.fitting import fit_path
    >>> vee = Path((LinePiece((0.0, 0.0), (1.0, 0.0)), LinePiece((1.0, 0.0), (0.0, 0.5))))
    >>> fig = figure_from_fit(fit_path(vee, 1e-3), name="vee")
    >>> [(j.kind, round(math.degrees(j.pivot), 6), j.reverse) for j in fig.curves[0].joins]
    [('cusp', -26.565051, True)]
    """
    _check_reverse(reverse_above_deg)
    paths = fit.paths if isinstance(fit, DrawingFit) else (fit,)
    if not fit.success:
        raise FitError(f"cannot make a figure from a failed fit: {fit.message}")
    curves = _figure_curves(paths, reverse_above_deg, lambda run: run.segments)
    tols = sorted({p.tol for p in paths})
    return Figure(name, tuple(curves), params, provenance=(
        f"arc-spline fit ({paths[0].method}) within a certified Hausdorff distance of "
        f"{max(p.hausdorff for p in paths):.3g} (tol {', '.join(f'{t:.3g}' for t in tols)})"),
        extra={"fit": {"tol": tols[-1], "hausdorff": max(p.hausdorff for p in paths),
                       "n_arcs": sum(p.n_arcs for p in paths), "n_lines": sum(p.n_lines for p in paths)}})


def _check_reverse(reverse_above_deg) -> None:
    if not (isinstance(reverse_above_deg, (int, float)) and 0 <= reverse_above_deg <= 180):
        raise FitError(f"reverse_above_deg must be in [0, 180], got {reverse_above_deg!r}")


def _figure_curves(paths, reverse_above_deg: float, pieces_of) -> list[Curve]:
    """One curve per fitted path: a run's pieces (``pieces_of(run)``) joined smoothly, a
    :func:`~skatetrace.drawings.corners.corner_join` before every later run, and for a closed path the
    first run's join as closing."""
    curves = []
    for pf in paths:
        pieces: list = []
        joins: list[Join] = []
        for i, run in enumerate(pf.runs):
            items = tuple(pieces_of(run))
            if i > 0:
                joins.append(corner_join(run.corner, reverse_above_deg))
            joins.extend([SMOOTH] * (len(items) - 1))
            pieces.extend(items)
        closing = corner_join(pf.runs[0].corner, reverse_above_deg) if pf.closed else None
        curves.append(Curve(tuple(pieces), tuple(joins), 1, closing, pf.runs[0].start, pf.name))
    return curves
