"""Benchmark: robustness of the school figures (1.7 m skater, planned within 0.5 m) and the double flower.

Run: python bench/bench_robustness.py [NAME ...] [--trials N] [--steps K]   (default: the seventeen school
figures and the double flower, 32 trials, the command's steps)
Each figure is traced with the command line into a temporary folder (school figures with ``--reach 0.5m``,
the double flower as the README traces it) and studied with ``skatetrace robustness`` at its defaults:
issue 16's scenario (M, m, I each within +-5 %, 1 mm / 0.5 deg, 10 ms; in model units 1e-4 of the size and
0.01). Prints one row per figure: the open and the closed loop's p95 deviation relative to the figure's
size, the trials that diverged, the closed loop's largest cusp speed, and the wall times. Nothing is
asserted.
"""

import contextlib
import io
import json
import sys
import tempfile
import time
from pathlib import Path

from skatetrace.cli import main as cli
from skatetrace import school_names


def _rel(stats: dict, size: float) -> str:
    v = stats["p95"]
    return "diverged" if v is None else f"{v / size:.2e}"


def study(name: str, trials: int, steps: int | None = None) -> dict:
    """Trace ``name`` and study it; returns robustness.json's content with the wall times."""
    source, extra = (f"school:{name}", ["--reach", "0.5m"]) if name != "double-flower" else (name, [])
    with tempfile.TemporaryDirectory() as tmp, contextlib.redirect_stdout(io.StringIO()), \
            contextlib.redirect_stderr(io.StringIO()):
        t0 = time.perf_counter()
        traced = cli(["trace", source, *extra, "--out", tmp, "--no-plots", "--no-viewer"])
        t1 = time.perf_counter()
        if traced not in (0, 1):
            return {"figure": name, "error": f"trace exited {traced}"}
        code = cli(["robustness", tmp, "--trials", str(trials), "--no-plots",
                    *([] if steps is None else ["--steps", str(steps)])])
        t2 = time.perf_counter()
        path = Path(tmp) / "robustness.json"
        if code != 0 or not path.is_file():
            return {"figure": name, "error": f"robustness exited {code}"}
        data = json.loads(path.read_text())
    data.update(trace_seconds=t1 - t0, study_seconds=t2 - t1)
    return data


def main(argv: list[str]) -> list[dict]:
    opts = {"--trials": 32, "--steps": None}
    for flag in opts:
        if flag in argv:
            i = argv.index(flag)
            opts[flag] = int(argv[i + 1])
            argv = argv[:i] + argv[i + 2:]
    names = argv or [*school_names(), "double-flower"]
    print(f"{'figure':24s} {'size':>7s} {'open p95':>9s} {'closed p95':>10s} {'diverged':>9s} {'cusp':>8s} "
          f"{'trace s':>8s} {'study s':>8s}   (p95: largest deviation, relative to the size)")
    rows = []
    for name in names:
        d = study(name, opts["--trials"], opts["--steps"])
        rows.append(d)
        if "error" in d:
            print(f"{name:24s} {d['error']}", flush=True)
            continue
        size, cl = d["figure_size"], d["closed_loop"]
        cusp = cl["cusp_speed"]["max"]
        print(f"{name:24s} {size:7.3g} {_rel(d['open_loop']['max_deviation'], size):>9s} "
              f"{_rel(cl['max_deviation'], size):>10s} {cl['diverged']:>4d}/{cl['trials']:<4d} "
              f"{'-' if cusp is None else f'{cusp:.2g}':>8s} {d['trace_seconds']:8.1f} {d['study_seconds']:8.1f}",
              flush=True)
    return rows


if __name__ == "__main__":
    main(sys.argv[1:])
