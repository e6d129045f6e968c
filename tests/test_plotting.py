"""Plots: every axis names its quantity and unit, legends stand clear of the data, fit.png shows both fits.

The helpers :func:`axes_without_units` and :func:`legend_overlaps` are shared with
``test_paper_figures.py``.
"""

import re
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402
from matplotlib.backends.backend_agg import FigureCanvasAgg  # noqa: E402
from matplotlib.colors import to_rgba  # noqa: E402

from skatetrace import pattern, trace_figure, verify  # noqa: E402
from skatetrace.outputs import plotting  # noqa: E402

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"

# A unit closes the label: "x (m)", "t (model time)", "speed [m/s]".
_UNIT = re.compile(r"(\([^()]*\S[^()]*\)|\[[^\[\]]*\S[^\[\]]*\])\s*$")


def _is_colorbar(ax) -> bool:
    return getattr(ax, "_colorbar", None) is not None


def axes_without_units(fig) -> list:
    """``(axes index, "x" or "y", label)`` of every axis label that does not end with a unit in ( ) or [ ].

    A colour bar has one meaningful axis; its label must only be non-empty.
    """
    bad = []
    for i, ax in enumerate(fig.axes):
        if _is_colorbar(ax):
            label = ax.get_xlabel() or ax.get_ylabel()
            if not label.strip():
                bad.append((i, "colorbar", label))
            continue
        for which, label in (("x", ax.get_xlabel()), ("y", ax.get_ylabel())):
            if not _UNIT.search(label):
                bad.append((i, which, label))
    return bad


def _display_points(artist, step: float = 2.0) -> np.ndarray:
    """Display coordinates of a line's vertices and of the segments between them (every ``step`` px)."""
    xy = np.asarray(artist.get_xydata(), float)
    if xy.size == 0:
        return np.empty((0, 2))
    pts = artist.get_transform().transform(xy)
    if artist.get_linestyle() in ("None", "none", "", " "):
        return pts[np.isfinite(pts).all(axis=1)]
    out = [pts[np.isfinite(pts).all(axis=1)]]
    a, b = pts[:-1], pts[1:]
    ok = np.isfinite(a).all(axis=1) & np.isfinite(b).all(axis=1)
    a, b = a[ok], b[ok]
    n = np.ceil(np.hypot(*(b - a).T) / step).astype(int)
    for k in range(1, int(n.max(initial=0))):
        m = n > k
        out.append(a[m] + (b[m] - a[m]) * (k / n[m])[:, None])
    return np.concatenate(out)


def legend_overlaps(fig) -> list:
    """``(legend index, number of data points)`` for every legend that covers drawn data.

    The figure is rendered; the data are every line's vertices and segments in display
    coordinates, kept where they are drawn (inside their axes); a legend covers data when one
    such point falls inside its window extent.
    """
    if type(fig.canvas).__name__ == "FigureCanvasBase":
        FigureCanvasAgg(fig)
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    points = []
    for ax in fig.axes:
        if _is_colorbar(ax):
            continue
        box = ax.get_window_extent(renderer)
        for line in ax.lines:
            p = _display_points(line)
            inside = (p[:, 0] >= box.x0) & (p[:, 0] <= box.x1) & (p[:, 1] >= box.y0) & (p[:, 1] <= box.y1)
            points.append(p[inside])
    points = np.concatenate(points) if points else np.empty((0, 2))
    legends = [ax.get_legend() for ax in fig.axes if ax.get_legend() is not None] + list(fig.legends)
    bad = []
    for i, leg in enumerate(legends):
        lb = leg.get_window_extent(renderer)
        hit = ((points[:, 0] > lb.x0) & (points[:, 0] < lb.x1) & (points[:, 1] > lb.y0) & (points[:, 1] < lb.y1))
        if hit.any():
            bad.append((i, int(hit.sum())))
    return bad


@pytest.fixture(scope="module")
def flower():
    """The double flower traced and replayed (32 sections; well under a second)."""
    tr = trace_figure(pattern("double-flower"))
    return tr, verify(tr)


