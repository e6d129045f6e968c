"""Benchmark: every SVG of the corpus (tests/data/svg-corpus) traced end to end at 6 m / 1 mm and verified by replay.

Run: python bench/bench_corpus.py [FILE ...] [--reach none|auto|R] [--markdown] [--cli]
     (default: every file, the launch-glide-stop manoeuvres; ``--reach auto`` as the command line
     does by default for a figure in metres: planned within 0.288 x 1.7 m, and where that leaves
     sections unplanned the launch-glide-stop manoeuvres if they trace every section; ``--reach R``
     planned within R, whatever comes of it)

Per file, as ``skatetrace trace FILE --size 6m --tol 1mm`` does: read and fit (``resolve``), trace
and verify (``trace_and_verify``), the wall time of each, and the outcome: verified, not
verified (the first failing section's reason) or refused (the reader's or the fitter's reason),
and the verdict with both halves: exact (verified) and whether a 1.7 m skater could do it.
The summary gives the share verified, the share within 10 s, and the slowest files, as issue 17
asks. With ``--cli``, each file is also run as a user runs it, ``skatetrace trace FILE --size 6m
--tol 1mm`` in a fresh process (every file written: plots, viewer), and its wall time is given
beside the number of segments the drawing is read as (issue 17's target: at most 50 segments in
at most 10 s). Nothing is asserted about time.
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import skatetrace as st
from skatetrace.errors import SkatetraceError
from skatetrace.verification.feasibility import HumanLimits

CORPUS = Path(__file__).resolve().parent.parent / "tests" / "data" / "svg-corpus"


def _trace(figure, reach, fallback: bool):
    limits = HumanLimits.for_skater(1.7, 60.0)
    if fallback:  # as the command line under its default reach (trace_within_default_reach)
        options = st.TraceOptions(speed=2.0, reach=reach, reach_hint=False, all_or_nothing=True)
        kept = st.trace_within_default_reach(figure, figure.params, options, limits=limits)
        return kept.result, kept.fell_back
    options = st.TraceOptions(speed=2.0, reach=reach)
    return st.trace_and_verify(figure, figure.params, options, limits=limits), ""


def measure(name: str, reach: float | str | None) -> dict:
    """One corpus file end to end: the outcome and the time of each stage (``reach`` a length, None or "auto")."""
    from skatetrace.dynamics.presets import skater_reach

    t0 = time.perf_counter()
    try:
        res = st.resolve(CORPUS / name, size="6m", tol="1mm", height=1.7)
    except SkatetraceError as exc:
        return {"file": name, "outcome": "refused", "reason": str(exc), "fit_s": time.perf_counter() - t0,
                "trace_s": 0.0, "sections": 0, "verdict": "not traced"}
    t1 = time.perf_counter()
    segments = sum(len(path.pieces) for path in res.drawing.paths) if res.drawing is not None else 0
    done, fell_back = _trace(res.figure, skater_reach(1.7) if reach == "auto" else reach, reach == "auto")
    failed = next((s.message for s in done.trace.sections if not s.success), done.message)
    return {"file": name, "outcome": "verified" if done.success else "not verified",
            "reason": ({"too large": "launch-glide-stop (too large to plan by default)",
                        "over budget": "launch-glide-stop (the plan spent its budget)",
                        "unplanned": "launch-glide-stop (not every section planned)",
                        "unverified": "launch-glide-stop (the plan's replay failed the verification)"}.get(fell_back, ""))
            + ("" if done.success else failed), "fit_s": t1 - t0, "trace_s": time.perf_counter() - t1,
            "sections": len(done.trace.sections), "verdict": done.verdict, "segments": segments}


def command_line(name: str) -> tuple[float, int]:
    """``skatetrace trace FILE --size 6m --tol 1mm`` in a fresh process: its wall time in s and its exit code."""
    with tempfile.TemporaryDirectory() as out:
        t0 = time.perf_counter()
        done = subprocess.run([sys.executable, "-m", "skatetrace", "trace", str(CORPUS / name), "--size", "6m",
                               "--tol", "1mm", "--out", out], capture_output=True, text=True)
        return time.perf_counter() - t0, done.returncode


def summary(rows: list[dict]) -> str:
    """The share verified and within 10 s, and the five slowest files."""
    n = len(rows)
    ok = sum(r["outcome"] == "verified" for r in rows)
    fast = sum(r["fit_s"] + r["trace_s"] <= 10.0 for r in rows)
    slow = sorted(rows, key=lambda r: -(r["fit_s"] + r["trace_s"]))[:5]
    return (f"verified {ok} of {n} ({100.0 * ok / max(n, 1):.0f} %); within 10 s {fast} of {n}; slowest: "
            + ", ".join(f"{r['file']} {r['fit_s'] + r['trace_s']:.0f} s" for r in slow))


def cli_summary(rows: list[dict]) -> str:
    """The drawings of at most 50 segments run on the command line within 10 s, and the slowest."""
    small = [r for r in rows if "cli_s" in r and 0 < r.get("segments", 0) <= 50]  # (a refused file has none)
    fast = sum(r["cli_s"] <= 10.0 for r in small)
    slow = sorted(small, key=lambda r: -r["cli_s"])[:5]
    return (f"command line, drawings of at most 50 segments: within 10 s {fast} of {len(small)}; slowest: "
            + ", ".join(f"{r['file']} ({r['segments']} segments) {r['cli_s']:.1f} s" for r in slow))


def markdown(rows: list[dict]) -> str:
    cli = any("cli_s" in r for r in rows)
    head = ("| file | outcome | sections | fit s | trace and verify s | "
            + ("segments | command line s | " if cli else "") + "reason | verdict (verified · feasible) |")
    lines = [head, "|---" * (9 if cli else 7) + "|"]
    for r in rows:
        extra = f"{r.get('segments', 0)} | {r['cli_s']:.1f} | " if cli else ""
        lines.append(f"| {r['file']} | {r['outcome']} | {r['sections']} | {r['fit_s']:.1f} | {r['trace_s']:.1f} "
                     f"| {extra}{r['reason'][:90].replace('|', '/')} | {r['verdict'].replace('|', '/')} |")
    return "\n".join(lines)


def main(argv=None) -> list[dict]:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("files", nargs="*")
    ap.add_argument("--reach", default="none")
    ap.add_argument("--markdown", action="store_true")
    ap.add_argument("--cli", action="store_true", help="also time each file on the command line")
    args = ap.parse_args(argv)
    reach = None if args.reach == "none" else ("auto" if args.reach == "auto" else float(args.reach))
    names = args.files or sorted(p.name for p in CORPUS.glob("*.svg"))
    st.trace_and_verify(st.pattern("double-flower"), st.PAPER_PARAMS)  # compiled code warm
    rows = []
    for name in names:
        row = measure(name, reach)
        if args.cli:
            row["cli_s"], row["cli_exit"] = command_line(name)
        rows.append(row)
        cli = f" command line {row['cli_s']:5.1f} s ({row.get('segments', 0)} segments)" if args.cli else ""
        print(f"{name:46s} {row['outcome']:13s} {row['sections']:4d} fit {row['fit_s']:5.1f} s "
              f"trace {row['trace_s']:6.1f} s{cli} {row['reason'][:70]}", flush=True)
    print(summary(rows))
    if args.cli:
        print(cli_summary(rows))
    if args.markdown:
        print(markdown(rows))
    return rows


if __name__ == "__main__":
    main()
