"""Robustness studies (skatetrace.feedback.robustness), the result folders they read
(skatetrace.outputs.traced) and ``skatetrace robustness``."""

import json
import math

import numpy as np
import pytest

from skatetrace.cli import main
from skatetrace.cli.values import angle, duration, fraction, length_or_zero
from skatetrace.errors import SkatetraceError
from skatetrace.feedback import design, default_gains
from skatetrace.feedback.robustness import (SCHEMA, LoopOutcome, Perturbation, RobustnessStatus, default_perturbation,
                                            lqr_laws, perturbed_plant, quantiles, robustness)
from skatetrace.outputs.results import read_controls
from skatetrace.outputs.traced import load_feedback, load_traced

TWO_CURVES = {"schema": "skatetrace.figure/1", "name": "two strokes", "params": {"M": 2, "m": 1, "I": 3},
              "curves": [{"name": "a", "pieces": [{"type": "arc", "radius": 1.0, "sweep_deg": 120}]},
                         {"name": "b", "start": {"x": 3.0, "y": 0.0, "heading_deg": 90},
                          "pieces": [{"type": "arc", "radius": 1.0, "sweep_deg": -90}]}]}


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    """The s-bend traced with a rest at every join: three short sections, model units."""
    out = tmp_path_factory.mktemp("s-bend")
    assert main(["trace", "s-bend", "--rests", "joins", "--out", str(out), "--no-plots", "--no-viewer"]) == 0
    return out


@pytest.fixture(scope="module")
def study(folder):
    traced = load_traced(folder)
    laws, law = lqr_laws(traced.references, traced.params, traced.size)
    return traced, laws, law


def _run(study, perturbation, steps=300, laws=None, **kw):
    traced, default, law = study
    return robustness(traced.references, traced.sections, traced.params, default if laws is None else laws,
                      perturbation, size=traced.size, steps=steps, law=law if laws is None else None, **kw)


# --- Perturbation ------------------------------------------------------------------------------------

@pytest.mark.parametrize("field, value, exc, match", [
    ("param_error", 1.0, ValueError, r"`param_error` .* below 1 \(100 %\), got 1.0"),
    ("param_error", -0.01, ValueError, r"`param_error` .* >= 0, got -0.01"),
    ("position_error", math.nan, ValueError, "`position_error`.*got nan"),
    ("angle_error", math.inf, ValueError, "`angle_error`.*finite"),
    ("delay", -1e-3, ValueError, "`delay`"),
    ("noise", "0.1", TypeError, "`noise`.*must be a number, got '0.1'"),
    ("noise", True, TypeError, "`noise`"),
    ("trials", 0, ValueError, "`trials` must be a whole number from 1 to 10000, got 0"),
    ("trials", 10_001, ValueError, "`trials`"),
    ("trials", 2.0, ValueError, "`trials`.*got 2.0"),
    ("seed", -1, ValueError, "`seed` must be a whole number >= 0"),
])
def test_a_perturbation_refuses_what_it_cannot_mean(field, value, exc, match):
    with pytest.raises(exc, match=match):
        Perturbation(**{field: value})


def test_the_scenario_follows_the_figure_units():
    metres = default_perturbation(10.0, "m")
    assert (metres.param_error, metres.position_error, metres.delay, metres.trials) == (0.05, 1e-3, 0.01, 32)
    assert metres.angle_error == pytest.approx(math.radians(0.5))
    assert default_perturbation(2.0, "model").position_error == pytest.approx(2e-4)
    assert default_perturbation(2.0, "model", trials=3).trials == 3


def test_the_same_seed_draws_the_same_sleighs_and_a_larger_error_the_same_further():
    from skatetrace.dynamics.model import SleighParams

    params = SleighParams()
    a = perturbed_plant(params, Perturbation(param_error=0.05, position_error=1e-3, angle_error=0.01, trials=5))
    b = perturbed_plant(params, Perturbation(param_error=0.05, position_error=1e-3, angle_error=0.01, trials=5))
    c = perturbed_plant(params, Perturbation(param_error=0.10, position_error=1e-3, angle_error=0.01, trials=7))
    np.testing.assert_array_equal(a.M, b.M)
    np.testing.assert_allclose(c.M[:5] - params.M, 2 * (a.M - params.M))  # the first trials are the same
    np.testing.assert_allclose(np.hypot(a.dx, a.dy), 1e-3)  # displaced by exactly the distance
    assert set(np.abs(a.dtheta)) == {0.01} and np.all(np.abs(a.I / params.I - 1) <= 0.05)
    other = perturbed_plant(params, Perturbation(param_error=0.05, trials=5, seed=1))
    assert not np.array_equal(other.M, a.M)


