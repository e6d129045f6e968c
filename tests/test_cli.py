import csv
import json
import re
import subprocess
import sys

import numpy as np
import pytest
from scipy.interpolate import CubicHermiteSpline

from skatetrace.cli import main
from skatetrace.outputs.results import read_controls


def test_figures_lists_builtins(capsys):
    assert main(["figures"]) == 0
    assert "double-flower" in capsys.readouterr().out


def test_trace_user_figure_writes_everything(tmp_path, capsys):
    fig = {"schema": "skatetrace.figure/1", "name": "two", "params": {"M": 2, "m": 1, "I": 3},
           "curves": [{"pieces": [{"type": "arc", "radius": 1.0, "sweep_deg": 120},
                                  {"type": "line", "length": 1.5}],
                       "joins": [{"type": "cusp", "pivot_deg": -60}]}]}
    path = tmp_path / "two.json"
    path.write_text(json.dumps(fig))
    out = tmp_path / "out"
    assert main(["trace", str(path), "--out", str(out)]) == 0
    result = json.loads((out / "result.json").read_text())
    report = json.loads((out / "report.json").read_text())
    assert result["schema"] == "skatetrace.result/1" and result["success"]
    assert report["success"] and report["max_deviation"] < 1e-8
    assert {"figure.png", "controls.png", "speed.png", "mass_path.png", "energies.png"} <= {p.name for p in out.iterdir()}
    rows = list(csv.DictReader((out / "controls.csv").open()))
    assert list(rows[0]) == "piece,t,a,b,adot,bdot,x,y,theta,p1,p2,xi1,xi2,curve,section".split(",")
    t = np.array([float(r["t"]) for r in rows])
    assert np.all(np.diff(t) >= 0) and t[-1] > 0
    # Hermite interpolation of the samples reproduces the controls between samples
    a = np.array([float(r["a"]) for r in rows])
    ad = np.array([float(r["adot"]) for r in rows])
    sl = slice(0, 200)
    keep = np.diff(t[sl], prepend=-1) > 0
    s = CubicHermiteSpline(t[sl][keep], a[sl][keep], ad[sl][keep])
    assert abs(s(0.5 * (t[10] + t[11])) - 0.5 * (a[10] + a[11])) < 1e-3  # sanity: smooth between rows
    assert "max deviation" in capsys.readouterr().out


def test_bad_inputs_exit_2(tmp_path, capsys):
    bad = tmp_path / "bad.json"
    bad.write_text("{not json")
    assert main(["trace", str(bad), "--out", str(tmp_path / "o")]) == 2
    assert "not valid JSON" in capsys.readouterr().err
    assert main(["trace", "no-such-figure", "--out", str(tmp_path / "o")]) == 2
    assert main(["trace", "circle", "--M", "-1", "--out", str(tmp_path / "o")]) == 2
    assert "must be a positive" in capsys.readouterr().err
    assert main(["nonsense"]) == 2


def test_failed_verification_exits_1_and_still_writes_everything(tmp_path, capsys):
    """A tolerance no integrator can meet fails verification: exit 1, but nothing is lost."""
    out = tmp_path / "out"
    assert main(["trace", "circle", "--out", str(out), "--verify-tol", "1e-16", "--no-plots"]) == 1
    report = json.loads((out / "report.json").read_text())
    assert not report["success"] and "exceeds" in report["message"]
    assert (out / "controls.csv").exists() and (out / "result.json").exists()
    assert "verification: failed" in capsys.readouterr().out


def test_result_json_round_trips_the_figure(tmp_path):
    from skatetrace import pattern
    from skatetrace.outputs.results import load_result

    out = tmp_path / "out"
    assert main(["trace", "s-bend", "--out", str(out), "--no-plots"]) == 0
    data = load_result(out / "result.json")
    original = pattern("s-bend")
    assert [c.pieces for c in data["figure"].curves] == [c.pieces for c in original.curves]
    sec = data["sections"][0]
    assert len(sec["pieces"]) == 3
    # the second piece starts where the first ends, at the state the solver reports there
    first, second = sec["pieces"][0], sec["pieces"][1]
    assert second["start_time"] > first["start_time"]
    assert second["initial_state"]["xi2"] > 0
    assert abs(second["initial_state"]["xi1"] - second["curvature"] * second["initial_state"]["xi2"]) < 1e-8


def test_console_script_runs():
    proc = subprocess.run([sys.executable, "-m", "skatetrace.cli", "figures"], capture_output=True, text=True)
    assert proc.returncode == 0 and "circle" in proc.stdout


def test_example_figure_traces_end_to_end(tmp_path):
    from pathlib import Path

    example = Path(__file__).resolve().parents[1] / "examples" / "flower-with-stems.json"
    out = tmp_path / "out"
    assert main(["trace", str(example), "--out", str(out), "--no-plots"]) == 0
    result = json.loads((out / "result.json").read_text())
    assert result["curves"][0]["closure"]["closed"]
    assert len(result["sections"]) == 8 and all(s["success"] for s in result["sections"])


def test_rests_at_every_join_keep_the_path_and_are_reported(tmp_path, capsys):
    import json

    out = tmp_path / "o"
    assert main(["trace", "s-bend", "--rests", "joins", "--out", str(out), "--no-plots"]) == 0
    text = capsys.readouterr().out
    assert "note: rests added at smooth joins (before piece 1, before piece 2)" in text
    curve = json.loads((out / "result.json").read_text())["figure"]["curves"][0]
    assert curve["joins"] == [{"type": "cusp", "pivot_deg": 0.0}] * 2
    assert main(["trace", "s-bend", "--rests", "sometimes", "--out", str(out)]) == 2


