"""Run every benchmark scenario, print a summary table and write bench/RESULTS.md.

Run: python bench/run_all.py [--quick | --smoke] [--out PATH] [--readme PATH | --readme-only]

Scenarios (each a script in bench/, run in this one process, in this order):
1. ``bench_paper_arcs``: the paper's three arcs, exact engine vs the paper-style baseline;
2. ``bench_double_flower``: the double flower end to end, warm (trace / sample / verify) and from a
   cold CLI start;
3. ``bench_long_figure``: 200 distinct arcs, trace / sample / verify, failed sections listed;
4. ``bench_scaling``: time versus number of pieces (1 to 1000 distinct arcs) and versus the fit
   tolerance (examples/serpentine.svg);
5. ``bench_planning``: the school figures for a 1.7 m skater planned within 0.5 m (issue 15),
   against their launch-glide-stop manoeuvres;
6. ``bench_cold``: every school figure and example drawing (exact mode included) from a cold CLI
   start with the default planner, as multiples of the double flower's cold time in the same run,
   and each run's peak memory (issue 18).

``--quick``: fewer repetitions, sizes <= 100, one traced tolerance (a few minutes). ``--smoke``: tiny
cases (a straight line instead of the double flower, 3 arcs instead of 200, ...) for CI: the numbers
mean nothing. RESULTS.md records the date, machine (with load averages: the machine may be shared),
Python and package versions, every scenario's figures, the issue's targets met or not, and a
section "Profile and what would close the gap" to be completed by hand. Timings are never asserted.

A full run also rewrites the README's block of speed figures (between :data:`README_BEGIN` and
:data:`README_END`) from the targets it just wrote (:func:`readme_block`), so the README quotes the
script; ``--readme-only`` rewrites that block from the RESULTS.md already there, running nothing.
"""

from __future__ import annotations

import argparse
import datetime as _dt
import importlib.metadata
import math
import os
import platform
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
if str(HERE) not in sys.path:
    sys.path.insert(0, str(HERE))
import bench_cold  # noqa: E402
import bench_double_flower  # noqa: E402
import bench_long_figure  # noqa: E402
import bench_paper_arcs  # noqa: E402
import bench_planning  # noqa: E402
import bench_scaling  # noqa: E402

# Arguments of each scenario's main() per mode.
MODES = {
    "full": {
        "paper_arcs": ["3"],
        "double_flower": ["5", "--cold", "3", "--first", "3"],
        "long_figure": ["--pieces", "200"],
        "scaling": ["--sizes", "1", "10", "100", "1000", "--budget", "600"],
        "planning": ["--reach", "0.5"],
        "cold": ["--timeout", "300"],
    },
    "quick": {
        "paper_arcs": ["1"],
        "double_flower": ["1", "--cold", "1", "--first", "1"],
        "long_figure": ["--pieces", "200"],
        "scaling": ["--quick", "--runs", "1", "--tols", "1e-2", "1e-3", "1e-4", "--trace-tols", "1e-2", "--fit-runs", "1"],
        "planning": ["three", "paragraph-double-three", "--reach", "0.5"],
        "cold": ["school:three", "school:one-foot-eight", "figure-eight-svg", "three-turn-exact", "--flower-runs", "1",
                 "--timeout", "120"],
    },
    "smoke": {
        "paper_arcs": ["1", "--maxiter", "1"],
        "double_flower": ["1", "--cold", "1", "--first", "1", "--figure", "line"],
        "long_figure": ["--pieces", "3"],
        "scaling": ["--sizes", "1", "2", "--runs", "1", "--tols", "1e-2", "--trace-tols", "--fit-runs", "1"],
        "planning": ["paper-arc"],
        "cold": ["flower-with-stems", "--flower-runs", "1", "--timeout", "120"],
    },
}
SCRIPTS = {"paper_arcs": bench_paper_arcs, "double_flower": bench_double_flower, "long_figure": bench_long_figure,
           "scaling": bench_scaling, "planning": bench_planning, "cold": bench_cold}

# The targets.
FLOWER_WARM_S = 0.5
FLOWER_COLD_S = 2.0
FLOWER_FIRST_S = 10.0  # issue 18: the first run after a fresh install (an empty numba cache)
PAPER_SPEEDUP = 100.0
PAPER_RESIDUAL = 1e-10
LONG_S = 5.0
LINEAR_SLOPE = 1.1  # "linear": log-log slope over sizes >= 10 at most this
PLAN_S = 10.0  # issue 15: each school figure planned (and traced and verified) within this, warm
ARC_S = 0.5e-3  # issue 18: a single arc traced warm
THOUSAND_S = 1.0  # issue 18: 1000 distinct arcs traced warm
COLD_RATIO = bench_cold.TARGET_RATIO  # issue 18: every school figure and example drawing, cold, against the flower
FLOWER_MB = 300.0  # issue 18: the double flower's peak memory


def _later(first: dict) -> str:
    """How long after each first run its job for later runs ended (``bench_double_flower.first_runs``)."""
    ends = [v for v in first.get("later") or [] if v is not None]
    if not ends:
        return ""
    return "; the parts for later runs compiled in the background by " + ", ".join(f"{v:.0f}" for v in ends) + " s after"


# ----------------------------------------------------------------------------------------------
# Machine and versions
# ----------------------------------------------------------------------------------------------

def _read(path: str) -> str:
    try:
        return Path(path).read_text()
    except OSError:
        return ""


