import matplotlib

matplotlib.use("Agg")
import dataclasses  # noqa: E402
import io  # noqa: E402
import math  # noqa: E402
import types  # noqa: E402

import numpy as np  # noqa: E402
import pytest  # noqa: E402
from matplotlib.colors import to_rgba  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402

from skatetrace.figures.geometry import Pose  # noqa: E402
from skatetrace.dynamics.model import SleighParams, mass_energy  # noqa: E402
from skatetrace.paper import evaluate_exact_arc, evaluate_paper_arc, paper_row  # noqa: E402
from skatetrace.paper import figures  # noqa: E402
from skatetrace.figures.patterns import pattern  # noqa: E402
from test_plotting import axes_without_units, legend_overlaps  # noqa: E402  (tests/ is on sys.path)

GREEN, BLUE, RED, BLACK = (to_rgba(c) for c in ("tab:green", "tab:blue", "red", "black"))


@pytest.fixture(scope="module")
def evs():
    """Published evaluations of the main and point rows, exact-engine ones of the main rows."""
    out = {}
    for method in ("main", "point"):
        for k in (1, 2, 3):
            row = paper_row(method, k)
            out[method, k] = (row, evaluate_paper_arc(row, row.published, "published"))
    for k in (1, 2, 3):
        row = paper_row("main", k)
        out["exact", k] = (row, evaluate_exact_arc(row))
    return out


def _colours(ax):
    return {to_rgba(ln.get_color()) for ln in ax.lines}


def _render(fig):
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=40)
    return buf.getvalue()


def _vertical_red(ax):
    return sorted(float(ln.get_xdata()[0]) for ln in ax.lines
                  if to_rgba(ln.get_color()) == RED and len(set(np.asarray(ln.get_xdata(), float))) == 1)


def test_plot_arc_layout_colours_and_overlays(evs):
    row, ev = evs["main", 1]
    fig = figures.plot_arc(row, ev)
    assert isinstance(fig, Figure) and len(fig.axes) == 4
    for ax in fig.axes:  # every panel has a backward (blue) and a forward (green) part
        assert {GREEN, BLUE} <= _colours(ax)
    traj = fig.axes[0]
    full = [ln for ln in traj.lines if ln.get_label() == "full dynamics"]
    assert len(full) == 1 and to_rgba(full[0].get_color()) == RED and full[0].get_linestyle() == "--"
    assert np.allclose(full[0].get_xdata(), ev.full["x"])
    # green is exactly the t >= 0 part, blue the t < 0 part (joined at t = 0)
    t = ev.series["t"]
    green = [ln for ln in fig.axes[2].lines if to_rgba(ln.get_color()) == GREEN][0]
    blue = [ln for ln in fig.axes[2].lines if to_rgba(ln.get_color()) == BLUE][0]
    assert np.min(green.get_xdata()) >= 0.0 and np.max(blue.get_xdata()) <= 0.0
    assert len(green.get_xdata()) == np.sum(t >= 0)
    assert traj.get_aspect() == 1.0
    assert "main" in fig._suptitle.get_text() and "published" in fig._suptitle.get_text()
    assert not any(ln.get_label() == "target point" for ln in traj.lines)

    # the exact engine: one colour, no green/blue split
    row, ev = evs["exact", 2]
    fig = figures.plot_arc(row, ev)
    assert GREEN not in _colours(fig.axes[1]) and to_rgba("C0") in _colours(fig.axes[1])

    # point rows: a red dot on the target point
    row, ev = evs["point", 3]
    fig = figures.plot_arc(row, ev)
    dots = [ln for ln in fig.axes[0].lines if ln.get_label() == "target point"]
    assert len(dots) == 1 and to_rgba(dots[0].get_color()) == RED
    assert np.allclose([dots[0].get_xdata()[0], dots[0].get_ydata()[0]], row.target_point)

    # a given figure is cleared and reused
    again = figures.plot_arc(row, ev, fig=fig)
    assert again is fig and len(fig.axes) == 4


def test_plot_arc_mass(evs):
    row, ev = evs["main", 3]
    fig = figures.plot_arc_mass(row, ev)
    assert isinstance(fig, Figure) and len(fig.axes) == 3
    s = ev.series
    body = fig.axes[1]
    assert {GREEN, BLUE} <= _colours(body)
    blue = [ln for ln in body.lines if to_rgba(ln.get_color()) == BLUE][0]
    assert np.allclose(blue.get_xdata()[0], s["a"][0]) and np.allclose(blue.get_ydata()[0], s["b"][0])
    star = [ln for ln in fig.axes[2].lines if ln.get_marker() == "*"]
    assert len(star) == 1
    th, a, b = s["theta"][0], s["a"][0], s["b"][0]
    expected = (s["x"][0] + a * math.cos(th) - b * math.sin(th), s["y"][0] + a * math.sin(th) + b * math.cos(th))
    assert np.allclose([star[0].get_xdata()[0], star[0].get_ydata()[0]], expected)


