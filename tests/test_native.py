"""Compiled CasADi functions: the same numbers as CasADi's virtual machine, cached, and never a failure."""

import shutil
import subprocess
import time

import casadi as ca
import numpy as np
import pytest

import skatetrace as st
from skatetrace.figures.figure import figure_from_dict
from skatetrace.planning import native as nat
from skatetrace.planning.planner import plan_figure

needs_cc = pytest.mark.skipif(nat.compiler() is None, reason="no C compiler on this machine")


@pytest.fixture
def cache(tmp_path, monkeypatch):
    monkeypatch.setenv("SKATETRACE_CACHE_DIR", str(tmp_path))
    monkeypatch.delenv("SKATETRACE_NATIVE", raising=False)
    return tmp_path


def _function(scale=1.0):
    x = ca.SX.sym("x", 3)
    p = ca.SX.sym("p", 2)
    y = ca.vertcat(ca.sin(x[0] * p[0]) / (1 + x[1] ** 2), ca.sqrt(x[2] ** 2 + p[1]) * scale, x[0] * x[1] * x[2])
    return ca.Function("f", [x, p], [y, ca.jacobian(y, x)])


def _inputs(fn, rng, n=20):
    return [rng.uniform(0.5, 2.0, (fn.size1_in(i), n)) for i in range(fn.n_in())]


def _settled(cache, timeout=300.0):
    """Wait until the background builds have ended (each removes its folder last); the libraries' names."""
    deadline = time.monotonic() + timeout
    while any(p.is_dir() for p in cache.glob("casadi-*/*")):
        if time.monotonic() > deadline:  # pragma: no cover - a compiler hung
            pytest.fail(f"background builds still running after {timeout} s")
        time.sleep(0.05)
    return sorted(p.name for p in cache.rglob("*.so"))


def _loads(monkeypatch):
    """The libraries ``ca.external`` loads from now on, by file name."""
    loaded = []
    real = ca.external

    def external(name, path):
        loaded.append(nat.Path(path).name)
        return real(name, path)
    monkeypatch.setattr(nat.ca, "external", external)
    return loaded


@needs_cc
def test_the_compiled_function_gives_the_interpreted_numbers(cache, monkeypatch):
    fn = _function()
    loaded = _loads(monkeypatch)
    compiled = nat.native(fn)  # the quick build, while the optimised one compiles in the background
    assert compiled is not fn and not compiled.is_a("SXFunction")
    libraries = _settled(cache)
    assert len(libraries) == 2 and loaded == [n for n in libraries if n.endswith("-quick.so")]
    optimised = nat.native(fn)
    assert loaded[1:] == [n for n in libraries if not n.endswith("-quick.so")]
    args = _inputs(fn, np.random.default_rng(0))
    for got in (compiled, optimised):
        for want, value in zip(fn.map(20)(*args), got.map(20)(*args)):
            np.testing.assert_allclose(np.asarray(value), np.asarray(want), rtol=1e-14, atol=0)
        assert got.name_in() == fn.name_in() and got.sparsity_out(1) == fn.sparsity_out(1)
    # neither optimisation level reorders the arithmetic: the same bits
    for a, b in zip(compiled.map(20)(*args), optimised.map(20)(*args)):
        np.testing.assert_array_equal(np.asarray(a), np.asarray(b))


@needs_cc
def test_a_cached_function_is_loaded_without_the_compiler(cache, monkeypatch):
    first = nat.native(_function())
    libraries = _settled(cache)

    def no_compiler(*a, **k):
        raise AssertionError("compiled again")
    monkeypatch.setattr(subprocess, "run", no_compiler)
    monkeypatch.setattr(subprocess, "Popen", no_compiler)
    again = nat.native(_function())  # built anew: the same function, the same key
    assert not again.is_a("SXFunction")
    args = _inputs(first, np.random.default_rng(1), 1)
    np.testing.assert_array_equal(np.asarray(again(*args)[0]), np.asarray(first(*args)[0]))
    assert sorted(p.name for p in cache.rglob("*.so")) == libraries


@needs_cc
def test_no_second_background_build_while_one_runs(cache, monkeypatch):
    """Another process compiling the optimised library (its lock held) is left to it: the quick build is used."""
    import fcntl

    fn = _function()
    name = f"st_{nat._key(fn, nat.compiler())}"
    nat.cache_dir().mkdir(parents=True)
    with open(nat.cache_dir() / f"{name}.lock", "a+b") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)

        real = subprocess.Popen

        def no_job(args, **k):  # the quick build runs the compiler; a background build runs a shell
            if nat.Path(args[0]).name == "sh":
                raise AssertionError("a second background build")
            return real(args, **k)
        monkeypatch.setattr(subprocess, "Popen", no_job)
        compiled = nat.native(fn)
        assert not compiled.is_a("SXFunction")
    assert _settled(cache) == [f"{name}-quick.so"]


@needs_cc
def test_a_failed_background_build_leaves_nothing_behind(cache, monkeypatch):
    monkeypatch.setattr(nat, "FLAGS", nat.FLAGS + ("-fno-such-option-anywhere",))  # the optimised build fails
    fn = _function()
    compiled = nat.native(fn)
    assert not compiled.is_a("SXFunction")
    libraries = _settled(cache)
    assert len(libraries) == 1 and libraries[0].endswith("-quick.so")
    assert not [p for p in cache.glob("casadi-*/*") if p.suffix not in (".so", ".lock")]  # no sources, no folders
    # the lock is free again: the next plan tries once more
    started = []
    real = subprocess.Popen
    monkeypatch.setattr(subprocess, "Popen", lambda *a, **k: started.append(a) or real(*a, **k))
    nat.native(fn)
    assert len(started) == 1
    _settled(cache)