def machine() -> dict:
    cpuinfo = _read("/proc/cpuinfo")
    models = [line.split(":", 1)[1].strip() for line in cpuinfo.splitlines()
              if line.lower().startswith(("model name", "hardware", "cpu model"))]
    mem = next((line.split()[1] for line in _read("/proc/meminfo").splitlines() if line.startswith("MemTotal:")), None)
    try:
        affinity = len(os.sched_getaffinity(0))
    except (AttributeError, OSError):
        affinity = None
    quota = _read("/sys/fs/cgroup/cpu.max").strip()
    return {
        "platform": platform.platform(), "machine": platform.machine(), "node": platform.node(),
        "cpu_count": os.cpu_count(), "cpus_usable": affinity,
        "cpu_model": models[0] if models else (platform.processor() or "unknown"),
        "memory_gib": int(mem) / 2**20 if mem else None, "cgroup_cpu_max": quota or None,
        "python": f"{platform.python_implementation()} {platform.python_version()}",
    }


def versions() -> dict:
    out = {}
    for name in ("skatetrace", "numpy", "scipy", "numba", "llvmlite", "matplotlib", "svgelements", "defusedxml", "casadi"):
        try:
            out[name] = importlib.metadata.version(name)
        except importlib.metadata.PackageNotFoundError:
            out[name] = "not installed"
    return out


def loadavg() -> tuple[float, float, float] | None:
    try:
        return os.getloadavg()
    except OSError:
        return None


def _load(la) -> str:
    return "n/a" if la is None else " / ".join(f"{v:.2f}" for v in la)


# ----------------------------------------------------------------------------------------------
# Targets
# ----------------------------------------------------------------------------------------------


def _f(x, fmt=".3g") -> str:
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return "n/a"
    return format(x, fmt)


