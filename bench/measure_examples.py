"""Measure the documented examples as a user runs them, and write the user guide's table from the numbers.

The guide's figures for the examples (time, deviation, both verdicts) come from this script, never by
hand: it runs each command below from a cold start in a subprocess, reads the files it wrote, stores
the measurements in ``bench/examples.json`` (with the machine, versions and date), and rewrites the
block of docs/guide/examples.md between ``<!-- examples:begin -->`` and ``<!-- examples:end -->``. A
test holds that block to ``render(bench/examples.json)``.

Usage::

    python bench/measure_examples.py            # all examples (a few minutes on 2 cores)
    python bench/measure_examples.py --only double-flower,school-three
    python bench/measure_examples.py --render   # no measuring: rewrite the table from bench/examples.json

Deviations are shown as bounds rounded up to one significant digit: their last digits are round-off
and differ between machines (Intel and AMD); times to two significant digits, from one cold run.
"""

from __future__ import annotations

import argparse
import datetime as _dt
import json
import math
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT / "bench" / "examples.json"
#: The page whose table this script writes, between the markers below.
PAGE = ROOT / "docs" / "guide" / "examples.md"
BEGIN, END = "<!-- examples:begin -->", "<!-- examples:end -->"

#: name -> (arguments of ``skatetrace trace`` after the figure, what it is)
EXAMPLES = {
    "double-flower": (["double-flower"], "the paper's double flower (model units)"),
    "flower-with-stems": (["examples/flower-with-stems.json"], "a figure file (model units)"),
    "school-three": (["school:three", "--height", "1.7"], "school figure three, 1.7 m skater"),
    "school-circle-eight": (["school:circle-eight", "--height", "1.7"], "school figure circle eight"),
    "figure-eight-svg": (["examples/figure-eight.svg", "--size", "6m", "--tol", "1mm"], "SVG, 6 m, 1 mm"),
    "three-turn-svg": (["examples/three-turn.svg", "--size", "6m", "--tol", "1mm"], "SVG, 6 m, 1 mm"),
    "serpentine-svg": (["examples/serpentine.svg", "--size", "6m", "--tol", "1mm"], "SVG, 6 m, 1 mm (41 arcs)"),
    "points-eight-csv": (["examples/points-eight.csv", "--size", "6m", "--tol", "1mm"], "point list, 6 m, 1 mm"),
    "figure-eight-exact": (["examples/figure-eight.svg", "--size", "6m", "--exact"], "SVG, exact mode"),
    "serpentine-exact": (["examples/serpentine.svg", "--size", "6m", "--exact"], "SVG, exact mode"),
    "three-turn-exact": (["examples/three-turn.svg", "--size", "6m", "--exact"], "SVG, exact mode"),
    "points-eight-exact": (["examples/points-eight.csv", "--size", "6m", "--exact"], "point list, exact mode"),
}


def _bound(x: float | None) -> str:
    """``x`` rounded up to one significant digit, as a bound: 3.39e-9 -> '4e-9'."""
    if x is None or not math.isfinite(x):
        return "–"
    if x == 0:
        return "0"
    e = math.floor(math.log10(abs(x)))
    d = math.ceil(abs(x) / 10 ** e - 1e-9)
    if d == 10:
        d, e = 1, e + 1
    return f"{d}e{e}" if abs(e) > 2 else f"{d * 10.0 ** e:g}"


def _two(x: float) -> str:
    return f"{float(f'{x:.2g}'):g}"


def measure(name: str) -> dict:
    args, what = EXAMPLES[name]
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "out"
        t0 = time.perf_counter()
        proc = subprocess.run([sys.executable, "-m", "skatetrace", "trace", *args, "--out", str(out)], cwd=ROOT,
                              capture_output=True, text=True)
        seconds = time.perf_counter() - t0
        row = {"name": name, "command": "skatetrace trace " + " ".join(args), "what": what,
               "exit": proc.returncode, "seconds": seconds}
        report_path = out / "report.json"
        if report_path.is_file():
            rep = json.loads(report_path.read_text())
            feas = rep.get("feasibility") or {}
            reach = next((c for c in feas.get("checks", []) if c["name"] == "reach"), None)
            row.update(status=rep.get("status"), max_deviation=rep.get("max_deviation"),
                       tolerance=rep.get("tolerance"), verdict=rep.get("verdict"),
                       feasible=feas.get("feasible"), reach=None if reach is None else reach["value"],
                       reach_limit=None if reach is None else reach["limit"], unit=feas.get("limits", {}).get("unit"))
        fit_path = out / "fit.json"
        if fit_path.is_file():
            fit = json.loads(fit_path.read_text())
            row["fit_bound"] = fit.get("hausdorff_certified")
            if fit.get("exact"):
                row["exact_bound"] = fit["exact"].get("deviation")
        result_path = out / "result.json"
        if result_path.is_file():
            row["sections"] = len(json.loads(result_path.read_text())["sections"])
    return row


