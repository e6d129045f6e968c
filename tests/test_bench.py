"""The benchmark scripts run on a small case (timings are never asserted)."""

import math
from pathlib import Path

from scripts import load_script

BENCH = Path(__file__).resolve().parents[1] / "bench"


def _load(name):
    return load_script(BENCH / f"{name}.py")


def test_bench_paper_arcs_small(capsys):
    rows = _load("bench_paper_arcs").main(["1", "--maxiter", "1"])
    assert [r["arc"] for r in rows] == [1, 2, 3]
    for r in rows:
        assert r["exact_success"] and r["exact_residual"] <= 1e-10 and r["exact_end_speed"] <= 1e-10
        assert r["ratio"] > 0 and r["baseline_residual"] >= 0
    assert "ratio" in capsys.readouterr().out


def test_bench_robustness_small(capsys, tmp_path):
    md = tmp_path / "ROBUSTNESS.md"
    rows = _load("bench_robustness").main(["double-flower", "--trials", "2", "--steps", "200", "--markdown", str(md)])
    d = rows[0]
    assert "error" not in d and d["schema"] == "skatetrace.robustness/1"
    assert d["closed_loop"]["trials"] == d["open_loop"]["trials"] == 2
    assert "double-flower" in capsys.readouterr().out
    text = md.read_text()
    assert "| double-flower |" in text and "with 2 trials" in text


def test_the_readme_quotes_the_speed_figures_of_bench_results():
    # issue 18: the README quotes run_all's figures; its block is rewritten from bench/RESULTS.md
    mod = _load("run_all")
    when, rows = mod.targets_from_markdown((BENCH / "RESULTS.md").read_text())
    assert len(rows) >= 10 and all(r["met"] in (True, False) for r in rows)
    readme = (BENCH.parent / "README.md").read_text()
    block = readme.split(mod.README_BEGIN, 1)[1].split(mod.README_END, 1)[0]
    assert [mod.README_BEGIN, *block.split("\n")[1:-1], mod.README_END] == mod.readme_block(when, rows), \
        "run python bench/run_all.py --readme-only"
    counted = ("planned within", "x the double flower", "paper arc")  # counted in one row each
    for r in rows:  # every other target has its own row, met or not
        if not any(c in r["target"] for c in counted):
            assert f"| {r['target']} |" in block, r["target"]


def test_bench_school_small(capsys):
    rows = _load("bench_school").main(["circle-eight"])
    assert rows[0]["figure"] == "circle-eight" and rows[0]["success"]
    assert rows[0]["deviation"] <= rows[0]["tolerance"]
    assert "circle-eight" in capsys.readouterr().out


# ---- issue 6: the benchmark suite (bench/run_all.py and its scenarios), on tiny cases ----------


def test_distinct_arcs_generator():
    common = _load("_common")
    a, b = common.distinct_arcs(5), common.distinct_arcs(40)
    assert a == common.distinct_arcs(5)  # reproducible
    assert a.curves[0].pieces == b.curves[0].pieces[:5] and a.curves[0].joins == b.curves[0].joins[:4]  # nested
    curve = b.curves[0]
    assert all(j.is_cusp for j in curve.joins) and len(curve.sections()) == 40
    assert len({(p.curvature, p.length) for p in curve.pieces}) == 40
    for p in curve.pieces:
        assert 0.2 <= abs(p.curvature) <= 2.0 and 30.0 - 1e-9 <= abs(math.degrees(p.turn)) <= 200.0 + 1e-9
    assert (b.params.M, b.params.m, b.params.I) == (2.0, 1.0, 3.0)