def targets(res: dict) -> list[dict]:
    """One row per target: what, target, measured, ratio (as stated), met (True/False/None)."""
    rows = []
    fl = res.get("double_flower")
    if fl:
        warm = fl["median"]["total"]
        rows.append({"key": "flower_warm", "target": f"{fl['figure']} end to end, warm <= {FLOWER_WARM_S} s",
                     "measured": f"{warm:.3f} s (median of {fl['runs']}; trace {fl['median']['trace']:.3f}, "
                                 f"sample {fl['median']['sample']:.3f}, verify {fl['median']['verify']:.3f})",
                     "ratio": f"{warm / FLOWER_WARM_S:.2g}x the target", "met": warm <= FLOWER_WARM_S})
        cold = fl.get("cold")
        if cold:
            ok = cold["wall_median"] <= FLOWER_COLD_S and cold["success"]
            rows.append({"key": "flower_cold",
                         "target": f"{fl['figure']} end to end, cold CLI start <= {FLOWER_COLD_S} s",
                         "measured": f"{cold['wall_median']:.2f} s (median of {cold['runs']}; exit codes "
                                     f"{cold['returncodes']})",
                         "ratio": f"{cold['wall_median'] / FLOWER_COLD_S:.2g}x the target", "met": ok})
        first = fl.get("first")
        if first:
            ok = first["wall_median"] <= FLOWER_FIRST_S and first["success"]
            parts = ", ".join(f"{part} {sec} s" for part, sec in first["compiled"]) or "nothing"
            rows.append({"key": "flower_first",
                         "target": f"{fl['figure']}, the README's main job as a first run after a fresh install "
                                   f"(empty numba cache) <= {FLOWER_FIRST_S:g} s",
                         "measured": f"{first['wall_median']:.1f} s (median of {first['runs']}, plots and viewer "
                                     f"included; compiled in the run: {parts}"
                                     f"{'; the verification alongside' if first['ahead'] else ''}"
                                     f"{_later(first)})",
                         "ratio": f"{first['wall_median'] / FLOWER_FIRST_S:.2g}x the target", "met": ok})
    for r in res.get("paper_arcs", []):
        ok = r["ratio"] >= PAPER_SPEEDUP and r["exact_residual"] <= PAPER_RESIDUAL and r["exact_success"]
        rows.append({"key": f"paper_arc_{r['arc']}",
                     "target": f"paper arc {r['arc']}: >= {PAPER_SPEEDUP:g}x faster than the baseline, "
                               f"residual <= {PAPER_RESIDUAL:g}",
                     "measured": f"{r['ratio']:.1f}x ({r['baseline_s']:.3f} s vs {r['exact_s']:.4f} s); residual "
                                 f"{r['exact_residual']:.1e}, end speed {r['exact_end_speed']:.1e} "
                                 f"(baseline |dL| {r['baseline_residual']:.2g}, end speed "
                                 f"{r['baseline_end_speed']:.2g})",
                     "ratio": f"{r['ratio'] / PAPER_SPEEDUP:.2g} of the target speed-up", "met": ok})
    lf = res.get("long_figure")
    if lf:
        n = lf["pieces"]
        note = "" if not lf["failed"] else f"; {len(lf['failed'])} sections FAILED"
        rows.append({"key": "long_trace", "target": f"{n} distinct arcs <= {LONG_S:g} s (trace only)",
                     "measured": f"{lf['trace_s']:.2f} s ({lf['traced']}/{lf['sections']} sections traced{note})",
                     "ratio": f"{lf['trace_s'] / LONG_S:.2g}x the target",
                     "met": lf["trace_s"] <= LONG_S and not lf["failed"]})
        if lf.get("verified"):
            rows.append({"key": "long_total",
                         "target": f"{n} distinct arcs <= {LONG_S:g} s (trace + sample + verify)",
                         "measured": f"{lf['total_s']:.2f} s (trace {lf['trace_s']:.2f}, sample {lf['sample_s']:.2f}, "
                                     f"verify {lf['verify_s']:.2f}; verification "
                                     f"{'passed' if lf['verify_success'] else 'FAILED'})",
                         "ratio": f"{lf['total_s'] / LONG_S:.2g}x the target",
                         "met": lf["total_s"] <= LONG_S and lf["verify_success"] and not lf["failed"]})
    sc = res.get("scaling")
    if sc:
        p = sc["pieces"]
        sizes = [r["pieces"] for r in p["rows"] if not r["skipped"]]
        for key, label in (("trace", "trace"), ("total", "trace + sample + verify")):
            s = p[f"slope_{key}"]
            slope = s["ge10"] if not math.isnan(s["ge10"]) else s["all"]
            which = "sizes >= 10" if not math.isnan(s["ge10"]) else "all sizes"
            vs = [r["pieces"] for r in p["rows"] if r.get("verify_s")] if key == "total" else sizes
            rows.append({"key": f"linear_{key}", "target": f"cost linear in the number of pieces ({label})",
                         "measured": f"log-log slope {_f(slope, '.3f')} over {which} (pieces {vs}; all sizes "
                                     f"{_f(s['all'], '.3f')})",
                         "ratio": f"slope {_f(slope, '.2f')} (linear = 1; met if <= {LINEAR_SLOPE})",
                         "met": None if math.isnan(slope) else slope <= LINEAR_SLOPE})
    if sc:
        by_size = {r["pieces"]: r for r in sc["pieces"]["rows"] if not r["skipped"]}
        for n, limit, label in ((1, ARC_S, "a single arc"), (1000, THOUSAND_S, "1000 distinct arcs")):
            r = by_size.get(n)
            if r is not None:
                ms = r["trace_s"] * 1e3
                rows.append({"key": f"arcs_{n}", "target": f"{label} traced warm <= {limit * 1e3:g} ms",
                             "measured": f"{ms:.3g} ms ({ms / n:.3g} ms an arc; {len(r['failed'])} failed)",
                             "ratio": f"{r['trace_s'] / limit:.2g}x the target",
                             "met": r["trace_s"] <= limit and not r["failed"]})
    cold = res.get("cold")
    if cold:
        fl_c = cold["flower"]
        rows.append({"key": "flower_mb", "target": f"double-flower peak memory, cold CLI <= {FLOWER_MB:g} MB",
                     "measured": f"{fl_c['peak_mb']:.0f} MB (largest of {len(fl_c['wall'])} runs)",
                     "ratio": f"{fl_c['peak_mb'] / FLOWER_MB:.2g}x the target", "met": fl_c["peak_mb"] <= FLOWER_MB})
        for r in cold["rows"]:
            state = (f"stopped after {cold['timeout']:g} s" if r["timed_out"] else f"exit {r['returncode']}")
            rows.append({"key": f"cold_{r['name']}",
                         "target": f"{r['name']} from a cold CLI start <= {COLD_RATIO:g}x the double flower's",
                         "measured": f"{r['wall']:.1f} s against {fl_c['wall_median']:.2f} s ({state}; peak "
                                     f"{r['peak_mb']:.0f} MB); {r['verdict'][:60]}",
                         "ratio": f"{'>= ' if r['timed_out'] else ''}{r['ratio']:.2g}x the double flower",
                         "met": not r["timed_out"] and r["ratio"] <= COLD_RATIO})
    for r in res.get("planning", []):
        within = r["duration_after"] > 0 and r["reach_after"] <= r["reach"]
        rows.append({"key": f"plan_{r['figure']}",
                     "target": f"{r['figure']} planned within {r['reach']:g}, plan + trace + verify <= {PLAN_S:g} s warm",
                     "measured": f"{r['seconds']:.1f} s ({r['ratio']:.0f}x the double flower); mass within "
                                 f"{r['reach_after']:.3g}, verified {'yes' if r['verified'] else 'NO'}",
                     "ratio": f"{r['seconds'] / PLAN_S:.2g}x the target",
                     "met": r["seconds"] <= PLAN_S and r["verified"] and within})
    return rows


# ----------------------------------------------------------------------------------------------
# RESULTS.md
# ----------------------------------------------------------------------------------------------


def _table(header: list[str], rows: list[list]) -> list[str]:
    def cell(c) -> str:
        return str(c).replace("|", "\\|")

    out = ["| " + " | ".join(cell(c) for c in header) + " |", "|" + "|".join("---" for _ in header) + "|"]
    out += ["| " + " | ".join(cell(c) for c in r) + " |" for r in rows]
    return out


def _runs(pieces: dict) -> str:
    """How many runs each size's figures come from: "one run" or "the median of N runs"."""
    n = max((r.get("runs", 1) for r in pieces["rows"] if not r["skipped"]), default=1)
    return "one run" if n == 1 else f"the median of {n} runs"


def _met(m) -> str:
    return "n/a" if m is None else ("**met**" if m else "**not met**")


def _hand_analysis() -> dict[str, str]:
    """The hand-written profile paragraphs of bench/GAPS.md, by the key after each ``## ``."""
    path = Path(__file__).resolve().parent / "GAPS.md"
    if not path.is_file():
        return {}
    out: dict[str, list[str]] = {}
    key = None
    for line in path.read_text(encoding="utf-8").splitlines():
        if line.startswith("## "):
            key = line[3:].strip()
            out[key] = []
        elif key is not None:
            out[key].append(line)
    return {k: "\n".join(v).strip() for k, v in out.items()}