def test_animate_writes_gif_mp4_and_still_from_the_result_files(tmp_path, capsys):
    import imageio_ffmpeg
    from PIL import Image

    out = tmp_path / "run"
    assert main(["trace", "s-bend", "--out", str(out), "--no-plots"]) == 0
    capsys.readouterr()
    gif, mp4, png = tmp_path / "a.gif", tmp_path / "a.mp4", tmp_path / "a.png"
    assert main(["animate", str(out / "result.json"), "-o", str(gif), "--fps", "5", "--duration", "2",
                 "--size", "160x120"]) == 0
    captured = capsys.readouterr()
    assert "10 frames, 160x120 px" in captured.out and "10/10" in captured.err  # the progress bar
    with Image.open(gif) as im:
        assert im.n_frames == 10 and im.size == (160, 120)
    assert main(["animate", str(out), "-o", str(mp4), "--fps", "5", "--duration", "2", "--size", "160x120"]) == 0
    frames, _ = imageio_ffmpeg.count_frames_and_secs(str(mp4))
    meta = next(imageio_ffmpeg.read_frames(str(mp4)))
    assert frames == 10 and tuple(meta["size"]) == (160, 120)
    assert main(["animate", str(out), "-o", str(png), "--time", "1.0", "--size", "160x120"]) == 0
    with Image.open(png) as im:
        assert im.size == (160, 120)
    capsys.readouterr()
    assert main(["animate", str(out), "-o", str(tmp_path / "a.avi")]) == 2
    assert "must end in .gif, .mp4 or .png (got '.avi')" in capsys.readouterr().err
    assert main(["animate", str(tmp_path / "nothing"), "-o", str(gif)]) == 2
    assert main(["animate", str(out), "-o", str(gif), "--size", "wide"]) == 2


def test_trace_writes_the_viewer_and_view_rewrites_it(tmp_path, capsys):
    out = tmp_path / "run"
    assert main(["trace", "s-bend", "--out", str(out), "--no-plots"]) == 0
    page = (out / "viewer.html").read_text(encoding="utf-8")
    assert "s-bend" in page and "https://" not in page and 'type="application/json"' in page
    assert main(["view", str(out), "-o", str(tmp_path / "v.html")]) == 0
    assert "self-contained" in capsys.readouterr().out
    assert (tmp_path / "v.html").read_text(encoding="utf-8") == page  # the same files, the same page
    skip = tmp_path / "skip"
    assert main(["trace", "s-bend", "--out", str(skip), "--no-plots", "--no-viewer"]) == 0
    assert not (skip / "viewer.html").exists()
    assert main(["view", str(tmp_path / "nothing")]) == 2


@pytest.mark.slow
def test_double_flower_gif_and_mp4_at_the_defaults(tmp_path, capsys):
    # issue 5's acceptance: both videos of the double flower from the CLI, full length and size
    import imageio_ffmpeg
    from PIL import Image

    out = tmp_path / "flower"
    assert main(["trace", "double-flower", "--out", str(out), "--no-plots", "--no-viewer"]) == 0
    gif, mp4 = tmp_path / "flower.gif", tmp_path / "flower.mp4"
    assert main(["animate", str(out / "result.json"), "-o", str(gif)]) == 0
    assert main(["animate", str(out), "-o", str(mp4)]) == 0
    with Image.open(gif) as im:
        assert (im.n_frames, im.size) == (750, (800, 800))  # 30 s at 25 fps: the figure lasts 109 units
    frames, seconds = imageio_ffmpeg.count_frames_and_secs(str(mp4))
    assert frames == 750 and abs(seconds - 30.0) < 0.1
    assert tuple(next(imageio_ffmpeg.read_frames(str(mp4)))["size"]) == (800, 800)



# ---------------------------------------------------------------------------------------------------------
# Command-line and file conventions (issue 13): --version, output folders, file modes, strict JSON, --time

import os
import stat
from pathlib import Path


import skatetrace
from skatetrace.cli import commands as cli
from skatetrace.outputs.folder import MANIFEST

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
PLOTS = {"figure.png", "controls.png", "speed.png", "mass_path.png", "energies.png"}


def strict_loads(text):
    """json.loads that rejects NaN, Infinity and -Infinity, as JSON parsers outside Python do."""
    def reject(name):
        raise ValueError(f"not strict JSON: {name}")
    return json.loads(text, parse_constant=reject)


def test_version_in_process_and_as_python_m(capsys):
    assert main(["--version"]) == 0
    out = capsys.readouterr().out.strip()
    assert out.startswith("skatetrace ") and out.split()[1][0].isdigit()
    proc = subprocess.run([sys.executable, "-m", "skatetrace", "--version"], capture_output=True, text=True)
    assert proc.returncode == 0 and proc.stdout.strip() == out
    proc = subprocess.run([sys.executable, "-m", "skatetrace", "figures"], capture_output=True, text=True)
    assert proc.returncode == 0 and "double-flower" in proc.stdout
    proc = subprocess.run([sys.executable, "-m", "skatetrace", "trace"], capture_output=True, text=True)
    assert proc.returncode == 2 and "Traceback" not in proc.stderr


