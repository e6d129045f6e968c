"""`skatetrace reproduce` and its report: structure, self-containment, errata, exit codes."""

import json
import re

import matplotlib

matplotlib.use("Agg")

import pytest  # noqa: E402

from skatetrace.cli import main  # noqa: E402
from skatetrace.paper.report import reproduce, write_report  # noqa: E402


@pytest.fixture(scope="module")
def small():
    # Arc 2 of Tables 1-2 and 5-6: cheap, and enough to exercise every column.
    return reproduce(("main", "length"), (2,), maxiter=3)


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
    data = json.loads((tmp_path / "reproduction.json").read_text())
    assert data["schema"] == "skatetrace.reproduction/1"
    assert data["rows"][0]["evaluations"]["exact"]["ok"] is True


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
    code = main(["reproduce", "--out", str(tmp_path), "--methods", "main", "--arcs", "3", "--maxiter", "2",
                 "--no-figures"])
    out = capsys.readouterr().out
    assert code == 0, out
    assert "Table 1-2 arc 3" in out and "errata: 6 of 6 confirmed" in out  # no appendix row: no regularity item
    assert (tmp_path / "report.html").exists()


@pytest.mark.parametrize("args, needle", [
    (["--methods", "main,tables"], "unknown methods"),
    (["--arcs", "4"], "unknown arcs"),
    (["--arcs", "one"], "--arcs"),
    (["--maxiter", "0"], "--maxiter"),
])
def test_cli_reproduce_bad_arguments(tmp_path, capsys, args, needle):
    assert main(["reproduce", "--out", str(tmp_path), "--no-figures", *args]) == 2
    assert needle in capsys.readouterr().err
