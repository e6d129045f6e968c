"""Benchmark: the double flower end to end (trace, sample, verify), warm and from a cold CLI start.

Run: python bench/bench_double_flower.py [N] [--cold K] [--first K] [--figure NAME] [--quiet]

- warm: in this process, one untimed warm-up run (it loads or compiles numba's integrator), then N
  timed runs of trace_figure / schedule_from_trace / verify; the median of each stage and of the
  total, and each stage's share of the total; verify is split into its replay (integrating the full
  dynamics, ``skatetrace.verification.verify.replay``) and its checks (deviations, cusp speeds, invariants);
- cold: K runs of ``python -m skatetrace.cli trace NAME --out TMP --no-plots --no-viewer`` in a new
  process each (interpreter start, imports, resolve, trace, verify with rests as needed, writing
  result.json, controls.csv and report.json), median wall time; beside it the time the CLI reports
  for its own work and the median time of ``python -c "import skatetrace.cli"`` (start-up and imports).
  If ``python -m skatetrace.cli`` does not run, the ``skatetrace`` console script next to
  ``sys.executable`` is used. ``--cold 0`` skips this part. The package is byte-compiled first
  (``compileall``, as ``pip install`` does and as any run leaves it where Python may write
  ``__pycache__``): a cold start loads bytecode; it does not compile the sources (this sandbox sets
  ``PYTHONDONTWRITEBYTECODE=1``, which would otherwise make every start compile them, about 0.15 s).
- first run (issue 18): K runs of the README's main job, ``python -m skatetrace.cli trace NAME --out
  TMP`` (plots and viewer included), each with an empty numba cache of its own (``NUMBA_CACHE_DIR``
  set to a new folder: numba then neither reads nor writes the caches beside the sources), so each
  compiles what a first run after a fresh install compiles; median wall time, and the parts the CLI
  said it compiled; each run's job for later runs (``skatetrace.cli.compiled.compile_later``) is waited
  for before the next run, and how long after the run it ended is reported. ``--first 0`` (the
  default) skips this part.
- engines: the replay once more with ``verify.replay(..., engine="scipy")`` (solve_ivp with a Python
  right-hand side, the pre-compilation path) beside the median compiled replay, in this process:
  their ratio is the compiled replay's speed-up (``--no-engines`` skips it).
``--figure`` takes any built-in figure (``line`` or ``circle`` for a quick check). Timings are never asserted.
"""

from __future__ import annotations

import argparse
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from skatetrace import pattern, trace_figure
from skatetrace.cli.compiled import later_job_end
from skatetrace.verification.verify import replay, schedule_from_trace

if str(Path(__file__).resolve().parent) not in sys.path:
    sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import median, quiet_print, timed_verify  # noqa: E402

STAGES = ("trace", "sample", "verify", "total")
VERIFY_PARTS = ("replay", "checks")  # verify = replay (integrate the full dynamics) + checks


def run_once(name: str) -> tuple[dict, object, object]:
    """Times of one in-process run, with the trace and the verification report."""
    t0 = time.perf_counter()
    tr = trace_figure(pattern(name))
    t1 = time.perf_counter()
    sch, _ = schedule_from_trace(tr)
    t2 = time.perf_counter()
    rep, dv, dr = timed_verify(tr, sch)
    t3 = t2 + dv
    times = dict(zip(STAGES, (t1 - t0, t2 - t1, t3 - t2, t3 - t0)))
    times.update(replay=dr, checks=dv - dr)
    return times, tr, rep


def cli_command() -> list[str]:
    """``[python, -m, skatetrace.cli]`` if that runs, else the console script next to the interpreter."""
    cmd = [sys.executable, "-m", "skatetrace.cli"]
    probe = subprocess.run(cmd + ["--help"], capture_output=True, text=True)
    if probe.returncode == 0 and "trace" in probe.stdout:
        return cmd
    script = Path(sys.executable).parent / "skatetrace"
    if script.exists():
        return [str(script)]
    raise RuntimeError(f"neither {' '.join(cmd)} nor {script} runs: {probe.stderr.strip()[-300:]}")


def cold_runs(name: str, k: int) -> dict:
    import compileall

    import skatetrace

    compiled = compileall.compile_dir(str(Path(skatetrace.__file__).parent), quiet=1)
    cmd = cli_command()
    walls, reported, imports, codes, tails = [], [], [], [], []
    for _ in range(k):
        with tempfile.TemporaryDirectory(prefix="skatetrace-bench-") as tmp:
            t0 = time.perf_counter()
            proc = subprocess.run(cmd + ["trace", name, "--out", tmp, "--no-plots", "--no-viewer"],
                                  capture_output=True, text=True)
            walls.append(time.perf_counter() - t0)
            files = sorted(p.name for p in Path(tmp).iterdir())
        codes.append(proc.returncode)
        m = re.search(r"wrote .* in ([0-9.]+) s", proc.stdout)
        reported.append(float(m.group(1)) if m else None)
        tails.append((proc.stdout + proc.stderr).strip().splitlines()[-1:] or [""])
        t0 = time.perf_counter()
        subprocess.run([sys.executable, "-c", "import skatetrace.cli"], check=True)
        imports.append(time.perf_counter() - t0)
    return {"command": cmd + ["trace", name, "--out", "TMP", "--no-plots", "--no-viewer"], "runs": k,
            "wall": walls, "wall_median": median(walls), "reported": reported, "reported_median": median(reported),
            "import": imports, "import_median": median(imports), "returncodes": codes,
            "success": all(c == 0 for c in codes), "files": files, "last_line": tails[-1][0],
            "byte_compiled": bool(compiled)}


