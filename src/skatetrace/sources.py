"""From whatever the user names to a traceable :class:`~skatetrace.figure.Figure`.

A figure can be named as

- a built-in pattern (``double-flower``, ...): exact arcs in the paper's model units;
- ``school:NAME`` (``school:paragraph-three``): a school figure sized for a skater, exact arcs in
  metres with the SI skater preset;
- a figure JSON file (``skatetrace.figure/1``): exact arcs as written;
- a drawing: an SVG file or a point list (``.csv``, ``.txt``, ``.dat``), or a
  :class:`~skatetrace.curves.Drawing` made in Python; it is scaled to ``size`` and fitted by arc
  splines within ``tol`` (a certified Hausdorff distance).

:func:`resolve` returns the figure with the fit (if any), the unit of length and notes. The CLI and
notebooks share it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

from .curves import Drawing
from .errors import SkatetraceError
from .figure import Figure, load_figure
from .model import SleighParams
from .patterns import pattern, pattern_names

__all__ = ["Resolved", "resolve", "DRAWING_SUFFIXES", "DEFAULT_REL_TOL"]

DRAWING_SUFFIXES = (".svg", ".csv", ".txt", ".dat")
#: Fitting tolerance, as a fraction of the figure's size, when none is given.
DEFAULT_REL_TOL = 1e-3


@dataclass(frozen=True, slots=True, kw_only=True)
class Resolved:
    """A figure ready to trace, and how it was obtained.

    Attributes
    ----------
    figure : Figure
    kind : str
        ``"pattern"``, ``"school"``, ``"json"`` or ``"drawing"``.
    unit : str
        ``"m"`` (lengths in metres, SI parameters) or ``"model"`` (the paper's units).
    fit : DrawingFit or None
        For drawings: the arc-spline fit with its certified Hausdorff bound.
    drawing : Drawing or None
        For drawings: the drawing as fitted (after scaling).
    tol : float or None
        The fitting tolerance used (figure units).
    notes : tuple of str
    """

    figure: Figure
    kind: str
    unit: str
    fit: object | None = None
    drawing: Drawing | None = None
    tol: float | None = None
    notes: tuple = field(default=())


def _size(size) -> tuple[float | None, str | None]:
    if size is None:
        return None, None
    if isinstance(size, (int, float)) and not isinstance(size, bool):
        if not (size > 0 and math.isfinite(size)):
            raise SkatetraceError(f"size must be a positive length, got {size!r}")
        return float(size), "model"
    from .inputs import parse_length

    try:
        return parse_length(str(size))
    except SkatetraceError as exc:
        raise SkatetraceError(f"size: {exc}") from None


def _tol(tol, unit: str, size: float) -> float:
    if tol is None:
        return DEFAULT_REL_TOL * size
    if isinstance(tol, (int, float)) and not isinstance(tol, bool):
        value, tunit = float(tol), unit
    else:
        from .inputs import parse_length

        try:
            value, tunit = parse_length(str(tol))
        except SkatetraceError as exc:
            raise SkatetraceError(f"tolerance: {exc}") from None
        if tunit == "model":
            tunit = unit
    if tunit != unit:
        raise SkatetraceError(f"tolerance {tol!r} is in {tunit} but the figure is in {unit} units; "
                              "give both in metres (e.g. --size 6m --tol 1mm) or both without a unit")
    if not (value > 0 and math.isfinite(value)):
        raise SkatetraceError(f"tolerance must be a positive length, got {tol!r}")
    return value


def resolve(spec: str | Path | Drawing, *, size=None, tol=None, method: str = "greedy", height: float = 1.7,
            blade: float = 0.28, edge: str = "outside", direction: str = "forward", foot: str = "right",
            body_mass: float = 60.0) -> Resolved:
    """Turn a name, a file or a drawing into a figure to trace.

    Parameters
    ----------
    spec : str, path or Drawing
        See the module docstring.
    size : str or float, optional
        Drawings only: the larger side of the figure after scaling, e.g. ``"6m"`` (metres, SI
        skater) or ``12`` (model units). Default: the drawing's own units, as model units.
    tol : str or float, optional
        Drawings only: fitting tolerance (Hausdorff distance), in the figure's units or with a
        unit (``"1mm"``). Default ``1e-3`` of the figure's size.
    method : {"greedy", "min"}
        Arc-spline fit (:func:`skatetrace.fitting.fit_drawing`).
    height, blade, edge, direction, foot : school figures (:func:`skatetrace.school.school_figure`).
    body_mass : float
        kg, for the SI skater preset used with figures in metres.

    Raises
    ------
    SkatetraceError
        Unknown name, unreadable file, bad size or tolerance, or a fit that is not within ``tol``
        (the message says where it failed).
    """
    from .presets import skater_params

    if isinstance(spec, Drawing):
        return _drawing(spec, size, tol, method, body_mass, height)
    name = str(spec)
    if name.startswith("school:"):
        from .school import school_figure

        fig = school_figure(name.split(":", 1)[1], height=height, blade=blade, edge=edge, direction=direction,
                            foot=foot, params=skater_params(body_mass, height))
        return Resolved(figure=fig, kind="school", unit="m",
                        notes=(f"school figure for a skater {height:g} m tall, {body_mass:g} kg (SI units)",))
    if name in pattern_names():
        return Resolved(figure=pattern(name), kind="pattern", unit="model")
    path = Path(name)
    suffix = path.suffix.lower()
    if suffix in DRAWING_SUFFIXES:
        from .inputs import load_drawing

        return _drawing(load_drawing(path), size, tol, method, body_mass, height)
    if suffix == ".json" or path.exists():
        return Resolved(figure=load_figure(path), kind="json", unit="model")
    raise SkatetraceError(
        f"unknown figure {name!r}: not a built-in ({', '.join(pattern_names())}), not school:NAME "
        f"(see 'skatetrace figures') and no such file (.json figure, or a drawing: {', '.join(DRAWING_SUFFIXES)})")


def _drawing(drawing: Drawing, size, tol, method: str, body_mass: float, height: float) -> Resolved:
    from .fitting import figure_from_fit, fit_drawing
    from .presets import skater_params

    value, unit = _size(size)
    notes = list(drawing.notes)
    if value is not None:
        drawing = drawing.scaled_to(value, unit)
        notes.append(f"scaled to {value:g} {unit} across")
    else:
        unit = "model"
        notes.append(f"kept the drawing's own units ({drawing.size():.4g} across) as model units")
    fsize = drawing.size()
    tol_v = _tol(tol, unit, fsize)
    fit = fit_drawing(drawing, tol_v, method=method)
    if not fit.success:
        raise SkatetraceError(f"could not fit {drawing.name!r} within {tol_v:.3g}: {fit.message}")
    params = skater_params(body_mass, height) if unit == "m" else SleighParams()
    fig = figure_from_fit(fit, name=drawing.name, params=params)
    fig = Figure(fig.name, tuple(c.merged() for c in fig.curves), fig.params, fig.description, fig.provenance,
                 fig.extra)
    notes.append(f"fitted by {fit.n_arcs} arcs and {fit.n_lines} lines within {fit.hausdorff:.3g} "
                 f"(certified; tolerance {tol_v:.3g} {unit})")
    return Resolved(figure=fig, kind="drawing", unit=unit, fit=fit, drawing=drawing, tol=tol_v, notes=tuple(notes))
