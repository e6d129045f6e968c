"""The compiled core's cache: cold and warm as numba sees it (skatetrace.cli.compiled)."""

import os
import subprocess
import sys

import pytest

from skatetrace.cli import compiled


def test_entry_points_are_numba_dispatchers_with_a_cache():
    for part, dispatcher in compiled._dispatchers():
        assert dispatcher._cache is not None, part  # cache=True, so a later run can load it


def test_unknown_cache_layout_is_none_not_a_crash(monkeypatch):
    def broken():
        raise AttributeError("numba moved its cache")
        yield

    monkeypatch.setattr(compiled, "_dispatchers", broken)
    assert compiled.cache_is_warm() is None


def test_in_this_process_after_a_trace_the_cache_is_warm():
    compiled.warm_up()
    assert compiled.cache_is_warm() is True


@pytest.mark.slow
def test_a_fresh_cache_is_cold_then_warm_in_the_next_process(tmp_path):
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path)}
    code = ("import sys, skatetrace.cli.compiled as c; parts = []; print(c.cache_is_warm()); "
            "c.warm_up(lambda p, i, n: parts.append((p, i, n))); print(len(parts), parts[0][1:] if parts else None)")
    first = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True)
    assert first.stdout.split("\n")[:2] == ["False", "7 (1, 7)"]
    again = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True)
    assert again.stdout.split("\n")[:2] == ["True", "0 None"]


@pytest.mark.slow
def test_a_first_run_compiles_only_what_it_needs_and_says_so(tmp_path):
    """A launch-glide-stop trace compiles the integrator, the replay and the distance checks, named
    as they compile, and neither the closed-loop replay nor the planner's finish (half the time of
    compiling everything): those compile in a job of their own, for later runs, which the run names
    and does not wait for. Once it ends, the next run compiles nothing and says nothing of it, and
    neither does compiling (or loading) every part through the real callers (``warm_up``): the job
    compiled them with the argument types of every run."""
    cache = tmp_path / "cache"
    env = {**os.environ, "NUMBA_CACHE_DIR": str(cache), "SKATETRACE_COMPILE_LATER": "1"}
    cmd = [sys.executable, "-m", "skatetrace", "trace", "line", "--out", str(tmp_path / "o"), "--no-plots",
           "--no-viewer"]
    first = subprocess.run(cmd, env=env, capture_output=True, text=True, check=True)
    assert first.stderr.count("first run on this machine") == 1
    assert "  compiling the manoeuvre integrator\n" in first.stderr
    assert "  compiled the manoeuvre integrator in " in first.stderr
    # the verification's parts compile in a second process while the run traces (or, should that
    # process not be done in time, in the run itself, said as the integrator is)
    assert "  compiling the verification's parts alongside, in a second process\n" in first.stderr
    for part in ("the verifying replay", "the distance checks"):
        assert (f"  compiling {part}\n" in first.stderr) == (f"  compiled {part} in " in first.stderr)
    for part in compiled.LATER:
        assert f"  compiling {part}\n" not in first.stderr and f"  compiled {part} in " not in first.stderr
    later = "  compiling for later runs, in the background at the lowest priority: " + ", ".join(compiled.LATER)
    assert later + "\n" in first.stderr
    waited = compiled.later_job_end(cache)
    assert waited is not None and waited < float("inf")  # a job was started, and it ended
    again = subprocess.run(cmd, env=env, capture_output=True, text=True, check=True)
    assert "compil" not in again.stderr
    code = ("import skatetrace.cli.compiled as c; parts = []; c.warm_up(lambda p, i, n: parts.append(p)); "
            "from skatetrace.dynamics.integrator import _run; "
            "print(parts, c.cache_is_warm(), len(_run._cache._cache_file._load_index()))")
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True)
    # the planner's finish calls the trace's own integrator (one compiled signature, not a second
    # one specialised on literal arguments)
    assert out.stdout.strip() == "[] True 1"


def test_no_job_for_later_runs_where_it_is_turned_off_or_nothing_is_missing(monkeypatch):
    monkeypatch.setenv("SKATETRACE_COMPILE_LATER", "0")
    assert compiled.compile_later() == ()
    monkeypatch.setenv("SKATETRACE_COMPILE_LATER", "1")
    monkeypatch.setattr(compiled, "_part_is_cached", lambda part: True)
    assert compiled.compile_later() == ()


@pytest.mark.slow
def test_compile_ahead_fills_the_cache_with_the_types_verification_uses(tmp_path):
    """The second process compiles the replay and the distance checks through their own callers on
    tiny inputs: afterwards a real verification in another process loads them and compiles neither
    (a mismatch of argument types would compile them again)."""
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "cache")}
    ahead = ("import skatetrace.cli.compiled as c; p = c.compile_ahead(); p.join(); print(p.exitcode); "
             "print(c._part_is_cached('the verifying replay'), c._part_is_cached('the distance checks')); "
             "print(c.compile_ahead())")
    out = subprocess.run([sys.executable, "-c", ahead], env=env, capture_output=True, text=True, check=True)
    assert out.stdout.split("\n")[:3] == ["0", "True True", "None"]  # nothing left to compile ahead
    run = ("import skatetrace as st, skatetrace.cli.compiled as c; from skatetrace.figures.patterns import pattern; "
           "tr = st.trace_figure(pattern('circle')); parts = []; "
           "ctx = c.reporting(lambda part, s: parts.append(part)); ctx.__enter__(); r = st.verify(tr); "
           "print(r.success, sorted(set(parts)))")
    out = subprocess.run([sys.executable, "-c", run], env=env, capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "True []"
