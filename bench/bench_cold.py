"""Benchmark: school figures and example drawings from a cold CLI start, as multiples of the double flower (issue 18).

Run: python bench/bench_cold.py [NAME ...] [--timeout S] [--flower-runs K] [--heights H ...] [--corpus] [--exact]

Each command runs as a user runs it, in a fresh interpreter: ``skatetrace trace FIGURE ...
--no-plots --no-viewer`` into an empty folder, with the default planner (``--reach auto`` for a
figure in metres). The double flower runs first (``--flower-runs`` times, the median kept), then
every NAME in the same sitting: ``school:NAME`` for each school figure of a 1.7 m skater and the
example drawings of ``bench/measure_examples.py`` (exact mode included). Per command: the wall
time, its ratio to the double flower's, the exit code, the verdict line, and the command's peak
resident memory (``VmHWM`` of its main process, read every 20 ms; the planner's and the tracer's
worker processes are not counted). A command still running after ``--timeout`` seconds is
stopped and reported as such (its ratio is at least the timeout's). Nothing is asserted about time.

``--heights H ...``, ``--corpus`` and ``--exact`` add figures that no default was tuned on: every
school figure for skaters of those heights, every drawing of ``tests/data/svg-corpus`` at 6 m
within 1 mm, and every such drawing in exact mode (``--exact``: its curvature splines within 1e-7
of its size); the last line counts the commands within issue 18's 5x.
"""

from __future__ import annotations

import argparse
import os
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
if str(HERE) not in sys.path:
    sys.path.insert(0, str(HERE))
from _common import median  # noqa: E402
from bench_double_flower import cli_command  # noqa: E402
from measure_examples import EXAMPLES, ROOT  # noqa: E402

from skatetrace import school_names  # noqa: E402

FLOWER = ["double-flower"]
#: Issue 18's target: every command within this many times the double flower's cold time.
TARGET_RATIO = 5.0
#: Drawings no default was tuned for (``--corpus``), traced as the command line's examples are.
CORPUS = ROOT / "tests" / "data" / "svg-corpus"


def commands(heights=(), corpus: bool = False, exact: bool = False) -> dict[str, list[str]]:
    """Every measured command's arguments after ``skatetrace trace``, by name (the double flower excluded).

    By default the school figures of a 1.7 m skater and the example drawings, issue 18's targets.
    ``heights`` adds every school figure for a skater of each of those heights
    (``school:NAME@H``), and ``corpus`` every drawing of ``tests/data/svg-corpus`` scaled to 6 m
    within 1 mm (``corpus:FILE``): figures that no default of the planner or the tracer was tuned
    on, as a user's would be; ``exact`` each of those drawings in exact mode (``corpus-exact:FILE``).
    """
    out = {f"school:{name}": [f"school:{name}", "--height", "1.7"] for name in school_names()}
    for name, (args, _what) in EXAMPLES.items():
        if args != FLOWER and not args[0].startswith("school:"):
            out[name] = list(args)
    for height in heights:
        for name in school_names():
            out[f"school:{name}@{height:g}"] = [f"school:{name}", "--height", f"{height:g}"]
    drawings = {path.name: [str(path.relative_to(ROOT)), "--size", "6m", "--tol", "1mm"]
                for path in sorted(CORPUS.glob("*.svg"))}
    if corpus:
        out.update({f"corpus:{name}": args for name, args in drawings.items()})
    if exact:
        out.update({f"corpus-exact:{name}": args + ["--exact"] for name, args in drawings.items()})
    return out


