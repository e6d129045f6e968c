import os
from pathlib import Path
from unittest import mock

import numpy as np
import pytest

from skatetrace.outputs.files import atomic_write, staged


def test_atomic_write_replaces_whole_file(tmp_path):
    p = tmp_path / "a.json"
    atomic_write(p, "old")
    atomic_write(p, "new")
    assert p.read_text() == "new"
    assert os.listdir(tmp_path) == ["a.json"]


def test_interrupted_write_keeps_the_old_file_and_no_temporary(tmp_path, monkeypatch):
    p = tmp_path / "a.json"
    atomic_write(p, "old")

    def boom(src, dst):
        raise KeyboardInterrupt

    monkeypatch.setattr(os, "replace", boom)
    with pytest.raises(KeyboardInterrupt):
        atomic_write(p, "new")
    assert p.read_text() == "old"
    assert os.listdir(tmp_path) == ["a.json"]


def test_result_records_every_tracer_setting():
    from dataclasses import asdict

    import skatetrace as st
    from skatetrace.outputs.results import result_dict

    options = st.TraceOptions(speed=1.5, placement="first", search=3)
    d = result_dict(st.trace_figure(st.pattern("circle"), options=options))
    assert d["options"] == asdict(options)


@pytest.mark.parametrize("n", [0, 1, 7, 1001])
def test_controls_csv_formatted_in_chunks_and_processes_is_the_same_text_and_reads_back_exactly(
        tmp_path, monkeypatch, pools_made, n):
    import numpy as np

    from skatetrace.dynamics.controls import ControlSchedule
    from skatetrace.outputs import results

    rng = np.random.default_rng(n)
    schedule = ControlSchedule(t=np.sort(rng.random(n)), a=rng.normal(size=n), b=rng.normal(size=n) * 1e-300,
                               adot=rng.normal(size=n) * 1e300, bdot=-rng.random(n), section=np.arange(n) % 3,
                               piece=np.arange(n) % 2)
    states = {k: rng.normal(size=n) for k in ("x", "y", "theta", "p1", "p2", "xi1", "xi2")}
    monkeypatch.setattr(results, "_SPLIT_ROWS", 10**9)
    results._write_csv(tmp_path / "whole.csv", schedule, states, [0, 1, 1])
    whole = (tmp_path / "whole.csv").read_text()
    # rounds of chunks of 3 rows, each round shared out between processes, the last one short
    monkeypatch.setattr(results, "_SPLIT_ROWS", 2)
    monkeypatch.setattr(results, "_CHUNK_ROWS", 3)
    seen = []
    with results.reporting(lambda *args: seen.append(args)):
        results._write_csv(tmp_path / "controls.csv", schedule, states, [0, 1, 1])
    halves = (tmp_path / "controls.csv").read_text()
    assert halves == whole and whole.count("\n") == n + 1
    assert whole.splitlines()[0] == ",".join(results.CSV_COLUMNS)
    # progress: rows written so far, rising to all of them
    assert [done for _, done, _ in seen] == sorted({done for _, done, _ in seen})
    assert all(stage == "writing controls.csv" and total == n for stage, _, total in seen)
    assert (seen[-1][1] if seen else 0) == n and (n < 7 or len(seen) > 1)
    back = results.read_controls(tmp_path / "controls.csv")
    for k in ("t", "a", "b", "adot", "bdot"):
        np.testing.assert_array_equal(back[k], getattr(schedule, k))
    np.testing.assert_array_equal(back["curve"], np.array([0, 1, 1])[schedule.section])


