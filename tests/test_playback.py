"""Traced figures read back from their result files (skatetrace.outputs.playback)."""

import json

import numpy as np
import pytest

from skatetrace.cli import main
from skatetrace.errors import SkatetraceError
from skatetrace.outputs.results import read_controls
from skatetrace.outputs.playback import load_playback


@pytest.fixture(scope="module")
def traced(tmp_path_factory):
    out = tmp_path_factory.mktemp("s-bend")
    assert main(["trace", "s-bend", "--rests", "joins", "--out", str(out), "--no-plots"]) == 0
    return out


def test_playback_matches_the_files(traced):
    pb = load_playback(traced)
    result = json.loads((traced / "result.json").read_text())
    cols = read_controls(traced / "controls.csv")
    assert pb.unit == result["unit"] == "model" and pb.name == "s-bend"
    np.testing.assert_array_equal(pb.t, cols["t"])
    # the mass on the ice is the contact point plus the body-frame offset turned by the heading
    c, s = np.cos(pb.theta), np.sin(pb.theta)
    np.testing.assert_allclose(pb.mass_x, pb.x + pb.a * c - pb.b * s, atol=1e-12)
    np.testing.assert_allclose(pb.mass_y, pb.y + pb.a * s + pb.b * c, atol=1e-12)
    # a rest at every section's start and at the end, where the blade is still
    n = len(result["sections"])
    assert n > 1 and pb.rests.shape == (2, n + 1)
    np.testing.assert_allclose(pb.rest_times[:-1], [sec["start_time"] for sec in result["sections"]], atol=1e-12)
    rows = np.searchsorted(pb.t, pb.rest_times)
    assert np.all(np.abs(pb.speed[rows]) < 1e-8)
    assert np.all(np.diff(pb.section) >= 0) and pb.section[-1] == n - 1
    assert np.all(pb.ke_total >= 0) and pb.ke_total.max() > 0
    assert pb.summary["verification"]["status"] == "passed"
    x0, x1, y0, y1 = pb.bounds()
    assert x0 < pb.x.min() and x1 > pb.x.max() and y0 < pb.y.min() and y1 > pb.y.max()
    rows = pb.frame_rows(50)
    assert rows[0] == 0 and rows[-1] == pb.t.size - 1 and np.all(np.diff(pb.t[rows]) >= 0)
    assert load_playback(traced / "result.json").t.size == pb.t.size


def test_controls_in_memory_give_the_playback_of_the_files(traced, tmp_path):
    # the command line builds its viewer from the rows it has just written, without reading them back
    from_files = load_playback(traced)
    for name in ("result.json", "report.json"):
        (tmp_path / name).write_text((traced / name).read_text())
    columns = read_controls(traced / "controls.csv")
    from_memory = load_playback(tmp_path, columns)  # this folder has no controls.csv
    for field in ("t", "x", "y", "theta", "a", "b", "adot", "bdot", "mass_x", "mass_y", "speed", "omega",
                  "ke_skate", "ke_mass", "section", "rests", "rest_times"):
        np.testing.assert_array_equal(getattr(from_memory, field), getattr(from_files, field), err_msg=field)
    assert from_memory.summary == from_files.summary
    with pytest.raises(SkatetraceError, match="controls.csv not found"):
        load_playback(tmp_path)


def test_missing_or_broken_results_are_clear_errors(tmp_path, traced):
    with pytest.raises(SkatetraceError, match="result.json not found"):
        load_playback(tmp_path)
    (tmp_path / "result.json").write_text((traced / "result.json").read_text())
    with pytest.raises(SkatetraceError, match="controls.csv not found"):
        load_playback(tmp_path)
    (tmp_path / "controls.csv").write_text("t,a\n1,2\n")
    with pytest.raises(SkatetraceError, match="cannot read the results"):
        load_playback(tmp_path)
    with pytest.raises(ValueError, match="at least one frame"):
        load_playback(traced).frame_rows(0)


def test_a_controls_file_cut_short_names_its_line(traced, tmp_path):
    # issue 19: a run killed while writing left a partial last row, read back as numpy's "inhomogeneous shape"
    text = (traced / "controls.csv").read_text()
    cut = tmp_path / "controls.csv"
    cut.write_text(text[: len(text) // 2].rsplit(",", 3)[0])
    with pytest.raises(ValueError, match=r"line \d+ has \d+ of the \d+ columns: the file is cut short"):
        read_controls(cut)