def test_plot_energies(evs):
    pairs = [evs["main", k] for k in (3, 1, 2)]
    fig = figures.plot_energies(pairs)
    assert isinstance(fig, Figure) and len(fig.axes) == 6
    assert [ax.get_title() for ax in fig.axes[::2]] == ["arc 1: control mass", "arc 2: control mass",
                                                        "arc 3: control mass"]
    assert all(ax.get_yscale() == "linear" for ax in fig.axes)  # the main arcs' energies stay bounded
    row, ev = evs["main", 1]
    s = ev.series
    km = mass_energy(SleighParams(), s["xi1"], s["xi2"], s["a"], s["b"], s["adot"], s["bdot"])
    drawn = np.concatenate([ln.get_ydata() for ln in fig.axes[0].lines if to_rgba(ln.get_color()) == GREEN])
    assert np.allclose(drawn, km[s["t"] >= 0])

    # appendix arc 1: the mass energy blows up near a = 0 -> log scale; the skate's does not
    fig = figures.plot_energies([evs["point", 1]])
    assert len(fig.axes) == 2
    assert fig.axes[0].get_yscale() == "log" and fig.axes[1].get_yscale() == "linear"


def test_plot_leaf_switch_lines_and_colours(evs):
    (r3, e3), (r2, e2) = evs["main", 3], evs["main", 2]
    fig = figures.plot_leaf([(r3, e3), (r2, e2), (r3, e3)])
    assert isinstance(fig, Figure) and len(fig.axes) == 4
    d3 = e3.series["t"][-1] - e3.series["t"][0]
    d2 = e2.series["t"][-1] - e2.series["t"][0]
    for ax in fig.axes[1:]:
        assert np.allclose(_vertical_red(ax), [d3, d3 + d2])
        assert {BLACK, GREEN, BLUE} <= _colours(ax)
    assert _vertical_red(fig.axes[0]) == []
    paths = [ln for ln in fig.axes[0].lines if ln.get_gid() == "path"]
    assert [to_rgba(ln.get_color()) for ln in paths] == [BLACK, GREEN, BLUE]
    placed = pattern("double-flower").curves[1].layout()
    for ln, p in zip(paths, placed):
        assert np.allclose([ln.get_xdata()[0], ln.get_ydata()[0]], [p.start.x, p.start.y], atol=1e-12)
    # the time axis is continuous: the last arc ends at the total duration
    xi2 = [ln for ln in fig.axes[1].lines if to_rgba(ln.get_color()) == BLUE][0]
    assert np.isclose(xi2.get_xdata()[-1], 2 * d3 + d2)


def test_place_path_is_a_rigid_motion_onto_the_pose(evs):
    _, ev = evs["main", 2]
    s = ev.series
    pose = Pose(3.0, -2.0, 2.1)
    X, Y = figures.place_path(s["x"], s["y"], s["theta"], pose)
    assert X[0] == pytest.approx(pose.x, abs=1e-14) and Y[0] == pytest.approx(pose.y, abs=1e-14)
    # the direction of travel at the start is the pose's heading (the arc starts forwards)
    k = 5
    assert math.atan2(Y[k] - Y[0], X[k] - X[0]) == pytest.approx(pose.heading, abs=2e-2)
    # distances are preserved
    i, j = 100, 900
    assert math.hypot(X[i] - X[j], Y[i] - Y[j]) == pytest.approx(math.hypot(s["x"][i] - s["x"][j],
                                                                              s["y"][i] - s["y"][j]), rel=1e-12)
    # exact toy case: the unit x-step turned by 90 degrees
    X, Y = figures.place_path([1.0, 2.0], [1.0, 1.0], [0.0, 0.0], Pose(0.0, 0.0, math.pi / 2))
    assert np.allclose(X, [0.0, 0.0]) and np.allclose(Y, [0.0, 1.0])
    # a non-finite first sample: the first finite sample is the anchor, the bad one stays NaN
    X, Y = figures.place_path([np.nan, 1.0, 2.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0], Pose(5.0, 5.0, 0.0))
    assert np.isnan(X[0]) and np.allclose(X[1:], [5.0, 6.0]) and np.allclose(Y[1:], [5.0, 5.0])
    X, Y = figures.place_path([np.inf], [0.0], [0.0], Pose(0.0, 0.0, 0.0))
    assert X.size == 0 and Y.size == 0


