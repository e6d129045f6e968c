"""CasADi's own OpenBLAS is found, held to one thread while IPOPT solves, and given back as it was."""

import subprocess
import sys
from pathlib import Path

import casadi as ca
import numpy as np
import pytest

from skatetrace.planning import blas

CASADI = Path(ca.__file__).resolve().parent
SHIPPED = any("openblas" in p.name for p in CASADI.iterdir())
needs_lib = pytest.mark.skipif(not SHIPPED, reason="this CasADi ships no OpenBLAS of its own")


@needs_lib
def test_the_library_shipped_with_casadi_is_found():
    lib = blas.library()
    assert lib is not None, f"{CASADI} has an OpenBLAS, yet it was not found"
    assert lib.openblas_get_num_threads() >= 1


@needs_lib
def test_one_thread_inside_the_block_and_the_count_restored_after():
    lib = blas.library()
    before = lib.openblas_get_num_threads()
    lib.openblas_set_num_threads(3)
    try:
        with blas.one_thread():
            assert lib.openblas_get_num_threads() == 1
        assert lib.openblas_get_num_threads() == 3
        with pytest.raises(RuntimeError), blas.one_thread():
            raise RuntimeError("a failed solve")
        assert lib.openblas_get_num_threads() == 3
    finally:
        lib.openblas_set_num_threads(before)


def test_the_soname_is_preferred_over_the_copies(tmp_path):
    for name in ("libcasadi-tp-openblas.so", "libcasadi-tp-openblas.so.0.3", "libcasadi-tp-openblas.so.0",
                 "libcasadi_nlpsol_ipopt.so", "libopenblas.so.0"):
        (tmp_path / name).write_bytes(b"")
    names = [p.name for p in blas._candidates(tmp_path)]
    assert names == ["libcasadi-tp-openblas.so.0", "libcasadi-tp-openblas.so"]


def test_a_program_is_solved_where_there_is_no_library(monkeypatch, small_program):
    monkeypatch.setattr(blas, "library", lambda: None)
    np.testing.assert_allclose(small_program(), [1.0, -2.0], atol=1e-6)


_ONE_INSTANCE = """
import sys
from pathlib import Path
from skatetrace.planning import blas
from skatetrace.planning.nlp import SparseProgram
def solve():
    prog = SparseProgram(1)
    prog.minimize((prog.x[0] - 1.0) ** 2)
    assert prog.solve({"print_time": False, "ipopt.print_level": 0, "ipopt.sb": "yes"}).success
if sys.argv[1] == "ipopt first":
    solve()
    lib = blas.library()
else:
    lib = blas.library()
    solve()
mapped = {line.split()[-1] for line in Path("/proc/self/maps").read_text().splitlines() if "casadi-tp-openblas" in line}
print(len(mapped), lib is not None)
"""


@needs_lib
@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc/self/maps")
@pytest.mark.parametrize("order", ["ipopt first", "library first"])
def test_the_instance_held_is_the_one_ipopt_runs_on(order):
    # The wheel ships copies of the library under three names: had another copy been loaded,
    # IPOPT would run on a second instance, whose threads one_thread never touches.
    out = subprocess.run([sys.executable, "-c", _ONE_INSTANCE, order], capture_output=True, text=True, check=True)
    assert out.stdout.split() == ["1", "True"], out.stdout + out.stderr


@needs_lib
def test_a_solve_leaves_the_thread_count_as_it_found_it(small_program):
    lib = blas.library()
    before = lib.openblas_get_num_threads()
    np.testing.assert_allclose(small_program(), [1.0, -2.0], atol=1e-6)
    assert lib.openblas_get_num_threads() == before
