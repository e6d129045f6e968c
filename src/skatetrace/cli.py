"""Command-line interface: ``skatetrace trace``, ``skatetrace figures``, ``skatetrace reproduce``.

The only module that prints or exits. Exit codes: 0 success, 1 a solve or verification that
failed, 2 a usage error (bad arguments, unreadable or malformed figure file).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from .errors import SkatetraceError
from .figure import load_figure
from .model import SleighParams
from .patterns import pattern, pattern_names
from .tracing import TraceOptions, trace_figure

__all__ = ["main"]


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="skatetrace", description="Controls that make a skater trace a figure exactly.")
    sub = p.add_subparsers(dest="command", required=True)
    t = sub.add_parser("trace", help="trace a figure, verify it by re-simulation, write results")
    t.add_argument("figure", help=f"a built-in figure ({', '.join(pattern_names())}) or a figure JSON file")
    t.add_argument("--out", default="out", help="output folder (default: out)")
    t.add_argument("--M", type=float, help="sleigh mass (default: the figure's, else 2)")
    t.add_argument("--m", type=float, help="moving mass (default: the figure's, else 1)")
    t.add_argument("--I", type=float, help="sleigh inertia about the contact point (default: the figure's, else 3)")
    t.add_argument("--speed", type=float, default=1.0, help="glide speed (default: 1)")
    t.add_argument("--tol", type=float, default=1e-6, help="allowed deviation as a fraction of the figure size (default: 1e-6)")
    t.add_argument("--no-plots", action="store_true", help="skip the PNG plots")
    sub.add_parser("figures", help="list the built-in figures")
    r = sub.add_parser("reproduce", help="reproduce the paper's tables three ways, with figures and errata")
    r.add_argument("--out", default="rep", help="output folder (default: rep)")
    r.add_argument("--methods", default="main,point,length",
                   help="comma-separated subset of main (Tables 1-2), point (3-4), length (5-6)")
    r.add_argument("--arcs", default="1,2,3", help="comma-separated subset of the arcs 1, 2, 3")
    r.add_argument("--maxiter", type=int, help="cap on BFGS iterations of the re-run procedure (default: scipy's)")
    r.add_argument("--no-figures", action="store_true", help="skip the figures (tables and errata only)")
    return p


def _load(name: str):
    if name in pattern_names():
        return pattern(name)
    path = Path(name)
    if path.suffix.lower() == ".json" or path.exists():
        return load_figure(path)
    raise SkatetraceError(f"unknown figure {name!r}: not a built-in ({', '.join(pattern_names())}) and no such file")


def _trace(args) -> int:
    from .io import write_results
    from .verify import schedule_from_trace, verify

    t0 = time.perf_counter()
    figure = _load(args.figure)
    base = figure.params or SleighParams()
    params = SleighParams(M=args.M if args.M is not None else base.M, m=args.m if args.m is not None else base.m,
                          I=args.I if args.I is not None else base.I)
    options = TraceOptions(speed=args.speed)

    def progress(done, total):
        print(f"\rtracing sections {done}/{total}", end="", file=sys.stderr, flush=True)

    trace = trace_figure(figure, params, options, progress=progress)
    print(file=sys.stderr)
    schedule, states = schedule_from_trace(trace)
    report = verify(trace, schedule, rel_tol=args.tol)
    out = Path(args.out)
    write_results(out, trace, schedule, states, report)
    if not args.no_plots:
        from .plotting import save_all

        save_all(trace, report, out)
    elapsed = time.perf_counter() - t0
    print(f"figure {figure.name}: {len(figure.curves)} curve(s), {len(trace.sections)} section(s), "
          f"M={params.M:g} m={params.m:g} I={params.I:g}")
    print(f"{'section':>7} {'pieces':>14} {'length':>9} {'duration':>9} {'max residual':>13} {'status':>8}")
    for i, s in enumerate(trace.sections):
        res = max(s.residuals.values()) if s.residuals else float("nan")
        pcs = ",".join(str(p.index) for p in s.section.pieces)
        print(f"{i:>7} {pcs:>14} {s.length:>9.4f} {s.duration:>9.4f} {res:>13.2e} {'ok' if s.success else 'FAILED':>8}")
        if not s.success:
            print(f"        reason: {s.message}")
    for c in figure.curves:
        cl = c.closure()
        print(f"curve {c.name}: {'closed' if cl['closed'] else 'open'} (end-to-start gap {cl['position_gap']:.2e}, "
              f"heading gap {cl['heading_gap']:.2e} rad)")
    print(f"max deviation {report.max_deviation:.3e} (tolerance {report.tolerance:.3e}, figure size {report.figure_size:.4g}); "
          f"max cusp speed {report.max_cusp_speed:.3e}")
    print(f"verification: {report.status} ({report.message}); wrote {out}/ in {elapsed:.1f} s")
    return 0 if (trace.success and report.success) else 1


def _reproduce(args) -> int:
    from .paper.report import reproduce, write_report

    methods = [m.strip() for m in args.methods.split(",") if m.strip()]
    try:
        arcs = [int(a) for a in args.arcs.split(",") if a.strip()]
    except ValueError:
        raise SkatetraceError(f"--arcs must be comma-separated arc numbers 1, 2, 3, got {args.arcs!r}") from None
    if args.maxiter is not None and args.maxiter < 1:
        raise SkatetraceError(f"--maxiter must be a positive number of iterations, got {args.maxiter}")
    t0 = time.perf_counter()
    rep = reproduce(methods, arcs, maxiter=args.maxiter,
                    progress=lambda msg: print(msg, file=sys.stderr, flush=True))
    paths = write_report(rep, args.out, figures=not args.no_figures)
    print(f"{'row':>16} {'printed error':>13} {'published cost':>14} {'full dev.':>9} {'re-run cost':>11} "
          f"{'full dev.':>9} {'exact dev.':>10}")
    for rr in rep.rows:
        err = rr.row.published_error
        print(f"{'Table ' + rr.row.tables + ' arc ' + str(rr.row.arc):>16} {err if err is not None else float('nan'):>13.4g} "
              f"{rr.published.cost:>14.3g} {rr.published.full_deviation:>9.2g} {rr.rerun.cost:>11.3g} "
              f"{rr.rerun.full_deviation:>9.2g} {rr.exact.full_deviation:>10.2g}")
    confirmed = sum(e.confirmed for e in rep.errata)
    print(f"errata: {confirmed} of {len(rep.errata)} confirmed")
    print(f"{rep.message}; wrote {len(paths)} files to {args.out}/ (report.md, report.html) in "
          f"{time.perf_counter() - t0:.0f} s")
    return 0 if rep.success else 1


def main(argv: list[str] | None = None) -> int:
    """Run the command line; returns the exit code."""
    parser = _parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:
        return int(exc.code or 0)
    try:
        if args.command == "figures":
            for name in pattern_names():
                print(f"{name:22s} {pattern(name).description}")
            return 0
        if args.command == "reproduce":
            return _reproduce(args)
        return _trace(args)
    except (SkatetraceError, ValueError, TypeError) as exc:
        print(f"skatetrace: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
