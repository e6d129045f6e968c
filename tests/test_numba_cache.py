"""Numba's on-disk cache under saves at the same time (skatetrace.dynamics.numba_cache)."""

import threading

import pytest
from numba import njit
from numba.core import config
from numba.core.caching import Cache, FunctionCache

from skatetrace.dynamics import dop853, numba_cache


def _saved_side_by_side(tmp_path, monkeypatch, module: str):
    """Two signatures of one function saved by two threads, the second reading the index while the first
    has read it and not yet written it back (or, where the first holds the lock, after it has).

    Returns the cache's index and the signatures each of the two loads back (None where lost).
    """
    monkeypatch.setattr(config, "CACHE_DIR", str(tmp_path))

    def twice(x):
        return x + x

    twice.__module__ = module
    f = njit(twice)
    f(1), f(1.5)
    (sig_a, cres_a), (sig_b, cres_b) = f.overloads.items()
    cache = FunctionCache(f.py_func)
    index_file = cache._cache_file
    plain = index_file._load_index
    first_read, second_read = threading.Event(), threading.Event()

    def load_index():
        index = plain()
        if not first_read.is_set():
            first_read.set()
            second_read.wait(0.5)  # in vain where the second save waits for the lock
        else:
            second_read.set()
        return index

    monkeypatch.setattr(index_file, "_load_index", load_index)

    def second():
        first_read.wait(10.0)
        cache.save_overload(sig_b, cres_b)

    threads = [threading.Thread(target=cache.save_overload, args=(sig_a, cres_a)), threading.Thread(target=second)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(30.0)
    monkeypatch.setattr(index_file, "_load_index", plain)
    loaded = [cache.load_overload(sig, f.targetctx) for sig in (sig_a, sig_b)]
    return plain(), [None if cres is None else tuple(cres.signature.args) for cres in loaded], (sig_a, sig_b)


def test_importing_a_compiled_module_guards_the_saves_once():
    assert dop853.guard_saves is numba_cache.guard_saves  # imported above: its import installed the guard
    numba_cache.guard_saves()  # again: not wrapped twice
    assert Cache.save_overload._skatetrace_guarded
    assert not getattr(Cache.save_overload.__wrapped__, "_skatetrace_guarded", False)


def test_saves_of_two_signatures_at_once_keep_both(tmp_path, monkeypatch):
    index, loaded, sigs = _saved_side_by_side(tmp_path, monkeypatch, "skatetrace.test_numba_cache")
    assert len(index) == 2 and len(set(index.values())) == 2
    assert loaded == [tuple(s) for s in sigs]  # each signature loads its own code
    assert list(tmp_path.rglob(numba_cache.LOCK_NAME))  # the lock file, beside the index


@pytest.mark.parametrize("module", ["elsewhere", "skatetrace_lookalike"])
def test_other_packages_saves_are_numbas_own(tmp_path, monkeypatch, module):
    """The race the guard prevents, shown on a function that is not skatetrace's: the second save read
    the index before the first wrote it back, and one signature is lost from it."""
    index, loaded, _ = _saved_side_by_side(tmp_path, monkeypatch, module)
    assert len(index) == 1
    assert loaded.count(None) == 1
    assert not list(tmp_path.rglob(numba_cache.LOCK_NAME))


@pytest.mark.parametrize("refused", ["open", "flock"])
def test_a_save_goes_on_where_the_lock_cannot_be_had(tmp_path, monkeypatch, refused):
    """A lock file that cannot be opened, or a file system that refuses locks: saved as numba saves."""
    monkeypatch.setattr(config, "CACHE_DIR", str(tmp_path))

    def refuse(*args, **kwargs):
        raise OSError("no locks here")

    if refused == "open":
        monkeypatch.setattr(numba_cache, "open", refuse, raising=False)
    else:
        monkeypatch.setattr(numba_cache.fcntl, "flock", refuse)

    def thrice(x):
        return 3 * x

    thrice.__module__ = "skatetrace.test_numba_cache"
    f = njit(thrice)
    f(2)
    ((sig, cres),) = f.overloads.items()
    cache = FunctionCache(f.py_func)
    cache.save_overload(sig, cres)
    assert tuple(cache.load_overload(sig, f.targetctx).signature.args) == tuple(sig)
