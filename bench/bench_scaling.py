"""Benchmark: how the cost grows with the number of pieces and with the requested fit tolerance.

Run: python bench/bench_scaling.py [--quick] [--sizes N ...] [--runs R] [--verify-max N] [--budget S]
                                   [--tols T ...] [--trace-tols T ...] [--quiet]

Pieces: ``_common.distinct_arcs(n)`` (distinct arcs joined at cusps, seed 0; the figures are nested,
each size's arcs the first of the next) for each size (default
1, 10, 100, 1000; ``--quick`` keeps those <= 100): trace time for every size, sample and verify
times for sizes up to ``--verify-max``, each the median of ``--runs`` runs (default 3: one run
alone lets a moment of load on a shared machine bend the slope). A size is not run (the reason recorded) when its trace time,
extrapolated from the sizes before it (see ``extrapolate``: never below linear), exceeds ``--budget``
seconds (default 600); it is traced but not verified when trace + sample + verify would exceed it. Least-squares slopes of
log(time) against log(pieces), over all measured sizes and over sizes >= 10 (where per-call overhead
no longer dominates): a slope near 1 is linear growth. Verify is split into its replay (integration
of the full dynamics) and its checks; their slopes against the simulated duration are given too.

Tolerance: ``examples/serpentine.svg`` (or ``--drawing``) scaled to 6 m, fitted with ``fit_drawing`` at tolerances
1e-2 to 1e-5 of its size (median of 3 fits): arcs and lines used, certified bound / tolerance, fit
time; the resulting figure (consecutive equal arcs merged, as the CLI does; a 1.7 m skater's
parameters, 2 m/s) traced at the ``--trace-tols`` (default 1e-2, 1e-3, 1e-4). Slopes of log(arcs)
and log(fit time) against log(1 / tolerance). Timings are never asserted.
"""

from __future__ import annotations

import argparse
import math
import sys
import warnings
from pathlib import Path

from skatetrace import Figure, TraceOptions, figure_from_fit, fit_drawing, read_svg, skater_params, trace_figure

HERE = Path(__file__).resolve().parent
if str(HERE) not in sys.path:
    sys.path.insert(0, str(HERE))
from _common import loglog_slope, median, quiet_print, timed, warm_up  # noqa: E402
from bench_long_figure import measure  # noqa: E402

SERPENTINE = HERE.parent / "examples" / "serpentine.svg"


def extrapolate(rows, key: str, n: int) -> float:
    """Time of stage ``key`` at ``n`` pieces, from the measured sizes: a power law through the last two
    (exponent clamped to [1, 3], so never below linear), or linear from a single one; 0 with none."""
    done = [r for r in rows if not r["skipped"] and r.get(key)]
    if not done:
        return 0.0
    last = done[-1]
    slope = 1.0
    if len(done) >= 2 and done[-2]["pieces"] < last["pieces"]:
        a = done[-2]
        slope = math.log(last[key] / a[key]) / math.log(last["pieces"] / a["pieces"])
        slope = min(max(slope, 1.0), 3.0)
    return last[key] * (n / last["pieces"]) ** slope


