"""Every kind of figure the paper shows, drawn from :class:`~skatetrace.paper.evaluate.ArcEvaluation` s.

Rhodes & Putkaradze, "Trajectory tracing in figure skating" (``shared/reference``), figure kinds:

- :func:`plot_arc`: "Arc k trajectory (top left), xi^2 profile (top right), a(t) (bottom left) and
  b(t) (bottom right). Green and blue indicate the forward- and backward-in-time solutions";
- :func:`plot_arc_mass`: skate trajectory, control-mass trajectory in the body frame, and both in the
  spatial frame with a star at the initial point of the control mass;
- :func:`plot_energies`: kinetic energy of the control mass (left) and of the skate (right), one row
  per arc;
- :func:`plot_leaf`: one outer leaf (arc 3, arc 2, arc 3) in black, green and blue, with red vertical
  lines where the controls switch between arcs;
- :func:`plot_pattern`: the full double flower rebuilt from the three arcs by rigid motions;
- :func:`plot_endpoints`: the appendix's arcs with their optimal end points (red markers);
- :func:`save_paper_figures`: all of the above as PNG files, per method.

Conventions: in a paper arc's series ``t < 0`` is the backward-in-time part (blue) and ``t >= 0`` the
forward part (green); the exact engine's series (``label == "exact"``) runs from ``0`` with no split
and is drawn in one colour (``C0``). Non-finite samples (the appendix arcs pass through the
singular set ``a = 0`` of (b_diff_eq)) are masked, never plotted, and never raise. Every axis
names its quantity and unit: the paper's dimensionless model units (``model length``, ``model
time``, ...; :func:`skatetrace.outputs.plotting.axis_units`).

Figures are built with the object API (:class:`matplotlib.figure.Figure`), so nothing is registered
with pyplot and nothing needs closing; matplotlib is imported inside the functions only.
"""

from __future__ import annotations

import io
import math
from pathlib import Path

import numpy as np

from ..dynamics.model import SleighParams, mass_energy, skate_energy
from ..figures.geometry import Pose, segment_points
from ..outputs.plotting import axis_units
from .tables import METHODS

__all__ = ["plot_arc", "plot_arc_mass", "plot_energies", "plot_leaf", "plot_pattern", "plot_endpoints",
           "place_path", "save_paper_figures"]

_FORWARD = "tab:green"
_BACKWARD = "tab:blue"
_EXACT = "C0"
_LEAF_COLOURS = ("black", "tab:green", "tab:blue")
_TARGET_STYLE = {"color": "0.75", "ls": "--", "lw": 1.0}
_LOG_SPAN = 1e4  # four decades
_DPI = 110
#: Which of the paper's arcs each piece of the double flower's curves is (inner, outer).
_INNER_ARCS = (1,)
_ORDINALS = ("first", "second", "third")
_OUTER_ARCS = (3, 2, 3)
#: The paper's dimensionless units, named on every axis as in :mod:`skatetrace.outputs.plotting`.
_U = axis_units("model")
_X = f"x ({_U['length']})"
_Y = f"y ({_U['length']})"
_T = f"t ({_U['time']})"
_XI2 = rf"$\xi^2$, blade speed ({_U['speed']})"
_A = f"a ({_U['length']})"
_B = f"b ({_U['length']})"


# --------------------------------------------------------------------------------------- helpers


def _new_figure(fig, figsize):
    """``fig`` cleared, or a new :class:`matplotlib.figure.Figure` not registered with pyplot."""
    if fig is None:
        from matplotlib.figure import Figure

        return Figure(figsize=figsize, layout="constrained")
    fig.clear()
    return fig


def _clean(v) -> np.ndarray:
    """1-d float array with every non-finite value replaced by NaN (empty if ``v`` is unusable)."""
    if v is None:
        return np.empty(0)
    try:
        a = np.array(v, dtype=float).ravel()
    except (TypeError, ValueError):
        return np.empty(0)
    a[~np.isfinite(a)] = np.nan
    return a


def _get(d, key) -> np.ndarray:
    return _clean(d.get(key)) if isinstance(d, dict) else np.empty(0)


def _common(*arrays) -> list[np.ndarray]:
    """The arrays cut to their common length."""
    n = min((a.size for a in arrays), default=0)
    return [a[:n] for a in arrays]


