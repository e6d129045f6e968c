"""Benchmark: robustness of the school figures (1.7 m skater, planned within 0.5 m) and the double flower.

Run: python bench/bench_robustness.py [NAME ...] [--trials N] [--steps K] [--markdown PATH]   (default: the
seventeen school figures and the double flower, 32 trials, the command's steps; ``--markdown`` also writes the
table, dated, for ``bench/run_all.py`` to include in ``RESULTS.md``: ``bench/ROBUSTNESS.md``)
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
import os
import sys
import tempfile
import time
from datetime import datetime, timezone
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


def markdown(rows: list[dict], trials: int, seconds: float) -> str:
    """The table of ``rows`` as the section ``bench/run_all.py`` includes in ``RESULTS.md``."""
    load = " / ".join(f"{v:.2f}" for v in os.getloadavg())
    lines = [f"Written by `python bench/bench_robustness.py` on {datetime.now(timezone.utc):%Y-%m-%d %H:%M} UTC "
             f"in {seconds / 60:.0f} min ({os.cpu_count()} CPUs, load average at the end {load}). Each figure "
             "traced by the command line (school figures for a 1.7 m skater with `--reach 0.5m`, the double "
             f"flower as the README traces it), then `skatetrace robustness` at its defaults with {trials} "
             "trials: M, m, I each within ±5 %, each curve 1 mm and 0.5° off (model units: 1e-4 of the size), "
             "a 10 ms delay (model units: 0.01). p95: the 95th percentile over the trials of each trial's "
             "largest deviation from the figure, relative to the figure's size; the target of issue 16 is "
             "1e-3 for the closed loop.", "",
             "| figure | size | open loop p95 | closed loop p95 | diverged (closed) | cusp speed (closed, max) | "
             "trace s | study s |", "|---|---|---|---|---|---|---|---|"]
    for d in rows:
        if "error" in d:
            lines.append(f"| {d['figure']} | {d['error']} | | | | | | |")
            continue
        size, cl = d["figure_size"], d["closed_loop"]
        cusp = cl["cusp_speed"]["max"]
        lines.append(f"| {d['figure']} | {size:.3g} {'m' if d.get('unit') == 'm' else 'units'} | "
                     f"{_rel(d['open_loop']['max_deviation'], size)} | {_rel(cl['max_deviation'], size)} | "
                     f"{cl['diverged']}/{cl['trials']} | {'-' if cusp is None else f'{cusp:.2g}'} | "
                     f"{d['trace_seconds']:.1f} | {d['study_seconds']:.1f} |")
    return "\n".join(lines) + "\n"


def main(argv: list[str]) -> list[dict]:
    t0 = time.perf_counter()
    opts = {"--trials": 32, "--steps": None, "--markdown": None}
    for flag in opts:
        if flag in argv:
            i = argv.index(flag)
            opts[flag] = argv[i + 1] if flag == "--markdown" else int(argv[i + 1])
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
    if opts["--markdown"]:
        Path(opts["--markdown"]).write_text(markdown(rows, opts["--trials"], time.perf_counter() - t0),
                                            encoding="utf-8")
    return rows


if __name__ == "__main__":
    main(sys.argv[1:])