def test_quantiles_keep_a_diverged_trial_infinite():
    assert quantiles(np.arange(1.0, 5.0)) == {"p50": 2.5, "p95": pytest.approx(3.85), "max": 4.0}
    assert quantiles([1.0, math.nan, 3.0]) == {"p50": 3.0, "p95": math.inf, "max": math.inf}
    out = LoopOutcome(deviation=np.array([1e-3, np.inf]), cusp_speed=np.array([0.0, np.inf]), paths=(),
                      seconds=0.1).to_dict()
    assert out["diverged"] == 1 and out["max_deviation"] == {"p50": None, "p95": None, "max": None}
    json.dumps(out, allow_nan=False)


# --- the study ---------------------------------------------------------------------------------------

def test_without_perturbation_both_loops_stay_on_the_figure(study):
    traced = study[0]
    report = _run(study, Perturbation(param_error=0.0, trials=2), steps=400)
    assert report.success and report.status is RobustnessStatus.COMPLETE
    assert report.replayed == report.sections == 3
    for fam in (report.open_loop, report.closed_loop):
        assert fam.diverged == 0 and fam.trials == 2
        assert np.max(fam.deviation) <= 1e-5 * traced.size
        assert np.max(fam.cusp_speed) <= 1e-4  # speeds of order 1
        assert [p.shape[2] for p in fam.paths] == [2, 2, 2]


def test_the_same_seed_gives_the_same_study(study):
    p = Perturbation(param_error=0.03, position_error=1e-3, angle_error=0.01, delay=0.01, noise=1e-4, trials=3,
                     seed=4)
    a, b = _run(study, p, steps=200), _run(study, p, steps=200)
    for fa, fb in ((a.open_loop, b.open_loop), (a.closed_loop, b.closed_loop)):
        np.testing.assert_array_equal(fa.deviation, fb.deviation)
        np.testing.assert_array_equal(fa.cusp_speed, fb.cusp_speed)
    c = _run(study, Perturbation(**{**p.to_dict(), "seed": 5}), steps=200)
    assert not np.array_equal(c.open_loop.deviation, a.open_loop.deviation)


def test_batches_of_trials_measure_what_one_batch_does(study, monkeypatch):
    import skatetrace.feedback.robustness as module

    p = Perturbation(param_error=0.02, position_error=1e-3, trials=3)
    whole = _run(study, p, steps=150)
    calls = []
    monkeypatch.setattr(module, "MAX_SAMPLES", 1)  # one trial a batch
    parts = _run(study, p, steps=150, progress=lambda done, total: calls.append((done, total)))
    for a, b in ((whole.open_loop, parts.open_loop), (whole.closed_loop, parts.closed_loop)):
        np.testing.assert_allclose(b.deviation, a.deviation, rtol=1e-12)
        np.testing.assert_allclose(b.cusp_speed, a.cusp_speed, rtol=1e-12, atol=1e-15)
        assert [q.shape[2] for q in b.paths] == [3, 3, 3]
    assert calls == [(k, 18) for k in range(1, 19)]  # 3 sections x 3 batches x 2 loops


def test_the_open_loop_strays_further_the_larger_the_parameter_error(study):
    medians = [np.median(_run(study, Perturbation(param_error=e, trials=4)).open_loop.deviation)
               for e in (0.002, 0.01, 0.05)]
    assert medians[0] < medians[1] < medians[2]


def test_the_report_is_json_with_its_schema(study):
    report = _run(study, Perturbation(param_error=0.01, trials=2), steps=200)
    data = json.loads(json.dumps(report.to_dict(), allow_nan=False))
    assert data["schema"] == SCHEMA == "skatetrace.robustness/1"
    assert {"success", "status", "message", "figure_size", "perturbation", "law", "steps", "sections", "replayed",
            "failed_laws", "open_loop", "closed_loop"} <= set(data)
    assert data["perturbation"] == Perturbation(param_error=0.01, trials=2).to_dict()
    assert data["law"]["name"] == "lqr" and data["steps"] == 200
    for loop in ("open_loop", "closed_loop"):
        assert set(data[loop]) == {"trials", "diverged", "max_deviation", "cusp_speed", "mass_reach", "seconds"}
        assert set(data[loop]["max_deviation"]) == set(data[loop]["cusp_speed"]) == set(data[loop]["mass_reach"]) \
            == {"p50", "p95", "max"}
        assert data[loop]["trials"] == 2


