"""Plots of a traced figure: the paper's kinds of figures, from a trace and its replay.

matplotlib is imported inside the functions only (importing this module does not load it). Every
plot function takes ``ax=None`` and returns the artists; nothing calls ``plt.show()``.

Units on the axes. Every axis names its quantity and its unit in parentheses. A figure in metres
(``unit="m"``, SI parameters) has lengths in m, times in s, speeds in m/s and energies in J; any
other figure is in the paper's dimensionless model units, labelled ``model length``,
``model time``, ``model length/time`` and ``model energy`` (see :func:`axis_units`).

Legends stand outside the axes (to the right), so they never cover data.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from ..dynamics.model import mass_energy, skate_energy
from ..figures.geometry import segment_points

if TYPE_CHECKING:  # annotations only: importing plotting does not load the tracer
    from ..tracing.sections import FigureTrace
    from ..verification.verify import VerificationReport

__all__ = ["axis_units", "plot_figure", "plot_controls", "plot_speed", "plot_mass_path", "plot_energies",
           "plot_fit", "plot_fit_curvature", "fit_figure", "PlotsAhead", "save_all", "tradeoff_figure",
           "robustness_figure"]

_UNITS = {
    "m": {"length": "m", "time": "s", "speed": "m/s", "acceleration": "m/s²", "energy": "J", "curvature": "1/m"},
    "model": {"length": "model length", "time": "model time", "speed": "model length/time",
              "acceleration": "model length/time²", "energy": "model energy", "curvature": "1/model length"},
}
#: Rows of the replay drawn in each plot of :func:`save_all` at most (a long figure's replay holds up
#: to 200,000; an image 1100 pixels wide shows a few thousand).
PLOT_ROWS = 20_000
#: Legend outside the axes, top right: it never covers data.
_OUTSIDE = {"loc": "upper left", "bbox_to_anchor": (1.02, 1.0), "borderaxespad": 0.0, "fontsize": 8}


def axis_units(unit: str = "model") -> dict[str, str]:
    """Unit names for axis labels, by the figure's unit of length.

    Parameters
    ----------
    unit : {"model", "m"}
        ``"m"``: a figure in metres with SI parameters (kg, kg m^2); ``"model"``: the paper's
        dimensionless units.

    Returns
    -------
    dict
        Keys ``length``, ``time``, ``speed``, ``acceleration``, ``energy``, ``curvature``.

    Raises
    ------
    ValueError
        Any other ``unit``.

    Examples
    --------
    >>> axis_units("m")["energy"], axis_units()["time"]
    ('J', 'model time')
    """
    try:
        return dict(_UNITS[unit])
    except (KeyError, TypeError):
        raise ValueError(f"unit must be 'model' (the paper's units) or 'm' (metres, SI), got {unit!r}") from None


def _ax(ax):
    if ax is None:
        import matplotlib.pyplot as plt

        _, ax = plt.subplots(layout="constrained")
    return ax


def _legend(ax):
    # An equal-aspect axes shrinks after the layout has made room for the legend; anchored left,
    # it shrinks away from the legend instead of pushing it off the figure.
    ax.set_anchor("W")
    return ax.legend(**_OUTSIDE)


def plot_figure(trace: FigureTrace, report: VerificationReport, ax=None, unit: str = "model"):
    """The replayed blade path (solid) over the target figure (dashed), rest points marked."""
    u = axis_units(unit)
    ax = _ax(ax)
    artists = []
    for i, p in enumerate(p for c in trace.figure.curves for p in c.layout()):
        xy = segment_points(p.start, p.segment, 200)
        artists += ax.plot(xy[0], xy[1], "--", color="0.6", lw=2.5, label="target figure" if i == 0 else None)
    rep = report.replay
    for i, si in enumerate(np.unique(rep.section)):
        m = rep.section == si
        artists += ax.plot(rep.state[3, m], rep.state[4, m], "-", color="C0", lw=0.9,
                           label="replayed blade path" if i == 0 else None)
    # every section starts at rest: the first piece of a curve and every piece after a cusp
    cusps = [(p.start.x, p.start.y) for c in trace.figure.curves for p in c.layout()
             if p.join_before is None or p.join_before.is_cusp]
    if cusps:
        artists.append(ax.plot(*np.array(cusps).T, "o", color="C3", ms=3, label="curve starts and cusps (at rest)")[0])
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel(f"x ({u['length']})")
    ax.set_ylabel(f"y ({u['length']})")
    ax.set_title(f"{trace.figure.name}: replay over target, max deviation {report.max_deviation:.2e} {u['length']}")
    _legend(ax)
    return artists


def _time_axes(ax, ylabel: str, unit: str) -> None:
    ax.set_xlabel(f"t ({axis_units(unit)['time']})")
    ax.set_ylabel(ylabel)
    _legend(ax)


def _switches(ax, trace: FigureTrace):
    return [ax.axvline(t, color="C3", lw=0.5, alpha=0.5, label="section starts (at rest)" if i == 0 else None)
            for i, t in enumerate(trace.start_times[1:])]


def plot_controls(trace: FigureTrace, report: VerificationReport, ax=None, unit: str = "model"):
    """a(t) and b(t) with section switches marked."""
    ax = _ax(ax)
    rep = report.replay
    artists = (ax.plot(rep.t, rep.controls[0], label="a(t), along the blade")
               + ax.plot(rep.t, rep.controls[1], label="b(t), left of the blade"))
    artists += _switches(ax, trace)
    _time_axes(ax, f"mass position, body frame ({axis_units(unit)['length']})", unit)
    ax.set_title("controls: position of the moving mass relative to the blade")
    return artists


def plot_speed(trace: FigureTrace, report: VerificationReport, ax=None, unit: str = "model"):
    """Speed along the blade xi2(t), section starts (cusps, rests) marked."""
    ax = _ax(ax)
    rep = report.replay
    _, xi2, _ = rep.velocities(trace.params)
    artists = ax.plot(rep.t, xi2, label=r"$\xi^2$, speed along the blade")
    starts = np.array(trace.start_times + (trace.duration,))
    artists.append(ax.plot(starts, np.zeros_like(starts), "o", color="C3", ms=3,
                           label="section starts and ends (at rest)")[0])
    _time_axes(ax, rf"speed along the blade $\xi^2$ ({axis_units(unit)['speed']})", unit)
    ax.set_title("speed of the blade")
    return artists


def plot_mass_path(trace: FigureTrace, report: VerificationReport, ax=None, unit: str = "model"):
    """Path of the moving mass in the body frame, one colour per section (colour bar), contact point marked.

    Sections are coloured in skating order along the ``viridis`` colour map; a colour bar below
    the axes says which colour is which section. Each section's start (open circle) and end
    (cross) are marked, and the blade's contact point (``+``, the origin of the body frame).

    Returns
    -------
    list
        The lines drawn, then the :class:`matplotlib.colorbar.Colorbar` (its axes is added to
        ``ax.figure``).
    """
    import matplotlib as mpl

    length = axis_units(unit)["length"]
    ax = _ax(ax)
    rep = report.replay
    sections = np.unique(rep.section)
    n = max(len(sections), 1)
    cmap = mpl.colormaps["viridis"]
    if n > cmap.N:  # a colour a section: BoundaryNorm needs at least as many colours as sections
        cmap = cmap.resampled(n)
    norm = mpl.colors.BoundaryNorm(np.arange(0.5, n + 1.5), cmap.N)
    artists = []
    starts, ends = [], []
    for k, si in enumerate(sections, start=1):
        m = rep.section == si
        a, b = rep.controls[0, m], rep.controls[1, m]
        artists += ax.plot(a, b, lw=0.9, color=cmap(norm(k)))
        if a.size:
            starts.append((a[0], b[0]))
            ends.append((a[-1], b[-1]))
    if starts:
        artists += ax.plot(*np.array(starts).T, "o", mfc="none", mec="k", ms=6, ls="none",
                           label="section starts (at rest)")
        artists += ax.plot(*np.array(ends).T, "x", color="C3", ms=6, ls="none", label="section ends (at rest)")
    artists += ax.plot([0], [0], "k+", ms=12, mew=1.5, ls="none", label="contact point of the blade")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel(f"a, along the blade ({length})")
    ax.set_ylabel(f"b, left of the blade ({length})")
    ax.set_title("mass path in the body frame")
    sm = mpl.cm.ScalarMappable(norm=norm, cmap=cmap)
    cbar = ax.figure.colorbar(sm, ax=ax, location="bottom", shrink=0.8, pad=0.02, aspect=40)
    cbar.set_label(f"section, in skating order (1 to {n})")
    cbar.set_ticks(_ticks(n))
    _legend(ax)
    return artists + [cbar]


def _ticks(n: int) -> list[int]:
    """At most about eight whole-number ticks from 1 to ``n``, both ends included."""
    step = max(1, int(np.ceil(n / 8)))
    ticks = list(range(1, n + 1, step))
    if ticks[-1] != n:
        ticks.append(n)
    return ticks


def plot_energies(trace: FigureTrace, report: VerificationReport, ax=None, unit: str = "model"):
    """Kinetic energies of the skate and of the moving mass."""
    ax = _ax(ax)
    rep = report.replay
    xi1, xi2, _ = rep.velocities(trace.params)
    ks = skate_energy(trace.params, xi1, xi2)
    km = mass_energy(trace.params, xi1, xi2, *rep.controls)
    artists = ax.plot(rep.t, ks, label="skate") + ax.plot(rep.t, km, label="moving mass")
    _time_axes(ax, f"kinetic energy ({axis_units(unit)['energy']})", unit)
    ax.set_title("kinetic energies")
    return artists


def _thinned(report: VerificationReport, rows: int) -> VerificationReport:
    """``report`` with its replay cut to about ``rows`` rows spread evenly, keeping the first and last
    row of every section (where the plots mark the rests): the memory a plot takes is then bounded."""
    from dataclasses import replace

    rep = report.replay
    n = rep.t.size
    if n <= rows:
        return report
    ends = np.flatnonzero(np.diff(rep.section) != 0)
    keep = np.unique(np.concatenate([np.linspace(0, n - 1, rows).round().astype(int), ends, ends + 1]))
    return replace(report, replay=rep.take(keep))


#: The plots :func:`save_all` writes: file name (without ``.png``), function and size in inches.
_SAVED = (("figure", plot_figure, (10, 8)), ("controls", plot_controls, (12, 4)), ("speed", plot_speed, (12, 4)),
          ("mass_path", plot_mass_path, (9.5, 7.5)), ("energies", plot_energies, (12, 4)))


def _ready_to_plot() -> None:
    """Import what drawing a plot needs (matplotlib's pyplot, on its non-interactive Agg backend)."""
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot  # noqa: F401


def _png(shared: tuple, name: str) -> bytes:
    """The plot ``name`` of :data:`_SAVED` drawn from ``shared = (trace, report, unit)``, as PNG bytes."""
    import io

    _ready_to_plot()
    import matplotlib.pyplot as plt

    trace, report, unit = shared
    fn, size = next((fn, size) for plot, fn, size in _SAVED if plot == name)
    fig, ax = plt.subplots(figsize=size, layout="constrained")
    try:
        fn(trace, report, ax=ax, unit=unit)
        buf = io.BytesIO()
        fig.savefig(buf, format="png", dpi=110)
    finally:
        plt.close(fig)
    return buf.getvalue()


class PlotsAhead:
    """The plots of :func:`save_all`, drawn in children made ready (matplotlib imported) before the trace is known.

    The command line makes one as the run begins: its two children import matplotlib while the
    figure is traced, on a core the tracing leaves idle at times; :meth:`start` hands them the
    trace and its replay, they draw while this process writes the other files, and :meth:`write`
    collects the images. Where it has no children (``workers=1``, forking not safe), or one fails,
    the plots are drawn as :func:`save_all` draws them, with the same images either way. Use it
    as a context manager: leaving the block ends children still waiting or drawing.
    """

    def __init__(self, workers: int | None = None, *, ahead: bool = True):
        from ..processes import Primed

        # ahead=False: no children now; the plots are drawn by map_forked once started
        self._primed = Primed(_ready_to_plot, children=2 if ahead else 0, workers=workers)

    def start(self, trace: FigureTrace, report: VerificationReport, *, unit: str = "model") -> None:
        """Begin drawing the plots of ``trace`` and ``report`` (see :func:`save_all`).

        Raises
        ------
        ValueError
            If ``unit`` is not one of :func:`axis_units`' (before anything is drawn).
        """
        axis_units(unit)  # a bad unit fails before anything is drawn
        if not self._primed.children:
            _ready_to_plot()  # here, once, before map_forked's children are forked (they share it)
        shared = (trace, _thinned(report, PLOT_ROWS), unit)
        self._primed.submit(_png, shared, [name for name, _fn, _size in _SAVED])

    def write(self, out) -> list:
        """Write the plots begun by :meth:`start` into the folder ``out`` (it must exist); their paths."""
        from pathlib import Path

        from .files import atomic_write

        written = []
        # written here, so that the output folder records every file
        for (name, _fn, _size), png in zip(_SAVED, self._primed.results()):
            atomic_write(Path(out) / f"{name}.png", png)
            written.append(Path(out) / f"{name}.png")
        return written

    def __enter__(self) -> "PlotsAhead":
        return self

    def __exit__(self, *exc) -> None:
        self._primed.__exit__(*exc)


def save_all(trace: FigureTrace, report: VerificationReport, out, *, unit: str = "model",
             workers: int | None = None) -> list:
    """Write figure.png, controls.png, speed.png, mass_path.png and energies.png into ``out``.

    Parameters
    ----------
    trace, report
        The traced figure and its verification (the replay is what is drawn).
    out : str or Path
        Folder (it must exist).
    unit : {"model", "m"}
        The figure's unit of length, for the axis labels (see :func:`axis_units`).
    workers : int, optional
        Processes to draw them in (side by side in forked ones: half the time on two cores).

    Returns
    -------
    list of Path
        The files written. :class:`PlotsAhead` draws the same images, begun earlier.
    """
    with PlotsAhead(workers, ahead=False) as plots:
        plots.start(trace, report, unit=unit)
        return plots.write(out)


def plot_fit(drawing, fit, ax=None, *, exact=None, unit: str = "model"):
    """The arc fit (and, given ``exact``, the curvature splines) over the input drawing, in the plane.

    Parameters
    ----------
    drawing : Drawing
        Drawn thick, light grey.
    fit : DrawingFit
        Arcs in blue, lines in green, knots (where each arc or line starts) as black dots, corners
        (runs that start with a turn of travel direction) as red triangles, and a red circle where
        the largest sampled distance was found.
    ax : matplotlib.axes.Axes, optional
    exact : ExactDrawingFit, optional
        Exact mode's curvature splines (spirals, arcs and lines), dashed magenta, and a magenta
        square where their largest sampled distance was found. At the scale of the drawing they lie
        on the arc fit; :func:`plot_fit_curvature` shows them apart.
    unit : {"model", "m"}
        The drawing's unit of length, for the axis labels.

    Returns
    -------
    list
        The artists drawn. Those of the curvature splines have the gid ``"exact"``.
    """
    length = axis_units(unit)["length"]
    ax = _ax(ax)
    artists = []
    first = set()

    def label(name: str) -> str | None:
        if name in first:
            return None
        first.add(name)
        return name

    for path in drawing.paths:
        pts = path.points(200)
        artists += ax.plot(pts[0], pts[1], "-", color="0.8", lw=5, solid_capstyle="round", label=label("drawing"))
    knots, corners = [], []
    for pf in fit.paths:
        for run in pf.runs:
            poses = run.poses()
            for pose, seg in zip(poses, run.segments):
                xy = segment_points(pose, seg, 60)
                if seg.curvature == 0.0:
                    artists += ax.plot(xy[0], xy[1], "-", color="C2", lw=1.4, label=label("fitted lines"))
                else:
                    artists += ax.plot(xy[0], xy[1], "-", color="C0", lw=1.2, label=label("fitted arcs"))
            knots += [(p.x, p.y) for p in poses]
            if run.corner is not None:
                corners.append((run.start.x, run.start.y))
    if knots:
        artists += ax.plot(*np.array(knots).T, ".", color="k", ms=3, ls="none", label="knots of the arc fit")
    if corners:
        artists += ax.plot(*np.array(corners).T, "^", color="C3", ms=6, ls="none", label="corners (cusps)")
    worst = [pf.where for pf in fit.paths if pf.where is not None and pf.hausdorff == fit.hausdorff]
    if worst:
        artists += ax.plot([worst[0].x], [worst[0].y], "o", mfc="none", mec="red", ms=11, ls="none",
                           label=f"largest distance, arc fit\n(<= {fit.hausdorff:.2g} {length}, certified)")
    title = f"{fit.n_arcs} arcs, {fit.n_lines} lines within {fit.hausdorff:.3g} {length} (certified Hausdorff distance)"
    if exact is not None:
        artists += _plot_exact(ax, exact, length)
        title += (f"\nexact mode: {exact.n_spirals} spirals, {exact.n_arcs} arcs, {exact.n_lines} lines "
                  f"within {exact.deviation:.3g} {length} (measured)")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel(f"x ({length})")
    ax.set_ylabel(f"y ({length})")
    ax.set_title(title, fontsize=10)
    _legend(ax)
    return artists


def _plot_exact(ax, exact, length: str) -> list:
    """Exact mode's pieces and its worst sampled point (gid ``"exact"``)."""
    artists = []
    for pf in exact.paths:
        for run in pf.runs:
            for pose, piece in zip(run.poses(), run.pieces):
                xy = segment_points(pose, piece, 60)
                artists += ax.plot(xy[0], xy[1], "--", color="m", lw=1.0, gid="exact",
                                   label="curvature splines (exact mode)" if not artists else None)
    worst = [pf.where for pf in exact.paths if pf.where is not None and pf.deviation == exact.deviation]
    if worst:
        artists += ax.plot([worst[0].x], [worst[0].y], "s", mfc="none", mec="m", ms=11, ls="none", gid="exact",
                           label=f"largest distance, exact mode\n({exact.deviation:.2g} {length}, measured)")
    return artists


def _curvature_steps(pieces, s0: float, n: int) -> tuple[np.ndarray, np.ndarray, list[float]]:
    """Arc length and curvature along consecutive pieces from ``s0`` (NaN between pieces), and their starts."""
    ss, ks, starts = [], [], []
    for piece in pieces:
        sigma = np.linspace(0.0, piece.length, n if not getattr(piece, "constant", True) else 2)
        ss += [s0 + sigma, [np.nan]]
        ks += [piece.curvature_at(sigma), [np.nan]]
        starts.append(s0)
        s0 += piece.length
    if not ss:
        return np.empty(0), np.empty(0), starts
    return np.concatenate(ss), np.concatenate(ks), starts


def plot_fit_curvature(fit, ax=None, *, exact=None, unit: str = "model"):
    """Curvature against arc length: the arc fit's steps and, given ``exact``, the curvature splines.

    Paths and their runs follow each other along the arc-length axis (each run from the arc length
    of the source curve where it starts); dotted grey lines mark where a run starts at a corner
    or a new path begins.

    Parameters
    ----------
    fit : DrawingFit
        Its arcs and lines: constant curvature per piece (blue), knots as black dots.
    ax : matplotlib.axes.Axes, optional
    exact : ExactDrawingFit, optional
        Exact mode's pieces, whose curvature is a cubic of arc length (magenta, gid ``"exact"``).
    unit : {"model", "m"}
        The drawing's unit of length, for the axis labels.

    Returns
    -------
    list
        The artists drawn.
    """
    length = axis_units(unit)["length"]
    ax = _ax(ax)
    artists = []
    knot_s, knot_k, breaks = [], [], set()
    exact_paths = list(exact.paths) if exact is not None else []
    s_path, drawn_exact = 0.0, False
    for i, pf in enumerate(fit.paths):
        s_run = s_path
        for run in pf.runs:
            if s_run > 0.0:
                breaks.add(s_run)
            s, k, starts = _curvature_steps(run.segments, s_run, 2)
            artists += ax.plot(s, k, "-", color="C0", lw=1.4, label="arc fit" if not knot_s else None)
            knot_s += starts
            knot_k += [seg.curvature for seg in run.segments]
            s_run += run.curve_length
        # exact mode splits the path at its own corners: its runs are laid out by their own lengths
        s_ex = s_path
        for run in exact_paths[i].runs if i < len(exact_paths) else ():
            if s_ex > 0.0:
                breaks.add(s_ex)
            s, k, _ = _curvature_steps(run.pieces, s_ex, 40)
            artists += ax.plot(s, k, "-", color="m", lw=1.0, gid="exact",
                               label=None if drawn_exact else "curvature splines (exact mode)")
            drawn_exact = True
            s_ex += run.curve_length
        s_path = s_run
    if knot_s:
        artists += ax.plot(knot_s, knot_k, ".", color="k", ms=3, ls="none", label="knots of the arc fit")
    shown: list[float] = []
    for b in sorted(breaks):  # arc and exact runs start at the same corners, up to rounding
        if shown and b - shown[-1] <= 1e-9 * max(s_path, 1.0):
            continue
        artists.append(ax.axvline(b, color="0.6", ls=":", lw=0.8, label=None if shown else "corner or new path"))
        shown.append(b)
    ax.axhline(0.0, color="0.85", lw=0.6, zorder=0)
    ax.set_xlabel(f"arc length along the drawing ({length})")
    ax.set_ylabel(f"curvature ({axis_units(unit)['curvature']})")
    ax.set_title("curvature of the pieces", fontsize=10)
    _legend(ax)
    return artists


def fit_figure(drawing, fit, *, exact=None, unit: str = "model"):
    """fit.png's figure: :func:`plot_fit` above :func:`plot_fit_curvature`.

    Returns
    -------
    matplotlib.figure.Figure
        Not registered with pyplot (nothing to close); two axes, plus their legends.
    """
    from matplotlib.figure import Figure

    axis_units(unit)  # a bad unit fails before anything is drawn
    fig = Figure(figsize=(10, 11), layout="constrained")
    ax_xy, ax_k = fig.subplots(2, 1, height_ratios=(3, 1.2))
    plot_fit(drawing, fit, ax_xy, exact=exact, unit=unit)
    plot_fit_curvature(fit, ax_k, exact=exact, unit=unit)
    return fig


def tradeoff_figure(sweep, *, unit: str = "model"):
    """tradeoff.png's figure: peak force, effort and duration against the reach, today's manoeuvres as reference lines.

    ``sweep`` is a :class:`~skatetrace.pipeline.ReachSweep`. Reaches that were not planned and
    verified are marked with crosses on the axis; the reference (the launch-glide-stop
    manoeuvres, whose mass goes ``sweep.reference.distance`` from the blade) is a dashed line.

    Returns
    -------
    matplotlib.figure.Figure
        Not registered with pyplot; three axes sharing the reach.
    """
    from matplotlib.figure import Figure

    u = axis_units(unit)
    force = "N" if unit == "m" else "model force"
    fig = Figure(figsize=(7.5, 9), layout="constrained")
    axes = fig.subplots(3, 1, sharex=True)
    reach = np.array([p.reach for p in sweep.points], dtype=float)
    ok = np.array([p.success for p in sweep.points], dtype=bool)
    rows = (("peak_force", f"peak force on the mass ({force})"),
            ("effort", "effort: ∫ |force|² dt" + (" (N² s)" if unit == "m" else " (model units)")),
            ("duration", f"duration ({u['time']})"))
    for ax, (key, label) in zip(axes, rows):
        _ax(ax)
        y = np.array([getattr(p, key) for p in sweep.points], dtype=float)
        ax.plot(reach[ok], y[ok], "o-", color="#ef7d18", label="planned within the reach")
        if np.any(~ok):
            ax.plot(reach[~ok], np.zeros(int(np.sum(~ok))), "x", color="#c0392b", ms=9, clip_on=False,
                    label="not planned / not verified")
        ref = getattr(sweep.reference, key)
        if np.isfinite(ref):
            ax.axhline(ref, ls="--", color="0.4", lw=1.0,
                       label=f"launch-glide-stop (mass {sweep.reference.distance:.3g} {u['length']} out)")
        ax.set_ylabel(label)
        ax.set_ylim(bottom=0.0)
    _legend(axes[0])
    axes[-1].set_xlabel(f"reach: largest distance of the mass from the blade ({u['length']})")
    axes[0].set_title(f"{sweep.figure}: the cost of a smaller reach (least {sweep.objective})")
    return fig


def _paths(ax, paths, colour: str, label: str, far: tuple[float, float, float]) -> None:
    """Every kept trial's blade path, thin and see-through; points far off the figure are left out."""
    cx, cy, reach = far
    labelled = False
    for path in paths:
        if path is None:
            continue
        x, y = path[0], path[1]
        with np.errstate(invalid="ignore"):
            off = ~(np.abs(x - cx) + np.abs(y - cy) <= reach)  # NaN too: drawing stops where the replay diverged
        lines = ax.plot(np.where(off, np.nan, x), np.where(off, np.nan, y), "-", color=colour, lw=0.6, alpha=0.35)
        if lines and not labelled:
            lines[0].set_label(label)
            labelled = True


def robustness_figure(report, sections, *, name: str = "", unit: str = "model"):
    """robustness.png's figure: the target figure and the replayed blade paths of both families over it.

    Parameters
    ----------
    report : RobustnessReport
        A study of :func:`skatetrace.feedback.robustness.robustness`; its kept paths are drawn, the
        open loop in red, the closed loop in blue.
    sections : sequence of Section
        The figure's sections (the target, dashed grey).
    name, unit : str
        The figure's name for the title; its unit of length (see :func:`axis_units`).

    Returns
    -------
    matplotlib.figure.Figure
        Not registered with pyplot. The axes show the figure with a margin of a fifth of its size:
        paths that stray further leave the frame.
    """
    from matplotlib.figure import Figure

    from ..feedback.robustness import quantiles

    u = axis_units(unit)
    pieces = [p for s in sections for p in s.pieces]
    xy = np.hstack([segment_points(p.start, p.segment, 200) for p in pieces])
    size = report.figure_size
    pad = 0.2 * size
    x0, x1, y0, y1 = xy[0].min() - pad, xy[0].max() + pad, xy[1].min() - pad, xy[1].max() + pad
    # the frame takes the figure's own shape; title above, legend below
    fig = Figure(figsize=(9.0, float(np.clip(8.0 * (y1 - y0) / (x1 - x0), 3.5, 9.0)) + 2.2), layout="constrained")
    ax = fig.subplots()
    for i, p in enumerate(pieces):
        pts = segment_points(p.start, p.segment, 200)
        ax.plot(pts[0], pts[1], "--", color="0.55", lw=2.5, label="target figure" if i == 0 else None)
    cx, cy = 0.5 * (xy[0].min() + xy[0].max()), 0.5 * (xy[1].min() + xy[1].max())
    far = (cx, cy, 1e3 * size)
    for fam, colour, what in ((report.open_loop, "C3", "open loop"), (report.closed_loop, "C0", "closed loop")):
        p95 = quantiles(fam.deviation)["p95"]
        shown = min(fam.trials, max((p.shape[2] for p in fam.paths if p is not None), default=0))
        label = (f"{what}: {shown} of {fam.trials} trials, p95 deviation {p95:.3g} {u['length']}, "
                 f"{fam.diverged} diverged")
        _paths(ax, fam.paths, colour, label, far)
    starts = np.array([(s.pieces[0].start.x, s.pieces[0].start.y) for s in sections])
    ax.plot(starts[:, 0], starts[:, 1], "o", color="k", ms=3, label="rests (section starts)")
    ax.set_xlim(x0, x1)
    ax.set_ylim(y0, y1)
    ax.set_aspect("equal", adjustable="box")
    ax.set_xlabel(f"x ({u['length']})")
    ax.set_ylabel(f"y ({u['length']})")
    pert = report.perturbation
    ax.set_title(f"{name}: {pert.trials} perturbed sleighs, open loop against closed loop\n"
                 f"M, m, I each within ±{100 * pert.param_error:.3g} %; each curve starts {pert.position_error:.3g} "
                 f"{u['length']} and ±{np.degrees(pert.angle_error):.3g}° off; delay {pert.delay:.3g} {u['time']}; "
                 f"noise {pert.noise:.3g} {u['length']}", fontsize=10)
    fig.legend(loc="outside lower center", fontsize=8, ncols=2)
    return fig