def test_plot_pattern_places_every_piece(evs):
    by_arc = {k: evs["exact", k] for k in (1, 2, 3)}
    fig = figures.plot_pattern(by_arc)
    assert isinstance(fig, Figure) and len(fig.axes) == 1
    ax = fig.axes[0]
    paths = [ln for ln in ax.lines if ln.get_gid() == "path"]
    targets = [ln for ln in ax.lines if ln.get_gid() == "target"]
    fl = pattern("double-flower")
    placed = fl.curves[0].layout() + fl.curves[1].layout()
    assert len(paths) == len(targets) == len(placed) == 32
    for ln, p in zip(paths, placed):
        assert np.allclose([ln.get_xdata()[0], ln.get_ydata()[0]], [p.start.x, p.start.y], atol=1e-12)
    # the exact arcs have the target lengths: each path ends where its target piece ends
    for ln, tg in zip(paths, targets):
        assert np.allclose([ln.get_xdata()[-1], ln.get_ydata()[-1]], [tg.get_xdata()[-1], tg.get_ydata()[-1]],
                           atol=1e-6)
    assert ax.get_aspect() == 1.0
    # the published main arc 1 is much too short (not fudged): its ends miss the targets' ends
    by_arc = {k: evs["main", k] for k in (1, 2, 3)}
    fig = figures.plot_pattern(by_arc, title="x")
    paths = [ln for ln in fig.axes[0].lines if ln.get_gid() == "path"]
    targets = [ln for ln in fig.axes[0].lines if ln.get_gid() == "target"]
    gap = math.hypot(paths[0].get_xdata()[-1] - targets[0].get_xdata()[-1],
                     paths[0].get_ydata()[-1] - targets[0].get_ydata()[-1])
    assert gap > 0.5 and fig.axes[0].get_title() == "x"
    # a missing arc leaves its pieces out
    fig = figures.plot_pattern({1: evs["main", 1]})
    assert len([ln for ln in fig.axes[0].lines if ln.get_gid() == "path"]) == 8


def test_plot_endpoints(evs):
    pairs = [evs["point", k] for k in (1, 2, 3)]
    fig = figures.plot_endpoints(pairs)
    assert isinstance(fig, Figure) and len(fig.axes) == 3
    top, left, right = fig.axes
    assert top.get_position().width > 1.5 * left.get_position().width  # arc 1 spans the top row
    for ax, (row, _) in zip(fig.axes, pairs):
        dots = [ln for ln in ax.lines if ln.get_label() == "target point"]
        assert len(dots) == 1 and to_rgba(dots[0].get_color()) == RED
        assert np.allclose([dots[0].get_xdata()[0], dots[0].get_ydata()[0]], row.target_point)
        assert {GREEN, BLUE} <= _colours(ax)
    assert len(figures.plot_endpoints(pairs[:2]).axes) == 2