def test_any_law_with_rates_can_be_studied_and_a_failed_one_is_data(study):
    traced, laws, _ = study

    class Schedule:
        """The schedule's own rates: a 'closed loop' that is the open loop."""

        def __init__(self, ref):
            self.ref = ref

        def rates(self, t, z, measured_at=None):
            _, u = self.ref.state_at(np.full(z.shape[1], t))
            return u[0], u[1]

    p = Perturbation(param_error=0.02, trials=2)
    same = _run(study, p, steps=200, laws=[Schedule(r) for r in traced.references])
    np.testing.assert_array_equal(same.closed_loop.deviation, same.open_loop.deviation)
    assert same.success and same.law == {"name": "Schedule"}
    failed = design(traced.references[1], traced.params, default_gains(traced.size), max_nfev=1)
    report = _run(study, p, steps=200, laws=[laws[0], failed, laws[2]])
    assert not report.success and report.status is RobustnessStatus.LAW_FAILED
    assert report.failed_laws[0][0] == 1 and "section 1" in report.message and "Riccati" in report.message
    assert report.to_dict()["failed_laws"] == [{"section": 1, "message": failed.message}]


def test_nothing_traced_is_reported_not_replayed(study):
    traced = study[0]
    report = robustness([None], traced.sections[:1], traced.params, [None], size=traced.size)
    assert not report.success and report.status is RobustnessStatus.NOTHING_TRACED and report.replayed == 0


def test_arguments_that_do_not_fit_are_refused(study):
    traced, laws, _ = study
    with pytest.raises(ValueError, match="one entry per section"):
        robustness(traced.references, traced.sections, traced.params, laws[:2], size=traced.size)
    with pytest.raises(ValueError, match="needs a law"):
        robustness(traced.references, traced.sections, traced.params, [None] * 3, size=traced.size)
    with pytest.raises(ValueError, match="`steps`"):
        robustness(traced.references, traced.sections, traced.params, laws, size=traced.size, steps=0)
    with pytest.raises(ValueError, match="delay of 1e-09 needs"):
        robustness(traced.references, traced.sections, traced.params, laws, Perturbation(delay=1e-9),
                   size=traced.size)


# --- result folders ----------------------------------------------------------------------------------

def test_a_folder_reads_back_as_sections_and_references(folder, tmp_path):
    traced = load_traced(folder / "result.json")
    result = json.loads((folder / "result.json").read_text())
    assert traced.unit == "model" and traced.name == "s-bend" and traced.traced == 3
    for ref, sec in zip(traced.references, result["sections"]):
        assert ref.grid[0] == 0.0 and ref.duration == pytest.approx(sec["metrics"]["duration"], rel=1e-12)
        first = sec["pieces"][0]["initial_state"]
        assert np.allclose(ref.z[3:5, 0], [first["x"], first["y"]], atol=1e-12)
    # two curves whose pieces are both numbered 0: the rows are still told apart
    path = tmp_path / "two.json"
    path.write_text(json.dumps(TWO_CURVES))
    assert main(["trace", str(path), "--out", str(tmp_path / "two"), "--no-plots", "--no-viewer"]) == 0
    two = load_traced(tmp_path / "two")
    assert two.traced == 2
    starts = [s.pieces[0].start for s in two.sections]
    for ref, start in zip(two.references, starts):
        assert np.hypot(ref.z[3, 0] - start.x, ref.z[4, 0] - start.y) < 1e-12
    # controls.csv names each row's curve and section (piece restarts at 0 on every curve)
    cols = read_controls(tmp_path / "two" / "controls.csv")
    assert set(cols["piece"].tolist()) == {0}
    assert cols["curve"].tolist() == cols["section"].tolist() and set(cols["curve"].tolist()) == {0, 1}
    assert np.all(np.diff(cols["section"]) >= 0) and np.all(np.diff(cols["t"]) >= 0)
    assert json.loads((tmp_path / "two" / "result.json").read_text())["controls_schema"] == "skatetrace.controls/2"
    # a folder written before the columns were added still reads, to the same references
    lines = (tmp_path / "two" / "controls.csv").read_text().splitlines()
    old = tmp_path / "old"
    old.mkdir()
    (old / "result.json").write_text((tmp_path / "two" / "result.json").read_text())
    (old / "controls.csv").write_text("\n".join(",".join(line.split(",")[:13]) for line in lines) + "\n")
    legacy = load_traced(old)
    for a, b in zip(legacy.references, two.references):
        assert np.array_equal(a.z, b.z) and np.array_equal(a.grid, b.grid)
    # a section column that contradicts the times is refused
    body = [line.split(",") for line in lines]
    body[1][-1] = "1"
    (old / "controls.csv").write_text("\n".join(",".join(r) for r in body) + "\n")
    with pytest.raises(SkatetraceError, match="its section column"):
        load_traced(old)