def robustness_section() -> list[str]:
    """Closed-loop robustness per school figure, as ``bench/bench_robustness.py --markdown`` recorded it
    in ``bench/ROBUSTNESS.md`` (a run of a quarter of an hour, kept out of this runner)."""
    path = Path(__file__).resolve().parent / "ROBUSTNESS.md"
    body = path.read_text(encoding="utf-8").strip() if path.is_file() else \
        "Not recorded: run `python bench/bench_robustness.py --markdown bench/ROBUSTNESS.md`."
    return ["## Robustness: open loop against the tracking law (issue 16)", "", body]


def profile_section(res: dict, tgt: list[dict]) -> list[str]:
    """The measured stage breakdown per unmet target, with a placeholder paragraph to fill in."""
    unmet = {t["key"] for t in tgt if t["met"] is False}
    L = ["## Profile and what would close the gap", "",
         "> The measured stage breakdown is written below each heading by the runner; the profile and "
         "the proposed change after it come from `bench/GAPS.md` (written by hand).", ""]
    if not unmet:
        return L + ["Every target was met in this run.", ""]
    fl = res.get("double_flower")
    analysis = _hand_analysis()

    def placeholder_for(key: str) -> list[str]:
        text = analysis.get(key)
        if text:
            return [text, ""]
        return [f"*Placeholder ({key}): profile (e.g. `python -m cProfile -s cumtime`) and what would close the "
                "gap; write it under `## " + key + "` in bench/GAPS.md.*", ""]
    if "flower_warm" in unmet:
        m, s = fl["median"], fl["share"]
        L += [f"### {fl['figure']}, warm end to end ({m['total']:.2f} s against {FLOWER_WARM_S} s)", "",
              f"Measured stage breakdown (median of {fl['runs']}): trace {m['trace']:.3f} s ({s['trace']:.0%}), "
              f"sample {m['sample']:.3f} s ({s['sample']:.0%}), verify {m['verify']:.3f} s ({s['verify']:.0%}: "
              f"replay of the full dynamics {m['replay']:.3f} s ({s['replay']:.0%}), checks {m['checks']:.3f} s "
              f"({s['checks']:.0%})). "
              f"{fl['sections']} sections of which {fl['distinct_sections']} are solved and the rest reused. "
              f"Even with trace and sample free, verify alone is {m['verify'] / FLOWER_WARM_S:.1f}x the target.", ""]
        L += placeholder_for("flower_warm")
    if "flower_cold" in unmet:
        c = fl["cold"]
        L += [f"### {fl['figure']}, cold CLI start ({c['wall_median']:.2f} s against {FLOWER_COLD_S} s)", "",
              f"Measured: wall {c['wall_median']:.2f} s = `import skatetrace.cli` about {c['import_median']:.2f} s "
              f"(interpreter start and imports, measured separately) + the CLI's own reported work "
              f"{c['reported_median']:.2f} s (resolve, trace, verify, write files; numba from its on-disk cache) "
              f"+ the rest (exit, unaccounted) {c['wall_median'] - c['import_median'] - c['reported_median']:.2f} s. "
              f"The warm in-process total is {fl['median']['total']:.2f} s.", ""]
        L += placeholder_for("flower_cold")
    if "flower_first" in unmet:
        f = fl["first"]
        parts = ", ".join(f"{part} {sec} s" for part, sec in f["compiled"]) or "nothing"
        L += [f"### {fl['figure']}, first run after a fresh install ({f['wall_median']:.1f} s against "
              f"{FLOWER_FIRST_S:g} s)", "",
              f"Measured: compiled in the run: {parts}"
              f"{'; the verification compiled alongside, in a second process' if f['ahead'] else ''}{_later(f)}."
              + (f" The same command with numba's cache warm takes {fl['cold']['wall_median']:.2f} s without plots "
                 "and viewer (cold CLI start above)." if fl.get("cold") else ""), ""]
        L += placeholder_for("flower_first")
    paper_unmet = [r for r in res.get("paper_arcs", []) if f"paper_arc_{r['arc']}" in unmet]
    if paper_unmet:
        L += ["### Paper arcs (>= 100x the baseline)", ""]
        for r in paper_unmet:
            L.append(f"- arc {r['arc']}: {r['ratio']:.1f}x; exact engine {r['exact_s'] * 1e3:.1f} ms "
                     f"({r['exact_nfev']} manoeuvre evaluations), baseline {r['baseline_s']:.3f} s; for 100x the exact "
                     f"engine would need {r['baseline_s'] / PAPER_SPEEDUP * 1e3:.1f} ms.")
        L += [""] + placeholder_for("paper_arcs")
    lf = res.get("long_figure")
    if unmet & {"long_trace", "long_total"}:
        L += [f"### {lf['pieces']} distinct arcs (<= {LONG_S:g} s)", ""]
        line = (f"Measured: trace {lf['trace_s']:.2f} s ({lf['trace_s'] / lf['pieces'] * 1e3:.1f} ms per section, "
                f"{lf['nfev']} manoeuvre evaluations)")
        if lf.get("verified"):
            tot = lf["total_s"]
            line += (f", sample {lf['sample_s']:.2f} s, verify {lf['verify_s']:.2f} s (replay {lf['replay_s']:.2f} s, "
                     f"checks {lf['checks_s']:.2f} s); shares of the total "
                     f"{tot:.1f} s: trace {lf['trace_s'] / tot:.0%}, sample {lf['sample_s'] / tot:.0%}, "
                     f"verify {lf['verify_s'] / tot:.0%}. Simulated duration of the figure {lf['duration']:.0f} "
                     f"time units")
        L += [line + ".", ""] + placeholder_for("long")
    arcs = [n for n in (1, 1000) if f"arcs_{n}" in unmet]
    if arcs:
        rows = {r["pieces"]: r for r in res["scaling"]["pieces"]["rows"] if not r["skipped"]}
        L += [f"### Distinct arcs traced warm (a single arc <= {ARC_S * 1e3:g} ms, 1000 <= {THOUSAND_S * 1e3:g} ms)",
              ""]
        for n in arcs:
            r = rows[n]
            L.append(f"- {n} distinct arc{'s' if n > 1 else ''}: {r['trace_s'] * 1e3:.3g} ms, {r['nfev']} manoeuvre "
                     f"integrations ({r['trace_s'] / max(r['nfev'], 1) * 1e6:.0f} us each, the Python around them "
                     "included)")
        L += [""] + placeholder_for("arcs")
    if unmet & {"linear_trace", "linear_total"}:
        p = res["scaling"]["pieces"]
        L += ["### Linear growth with the number of pieces", ""]
        for r in p["rows"]:
            if r["skipped"]:
                continue
            per = f"trace {r['trace_s'] / r['pieces'] * 1e3:.1f} ms/piece"
            if r.get("verify_s"):
                per += f", verify {r['verify_s'] / r['pieces'] * 1e3:.1f} ms/piece"
            L.append(f"- {r['pieces']} pieces: {per}")
        L += [""] + placeholder_for("linear")
    return L


