"""Benchmark: a long figure of distinct arcs (200 by default), traced, sampled and verified.

Run: python bench/bench_long_figure.py [--pieces N] [--seed S] [--runs R] [--no-verify] [--quiet]

The figure (``_common.distinct_arcs``): N arcs of curvature magnitude 0.2 to 2 (random sign) and
sweep 30 to 200 degrees, joined at cusps with pivots of -150 to 150 degrees, the paper's M = 2,
m = 1, I = 3, from ``numpy.random.default_rng(seed)``. Every arc is its own section and no two are
alike, so nothing is reused from the tracer's cache. After an untimed warm-up (one small figure),
R runs (median reported) of trace / sample / verify, verify split into its replay (the integration
of the full dynamics) and its checks. Sections that fail to trace or to verify are
listed, never hidden. Timings are never asserted.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from skatetrace import trace_figure
from skatetrace.verification.verify import schedule_from_trace

if str(Path(__file__).resolve().parent) not in sys.path:
    sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import distinct_arcs, median, quiet_print, timed, timed_verify, warm_up  # noqa: E402


def measure(n: int, seed: int = 0, runs: int = 1, do_verify: bool = True) -> dict:
    """Trace (and unless ``do_verify`` is false, sample and verify) ``distinct_arcs(n, seed)``."""
    fig = distinct_arcs(n, seed)
    t_trace, t_sample, t_verify, t_replay = [], [], [], []
    tr = rep = None
    for _ in range(runs):
        tr, dt = timed(trace_figure, fig)
        t_trace.append(dt)
        if do_verify:
            (sch, _), dt = timed(schedule_from_trace, tr)
            t_sample.append(dt)
            rep, dt, dr = timed_verify(tr, sch)
            t_verify.append(dt)
            t_replay.append(dr)
    failed = [{"section": i, "status": s.status.name, "message": s.message}
              for i, s in enumerate(tr.sections) if not s.success]
    resid = [max(s.residuals.values()) for s in tr.sections if s.success and s.residuals]
    out = {"pieces": n, "seed": seed, "runs": runs, "sections": len(tr.sections),
           "distinct_sections": len({id(s.phases) for s in tr.sections}),
           "traced": len(tr.sections) - len(failed), "failed": failed, "trace_success": tr.success,
           "max_residual": max(resid) if resid else float("nan"),
           "nfev": sum(s.nfev for s in tr.sections), "figure_size": fig.size(),
           "length": sum(p.length for p in fig.curves[0].pieces), "duration": tr.duration,
           "trace_times": t_trace, "trace_s": median(t_trace), "verified": do_verify}
    if do_verify:
        bad = [s for s in rep.sections if not s.get("passed")]
        out.update({"sample_times": t_sample, "verify_times": t_verify, "sample_s": median(t_sample),
                    "verify_s": median(t_verify), "replay_s": median(t_replay),
                    "checks_s": median([v - r for v, r in zip(t_verify, t_replay)]), "verify_success": rep.success, "verify_message": rep.message,
                    "verify_failed": [{"section": s["section"], "traced": s.get("traced", False),
                                       "message": s.get("message", "")} for s in bad],
                    "max_deviation": rep.max_deviation, "tolerance": rep.tolerance,
                    "max_cusp_speed": rep.max_cusp_speed})
        out["total_s"] = out["trace_s"] + out["sample_s"] + out["verify_s"]
    return out


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--pieces", type=int, default=200, help="number of distinct arcs (default 200)")
    ap.add_argument("--seed", type=int, default=0, help="seed of numpy.random.default_rng (default 0)")
    ap.add_argument("--runs", type=int, default=1, help="timed runs, median reported (default 1)")
    ap.add_argument("--no-verify", action="store_true", help="trace only")
    ap.add_argument("--quiet", action="store_true", help="print nothing; just return the results")
    args = ap.parse_args(argv)
    print = quiet_print(args.quiet)
    warm_up()
    r = measure(args.pieces, args.seed, args.runs, not args.no_verify)
    print(f"{r['pieces']} distinct arcs (seed {r['seed']}, total length {r['length']:.1f}, figure size "
          f"{r['figure_size']:.1f}): {r['sections']} sections, {r['distinct_sections']} solved, "
          f"{r['traced']} traced, {len(r['failed'])} failed, largest residual {r['max_residual']:.1e}")
    print(f"  trace   {r['trace_s']:8.3f} s   ({r['trace_s'] / r['pieces'] * 1e3:.1f} ms per section, "
          f"{r['nfev']} integrations)")
    if r["verified"]:
        print(f"  sample  {r['sample_s']:8.3f} s")
        print(f"  verify  {r['verify_s']:8.3f} s   ({'passed' if r['verify_success'] else 'FAILED'}: "
              f"max deviation {r['max_deviation']:.2e}, tolerance {r['tolerance']:.2e}, "
              f"max cusp speed {r['max_cusp_speed']:.2e})")
        print(f"    replay {r['replay_s']:7.3f} s   (integrating the full dynamics; simulated duration "
              f"{r['duration']:.1f}, {r['replay_s'] / r['duration'] * 1e3:.1f} ms per time unit)")
        print(f"    checks {r['checks_s']:7.3f} s   (deviations, cusp speeds, invariants)")
        print(f"  total   {r['total_s']:8.3f} s")
    for f in r["failed"]:
        print(f"  section {f['section']} FAILED to trace: {f['message']}")
    for f in r.get("verify_failed", []):
        print(f"  section {f['section']} failed verification {f['message']}")
    return r


if __name__ == "__main__":
    main(sys.argv[1:])
