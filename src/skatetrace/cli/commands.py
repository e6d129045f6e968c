"""The ``skatetrace`` subcommands: trace, tradeoff, fit, animate, view, robustness, figures, reproduce.

With :mod:`skatetrace.cli.robustness` (that command's own), the only modules that print or exit.
Exit codes: 0 success, 1 a solve or verification that failed, 2 a usage error (bad arguments,
unreadable or malformed figure file).
"""

from __future__ import annotations

import argparse
import io
import math
import sys
import time
from contextlib import contextmanager, nullcontext
from functools import partial
from pathlib import Path

from ..errors import SkatetraceError
from ..dynamics.model import SleighParams
from ..figures.patterns import pattern, pattern_names
from ..drawings.sources import DRAWING_SUFFIXES
from ..pipeline import REST_POLICIES
from ..dynamics.presets import REACH_PER_HEIGHT
from ..tracing.sections import TraceOptions
from .robustness import add_parser as _add_robustness_parser
from .robustness import run as _robustness
from .status import LongWork, StatusLine, long_fit, planning_progress
from .values import figure_length

__all__ = ["build_parser", "main"]


def _add_source_args(t) -> None:
    g = t.add_argument_group("drawings (SVG, point lists)")
    g.add_argument("--size", help="scale the drawing so its larger side is this, e.g. 6m or 12 (model units); "
                                  "default: the drawing's own units")
    g.add_argument("--tol", help="fitting tolerance, a certified Hausdorff distance, e.g. 1mm or 1e-3 "
                                 "(figure units); default 1e-3 of the figure's size")
    g.add_argument("--path", dest="paths", action="append", metavar="ID",
                   help="trace only this path of the drawing: its SVG element's id (all its subpaths) or a "
                        "subpath's name (ID#2); repeat to keep several (default: every drawn path)")
    g.add_argument("--fit", dest="method", choices=("greedy", "min"), default="greedy",
                   help="arc-spline fit: greedy subdivision or the minimum number of arcs (default greedy)")
    g.add_argument("--exact", nargs="?", const=True, default=None, metavar="TOL",
                   help="exact mode: trace the smooth runs as curvature splines (spirals whose curvature is a "
                        "cubic of arc length) within TOL (default 1e-7 of the figure's size) instead of arcs; "
                        "the arc fit is still made and both deviations are shown")
    s = t.add_argument_group("school figures (school:NAME)")
    s.add_argument("--height", type=float, default=1.7, help="skater height in m (default 1.7)")
    s.add_argument("--body-mass", type=float, default=60.0, help="skater body mass in kg (default 60)")
    s.add_argument("--blade", type=float, default=0.28, help="blade length in m (default 0.28)")
    s.add_argument("--edge", default="outside", help="outside or inside (default outside)")
    s.add_argument("--direction", default="forward", help="forward or backward (default forward)")
    s.add_argument("--foot", default="right", help="right or left (default right)")


def _add_planner_args(t) -> None:
    g = t.add_argument_group("bounded-reach planning (controls a skater could make)")
    g.add_argument("--reach", default=None,
                   help="keep the moving mass within this distance of the blade's contact point, e.g. 0.5m (or 0.5 "
                        "in the figure's units), and plan its motion (CasADi/IPOPT, then finished exactly; "
                        "1.5 to 9 s for a school figure); 'auto': "
                        f"{REACH_PER_HEIGHT:g} x --height, the trunk's length; 'none': the launch-glide-stop "
                        "manoeuvres (no bound); default auto for figures in metres, none in model units")
    g.add_argument("--objective", choices=("effort", "time"), default="effort",
                   help="what the planner minimises: effort (the squared force on the mass, at the glide speed's "
                        "pace; default) or time (needs --max-accel)")
    g.add_argument("--max-accel", type=float,
                   help="largest acceleration of the mass on the ice (figure units per s^2, e.g. m/s^2)")
    g.add_argument("--workers", type=int,
                   help="processes the independent work runs in, side by side: the planner's programs, the "
                        "tracer's distinct sections (default: every core, up to 8; 1: one after another); the "
                        "result is the same either way")


def _reach(args, unit: str) -> float | None:
    """``--reach`` in the figure's units: a length, ``auto`` (from ``--height``) or ``none``.

    Not given: ``auto`` for a figure in metres (a skater's figure: the answer should be one a
    skater could make), ``none`` in model units (no skater to take a reach from).
    """
    from ..dynamics.presets import skater_reach

    word = ("auto" if unit == "m" else "none") if args.reach is None else args.reach.strip().lower()
    if word == "none":
        return None
    if word == "auto":
        if unit != "m":
            raise SkatetraceError("--reach auto derives the reach from --height, for figures in metres; this figure "
                                  "is in model units: give a number (model units) or 'none'")
        return skater_reach(args.height)
    return figure_length(args.reach, unit, "--reach")