def write_markdown(path: Path, res: dict, meta: dict) -> None:
    mach, ver = meta["machine"], meta["versions"]
    tgt = targets(res)
    L = ["# skatetrace benchmark results", "",
         f"Written by `python bench/run_all.py{(' ' + ' '.join(meta['argv'])) if meta['argv'] else ''}` "
         f"(mode **{meta['mode']}**) on {meta['date']}; the runner took {meta['runtime_s']:.0f} s "
         f"({meta['runtime_s'] / 60:.1f} min).", ""]
    if meta["mode"] == "smoke":
        L += ["> **Smoke mode**: tiny cases for CI; these numbers are not benchmarks.", ""]
    shared = ("> **Shared machine**: other jobs were running on this machine during the run, so absolute "
              "times are inflated by an unknown amount. " if meta["shared"] else "> ")
    L += [shared + f"Load average (1 / 5 / 15 min) {_load(meta['load_start'])} at the start and "
          f"{_load(meta['load_end'])} at the end, on {mach['cpu_count']} CPUs; per scenario below. Ratios "
          "measured in one process (the paper arcs) are less affected than absolute times.", "",
          "## Machine", ""]
    mem = f"{mach['memory_gib']:.1f} GiB" if mach["memory_gib"] else "unknown"
    L += _table(["", ""], [["platform", mach["platform"]], ["architecture", mach["machine"]],
                           ["CPU", mach["cpu_model"]],
                           ["CPUs (os.cpu_count)", mach["cpu_count"]], ["CPUs usable (affinity)", mach["cpus_usable"]],
                           ["cgroup cpu.max", mach["cgroup_cpu_max"] or "n/a"],
                           ["memory (MemTotal)", mem], ["Python", mach["python"]]])
    L += ["", "## Versions", ""]
    L += _table(["package", "version"], [[k, v] for k, v in ver.items()])
    L += ["", "## Targets (issues 6, 15, 18)", ""]
    L += _table(["target", "measured", "as a ratio", "status"],
                [[t["target"], t["measured"], t["ratio"], _met(t["met"])] for t in tgt])
    L += ["", "Notes: the issue does not say whether the 200-arc target covers tracing only or also "
          "sampling and verification, so both are given. \"Linear\" is taken as a least-squares slope of "
          f"log(time) against log(pieces) of at most {LINEAR_SLOPE} over the sizes >= 10.", "",
          "## Scenarios", ""]
    L += [_scenario_header(meta, "paper_arcs", "1. The paper's three arcs: exact engine vs paper-style baseline")]
    pa = res.get("paper_arcs", [])
    if pa:
        L += [f"Same process, median of {pa[0]['runs']} runs each (exact engine warmed up first). "
              "Baseline: scipy BFGS over solve_ivp BDF from the Table 2 guess; its residual is |L_s - L_d|.", ""]
        L += _table(["arc", "baseline s", "exact s", "ratio", "baseline |dL|", "baseline end speed",
                     "exact residual", "exact end speed", "exact evaluations"],
                    [[r["arc"], f"{r['baseline_s']:.3f}", f"{r['exact_s']:.4f}", f"{r['ratio']:.1f}",
                      f"{r['baseline_residual']:.2e}", f"{r['baseline_end_speed']:.2e}", f"{r['exact_residual']:.1e}",
                      f"{r['exact_end_speed']:.1e}", r["exact_nfev"]] for r in pa])
    fl = res.get("double_flower")
    if fl:
        L += ["", _scenario_header(meta, "double_flower", f"2. {fl['figure']} end to end")]
        L += [f"{fl['sections']} sections ({fl['distinct_sections']} solved, the others reused by the tracer's "
              f"cache). Warm: in-process, median of {fl['runs']} after one warm-up run (the warm-up took "
              f"{fl['warmup_s']:.2f} s). Replay max deviation {fl['max_deviation']:.2e} (tolerance "
              f"{fl['tolerance']:.2e}), max cusp speed {fl['max_cusp_speed']:.2e}.", ""]
        m, s = fl["median"], fl["share"]
        names = {"replay": "verify: replay (integrate the full dynamics)", "checks": "verify: checks"}
        rows = [[names.get(k, k), f"{m[k]:.3f}", f"{s[k]:.1%}" if k in s else "100%",
                 ", ".join(f"{v:.3f}" for v in fl["stages"][k])]
                for k in ("trace", "sample", "verify", "replay", "checks", "total")]
        c = fl.get("cold")
        if c:
            rows.append(["cold CLI start (wall)", f"{c['wall_median']:.3f}", "",
                         ", ".join(f"{v:.3f}" for v in c["wall"])])
            rows.append(["  of which the CLI reports its work as", f"{_f(c['reported_median'], '.3f')}", "",
                         ", ".join(_f(v, ".3f") for v in c["reported"])])
            rows.append(["  `import skatetrace.cli` alone", f"{c['import_median']:.3f}", "",
                         ", ".join(f"{v:.3f}" for v in c["import"])])
        L += _table(["stage", "median s", "share of warm total", "runs s"], rows)
        e = fl.get("engines")
        if e:
            L += ["", f"The same replay through scipy's `solve_ivp` with a Python right-hand side "
                  f"(`verify.replay(..., engine=\"scipy\")`, the path before the compiled replay), once in the "
                  f"same process: {e['scipy_s']:.2f} s, {e['ratio']:.0f} times the compiled replay's "
                  f"{e['compiled_s']:.3f} s."]
        if c:
            L += ["", f"Cold command: `{' '.join(c['command'])}` (exit codes {c['returncodes']}; files written: "
                  f"{', '.join(c['files'])}). The CLI also resolves the figure, may add rests and writes the files. "
                  "The package was byte-compiled first (`compileall`, as `pip install` does), so a cold start "
                  "loads bytecode" + ("" if c.get("byte_compiled", True) else " (compileall reported an error)") + "."]
    lf = res.get("long_figure")
    if lf:
        L += ["", _scenario_header(meta, "long_figure", f"3. A long figure: {lf['pieces']} distinct arcs")]
        L += [f"`bench/_common.py: distinct_arcs({lf['pieces']}, seed={lf['seed']})`: |curvature| 0.2 to 2 "
              "(random sign), sweep 30 to 200 degrees, cusps with pivots of -150 to 150 degrees, M = 2, m = 1, "
              f"I = 3; total length {lf['length']:.1f}, figure size {lf['figure_size']:.1f}, simulated duration "
              f"{lf['duration']:.1f}. {lf['sections']} sections, {lf['distinct_sections']} solved (nothing reused).", ""]
        rows = [["trace", f"{lf['trace_s']:.2f}", f"{lf['trace_s'] / lf['pieces'] * 1e3:.1f}"]]
        if lf.get("verified"):
            rows += [["sample", f"{lf['sample_s']:.2f}", f"{lf['sample_s'] / lf['pieces'] * 1e3:.1f}"],
                     ["verify", f"{lf['verify_s']:.2f}", f"{lf['verify_s'] / lf['pieces'] * 1e3:.1f}"],
                     ["verify: replay (integrate the full dynamics)", f"{lf['replay_s']:.2f}",
                      f"{lf['replay_s'] / lf['pieces'] * 1e3:.1f}"],
                     ["verify: checks", f"{lf['checks_s']:.2f}", f"{lf['checks_s'] / lf['pieces'] * 1e3:.1f}"],
                     ["total", f"{lf['total_s']:.2f}", f"{lf['total_s'] / lf['pieces'] * 1e3:.1f}"]]
        L += _table(["stage", "s", "ms per section"], rows)
        L += ["", f"Sections traced: {lf['traced']} of {lf['sections']}; failed to trace: "
              + (", ".join(f"{f['section']} ({f['message']})" for f in lf["failed"]) or "none")
              + f". Largest boundary residual {lf['max_residual']:.1e}."]
        if lf.get("verified"):
            L += ["", f"Verification {'passed' if lf['verify_success'] else 'FAILED'}: max deviation "
                  f"{lf['max_deviation']:.2e} (tolerance {lf['tolerance']:.2e}), max cusp speed "
                  f"{lf['max_cusp_speed']:.2e}; sections failing verification: "
                  + (", ".join(str(f["section"]) for f in lf["verify_failed"]) or "none") + "."]
    sc = res.get("scaling")
    if sc:
        p = sc["pieces"]
        L += ["", _scenario_header(meta, "scaling", "4. Scaling")]
        L += ["### Versus the number of pieces", "",
              f"Nested figures from the same generator (the first n arcs of seed 0), {_runs(p)} each. A size is "
              "traced only, or not run, when its time extrapolated from the smaller sizes (a power law through "
              f"the last two, never below linear) exceeds {p['budget_s']:.0f} s; the note says which.",
              ""]
        rows = []
        for r in p["rows"]:
            if r["skipped"]:
                rows.append([r["pieces"], "", "skipped", "", "", "", "", "", "", "", "", "", r["note"]])
                continue
            v = bool(r.get("verify_s"))
            rows.append([r["pieces"], f"{r['duration']:.1f}", f"{r['trace_s']:.2f}",
                         f"{r['trace_s'] / r['pieces'] * 1e3:.1f}",
                         f"{r['sample_s']:.2f}" if v else "-", f"{r['verify_s']:.2f}" if v else "-",
                         f"{r['verify_s'] / r['pieces'] * 1e3:.1f}" if v else "-",
                         f"{r['verify_s'] / r['duration'] * 1e3:.1f}" if v else "-",
                         f"{r['replay_s']:.2f}" if v else "-", f"{r['checks_s']:.2f}" if v else "-",
                         len(r["failed"]), ("passed" if r["verify_success"] else "FAILED") if v else "-",
                         r["note"] or ""])
        L += _table(["pieces", "simulated time", "trace s", "trace ms/piece", "sample s", "verify s",
                     "verify ms/piece", "verify ms per unit of simulated time", "replay s", "checks s",
                     "failed sections",
                     "verification", "note"], rows)
        L += ["", "Least-squares slope of log(time) against log(pieces) (1 = linear):", ""]
        L += _table(["stage", "all sizes", "sizes >= 10"],
                    [[k, _f(p[f"slope_{k}"]["all"], ".3f"), _f(p[f"slope_{k}"]["ge10"], ".3f")]
                     for k in ("trace", "sample", "verify", "replay", "checks", "total")])
        L += ["", f"Against the simulated duration instead of the number of pieces: slope of log(verify time) "
              f"{_f(p['slope_verify_vs_duration'], '.3f')}, of log(replay time) "
              f"{_f(p['slope_replay_vs_duration'], '.3f')}."]
        tol = sc.get("tolerance")
        if tol:
            L += ["", "### Versus the fit tolerance", "",
                  f"`{tol['drawing']}` scaled to {tol['size_m']:.0f} m, `fit_drawing` (greedy) at tolerances relative "
                  "to its size (median fit time); the figure (equal consecutive arcs merged, 1.7 m skater, 2 m/s) "
                  "traced at some of them.", ""]
            L += _table(["tol / size", "arcs", "lines", "bound / tol", "fit s", "pieces", "sections", "trace s",
                         "traced"],
                        [[f"{r['tol_rel']:.0e}", r["arcs"], r["lines"], f"{r['bound_over_tol']:.3f}",
                          f"{r['fit_s']:.3f}", r.get("pieces", "-"), r.get("sections", "-"),
                          f"{r['trace_s']:.2f}" if r["traced"] else "-",
                          ("yes" if r["trace_success"] else "FAILED") if r["traced"] else "-"] for r in tol["rows"]])
            L += ["", f"Slope of log(arcs + lines) against log(1/tol): {_f(tol['slope_arcs'], '.3f')} (an arc "
                  f"spline's error falls as h^3, so about 1/3 is expected); of log(fit time): "
                  f"{_f(tol['slope_fit_time'], '.3f')}."]
    pl = res.get("planning")
    if pl:
        L += ["", _scenario_header(meta, "planning", "5. Bounded-reach planning (issue 15)"),
              "Each figure with the launch-glide-stop manoeuvres and planned within the reach, both replayed and "
              "assessed from their exported rows; the plan time (plan, trace and verify, warm, in one process "
              "with its worker processes) as a multiple of the double flower's warm trace-and-verify in the "
              "same run.", ""]
        L += bench_planning.markdown(pl).splitlines()
    cold = res.get("cold")
    if cold:
        L += ["", _scenario_header(meta, "cold", "6. From a cold CLI start, against the double flower (issue 18)"),
              "Each command as a user runs it (`skatetrace trace ... --no-plots --no-viewer`, the default "
              "planner), in a fresh interpreter, in this order in one sitting; the ratio is to the double "
              f"flower's median cold time ({cold['flower']['wall_median']:.2f} s, runs "
              f"{', '.join(f'{w:.2f}' for w in cold['flower']['wall'])} s). Peak memory: `VmHWM` of the command's main "
              "process, read every 20 ms (its worker processes not counted).", ""]
        L += _table(["command", "wall s", "x flower", "exit", "peak MB", "verdict"],
                    [[" ".join(r["args"]), f"{r['wall']:.1f}", f"{r['ratio']:.1f}",
                      "stopped" if r["timed_out"] else r["returncode"], f"{r['peak_mb']:.0f}", r["verdict"][:90].replace("|", "/")]
                     for r in cold["rows"]])
    L += [""] + robustness_section()
    L += [""] + profile_section(res, tgt)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text("\n".join(L) + "\n")