def test_bench_double_flower_small(capsys):
    out = _load("bench_double_flower").main(["1", "--cold", "1", "--figure", "line"])
    assert out["figure"] == "line" and out["runs"] == 1
    assert out["trace_success"] and out["verify_success"] and out["max_deviation"] <= out["tolerance"]
    assert set(out["median"]) == {"trace", "sample", "verify", "replay", "checks", "total"}
    assert math.isclose(sum(out["share"][k] for k in ("trace", "sample", "verify")), 1.0)
    med = out["median"]  # verify splits into the replay and the checks
    assert 0 < med["replay"] <= med["verify"] and math.isclose(med["replay"] + med["checks"], med["verify"])
    cold = out["cold"]
    assert cold["success"] and cold["returncodes"] == [0] and cold["wall_median"] > 0
    assert {"result.json", "controls.csv", "report.json"} <= set(cold["files"])
    assert "cold CLI start" in capsys.readouterr().out


def test_bench_long_figure_small(capsys):
    r = _load("bench_long_figure").main(["--pieces", "3"])
    assert r["pieces"] == r["sections"] == r["distinct_sections"] == r["traced"] == 3 and not r["failed"]
    assert r["trace_success"] and r["max_residual"] <= 1e-10
    assert r["verify_success"] and not r["verify_failed"] and r["max_deviation"] <= r["tolerance"]
    assert r["total_s"] >= r["trace_s"] > 0 and math.isclose(r["replay_s"] + r["checks_s"], r["verify_s"])
    assert "3 distinct arcs" in capsys.readouterr().out


def test_bench_scaling_small(tmp_path, capsys):
    mod = _load("bench_scaling")
    svg = tmp_path / "arc-line.svg"  # a semicircle and a line meeting at a corner: two quick sections
    svg.write_text('<svg xmlns="http://www.w3.org/2000/svg"><path d="M 0 0 A 50 50 0 0 1 100 0 L 100 -60"/></svg>')
    out = mod.main(["--sizes", "1", "2", "--tols", "1e-2", "1e-3", "--trace-tols", "1e-2", "--fit-runs", "1",
                    "--drawing", str(svg)])
    rows = out["pieces"]["rows"]
    assert [r["pieces"] for r in rows] == [1, 2]
    assert all(not r["skipped"] and not r["failed"] and r["verify_success"] for r in rows)
    for k in ("trace", "sample", "verify", "replay", "checks", "total"):
        assert math.isfinite(out["pieces"][f"slope_{k}"]["all"])
    tol = out["tolerance"]["rows"]
    assert [r["tol_rel"] for r in tol] == [1e-2, 1e-3]
    assert all(r["fit_success"] and r["bound_over_tol"] <= 1.0 for r in tol)
    assert tol[0]["arcs"] + tol[0]["lines"] <= tol[1]["arcs"] + tol[1]["lines"]
    assert tol[0]["traced"] and tol[0]["trace_success"] and not tol[1]["traced"]
    assert (tol[0]["arcs"], tol[0]["lines"], tol[0]["sections"]) == (1, 1, 2)
    # the cap: a size whose extrapolated time exceeds the budget is skipped, with the reason
    capped = mod.main(["--sizes", "1", "1000", "--budget", "1e-9", "--tols", "--quiet"])
    skipped = capped["pieces"]["rows"][1]
    assert skipped["pieces"] == 1000 and skipped["skipped"] and "budget" in skipped["note"]
    assert "tolerance" not in capped
    # --quick keeps sizes <= 100
    assert [r["pieces"] for r in mod.main(["--quick", "--sizes", "1", "1000", "--tols", "--quiet"])["pieces"]["rows"]] == [1]


