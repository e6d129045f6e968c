"""Benchmark: the double flower end to end (trace, sample, verify), median of N runs.

Run: python bench/bench_double_flower.py [N]
Reports the median wall time of each stage and the ratio of the total to tracing alone.
"""

import statistics
import sys
import time

from skatetrace import pattern, trace_figure, verify
from skatetrace.verify import schedule_from_trace


def main(n: int = 3) -> None:
    stages = {"trace": [], "schedule": [], "verify": [], "total": []}
    for _ in range(n):
        t0 = time.perf_counter()
        tr = trace_figure(pattern("double-flower"))
        t1 = time.perf_counter()
        sch, _ = schedule_from_trace(tr)
        t2 = time.perf_counter()
        rep = verify(tr, sch)
        t3 = time.perf_counter()
        assert tr.success and rep.success, (tr.message, rep.message)
        for k, v in zip(stages, (t1 - t0, t2 - t1, t3 - t2, t3 - t0)):
            stages[k].append(v)
    med = {k: statistics.median(v) for k, v in stages.items()}
    for k, v in med.items():
        print(f"{k:9s} {v:8.2f} s   ({v / med['trace']:.2f} x trace)")
    print(f"max deviation {rep.max_deviation:.2e}, max cusp speed {rep.max_cusp_speed:.2e}")


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 3)