def _seconds(values) -> str:
    return ", ".join("none" if v is None else f"{v:.1f} s" for v in values)


def first_runs(name: str, k: int) -> dict:
    """The README's main job with an empty numba cache, ``k`` times (a first run after a fresh install).

    Each run's job for later runs (the parts it does not need, compiled in the background) is waited
    for before the next run, as a user's next command would find it: ``later`` is how long after the
    run it ended (None where no job was started).
    """
    import os

    cmd = cli_command()
    walls, codes, compiled, later = [], [], [], []
    for _ in range(k):
        with tempfile.TemporaryDirectory(prefix="skatetrace-first-") as tmp:
            env = {**os.environ, "NUMBA_CACHE_DIR": str(Path(tmp) / "numba")}
            t0 = time.perf_counter()
            proc = subprocess.run(cmd + ["trace", name, "--out", str(Path(tmp) / "out")], capture_output=True,
                                  text=True, env=env)
            walls.append(time.perf_counter() - t0)
            later.append(later_job_end(Path(tmp) / "numba", timeout=300.0))
        codes.append(proc.returncode)
        compiled.append(re.findall(r"compiled (.+?) in ([0-9]+) s", proc.stderr))
    return {"command": cmd + ["trace", name, "--out", "TMP"], "runs": k, "wall": walls, "wall_median": median(walls),
            "returncodes": codes, "success": all(c == 0 for c in codes), "compiled": compiled[-1],
            "ahead": k > 0 and "alongside" in proc.stderr, "later": later}


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("n", nargs="?", type=int, default=3, help="warm runs (median reported; default 3)")
    ap.add_argument("--cold", type=int, default=3, help="cold CLI runs (default 3; 0 skips them)")
    ap.add_argument("--first", type=int, default=0, help="first runs with an empty numba cache (default 0: none)")
    ap.add_argument("--figure", default="double-flower", help="built-in figure (default double-flower)")
    ap.add_argument("--quiet", action="store_true", help="print nothing; just return the results")
    ap.add_argument("--no-engines", action="store_true", help="do not time the solve_ivp replay for comparison")
    args = ap.parse_args(argv)
    print = quiet_print(args.quiet)

    warm_up, tr, rep = run_once(args.figure)
    runs = []
    for _ in range(args.n):
        times, tr, rep = run_once(args.figure)
        if not (tr.success and rep.success):
            raise RuntimeError(f"{args.figure}: {tr.message}; {rep.message}")
        runs.append(times)
    med = {k: median([r[k] for r in runs]) for k in STAGES + VERIFY_PARTS}
    share = {k: med[k] / med["total"] for k in STAGES[:3] + VERIFY_PARTS}
    out = {"figure": args.figure, "runs": args.n, "warmup_s": warm_up["total"], "warmup": warm_up,
           "stages": {k: [r[k] for r in runs] for k in STAGES + VERIFY_PARTS}, "median": med, "share": share,
           "sections": len(tr.sections), "distinct_sections": len({id(s.phases) for s in tr.sections}),
           "trace_success": tr.success, "verify_success": rep.success, "max_deviation": rep.max_deviation,
           "tolerance": rep.tolerance, "max_cusp_speed": rep.max_cusp_speed}
    print(f"{args.figure}: {out['sections']} sections ({out['distinct_sections']} solved, the rest reused), "
          f"warm-up run {warm_up['total']:.2f} s, median of {args.n} warm runs:")
    for k in STAGES[:3] + VERIFY_PARTS + STAGES[3:]:
        label = f"  {k}" if k in VERIFY_PARTS else k  # replay and checks are parts of verify
        print(f"  {label:9s} {med[k]:8.3f} s" + (f"   {share[k]:6.1%} of the total" if k in share else ""))
    print(f"  max deviation {rep.max_deviation:.2e} (tolerance {rep.tolerance:.2e}), "
          f"max cusp speed {rep.max_cusp_speed:.2e}")
    if not args.no_engines:
        sch, _ = schedule_from_trace(tr)
        t0 = time.perf_counter()
        replay(tr, sch, engine="scipy")
        slow = time.perf_counter() - t0
        out["engines"] = {"scipy_s": slow, "compiled_s": med["replay"], "ratio": slow / med["replay"]}
        print(f"replay through solve_ivp (engine='scipy'): {slow:.2f} s, {slow / med['replay']:.0f} times the "
              f"compiled replay's {med['replay']:.3f} s")
    if args.cold > 0:
        cold = cold_runs(args.figure, args.cold)
        out["cold"] = cold
        print(f"cold CLI start ({' '.join(cold['command'][1:])}), median of {args.cold}: "
              f"{cold['wall_median']:.2f} s wall; the CLI reports {cold['reported_median']:.2f} s of work; "
              f"'import skatetrace.cli' alone {cold['import_median']:.2f} s; exit codes {cold['returncodes']}")
    if args.first > 0:
        first = first_runs(args.figure, args.first)
        out["first"] = first
        parts = ", ".join(f"{part} {sec} s" for part, sec in first["compiled"]) or "nothing"
        print(f"first run with an empty numba cache ({' '.join(first['command'][1:])}), median of {args.first}: "
              f"{first['wall_median']:.2f} s wall; compiled in the run: {parts}"
              f"{'; the verification compiled alongside' if first['ahead'] else ''}; exit codes {first['returncodes']}; "
              f"the job for later runs ended {_seconds(first['later'])} after each run")
    return out


if __name__ == "__main__":
    main(sys.argv[1:])