def pieces_scaling(sizes, verify_max: int, budget: float, print=print, runs: int = 3) -> dict:
    rows = []
    print(f"{'pieces':>6} {'sim time':>8} {'trace s':>8} {'ms/piece':>8} {'sample s':>8} {'verify s':>8} "
          f"{'ms/piece':>8} {'replay s':>8} {'checks s':>8} {'failed':>6} {'verified':>8}  note")
    for n in sizes:
        notes = []
        est_trace = extrapolate(rows, "trace_s", n)
        if est_trace > budget:
            rows.append({"pieces": n, "skipped": True, "trace_s": None, "verify_s": None,
                         "note": f"not run: trace extrapolated to {est_trace:.0f} s > budget {budget:.0f} s"})
            print(f"{n:>6} {'-':>8}  {rows[-1]['note']}")
            continue
        est_ver = extrapolate(rows, "sample_s", n) + extrapolate(rows, "verify_s", n)
        do_verify = n <= verify_max and est_trace + est_ver <= budget
        if n > verify_max:
            notes.append(f"verification skipped: {n} > --verify-max {verify_max}")
        elif not do_verify:
            notes.append(f"verification skipped: trace + sample + verify extrapolated to {est_trace + est_ver:.0f} s "
                         f"> budget {budget:.0f} s")
        elif est_trace + est_ver > 0:
            notes.append(f"extrapolated {est_trace + est_ver:.0f} s")
        r = measure(n, 0, runs, do_verify)
        r["skipped"] = False
        r["note"] = "; ".join(notes)
        if r["failed"]:
            r["note"] = "; ".join(filter(None, [r["note"], f"{len(r['failed'])} sections failed to trace"]))
        rows.append(r)
        ver = (f"{r['sample_s']:>8.2f} {r['verify_s']:>8.2f} {r['verify_s'] / n * 1e3:>8.1f} {r['replay_s']:>8.2f} "
               f"{r['checks_s']:>8.2f}" if do_verify else f"{'-':>8} {'-':>8} {'-':>8} {'-':>8} {'-':>8}")
        verified = ("passed" if r["verify_success"] else "FAILED") if do_verify else "-"
        print(f"{n:>6} {r['duration']:>8.1f} {r['trace_s']:>8.2f} {r['trace_s'] / n * 1e3:>8.1f} {ver} {len(r['failed']):>6} "
              f"{verified:>8}  {r['note']}")
    done = [r for r in rows if not r["skipped"]]
    ver = [r for r in done if r.get("verify_s")]

    def slopes(key, rs):
        return {"all": loglog_slope([r["pieces"] for r in rs], [r[key] for r in rs]),
                "ge10": loglog_slope([r["pieces"] for r in rs if r["pieces"] >= 10],
                                     [r[key] for r in rs if r["pieces"] >= 10])}

    out = {"rows": rows, "budget_s": budget, "verify_max": verify_max,
           "slope_trace": slopes("trace_s", done), "slope_sample": slopes("sample_s", ver),
           "slope_verify": slopes("verify_s", ver), "slope_replay": slopes("replay_s", ver),
           "slope_checks": slopes("checks_s", ver), "slope_total": slopes("total_s", ver),
           # the replay integrates the simulated time, so its cost follows that rather than the count
           "slope_verify_vs_duration": loglog_slope([r["duration"] for r in ver], [r["verify_s"] for r in ver]),
           "slope_replay_vs_duration": loglog_slope([r["duration"] for r in ver], [r["replay_s"] for r in ver])}
    for k in ("trace", "sample", "verify", "replay", "checks", "total"):
        s = out[f"slope_{k}"]
        print(f"slope of log({k} time) vs log(pieces): {s['all']:.3f} over all sizes, {s['ge10']:.3f} over sizes >= 10")
    print(f"slope of log(verify time) vs log(simulated duration): {out['slope_verify_vs_duration']:.3f}; "
          f"of log(replay time): {out['slope_replay_vs_duration']:.3f}")
    return out


