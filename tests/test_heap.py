"""While IPOPT solves, glibc's heap keeps a pad beyond its top, so freed workspace is not faulted in again."""

import contextlib
import platform
import subprocess
import sys

import numpy as np
import pytest

from skatetrace.planning import heap

GLIBC = sys.platform.startswith("linux") and platform.libc_ver()[0] == "glibc"
needs_glibc = pytest.mark.skipif(not GLIBC, reason="the pad is glibc's (mallopt)")


@needs_glibc
def test_glibc_is_found():
    assert heap.library() is not None


class _FakeLibc:
    def __init__(self, accepts=True):
        self.calls, self.accepts = [], accepts

    def mallopt(self, param, value):
        self.calls.append(("mallopt", param, value))
        return 1 if self.accepts else 0

    def malloc_trim(self, pad):
        self.calls.append(("malloc_trim", pad))
        return 1


def test_the_pad_is_set_for_the_block_and_the_default_restored_after_even_on_an_error(monkeypatch):
    fake = _FakeLibc()
    monkeypatch.setattr(heap, "library", lambda: fake)
    inside = [("mallopt", -2, heap.PAD), ("mallopt", -3, heap.MMAP_THRESHOLD), ("mallopt", -1, heap.TRIM_THRESHOLD)]
    after = [("mallopt", -2, 128 * 1024), ("malloc_trim", 0)]
    with heap.padded():
        assert fake.calls == inside
    assert fake.calls == inside + after
    fake.calls.clear()
    with pytest.raises(RuntimeError), heap.padded(1 << 20):
        raise RuntimeError("a failed solve")
    assert fake.calls == [("mallopt", -2, 1 << 20)] + inside[1:] + after


def test_nothing_else_is_touched_where_the_pad_is_refused(monkeypatch):
    fake = _FakeLibc(accepts=False)
    monkeypatch.setattr(heap, "library", lambda: fake)
    with heap.padded():
        pass
    assert fake.calls == [("mallopt", -2, heap.PAD)]


@pytest.mark.parametrize("pad", [-1, 1 << 31, 1.5, True, "1GiB", None])
def test_a_pad_that_is_not_a_number_of_bytes_mallopt_takes_is_refused(pad):
    with pytest.raises(ValueError, match="pad must be a whole number of bytes"):
        with heap.padded(pad):
            pass


def test_a_program_is_solved_where_the_c_library_is_not_glibc(monkeypatch, small_program):
    monkeypatch.setattr(heap, "library", lambda: None)
    np.testing.assert_allclose(small_program(), [1.0, -2.0], atol=1e-6)


def test_the_pad_changes_no_digit_of_a_solve(monkeypatch, small_program):
    padded = small_program()
    monkeypatch.setattr("skatetrace.planning.nlp.padded", contextlib.nullcontext)
    assert np.array_equal(padded, small_program())


# Six workspaces of 64 MiB, each written through and freed, as MUMPS does at every factorisation.
# A block of 31 MiB (under the mmap threshold) first makes the heap grow, which is when glibc adds
# the pad. Prints the page faults of the six.
_FAULTS = """
import contextlib, ctypes, resource, sys
from skatetrace.planning import heap
libc = ctypes.CDLL(None)
libc.malloc.restype = ctypes.c_void_p
libc.malloc.argtypes = [ctypes.c_size_t]
libc.free.argtypes = [ctypes.c_void_p]
size = 64 << 20
with heap.padded() if sys.argv[1] == "padded" else contextlib.nullcontext():
    libc.free(libc.malloc(31 << 20))
    before = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
    for _ in range(6):
        p = libc.malloc(size)
        ctypes.memset(p, 1, size)
        libc.free(p)
    print(resource.getrusage(resource.RUSAGE_SELF).ru_minflt - before)
"""


@needs_glibc
def test_freed_workspace_is_not_faulted_in_again_inside_the_block():
    # The robust fact, not a count: without the pad each workspace is mapped afresh and faulted
    # in page by page (or huge page by huge page); with it, the first is kept for the next five.
    faults = {}
    for mode in ("plain", "padded"):
        out = subprocess.run([sys.executable, "-c", _FAULTS, mode], capture_output=True, text=True, check=True)
        faults[mode] = int(out.stdout.split()[-1])
    assert faults["padded"] * 3 < faults["plain"], faults
