"""Benchmark: the paper's procedure against the exact engine on the same arcs (Tables 1-2).

Run: python bench/bench_paper_arcs.py [N] [--maxiter K] [--quiet] [--no-warmup]

For each of the paper's three arcs, in one process:
- baseline: the paper-style procedure (scipy BFGS over solve_ivp BDF with a stop event, from the
  Table 2 guess), its residual |L_s - L_d| (reduced model, accurate re-evaluation) and the largest
  end speed;
- exact: skatetrace tracing the same arc rest to rest, its Newton residual (end speed and length)
  and the largest end speed of the traced arc.
Prints median times over N runs and the ratio baseline / exact (machine noise cancels in a ratio).
Before timing, the exact engine traces arc 1 once untimed, so its compiled integrator is loaded
(``--no-warmup`` leaves the first exact run cold). ``main`` returns one dict per arc; ``--quiet``
prints nothing (``bench/run_all.py`` makes its own table).
"""

import argparse
import statistics
import sys
import time
from pathlib import Path

from skatetrace import Curve, Figure, Pose, Segment, SleighParams, TraceOptions, trace_figure
from skatetrace.paper import TIGHT_SOLVER, paper_cost, paper_rows, run_procedure

if str(Path(__file__).resolve().parent) not in sys.path:
    sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import quiet_print  # noqa: E402


def exact_arc(row):
    start = Pose(row.initial[3], row.initial[4], row.initial[2])
    fig = Figure(row.key, (Curve((Segment(1.0 / row.radius, row.exact_length),), start=start),), SleighParams())
    return trace_figure(fig, options=TraceOptions())


def main(argv=None) -> list[dict]:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("n", nargs="?", type=int, default=3, help="runs per arc (median reported)")
    ap.add_argument("--maxiter", type=int, default=None, help="cap on BFGS iterations (default: scipy's)")
    ap.add_argument("--quiet", action="store_true", help="print nothing; just return the rows")
    ap.add_argument("--no-warmup", action="store_true", help="no untimed exact run before timing")
    args = ap.parse_args(argv)
    print = quiet_print(args.quiet)
    rows = [r for r in paper_rows() if r.method == "main"]
    if not args.no_warmup:
        exact_arc(rows[0])
    out = []
    print(f"{'arc':>4} {'baseline s':>10} {'exact s':>8} {'ratio':>7} {'baseline |dL|':>13} {'baseline end v':>14} "
          f"{'exact residual':>14} {'exact end v':>11}")
    for row in rows:
        tb, te = [], []
        for _ in range(args.n):
            t0 = time.perf_counter()
            proc = run_procedure(row, maxiter=args.maxiter)
            tb.append(time.perf_counter() - t0)
            t0 = time.perf_counter()
            tr = exact_arc(row)
            te.append(time.perf_counter() - t0)
        cost, arc = paper_cost(row, proc.values, options=TIGHT_SOLVER)
        base_res = abs(arc.length - row.target_length)
        base_v = max(abs(v) for v in arc.end_speeds())
        sec = tr.sections[0]
        ex_res = max(sec.residuals.values())
        v = sec.evaluate([0.0, sec.duration])["xi2"]
        ex_v = max(abs(float(x)) for x in v)
        mb, me = statistics.median(tb), statistics.median(te)
        out.append({"arc": row.arc, "baseline_s": mb, "exact_s": me, "ratio": mb / me, "baseline_residual": base_res,
                    "baseline_end_speed": base_v, "exact_residual": ex_res, "exact_end_speed": ex_v,
                    "exact_success": tr.success, "exact_nfev": sec.nfev, "runs": args.n,
                    "baseline_times": tb, "exact_times": te})
        print(f"{row.arc:>4} {mb:>10.3f} {me:>8.3f} {mb / me:>7.2f} {base_res:>13.3e} {base_v:>14.2e} "
              f"{ex_res:>14.2e} {ex_v:>11.2e}")
    return out


if __name__ == "__main__":
    main()