def _scenario_header(meta: dict, key: str, title: str) -> str:
    s = meta["scenarios"].get(key, {})
    return (f"## {title}\n\n*Wall time {s.get('seconds', math.nan):.0f} s; load average "
            f"{_load(s.get('load_start'))} before, {_load(s.get('load_end'))} after; arguments "
            f"`{' '.join(s.get('argv', []))}`.*\n")


# ----------------------------------------------------------------------------------------------
# Summary table and main
# ----------------------------------------------------------------------------------------------


README_BEGIN = "<!-- speed: written by python bench/run_all.py from bench/RESULTS.md; do not edit -->"
README_END = "<!-- end of speed -->"


def targets_from_markdown(text: str) -> tuple[str, list[dict]]:
    """The first line (date, mode) and the rows of the targets table of a RESULTS.md."""
    lines = text.splitlines()
    start = next(i for i, line in enumerate(lines) if line.startswith("## Targets"))
    rows = []
    for line in lines[start + 1:]:
        if line.startswith("## "):
            break
        if not line.startswith("| ") or line.startswith("| target |"):
            continue
        cells = [c.strip() for c in line.strip("|").split(" | ")]
        if len(cells) == 4:
            rows.append({"target": cells[0], "measured": cells[1], "ratio": cells[2],
                         "met": {"**met**": True, "**not met**": False}.get(cells[3])})
    when = next((line for line in lines if line.startswith("Written by")), "")
    return when, rows