@pytest.mark.parametrize("odd", [None, np.nan, -np.inf])
def test_controls_csv_formatted_run_by_run_is_the_same_text_as_row_by_row(tmp_path, monkeypatch, odd):
    """Rows of one piece, curve and section are formatted as one table with the integers spliced
    in: the same bytes as row by row; a chunk holding a value that is not finite goes row by row."""
    from skatetrace.dynamics.controls import ControlSchedule
    from skatetrace.outputs import results

    rng = np.random.default_rng(3)
    n = 3000
    section = np.repeat(np.arange(6), n // 6)
    piece = (np.arange(n) // 125) % 3  # runs of 125 rows, several pieces a section
    schedule = ControlSchedule(t=np.sort(rng.random(n)) * 10.0, a=rng.normal(size=n), b=rng.normal(size=n) * 1e-7,
                               adot=rng.normal(size=n) * 1e17, bdot=-rng.random(n), section=section, piece=piece)
    states = {k: rng.normal(size=n) for k in ("x", "y", "theta", "p1", "p2", "xi1", "xi2")}
    if odd is not None:
        states["xi2"][1234] = odd
    texts = []
    for run_rows in (10**9, 1):  # row by row, then run by run where the runs allow
        monkeypatch.setattr(results, "_RUN_ROWS", run_rows)
        results._write_csv(tmp_path / "c.csv", schedule, states, [0, 0, 1, 1, 2, 2])
        texts.append((tmp_path / "c.csv").read_bytes())
    assert texts[0] == texts[1] and texts[0].count(b"\n") == n + 1
    back = results.read_controls(tmp_path / "c.csv")
    np.testing.assert_array_equal(back["xi2"], states["xi2"])
    np.testing.assert_array_equal(back["piece"], piece)
    np.testing.assert_array_equal(back["curve"], section // 2)


def test_controls_csv_floats_read_back_as_the_same_doubles_in_their_shortest_digits():
    """Every double, subnormals and the largest included, is written with as few digits as repr
    uses and reads back exactly; a column holding nan or inf is written as repr writes it."""
    import numpy as np

    from skatetrace.outputs.results import _column_text

    rng = np.random.default_rng(7)
    bits = rng.integers(0, 2**63, size=20000, dtype=np.uint64) | (rng.integers(0, 2, 20000, dtype=np.uint64) << 63)
    values = bits.view(np.float64)
    values = np.concatenate([values[np.isfinite(values)], [0.0, -0.0, 5e-324, 1.7976931348623157e308, 1e-7, 1e16,
                                                           0.1, 1 / 3, 123456789.0, -2.5e-300]])
    text = _column_text(values)
    back = np.array([float(t) for t in text])
    assert np.array_equal(back.view(np.uint64), values.view(np.uint64))  # -0.0 too, bit for bit

    def digits(s: str) -> int:
        return len(s.split("e")[0].lstrip("-").replace(".", "").strip("0"))

    assert all(digits(t.decode()) <= digits(repr(v)) for t, v in zip(text, values.tolist()))
    odd = np.array([1.5, np.nan, -np.inf, np.inf])
    assert _column_text(odd) == [b"1.5", b"nan", b"-inf", b"inf"]
    assert _column_text(np.array([0, 3, -12], dtype=np.int64)) == [b"0", b"3", b"-12"]
    assert _column_text(np.zeros(0)) == []


# ---------------------------------------------------------------------------------------------------------
# strict JSON, file modes, output folders

import json
import stat
import subprocess
import sys

import numpy as np

from skatetrace.errors import SkatetraceError
from skatetrace.outputs.folder import (MANIFEST, STAGING_PREFIX, OutputFolder, adopt, check_output_file,
                                       check_output_folder)
from skatetrace.outputs.files import dumps_json, file_mode, write_atomically


def strict_loads(text):
    """json.loads that rejects NaN, Infinity and -Infinity, as JSON parsers outside Python do."""
    def reject(name):
        raise ValueError(f"not JSON: {name}")
    return json.loads(text, parse_constant=reject)


def test_strict_loads_rejects_what_python_writes_by_default():
    with pytest.raises(ValueError, match="NaN"):
        strict_loads(json.dumps({"a": float("nan")}))
    with pytest.raises(ValueError, match="Infinity"):
        strict_loads(json.dumps([float("-inf")]))


def test_dumps_json_writes_null_for_nan_and_infinities():
    data = {"nan": float("nan"), "inf": np.float64(np.inf), "arr": np.array([1.0, -np.inf]), "i": np.int64(3),
            "ok": np.bool_(True), "nested": [{"x": (float("nan"), 2.5)}]}
    parsed = strict_loads(dumps_json(data))
    assert parsed == {"nan": None, "inf": None, "arr": [1.0, None], "i": 3, "ok": True,
                      "nested": [{"x": [None, 2.5]}]}


def _read_umask_in_child(umask):
    code = ("import os, pathlib, sys; os.umask(int(sys.argv[1], 8)); "
            "from skatetrace.outputs.files import atomic_write, file_mode; p = pathlib.Path(sys.argv[2]); "
            "atomic_write(p, 'x'); print(oct(os.stat(p).st_mode & 0o777), oct(file_mode()))")
    return code


@pytest.mark.parametrize("umask, mode", [(0o022, 0o644), (0o077, 0o600), (0o002, 0o664)])
def test_files_get_the_umasks_permissions_not_0600(tmp_path, umask, mode):
    # in a child process: the umask is process-wide, and other threads of this one may create files
    code = _read_umask_in_child(umask)
    p = tmp_path / f"f{umask:o}.json"
    out = subprocess.run([sys.executable, "-c", code, f"{umask:o}", str(p)], capture_output=True, text=True,
                         check=True).stdout.split()
    assert out == [oct(mode), oct(mode)]
    assert stat.S_IMODE(p.stat().st_mode) == mode


def test_file_mode_follows_this_process_umask(tmp_path):
    old = os.umask(0o027)
    try:
        assert file_mode() == 0o640
        write_atomically(tmp_path / "a.txt", lambda tmp: tmp.write_text("x"))
        assert stat.S_IMODE((tmp_path / "a.txt").stat().st_mode) == 0o640
    finally:
        os.umask(old)


def test_file_mode_without_proc(monkeypatch):
    import builtins

    real_open = builtins.open

    def no_proc(path, *args, **kwargs):
        if str(path).startswith("/proc"):
            raise FileNotFoundError(path)
        return real_open(path, *args, **kwargs)

    monkeypatch.setattr(builtins, "open", no_proc)
    old = os.umask(0o077)
    try:
        assert file_mode() == 0o600
        assert os.umask(0o077) == 0o077  # and the umask is as it was
    finally:
        os.umask(old)


@pytest.mark.parametrize("below, match", [
    ((), "f is a file, not a folder; give the name of a folder"),
    (("sub",), "cannot create folder .*sub: .*f is a file, not a folder"),
    (("a", "b"), "cannot create folder .*b: .*f is a file, not a folder"),
])
def test_output_folder_that_cannot_be_is_a_clear_error(tmp_path, below, match):
    (tmp_path / "f").write_text("x")
    target = tmp_path.joinpath("f", *below)
    with pytest.raises(SkatetraceError, match=match):
        check_output_folder(target)
    assert (tmp_path / "f").read_text() == "x"  # nothing lost


def test_output_folder_not_writable_is_a_clear_error(tmp_path, monkeypatch):
    import tempfile

    def denied(*args, **kwargs):
        raise PermissionError(13, "Permission denied")

    monkeypatch.setattr(tempfile, "mkstemp", denied)
    with pytest.raises(SkatetraceError, match=r"cannot write in folder .*Permission denied.*--out must be a folder"):
        check_output_folder(tmp_path / "new" / "deeper")
    assert not (tmp_path / "new").exists()  # the folders the check made are gone again


@pytest.mark.skipif(os.geteuid() == 0, reason="root may write anywhere")
def test_output_folder_under_a_read_only_folder(tmp_path):
    ro = tmp_path / "ro"
    ro.mkdir()
    ro.chmod(0o555)
    try:
        with pytest.raises(SkatetraceError, match="cannot create folder"):
            check_output_folder(ro / "out")
    finally:
        ro.chmod(0o755)


def test_output_folder_is_created_and_left_clean(tmp_path):
    created = check_output_folder(tmp_path / "a" / "b")
    assert created == [tmp_path / "a", tmp_path / "a" / "b"]
    assert list((tmp_path / "a" / "b").iterdir()) == []
    with pytest.raises(SkatetraceError, match="figures is a file"):
        (tmp_path / "a" / "b" / "figures").write_text("mine")
        check_output_folder(tmp_path / "a" / "b", subfolders=("figures",))


@pytest.mark.parametrize("name, kwargs, match", [
    ("x.avi", {"suffixes": (".gif", ".mp4", ".png")}, r"must end in \.gif, \.mp4 or \.png \(got '\.avi'\)"),
    ("noext", {"suffixes": (".gif",)}, r"must end in \.gif \(got 'no suffix'\)"),
    ("missing/x.gif", {"create_parent": False}, "folder .*missing does not exist"),
    ("f/x.gif", {}, "f is a file, not a folder"),
    ("d", {}, "is a folder; give the name of a file"),
])
def test_output_file_checks(tmp_path, name, kwargs, match):
    (tmp_path / "f").write_text("x")
    (tmp_path / "d").mkdir()
    with pytest.raises(SkatetraceError, match=match):
        check_output_file(tmp_path / name, **kwargs)


def test_output_folder_removes_only_its_own_stale_files(tmp_path):
    out = tmp_path / "out"
    with OutputFolder(out, "trace") as first:
        for name in ("result.json", "a.png", "b.png"):
            atomic_write(out / name, "1")
        atomic_write(tmp_path / "elsewhere.txt", "not in the folder")
    assert first.finish() == []
    assert strict_loads((out / MANIFEST).read_text())["files"] == ["a.png", "b.png", "result.json"]
    (out / "notes.txt").write_text("mine")
    second = OutputFolder(out, "trace")
    with second:
        atomic_write(out / "result.json", "2")
        atomic_write(out / "c.png", "2")
    assert second.finish() == ["a.png", "b.png"]
    assert sorted(p.name for p in out.iterdir()) == [MANIFEST, "c.png", "notes.txt", "result.json"]
    assert strict_loads((out / MANIFEST).read_text())["files"] == ["c.png", "result.json"]
    assert (tmp_path / "elsewhere.txt").exists()


def test_a_run_stopped_before_it_finishes_leaves_the_earlier_run_as_it_was(tmp_path):
    out = tmp_path / "out"
    with OutputFolder(out, "trace") as first:
        atomic_write(out / "a.png", "1")
        atomic_write(out / "result.json", "first")
        assert not (out / "a.png").exists()  # staged until the run is over
        assert staged(out / "a.png").read_text() == "1"
    first.finish()
    assert sorted(p.name for p in out.iterdir()) == [MANIFEST, "a.png", "result.json"]  # no staging left
    stopped = OutputFolder(out, "trace")
    with stopped:  # writes two files, then is stopped: no finish()
        atomic_write(out / "result.json", "second")
        atomic_write(out / "b.png", "2")
    # what a killed process leaves: its staging folder, with its files in it
    leftover = [p for p in out.iterdir() if p.name.startswith(STAGING_PREFIX)]
    assert len(leftover) == 1 and (leftover[0] / "b.png").exists()
    stopped._unlock()
    stopped._staging = None  # as if killed: nothing cleaned up
    assert (out / "result.json").read_text() == "first" and not (out / "b.png").exists()
    assert strict_loads((out / MANIFEST).read_text()) == {**strict_loads((out / MANIFEST).read_text()),
                                                          "complete": True, "files": ["a.png", "result.json"]}
    # a run killed while writing its manifest leaves the manifest's temporary file beside it
    half = out / ("." + MANIFEST[:-len(".json")] + ".k1ll3d.partial.json")
    half.write_text('{"schema": "skatetrace.manifest/1", "fi')
    mine = out / ".skatetrace-manifest-notes.partial.json"  # a user's file of a similar name stays
    mine.write_text("mine")
    nxt = OutputFolder(out, "trace")  # the next run removes the killed run's staging folder
    assert not leftover[0].exists() and not half.exists() and mine.exists()
    mine.unlink()
    with nxt:
        atomic_write(out / "c.png", "3")
    assert nxt.finish() == ["a.png", "result.json"]
    assert sorted(p.name for p in out.iterdir()) == [MANIFEST, "c.png"]


def test_staged_writes_go_only_where_the_folder_is(tmp_path):
    out = tmp_path / "out"
    run = OutputFolder(out, "trace")
    with run:
        atomic_write(tmp_path / "beside.txt", "not the run's")
        atomic_write(out / "figures" / "main-1.png", "x")
        assert (tmp_path / "beside.txt").read_text() == "not the run's"
        assert staged(tmp_path / "beside.txt") == tmp_path / "beside.txt"
        assert not (out / "figures").exists()
    assert run.finish() == []
    assert (out / "figures" / "main-1.png").read_text() == "x"
    assert strict_loads((out / MANIFEST).read_text())["files"] == ["figures/main-1.png"]


def test_a_run_that_wrote_nothing_removes_nothing(tmp_path):
    out = tmp_path / "out"
    with OutputFolder(out, "trace") as run:
        atomic_write(out / "a.png", "1")
    run.finish()
    again = OutputFolder(out, "trace")
    assert again.finish() == [] and (out / "a.png").exists()


def test_manifest_entries_outside_the_folder_are_ignored(tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    (tmp_path / "victim.txt").write_text("keep")
    (out / MANIFEST).write_text(json.dumps({"schema": "skatetrace.manifest/1", "files": ["../victim.txt",
                                            str(tmp_path / "victim.txt"), "ok.png"]}))
    (out / "ok.png").write_text("old")
    with OutputFolder(out, "trace") as run:
        atomic_write(out / "new.png", "x")
    assert run.finish() == ["ok.png"]
    assert (tmp_path / "victim.txt").read_text() == "keep"


def test_folders_from_before_manifests_are_recognised_by_their_schema(tmp_path):
    old = tmp_path / "old"
    old.mkdir()
    (old / "result.json").write_text(json.dumps({"schema": "skatetrace.result/1"}))
    for name in ("figure.png", "viewer.html", "notes.txt"):
        (old / name).write_text("old")
    with OutputFolder(old, "trace") as run:
        atomic_write(old / "result.json", "{}")
    assert run.finish() == ["figure.png", "viewer.html"]
    # a folder that is not skatetrace's loses nothing, even files named like skatetrace's
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "figure.png").write_text("a user's picture")
    with OutputFolder(mine, "trace") as run:
        atomic_write(mine / "result.json", "{}")
    assert run.finish() == [] and (mine / "figure.png").exists()


def test_adopt_adds_a_later_file_to_the_runs_manifest(tmp_path):
    out = tmp_path / "out"
    with OutputFolder(out, "trace") as run:
        atomic_write(out / "result.json", "{}")
    run.finish()
    atomic_write(out / "viewer.html", "<html>")
    assert adopt(out / "viewer.html")
    assert "viewer.html" in strict_loads((out / MANIFEST).read_text())["files"]
    assert not adopt(tmp_path / "loose.html")


# --- issue 19: one run at a time, and a folder a run did not finish is not read as one run's ---------------

def test_a_second_run_into_a_folder_being_written_is_refused(tmp_path, capsys):
    from skatetrace.cli import main

    out = tmp_path / "out"
    first = OutputFolder(out, "trace")
    with pytest.raises(SkatetraceError, match="another skatetrace run is writing into"):
        OutputFolder(out, "trace")
    assert main(["trace", "circle", "--out", str(out), "--no-plots", "--no-viewer"]) == 2
    assert "another skatetrace run is writing into" in capsys.readouterr().err
    first.finish()
    OutputFolder(out, "trace").finish()  # free again


def test_a_folder_whose_run_did_not_finish_is_refused_by_its_readers(tmp_path, capsys):
    from skatetrace.cli import main
    from skatetrace.outputs.folder import check_finished

    out = tmp_path / "out"
    assert main(["trace", "circle", "--out", str(out), "--no-plots", "--no-viewer"]) == 0
    check_finished(out)  # a finished run passes
    assert strict_loads((out / MANIFEST).read_text())["complete"] is True
    run = OutputFolder(out, "trace")
    with run:  # a second run writes two files, then dies while moving them into place
        atomic_write(out / "result.json", (out / "result.json").read_text() + " ")
        atomic_write(out / "controls.csv", "t\n")
    real_replace = os.replace

    def killed_after_one(src, dst):
        if Path(dst).name == "controls.csv":
            raise KeyboardInterrupt  # the kill, between the two moves
        real_replace(src, dst)

    with mock.patch("skatetrace.outputs.folder.os.replace", killed_after_one), pytest.raises(KeyboardInterrupt):
        run.finish()
    assert strict_loads((out / MANIFEST).read_text())["complete"] is False
    # the new result beside the old controls
    assert (out / "result.json").read_text().endswith(" ") and (out / "controls.csv").read_text() != "t\n"
    del run
    with pytest.raises(SkatetraceError, match="did not finish writing"):
        check_finished(out / "result.json")
    capsys.readouterr()
    for argv in (["view", str(out)], ["animate", str(out), "-o", str(tmp_path / "a.gif")],
                 ["robustness", str(out), "--trials", "2"]):
        assert main(argv) == 2
        err = capsys.readouterr().err
        assert "did not finish writing" in err and "skatetrace trace" in err, (argv, err)
    assert main(["trace", "circle", "--out", str(out), "--no-plots", "--no-viewer"]) == 0
    check_finished(out)  # the next finished run makes it one run's again
    assert main(["view", str(out)]) == 0


def _one_run(out, started):
    """The folder's files (beside the manifest and staging), checked to be one run's: the manifest's list,
    and all written before ``started`` (the earlier run) or all after it (the killed one)."""
    from skatetrace.errors import SkatetraceError
    from skatetrace.outputs.folder import check_finished

    manifest = strict_loads((out / MANIFEST).read_text())
    # (killed while writing its manifest, a run leaves the manifest's temporary file: the next removes it)
    names = sorted(p.name for p in out.iterdir() if p.name != MANIFEST and not p.name.startswith(STAGING_PREFIX)
                   and not (p.name.startswith("." + MANIFEST[:-len(".json")] + ".") and p.name.endswith(".partial.json")))
    if manifest["complete"] is False:
        # killed in the instant its files were moved in (on a loaded machine, now and then): the
        # folder may mix two runs, and says so; every reader refuses it
        with pytest.raises(SkatetraceError, match="did not finish writing"):
            check_finished(out)
        return None
    assert manifest["complete"] is True and names == manifest["files"], (names, manifest)
    newer = {(out / n).stat().st_mtime_ns >= started for n in names}
    assert len(newer) == 1, f"files of two runs side by side: {names}"
    return newer.pop()


def _written_since(out, started):
    """Whether a file under ``out`` (its staging folder included) was written at or after ``started``."""
    for p in out.rglob("*"):
        try:
            if p.is_file() and p.stat().st_mtime_ns >= started:
                return True
        except OSError:  # moved or removed meanwhile
            pass
    return False


@pytest.mark.slow
def test_a_killed_run_never_leaves_a_folder_of_two_runs(tmp_path):
    import signal
    import subprocess
    import sys
    import time

    from skatetrace.cli import main

    out = tmp_path / "out"
    argv = ["trace", "line", "--out", str(out), "--no-plots", "--no-viewer"]
    for delay in (None, 0.5, 1.5, 3.0):  # None: killed as soon as its first file is written
        assert main(["trace", "circle", "--out", str(out)]) == 0  # the earlier run: plots and viewer too
        time.sleep(0.01)
        started = time.time_ns()
        proc = subprocess.Popen([sys.executable, "-m", "skatetrace", *argv], stdout=subprocess.DEVNULL,
                                stderr=subprocess.DEVNULL)
        t0 = time.monotonic()
        while proc.poll() is None and time.monotonic() - t0 < (60 if delay is None else delay):
            if delay is None and _written_since(out, started):
                break
            time.sleep(0.002)
        proc.send_signal(signal.SIGKILL)
        proc.wait()
        # the earlier run's files as they were, or (killed too late) the new run's; None where it was
        # killed in the instant its files moved in, which every reader refuses (checked there)
        whole = _one_run(out, started)
        if delay is None and whole is not None:
            assert main(["view", str(out)]) == 0
    assert main(argv) == 0 and _one_run(out, started)  # the next run cleans up and is whole
    assert not list(out.glob(STAGING_PREFIX + "*")) and not list(out.glob(".*.partial.*"))
