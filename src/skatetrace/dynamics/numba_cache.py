"""Numba's on-disk cache made safe for processes that compile at the same time.

Numba keeps a compiled function's machine code in its cache in two kinds of files: an index per
function (which signature is in which data file) and a data file per signature. To save a new
signature it reads the index, gives the signature the first data file name not in it, writes the
index back and then the data file, with no lock. Two processes that compile *different* signatures
of one function at once can both read the index before either writes it. Both then take the same
file name, one signature drops out of the index, and the data file may hold the other's code.
A later run would load that code for the signature left in the index, and run a function compiled
for other argument types (numba issue 4807 reports the segfaults of such races).

skatetrace's processes compile at the same time on purpose:
- a first run's verification compiles alongside its trace (:func:`skatetrace.cli.compiled.compile_ahead`);
- the planner's and the tracer's workers compile in parallel;
- the parts for later runs compile in a background job (:func:`skatetrace.cli.compiled.compile_later`).

They share compiled helpers with different argument types. For example, the Runge-Kutta steps of
:mod:`.dop853` are compiled once for the manoeuvre integrator and once for the verifying replay
(``interpolate_into`` takes a contiguous array in one and any array in the other). So
:func:`guard_saves` makes every save of one of skatetrace's functions hold an exclusive lock
(``flock``) on a file in the cache's folder while it reads and writes the index and the data. Saves
of one folder then happen one after another, and each finds the signatures saved before it. Loading
needs no lock: numba writes each file under a temporary name and renames it into place. Other
packages' functions are saved as numba saves them.
"""

from __future__ import annotations

import contextlib
import functools
import os

try:
    import fcntl
except ImportError:  # pragma: no cover - not POSIX: saves stay as numba makes them
    fcntl = None

__all__ = ["LOCK_NAME", "guard_saves"]

#: The lock file that :func:`guard_saves` creates in each folder of numba's cache where skatetrace saves.
LOCK_NAME = "skatetrace-numba-cache.lock"


def _ours(cache) -> bool:
    """Whether ``cache`` (a numba ``Cache``) is one of skatetrace's functions'."""
    module = getattr(getattr(cache, "_py_func", None), "__module__", None) or ""
    return module == "skatetrace" or module.startswith("skatetrace.")


def guard_saves() -> None:
    """Make numba's saves of skatetrace's compiled functions hold a lock on their cache folder (see the module).

    Idempotent: called by each module that compiles with ``cache=True`` (through the modules it
    imports), it wraps ``numba.core.caching.Cache.save_overload`` once per process. A save whose
    lock file cannot be opened (a read-only folder: numba then saves nothing there either) goes
    on as numba's own, and so does one where the file system refuses the lock.
    """
    from numba.core.caching import Cache

    if fcntl is None or getattr(Cache.save_overload, "_skatetrace_guarded", False):
        return
    unguarded = Cache.save_overload

    @functools.wraps(unguarded)
    def save_overload(self, sig, data):
        if not _ours(self):
            return unguarded(self, sig, data)
        try:
            self._impl.locator.ensure_cache_path()
            lock = open(os.path.join(self._cache_path, LOCK_NAME), "a+b")
        except OSError:
            return unguarded(self, sig, data)
        with lock:  # closing the file releases the lock
            with contextlib.suppress(OSError):  # a file system without locks: saved as numba saves
                fcntl.flock(lock, fcntl.LOCK_EX)
            return unguarded(self, sig, data)

    save_overload._skatetrace_guarded = True
    Cache.save_overload = save_overload
