"""The benchmark scripts run on a small case (timings are never asserted)."""

import importlib.util
from pathlib import Path

BENCH = Path(__file__).resolve().parents[1] / "bench"


def _load(name):
    spec = importlib.util.spec_from_file_location(name, BENCH / f"{name}.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_bench_paper_arcs_small(capsys):
    rows = _load("bench_paper_arcs").main(["1", "--maxiter", "1"])
    assert [r["arc"] for r in rows] == [1, 2, 3]
    for r in rows:
        assert r["exact_success"] and r["exact_residual"] <= 1e-10 and r["exact_end_speed"] <= 1e-10
        assert r["ratio"] > 0 and r["baseline_residual"] >= 0
    assert "ratio" in capsys.readouterr().out


def test_bench_school_small(capsys):
    rows = _load("bench_school").main(["circle-eight"])
    assert rows[0]["figure"] == "circle-eight" and rows[0]["success"]
    assert rows[0]["deviation"] <= rows[0]["tolerance"]
    assert "circle-eight" in capsys.readouterr().out
