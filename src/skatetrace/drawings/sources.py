"""From whatever the user names to a traceable :class:`~skatetrace.figures.figure.Figure`.

A figure can be named as

- a built-in pattern (``double-flower``, ...): exact arcs in the paper's model units;
- ``school:NAME`` (``school:paragraph-three``): a school figure sized for a skater, exact arcs in
  metres with the SI skater preset;
- a figure JSON file (``skatetrace.figure/1``): exact arcs as written;
- a drawing: an SVG file or a point list (``.csv``, ``.txt``, ``.dat``), or a
  :class:`~skatetrace.drawings.curves.Drawing` made in Python; it is scaled to ``size`` and fitted by arc
  splines within ``tol`` (a certified Hausdorff distance). In *exact mode* (``exact=...``) its
  smooth runs are instead traced as curvature splines (:mod:`skatetrace.drawings.exact`) within a far
  smaller distance; the arc fit is still made, so that both deviations can be shown.

:func:`resolve` returns the figure with the fit (if any), the unit of length and notes. The CLI and
notebooks share it.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field, replace
from pathlib import Path

from .curves import Drawing
from ..errors import SkatetraceError
from ..figures.figure import Figure, load_figure
from ..dynamics.model import SleighParams
from ..figures.patterns import pattern, pattern_names

__all__ = ["Resolved", "resolve", "DRAWING_SUFFIXES", "DEFAULT_REL_TOL", "DEFAULT_EXACT_REL_TOL"]

DRAWING_SUFFIXES = (".svg", ".csv", ".txt", ".dat")
#: Fitting tolerance, as a fraction of the figure's size, when none is given.
DEFAULT_REL_TOL = 1e-3
#: Exact mode's tolerance for the curvature spline, as a fraction of the figure's size: a tenth of
#: the default verification tolerance, so that the replay, not the representation, limits the match.
DEFAULT_EXACT_REL_TOL = 1e-7
#: Arc mode's corner tolerance (degrees): joins turning by less are smooth. Exact mode uses less.
EXACT_MAX_CORNER_DEG = 0.5
#: Share of the arc-fitting tolerance that absorbing tiny pieces may take (each moves the drawing by
#: half its length, see :meth:`~skatetrace.drawings.curves.Drawing.absorbed`); the fit keeps the rest.
ABSORB_SHARE = 2.0 / 3.0
#: Smallest arc-fitting tolerance, as a fraction of the figure's size: the certified fit needs
#: about 17 s per example drawing at 1e-9 and does not finish in minutes at 1e-12. Exact mode
#: (curvature splines) reaches far smaller distances quickly.
MIN_REL_TOL = 1e-8
#: Sizes a drawing may be scaled to (metres or model units); its pieces must then lie within the
#: figure limits of :mod:`skatetrace.figures.figure` (lengths 1e-9 to 1e9).
MIN_SIZE, MAX_SIZE = 1e-6, 1e6


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
        The arc-fitting tolerance used (figure units).
    exact : ExactDrawingFit or None
        Exact mode: the curvature splines the figure is made of, with their measured deviation.
    exact_tol : float or None
        Exact mode: the tolerance of the curvature splines (figure units).
    notes : tuple of str
    """

    figure: Figure
    kind: str
    unit: str
    fit: object | None = None
    drawing: Drawing | None = None
    tol: float | None = None
    exact: object | None = None
    exact_tol: float | None = None
    notes: tuple = field(default=())

    @property
    def representation_error(self) -> float | None:
        """Distance bound between the traced figure's pieces and the drawing (``None`` if not a drawing)."""
        if self.exact is not None:
            return self.exact.deviation
        return None if self.fit is None else self.fit.hausdorff

    @property
    def representation_tol(self) -> float | None:
        """Tolerance of the traced figure's pieces (the exact tolerance in exact mode)."""
        return self.exact_tol if self.exact is not None else self.tol