def readme_block(when: str, tgt: list[dict]) -> list[str]:
    """The README's speed figures: each target as measured, the cold runs of issue 18 counted."""
    cold = [t for t in tgt if "from a cold CLI start <=" in t["target"] and "x the double flower" in t["target"]]
    planned = [t for t in tgt if " planned within " in t["target"]]
    rows = []
    for t in tgt:
        if t in cold or t in planned or t["target"].startswith("paper arc"):
            continue
        rows.append([t["target"], t["measured"].split(" (")[0], _met(t["met"])])
    if planned:
        secs = [float(t["measured"].split(" s")[0]) for t in planned]
        rows.append([f"every school figure planned within 0.5 m, plan + trace + verify <= {PLAN_S:g} s warm",
                     f"{sum(bool(t['met']) for t in planned)} of {len(planned)} ({min(secs):.1f} to {max(secs):.1f} s)",
                     _met(all(t["met"] for t in planned))])
    arcs = [t for t in tgt if t["target"].startswith("paper arc")]
    if arcs:
        rows.append([f"the paper's {len(arcs)} arcs >= {PAPER_SPEEDUP:g}x faster than the paper-style baseline",
                     ", ".join(t["measured"].split(" (")[0] for t in arcs), _met(all(t["met"] for t in arcs))])
    if cold:
        missed = [f"{t['target'].split(' from a cold')[0]} {t['ratio'].split(' ')[0]}" for t in cold if not t["met"]]
        rows.append([f"every school figure and example drawing from a cold CLI start <= {COLD_RATIO:g}x the double "
                     "flower's", f"{sum(bool(t['met']) for t in cold)} of {len(cold)}"
                     + (f" (not: {', '.join(missed)})" if missed else ""), _met(not missed)])
    stamp = when.replace("Written by ", "").rstrip(".") or "python bench/run_all.py"
    return [README_BEGIN, "", f"Measured by {stamp}; the whole table, with every scenario, is in "
            "[bench/RESULTS.md](bench/RESULTS.md).", "", *_table(["target", "measured", "status"], rows), "",
            README_END]