@pytest.mark.parametrize("setting", ["no compiler", "compiler fails", "turned off", "unwritable cache"])
def test_where_compiling_cannot_be_done_the_function_is_returned_as_it_was(cache, monkeypatch, setting, tmp_path):
    if setting == "no compiler":
        monkeypatch.setenv("CC", str(tmp_path / "no-such-compiler"))
    elif setting == "compiler fails":
        monkeypatch.setenv("CC", "false")
    elif setting == "turned off":
        monkeypatch.setenv("SKATETRACE_NATIVE", "0")
    else:
        blocker = tmp_path / "a-file"
        blocker.write_text("")
        monkeypatch.setenv("SKATETRACE_CACHE_DIR", str(blocker / "cache"))
    fn = _function()
    assert nat.native(fn) is fn
    assert not list(tmp_path.rglob("*.so"))


def test_an_mx_function_is_returned_as_it_was(cache):
    x = ca.MX.sym("x", 2)
    fn = ca.Function("g", [x], [2 * x])
    assert nat.native(fn) is fn


def test_the_cache_lives_under_the_directory_asked_for(cache):
    assert nat.cache_dir().parent == cache
    assert ca.__version__ in nat.cache_dir().name


def _plan_arc(monkeypatch, on: bool, params=None):
    monkeypatch.setenv("SKATETRACE_NATIVE", "1" if on else "0")
    fig = figure_from_dict({"schema": "skatetrace.figure/1",
                            "curves": [{"pieces": [{"type": "arc", "radius": 1.2, "sweep_deg": 198}]}]})
    return plan_figure(fig, params, options=st.TraceOptions(reach=1.0))


@needs_cc
def test_a_plan_is_the_same_compiled_or_interpreted(cache, monkeypatch):
    plain = _plan_arc(monkeypatch, False)
    assert not list(cache.rglob("*.so"))
    fast = _plan_arc(monkeypatch, True)
    libraries = _settled(cache)
    assert len(libraries) == 6  # the blocks' Jacobian, gradient and Hessian, quick and optimised
    for trace in (plain, fast):
        assert trace.success, trace.message
        assert trace.sections[0].metrics["reach"] <= 1.0
    # IPOPT solves the same program with the same numbers: the same optimum, to its tolerance
    a, b = plain.sections[0], fast.sections[0]
    assert b.duration == pytest.approx(a.duration, rel=1e-6)
    assert b.metrics["reach"] == pytest.approx(a.metrics["reach"], rel=1e-6)
    # planned again: the optimised libraries loaded from the cache, nothing new compiled
    loaded = _loads(monkeypatch)
    again = _plan_arc(monkeypatch, True)
    assert sorted(p.name for p in cache.rglob("*.so")) == libraries
    assert loaded and not [n for n in loaded if n.endswith("-quick.so")]
    assert again.sections[0].duration == b.duration  # the same numbers, bit for bit


@needs_cc
def test_a_damaged_library_in_the_cache_is_compiled_again(cache):
    fn = _function()
    nat.native(fn)
    libraries = _settled(cache)
    [library] = [p for p in cache.rglob("st_*.so") if not p.name.endswith("-quick.so")]
    library.write_bytes(b"not a shared library")
    again = nat.native(fn)  # the quick build, while the damaged one is compiled again
    assert not again.is_a("SXFunction")
    args = _inputs(fn, np.random.default_rng(2), 1)
    np.testing.assert_allclose(np.asarray(again(*args)[0]), np.asarray(fn(*args)[0]), rtol=1e-14)
    assert _settled(cache) == libraries
    assert not nat.native(fn).is_a("SXFunction")


def test_no_home_folder_means_no_cache_not_an_error(monkeypatch):
    monkeypatch.delenv("SKATETRACE_CACHE_DIR", raising=False)
    monkeypatch.delenv("XDG_CACHE_HOME", raising=False)

    def no_home():
        raise RuntimeError("Could not determine home directory.")
    monkeypatch.setattr(nat.Path, "home", staticmethod(no_home))
    fn = _function()
    assert nat.native(fn) is fn


def test_ctrl_c_while_compiling_stops_the_run_even_where_casadi_makes_it_an_error(cache, monkeypatch):
    import os
    import signal
    import time

    monkeypatch.setenv("CC", "cc")  # a compiler is named; it is never run
    monkeypatch.setattr(nat.shutil, "which", lambda name: "/usr/bin/cc")

    def interrupted(*args):
        try:
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(1.0)
        except KeyboardInterrupt:
            raise RuntimeError("Error in Function::generate: KeyboardInterruptException") from None

    monkeypatch.setattr(nat, "_build", interrupted)
    # Ctrl-C as Python handles it by default, also where the suite runs with it ignored (``pytest &``)
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        with pytest.raises(KeyboardInterrupt):
            nat.native(_function())
    finally:
        signal.signal(signal.SIGINT, previous)
    # without an interrupt, the same error is a function left interpreted
    monkeypatch.setattr(nat, "_build", lambda *a: (_ for _ in ()).throw(RuntimeError("no")))
    fn = _function()
    assert nat.native(fn) is fn


@needs_cc
def test_folders_left_by_killed_jobs_are_swept_when_a_job_starts(cache):
    import os

    folder = nat.cache_dir()
    folder.mkdir(parents=True)
    stale, fresh = folder / "tmpkilled", folder / "tmprunning"
    for path in (stale, fresh):
        path.mkdir()
        (path / "st_x.c").write_text("/* a job's source */")
    old = time.time() - nat.STALE - 60.0
    os.utime(stale, (old, old))
    nat.native(_function())  # starts a background job, which sweeps first
    assert not stale.exists() and fresh.exists()  # a folder younger than STALE may be a running job's
    shutil.rmtree(fresh)
    assert len(_settled(cache)) == 2