def test_run_all_smoke(tmp_path, capsys):
    results = BENCH / "RESULTS.md"
    before = results.stat().st_mtime_ns if results.exists() else None
    mod = _load("run_all")
    readme = tmp_path / "README.md"
    readme.write_text(f"# x\n\n{mod.README_BEGIN}\nSTALE BLOCK\n{mod.README_END}\n\nLicense\n")
    out = mod.main(["--smoke", "--out", str(tmp_path / "RESULTS.md"), "--readme", str(readme)])
    assert (results.stat().st_mtime_ns if results.exists() else None) == before  # bench/RESULTS.md untouched
    quoted = readme.read_text()
    assert "STALE BLOCK" not in quoted and quoted.startswith("# x\n") and quoted.endswith("\nLicense\n")
    assert "| a single arc traced warm <= 0.5 ms |" in quoted and "| every school figure and example drawing" in quoted
    text = (tmp_path / "RESULTS.md").read_text()
    for heading in ("## Machine", "## Versions", "## Targets (issues 6, 15, 18)", "## 1. The paper's three arcs",
                    "## 2. line end to end", "## 3. A long figure: 3 distinct arcs", "## 4. Scaling",
                    "## 5. Bounded-reach planning (issue 15)", "| paper-arc |",
                    "## 6. From a cold CLI start, against the double flower (issue 18)",
                    "## Profile and what would close the gap", "Smoke mode", "Load average"):
        assert heading in text
    for pkg in ("numpy", "scipy", "numba", "matplotlib", "skatetrace"):
        assert f"| {pkg} |" in text
    keys = {t["key"] for t in out["targets"]}
    assert {"flower_warm", "flower_cold", "flower_first", "paper_arc_1", "paper_arc_2", "paper_arc_3", "long_trace", "long_total",
            "linear_trace", "linear_total", "plan_paper-arc", "arcs_1", "flower_mb", "cold_flower-with-stems"} <= keys
    assert all(t["met"] in (True, False, None) for t in out["targets"])
    res = out["results"]
    assert all(r["exact_success"] and r["exact_residual"] <= 1e-10 for r in res["paper_arcs"])
    assert res["long_figure"]["traced"] == 3 and res["long_figure"]["verify_success"]
    assert res["double_flower"]["cold"]["success"]
    first = res["double_flower"]["first"]  # a real first run: the integrator compiled in it
    assert first["success"] and any(part == "the manoeuvre integrator" for part, _ in first["compiled"])
    # and its job for later runs compiled the rest, waited for before the cache was removed
    assert first["later"] and all(v is not None and v < float("inf") for v in first["later"])
    # every table row has as many cells as its header (a '|' inside a cell would break it)
    lines = text.splitlines()
    for i, line in enumerate(lines):
        if line.startswith("|---"):
            n = lines[i - 1].replace("\\|", "").count("|")
            j = i + 1
            while j < len(lines) and lines[j].startswith("|"):
                assert lines[j].replace("\\|", "").count("|") == n, lines[j]
                j += 1
    assert "wrote" in capsys.readouterr().out


def test_an_unmet_arc_target_gets_its_measured_integrations_and_the_hand_written_profile():
    mod = _load("run_all")
    res = {"scaling": {"pieces": {"rows": [{"pieces": 1, "skipped": False, "trace_s": 1.66e-3, "nfev": 55},
                                           {"pieces": 1000, "skipped": False, "trace_s": 0.645, "nfev": 30_000}]}}}
    text = "\n".join(mod.profile_section(res, [{"key": "arcs_1", "met": False}, {"key": "arcs_1000", "met": True}]))
    assert "### Distinct arcs traced warm" in text and "- 1 distinct arc: 1.66 ms, 55 manoeuvre integrations" in text
    assert "1000 distinct arcs" not in text  # met: not profiled
    assert mod._hand_analysis()["arcs"] in text and "Placeholder" not in text