def update_readme(readme: Path, results: Path) -> bool:
    """Rewrite the README's speed block from ``results`` (RESULTS.md); False if the README has no block."""
    text = readme.read_text(encoding="utf-8")
    if README_BEGIN not in text or README_END not in text:
        return False
    head, rest = text.split(README_BEGIN, 1)
    tail = rest.split(README_END, 1)[1]
    block = "\n".join(readme_block(*targets_from_markdown(results.read_text(encoding="utf-8"))))
    readme.write_text(head + block + tail, encoding="utf-8")
    return True


def summary(res: dict, tgt: list[dict]) -> str:
    w = max(len(t["target"]) for t in tgt) if tgt else 10
    lines = [f"{'target':<{w}}  {'status':<9}  measured", "-" * (w + 60)]
    for t in tgt:
        status = "n/a" if t["met"] is None else ("met" if t["met"] else "NOT MET")
        lines.append(f"{t['target']:<{w}}  {status:<9}  {t['measured']}  [{t['ratio']}]")
    return "\n".join(lines)


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    g = ap.add_mutually_exclusive_group()
    g.add_argument("--quick", action="store_true", help="a fast pass: fewer runs, sizes <= 100")
    g.add_argument("--smoke", action="store_true", help="tiny cases for CI (numbers meaningless)")
    ap.add_argument("--out", default=str(HERE / "RESULTS.md"), help="where to write RESULTS.md (default bench/RESULTS.md)")
    ap.add_argument("--readme", default=None,
                    help="README whose speed block to rewrite from the results (default: the project's README in "
                         "a full run, none otherwise)")
    ap.add_argument("--readme-only", action="store_true",
                    help="rewrite the README's speed block from the RESULTS.md at --out, and run nothing")
    ap.add_argument("--dedicated", action="store_true",
                    help="the machine ran nothing else: drop the shared-machine warning from RESULTS.md")
    args = ap.parse_args(argv)
    mode = "smoke" if args.smoke else ("quick" if args.quick else "full")
    readme = Path(args.readme) if args.readme else (HERE.parent / "README.md" if mode == "full" else None)
    if args.readme_only:
        done = update_readme(readme or HERE.parent / "README.md", Path(args.out))
        print(f"{'rewrote' if done else 'found no speed block in'} {readme or HERE.parent / 'README.md'}")
        return {"readme": done}
    argv_list = list(sys.argv[1:] if argv is None else argv)
    start = time.perf_counter()
    meta = {"mode": mode, "argv": argv_list, "shared": not args.dedicated, "date": _dt.datetime.now().astimezone().strftime("%Y-%m-%d %H:%M:%S %Z"),
            "machine": machine(), "versions": versions(), "load_start": loadavg(), "scenarios": {}}
    print(f"skatetrace benchmarks, mode {mode}, {meta['date']}; load average {_load(meta['load_start'])}", flush=True)
    res = {}
    for key, script in SCRIPTS.items():
        args_k = MODES[mode][key]
        print(f"\n=== {key}: {script.__name__}.main({args_k}) ===", flush=True)
        la0, t0 = loadavg(), time.perf_counter()
        res[key] = script.main(list(args_k))
        meta["scenarios"][key] = {"seconds": time.perf_counter() - t0, "load_start": la0, "load_end": loadavg(),
                                  "argv": args_k}
    meta["load_end"] = loadavg()
    meta["runtime_s"] = time.perf_counter() - start
    tgt = targets(res)
    print("\n" + summary(res, tgt), flush=True)
    out = Path(args.out)
    write_markdown(out, res, meta)
    if readme is not None and update_readme(readme, out):
        print(f"rewrote the speed block of {readme}")
    print(f"\nwrote {out} (runner took {meta['runtime_s']:.0f} s; load average {_load(meta['load_end'])} at the end)",
          flush=True)
    return {"results": res, "targets": tgt, "meta": meta, "out": str(out)}


if __name__ == "__main__":
    main()