def render(data: dict) -> str:
    """The page's table block (without the markers) for the measurements ``data``."""
    lines = [f"Measured by `python bench/measure_examples.py` on {data['date']} ({data['machine']}; one cold run "
             "each, plots and viewer included; deviations rounded up to one digit, as bounds):", "",
             "| command | exit | time | sections | replay deviation (tolerance) | drawing fit | mass reach (limit) "
             "| verdict |", "|---|---|---|---|---|---|---|---|"]
    for r in data["rows"]:
        unit = " m" if r.get("unit") == "m" else ""
        fit = ""
        if r.get("exact_bound") is not None:
            fit = f"splines ≤ {_bound(r['exact_bound'])}{unit}"
        elif r.get("fit_bound") is not None:
            fit = f"arcs ≤ {_bound(r['fit_bound'])}{unit}"
        dev = (f"≤ {_bound(r['max_deviation'])}{unit} ({_two(r['tolerance'])})" if r.get("max_deviation") is not None
               else "–")
        reach = (f"{_two(r['reach'])}{unit} ({_two(r['reach_limit'])})" if r.get("reach") is not None else "–")
        verdict = {True: "verified · feasible", False: "verified · not feasible"}.get(r.get("feasible"), "–") \
            if r.get("status") == "passed" else (r.get("status") or "failed")
        lines.append(f"| `{r['command']}` | {r['exit']} | {_two(r['seconds'])} s | {r.get('sections', '–')} | {dev} "
                     f"| {fit or '–'} | {reach} | {verdict} |")
    return "\n".join(lines)


def write_table(data: dict, page: Path = PAGE) -> None:
    """Rewrite the block between ``BEGIN`` and ``END`` of ``page`` with ``render(data)``."""
    text = page.read_text(encoding="utf-8")
    if BEGIN not in text or END not in text:
        raise SystemExit(f"{page}: the markers {BEGIN} and {END} are missing; put them where the table goes")
    i, j = text.index(BEGIN) + len(BEGIN), text.index(END)
    page.write_text(text[:i] + "\n" + render(data) + "\n" + text[j:], encoding="utf-8")


def render_only(data_path: Path = DATA, page: Path = PAGE) -> None:
    """Rewrite the page's table from the stored measurements, measuring nothing."""
    write_table(json.loads(data_path.read_text(encoding="utf-8")), page)


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--only", help="comma-separated subset of: " + ", ".join(EXAMPLES))
    p.add_argument("--render", action="store_true",
                   help="measure nothing: only rewrite docs/guide/examples.md's table from bench/examples.json")
    args = p.parse_args(argv)
    if args.render:
        render_only()
        return 0
    names = list(EXAMPLES) if not args.only else [n.strip() for n in args.only.split(",")]
    unknown = [n for n in names if n not in EXAMPLES]
    if unknown:
        p.error(f"unknown example(s) {', '.join(unknown)}; choose from {', '.join(EXAMPLES)}")
    old = json.loads(DATA.read_text()) if DATA.is_file() else {"rows": []}
    rows = {r["name"]: r for r in old["rows"]}
    for name in names:
        print(f"{name} ...", file=sys.stderr, flush=True)
        rows[name] = measure(name)
        print(f"  exit {rows[name]['exit']}, {rows[name]['seconds']:.1f} s", file=sys.stderr, flush=True)
    cpu = platform.processor() or platform.machine()
    try:
        cpu = next(line.split(":", 1)[1].strip() for line in Path("/proc/cpuinfo").read_text().splitlines()
                   if line.startswith("model name"))
    except (OSError, StopIteration):
        pass
    data = {"date": _dt.date.today().isoformat(), "machine": f"{os.cpu_count()} cores, {cpu}",
            "python": platform.python_version(), "rows": [rows[n] for n in EXAMPLES if n in rows]}
    DATA.write_text(json.dumps(data, indent=1) + "\n", encoding="utf-8")
    write_table(data)
    return 0


if __name__ == "__main__":
    sys.exit(main())