def test_bench_cold_times_each_command_against_the_flower_and_stops_one_past_its_timeout(capsys):
    # issue 18: every school figure and example drawing, exact mode included, against the double flower
    bench = _load("bench_cold")
    every = bench.commands()
    from skatetrace import school_names

    assert {f"school:{n}" for n in school_names()} <= set(every)
    assert {"serpentine-exact", "points-eight-exact", "three-turn-svg"} <= set(every) and "double-flower" not in every
    # figures no default was tuned on: other skaters' school figures, the corpus's drawings
    more = bench.commands((1.5, 1.9), corpus=True)
    assert set(every) < set(more) and more["school:three@1.9"] == ["school:three", "--height", "1.9"]
    drawings = {k: v for k, v in more.items() if k.startswith("corpus:")}
    assert len(drawings) == len(list(bench.CORPUS.glob("*.svg"))) > 50
    assert all((bench.ROOT / v[0]).is_file() and v[1:] == ["--size", "6m", "--tol", "1mm"] for v in drawings.values())
    exact = {k: v for k, v in bench.commands(exact=True).items() if k.startswith("corpus-exact:")}
    same = {k.split(":", 1)[1]: v for k, v in drawings.items()}
    assert {k.split(":", 1)[1]: v[:-1] for k, v in exact.items()} == same
    assert all(v[-1] == "--exact" for v in exact.values())
    out = bench.main(["flower-with-stems", "--flower-runs", "1"])
    (row,) = out["rows"]
    assert out["flower"]["returncodes"] == [0] and row["returncode"] == 0 and not row["timed_out"]
    assert row["ratio"] == row["wall"] / out["flower"]["wall_median"] and 10.0 < row["peak_mb"]
    # the command's own peak, not this (larger) test process's, which fork and exec would carry over
    import resource

    assert row["peak_mb"] < 0.9 * resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0 or row["peak_mb"] < 400.0
    assert row["verdict"].startswith("verified")
    stopped = bench.main(["school:three", "--flower-runs", "1", "--timeout", "0.2"])
    assert stopped["rows"][0]["timed_out"] and stopped["rows"][0]["returncode"] is None
    printed = capsys.readouterr().out
    assert "TIMED OUT" in printed and "within 5x the double flower: 0 of 1 commands" in printed


def test_bench_planning_on_the_paper_arc(capsys):
    bench = _load("bench_planning")
    rows = bench.main(["paper-arc", "--markdown"])
    row = rows[0]
    assert row["verified"] and row["residual"] <= 1e-10
    assert row["reach_after"] <= 1.0 < row["reach_before"]
    out = capsys.readouterr().out
    assert "| paper-arc |" in out and "x flower" in out


def test_bench_corpus_reports_each_outcome(capsys):
    rows = _load("bench_corpus").main(["feather-activity.svg", "camr-rhodonea.svg", "--markdown"])
    assert [r["outcome"] for r in rows] == ["verified", "refused"]
    assert "camr-rhodonea.svg" in rows[1]["reason"]
    out = capsys.readouterr().out
    assert "verified 1 of 2 (50 %)" in out and "| camr-rhodonea.svg | refused |" in out
    assert rows[0]["verdict"].startswith("verified · ") and "feasible" in rows[0]["verdict"]


def test_bench_corpus_traces_as_the_command_line_does_by_default(capsys):
    # --reach auto: planned within the reach of a 1.7 m skater (the command line's default in metres)
    rows = _load("bench_corpus").main(["bootstrap-dice-1.svg", "--reach", "auto"])
    assert rows[0]["outcome"] == "verified" and rows[0]["reason"] == ""  # planned, no fallback needed
    assert rows[0]["verdict"].startswith("verified · ")


def test_bench_corpus_runs_each_file_on_the_command_line_too(capsys):
    rows = _load("bench_corpus").main(["resvg-display-none-bbox-impact.svg", "camr-rhodonea.svg", "--cli",
                                       "--markdown"])
    row = rows[0]
    assert rows[1]["outcome"] == "refused" and rows[1]["cli_exit"] == 2  # refused on the command line too
    assert row["outcome"] == "verified" and row["cli_exit"] == 0 and row["cli_s"] > 0.0
    assert 0 < row["segments"] <= 50  # the segments the drawing is read as
    out = capsys.readouterr().out
    assert "command line, drawings of at most 50 segments: within 10 s" in out
    assert "| segments | command line s |" in out
