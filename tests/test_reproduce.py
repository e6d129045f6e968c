"""`skatetrace reproduce` and its report: structure, self-containment, errata, exit codes."""

import json
import math
import re

import matplotlib

matplotlib.use("Agg")

import pytest  # noqa: E402

from skatetrace.cli import main  # noqa: E402
from skatetrace.paper.conditioning import (  # noqa: E402
    Perturbation, condition_paper_arc, format_stable, perturbations, spread_of, stable_digits,
)
from skatetrace.paper.report import reproduce, strict_json, write_report  # noqa: E402
from skatetrace.paper.tables import paper_row  # noqa: E402

pytestmark = pytest.mark.slow  # the paper's nine rows, three ways: the quick subset leaves them out

# Two perturbed runs instead of seven keep the suite fast; the machinery is the same.
FEW = perturbations(rtols=(1e-10,), seeds=(1,))


def _strict_loads(text):
    """json.loads that refuses NaN and Infinity (Python's json accepts them by default)."""
    def refuse(name):
        raise ValueError(f"not strict JSON: {name}")
    return json.loads(text, parse_constant=refuse)


@pytest.fixture(scope="module")
def small():
    # Arc 2 of Tables 1-2 and 5-6: cheap, and enough to exercise every column.
    return reproduce(("main", "length"), (2,), maxiter=3, runs=FEW)


def test_rows_three_ways(small):
    assert small.success, small.message
    assert [r.row.key for r in small.rows] == ["main-arc2", "length-arc2"]
    for rr in small.rows:
        assert rr.published.label == "published" and rr.rerun.label == "re-run" and rr.exact.label == "exact"
        assert rr.procedure.nit <= 3
        assert rr.rounding.cost <= rr.rounding.published_cost
        # the same arc (same r, same length, same start) is traced once and shared
    assert small.rows[0].exact is small.rows[1].exact
    assert small.rows[0].exact.ok and small.rows[0].exact.full_deviation <= 1e-9


def test_main_row_finding(small):
    rr = small.rows[0]
    # Table 2 arc 2: printed error 6.144e-4; the published optimum is far off in length and
    # strays from its circle in the full dynamics.
    assert rr.published.cost > 100 * rr.row.published_error, rr.published.cost
    assert rr.rounding.cost > 100 * rr.row.published_error, rr.rounding.cost
    assert rr.published.full_deviation > 1e-2
    assert not rr.published.ok


def test_errata_all_confirmed(small):
    keys = {e.key: e for e in small.errata}
    assert set(keys) == {"invariant", "skate-energy", "mass-velocity", "b-singular-set", "regularity", "tables",
                         "double-flower"}
    assert all(e.confirmed for e in small.errata), [e.key for e in small.errata if not e.confirmed]
    assert "20 inner arcs and 10 leaves" in keys["double-flower"].correct


def test_reading_study_covers_every_reading(small):
    readings = small.readings
    assert {(d["closure"], d["time"]) for d in readings} == {(c, t) for c in ("xi2", "xi1", "formulas")
                                                             for t in ("each", "split")}
    assert {d["events"] for d in readings} == {"all zeros", "step ends"}
    assert len(readings) == 3 * 6 * 2
    # no reading brings any published optimum to its printed error
    assert all(d["cost"] > 10 * d["printed_error"] for d in readings)


