"""An exact-mode fit as a :class:`~skatetrace.figures.figure.Figure`, ready to trace."""

from __future__ import annotations

from ..errors import FitError
from ..figures.figure import Figure
from .exact_results import ExactDrawingFit, ExactPathFit
from .to_figure import _check_reverse, _figure_curves

__all__ = ["figure_from_exact"]


def figure_from_exact(fit: ExactPathFit | ExactDrawingFit, *, name: str, params=None,
                      reverse_above_deg: float = 90.0) -> Figure:
    """A :class:`~skatetrace.figures.figure.Figure` from an exact-mode fit: one curve per path.

    Pieces of a run are joined smoothly; at corners the joins of
    :func:`skatetrace.drawings.corners.corner_join` (a cusp that pivots, or reverses above
    ``reverse_above_deg``); a closed path's curve gets the closing join. Laid out with
    :meth:`Curve.layout`, the pieces reproduce the fit's layout (as :func:`skatetrace.drawings.to_figure.figure_from_fit`).

    Raises
    ------
    FitError
        If the fit did not succeed, or ``reverse_above_deg`` is not in ``[0, 180]``.
    """
    _check_reverse(reverse_above_deg)
    if not isinstance(fit, (ExactPathFit, ExactDrawingFit)):
        raise FitError(f"expected an ExactPathFit or ExactDrawingFit, got {type(fit).__name__}")
    paths = fit.paths if isinstance(fit, ExactDrawingFit) else (fit,)
    if not fit.success:
        raise FitError(f"cannot make a figure from a failed fit: {fit.message}")
    curves = _figure_curves(paths, reverse_above_deg, lambda run: run.pieces)
    tols = sorted({p.tol for p in paths})
    deviation = max(p.deviation for p in paths)
    return Figure(name, tuple(curves), params, provenance=(
        "exact-mode curvature spline (Segments and Spirals with curvature cubic in arc length) within a "
        f"measured deviation of {deviation:.3g} from the drawing (tol {', '.join(f'{t:.3g}' for t in tols)})"),
        extra={"exact": {"tol": tols[-1], "deviation": deviation, "n_spirals": sum(p.n_spirals for p in paths),
                         "n_arcs": sum(p.n_arcs for p in paths), "n_lines": sum(p.n_lines for p in paths)}})