def _version() -> str:
    """The installed distribution's version, else the package's own (a source checkout on sys.path)."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("skatetrace")
    except PackageNotFoundError:
        from .. import __version__

        return __version__


class _Parser(argparse.ArgumentParser):
    """argparse whose usage errors read like every other: ``skatetrace: error: ...``, exit code 2."""

    def error(self, message: str):
        self.exit(2, f"skatetrace: error: {message} (see '{self.prog} --help')\n")


def build_parser() -> argparse.ArgumentParser:
    """The ``skatetrace`` argument parser, with every subcommand and option.

    Public so that the documentation's CLI reference is generated from it (sphinx-argparse) and
    cannot drift from the command line.

    Returns
    -------
    argparse.ArgumentParser
        A parser whose usage errors print ``skatetrace: error: ...`` and exit with code 2.

    Examples
    --------
    >>> args = build_parser().parse_args(["trace", "circle", "--out", "out"])
    >>> args.command, args.figure, args.out
    ('trace', 'circle', 'out')
    """
    p = _Parser(prog="skatetrace", description="Controls that make a skater trace a figure exactly.")
    p.add_argument("--version", action="version", version=f"skatetrace {_version()}")
    sub = p.add_subparsers(dest="command", required=True)
    t = sub.add_parser("trace", help="trace a figure, verify it by re-simulation, write results")
    t.add_argument("figure", help=f"a built-in figure ({', '.join(pattern_names())}), school:NAME, a figure JSON "
                                  "file, or a drawing (.svg, .csv, .txt, .dat)")
    t.add_argument("--out", default="out", help="output folder (default: out)")
    t.add_argument("--M", type=float, help="sleigh mass (default: the figure's, else 2)")
    t.add_argument("--m", type=float, help="moving mass (default: the figure's, else 1)")
    t.add_argument("--I", type=float, help="sleigh inertia about the contact point (default: the figure's, else 3)")
    t.add_argument("--speed", type=float, help="glide speed (default: 1 model unit, 2 m/s for figures in metres)")
    t.add_argument("--verify-tol", type=float, default=1e-6,
                   help="allowed deviation from the traced pieces as a fraction of the figure size (default 1e-6)")
    t.add_argument("--rests", choices=REST_POLICIES, default="auto",
                   help="rests at smooth joins: auto (where a section's replay fails verification, split it "
                        "and the sections before it at their middle join and try again), never, or joins "
                        "(at every smooth join); default auto")
    t.add_argument("--no-plots", action="store_true", help="skip the PNG plots")
    t.add_argument("--no-viewer", action="store_true", help="skip viewer.html (the self-contained HTML viewer)")
    _add_planner_args(t)
    _add_source_args(t)
    d = sub.add_parser("tradeoff", help="plan a figure within a range of reaches: peak force, effort and duration "
                                        "against the reach, beside the launch-glide-stop manoeuvres")
    d.add_argument("figure", help="as for 'trace'")
    d.add_argument("--out", default="tradeoff", help="output folder for tradeoff.json and tradeoff.png "
                                                     "(default: tradeoff)")
    d.add_argument("--reaches", help="comma-separated reaches, e.g. 0.3m,0.4m,0.5m (or plain numbers in the "
                                     "figure's units); default 0.6, 0.8, 1, 1.25 and 1.5 times --reach auto for "
                                     "figures in metres, times 1 in model units")
    d.add_argument("--speed", type=float, help="glide speed (default: 1 model unit, 2 m/s for figures in metres)")
    d.add_argument("--objective", choices=("effort", "time"), default="effort", help="as for 'trace'")
    d.add_argument("--max-accel", type=float, help="as for 'trace'")
    d.add_argument("--workers", type=int, help="as for 'trace'")
    d.add_argument("--verify-tol", type=float, default=1e-6, help="as for 'trace'")
    d.add_argument("--no-plots", action="store_true", help="skip tradeoff.png")
    d.set_defaults(M=None, m=None, I=None)
    _add_source_args(d)
    f = sub.add_parser("fit", help="fit a drawing by arcs and lines (and, with --exact, curvature splines) "
                                   "without tracing: pieces, certified tolerance, plot")
    f.add_argument("drawing", help="an SVG file or a point list (.csv, .txt, .dat)")
    f.add_argument("--out", default="fit", help="output folder for fit.json and fit.png (default: fit)")
    f.add_argument("--no-plots", action="store_true", help="skip fit.png")
    _add_source_args(f)
    a = sub.add_parser("animate", help="a GIF or MP4 (or a PNG still) of a traced figure, from its result files")
    a.add_argument("source", help="the output folder of 'skatetrace trace', or its result.json")
    a.add_argument("-o", "--output", required=True, help="file to write: .gif, .mp4, or .png for one frame")
    a.add_argument("--fps", type=float, default=25.0, help="frames per second (default 25)")
    a.add_argument("--duration", type=float,
                   help="length of the video in s (default: the figure's own time, kept within 8 to 30 s)")
    a.add_argument("--size", default="800x800", help="WIDTHxHEIGHT in pixels (default 800x800)")
    a.add_argument("--time", type=float, help="for a .png still: the figure's time to draw (default: 60%% through)")
    v = sub.add_parser("view", help="one self-contained HTML file that plays a traced figure (no network needed)")
    v.add_argument("source", help="the output folder of 'skatetrace trace', or its result.json")
    v.add_argument("-o", "--output", help="HTML file to write (default: viewer.html in the source folder)")
    _add_robustness_parser(sub)
    sub.add_parser("figures", help="list the built-in figures and the school figures")
    r = sub.add_parser("reproduce", help="reproduce the paper's tables three ways, with figures and errata")
    r.add_argument("--out", default="rep", help="output folder (default: rep)")
    r.add_argument("--methods", default="main,point,length",
                   help="comma-separated subset of main (Tables 1-2), point (3-4), length (5-6)")
    r.add_argument("--arcs", default="1,2,3", help="comma-separated subset of the arcs 1, 2, 3")
    r.add_argument("--maxiter", type=int, help="cap on BFGS iterations of the re-run procedure (default: scipy's)")
    r.add_argument("--no-figures", action="store_true", help="skip the figures (tables and errata only)")
    r.add_argument("--no-conditioning", action="store_true",
                   help="skip re-running each evaluation under tiny perturbations (saves about 1.5 min; the report "
                        "then prints one run's digits)")
    return p


def _resolve(args, name: str):
    from ..drawings.fitting import reporting
    from ..drawings.sources import resolve

    with reporting(long_fit(StatusLine())):
        return resolve(name, size=args.size, tol=args.tol, method=args.method, height=args.height, blade=args.blade,
                       edge=args.edge, direction=args.direction, foot=args.foot, body_mass=args.body_mass,
                       exact=args.exact, paths=getattr(args, "paths", None))


def _exact_summary(res) -> dict | None:
    ex = res.exact
    if ex is None:
        return None
    return {
        "tol": res.exact_tol, "deviation": ex.deviation, "n_spirals": ex.n_spirals, "n_arcs": ex.n_arcs,
        "n_lines": ex.n_lines, "message": ex.message,
        "paths": [{"name": pf.name, "runs": len(pf.runs), "n_spirals": pf.n_spirals, "n_arcs": pf.n_arcs,
                   "n_lines": pf.n_lines, "deviation": pf.deviation, "sampled": pf.sampled,
                   "where": None if pf.where is None else list(pf.where)} for pf in ex.paths],
    }


def _fit_summary(res) -> dict:
    fit = res.fit
    return {
        "schema": "skatetrace.fit/1", "success": fit.success, "message": fit.message, "unit": res.unit,
        "tol": res.tol, "hausdorff_certified": fit.hausdorff, "hausdorff_sampled": fit.hausdorff_sampled,
        "n_arcs": fit.n_arcs, "n_lines": fit.n_lines, "notes": list(res.notes),
        "paths": [{
            "name": pf.name, "closed": pf.closed, "runs": len(pf.runs), "n_arcs": pf.n_arcs, "n_lines": pf.n_lines,
            "hausdorff_certified": pf.hausdorff, "hausdorff_sampled": pf.hausdorff_sampled,
            "where": None if pf.where is None else pf.where._asdict(), "curve_length": pf.curve_length,
            "spline_length": pf.spline_length, "method": pf.method, "greedy_count": pf.greedy_count,
            "min_count": pf.min_count,
            "corners_deg": [None if r.corner is None else math.degrees(r.corner) for r in pf.runs],
        } for pf in fit.paths],
        "exact": _exact_summary(res),
        "figure": res.figure.to_dict(),
    }


def _fit_png(res) -> bytes:
    """fit.png's bytes: the arc fit (and exact mode's splines) over the drawing."""
    from ..outputs.plotting import fit_figure

    fig = fit_figure(res.drawing, res.fit, exact=res.exact, unit=res.unit)
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=110)
    return buf.getvalue()


def _write_fit(res, out: Path, png: bytes | None) -> list[Path]:
    """Write fit.json and (given its bytes) fit.png, each whole or not at all."""
    from ..outputs.files import atomic_write, dumps_json

    written = [out / "fit.json"]
    atomic_write(out / "fit.json", dumps_json(_fit_summary(res)))  # strict JSON: NaN written as null
    if png is not None:
        atomic_write(out / "fit.png", png)
        written.append(out / "fit.png")
    return written


def _fit(args) -> int:
    t0 = time.perf_counter()
    res = _resolve(args, args.drawing)
    if res.kind != "drawing":
        raise SkatetraceError(f"{args.drawing!r} is not a drawing: 'fit' takes an SVG or a point list "
                              f"({', '.join(DRAWING_SUFFIXES)})")
    out = Path(args.out)
    paths = _write_fit(res, out, None if args.no_plots else _fit_png(res))
    fit = res.fit
    for note in res.notes:
        print(f"note: {note}")
    print(f"drawing {res.drawing.name}: {len(fit.paths)} path(s), {res.drawing.size():.4g} {res.unit} across")
    print(f"{'path':>4} {'name':>16} {'runs':>5} {'arcs':>5} {'lines':>6} {'greedy':>7} {'min':>5} "
          f"{'hausdorff':>10} {'where (x, y)':>22}")
    for i, pf in enumerate(fit.paths):
        where = "" if pf.where is None else f"({pf.where.x:.4g}, {pf.where.y:.4g})"
        print(f"{i:>4} {pf.name[:16]:>16} {len(pf.runs):>5} {pf.n_arcs:>5} {pf.n_lines:>6} {pf.greedy_count:>7} "
              f"{'-' if pf.min_count is None else pf.min_count:>5} {pf.hausdorff:>10.3g} {where:>22}")
    print(f"arc mode: certified Hausdorff distance {fit.hausdorff:.3g} <= tolerance {res.tol:.3g} {res.unit}")
    if res.exact is not None:
        ex = res.exact
        print(f"exact mode: {ex.n_spirals} spirals, {ex.n_arcs} arcs, {ex.n_lines} lines within {ex.deviation:.3g} "
              f"{res.unit} of the drawing (measured; tolerance {res.exact_tol:.3g})")
    print(f"wrote {', '.join(p.name for p in paths)} to {out}/ in {time.perf_counter() - t0:.1f} s")
    return 0


def _human_limits(args, res, params: SleighParams):
    """The feasibility limits: the skater of ``--height``/``--body-mass`` in metres, else model units."""
    from ..verification.feasibility import HumanLimits

    if res.unit == "m":
        return HumanLimits.for_skater(args.height, args.body_mass, moving_mass=params.m)
    return None  # trace_and_verify then takes model units at the scale of the paper's figure


def _print_feasibility(done) -> None:
    """The second verdict, check by check, and a warning on stderr when a skater could not do it."""
    f = done.feasibility
    if f is None:
        return
    print(f"feasibility: {f.status} (limits for {f.limits.assumptions})")
    if f.status == "not assessed":
        print(f"  {f.message}")
        return
    for c in f.checks:
        print(f"  {'ok' if c.passed else 'BEYOND':>6}  {c.phrase()}")
    info = f.info
    print(f"  peak force on the mass {info['peak_force_on_mass']:.3g} {info['force_unit']} (limit "
          f"{info['force_limit']:.3g}), peak mass kinetic energy {info['peak_mass_kinetic_energy']:.3g} "
          f"{info['energy_unit']}")
    print(f"  at the cusps: mass speed up to {info['max_cusp_mass_speed']:.3g} relative to the stopped blade, velocity "
          f"jump up to {info['max_cusp_impulse']:.3g} {info['impulse_unit']} (impulse); effort (integral of the squared "
          f"force) {info['effort']:.4g}")
    if not f.feasible:
        print(f"skatetrace: warning: {done.verdict}", file=sys.stderr)


@contextmanager
def _compiling():
    """Name each part of the numerical core as this run compiles it (a first run on a machine: numba's
    cache is cold), after one line saying so; silent where everything loads from the cache."""
    from .compiled import first_run

    said = []

    def say(line: str) -> None:
        if not said:
            said.append(True)
            print("skatetrace: first run on this machine: compiling the numerical core, the parts this run needs, "
                  "once (later runs load them)", file=sys.stderr, flush=True)
        print(line, file=sys.stderr, flush=True)

    with first_run(say):
        yield


def _trace(args) -> int:
    from ..outputs.plotting import PlotsAhead
    from ..processes import Background

    t0 = time.perf_counter()
    res = _resolve(args, args.figure)
    # fit.png is drawn in a child while the figure is traced (which leaves a core idle at times),
    # and the other plots' children import matplotlib meanwhile
    drawn = Background(partial(_fit_png, res), args.workers) if res.fit is not None and not args.no_plots else None
    plots = None if args.no_plots else PlotsAhead(args.workers)
    with drawn or nullcontext(), plots or nullcontext():
        return _traced(args, res, drawn, plots, t0)


def _traced(args, res, drawn, plots, t0: float) -> int:
    """``trace`` once the figure is read: ``drawn`` draws fit.png, ``plots`` the others (None without plots)."""
    from ..outputs.results import reporting as writing
    from ..outputs.results import write_results
    from ..pipeline import too_large_to_plan, trace_and_verify, trace_within_default_reach
    from ..verification.verify import reporting as verifying

    figure = res.figure
    base = figure.params or SleighParams()
    params = SleighParams(M=args.M if args.M is not None else base.M, m=args.m if args.m is not None else base.m,
                          I=args.I if args.I is not None else base.I)
    speed = args.speed if args.speed is not None else (2.0 if res.unit == "m" else 1.0)
    # the default reach (not asked for) falls back to the launch-glide-stop manoeuvres where a
    # section has no plan: searching larger reaches for it would only delay that
    options = TraceOptions(speed=speed, reach=_reach(args, res.unit), objective=args.objective,
                           max_accel=args.max_accel, workers=args.workers, reach_hint=args.reach is not None,
                           all_or_nothing=args.reach is None)
    # a default reach plans a figure only up to a size (trace_within_default_reach), which a note says later
    if options.reach is not None and (args.reach is not None or not too_large_to_plan(figure, params, options)):
        print(f"note: planning the mass's motion within {options.reach:.4g} {res.unit if res.unit == 'm' else 'model units'} "
              f"of the blade for least {options.objective} (--reach none: the launch-glide-stop manoeuvres)")
    for note in res.notes:
        print(f"note: {note}")

    status = StatusLine()

    def progress(done, total):
        # the line ends with the round, so that what verification says (compiling, first time) starts a line
        status.show("sections", f"tracing sections {done}/{total}", done == total)

    limits = _human_limits(args, res, params)
    checking = LongWork(status, "verifying: {stage} {done}/{total} sections")
    with planning_progress(options, status), verifying(checking):
        if args.reach is None and options.reach is not None:
            # not asked for: the plan if it traces and verifies, else the launch-glide-stop manoeuvres
            # if they do (the user asked for a trace, not a plan), else the whole plan with its failures
            kept = trace_within_default_reach(figure, params, options, rests=args.rests, rel_tol=args.verify_tol,
                                              limits=limits, progress=progress)
            if kept.fell_back:
                what = {"too large": "this figure is not planned within",
                        "over budget": "the plan was given up within",
                        "unplanned": "not every section could be planned within",
                        "unverified": "the plan's replay failed the verification within"}[kept.fell_back]
                ask = ("Give --reach auto to plan it (tens of seconds or more)"
                       if kept.fell_back in ("too large", "over budget") else "Give --reach to see the plan and its failures")
                print(f"note: {what} the default reach {options.reach:.4g} m ({kept.reason}); traced with the "
                      f"launch-glide-stop manoeuvres instead (as --reach none). {ask}")
            done, options = kept.result, kept.options
        else:
            done = trace_and_verify(figure, params, options, rests=args.rests, rel_tol=args.verify_tol,
                                    limits=limits, progress=progress)
    figure, trace, schedule, states, report = done.figure, done.trace, done.schedule, done.states, done.report
    if done.rests:
        where = ", ".join(f"before piece {pi}" + (f" of curve {ci}" if len(figure.curves) > 1 else "")
                          for ci, pi in done.rests)
        print(f"note: rests added at smooth joins ({where}): sections failed to trace or their replay strayed "
              f"more than allowed; {done.rounds} trace-and-verify rounds")
    if plots is not None:
        plots.start(trace, report, unit=res.unit)  # drawn in its children while the other files are written
    out = Path(args.out)
    with writing(LongWork(status, "{stage}: {done}/{total} rows")):
        write_results(out, trace, schedule, states, report, unit=res.unit, feasibility=done.feasibility)
    if res.fit is not None:
        _write_fit(res, out, None if drawn is None else drawn.result())
    if not args.no_viewer and schedule.t.size < 2:
        print("note: viewer.html not written: no section could be traced, so there is nothing to play")
    elif not args.no_viewer:
        from ..outputs.files import staged
        from ..outputs.playback import load_playback
        from ..outputs.viewer import write_viewer

        # this run's result.json, where it is until the run's files are moved in together; the
        # controls as just written to controls.csv (its floats round-trip), not read back
        columns = {"t": schedule.t, "a": schedule.a, "b": schedule.b, "adot": schedule.adot, "bdot": schedule.bdot,
                   **states}
        write_viewer(load_playback(staged(out / "result.json"), columns), out / "viewer.html")
    if plots is not None:
        plots.write(out)
    elapsed = time.perf_counter() - t0
    unit = "m" if res.unit == "m" else "model units"
    print(f"figure {figure.name}: {len(figure.curves)} curve(s), {len(trace.sections)} section(s), "
          f"M={params.M:g} m={params.m:g} I={params.I:g} ({'SI: kg, kg m^2, m, s' if res.unit == 'm' else 'model units'})")
    planned = options.reach is not None
    extra = f" {'reach':>9} {'link':>10} {'impulse':>9}" if planned else ""
    print(f"{'section':>7} {'pieces':>14} {'length':>9} {'duration':>9} {'max residual':>13}{extra} {'status':>8}")
    for i, s in enumerate(trace.sections):
        resid = max(s.residuals.values()) if s.residuals else float("nan")
        pcs = ",".join(str(p.index) for p in s.section.pieces)
        if len(pcs) > 14:
            pcs = pcs[:6] + ".." + pcs[-6:]
        extra = ""
        if planned:
            m = s.metrics or {}
            extra = (f" {m.get('reach', float('nan')):>9.4f} {m.get('link', '-'):>10} "
                     f"{m.get('link_impulse', float('nan')):>9.3g}")
        print(f"{i:>7} {pcs:>14} {s.length:>9.4f} {s.duration:>9.4f} {resid:>13.2e}{extra} "
              f"{'ok' if s.success else 'FAILED':>8}")
        if not s.success:
            print(f"        reason: {s.message}")
    for c in figure.curves:
        cl = c.closure()
        print(f"curve {c.name}: {'closed' if cl['closed'] else 'open'} (end-to-start gap {cl['position_gap']:.2e}, "
              f"heading gap {cl['heading_gap']:.2e} rad)")
    replayed = schedule.t.size > 0
    if replayed:
        print(f"max deviation from the traced pieces {report.max_deviation:.3e} {unit} (tolerance "
              f"{report.tolerance:.3e}, figure size {report.figure_size:.4g}); max cusp speed "
              f"{report.max_cusp_speed:.3e}")
    else:
        print("nothing was replayed: no section could be traced")
    ok = trace.success and report.success
    if res.fit is not None and replayed:
        size = report.figure_size
        if res.exact is not None:
            bound = res.exact.deviation + report.max_deviation
            allowed = res.exact_tol + args.verify_tol * size
            print(f"arc mode would deviate from the drawing by up to {res.fit.hausdorff:.3e} {unit} (certified arc "
                  f"fit, {res.fit.n_arcs} arcs, {res.fit.n_lines} lines) plus its replay")
            print(f"exact mode: deviation from the drawing <= {bound:.3e} {unit} (curvature splines "
                  f"{res.exact.deviation:.3e} + replay {report.max_deviation:.3e}); allowed {allowed:.3e} "
                  f"(exact tolerance + {args.verify_tol:g} x size)")
        else:
            bound = res.fit.hausdorff + report.max_deviation
            allowed = res.tol + args.verify_tol * size
            print(f"deviation from the drawing <= {bound:.3e} {unit} (certified fit {res.fit.hausdorff:.3e} + replay "
                  f"{report.max_deviation:.3e}); allowed {allowed:.3e} (fit tolerance + {args.verify_tol:g} x size)")
        ok = ok and bound <= allowed
    _print_feasibility(done)
    print(f"verification: {report.status} ({report.message}); wrote {out}/ in {elapsed:.1f} s")
    print(f"verdict: {done.verdict}")
    return 0 if ok else 1


def _pixels(text: str) -> tuple[int, int]:
    try:
        w, h = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise SkatetraceError(f"--size must be WIDTHxHEIGHT in whole pixels, e.g. 800x800; got {text!r}") from None
    return w, h


def _progress_bar(label: str):
    """A progress callback drawing ``label [####....] done/total`` on stderr, redrawn once per percent."""
    shown = [-1]

    def show(done: int, total: int) -> None:
        percent = 100 * done // max(total, 1)
        if percent == shown[0] and done < total:
            return
        shown[0] = percent
        filled = 30 * done // max(total, 1)
        end = "\n" if done >= total else ""
        print(f"\r{label} [{'#' * filled}{'.' * (30 - filled)}] {done}/{total}", end=end, file=sys.stderr,
              flush=True)
    return show


def _still_time(args, pb) -> float:
    """``--time`` (on the clock the frames show: 0 at the start) checked against the figure's duration."""
    if args.time is None:
        return 0.6 * pb.duration
    unit = "s" if pb.unit == "m" else "time units"
    if not (math.isfinite(args.time) and -5e-6 <= args.time <= pb.duration * (1 + 5e-6) + 5e-6):
        raise SkatetraceError(f"--time {args.time:g} is outside the figure's time: give a time from 0 to "
                              f"{pb.duration:.6g} {unit} (the figure's duration)")
    return min(max(args.time, 0.0), pb.duration)


def _animate(args) -> int:
    from ..outputs.animation import SUFFIXES, STILL_SUFFIXES, AnimationOptions, animate, save_still
    from ..outputs.folder import check_finished, check_output_file
    from ..outputs.playback import load_playback

    t0 = time.perf_counter()
    check_output_file(args.output, label="-o", suffixes=SUFFIXES + STILL_SUFFIXES, create_parent=False)
    check_finished(args.source)
    out = Path(args.output)
    if args.time is not None and out.suffix.lower() not in STILL_SUFFIXES:
        raise SkatetraceError(f"--time picks the one frame of a still: use it with -o NAME.png (a "
                              f"{out.suffix.lower()} plays the whole figure)")
    options = AnimationOptions(fps=args.fps, duration=args.duration, size_px=_pixels(args.size))
    pb = load_playback(args.source)
    if out.suffix.lower() in STILL_SUFFIXES:
        at = _still_time(args, pb)
        save_still(pb, out, float(pb.t[0]) + at, options)
        print(f"wrote a still of {pb.name} at t = {at:.6g} {'s' if pb.unit == 'm' else 'time units'} "
              f"to {out} in {time.perf_counter() - t0:.1f} s")
        return 0
    res = animate(pb, out, options, progress=_progress_bar("rendering frames"))
    print(f"wrote {res.path}: {res.frames} frames, {res.width}x{res.height} px, {res.fps:g} fps "
          f"({res.frames / res.fps:.1f} s of video for {pb.duration:.4g} {'s' if pb.unit == 'm' else 'time units'} "
          f"of skating) in {time.perf_counter() - t0:.1f} s")
    return 0


def _view(args) -> int:
    from ..outputs.folder import adopt, check_finished, check_output_file, output_path
    from ..outputs.playback import load_playback
    from ..outputs.viewer import write_viewer

    t0 = time.perf_counter()
    check_finished(args.source)
    src = Path(args.source)
    if args.output is not None:
        output_path(args.output, "-o")  # an empty name is refused, not read as the current folder
    target = Path(args.output) if args.output else (src.parent if src.suffix == ".json" else src) / "viewer.html"
    if target.is_dir():
        target = target / "viewer.html"
    check_output_file(target, label="-o" if args.output else "view", suffixes=(".html", ".htm"))
    pb = load_playback(args.source)
    path = write_viewer(pb, target)
    if path.name == "viewer.html":
        adopt(path)  # in a run's folder, the viewer is that run's: the next run there replaces or removes it
    print(f"wrote {path} ({path.stat().st_size / 1024:.0f} KiB, self-contained: open it in any browser) "
          f"in {time.perf_counter() - t0:.1f} s")
    return 0


def _reproduce(args) -> int:
    from ..paper.report import reproduce, write_report

    methods = [m.strip() for m in args.methods.split(",") if m.strip()]
    try:
        arcs = [int(a) for a in args.arcs.split(",") if a.strip()]
    except ValueError:
        raise SkatetraceError(f"--arcs must be comma-separated arc numbers 1, 2, 3, got {args.arcs!r}") from None
    if args.maxiter is not None and args.maxiter < 1:
        raise SkatetraceError(f"--maxiter must be a positive number of iterations, got {args.maxiter}")
    rep = reproduce(methods, arcs, maxiter=args.maxiter, conditioning=not args.no_conditioning,
                    progress=lambda msg: print(msg, file=sys.stderr, flush=True))
    t0 = time.perf_counter()
    out = Path(args.out)  # "rep/" and "rep" name the same folder; printed once, without a doubled slash
    paths = write_report(rep, out, figures=not args.no_figures)
    # Digits the perturbed re-runs share (or "ill-conditioned (spread ...)"), as report.md prints them.
    table = [["row", "printed error", "published cost", "full dev.", "re-run cost", "full dev.", "exact dev."]]
    for rr in rep.rows:
        err = rr.row.published_error
        table.append([f"Table {rr.row.tables} arc {rr.row.arc}", f"{err:.4g}" if err is not None else "—",
                      rr.text("published", "cost"), rr.text("published", "full_deviation"), rr.text("rerun", "cost"),
                      rr.text("rerun", "full_deviation"), rr.text("exact", "full_deviation")])
    widths = [max(len(r[k]) for r in table) for k in range(len(table[0]))]
    for r in table:
        print("  ".join(c.ljust(w) for c, w in zip(r, widths)).rstrip())
    if args.no_conditioning:
        print("conditioning not measured (--no-conditioning): one run's digits; rows that reach a = 0 are ill-conditioned")
    confirmed = sum(e.confirmed for e in rep.errata)
    print(f"errata: {confirmed} of {len(rep.errata)} confirmed")
    print(f"{rep.message}; computed in {rep.seconds:.0f} s (as report.md says); wrote {len(paths)} files to "
          f"{out.as_posix()}/ (report.md, report.html) in {time.perf_counter() - t0:.0f} s more")
    return 0 if rep.success else 1


def _figures(args) -> int:
    from ..figures.school import school_names

    for name in pattern_names():
        print(f"{name:24s} {pattern(name).description}")
    for name in school_names():
        print(f"school:{name:17s} school figure sized for a skater (--height, --edge, --direction, --foot)")
    return 0


def _check_values(args) -> None:
    """Refuse bad numbers (zero, negative, NaN, infinite, out of range) before any work is done."""
    from ..figures.figure import PARAM_RANGE
    from ..tracing.options import SPEED_RANGE

    def positive(name: str, value, upper: float = math.inf) -> None:
        if value is not None and not (math.isfinite(value) and 0 < value <= upper):
            bound = "" if upper == math.inf else f" at most {upper:g}"
            raise SkatetraceError(f"{name} must be a positive finite number{bound}, got {value!r}")

    if args.command not in ("trace", "fit", "tradeoff"):
        return
    for name, upper in (("height", 1e3), ("body_mass", 1e6), ("blade", 1e3)):
        positive("--" + name.replace("_", "-"), getattr(args, name), upper)
    lengths = [("--size", args.size), ("--tol", args.tol), ("--exact", None if args.exact is True else args.exact)]
    if any(value is not None for _, value in lengths):  # checked for every figure, not only drawings
        from ..drawings.lengths import parse_length

        for name, value in lengths:
            try:
                value is None or parse_length(value)
            except SkatetraceError as exc:
                raise SkatetraceError(f"{name}: {exc}") from None
    if args.command in ("trace", "tradeoff"):
        positive("--max-accel", args.max_accel)
        if args.workers is not None and not 1 <= args.workers <= 1024:
            raise SkatetraceError(f"--workers must be a whole number from 1 to 1024, got {args.workers!r}")
    if args.command == "trace":
        for name in ("M", "m", "I"):
            value = getattr(args, name)
            if value is not None and not PARAM_RANGE[0] <= value <= PARAM_RANGE[1]:
                raise SkatetraceError(f"--{name} must be a positive number between {PARAM_RANGE[0]:g} and "
                                      f"{PARAM_RANGE[1]:g}, got {value!r}")
    if args.command in ("trace", "tradeoff"):
        positive("--verify-tol", args.verify_tol, 1.0)
        if args.speed is not None and not SPEED_RANGE[0] <= args.speed <= SPEED_RANGE[1]:
            raise SkatetraceError(f"--speed must be a positive number between {SPEED_RANGE[0]:g} and "
                                  f"{SPEED_RANGE[1]:g}, got {args.speed!r}")


def _reaches(args, unit: str) -> list[float]:
    """``--reaches`` in the figure's units, or the default sweep around the reach for the figure's units."""
    from ..dynamics.presets import skater_reach

    if args.reaches is None:
        base = skater_reach(args.height) if unit == "m" else 1.0
        return [f * base for f in (0.6, 0.8, 1.0, 1.25, 1.5)]
    return [figure_length(word, unit, "--reaches") for word in args.reaches.split(",")]


def _tradeoff(args) -> int:
    from ..outputs.files import atomic_write, dumps_json, write_atomically
    from ..pipeline import sweep_reach

    t0 = time.perf_counter()
    res = _resolve(args, args.figure)
    params = res.figure.params or SleighParams()
    speed = args.speed if args.speed is not None else (2.0 if res.unit == "m" else 1.0)
    reaches = _reaches(args, res.unit)
    options = TraceOptions(speed=speed, objective=args.objective, max_accel=args.max_accel, workers=args.workers,
                           reach=min(reaches))  # checks the objective's needs before any work
    unit = "m" if res.unit == "m" else "model units"
    print(f"planning {res.figure.name} within {len(reaches)} reaches ({', '.join(f'{r:.3g}' for r in sorted(reaches))} "
          f"{unit}) and with the launch-glide-stop manoeuvres, least {args.objective}")
    sweep = sweep_reach(res.figure, reaches, params, options, rel_tol=args.verify_tol,
                        limits=_human_limits(args, res, params), progress=_progress_bar("reaches"))
    out = Path(args.out)
    atomic_write(out / "tradeoff.json", dumps_json({**sweep.to_dict(), "unit": res.unit}))
    written = ["tradeoff.json"]
    if not args.no_plots:
        from ..outputs.plotting import tradeoff_figure

        fig = tradeoff_figure(sweep, unit=res.unit)
        write_atomically(out / "tradeoff.png", lambda tmp: fig.savefig(tmp, format="png", dpi=110))
        written.append("tradeoff.png")
    print(f"{'reach':>9} {'distance':>9} {'peak force':>11} {'effort':>10} {'duration':>9} {'cusp impulse':>12} "
          f"{'time':>6}  verdict")
    for p in (sweep.reference, *sweep.points):
        name = "none" if p.reach is None else f"{p.reach:.4g}"
        verdict = "verified" if p.success else "FAILED: " + p.message
        if p.success:
            verdict += ", humanly feasible" if p.feasible else ", not humanly feasible"
        print(f"{name:>9} {p.distance:>9.3g} {p.peak_force:>11.3g} {p.effort:>10.3g} {p.duration:>9.4g} "
              f"{p.cusp_impulse:>12.3g} {p.seconds:>5.0f}s  {verdict}")
    smallest = sweep.smallest_reach
    print(f"smallest reach planned and verified: {'none' if smallest is None else f'{smallest:.4g} {unit}'}; wrote "
          f"{', '.join(written)} to {out}/ in {time.perf_counter() - t0:.1f} s")
    return 0 if sweep.success else 1


def _run(args) -> int:
    commands = {"figures": _figures, "fit": _fit, "reproduce": _reproduce, "animate": _animate, "view": _view,
                "trace": _trace, "tradeoff": _tradeoff, "robustness": _robustness}
    if args.command in ("figures", "animate", "view"):  # nothing compiled: numba need not even be imported
        return commands[args.command](args)
    with _compiling():
        return commands[args.command](args)


def _output_folder(args):
    """The ``--out`` folder of ``trace``, ``fit`` and ``reproduce``, checked (and created) before any work."""
    from ..outputs.folder import OutputFolder

    if args.command in ("trace", "fit", "tradeoff"):
        return OutputFolder(args.out, args.command)
    if args.command == "reproduce":
        return OutputFolder(args.out, args.command, subfolders=() if args.no_figures else ("figures",))
    return None


def _finish_folder(folder) -> None:
    """Remove the files of an earlier run this one did not write, and say which."""
    removed = folder.finish()
    if removed:
        print(f"note: removed {len(removed)} file(s) an earlier run wrote to {folder.path}/ and this one did not "
              f"(so that the folder holds one run's results): {', '.join(removed)}")


def _attached(parser: argparse.ArgumentParser, argv: list[str]) -> list[str]:
    """``argv`` with a value that starts with ``-`` attached to its option (``--size -3m`` as ``--size=-3m``).

    argparse takes ``-3m`` for an option and says "expected one argument"; attached, the value
    reaches the option's own check, which says what is wrong with it.
    """
    takes_value, options = set(), set()
    subparsers = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    for p in [parser] + [sp for a in subparsers for sp in a.choices.values()]:
        for action in p._actions:
            options.update(action.option_strings)
            if action.option_strings and action.nargs is None and not isinstance(action, argparse._HelpAction):
                takes_value.update(s for s in action.option_strings if s.startswith("--"))
    out, i = [], 0
    while i < len(argv):
        word = argv[i]
        if (word in takes_value and i + 1 < len(argv) and argv[i + 1].startswith("-") and argv[i + 1] not in options
                and argv[i + 1] != "--"):
            out.append(f"{word}={argv[i + 1]}")
            i += 2
            continue
        out.append(word)
        i += 1
    return out


def main(argv: list[str] | None = None) -> int:
    """Run the command line; returns the exit code."""
    parser = build_parser()
    try:
        args = parser.parse_args(_attached(parser, list(sys.argv[1:] if argv is None else argv)))
    except SystemExit as exc:
        return int(exc.code or 0)
    try:
        _check_values(args)
        folder = _output_folder(args)  # checked before any work
        if folder is None:
            return _run(args)
        try:
            with folder:
                code = _run(args)
        except Exception:
            if folder.written:
                _finish_folder(folder)  # what the run wrote before its error, as one run's files
            else:
                folder.discard()  # the folders the check created, if nothing was written into them
            raise
        except BaseException:
            folder.discard()  # interrupted: the earlier run's files stay as they were
            raise
        _finish_folder(folder)
        return code
    except (SkatetraceError, ValueError, TypeError, OSError) as exc:
        print(f"skatetrace: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("\nskatetrace: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
