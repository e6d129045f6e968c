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
    assert first.stdout.split("\n")[:2] == ["False", "5 (1, 5)"]
    again = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True)
    assert again.stdout.split("\n")[:2] == ["True", "0 None"]