def _is_exact(ev) -> bool:
    return getattr(ev, "label", "") == "exact"


def _series(ev) -> dict:
    s = getattr(ev, "series", None)
    return s if isinstance(s, dict) else {}


def _has_data(ev) -> bool:
    return _get(_series(ev), "t").size > 0


def _halves(t: np.ndarray) -> tuple[slice, slice]:
    """Backward (``t < 0``, up to and including the first ``t >= 0`` sample) and forward slices."""
    n = t.size
    with np.errstate(invalid="ignore"):
        fwd = np.flatnonzero(t >= 0)
    i0 = int(fwd[0]) if fwd.size else n
    return (slice(0, min(i0 + 1, n)) if i0 > 0 else slice(0, 0)), slice(i0, n)


def _plot_split(ax, t, u, v, exact: bool, labels: bool = False, **kw) -> list:
    """``v`` against ``u``: forward green, backward blue, or one colour for the exact engine."""
    t, u, v = _common(t, u, v)
    if exact:
        return ax.plot(u, v, color=_EXACT, label="exact engine" if labels else None, **kw)
    back, fwd = _halves(t)
    lines = []
    if u[back].size:
        lines += ax.plot(u[back], v[back], color=_BACKWARD, label="backward in time" if labels else None, **kw)
    if u[fwd].size:
        lines += ax.plot(u[fwd], v[fwd], color=_FORWARD, label="forward in time" if labels else None, **kw)
    return lines


def _no_data(ax, ev=None) -> None:
    notes = "; ".join(getattr(ev, "notes", ()) or ())
    text = "no data" + (f"\n{notes[:120]}" if notes else "")
    ax.text(0.5, 0.5, text, transform=ax.transAxes, ha="center", va="center", fontsize=8, color="0.4", wrap=True)


def _figure_legend(fig, axes, extra=()):
    """One legend for the whole figure, below its axes (outside them, so it never covers data).

    The entries are the labelled artists of ``axes`` (first of each label) and the ``extra``
    proxy artists; nothing is drawn when there is no entry.
    """
    from matplotlib.layout_engine import ConstrainedLayoutEngine

    entries: dict[str, object] = {}
    for ax in axes:
        for handle, label in zip(*ax.get_legend_handles_labels()):
            entries.setdefault(label, handle)
    for handle in extra:
        entries.setdefault(handle.get_label(), handle)
    if not entries:
        return None
    if not isinstance(fig.get_layout_engine(), ConstrainedLayoutEngine):
        fig.set_layout_engine("constrained")  # "outside" placement needs it
    return fig.legend(list(entries.values()), list(entries), loc="outside lower center",
                      ncols=min(len(entries), 4), fontsize=8, frameon=False)


def _proxy(label: str, **style):
    """A legend entry for something drawn without a label of its own."""
    from matplotlib.lines import Line2D

    return Line2D([], [], label=label, **style)


def _circle(ax, row) -> None:
    cx, cy = row.centre
    phi = np.linspace(0.0, 2 * math.pi, 361)
    ax.plot(cx + row.radius * np.cos(phi), cy + row.radius * np.sin(phi), **_TARGET_STYLE, label="target circle")


def _target_point(ax, row) -> None:
    if getattr(row, "target_point", None) is not None:
        ax.plot([row.target_point[0]], [row.target_point[1]], "o", color="red", ms=6, label="target point", zorder=5)


