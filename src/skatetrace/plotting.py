"""Plots of a traced figure: the paper's kinds of figures, from a trace and its replay.

Only this module imports matplotlib. Every function takes ``ax=None`` and returns the artists.
"""

from __future__ import annotations

import numpy as np

from .geometry import segment_points
from .model import mass_energy, skate_energy
from .tracing import FigureTrace
from .verify import VerificationReport

__all__ = ["plot_figure", "plot_controls", "plot_speed", "plot_mass_path", "plot_energies", "plot_fit", "save_all"]


def _ax(ax):
    if ax is None:
        import matplotlib.pyplot as plt

        _, ax = plt.subplots()
    return ax


def plot_figure(trace: FigureTrace, report: VerificationReport, ax=None):
    """The replayed blade path (solid) over the target figure (dashed), cusps marked."""
    ax = _ax(ax)
    artists = []
    for c in trace.figure.curves:
        for p in c.layout():
            xy = segment_points(p.start, p.segment, 200)
            artists += ax.plot(xy[0], xy[1], "--", color="0.6", lw=2.5, label=None)
    rep = report.replay
    for si in np.unique(rep.section):
        m = rep.section == si
        artists += ax.plot(rep.state[3, m], rep.state[4, m], "-", color="C0", lw=0.9)
    # every section starts at rest: the first piece of a curve and every piece after a cusp
    cusps = [(p.start.x, p.start.y) for c in trace.figure.curves for p in c.layout()
             if p.join_before is None or p.join_before.is_cusp]
    if cusps:
        artists.append(ax.plot(*np.array(cusps).T, "o", color="C3", ms=3)[0])
    ax.set_aspect("equal")
    ax.set_xlabel("x")
    ax.set_ylabel("y")
    ax.set_title(f"{trace.figure.name}: replay (blue) over target (grey), max deviation {report.max_deviation:.2e}")
    return artists


def _time_axes(ax, ylabel: str) -> None:
    ax.set_xlabel("t")
    ax.set_ylabel(ylabel)
    ax.legend()


def _switches(ax, trace: FigureTrace):
    return [ax.axvline(t, color="C3", lw=0.5, alpha=0.5) for t in trace.start_times[1:]]


def plot_controls(trace: FigureTrace, report: VerificationReport, ax=None):
    """a(t) and b(t) with section switches marked."""
    ax = _ax(ax)
    rep = report.replay
    artists = ax.plot(rep.t, rep.controls[0], label="a(t)") + ax.plot(rep.t, rep.controls[1], label="b(t)")
    artists += _switches(ax, trace)
    _time_axes(ax, "mass position (body frame)")
    return artists


def plot_speed(trace: FigureTrace, report: VerificationReport, ax=None):
    """Speed along the blade xi2(t), cusps marked."""
    ax = _ax(ax)
    rep = report.replay
    _, xi2, _ = rep.velocities(trace.params)
    artists = ax.plot(rep.t, xi2, label="xi2 (speed)")
    starts = np.array(trace.start_times + (trace.duration,))
    artists.append(ax.plot(starts, np.zeros_like(starts), "o", color="C3", ms=3, label="cusps")[0])
    _time_axes(ax, "xi2")
    return artists


def plot_mass_path(trace: FigureTrace, report: VerificationReport, ax=None):
    """Path of the moving mass in the body frame, one line per section."""
    ax = _ax(ax)
    rep = report.replay
    artists = []
    for si in np.unique(rep.section):
        m = rep.section == si
        artists += ax.plot(rep.controls[0, m], rep.controls[1, m], lw=0.8)
    artists.append(ax.plot([0], [0], "k+", ms=10)[0])
    ax.set_aspect("equal")
    ax.set_xlabel("a (along the blade)")
    ax.set_ylabel("b (left of the blade)")
    ax.set_title("mass path in the body frame (+ = contact point)")
    return artists


def plot_energies(trace: FigureTrace, report: VerificationReport, ax=None):
    """Kinetic energies of the skate and of the moving mass."""
    ax = _ax(ax)
    rep = report.replay
    xi1, xi2, _ = rep.velocities(trace.params)
    ks = skate_energy(trace.params, xi1, xi2)
    km = mass_energy(trace.params, xi1, xi2, *rep.controls)
    artists = ax.plot(rep.t, ks, label="skate") + ax.plot(rep.t, km, label="mass")
    _time_axes(ax, "kinetic energy")
    return artists


def save_all(trace: FigureTrace, report: VerificationReport, out) -> list:
    """Write figure.png, controls.png, speed.png, mass_path.png and energies.png into ``out``."""
    import io
    from pathlib import Path

    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    from .io import atomic_write

    out = Path(out)
    written = []
    for name, fn, size in (("figure", plot_figure, (8, 8)), ("controls", plot_controls, (10, 4)),
                           ("speed", plot_speed, (10, 4)), ("mass_path", plot_mass_path, (6, 6)),
                           ("energies", plot_energies, (10, 4))):
        fig, ax = plt.subplots(figsize=size)
        fn(trace, report, ax=ax)
        fig.tight_layout()
        buf = io.BytesIO()
        fig.savefig(buf, format="png", dpi=110)
        plt.close(fig)
        atomic_write(out / f"{name}.png", buf.getvalue())
        written.append(out / f"{name}.png")
    return written


def plot_fit(drawing, fit, ax=None):
    """Fitted arcs and lines (colours alternate) over the input drawing (thick grey), knots marked.

    The title gives the certified Hausdorff bound; a red circle marks where the largest sampled
    distance was found.
    """
    ax = _ax(ax)
    artists = []
    for path in drawing.paths:
        pts = path.points(200)
        artists += ax.plot(pts[0], pts[1], "-", color="0.75", lw=4, solid_capstyle="round")
    for pf in fit.paths:
        for run in pf.runs:
            poses = run.poses()
            for i, (pose, seg) in enumerate(zip(poses, run.segments)):
                xy = segment_points(pose, seg, 60)
                artists += ax.plot(xy[0], xy[1], "-", color="C0" if i % 2 == 0 else "C1", lw=1.2)
            xs = [p.x for p in poses]
            ys = [p.y for p in poses]
            artists += ax.plot(xs, ys, ".", color="k", ms=3)
        if pf.where is not None and pf.hausdorff == fit.hausdorff:
            artists += ax.plot([pf.where.x], [pf.where.y], "o", mfc="none", mec="red", ms=10)
    ax.set_aspect("equal")
    ax.set_title(f"{fit.n_arcs} arcs, {fit.n_lines} lines; Hausdorff distance <= {fit.hausdorff:.3g} (certified)")
    return artists