@pytest.fixture(scope="module")
def three_turn():
    """The three turn at 6 m, arc fit at 1 cm and exact mode at 1 mm (it has corners; under a second)."""
    from skatetrace.drawings.sources import resolve

    return resolve(str(EXAMPLES / "three-turn.svg"), size="6m", tol="1cm", exact="1mm")


_PLOTS = (plotting.plot_figure, plotting.plot_controls, plotting.plot_speed, plotting.plot_mass_path,
          plotting.plot_energies)


def test_the_helpers_can_fail():
    fig, ax = plt.subplots()
    ax.plot([0, 1], [0, 1], label="data")
    ax.set_xlabel("x")
    ax.set_ylabel("y (m)")
    ax.legend(loc="center")  # right on the diagonal
    assert axes_without_units(fig) == [(0, "x", "x")]
    assert legend_overlaps(fig) and legend_overlaps(fig)[0][1] > 0
    ax.get_legend().remove()
    ax.legend(loc="upper left", bbox_to_anchor=(1.02, 1.0))
    assert legend_overlaps(fig) == []
    ax.set_xlabel("x (model length)")
    ax.set_ylabel("y (model")  # unbalanced: not a unit
    assert axes_without_units(fig) == [(0, "y", "y (model")]
    plt.close(fig)


@pytest.mark.parametrize("unit, length, time, energy, speed",
                         [("model", "model length", "model time", "model energy", "model length/time"),
                          ("m", "m", "s", "J", "m/s")])
def test_every_axis_has_its_unit_and_legends_stand_clear(flower, unit, length, time, energy, speed):
    tr, rep = flower
    expected_y = {plotting.plot_figure: length, plotting.plot_controls: length, plotting.plot_speed: speed,
                  plotting.plot_mass_path: length, plotting.plot_energies: energy}
    for fn in _PLOTS:
        fig, ax = plt.subplots(figsize=(9, 6), layout="constrained")
        artists = fn(tr, rep, ax=ax, unit=unit)
        assert len(artists) >= 2 and len(ax.lines) >= 2, fn.__name__
        assert axes_without_units(fig) == [], fn.__name__
        assert ax.get_ylabel().endswith(f"({expected_y[fn]})"), (fn.__name__, ax.get_ylabel())
        x_unit = length if fn in (plotting.plot_figure, plotting.plot_mass_path) else time
        assert ax.get_xlabel().endswith(f"({x_unit})"), (fn.__name__, ax.get_xlabel())
        assert ax.get_legend() is not None and len(ax.get_legend().get_texts()) >= 2, fn.__name__
        assert legend_overlaps(fig) == [], fn.__name__
        plt.close(fig)


def test_mass_path_colours_sections_in_order_with_a_colour_bar(flower):
    tr, rep = flower
    n = len(np.unique(rep.replay.section))
    assert n == 32
    fig, ax = plt.subplots(figsize=(9, 7), layout="constrained")
    artists = plotting.plot_mass_path(tr, rep, ax=ax, unit="m")
    cbar = artists[-1]
    assert cbar.ax in fig.axes and "section" in cbar.ax.get_xlabel()
    assert cbar.norm.vmin == pytest.approx(0.5) and cbar.norm.vmax == pytest.approx(n + 0.5)
    ticks = list(cbar.get_ticks())
    assert ticks[0] == 1 and ticks[-1] == n and len(ticks) <= 10
    # one line per section, each in the colour bar's colour for its place in the order
    paths = [ln for ln in ax.lines if ln.get_linestyle() == "-"]
    assert len(paths) == n
    assert [to_rgba(ln.get_color()) for ln in paths] == [to_rgba(cbar.cmap(cbar.norm(k))) for k in range(1, n + 1)]
    assert len({to_rgba(ln.get_color()) for ln in paths}) == n
    # the legend names the markers, not the 32 sections
    texts = [t.get_text() for t in ax.get_legend().get_texts()]
    assert len(texts) == 3 and any("start" in t for t in texts) and any("contact point" in t for t in texts)
    assert legend_overlaps(fig) == []
    plt.close(fig)