def _energies(ev, params: SleighParams) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``t``, mass and skate kinetic energies of ``ev.series`` (non-finite masked)."""
    s = _series(ev)
    t, xi1, xi2, a, b, ad, bd = _common(*(_get(s, k) for k in ("t", "xi1", "xi2", "a", "b", "adot", "bdot")))
    with np.errstate(all="ignore"):
        km = _clean(mass_energy(params, xi1, xi2, a, b, ad, bd))
        ks = _clean(skate_energy(params, xi1, xi2))
    return t, km, ks


def _auto_log(ax, values: np.ndarray) -> None:
    """Log y-scale if the positive finite values span more than four decades.

    The span is measured from the median up to the maximum, so that energies vanishing at the
    ends of an arc (the skate comes to rest) do not count, while a blow-up near the singular set
    does.
    """
    v = values[np.isfinite(values) & (values > 0)]
    if v.size and float(np.max(v)) > _LOG_SPAN * float(np.median(v)):
        ax.set_yscale("log")


def _anchor(x, y, theta) -> int | None:
    """Index of the first sample where ``x``, ``y`` and ``theta`` are all finite."""
    x, y, theta = _common(x, y, theta)
    ok = np.flatnonzero(np.isfinite(x) & np.isfinite(y) & np.isfinite(theta))
    return int(ok[0]) if ok.size else None


def place_path(x, y, theta, pose: Pose) -> tuple[np.ndarray, np.ndarray]:
    """Move a path rigidly so that its start point and heading coincide with ``pose``.

    Parameters
    ----------
    x, y, theta : array_like
        The path and the blade heading along it. The start is the first sample where all three are
        finite (normally the first one).
    pose : Pose
        Where the path must start (``x, y``) and which way it must head (``heading``).

    Returns
    -------
    X, Y : ndarray
        The rotated and translated path (non-finite samples stay NaN); empty arrays if the path
        has no finite sample.

    Examples
    --------
    >>> X, Y = place_path([0.0, 1.0], [0.0, 0.0], [0.0, 0.0], Pose(2.0, 3.0, math.pi / 2))
    >>> [round(float(v), 12) for v in (X[0], Y[0], X[1], Y[1])]
    [2.0, 3.0, 2.0, 4.0]
    """
    x, y, theta = _common(_clean(x), _clean(y), _clean(theta))
    i = _anchor(x, y, theta)
    if i is None:
        return np.empty(0), np.empty(0)
    phi = pose.heading - theta[i]
    c, s = math.cos(phi), math.sin(phi)
    dx, dy = x - x[i], y - y[i]
    return pose.x + c * dx - s * dy, pose.y + s * dx + c * dy


def _placed_path(ev, pose: Pose) -> tuple[np.ndarray, np.ndarray]:
    s = _series(ev)
    return place_path(_get(s, "x"), _get(s, "y"), _get(s, "theta"), pose)


def _double_flower():
    from ..figures.patterns import pattern

    return pattern("double-flower")


# ----------------------------------------------------------------------------------- the figures


def plot_arc(row, ev, fig=None):
    """One arc as in the paper's Figs. "Arc k trajectory, xi^2 profile, a(t), b(t)".

    Parameters
    ----------
    row : PaperRow
        The table row (radius, centre, target point).
    ev : ArcEvaluation
        Its evaluation: ``ev.series`` is drawn, forward part (``t >= 0``) green, backward part
        (``t < 0``) blue, or in one colour (``C0``) for the exact engine (``ev.label == "exact"``).
        The full-dynamics re-simulation ``ev.full`` is drawn over the trajectory, dashed red.
    fig : matplotlib.figure.Figure, optional
        Figure to draw on (cleared first); a new one by default.

    Returns
    -------
    matplotlib.figure.Figure
        Four axes: trajectory (top left, equal aspect, target circle dashed light grey, red dot at
        the target point of point-based rows), ``xi2(t)`` (top right), ``a(t)`` (bottom left) and
        ``b(t)`` (bottom right).
    """
    fig = _new_figure(fig, (9.0, 7.0))
    (ax_xy, ax_v), (ax_a, ax_b) = fig.subplots(2, 2)
    s, exact = _series(ev), _is_exact(ev)
    t = _get(s, "t")
    _circle(ax_xy, row)
    if t.size:
        _plot_split(ax_xy, t, _get(s, "x"), _get(s, "y"), exact, labels=True, lw=1.8)
        for ax, key in ((ax_v, "xi2"), (ax_a, "a"), (ax_b, "b")):
            _plot_split(ax, t, t, _get(s, key), exact, lw=1.5)
    else:
        for ax in (ax_xy, ax_v, ax_a, ax_b):
            _no_data(ax, ev)
    fx, fy = _common(_get(getattr(ev, "full", {}), "x"), _get(getattr(ev, "full", {}), "y"))
    if fx.size:
        ax_xy.plot(fx, fy, "--", color="red", lw=1.0, label="full dynamics")
    _target_point(ax_xy, row)
    ax_xy.set_aspect("equal", adjustable="datalim")
    ax_xy.set(xlabel=_X, ylabel=_Y, title=f"arc {row.arc} trajectory")
    _figure_legend(fig, [ax_xy])
    ax_v.axhline(0.0, color="0.8", lw=0.6)
    ax_v.set(xlabel=_T, ylabel=_XI2, title=r"$\xi^2$ profile")
    ax_a.set(xlabel=_T, ylabel=_A, title="a(t)")
    ax_b.set(xlabel=_T, ylabel=_B, title="b(t)")
    fig.suptitle(f"{row.method} method, arc {row.arc}: {getattr(ev, 'label', '')}")
    return fig


def plot_arc_mass(row, ev, fig=None):
    """Skate and control mass of one arc, as in the paper's "skate trajectories (left), control mass
    trajectories (middle), and overlay of skate and control mass trajectories in spatial frame (right)".

    Parameters
    ----------
    row : PaperRow
    ev : ArcEvaluation
        Forward part green, backward part blue (one colour for the exact engine).
    fig : matplotlib.figure.Figure, optional
        Figure to draw on (cleared first); a new one by default.

    Returns
    -------
    matplotlib.figure.Figure
        Three axes: the skate's path ``(x, y)``; the mass in the body frame (``b`` against ``a``);
        the skate (solid) and the mass in the spatial frame,
        ``(x + a cos th - b sin th, y + a sin th + b cos th)`` (dashed), with a black star where
        the mass starts (the first finite sample: the start of the motion, ``t = t1``).
    """
    fig = _new_figure(fig, (13.0, 4.6))
    ax_s, ax_m, ax_o = fig.subplots(1, 3)
    s, exact = _series(ev), _is_exact(ev)
    t, x, y, th, a, b = _common(*(_get(s, k) for k in ("t", "x", "y", "theta", "a", "b")))
    if t.size:
        with np.errstate(invalid="ignore"):
            mx = x + a * np.cos(th) - b * np.sin(th)
            my = y + a * np.sin(th) + b * np.cos(th)
        _plot_split(ax_s, t, x, y, exact, labels=True, lw=1.6)
        _plot_split(ax_m, t, a, b, exact, lw=1.4)
        _plot_split(ax_o, t, x, y, exact, lw=1.6)
        _plot_split(ax_o, t, mx, my, exact, lw=1.0, ls="--")
        ok = np.flatnonzero(np.isfinite(mx) & np.isfinite(my))
        if ok.size:
            ax_o.plot([mx[ok[0]]], [my[ok[0]]], "*", color="black", ms=13, zorder=5,
                      label="start of the control mass")
    else:
        for ax in (ax_s, ax_m, ax_o):
            _no_data(ax, ev)
    ax_m.plot([0.0], [0.0], "k+", ms=9, label="contact point of the blade")
    for ax in (ax_s, ax_m, ax_o):
        ax.set_aspect("equal", adjustable="datalim")
    ax_s.set(xlabel=_X, ylabel=_Y, title="skate trajectory")
    ax_m.set(xlabel=f"a, along the blade ({_U['length']})", ylabel=f"b, left of the blade ({_U['length']})",
             title="control mass, body frame")
    ax_o.set(xlabel=_X, ylabel=_Y, title="skate, control mass (dashed), * start")
    _figure_legend(fig, [ax_s, ax_m, ax_o], extra=(_proxy("skate (solid)", color="0.3", ls="-"),
                                                   _proxy("control mass (dashed)", color="0.3", ls="--")))
    fig.suptitle(f"{row.method} method, arc {row.arc}: {getattr(ev, 'label', '')}")
    return fig


def plot_energies(pairs, fig=None, params: SleighParams = SleighParams()):
    """Kinetic energies, as in the paper's "Energy over time for control mass (left) and skate (right)".

    Parameters
    ----------
    pairs : list of (PaperRow, ArcEvaluation)
        Any of arcs 1-3; one row of panels per pair, ordered by arc.
    fig : matplotlib.figure.Figure, optional
        Figure to draw on (cleared first); a new one by default.
    params : SleighParams
        Masses and inertia (the paper's ``M = 2, m = 1, I = 3`` by default).

    Returns
    -------
    matplotlib.figure.Figure
        ``2 * len(pairs)`` axes: :func:`~skatetrace.dynamics.model.mass_energy` (left) and
        :func:`~skatetrace.dynamics.model.skate_energy` (right) against ``t``. A panel switches to a log
        y-scale when its maximum exceeds its median by more than four decades (the appendix arcs'
        mass energy blows up near ``a = 0``); non-finite values are left out.
    """
    pairs = sorted(pairs, key=lambda p: p[0].arc)
    n = max(len(pairs), 1)
    fig = _new_figure(fig, (10.0, 2.8 * n + 0.6))
    axes = np.atleast_2d(fig.subplots(n, 2, squeeze=False))
    if not pairs:
        for ax, who in zip(axes.ravel(), ("m", "{skate}")):
            _no_data(ax)
            ax.set(xlabel=_T, ylabel=rf"$KE_{who}$ ({_U['energy']})")
    for (row, ev), (ax_m, ax_s) in zip(pairs, axes):
        t, km, ks = _energies(ev, params)
        if t.size:
            _plot_split(ax_m, t, t, km, _is_exact(ev), labels=True, lw=1.5)
            _plot_split(ax_s, t, t, ks, _is_exact(ev), lw=1.5)
            _auto_log(ax_m, km)
            _auto_log(ax_s, ks)
        else:
            _no_data(ax_m, ev)
            _no_data(ax_s, ev)
        ax_m.set(xlabel=_T, ylabel=rf"$KE_m$ ({_U['energy']})", title=f"arc {row.arc}: control mass")
        ax_s.set(xlabel=_T, ylabel=rf"$KE_{{skate}}$ ({_U['energy']})", title=f"arc {row.arc}: skate")
    if pairs:
        row, ev = pairs[0]
        fig.suptitle(f"{row.method} method: kinetic energies ({getattr(ev, 'label', '')})")
    _figure_legend(fig, axes.ravel())
    return fig


def plot_leaf(pairs, fig=None):
    """One outer leaf (arc 3, arc 2, arc 3), as in the paper's "Trajectory of a single leaf".

    Parameters
    ----------
    pairs : list of (PaperRow, ArcEvaluation)
        ``[(row3, ev3), (row2, ev2), (row3, ev3)]``: the arcs in the order they are skated; pair
        ``i`` is drawn in black, green, blue for ``i = 0, 1, 2``.
    fig : matplotlib.figure.Figure, optional
        Figure to draw on (cleared first); a new one by default.

    Returns
    -------
    matplotlib.figure.Figure
        Four axes: the leaf's trajectory (top left), ``xi2`` (top right), ``a`` (bottom left) and
        ``b`` (bottom right) against time. In time the arcs follow each other: each arc's series,
        from its own first to last sample, is shifted to start where the previous one ended; red
        vertical lines mark the switches. In space pair ``i`` is moved rigidly onto the start pose
        of piece ``i`` of the outer curve of ``pattern("double-flower")`` (the target leaf is drawn
        dashed light grey): arcs of the wrong length leave gaps.
    """
    fig = _new_figure(fig, (9.0, 7.0))
    (ax_xy, ax_v), (ax_a, ax_b) = fig.subplots(2, 2)
    placed = _double_flower().curves[1].layout()
    for p in placed[:3]:
        xy = segment_points(p.start, p.segment, 200)
        ax_xy.plot(xy[0], xy[1], **_TARGET_STYLE, gid="target")
    offset, switches = 0.0, []
    for i, (row, ev) in enumerate(pairs):
        colour = _LEAF_COLOURS[i % len(_LEAF_COLOURS)]
        if i > 0:
            switches.append(offset)
        s = _series(ev)
        X, Y = _placed_path(ev, placed[i].start) if i < len(placed) else (np.empty(0), np.empty(0))
        if X.size:
            ax_xy.plot(X, Y, color=colour, lw=1.8, label=f"{_ORDINALS[i % 3]}: arc {row.arc}", gid="path")
        t = _get(s, "t")
        tf = t[np.isfinite(t)]
        if not tf.size:
            continue
        ts = t - tf[0] + offset
        for ax, key in ((ax_v, "xi2"), (ax_a, "a"), (ax_b, "b")):
            u, v = _common(ts, _get(s, key))
            ax.plot(u, v, color=colour, lw=1.5)
        offset += float(tf[-1] - tf[0])
    for ax in (ax_v, ax_a, ax_b):
        for ts in switches:
            ax.axvline(ts, color="red", lw=1.0, gid="switch")
    ax_xy.set_aspect("equal", adjustable="datalim")
    ax_xy.set(xlabel=_X, ylabel=_Y, title="single leaf")
    _figure_legend(fig, [ax_xy], extra=[_proxy("target leaf", **_TARGET_STYLE)]
                   + ([_proxy("controls switch to the next arc", color="red", lw=1.0)] if switches else []))
    ax_v.axhline(0.0, color="0.8", lw=0.6)
    ax_v.set(xlabel=_T, ylabel=_XI2, title=r"$\xi^2$ profile")
    ax_a.set(xlabel=_T, ylabel=_A, title="a(t)")
    ax_b.set(xlabel=_T, ylabel=_B, title="b(t)")
    if pairs:
        row, ev = pairs[0]
        fig.suptitle(f"{row.method} method: leaf (arc 3, arc 2, arc 3), {getattr(ev, 'label', '')}")
    return fig


def plot_pattern(pairs_by_arc, fig=None, title: str = "Full pattern reconstruction"):
    """The double flower rebuilt from the three arcs, as in the paper's "Full pattern reconstruction".

    Parameters
    ----------
    pairs_by_arc : dict
        ``{1: (row, ev), 2: (row, ev), 3: (row, ev)}``; a missing arc leaves its pieces empty.
    fig : matplotlib.figure.Figure, optional
        Figure to draw on (cleared first); a new one by default.
    title : str
        Axes title.

    Returns
    -------
    matplotlib.figure.Figure
        One axes, equal aspect. Every placed piece of ``pattern("double-flower")`` (inner curve:
        arc 1 each; outer curve: arc 3, arc 2, arc 3 repeated) gets the corresponding arc's path
        moved rigidly onto the piece's start pose (:func:`place_path`); the target figure is drawn
        thinly, dashed light grey. Arcs that miss their target length do not close the figure,
        and are not adjusted to.
    """
    fig = _new_figure(fig, (7.5, 7.5))
    ax = fig.subplots()
    fl = _double_flower()
    for curve, arcs in zip(fl.curves, (_INNER_ARCS, _OUTER_ARCS)):
        for j, p in enumerate(curve.layout()):
            xy = segment_points(p.start, p.segment, 200)
            ax.plot(xy[0], xy[1], **{**_TARGET_STYLE, "lw": 0.8}, gid="target")
            pair = pairs_by_arc.get(arcs[j % len(arcs)])
            if pair is None:
                continue
            X, Y = _placed_path(pair[1], p.start)
            if X.size:
                ax.plot(X, Y, color="black", lw=1.3, gid="path")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set(xlabel=_X, ylabel=_Y, title=title)
    _figure_legend(fig, [ax], extra=[_proxy("target figure", **{**_TARGET_STYLE, "lw": 0.8}),
                                     _proxy("the arcs, each moved onto its piece", color="black", lw=1.3)])
    return fig


def plot_endpoints(pairs, fig=None):
    """The appendix's "Arc trajectories and optimal end points (red marker)".

    Parameters
    ----------
    pairs : list of (PaperRow, ArcEvaluation)
        Point-based rows; one panel per pair, ordered by arc: with all three arcs, arc 1 on top
        and arcs 2 and 3 bottom left and right, as in the paper; otherwise side by side.
    fig : matplotlib.figure.Figure, optional
        Figure to draw on (cleared first); a new one by default.

    Returns
    -------
    matplotlib.figure.Figure
        ``len(pairs)`` axes: the trajectory (forward green, backward blue), the target circle
        dashed light grey and a red dot at ``row.target_point``.
    """
    pairs = sorted(pairs, key=lambda p: p[0].arc)
    n = len(pairs)
    fig = _new_figure(fig, (9.0, 8.5) if n == 3 else (4.5 * max(n, 1), 4.5))
    if n == 3:
        gs = fig.add_gridspec(2, 2)
        axes = [fig.add_subplot(gs[0, :]), fig.add_subplot(gs[1, 0]), fig.add_subplot(gs[1, 1])]
    elif n:
        axes = list(np.ravel(fig.subplots(1, n, squeeze=False)))
    else:
        axes = []
        empty = fig.subplots()
        _no_data(empty)
        empty.set(xlabel=_X, ylabel=_Y)
    for (row, ev), ax in zip(pairs, axes):
        s = _series(ev)
        t = _get(s, "t")
        _circle(ax, row)
        if t.size:
            _plot_split(ax, t, _get(s, "x"), _get(s, "y"), _is_exact(ev), labels=True, lw=1.8)
        else:
            _no_data(ax, ev)
        _target_point(ax, row)
        ax.set_aspect("equal", adjustable="datalim")
        ax.set(xlabel=_X, ylabel=_Y, title=f"arc {row.arc}")
    if pairs:
        row, ev = pairs[0]
        fig.suptitle(f"{row.method} method: arcs and optimal end points ({getattr(ev, 'label', '')})")
    _figure_legend(fig, axes)
    return fig


# ------------------------------------------------------------------------------------------ save


def _save(fig, path: Path) -> Path:
    from ..outputs.files import atomic_write

    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=_DPI)
    fig.clear()  # not registered with pyplot: clearing releases it
    atomic_write(path, buf.getvalue())
    return path


def save_paper_figures(results, out_dir) -> list[Path]:
    """Write every figure of every method present in ``results`` as PNG files into ``out_dir``.

    Parameters
    ----------
    results : iterable
        Objects with attributes ``row`` (:class:`~skatetrace.paper.tables.PaperRow`),
        ``published``, ``rerun`` and ``exact`` (:class:`~skatetrace.paper.evaluate.ArcEvaluation`
        of the paper's published optimum, of the re-run procedure and of the exact engine).
    out_dir : str or Path
        Created if needed.

    Returns
    -------
    list of Path
        The files written, per method present: ``{method}-arc{k}.png``, ``{method}-arc{k}-exact.png``,
        ``{method}-arc{k}-mass.png`` (per arc), ``{method}-energies.png``,
        ``{method}-energies-exact.png``, ``{method}-leaf.png`` (arcs 2 and 3 needed),
        ``{method}-pattern.png`` and ``{method}-pattern-exact.png`` (arcs 1-3 needed), and
        ``point-endpoints.png``. A figure whose arcs (or evaluations) are missing is skipped.
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    by_method: dict[str, dict[int, object]] = {}
    for r in results:
        by_method.setdefault(r.row.method, {})[int(r.row.arc)] = r
    written: list[Path] = []

    def save(fig, name: str) -> None:
        written.append(_save(fig, out / name))

    for method in sorted(by_method, key=lambda m: METHODS.index(m) if m in METHODS else len(METHODS)):
        arcs = by_method[method]
        pub = {k: (r.row, r.published) for k, r in sorted(arcs.items()) if getattr(r, "published", None) is not None}
        exa = {k: (r.row, r.exact) for k, r in sorted(arcs.items()) if getattr(r, "exact", None) is not None}
        for k in sorted(arcs):
            if k in pub:
                save(plot_arc(*pub[k]), f"{method}-arc{k}.png")
            if k in exa:
                save(plot_arc(*exa[k]), f"{method}-arc{k}-exact.png")
            if k in pub:
                save(plot_arc_mass(*pub[k]), f"{method}-arc{k}-mass.png")
        if pub:
            save(plot_energies(list(pub.values())), f"{method}-energies.png")
        if exa:
            save(plot_energies(list(exa.values())), f"{method}-energies-exact.png")
        if 2 in pub and 3 in pub:
            save(plot_leaf([pub[3], pub[2], pub[3]]), f"{method}-leaf.png")
        if all(k in pub for k in (1, 2, 3)):
            save(plot_pattern(pub, title=f"{method} method: full pattern reconstruction (published)"),
                 f"{method}-pattern.png")
        if all(k in exa for k in (1, 2, 3)):
            save(plot_pattern(exa, title=f"{method} method: full pattern, exact engine"),
                 f"{method}-pattern-exact.png")
        if method == "point" and pub:
            save(plot_endpoints(list(pub.values())), "point-endpoints.png")
    return written
