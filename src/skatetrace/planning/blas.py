"""CasADi's own OpenBLAS, which MUMPS factorises IPOPT's systems with, held to one thread while the planner solves.

CasADi's wheels bundle an OpenBLAS of their own (``libcasadi-tp-openblas``), separate from
numpy's, that starts as many threads as the machine has cores unless ``OPENBLAS_NUM_THREADS``
says otherwise. MUMPS calls it on small dense fronts, where a second thread only waits; and the
planner already solves its independent programs in one process per core
(:mod:`skatetrace.planning.pool`), so two threads each oversubscribe the machine. Measured on this
project's 2-core machine (2026-11-27, the 24 planned corpus drawings and 17 school figures under
the command line's default reach, one sitting each): 232 s with the library's default of two
threads, 208 s with one; heroicons-paper-airplane 13.8 s against 9.9 s.

The thread count also changes the round-off of the factorisations, and IPOPT's path with it:
svgpathtools-negative-scale took 202 iterations in its programs with two threads and 292 with one.
Held to one thread, a plan is the same on a machine of any number of cores.

:func:`one_thread` sets the count to one for the length of a ``with`` block and restores what was
there; where the library cannot be found (a CasADi built without it, another platform's file
names), it does nothing.
"""

from __future__ import annotations

import contextlib
import ctypes
import functools
import re
from pathlib import Path

import casadi as ca

__all__ = ["one_thread", "library"]

#: The file names of CasADi's OpenBLAS: its soname first (the file its other libraries load), then
#: the other copies the wheel ships under other names.
_NAMES = re.compile(r"^(lib)?casadi-tp-openblas(\.so\.\d+|\.\d+\.dylib|\.dylib|\.dll|\.so)$")


def _candidates(folder: Path) -> list[Path]:
    """CasADi's OpenBLAS files in ``folder``, the soname-like names (``.so.N``) first."""
    found = [p for p in folder.iterdir() if _NAMES.match(p.name)]
    return sorted(found, key=lambda p: (not re.search(r"\.so\.\d+$", p.name), p.name))


@functools.lru_cache(maxsize=1)
def library() -> ctypes.CDLL | None:
    """CasADi's OpenBLAS, loaded (the instance its IPOPT uses), or None where it cannot be found."""
    try:
        folder = Path(ca.__file__).resolve().parent
        for path in _candidates(folder):
            try:
                lib = ctypes.CDLL(str(path))
            except OSError:
                continue
            if hasattr(lib, "openblas_set_num_threads") and hasattr(lib, "openblas_get_num_threads"):
                lib.openblas_get_num_threads.restype = ctypes.c_int
                lib.openblas_set_num_threads.argtypes = [ctypes.c_int]
                return lib
    except OSError:
        return None
    return None


@contextlib.contextmanager
def one_thread():
    """Within the ``with`` block, CasADi's OpenBLAS runs on one thread; afterwards as many as before."""
    lib = library()
    if lib is None:
        yield
        return
    before = int(lib.openblas_get_num_threads())
    if before != 1:
        lib.openblas_set_num_threads(1)
    try:
        yield
    finally:
        if before != 1:
            lib.openblas_set_num_threads(before)