def test_report_files(small, tmp_path):
    paths = write_report(small, tmp_path, figures=False)
    names = {p.name for p in paths}
    assert names == {"report.md", "report.html", "reproduction.json"}
    md = (tmp_path / "report.md").read_text()
    for col in ("Paper (printed)", "Published optimum, evaluated", "Procedure re-run from the guess", "Exact engine"):
        assert col in md
    assert "## Errata" in md and "Tables 1-2" in md and "Tables 5-6" in md
    assert "6.144e-04" in md or "0.0006144" in md
    html = (tmp_path / "report.html").read_text()
    assert html.startswith("<!DOCTYPE html>")
    assert not re.search(r"(src|href)=['\"]https?:", html), "the page must not load anything from the network"
    data = _strict_loads((tmp_path / "reproduction.json").read_text(encoding="utf-8"))
    assert data["schema"] == "skatetrace.reproduction/1"
    assert data["rows"][0]["evaluations"]["exact"]["ok"] is True
    # every evaluation carries its spread over the nominal and the perturbed runs
    for row in data["rows"]:
        for which in ("published", "rerun", "exact"):
            cond = row["conditioning"][which]
            assert len(cond["runs"]) == 1 + len(FEW)
            cost = cond["yardsticks"]["cost"]
            assert cost["runs"] == 1 + len(FEW) and isinstance(cost["text"], str)
            if cost["min"] is not None:
                assert cost["min"] <= cost["max"]
    assert data["settings"]["conditioning"]["runs"][0]["rtol"] == 1e-10
    # Table 6 arc 2 reaches a = 0 forward: its crossing is in the JSON (a fact of the approach, not of round-off)
    fwd = data["rows"][1]["crossings"][0]
    assert fwd["direction"] == 1 and fwd["reaches"] is True and fwd["blows_up"] is False
    assert "How the published optimum meets a = 0" in md and "**Conditioning.**" in md


def test_report_embeds_figures(tmp_path):
    rep = reproduce(("main",), (2,), maxiter=1)
    paths = write_report(rep, tmp_path, figures=True)
    pngs = [p for p in paths if p.suffix == ".png"]
    assert pngs and all(p.stat().st_size > 1000 for p in pngs)
    html = (tmp_path / "report.html").read_text()
    assert html.count("data:image/png;base64,") == len(pngs)
    md = (tmp_path / "report.md").read_text()
    assert all(f"figures/{p.name}" in md for p in pngs)


def test_cli_reproduce(tmp_path, capsys):
    out_dir = tmp_path / "rep"
    code = main(["reproduce", "--out", str(out_dir) + "/", "--methods", "main", "--arcs", "3", "--maxiter", "2",
                 "--no-figures", "--no-conditioning"])
    out = capsys.readouterr().out
    assert code == 0, out
    assert "Table 1-2 arc 3" in out and "errata: 6 of 6 confirmed" in out  # no appendix row: no regularity item
    assert (out_dir / "report.html").exists()
    # a trailing slash on --out is not doubled anywhere
    assert f"{out_dir.as_posix()}/ " in out and "//" not in out
    md = (out_dir / "report.md").read_text(encoding="utf-8")
    assert "//" not in md.replace("https://", "")
    # one run time, measured once: the CLI prints the number report.md states
    cli_s = re.search(r"computed in (\d+) s", out).group(1)
    md_s = re.search(r"Generated by skatetrace on .* in (\d+) s", md).group(1)
    assert cli_s == md_s
    assert "Conditioning not measured" in md and "conditioning not measured" in out
    _strict_loads((out_dir / "reproduction.json").read_text(encoding="utf-8"))


def test_strict_json_writes_null_for_nan_and_infinity(small, tmp_path):
    text = strict_json({"a": math.nan, "b": [1.0, -math.inf], "c": {"d": (math.inf,)}})
    assert _strict_loads(text) == {"a": None, "b": [1.0, None], "c": {"d": [None]}}
    with pytest.raises(ValueError, match="not strict"):
        _strict_loads('{"a": NaN}')
    # A run with NaN among its numbers still writes strict JSON: Table 6 arc 2 has no zero of a backward,
    # so that crossing's exponents are NaN, written as null.
    assert math.isnan(small.rows[1].crossings[1].mu)
    write_report(small, tmp_path, figures=False)
    raw = (tmp_path / "reproduction.json").read_text(encoding="utf-8")
    assert "NaN" not in raw and "Infinity" not in raw
    assert _strict_loads(raw)["rows"][1]["crossings"][1]["mu"] is None


@pytest.mark.parametrize("lo, hi, digits", [
    (0.0855, 0.0856, 2), (1.0, 1.0, 4), (2.9e-6, 4.9e-5, 0), (-1.0, 1.0, 0), (0.14299, 0.14301, 3),
    (4.46, 4.4601, 4), (1.0, 1.05, 1), (math.nan, 1.0, 0), (1.0, math.inf, 0), (-2.11, -2.1101, 4),
])
def test_stable_digits(lo, hi, digits):
    assert stable_digits(lo, hi) == digits
    assert stable_digits(hi, lo) == digits