def test_the_script_runs_main_then_keeps_the_collector_off_the_exit(monkeypatch, capsys):
    import gc
    import importlib.metadata as md

    from skatetrace.cli import entry

    frozen = []
    monkeypatch.setattr(gc, "freeze", lambda: frozen.append(True))  # this test process must not freeze
    assert entry.script(["--version"]) == 0 and frozen == [True]
    assert capsys.readouterr().out.startswith("skatetrace ")
    assert entry.script(["trace"]) == 2 and frozen == [True, True]  # a usage error too

    def failing(argv):
        raise RuntimeError("a bug")

    monkeypatch.setattr(entry, "main", failing)
    with pytest.raises(RuntimeError, match="a bug"):  # the traceback is Python's, as from main
        entry.script([])
    assert len(frozen) == 3
    scripts = [ep for ep in md.entry_points(group="console_scripts") if ep.name == "skatetrace"]
    if scripts:  # installed: the script is this entry, not main
        assert scripts[0].value == "skatetrace.cli:script"


def test_the_process_ends_soon_after_its_last_line(tmp_path):
    # The exit's collections took 0.4 s after a trace (numba's and CasADi's objects); the script
    # skips them. Time is not asserted (machines differ): the collector's state at exit is.
    code = ("import atexit, gc, sys; from skatetrace.cli import script; "
            "atexit.register(lambda: print('frozen', gc.get_freeze_count() > 0)); "
            "sys.exit(script(['trace', 'line', '--out', sys.argv[1], '--no-plots', '--no-viewer']))")
    proc = subprocess.run([sys.executable, "-c", code, str(tmp_path / "o")], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.rstrip().endswith("frozen True")


def test_version_falls_back_to_the_packages_own(monkeypatch):
    import importlib.metadata as md

    def missing(name):
        raise md.PackageNotFoundError(name)

    monkeypatch.setattr(md, "version", missing)
    assert cli._version() == skatetrace.__version__


def _no_work(monkeypatch):
    """Make any tracing or fitting fail the test: the checks must come first."""
    def forbidden(*args, **kwargs):
        raise AssertionError("work started before the output folder was checked")

    monkeypatch.setattr(cli, "_resolve", forbidden)


@pytest.mark.parametrize("command", [["trace", "circle"], ["fit", str(EXAMPLES / "points-eight.csv")],
                                     ["reproduce", "--arcs", "1"]])
@pytest.mark.parametrize("where, match", [
    (lambda d: d / "taken", "taken is a file, not a folder"),
    (lambda d: d / "taken" / "sub", "cannot create folder .*sub: .*taken is a file"),
])
def test_out_that_cannot_be_a_folder_exits_2_before_any_work(tmp_path, capsys, monkeypatch, command, where, match):
    import re

    _no_work(monkeypatch)
    monkeypatch.setattr("skatetrace.paper.report.reproduce", lambda *a, **k: pytest.fail("work started"),
                        raising=False)
    (tmp_path / "taken").write_text("precious")
    assert main([*command, "--out", str(where(tmp_path))]) == 2
    err = capsys.readouterr().err
    assert err.startswith("skatetrace: error: --out: ") and re.search(match, err) and "Traceback" not in err
    assert (tmp_path / "taken").read_text() == "precious"  # nothing lost
    assert sorted(p.name for p in tmp_path.iterdir()) == ["taken"]


@pytest.mark.parametrize("argv, match", [
    (["trace", "circle", "--out", ""], "--out: '' names no folder"),
    (["trace", "circle", "--out", "  "], "--out: '  ' names no folder"),
    (["fit", str(EXAMPLES / "points-eight.csv"), "--out", ""], "--out: '' names no folder"),
    (["animate", "results", "-o", ""], "-o: '' names no file"),
    (["view", "results", "-o", ""], "-o: '' names no file"),
])
def test_an_empty_output_name_is_refused_not_read_as_the_current_folder(tmp_path, capsys, monkeypatch, argv, match):
    """Issue 19: ``--out ""`` wrote every file into the current folder."""
    _no_work(monkeypatch)
    monkeypatch.chdir(tmp_path)
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith("skatetrace: error: ") and match in err and "Traceback" not in err
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("command, name", [(["trace", "circle"], "result.json"), (["trace", "circle"], "speed.png"),
                                           (["fit", str(EXAMPLES / "points-eight.csv")], "fit.png")])
def test_a_folder_in_place_of_an_output_file_exits_2_before_any_work(tmp_path, capsys, monkeypatch, command, name):
    """Issue 19: a folder holding a directory called result.json failed with a raw 'Is a directory' after the work."""
    _no_work(monkeypatch)
    (tmp_path / "out" / name).mkdir(parents=True)
    assert main([*command, "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert f"{name} is a folder, and '{command[0]}' writes a file of that name there" in err, err
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == [name]


def test_an_output_name_too_long_for_the_file_system_exits_2_before_any_work(tmp_path, capsys, monkeypatch):
    _no_work(monkeypatch)
    assert main(["trace", "circle", "--out", str(tmp_path / ("x" * 300))]) == 2
    err = capsys.readouterr().err
    assert err.startswith("skatetrace: error: --out: cannot use ")
    assert "characters) as a folder" in err and "give a shorter name" in err and len(err) < 300


def test_out_without_write_permission_exits_2_before_any_work(tmp_path, capsys, monkeypatch):
    import tempfile

    _no_work(monkeypatch)

    def denied(*args, **kwargs):
        raise PermissionError(13, "Permission denied")

    monkeypatch.setattr(tempfile, "mkstemp", denied)
    assert main(["trace", "circle", "--out", str(tmp_path / "new")]) == 2
    assert "cannot write in folder" in capsys.readouterr().err
    assert not (tmp_path / "new").exists()  # the folder the check made is gone again


def test_a_folder_made_for_a_run_that_fails_is_removed(tmp_path, capsys):
    assert main(["trace", "no-such-figure", "--out", str(tmp_path / "a" / "b")]) == 2
    assert not (tmp_path / "a").exists()


def test_a_write_that_fails_is_an_error_not_a_traceback(tmp_path, capsys, monkeypatch):
    import skatetrace.outputs.results

    def full(*args, **kwargs):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(skatetrace.outputs.results, "write_results", full)
    assert main(["trace", "circle", "--out", str(tmp_path / "o"), "--no-plots", "--no-viewer"]) == 2
    assert "skatetrace: error: [Errno 28] No space left on device" in capsys.readouterr().err


def test_reused_folder_holds_one_runs_files_and_keeps_the_users(tmp_path, capsys):
    out = tmp_path / "o"
    assert main(["trace", "circle", "--out", str(out)]) == 0
    assert PLOTS <= {p.name for p in out.iterdir()}
    (out / "notes.txt").write_text("my notes")
    capsys.readouterr()
    assert main(["trace", "line", "--out", str(out), "--no-plots"]) == 0
    text = capsys.readouterr().out
    names = {p.name for p in out.iterdir()}
    assert names == {"result.json", "controls.csv", "report.json", "viewer.html", "notes.txt", MANIFEST}
    assert f"note: removed 5 file(s) an earlier run wrote to {out}/" in text
    assert all(p in text for p in PLOTS)
    assert (out / "notes.txt").read_text() == "my notes"
    assert json.loads((out / "result.json").read_text())["figure"]["name"] == "line"
    page = (out / "viewer.html").read_text(encoding="utf-8")
    assert "<title>line " in page and "<title>circle" not in page
    # --no-viewer: the old viewer would play another run, so it goes too
    assert main(["trace", "line", "--out", str(out), "--no-plots", "--no-viewer"]) == 0
    assert not (out / "viewer.html").exists() and (out / "notes.txt").exists()


def test_view_into_a_run_folder_belongs_to_that_run(tmp_path, capsys):
    out = tmp_path / "o"
    assert main(["trace", "line", "--out", str(out), "--no-plots", "--no-viewer"]) == 0
    assert main(["view", str(out)]) == 0
    assert "viewer.html" in strict_loads((out / MANIFEST).read_text())["files"]
    assert main(["trace", "circle", "--out", str(out), "--no-plots", "--no-viewer"]) == 0
    assert not (out / "viewer.html").exists()
    assert main(["view", str(out), "-o", str(tmp_path / "v.txt")]) == 2
    assert "must end in .html or .htm" in capsys.readouterr().err


def test_fit_into_a_trace_folder_leaves_no_trace_files(tmp_path, capsys):
    out = tmp_path / "o"
    assert main(["trace", "line", "--out", str(out), "--no-plots"]) == 0
    assert main(["fit", str(EXAMPLES / "points-eight.csv"), "--out", str(out), "--no-plots"]) == 0
    assert {p.name for p in out.iterdir()} == {"fit.json", MANIFEST}


@pytest.mark.parametrize("umask, mode", [(0o022, 0o644), (0o077, 0o600)])
def test_every_file_gets_the_umasks_permissions(tmp_path, umask, mode):
    out = tmp_path / "o"
    old = os.umask(umask)
    try:
        assert main(["trace", "s-bend", "--out", str(out)]) == 0
    finally:
        os.umask(old)
    files = [p for p in out.rglob("*") if p.is_file()]
    assert len(files) >= 9
    assert {p.name: oct(stat.S_IMODE(p.stat().st_mode)) for p in files} == {p.name: oct(mode) for p in files}


def _viewer_data(page: str) -> str:
    start = page.index('type="application/json"')
    return page[page.index(">", start) + 1:page.index("</script>", start)]


def test_every_json_file_is_strict(tmp_path, capsys):
    out = tmp_path / "o"
    assert main(["trace", "s-bend", "--out", str(out)]) == 0
    for name in ("result.json", "report.json", MANIFEST):
        strict_loads((out / name).read_text())
    strict_loads(_viewer_data((out / "viewer.html").read_text(encoding="utf-8")))
    fit = tmp_path / "fit"
    assert main(["fit", str(EXAMPLES / "points-eight.csv"), "--out", str(fit), "--no-plots"]) == 0
    strict_loads((fit / "fit.json").read_text())


def test_fit_json_writes_nan_as_null(tmp_path, capsys, monkeypatch):
    summary = cli._fit_summary

    def with_nan(res):
        data = summary(res)
        data["hausdorff_sampled"] = float("nan")
        data["paths"][0]["curve_length"] = float("inf")
        return data

    monkeypatch.setattr(cli, "_fit_summary", with_nan)
    out = tmp_path / "fit"
    assert main(["fit", str(EXAMPLES / "points-eight.csv"), "--out", str(out), "--no-plots"]) == 0
    data = strict_loads((out / "fit.json").read_text())
    assert data["hausdorff_sampled"] is None and data["paths"][0]["curve_length"] is None


def test_animate_refuses_a_time_outside_the_figure_and_lists_suffixes(tmp_path, capsys):
    out = tmp_path / "run"
    assert main(["trace", "s-bend", "--out", str(out), "--no-plots", "--no-viewer"]) == 0
    duration = json.loads((out / "result.json").read_text())["duration"]
    capsys.readouterr()
    png = tmp_path / "still.png"
    for t in ("9999", "-1", str(duration * 1.01)):
        assert main(["animate", str(out), "-o", str(png), "--time", t, "--size", "64x64"]) == 2
        err = capsys.readouterr().err
        assert f"is outside the figure's time: give a time from 0 to {duration:.6g}" in err
    assert not png.exists()
    assert main(["animate", str(out), "-o", str(png), "--time", str(duration), "--size", "64x64"]) == 0
    assert f"at t = {duration:.6g}" in capsys.readouterr().out
    assert main(["animate", str(out), "-o", str(tmp_path / "a.gif"), "--time", "1"]) == 2
    assert "use it with -o NAME.png" in capsys.readouterr().err
    assert main(["animate", str(out), "-o", str(tmp_path / "x.avi")]) == 2
    err = capsys.readouterr().err
    assert all(s in err for s in (".gif", ".mp4", ".png")) and "'.avi'" in err
    assert main(["animate", str(out), "-o", str(tmp_path / "run")]) == 2  # a folder, not a file name
    assert main(["animate", str(out), "-o", str(tmp_path / "no" / "a.gif")]) == 2
    assert "does not exist" in capsys.readouterr().err


def test_first_run_says_it_compiles_once(tmp_path, capsys, monkeypatch):
    """One line the first time numba compiles a part, then a line per part as it starts and ends;
    nothing where everything loads from the cache (the parts compile for real in test_compiled.py)."""
    from contextlib import contextmanager

    import skatetrace.cli.compiled as compiled

    calls = []

    @contextmanager
    def reporting(progress):
        calls.append(1)
        progress("a", None)
        progress("a", 6.2)
        progress("b", None)
        progress("b", 4.0)
        yield

    monkeypatch.setattr(compiled, "reporting", reporting)
    assert main(["trace", "line", "--out", str(tmp_path / "o"), "--no-plots", "--no-viewer"]) == 0
    err = capsys.readouterr().err
    assert err.count("first run on this machine: compiling the numerical core") == 1
    assert "  compiling a\n  compiled a in 6 s\n  compiling b\n  compiled b in 4 s\n" in err
    assert calls == [1]

    @contextmanager
    def warm(progress):
        yield

    monkeypatch.setattr(compiled, "reporting", warm)
    assert main(["trace", "line", "--out", str(tmp_path / "o"), "--no-plots", "--no-viewer"]) == 0
    assert "compil" not in capsys.readouterr().err
    assert main(["figures"]) == 0  # a command that compiles nothing does not listen at all
    assert calls == [1]


def _arc_file(tmp_path):
    path = tmp_path / "arc.json"
    path.write_text(json.dumps({"schema": "skatetrace.figure/1", "params": {"M": 2, "m": 1, "I": 3},
                                "curves": [{"pieces": [{"type": "arc", "radius": 1.2, "sweep_deg": 198}]}]}))
    return path


@pytest.mark.parametrize("reach, why", [("auto", "model units"), ("0.5m", "physical length"), ("-1", "positive"),
                                        ("far", "cannot read")])
def test_trace_reach_that_cannot_apply_is_a_usage_error(tmp_path, capsys, reach, why):
    assert main(["trace", str(_arc_file(tmp_path)), "--reach", reach, "--out", str(tmp_path / "o")]) == 2
    assert why in capsys.readouterr().err


@pytest.mark.parametrize("given, unit, expected", [(None, "m", 0.288 * 1.8), (None, "model", None),
                                                   ("none", "m", None), ("auto", "m", 0.288 * 1.8), ("0.4m", "m", 0.4),
                                                   ("2", "model", 2.0)])
def test_reach_defaults_to_the_skaters_in_metres_and_none_in_model_units(given, unit, expected):
    """Issue 15: a figure in metres is a skater's figure, planned within a trunk's length unless told."""
    import argparse

    from skatetrace.cli.commands import _reach

    got = _reach(argparse.Namespace(reach=given, height=1.8), unit)
    assert got == (None if expected is None else pytest.approx(expected, rel=1e-3))


def test_trace_in_metres_plans_within_the_skaters_reach_by_default(tmp_path, capsys):
    out = tmp_path / "o"
    assert main(["trace", "school:loop", "--out", str(out), "--no-plots", "--no-viewer"]) == 0
    assert "planning the mass's motion within 0.4896 m" in capsys.readouterr().out
    result = json.loads((out / "result.json").read_text())
    assert result["options"]["reach"] == pytest.approx(0.288 * 1.7)
    rows = read_controls(out / "controls.csv")
    assert np.max(np.hypot(rows["a"], rows["b"])) <= result["options"]["reach"]


def test_a_default_reach_that_cannot_plan_falls_back_to_the_unbounded_trace(tmp_path, capsys, monkeypatch):
    """Not asked for a plan, the user still gets the figure traced, and is told why it was not planned."""
    import dataclasses

    import skatetrace.pipeline as pipeline
    from skatetrace.tracing.sections import TraceStatus, trace_figure

    def no_plan(figure, params, options, progress=None):
        tr = trace_figure(figure, params, dataclasses.replace(options, reach=None))
        bad = dataclasses.replace(tr.sections[0], success=False, status=TraceStatus.INFEASIBLE, message="no plan here")
        return dataclasses.replace(tr, sections=(bad,) + tr.sections[1:])

    monkeypatch.setattr(pipeline, "plan_figure", no_plan)
    out = tmp_path / "o"
    assert main(["trace", "school:loop", "--out", str(out), "--no-plots", "--no-viewer"]) == 0
    printed = capsys.readouterr().out
    assert "within the default reach 0.4896 m (no plan here); traced with the launch-glide-stop" in printed
    assert json.loads((out / "result.json").read_text())["options"]["reach"] is None
    # asked for, the reach is kept and its failure reported
    assert main(["trace", "school:loop", "--reach", "auto", "--out", str(out), "--no-plots", "--no-viewer"]) == 1
    assert "launch-glide-stop manoeuvres instead" not in capsys.readouterr().out


def test_a_default_reach_whose_plan_fails_its_replay_falls_back_to_the_unbounded_trace(tmp_path, capsys, mocked_plans):
    # w3c-styling-css-01-b: every section planned, the replay 8.25e-6 from the figure at 6e-6
    made = mocked_plans(plan_verifies=False)
    out = tmp_path / "o"
    assert main(["trace", "school:loop", "--out", str(out), "--no-plots", "--no-viewer", "--rests", "never"]) == 0
    printed = capsys.readouterr().out
    assert ("the plan's replay failed the verification within the default reach 0.4896 m (deviation 8e-06 exceeds "
            "6e-06); traced with the launch-glide-stop manoeuvres instead") in printed
    assert [o.reach is None for o in made] == [False, True]
    assert json.loads((out / "result.json").read_text())["options"]["reach"] is None
    # asked for, the plan is kept with its failure
    assert main(["trace", "school:loop", "--reach", "auto", "--out", str(out), "--no-plots", "--no-viewer",
                 "--rests", "never"]) == 1
    assert "launch-glide-stop manoeuvres instead" not in capsys.readouterr().out


def test_a_drawing_too_large_to_plan_by_default_is_traced_with_the_launch_glide_stop_manoeuvres(tmp_path, capsys):
    # issue 17: 16 circles and lines, programs of 11,056 unknowns (14,512 before the collocation's end
    # states were merged with its nodes), planned in 3.5 s but drawings of this size took up to
    # minutes (vivus-hi-there: 80,779 then, 145 s); traced as they are, 0.2 s
    drawing = str(Path(__file__).parent / "data" / "svg-corpus" / "svgpathtools-zero-radius-arcs.svg")
    out = tmp_path / "o"
    assert main(["trace", drawing, "--size", "6m", "--tol", "1mm", "--out", str(out), "--no-plots",
                 "--no-viewer"]) == 0
    printed = capsys.readouterr().out
    # 11,056 unknowns here (16 pieces): the count is asserted only as far as round-off cannot move it
    assert re.search(r"this figure is not planned within the default reach 0\.4896 m \(11,\d{3} unknowns in its "
                     r"programs, more than 9,200: larger than a school figure\); traced with the launch-glide-stop",
                     printed), printed
    assert "Give --reach auto to plan it" in printed and "note: planning the mass's motion" not in printed
    assert json.loads((out / "result.json").read_text())["options"]["reach"] is None


def test_a_default_plan_that_spends_its_budget_is_given_up_for_the_launch_glide_stop_manoeuvres(tmp_path, capsys,
                                                                                                monkeypatch):
    # a plan not asked for is bounded in IPOPT's work (pipeline.DEFAULT_PLAN_BUDGET): icons of 12 to
    # 41 pieces spent 14 to 43 s planning, where the launch-glide-stop trace takes 1 to 3 s
    import skatetrace.pipeline as pipeline

    monkeypatch.setitem(pipeline.trace_within_default_reach.__kwdefaults__, "max_work", 1000)
    out = tmp_path / "o"
    assert main(["trace", "school:loop", "--out", str(out), "--no-plots", "--no-viewer"]) == 0
    printed = capsys.readouterr().out
    assert re.search(r"note: the plan was given up within the default reach 0\.4896 m \(reach 0\.4896: not planned: "
                     r"the planning budget of 1,000 \(IPOPT iterations x unknowns\) was spent after 1 program "
                     r"\([\d,]+\)\); traced with the launch-glide-stop manoeuvres instead \(as --reach none\)\. "
                     r"Give --reach auto to plan it", printed), printed
    assert json.loads((out / "result.json").read_text())["options"]["reach"] is None


def test_the_default_reach_plans_all_or_nothing_and_wholly_where_nothing_else_traces(tmp_path, capsys, monkeypatch):
    # the default reach stops planning at a section without a plan (the launch-glide-stop
    # manoeuvres trace the figure then); where they fail too, the whole plan is made and kept
    import dataclasses

    import skatetrace.pipeline as pipeline
    from skatetrace.tracing.sections import TraceStatus, trace_figure

    asked = []

    def failing_first(trace):
        bad = dataclasses.replace(trace.sections[0], success=False, status=TraceStatus.INFEASIBLE, message="no way")
        return dataclasses.replace(trace, sections=(bad,) + trace.sections[1:])

    def plan(figure, params, options, progress=None):
        asked.append(options.all_or_nothing)
        return failing_first(trace_figure(figure, params, dataclasses.replace(options, reach=None)))

    monkeypatch.setattr(pipeline, "plan_figure", plan)
    monkeypatch.setattr(pipeline, "trace_figure", lambda *a, **k: failing_first(trace_figure(*a, **k)))
    out = tmp_path / "o"
    assert main(["trace", "school:loop", "--out", str(out), "--no-plots", "--no-viewer", "--rests", "never"]) == 1
    assert asked == [True, False]
    assert json.loads((out / "result.json").read_text())["options"]["all_or_nothing"] is False  # the whole plan's
    asked.clear()
    assert main(["trace", "school:loop", "--reach", "auto", "--out", str(out), "--no-plots", "--no-viewer",
                 "--rests", "never"]) == 1
    assert asked == [False]  # asked for, the reach plans every curve as far as it goes


def test_trace_reach_plans_within_it_and_reports_the_cusps(tmp_path, capsys):
    out = tmp_path / "o"
    assert main(["trace", str(_arc_file(tmp_path)), "--reach", "1", "--out", str(out), "--no-plots",
                 "--no-viewer"]) == 0
    cap = capsys.readouterr()
    printed = cap.out
    assert "planning the mass's motion within 1 model units" in printed and "reach" in printed
    assert "planning: warm starts solved 1/1\n" in cap.err  # the planner's progress, batch by batch
    result = json.loads((out / "result.json").read_text())
    assert result["options"]["reach"] == 1.0
    rows = list(csv.DictReader((out / "controls.csv").open()))
    assert max(np.hypot(float(r["a"]), float(r["b"])) for r in rows) <= 1.0
    info = json.loads((out / "report.json").read_text())["feasibility"]["info"]
    assert {"max_cusp_impulse", "max_cusp_mass_speed", "effort"} <= set(info)


def test_trace_reach_too_small_is_answered_as_data(tmp_path, capsys):
    out = tmp_path / "o"
    assert main(["trace", str(_arc_file(tmp_path)), "--reach", "0.02", "--out", str(out), "--no-plots"]) == 1
    printed = capsys.readouterr().out
    assert "no motion of the mass within the reach" in printed and "on its own it plans within" in printed
    result = json.loads((out / "result.json").read_text())
    assert not result["success"] and (out / "report.json").exists()
    sec = result["sections"][0]
    assert sec["status"] == "INFEASIBLE" and 0.02 < sec["metrics"]["smallest_feasible_reach"] <= 0.1


def test_tradeoff_sweeps_the_reach_and_marks_what_fails(tmp_path, capsys):
    out = tmp_path / "t"
    assert main(["tradeoff", str(_arc_file(tmp_path)), "--reaches", "1.5,0.02,1", "--out", str(out)]) == 0
    data = json.loads((out / "tradeoff.json").read_text())
    assert data["schema"] == "skatetrace.tradeoff/1" and (out / "tradeoff.png").stat().st_size > 0
    reach = [p["reach"] for p in data["points"]]
    assert reach == [0.02, 1.0, 1.5]                       # swept in increasing order
    ok = [p["success"] for p in data["points"]]
    assert ok == [False, True, True] and data["smallest_reach"] == 1.0
    for p in data["points"][1:]:
        assert p["distance"] <= p["reach"]
    # a larger reach costs no more force; today's manoeuvres put the mass further out than any
    assert data["points"][2]["peak_force"] <= data["points"][1]["peak_force"]
    assert data["reference"]["reach"] is None and data["reference"]["distance"] > 1.5
    printed = capsys.readouterr().out
    assert "smallest reach planned and verified: 1 model units" in printed and "FAILED" in printed


@pytest.mark.parametrize("args, why", [(["--reaches", "0.5m"], "physical length"), (["--reaches", "0,1"], "positive"),
                                       (["--objective", "time"], "max_accel"), (["--max-accel", "-2"], "max-accel"),
                                       (["--workers", "0"], "--workers must be a whole number from 1")])
def test_tradeoff_refuses_what_cannot_be_swept(tmp_path, capsys, args, why):
    assert main(["tradeoff", str(_arc_file(tmp_path)), *args, "--out", str(tmp_path / "t")]) == 2
    assert why in capsys.readouterr().err


@pytest.mark.slow
@pytest.mark.parametrize("whom", ["group", "parent"])
def test_ctrl_c_stops_the_planner_and_its_workers_with_one_line(tmp_path, whom):
    """Issue 19: CasADi turned Ctrl-C inside IPOPT into a failed solve and the planner went on to the
    end. Now the run stops: exit 130, one line, no traceback (from the workers either), no process left.
    ``group``: a terminal's Ctrl-C reaches every process; ``parent``: only the command's own."""
    import signal
    import time

    # as from a terminal: a suite run in the background (``pytest &``) has Ctrl-C ignored, which its
    # children inherit, and a command started that way rightly carries on
    run = subprocess.Popen([sys.executable, "-m", "skatetrace", "trace", "school:paragraph-double-three",
                            "--out", str(tmp_path / "out"), "--no-plots", "--no-viewer"],
                           stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True,
                           preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    assert run.stdout.readline().startswith("note:")  # the figure is read: planning has begun
    time.sleep(2.0)
    assert run.poll() is None, "the run ended before it could be interrupted"
    if whom == "group":
        os.killpg(run.pid, signal.SIGINT)
    else:
        run.send_signal(signal.SIGINT)
    _, err = run.communicate(timeout=120)
    assert run.returncode == 130, err
    lines = [ln for ln in err.replace("\r", "\n").splitlines() if ln.strip() and not ln.startswith("CasADi")]
    assert lines[-1] == "skatetrace: interrupted" and "Traceback" not in err, err
    time.sleep(0.5)
    with pytest.raises(ProcessLookupError):
        os.killpg(run.pid, 0)  # no worker left behind


def test_progress_of_two_kinds_keeps_each_count_on_a_line_of_its_own(capsys):
    # the planner's batches report while sections are traced: neither overwrites the other's count
    from skatetrace.cli.status import StatusLine

    status = StatusLine()
    status.show("sections", "tracing sections 1/3", False)
    status.show("warm starts", "planning: warm starts solved 1/2", False)
    status.show("warm starts", "planning: warm starts solved 2/2", True)
    status.show("sections", "tracing sections 2/3", False)
    status.show("sections", "tracing sections 3/3", True)
    shown = [line.split("\r")[-1] for line in capsys.readouterr().err.split("\n")]  # what a terminal keeps
    assert shown == ["tracing sections 1/3", "planning: warm starts solved 2/2", "tracing sections 3/3", ""]


def test_a_long_fit_shows_its_pieces_and_a_short_one_nothing(capsys, monkeypatch):
    # a drawing of 20,000 lines fitted for tens of seconds in silence; one that fits within a
    # second (nearly all) prints nothing
    from skatetrace.cli import status

    clock = iter([0.0, 0.3, 0.6, 0.9] + [10.0, 10.5, 11.0, 11.5, 12.0, 12.5])
    monkeypatch.setattr(status.time, "perf_counter", lambda: next(clock))
    fit = status.long_fit(status.StatusLine())
    for done in (0, 100, 200):
        fit("fitting", done, 300)
    fit("fitting", 300, 300)  # within a second: nothing
    assert capsys.readouterr().err == ""
    for stage, done in (("splitting", 0), ("fitting", 0), ("fitting", 5000), ("merging", 0), ("fitting", 20000)):
        fit(stage, done, 20000)
    shown = [line.split("\r")[-1] for line in capsys.readouterr().err.split("\n")]
    assert shown == ["fitting: 5000/20000 pieces of the drawing", "merging: 0/20000 pieces of the drawing",
                     "fitting: 20000/20000 pieces of the drawing", ""]


def test_long_work_is_redrawn_at_most_ten_times_a_second_and_at_its_end(capsys, monkeypatch):
    # a zigzag's 2,000 sections are replayed in a few seconds: not 2,000 redraws of the line
    from skatetrace.cli import status

    times = iter(0.01 * np.arange(401))  # 4 s of reports, one every 10 ms
    monkeypatch.setattr(status.time, "perf_counter", lambda: next(times))
    work = status.LongWork(status.StatusLine(), "verifying: {stage} {done}/{total} sections")
    for done in range(400):
        work("replaying", done, 400)
    work("replaying", 400, 400)
    drawn = [part for part in capsys.readouterr().err.replace("\n", "\r").split("\r") if part]
    # the first after a second, then every 0.1 s (round-off may add or drop one), then the end
    assert 28 <= len(drawn) <= 32, drawn
    assert drawn[0] == "verifying: replaying 100/400 sections" and drawn[-1] == "verifying: replaying 400/400 sections"


@pytest.mark.parametrize("forks, workers", [(True, []), (False, []), (True, ["--workers", "1"])])
def test_trace_draws_fit_png_beside_the_tracing_as_fit_draws_it(tmp_path, monkeypatch, forks, workers):
    """trace draws fit.png in a child while the figure is traced (where it may fork, and more than
    one process is allowed): the same file as ``skatetrace fit`` draws, recorded with the run's
    other files."""
    from skatetrace import processes

    monkeypatch.setattr(processes, "can_fork", lambda: forks)
    monkeypatch.setattr(processes, "available_workers", lambda: 2)  # whatever this machine has
    parent = os.getpid()
    drawn_in = []
    real = cli._fit_png

    def spy(res):
        drawn_in.append(os.getpid() != parent)
        return real(res)

    monkeypatch.setattr(cli, "_fit_png", spy)
    svg = tmp_path / "bean.svg"
    svg.write_text('<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 100 100">'
                   '<path d="M10 50 C10 10 90 10 90 50 C90 90 10 90 10 50"/></svg>')
    common = ["--size", "4m", "--tol", "1mm"]
    assert main(["trace", str(svg), *common, "--reach", "none", "--out", str(tmp_path / "t"), "--no-viewer",
                 *workers]) == 0
    assert drawn_in == ([] if forks and not workers else [False])  # a child's own list is not this one's
    assert main(["fit", str(svg), *common, "--out", str(tmp_path / "f")]) == 0
    assert (tmp_path / "t" / "fit.png").read_bytes() == (tmp_path / "f" / "fit.png").read_bytes()
    assert "fit.png" in json.loads((tmp_path / "t" / MANIFEST).read_text())["files"]