def _size(size) -> tuple[float | None, str | None]:
    if size is None:
        return None, None
    if isinstance(size, (int, float)) and not isinstance(size, bool):
        if not (size > 0 and math.isfinite(size)):
            raise SkatetraceError(f"size must be a positive length, got {size!r}")
        value, unit = float(size), "model"
    else:
        from .lengths import parse_length

        try:
            value, unit = parse_length(str(size))
        except SkatetraceError as exc:
            raise SkatetraceError(f"size: {exc}") from None
    _check_size(value, f"size {size!r}")
    return value, unit


def _check_size(value: float, what: str) -> None:
    if not MIN_SIZE <= value <= MAX_SIZE:
        raise SkatetraceError(f"{what} is {value:.3g} across; a drawing must be scaled to between {MIN_SIZE:g} and "
                              f"{MAX_SIZE:g} (metres or model units), e.g. --size 6m")


def _tol(tol, unit: str, size: float, default: float = DEFAULT_REL_TOL, floor: float = 0.0) -> float:
    if tol is None:
        return default * size
    if isinstance(tol, (int, float)) and not isinstance(tol, bool):
        value, tunit = float(tol), unit
    else:
        from .lengths import parse_length

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
    if value < floor * size:
        raise SkatetraceError(f"tolerance {tol!r} is below {floor:g} of the figure's size ({floor * size:.3g} {unit}); "
                              "for closer fits use exact mode (--exact)")
    return value