@pytest.mark.parametrize("values, kwargs, text", [
    ([0.08553, 0.08554, 0.08552], {}, "0.0855"),
    ([0.0855, 0.0855], {}, "0.0855"),
    ([4.457, 4.4571], {}, "4.46"),
    ([0.4833, 0.5133], {}, "0.5"),  # 6 % apart: one digit
    ([2.884e-6, 2.122e-4], {}, "ill-conditioned (spread 2.9e-06 to 0.00021)"),
    ([-0.0053, 0.0146], {}, "ill-conditioned (spread -0.0053 to 0.015)"),
    ([2.87e-10, 7.3e-11, 5.1e-10], {"residual": True}, "≤ 1e-9"),
    ([1e-10], {"residual": True}, "≤ 1e-10"),
    ([0.0, 0.0], {"residual": True}, "0"),
    ([0.87, 0.87], {"residual": True}, "0.870"),  # above the floor a residual is a value
    ([math.inf, math.inf], {}, "inf"),
    ([1.0, math.inf], {}, "ill-conditioned (spread 1 to inf)"),
    ([math.nan, 1.0], {}, "ill-conditioned (nan in 1 of 2 runs)"),
])
def test_format_stable(values, kwargs, text):
    assert format_stable(values, **kwargs) == text


def test_spread_verdicts_and_dicts():
    same = spread_of("ok", "verdict", [True, True, True])
    split = spread_of("ok", "verdict", [False, True, False])
    assert same.text() == "yes" and same.stable
    assert split.text() == "ill-conditioned (yes in 1 of 3 runs)" and not split.stable
    assert split.to_dict()["yes"] == 1
    cost = spread_of("cost", "value", [3.0, 2.0, 4.0])
    assert (cost.nominal, cost.lo, cost.hi) == (3.0, 2.0, 4.0) and not cost.stable
    assert cost.to_dict()["stable_digits"] == 0
    with pytest.raises(ValueError, match="kind"):
        spread_of("x", "number", [1.0])
    with pytest.raises(ValueError, match="no runs"):
        spread_of("x", "value", [])


def test_perturbations():
    runs = perturbations()
    assert [p.rtol for p in runs[:4]] == [1e-10, 1e-11, 1e-12, 1e-13]
    assert [p.seed for p in runs[4:]] == [1, 2, 3] and all(p.rtol is None for p in runs[4:])
    x = (2.0, -3.0, 0.0, 0.0, -1.2)
    assert Perturbation("none").initial(x) == x
    y = runs[4].initial(x)
    assert y != x and y != runs[5].initial(x)
    rel = [abs(b / a - 1) for a, b in zip(x, y) if a != 0]
    assert all(0.5e-12 < r < 2e-12 for r in rel), rel
    assert [abs(v) for v in y[2:4]] == [1e-12, 1e-12]  # zeros move by eps
    assert runs[4].initial(x) == runs[4].initial(x)  # seeded: the same every time
    for bad in ({"rtols": (0.0,)}, {"eps": -1.0}):
        with pytest.raises(ValueError):
            perturbations(**bad)


def test_condition_paper_arc_on_a_well_conditioned_row():
    # Table 2 arc 2 never reaches a singular control: every yardstick agrees across the runs.
    row = paper_row("main", 2)
    cond = condition_paper_arc(row, row.published, runs=FEW)
    assert cond.labels == ("nominal", "rtol 1e-10", FEW[1].label)
    assert cond.ill_conditioned == ()
    assert cond.text("cost") == "0.0855" and cond.text("ok") == "no"
    assert cond.spreads["cost"].hi - cond.spreads["cost"].lo < 1e-6


@pytest.mark.parametrize("args, needle", [
    (["--methods", "main,tables"], "unknown methods"),
    (["--arcs", "4"], "unknown arcs"),
    (["--arcs", "one"], "--arcs"),
    (["--maxiter", "0"], "--maxiter"),
])
def test_cli_reproduce_bad_arguments(tmp_path, capsys, args, needle):
    assert main(["reproduce", "--out", str(tmp_path), "--no-figures", *args]) == 2
    assert needle in capsys.readouterr().err