def tolerance_scaling(tols, trace_tols, fit_runs: int = 3, print=print, source: Path = SERPENTINE) -> dict:
    source = Path(source)
    drawing = read_svg(source).scaled_to(6.0, "m")
    size = drawing.size()
    params = skater_params(height=1.7)
    rows = []
    print(f"{source.name[:16]:>16} at 6 m: {'tol/size':>8} {'arcs':>5} {'lines':>5} {'bound/tol':>9} {'fit s':>7} "
          f"{'pieces':>6} {'sections':>8} {'trace s':>8} {'traced':>6}")
    for rel in tols:
        times = []
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            for _ in range(fit_runs):
                fit, dt = timed(fit_drawing, drawing, rel * size)
                times.append(dt)
        row = {"tol_rel": rel, "tol": rel * size, "fit_success": fit.success, "arcs": fit.n_arcs,
               "lines": fit.n_lines, "bound_over_tol": fit.hausdorff / (rel * size), "fit_s": median(times),
               "fit_times": times, "traced": False}
        if fit.success:
            fig = figure_from_fit(fit, name=drawing.name, params=params)
            fig = Figure(fig.name, tuple(c.merged() for c in fig.curves), fig.params)
            row["pieces"] = sum(len(c.pieces) for c in fig.curves)
            row["sections"] = sum(len(c.sections()) for c in fig.curves)
            if any(math.isclose(rel, t, rel_tol=1e-9) for t in trace_tols):
                tr, dt = timed(trace_figure, fig, params, TraceOptions(speed=2.0))
                row.update({"traced": True, "trace_s": dt, "trace_success": tr.success,
                            "trace_failed": [s.message for s in tr.sections if not s.success]})
        rows.append(row)
        tail = (f"{row['trace_s']:>8.2f} {'yes' if row['trace_success'] else 'FAILED':>6}" if row["traced"]
                else f"{'-':>8} {'-':>6}")
        print(f"{'':22s}{rel:>8.0e} {row['arcs']:>5d} {row['lines']:>5d} {row['bound_over_tol']:>9.3f} "
              f"{row['fit_s']:>7.3f} {row.get('pieces', 0):>6d} {row.get('sections', 0):>8d} {tail}")
    inv = [1.0 / r["tol_rel"] for r in rows]
    try:
        shown = str(source.resolve().relative_to(HERE.parent))
    except ValueError:
        shown = str(source)
    out = {"drawing": shown, "size_m": size, "rows": rows,
           "slope_arcs": loglog_slope(inv, [r["arcs"] + r["lines"] for r in rows]),
           "slope_fit_time": loglog_slope(inv, [r["fit_s"] for r in rows])}
    print(f"slope of log(arcs + lines) vs log(1/tol): {out['slope_arcs']:.3f}; "
          f"of log(fit time): {out['slope_fit_time']:.3f}")
    return out


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="sizes <= 100 only")
    ap.add_argument("--sizes", type=int, nargs="+", default=[1, 10, 100, 1000], help="numbers of distinct arcs")
    ap.add_argument("--runs", type=int, default=3, help="runs per size, median reported (default 3)")
    ap.add_argument("--verify-max", type=int, default=1000, help="verify sizes up to this (default 1000)")
    ap.add_argument("--budget", type=float, default=600.0,
                    help="skip a stage of a size whose time, extrapolated linearly, exceeds this (s; default 600)")
    ap.add_argument("--tols", type=float, nargs="*", default=[1e-2, 1e-3, 1e-4, 1e-5],
                    help="fit tolerances relative to the drawing's size (none: skip the tolerance part)")
    ap.add_argument("--trace-tols", type=float, nargs="*", default=[1e-2, 1e-3, 1e-4],
                    help="of those, the ones whose figure is traced")
    ap.add_argument("--fit-runs", type=int, default=3, help="fits per tolerance, median reported (default 3)")
    ap.add_argument("--drawing", default=str(SERPENTINE), help="SVG for the tolerance part (default examples/serpentine.svg)")
    ap.add_argument("--quiet", action="store_true", help="print nothing; just return the results")
    args = ap.parse_args(argv)
    print = quiet_print(args.quiet)
    sizes = sorted(set(n for n in args.sizes if n <= 100 or not args.quick))
    warm_up()
    out = {"quick": args.quick, "pieces": pieces_scaling(sizes, args.verify_max, args.budget, print, args.runs)}
    if args.tols:
        out["tolerance"] = tolerance_scaling(args.tols, args.trace_tols, args.fit_runs, print, args.drawing)
    return out


if __name__ == "__main__":
    main(sys.argv[1:])