def resolve(spec: str | Path | Drawing, *, size=None, tol=None, method: str = "greedy", height: float = 1.7,
            blade: float = 0.28, edge: str = "outside", direction: str = "forward", foot: str = "right",
            body_mass: float = 60.0, exact=None, paths=None) -> Resolved:
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
        Arc-spline fit (:func:`skatetrace.drawings.fitting.fit_drawing`).
    exact : None, True, str or float
        Drawings only: trace the smooth runs exactly, as curvature splines
        (:func:`skatetrace.drawings.exact.fit_exact_drawing`), within this distance (as ``tol``; ``True``:
        ``1e-7`` of the figure's size). ``None`` or ``False``: arcs and lines.
    paths : sequence of str, optional
        Drawings only: trace only these paths, by the ``id`` of their SVG element (all its subpaths)
        or a subpath's name (``"id#2"``); see :meth:`~skatetrace.drawings.curves.Drawing.selected`.
    height, blade, edge, direction, foot : school figures (:func:`skatetrace.figures.school.school_figure`).
    body_mass : float
        kg, for the SI skater preset used with figures in metres.

    Raises
    ------
    SkatetraceError
        Unknown name, unreadable file, bad size or tolerance, or a fit that is not within ``tol``
        (the message says where it failed).
    """
    from ..dynamics.presets import skater_params

    if isinstance(spec, Drawing):
        return _drawing(_pick(spec, paths), size, tol, method, body_mass, height, exact)
    name = str(spec)
    if paths is not None and Path(name).suffix.lower() not in DRAWING_SUFFIXES:
        raise SkatetraceError(f"paths are picked from drawings ({', '.join(DRAWING_SUFFIXES)}); {name!r} is not one")
    if name.startswith("school:"):
        from ..figures.school import school_figure

        fig = school_figure(name.split(":", 1)[1], height=height, blade=blade, edge=edge, direction=direction,
                            foot=foot, params=skater_params(body_mass, height))
        return Resolved(figure=fig, kind="school", unit="m",
                        notes=(f"school figure for a skater {height:g} m tall, {body_mass:g} kg (SI units)",
                               *_exact_note(exact)))
    if name in pattern_names():
        return Resolved(figure=pattern(name), kind="pattern", unit="model", notes=_exact_note(exact))
    path = Path(name)
    suffix = path.suffix.lower()
    if suffix in DRAWING_SUFFIXES:
        from .load import load_drawing

        return _drawing(_pick(load_drawing(path), paths), size, tol, method, body_mass, height, exact)
    if suffix == ".json" or path.exists():
        return Resolved(figure=load_figure(path), kind="json", unit="model", notes=_exact_note(exact))
    raise SkatetraceError(
        f"unknown figure {name!r}: not a built-in ({', '.join(pattern_names())}), not school:NAME "
        f"(see 'skatetrace figures') and no such file (.json figure, or a drawing: {', '.join(DRAWING_SUFFIXES)})")


def _merged(fig: Figure) -> Figure:
    """The figure with consecutive arcs of one radius made one piece (they trace faster as one)."""
    return Figure(fig.name, tuple(c.merged() for c in fig.curves), fig.params, fig.description, fig.provenance,
                  fig.extra)


def _exact_note(exact) -> tuple[str, ...]:
    if exact is None or exact is False:
        return ()
    return ("exact mode applies to drawings; this figure's arcs, lines and spirals are traced as given",)


def _pick(drawing: Drawing, paths) -> Drawing:
    if paths is None:
        return drawing
    if isinstance(paths, str):
        paths = [paths]
    try:
        return drawing.selected(paths)
    except ValueError as exc:
        raise SkatetraceError(str(exc)) from None


def _with_gaps(fit, gaps: dict[str, float], tol: float):
    """The fit of paths closed (or with tiny pieces absorbed) moving them by up to ``gaps`` (by name), with its
    bounds to the drawing as given: each such path's distances plus its gap (no point of it moved further),
    and the tolerance ``tol``."""
    from .fit_results import gathered

    if not gaps:
        return fit
    return gathered((replace(pf, hausdorff=pf.hausdorff + gaps.get(pf.name, 0.0),
                             hausdorff_sampled=pf.hausdorff_sampled + gaps.get(pf.name, 0.0), tol=tol)
                     for pf in fit.paths), name=fit.name, tol=tol)


def _with_specks(fit, drawing: Drawing, specks: dict, tol: float, method: str):
    """The fit of ``drawing``: its specks' circles (by path index) among the other paths' ``fit`` (None if
    every path is a speck), in the drawing's order, within the tolerance ``tol``."""
    from .fit_results import gathered
    from .specks import speck_fit

    if not specks:
        return fit
    others = iter(fit.paths if fit is not None else ())
    return gathered((speck_fit(p, specks[i], tol, method) if i in specks else next(others)
                     for i, p in enumerate(drawing.paths)), name=drawing.name, tol=tol)


def _specks_note(drawing: Drawing, specks: dict, unit: str) -> str:
    from .specks import SPECK_RADIUS

    names = [drawing.paths[i].name for i in specks]
    return (f"traced {len(specks)} path(s) too small to trace as drawn (within {SPECK_RADIUS:g} x the tolerance of "
            f"their centres, their pieces sections of a fraction of a millimetre) as the circles they lie within "
            f"{ABSORB_SHARE:.3g} x the tolerance of (up to {max(s.bound for s in specks.values()):.3g} {unit} "
            f"away, certified; the fit's bound includes it): {', '.join(names[:5])}{' ...' if len(names) > 5 else ''}")


def _kink_corner_deg(drawing: Drawing, tol: float) -> float:
    """Smallest turn (degrees, at most ``EXACT_MAX_CORNER_DEG``) of a join that must be a corner.

    A join whose tangent turns by ``delta`` displaces the rest of the path by about ``delta`` times
    its length when it is kept smooth: a corner from a tenth of ``tol`` on.
    """
    length = sum(p.length() for p in drawing.paths)
    return min(EXACT_MAX_CORNER_DEG, math.degrees(tol / (10.0 * length))) if length > 0 else EXACT_MAX_CORNER_DEG


def _absorbed_fit(fitted: Drawing, fit_tol: float, gaps: dict[str, float], corner_deg: float, arc_mode: bool, fit):
    """The pieces shorter than ``2 ABSORB_SHARE`` times ``fit_tol`` between two joins turning by more
    than ``corner_deg`` absorbed into their neighbours (arc mode only), and ``fit(drawing, tol)`` of
    that drawing in what is left of the tolerance.

    Returns ``(fit, drawing, tol, gaps, moves)``: the fit (None where nothing was absorbed), and
    the drawing, tolerance, gaps and moves to go on with: the absorbed ones where the fit
    succeeded, else those given (and no moves).
    """
    absorbed, moves = fitted.absorbed(2.0 * ABSORB_SHARE * fit_tol, corner_deg) if arc_mode else (fitted, {})
    if not moves:
        return None, fitted, fit_tol, gaps, {}
    result = fit(absorbed, fit_tol - max(moves.values()))
    if not result.success:
        return result, fitted, fit_tol, gaps, {}
    merged = {name: gaps.get(name, 0.0) + moves.get(name, 0.0) for name in {*gaps, *moves}}
    return result, absorbed, fit_tol - max(moves.values()), merged, moves


def _absorbed_note(moves: dict[str, float], corners: str, unit: str) -> str:
    return (f"absorbed the pieces between two {corners} shorter than {2.0 * ABSORB_SHARE:.3g} x the tolerance into "
            f"their neighbours (an open path's end piece at such a corner, shorter than {ABSORB_SHARE:.3g} x it, "
            f"is dropped), moving the drawing by up to {max(moves.values()):.3g} {unit} (the fit's bound "
            f"includes it): {', '.join(list(moves)[:5])}{' ...' if len(moves) > 5 else ''}")


def _arc_fit(drawing: Drawing, tol_v: float, arc_mode: bool, method: str, unit: str, notes: list):
    """The arc fit of ``drawing`` within ``tol_v``, its bound to the drawing as given; what was done to
    make it fit is appended to ``notes``.

    Raises
    ------
    SkatetraceError
        Where no attempt fits.
    """
    from .fitting import fit_drawing

    # In arc mode a path drawn closed but whose ends miss by less than the tolerance is closed
    # exactly; the fit then gets what is left of the tolerance, and its bound is to the drawing as given.
    fitted, gaps = drawing.closed_within(tol_v) if arc_mode else (drawing, {})
    fit_tol = tol_v - max(gaps.values(), default=0.0)
    if gaps:
        notes.append(f"closed {len(gaps)} path(s) whose ends were within {tol_v:.3g} {unit} of their starts "
                     f"(up to {max(gaps.values()):.3g}; the fit's bound includes it): "
                     f"{', '.join(list(gaps)[:5])}{' ...' if len(gaps) > 5 else ''}")
    # A piece between two corners shorter than 2 ABSORB_SHARE times the tolerance is a section of its
    # own, started and stopped within a millimetre: absorbed into its neighbours (moving the drawing by half its
    # length), where the fit still succeeds in what is left of the tolerance; else fitted as it is.
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")

        def soft_or_sharp(d, t):
            """The fit with soft corners, else without: joins rounded because they turn little for their
            pieces' length can still add up along a run beyond the tolerance, and are corners again."""
            fit = fit_drawing(d, t, method=method)
            if not fit.success:
                sharp = fit_drawing(d, t, method=method, soft_corners=False)
                fit = sharp if sharp.success else fit
            if fit.success:
                caught.clear()  # the complaints of the attempts before it were answered
            return fit

        # either way the tiny pieces absorbed, where that fits: in what is left of the tolerance the
        # soft joins may add up beyond it (a tabler icon's 0.3 mm closing line stayed a section)
        fit, fitted, fit_tol, gaps, moves = _absorbed_fit(fitted, fit_tol, gaps, EXACT_MAX_CORNER_DEG, arc_mode,
                                                          soft_or_sharp)
        if moves:
            notes.append(_absorbed_note(moves, "corners", unit))
        if fit is None or not fit.success:
            fit = soft_or_sharp(fitted, fit_tol)
    tight = _kink_corner_deg(drawing, tol_v)
    if not fit.success and tight < EXACT_MAX_CORNER_DEG:
        # The arc spline is tangent-continuous through a smooth join, so a join that turns by delta
        # displaces the rest of its run by about delta times its length: where that breaks the fit,
        # every join that could cost a tenth of the tolerance is made a corner (a rest) instead.
        # A tiny piece between two of these corners is then a section of its own, started and
        # stopped within it (0.43 mm in an icon at 6 m): absorbed as above, where the fit allows.
        def sharp_fit(d, t):
            return fit_drawing(d, t, method=method, corner_tol_deg=tight, soft_corners=False)

        retry, fitted, fit_tol, gaps, tiny_moves = _absorbed_fit(fitted, fit_tol, gaps, tight, arc_mode, sharp_fit)
        if retry is None or not retry.success:
            retry = sharp_fit(fitted, fit_tol)
        if retry.success:
            notes.append(f"joins turning by more than {tight:.2g} degrees made corners (rests): kept smooth, "
                         f"they moved the rest of their curve by more than the tolerance ({fit.message})")
            if tiny_moves:
                notes.append(_absorbed_note(tiny_moves, "such corners", unit))
            fit, caught = retry, []  # the first attempt's complaints were answered
    for w in caught:
        warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    if not fit.success:
        raise SkatetraceError(f"could not fit {drawing.name!r} within {tol_v:.3g}: {fit.message}")
    fit = _with_gaps(fit, gaps, tol_v)
    return fit


def _drawing(drawing: Drawing, size, tol, method: str, body_mass: float, height: float, exact=None) -> Resolved:
    from .specks import find_specks
    from .to_figure import figure_from_fit
    from ..dynamics.presets import skater_params

    value, unit = _size(size)
    notes = list(drawing.notes)
    if value is not None:
        drawing = drawing.scaled_to(value, unit)
        notes.append(f"scaled to {value:g} {unit} across")
    else:
        unit = "model"
        notes.append(f"kept the drawing's own units ({drawing.size():.4g} across) as model units")
    fsize = drawing.size()
    if value is None:
        _check_size(fsize, f"the drawing {drawing.name!r}, in its own units,")
    tol_v = _tol(tol, unit, fsize, floor=MIN_REL_TOL)
    arc_mode = exact is None or exact is False
    # In arc mode a path too small to trace as drawn, near a circle, is traced as that circle.
    specks = find_specks(drawing, tol_v, ABSORB_SHARE * tol_v) if arc_mode else {}
    if specks:
        notes.append(_specks_note(drawing, specks, unit))
    rest = tuple(p for i, p in enumerate(drawing.paths) if i not in specks)
    fit = _arc_fit(replace(drawing, paths=rest), tol_v, arc_mode, method, unit, notes) if rest else None
    fit = _with_specks(fit, drawing, specks, tol_v, method)
    params = skater_params(body_mass, height) if unit == "m" else SleighParams()
    notes.append(f"arc mode: {fit.n_arcs} arcs and {fit.n_lines} lines within {fit.hausdorff:.3g} "
                 f"(certified; tolerance {tol_v:.3g} {unit})")
    if arc_mode:
        fig = _merged(figure_from_fit(fit, name=drawing.name, params=params))
        return Resolved(figure=fig, kind="drawing", unit=unit, fit=fit, drawing=drawing, tol=tol_v,
                        notes=tuple(notes))
    from .exact import fit_exact_drawing
    from .exact_figure import figure_from_exact

    exact_v = _tol(None if exact is True else exact, unit, fsize, DEFAULT_EXACT_REL_TOL)
    # in exact mode any kink that could cost a tenth of the tolerance is a corner
    ex = fit_exact_drawing(drawing, exact_v, corner_tol_deg=_kink_corner_deg(drawing, exact_v))
    if not ex.success:
        raise SkatetraceError(f"could not represent {drawing.name!r} exactly within {exact_v:.3g}: {ex.message}")
    fig = _merged(figure_from_exact(ex, name=drawing.name, params=params))
    notes.append(f"exact mode: {ex.n_spirals} spirals, {ex.n_arcs} arcs and {ex.n_lines} lines within "
                 f"{ex.deviation:.3g} (measured; tolerance {exact_v:.3g} {unit})")
    kinks = [abs(r.corner) for pf in ex.paths for r in pf.runs
             if r.corner is not None and 0.0 < abs(r.corner) <= math.radians(EXACT_MAX_CORNER_DEG)]
    if kinks:
        notes.append(f"exact mode: {len(kinks)} join(s) of the drawing are not tangent-continuous (they turn by "
                     f"up to {math.degrees(max(kinks)):.2g} degrees); the skater stops and pivots there, where "
                     "arc mode glides through")
    return Resolved(figure=fig, kind="drawing", unit=unit, fit=fit, drawing=drawing, tol=tol_v, exact=ex,
                    exact_tol=exact_v, notes=tuple(notes))