@pytest.mark.slow
def test_save_paper_figures(evs, tmp_path):
    def res(key, exact):
        row, pub = evs[key]
        return types.SimpleNamespace(row=row, published=pub, rerun=pub, exact=exact)

    _, ev = evs["point", 1]
    failed = dataclasses.replace(ev, label="exact", series={}, full={}, notes=("trace failed",))
    results = [res(("main", k), evs["exact", k][1]) for k in (1, 2, 3)]
    results += [res(("point", k), failed) for k in (1, 2)]  # point arc 3 missing: no leaf, no pattern
    written = figures.save_paper_figures(results, tmp_path / "figs")
    names = {p.name for p in written}
    expected = {f"main-arc{k}{s}.png" for k in (1, 2, 3) for s in ("", "-exact", "-mass")}
    expected |= {"main-energies.png", "main-energies-exact.png", "main-leaf.png", "main-pattern.png",
                 "main-pattern-exact.png"}
    expected |= {f"point-arc{k}{s}.png" for k in (1, 2) for s in ("", "-exact", "-mass")}
    expected |= {"point-energies.png", "point-energies-exact.png", "point-endpoints.png"}
    assert names == expected and len(written) == len(expected)
    for p in written:
        assert p.parent == tmp_path / "figs" and p.stat().st_size > 5000
        assert p.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def _damaged(ev):
    s = {k: np.array(v, dtype=float, copy=True) for k, v in ev.series.items()}
    n = s["t"].size
    for key in ("x", "y", "theta", "a", "b", "xi2", "adot"):
        s[key][[0, n // 3, n // 2]] = [np.nan, np.inf, -np.inf]
    s["bdot"][n // 4] = 1e300
    full = {k: (np.asarray(v)[: 7] if isinstance(v, np.ndarray) else v) for k, v in ev.full.items()}
    full["x"] = np.array([np.inf, 0.0, np.nan])
    return dataclasses.replace(ev, series=s, full=full)


def test_figures_survive_nonfinite_and_empty_series(evs):
    (r1, e1), (r2, e2), (r3, e3) = (evs["main", k] for k in (1, 2, 3))
    bad = {k: (r, _damaged(e)) for k, (r, e) in ((1, (r1, e1)), (2, (r2, e2)), (3, (r3, e3)))}
    empty = dataclasses.replace(e2, label="exact", series={}, full={})
    t_only = dataclasses.replace(e2, series={"t": np.array([])}, full={"t": np.array([0.0])})
    figs = [figures.plot_arc(*bad[1]), figures.plot_arc(r2, empty), figures.plot_arc(r2, t_only),
            figures.plot_arc_mass(*bad[2]), figures.plot_arc_mass(r2, empty),
            figures.plot_energies([bad[1], (r2, empty), bad[3]]), figures.plot_energies([]),
            figures.plot_leaf([bad[3], (r2, empty), bad[3]]), figures.plot_pattern({1: bad[1], 2: (r2, empty)}),
            figures.plot_endpoints([bad[1], (r2, empty)]), figures.plot_endpoints([])]
    for fig in figs:
        assert isinstance(fig, Figure) and len(_render(fig)) > 1000
        assert axes_without_units(fig) == []  # "no data" panels are labelled too
    assert any("no data" in t.get_text() for t in figs[1].axes[0].texts)
    # the damaged samples are masked, the rest is drawn
    traj = figs[0].axes[0]
    drawn = np.concatenate([ln.get_xdata() for ln in traj.lines if to_rgba(ln.get_color()) in (GREEN, BLUE)])
    assert np.isnan(drawn).sum() >= 3 and not np.isinf(drawn).any() and np.isfinite(drawn).sum() > 1000
    # the leaf still switches twice in each time panel, even around an empty arc
    assert all(len(_vertical_red(ax)) == 2 for ax in figs[7].axes[1:])


def _legend_texts(fig):
    return [t.get_text() for leg in fig.legends for t in leg.get_texts()]


def test_every_paper_figure_names_its_units_and_keeps_its_legend_off_the_data(evs):
    main = [evs["main", k] for k in (1, 2, 3)]
    point = [evs["point", k] for k in (1, 2, 3)]
    exact = {k: evs["exact", k] for k in (1, 2, 3)}
    figs = {
        "arc": figures.plot_arc(*evs["main", 1]), "arc point": figures.plot_arc(*evs["point", 3]),
        "arc exact": figures.plot_arc(*evs["exact", 2]), "mass": figures.plot_arc_mass(*evs["main", 3]),
        "energies": figures.plot_energies(main), "energies log": figures.plot_energies(point),
        "energies none": figures.plot_energies([]), "leaf": figures.plot_leaf([main[2], main[1], main[2]]),
        "pattern": figures.plot_pattern(exact), "endpoints": figures.plot_endpoints(point),
        "endpoints none": figures.plot_endpoints([]),
    }
    for name, fig in figs.items():
        assert axes_without_units(fig) == [], name
        for ax in fig.axes:  # the paper's dimensionless units, by name
            assert ax.get_xlabel().endswith(("(model length)", "(model time)")), (name, ax.get_xlabel())
            assert ax.get_ylabel().endswith(("(model length)", "(model length/time)", "(model energy)")), name
        assert all(ax.get_legend() is None for ax in fig.axes), name  # one legend per figure, below the axes
        if "none" not in name:
            assert len(fig.legends) == 1 and len(_legend_texts(fig)) >= 2, name
    assert figs["energies log"].axes[0].get_yscale() == "log"
    # rendering is the slow part: one figure of each layout
    for name in ("arc point", "mass", "energies log", "leaf", "pattern", "endpoints"):
        assert legend_overlaps(figs[name]) == [], name
    assert {"backward in time", "forward in time", "full dynamics", "target point", "target circle"} <= set(
        _legend_texts(figs["arc point"]))
    assert "exact engine" in _legend_texts(figs["arc exact"])
    assert {"contact point of the blade", "start of the control mass", "skate (solid)",
            "control mass (dashed)"} <= set(_legend_texts(figs["mass"]))
    assert _legend_texts(figs["leaf"])[:3] == ["first: arc 3", "second: arc 2", "third: arc 3"]
    assert "controls switch to the next arc" in _legend_texts(figs["leaf"])
    assert "target figure" in _legend_texts(figs["pattern"])