def test_save_all_writes_five_pngs_and_checks_its_unit(flower, tmp_path):
    tr, rep = flower
    written = plotting.save_all(tr, rep, tmp_path, unit="m")
    assert [p.name for p in written] == ["figure.png", "controls.png", "speed.png", "mass_path.png", "energies.png"]
    assert all(p.stat().st_size > 5000 and p.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" for p in written)
    with pytest.raises(ValueError, match="unit must be 'model'.*or 'm'.*got 'km'"):
        plotting.save_all(tr, rep, tmp_path / "x", unit="km")
    assert not (tmp_path / "x").exists()


def test_plots_drawn_ahead_in_primed_children_are_save_alls_images(flower, tmp_path, forking):
    # the command line's plots: children made ready while the figure is traced draw them; the same
    # images as save_all's, written and recorded by this process
    from skatetrace.outputs.files import record_writes

    tr, rep = flower
    (tmp_path / "a").mkdir()
    (tmp_path / "b").mkdir()
    expected = plotting.save_all(tr, rep, tmp_path / "a", unit="m")
    seen = []
    with plotting.PlotsAhead(workers=2) as plots:
        assert plots._primed.children == 2
        with pytest.raises(ValueError, match="unit must be"):
            plots.start(tr, rep, unit="km")  # refused before anything is handed to the children
        plots.start(tr, rep, unit="m")
        with record_writes(seen.append):
            written = plots.write(tmp_path / "b")
    assert [p.name for p in seen] == [p.name for p in written] == [p.name for p in expected]
    assert [p.read_bytes() for p in written] == [p.read_bytes() for p in expected]


def test_the_plots_draw_a_bounded_number_of_rows_and_keep_every_rest(flower):
    """Issue 19: a long figure's replay is cut to about PLOT_ROWS rows before it is drawn, keeping the
    first and last row of every section (the rests the plots mark)."""
    _, rep = flower
    full = rep.replay
    assert full.t.size > 1000
    cut = plotting._thinned(rep, 500)
    r = cut.replay
    sections = np.unique(full.section).size
    assert r.t.size <= 500 + 2 * sections
    assert np.all(np.diff(r.t) >= 0)
    for si in np.unique(full.section):
        rows = full.t[full.section == si]
        kept = r.t[r.section == si]
        assert kept[0] == rows[0] and kept[-1] == rows[-1]
    assert cut.max_deviation == rep.max_deviation  # only the rows drawn change
    assert plotting._thinned(rep, full.t.size) is rep


def _gids(ax, gid):
    return [ln for ln in ax.lines if ln.get_gid() == gid]


def test_fit_figure_labels_legends_and_exact_splines(three_turn):
    res = three_turn
    ex, fit = res.exact, res.fit
    assert ex is not None and len(ex.paths[0].runs) > len(fit.paths[0].runs)  # exact mode has its own corners
    fig = plotting.fit_figure(res.drawing, fit, exact=ex, unit=res.unit)
    xy, curv = fig.axes
    assert axes_without_units(fig) == []
    assert xy.get_xlabel() == "x (m)" and curv.get_ylabel() == "curvature (1/m)"
    assert legend_overlaps(fig) == []
    labels = [t.get_text() for t in xy.get_legend().get_texts()]
    for needle in ("drawing", "fitted arcs", "knots of the arc fit", "corners", "largest distance, arc fit",
                   "curvature splines (exact mode)", "largest distance, exact mode"):
        assert any(t.startswith(needle) for t in labels), needle
    # every exact piece drawn in the plane (plus the worst point), every exact run in the curvature panel
    n_pieces = sum(len(r.pieces) for pf in ex.paths for r in pf.runs)
    assert len(_gids(xy, "exact")) == n_pieces + 1
    assert len(_gids(curv, "exact")) == sum(len(pf.runs) for pf in ex.paths)
    # the exact curves start on their pieces' start poses, in the plane and in curvature
    first = ex.paths[0].runs[0]
    line = _gids(xy, "exact")[0]
    assert np.allclose([line.get_xdata()[0], line.get_ydata()[0]], [first.start.x, first.start.y])
    line = _gids(curv, "exact")[0]
    assert line.get_ydata()[0] == pytest.approx(first.pieces[0].curvature_at(0.0))
    # the arc fit's curvature is a step per segment at the segment's curvature
    arcs = [ln for ln in curv.lines if ln.get_label() == "arc fit"]
    assert len(arcs) == 1
    k = arcs[0].get_ydata()
    segs = [s.curvature for pf in fit.paths for r in pf.runs for s in r.segments]
    assert np.allclose(k[np.isfinite(k)][::2], segs[: len(k[np.isfinite(k)][::2])])

    # without exact mode: nothing of it is drawn, and model units are named as such
    fig = plotting.fit_figure(res.drawing, fit, unit="model")
    assert all(not _gids(ax, "exact") for ax in fig.axes)
    assert fig.axes[0].get_ylabel() == "y (model length)" and axes_without_units(fig) == []
    assert not any("exact" in t.get_text() for t in fig.axes[0].get_legend().get_texts())
    with pytest.raises(ValueError, match="unit must be"):
        plotting.fit_figure(res.drawing, fit, unit="metres")


def test_plot_fit_alone_takes_an_axes_and_returns_its_artists(three_turn):
    res = three_turn
    fig, ax = plt.subplots()
    artists = plotting.plot_fit(res.drawing, res.fit, ax, unit=res.unit)
    assert artists and all(a.axes is ax for a in artists)
    assert ax.get_xlabel() == "x (m)" and ax.get_ylabel() == "y (m)"
    plt.close(fig)


def test_trace_passes_the_figure_unit_to_the_plots(tmp_path, monkeypatch, capsys):
    # A circle drawn in an SVG, scaled to 4 m: the figure is in metres, so the plots must say m and s.
    from skatetrace.cli import main

    seen = {}

    def fake_start(self, trace, report, *, unit="model"):
        seen["unit"] = unit
        self._primed.submit(lambda shared, item: b"", None, [])  # no images: write() writes none

    monkeypatch.setattr(plotting.PlotsAhead, "start", fake_start)
    svg = tmp_path / "circle.svg"
    svg.write_text('<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 100 100"><circle cx="50" cy="50" r="40"/>'
                   '</svg>')
    main(["trace", str(svg), "--size", "4m", "--tol", "1mm", "--reach", "none", "--out", str(tmp_path / "o"),
          "--no-viewer"])
    assert seen == {"unit": "m"}
    assert (tmp_path / "o" / "fit.png").stat().st_size > 5000


def test_mass_path_colours_more_sections_than_the_colour_map_has_colours():
    # a drawing of 416 lines joined at corners (hicolor's gvim icon at 6 m) crashed the command line
    # after tracing it: BoundaryNorm had 416 bins for viridis's 256 colours
    from types import SimpleNamespace

    n = 416
    section = np.repeat(np.arange(n), 3)
    rng = np.random.default_rng(0)
    report = SimpleNamespace(replay=SimpleNamespace(section=section, controls=rng.normal(size=(4, section.size))))
    fig, ax = plt.subplots(figsize=(9, 7), layout="constrained")
    artists = plotting.plot_mass_path(None, report, ax=ax, unit="m")
    cbar = artists[-1]
    paths = [ln for ln in ax.lines if ln.get_linestyle() == "-"]
    assert len(paths) == n and cbar.norm.vmax == pytest.approx(n + 0.5)
    colours = [to_rgba(ln.get_color()) for ln in paths]
    assert colours == [to_rgba(cbar.cmap(cbar.norm(k))) for k in range(1, n + 1)]
    assert len(set(colours)) > 200  # the colour map's own colours, spread over the sections in order
    ticks = list(cbar.get_ticks())
    assert ticks[0] == 1 and ticks[-1] == n
    plt.close(fig)
