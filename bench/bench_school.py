"""Benchmark: school figures end to end for a 1.7 m skater (trace, sample, verify, rests as needed).

Run: python bench/bench_school.py [NAME ...]     (default: all seventeen figures)
Prints one row per figure: wall time, sections, rests added, trace-and-verify rounds, the largest
deviation of the replay from the figure against its tolerance, the largest cusp speed, and the
mass's largest distance from the blade. Nothing is asserted about time.
"""

import sys
import time

from skatetrace import TraceOptions, school_figure, school_names, skater_params, trace_and_verify


def main(names=None) -> list[dict]:
    names = list(names or []) or school_names()
    params = skater_params(height=1.7)
    rows = []
    print(f"{'figure':24s} {'time':>7s} {'sections':>8s} {'rests':>5s} {'rounds':>6s} {'deviation':>10s} "
          f"{'tolerance':>10s} {'cusp speed':>10s} {'max |a|,|b|':>11s} status")
    for name in names:
        t0 = time.perf_counter()
        res = trace_and_verify(school_figure(name, height=1.7), params, TraceOptions(speed=2.0))
        dt = time.perf_counter() - t0
        reach = max((max(s.metrics.get("max_abs_a", 0.0), s.metrics.get("max_abs_b", 0.0))
                     for s in res.trace.sections), default=float("nan"))
        row = {"figure": name, "seconds": dt, "sections": len(res.trace.sections), "rests": len(res.rests),
               "rounds": res.rounds, "deviation": res.report.max_deviation, "tolerance": res.report.tolerance,
               "cusp_speed": res.report.max_cusp_speed, "reach": reach, "success": res.success}
        rows.append(row)
        print(f"{name:24s} {dt:7.1f} {row['sections']:8d} {row['rests']:5d} {row['rounds']:6d} "
              f"{row['deviation']:10.2e} {row['tolerance']:10.2e} {row['cusp_speed']:10.2e} {reach:11.2f} "
              f"{'passed' if res.success else 'FAILED: ' + res.message}", flush=True)
    return rows


if __name__ == "__main__":
    main(sys.argv[1:])