def run_cold(args: list[str], timeout: float) -> dict:
    """One cold CLI run of ``skatetrace trace ARGS``: wall time, exit code, last lines, peak memory (MB)."""
    with tempfile.TemporaryDirectory(prefix="skatetrace-cold-") as tmp:
        log = Path(tmp) / "log"
        cmd = cli_command() + ["trace", *args, "--out", str(Path(tmp) / "out"), "--no-plots", "--no-viewer"]
        with open(log, "wb") as sink:
            t0 = time.perf_counter()
            # the examples' paths are relative to the repository; its own session, to stop it whole
            proc = subprocess.Popen(cmd, cwd=ROOT, stdout=sink, stderr=subprocess.STDOUT, start_new_session=True)
            pid, timed_out, peak_kb = proc.pid, False, 0
            while True:
                peak_kb = max(peak_kb, _high_water_kb(pid))
                done, status, _usage = os.wait4(pid, os.WNOHANG)
                if done:
                    break
                if time.perf_counter() - t0 > timeout:
                    timed_out = True
                    os.killpg(pid, signal.SIGKILL)
                    _done, status, _usage = os.wait4(pid, 0)
                    break
                time.sleep(0.02)
            wall = time.perf_counter() - t0
            proc.returncode = os.waitstatus_to_exitcode(status)  # reaped here, for its memory
        text = log.read_text(errors="replace").strip().splitlines()
    verdict = next((line for line in reversed(text) if line.startswith("verdict:")), text[-1] if text else "")
    return {"args": args, "wall": wall, "timed_out": timed_out,
            "returncode": None if timed_out else os.waitstatus_to_exitcode(status),
            "peak_mb": peak_kb / 1024.0, "verdict": verdict.removeprefix("verdict: ")}


def _high_water_kb(pid: int) -> int:
    """The process's peak resident memory so far (``VmHWM`` in ``/proc/PID/status``, kB; 0 if unreadable).

    Not ``ru_maxrss`` from ``wait4``: Linux carries that over from the parent through ``fork`` and
    ``exec``, so every command measured from a large benchmark process read as that process's size.
    """
    try:
        with open(f"/proc/{pid}/status") as f:
            for line in f:
                if line.startswith("VmHWM:"):
                    return int(line.split()[1])
    except (OSError, ValueError, IndexError):
        pass
    return 0


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("names", nargs="*", help="school:NAME or an example of bench/measure_examples.py (default: all)")
    ap.add_argument("--timeout", type=float, default=300.0, help="seconds before a command is stopped (default 300)")
    ap.add_argument("--flower-runs", type=int, default=3, help="cold runs of the double flower (default 3)")
    ap.add_argument("--heights", type=float, nargs="+", default=(), metavar="H",
                    help="also every school figure for a skater this tall (m): school:NAME@H")
    ap.add_argument("--corpus", action="store_true",
                    help="also every drawing of tests/data/svg-corpus at --size 6m --tol 1mm: corpus:FILE")
    ap.add_argument("--exact", action="store_true",
                    help="also every drawing of tests/data/svg-corpus in exact mode (as --corpus, with --exact): "
                         "corpus-exact:FILE")
    args = ap.parse_args(argv)
    every = commands(args.heights, args.corpus, args.exact)
    unknown = [n for n in args.names if n not in every]
    if unknown:
        ap.error(f"unknown name(s) {', '.join(unknown)}; choose from {', '.join(every)}")
    flower = [run_cold(FLOWER, args.timeout) for _ in range(max(args.flower_runs, 1))]
    base = median([r["wall"] for r in flower])
    print(f"{'double-flower':28s} {base:7.2f} s  1.0x  peak {max(r['peak_mb'] for r in flower):6.0f} MB  "
          f"(median of {len(flower)}) {flower[-1]['verdict'][:70]}", flush=True)
    rows = []
    for name in args.names or list(every):
        r = run_cold(every[name], args.timeout)
        r.update(name=name, ratio=r["wall"] / base)
        rows.append(r)
        state = "TIMED OUT" if r["timed_out"] else f"exit {r['returncode']}"
        print(f"{name:28s} {r['wall']:7.2f} s {r['ratio']:5.2f}x  peak {r['peak_mb']:6.0f} MB  {state}  "
              f"{r['verdict'][:70]}", flush=True)
    ran = [r for r in rows if r["returncode"] == 0 or r["timed_out"]]
    within = [r for r in ran if not r["timed_out"] and r["ratio"] <= TARGET_RATIO]
    print(f"within {TARGET_RATIO:g}x the double flower: {len(within)} of {len(ran)} commands that ran to the end or "
          f"timed out ({len(rows) - len(ran)} refused their input)")
    return {"flower": {"wall": [r["wall"] for r in flower], "wall_median": base,
                       "peak_mb": max(r["peak_mb"] for r in flower), "returncodes": [r["returncode"] for r in flower]},
            "rows": rows, "timeout": args.timeout}


if __name__ == "__main__":
    main()
