import csv
import json
import subprocess
import sys

import numpy as np
from scipy.interpolate import CubicHermiteSpline

from skatetrace.cli import main


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
    assert list(rows[0]) == "piece,t,a,b,adot,bdot,x,y,theta,p1,p2,xi1,xi2".split(",")
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
    from skatetrace.io import load_result

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
    assert "must end in .gif or .mp4" in capsys.readouterr().err
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
