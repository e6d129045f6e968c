"""The C heap kept padded while IPOPT solves, so that MUMPS's workspace is not faulted in afresh at every factorisation.

IPOPT factorises its KKT system with MUMPS at every iteration (and again at each inertia
correction). MUMPS allocates its workspace for each factorisation and zeroes the part its fronts
use. glibc's ``malloc`` maps a block that large, or takes it from the top of the heap, and gives
it back to the system when it is freed; so every factorisation faults the same pages in again.
Measured on this project's 2-core machine (2026-11-28, ``perf stat`` and ``perf record``, a cold
``skatetrace trace school:paragraph-double-three --height 1.7 --no-plots --no-viewer``, whose
linked program has 5,048 unknowns): 409,000 page faults, 56 % of them in MUMPS's ``memset``
(``dmumps_fac_asm_niv1``), 1.2 s of system time. With the pad: 150,000 faults, 0.5 s, and the run
7.5 -> 6.8 s; the same ``controls.csv`` to the byte. (A pad of 64 MiB changed nothing there, 128 MiB
did: the pad must hold the workspace.)

:func:`padded` sets glibc's ``M_TOP_PAD`` (the memory ``malloc`` takes from the system beyond each
request that grows the heap, and keeps when it trims it) for the length of a ``with`` block, so
that a workspace freed to the top of the heap stays there, its pages resident, for the next
factorisation. The pad is address space: only the pages MUMPS touches become resident, and they
are resident during each factorisation anyway. Afterwards the pad is glibc's default again (128
KiB) and the heap is trimmed, so a library user's process does not keep the workspace.

Setting any of ``malloc``'s parameters stops glibc from adjusting its mmap and trim thresholds as
it goes; they would stay wherever they happened to be (as low as 128 KiB, and then every larger
array is mapped and faulted in afresh: measured, 25 % more faults on the school rocker). So the
block also sets them to where glibc's own adjustment settles, :data:`MMAP_THRESHOLD` and
:data:`TRIM_THRESHOLD`, and leaves them there. Where the C library is not glibc (no ``mallopt``
or no ``gnu_get_libc_version``: musl, macOS, Windows) the block does nothing.
"""

from __future__ import annotations

import contextlib
import ctypes
import ctypes.util
import functools

__all__ = ["PAD", "MMAP_THRESHOLD", "TRIM_THRESHOLD", "library", "padded"]

#: The heap's top pad while IPOPT solves, in bytes (address space; see the module's docstring).
PAD = 1 << 30
#: glibc's mmap and trim thresholds from the first :func:`padded` block on: where glibc's own
#: adjustment settles (``DEFAULT_MMAP_THRESHOLD_MAX`` on 64-bit systems, and twice that), which
#: setting the pad would otherwise freeze wherever it happened to be.
MMAP_THRESHOLD = 32 << 20
TRIM_THRESHOLD = 64 << 20

# glibc's mallopt parameters, and the top pad's default (DEFAULT_TOP_PAD, 128 KiB)
_M_TRIM_THRESHOLD, _M_TOP_PAD, _M_MMAP_THRESHOLD = -1, -2, -3
_DEFAULT_TOP_PAD = 128 * 1024


@functools.lru_cache(maxsize=1)
def library() -> ctypes.CDLL | None:
    """The process's C library when it is glibc (``mallopt`` and ``malloc_trim`` found), else None."""
    try:
        libc = ctypes.CDLL(ctypes.util.find_library("c") or None)
    except OSError:
        return None
    if not all(hasattr(libc, name) for name in ("gnu_get_libc_version", "mallopt", "malloc_trim")):
        return None
    libc.mallopt.argtypes = [ctypes.c_int, ctypes.c_int]
    libc.mallopt.restype = ctypes.c_int
    libc.malloc_trim.argtypes = [ctypes.c_size_t]
    libc.malloc_trim.restype = ctypes.c_int
    return libc


@contextlib.contextmanager
def padded(pad: int = PAD):
    """Within the ``with`` block, glibc's heap keeps ``pad`` bytes beyond its top; afterwards its default, trimmed.

    Parameters
    ----------
    pad : int
        Bytes of address space (:data:`PAD`, 1 GiB, by default); ``mallopt`` takes an ``int``.

    Raises
    ------
    ValueError
        If ``pad`` is not a whole number of bytes in ``[0, 2**31)``.
    """
    if not isinstance(pad, int) or isinstance(pad, bool) or not 0 <= pad < 1 << 31:
        raise ValueError(f"pad must be a whole number of bytes in [0, 2**31), got {pad!r}")
    libc = library()
    if libc is None or not libc.mallopt(_M_TOP_PAD, pad):
        yield
        return
    libc.mallopt(_M_MMAP_THRESHOLD, MMAP_THRESHOLD)
    libc.mallopt(_M_TRIM_THRESHOLD, TRIM_THRESHOLD)
    try:
        yield
    finally:
        libc.mallopt(_M_TOP_PAD, _DEFAULT_TOP_PAD)
        libc.malloc_trim(0)