def test_missing_or_broken_folders_are_clear_errors(folder, tmp_path):
    with pytest.raises(SkatetraceError, match="result.json not found"):
        load_traced(tmp_path)
    (tmp_path / "result.json").write_text((folder / "result.json").read_text())
    lines = (folder / "controls.csv").read_text().splitlines()
    (tmp_path / "controls.csv").write_text("\n".join(lines[:len(lines) // 2]) + "\n")
    with pytest.raises(SkatetraceError, match=r"controls.csv does not match result.json"):
        load_traced(tmp_path)
    (tmp_path / "result.json").write_text("[1, 2]")
    with pytest.raises(SkatetraceError, match=r"cannot read the results in .*result.json"):
        load_traced(tmp_path)


# --- the command ---------------------------------------------------------------------------------------

@pytest.mark.parametrize("parse, text, expected", [
    (lambda t: fraction(t, "--param-error"), "5%", 0.05), (lambda t: fraction(t, "--param-error"), "0.05", 0.05),
    (lambda t: angle(t, "--initial-error"), "0.5deg", math.radians(0.5)),
    (lambda t: angle(t, "--initial-error"), "0.01rad", 0.01), (lambda t: angle(t, "--initial-error"), "0", 0.0),
    (lambda t: duration(t, "m", "--delay"), "10ms", 0.01), (lambda t: duration(t, "m", "--delay"), "0.01s", 0.01),
    (lambda t: duration(t, "model", "--delay"), "0.01", 0.01),
    (lambda t: length_or_zero(t, "m", "--noise"), "1mm", 1e-3), (lambda t: length_or_zero(t, "m", "--noise"), "0", 0.0),
    (lambda t: length_or_zero(t, "model", "--noise"), "0mm", 0.0),
])
def test_values_with_units(parse, text, expected):
    assert parse(text) == pytest.approx(expected)


def test_the_command_prints_writes_and_draws(folder, capsys):
    assert main(["robustness", str(folder), "--trials", "3", "--steps", "200", "--param-error", "2%",
                 "--initial-error", "1e-3,0.2deg", "--delay", "0.005", "--noise", "1e-5"]) == 0
    out = capsys.readouterr().out
    assert "open loop" in out and "closed loop" in out and "p95/size" in out and "mass reach" in out
    assert "the trace studied: verified · not humanly feasible" in out  # both verdicts of what is studied
    data = json.loads((folder / "robustness.json").read_text())
    assert data["schema"] == "skatetrace.robustness/1" and data["unit"] == "model" and data["figure"] == "s-bend"
    assert data["perturbation"]["param_error"] == 0.02 and data["perturbation"]["delay"] == 0.005
    assert data["perturbation"]["angle_error"] == pytest.approx(math.radians(0.2))
    assert data["open_loop"]["trials"] == data["closed_loop"]["trials"] == 3
    assert (folder / "robustness.png").stat().st_size > 10_000
    manifest = json.loads((folder / ".skatetrace-manifest.json").read_text())
    assert {"robustness.json", "robustness.png", "feedback.json"} <= set(manifest["files"])
    # the law tested is the law exported: read back, it is the study's own law
    traced = load_traced(folder)
    laws = load_feedback(traced)
    tested, _ = lqr_laws(traced.references, traced.params, traced.size)
    for got, want in zip(laws, tested):
        assert np.array_equal(got.t, want.t) and np.array_equal(got.K, want.K)


def test_the_robustness_figure_draws_both_families(study):
    from skatetrace.outputs.plotting import robustness_figure

    traced = study[0]
    report = _run(study, Perturbation(param_error=0.01, trials=2), steps=100)
    fig = robustness_figure(report, traced.sections, name="s-bend")
    ax = fig.axes[0]
    labels = [t.get_text() for t in fig.legends[0].get_texts()]
    assert any(s.startswith("open loop: 2 of 2 trials") for s in labels)
    assert any(s.startswith("closed loop: 2 of 2 trials") for s in labels)
    assert ax.get_xlabel() == "x (model length)"
    # the target's pieces, then per family one line per trial and traced section, and the rests
    assert len(ax.lines) == 3 + 2 * 3 * 2 + 1


@pytest.mark.parametrize("args, match", [
    (["--param-error", "100%"], "below 100 %"), (["--param-error", "nan"], "finite number >= 0"),
    (["--param-error=-5%"], "finite number >= 0"), (["--initial-error", "1mm"], "LENGTH,ANGLE"),
    (["--initial-error", "1e-3,0.5"], "needs a unit"), (["--initial-error", "1mm,0.5deg"], "physical length"),
    (["--delay", "10ms"], "physical time"), (["--noise", "inf"], "--noise"), (["--trials", "0"], "`trials`"),
    (["--steps", "0"], "--steps"),
])
def test_bad_values_exit_2(folder, capsys, args, match):
    assert main(["robustness", str(folder), *args]) == 2
    assert match in capsys.readouterr().err


def test_a_missing_folder_exits_2(tmp_path, capsys):
    assert main(["robustness", str(tmp_path / "nowhere")]) == 2
    err = capsys.readouterr().err
    assert "result.json not found" in err and "nowhere" in err


def test_under_five_percent_parameter_error_the_law_holds_the_s_bend(study):
    """The robust law (rate weight 3000, momenta seen through the model) against the schedule: no trial
    diverges, and the blade stays several times closer to the figure (measured: p95 0.013 against 0.090)."""
    rep = _run(study, Perturbation(param_error=0.05, trials=12, seed=3), steps=300)
    assert rep.closed_loop.diverged == 0
    # the open loop moves the mass exactly as the schedule does: its reach is the trace's own
    traced = study[0]
    planned = max(float(np.max(np.hypot(r.z[5], r.z[6]))) for r in traced.references)
    assert np.all(np.abs(rep.open_loop.mass_reach - planned) <= 1e-6 * planned)
    assert rep.to_dict()["closed_loop"]["mass_reach"]["max"] == pytest.approx(np.max(rep.closed_loop.mass_reach))
    open_p95 = quantiles(rep.open_loop.deviation)["p95"]
    closed_p95 = quantiles(rep.closed_loop.deviation)["p95"]
    assert closed_p95 < open_p95 / 3


@pytest.mark.slow
def test_the_planned_circle_eight_survives_five_percent_parameter_error(tmp_path):
    """The issue's scenario on the circle eight planned within 0.5 m: +-5 % on M, m, I, 1 mm / 0.5 deg, 10 ms.
    Measured (32 trials): closed loop p95 0.166 m, none diverged; open loop p95 1.22 m. The stiff law of the
    verification (rate weight 100), seeing the true momenta, diverged in 21 of 32 on an earlier plan. How
    far the open loop strays depends on the plan (p50 of 8 trials 1.31 m on one plan, 0.60 m on the next,
    the closed loop 0.065 and 0.067 m), so the closed loop's worst trial is compared with the open loop's
    worst, its median with the median."""
    out = tmp_path / "ce"
    assert main(["trace", "school:circle-eight", "--reach", "0.5m", "--out", str(out), "--no-plots",
                 "--no-viewer"]) == 0
    assert main(["robustness", str(out), "--trials", "8", "--steps", "2000", "--no-plots"]) == 0
    data = json.loads((out / "robustness.json").read_text())
    closed, opened = data["closed_loop"], data["open_loop"]
    assert closed["diverged"] == 0
    assert closed["max_deviation"]["max"] < opened["max_deviation"]["max"] / 5
    assert closed["max_deviation"]["p50"] < opened["max_deviation"]["p50"] / 5
    assert closed["max_deviation"]["max"] < 0.05 * data["figure_size"]
    # and the skater's reach stays near the plan's 0.5 m (measured 0.553 m at most; 0.516 on the plan before)
    assert closed["mass_reach"]["max"] <= 0.6
