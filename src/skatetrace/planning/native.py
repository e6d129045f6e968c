"""CasADi functions compiled to machine code by the system's C compiler, kept in a cache on disk.

IPOPT spends about half of a plan's time evaluating the collocation blocks' derivatives (the
Hessian of one interval is some 20,000 instructions of CasADi's virtual machine, run for every
interval at every iteration). :func:`native` generates C for such a function, compiles it once
with ``cc -O1`` into a shared library named by a hash of the function, and loads it as a CasADi
external: eleven times faster for the Hessian, the same numbers (CasADi's generated code performs
the virtual machine's operations in its order; the tests compare them).

The cache is ``$SKATETRACE_CACHE_DIR/casadi-<version>`` or ``~/.cache/skatetrace/casadi-<version>``;
a library is written under a temporary name and renamed into place, and a lock keeps two
processes (the planner's workers) from compiling the same function at once. The masses and the
planner's options are constants of the blocks, so each skater compiles once (about 5 s), and
every later plan for that skater loads the library. (Made inputs instead, they would serve every
skater, but change the expressions' rounding, and IPOPT's path with it: plans would move.)

Where there is no C compiler, the cache cannot be written, or compiling fails, the function is
returned as it was and evaluated by CasADi's virtual machine: slower, never wrong (a damaged
library is compiled again). ``SKATETRACE_NATIVE=0`` turns compiling off.
"""

from __future__ import annotations

import contextlib
import hashlib
import os
import platform
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import casadi as ca

from ..processes import recording_interrupts

try:
    import fcntl
except ImportError:  # pragma: no cover - platforms without POSIX locks: two processes may compile alike
    fcntl = None

__all__ = ["native", "cache_dir", "compiler"]

#: Optimisation of the generated code: -O1 evaluates the Hessian block 3.4 times faster than -O0
#: (0.40 against 1.29 ms for 36 intervals; the virtual machine 4.4 ms), and compiling it takes 4 s
#: once, against 0.7 s.
FLAGS = ("-O1", "-ffp-contract=off", "-shared", "-fPIC")
#: A compiler that takes longer than this is abandoned (the function stays interpreted).
TIMEOUT = 120.0


def compiler() -> str | None:
    """The C compiler to use: ``$CC`` if set, else ``cc``, ``gcc`` or ``clang`` on the PATH; None if there is none."""
    names = [os.environ["CC"]] if os.environ.get("CC") else ["cc", "gcc", "clang"]
    for name in names:
        path = shutil.which(name)
        if path:
            return path
    return None


def cache_dir() -> Path:
    """Where compiled functions are kept (see the module docstring)."""
    root = os.environ.get("SKATETRACE_CACHE_DIR")
    base = Path(root) if root else Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "skatetrace"
    return base / f"casadi-{ca.__version__}"


def _enabled() -> bool:
    return os.environ.get("SKATETRACE_NATIVE", "1").strip().lower() not in ("0", "no", "false", "off")


def _key(fn: ca.Function, cc: str) -> str:
    h = hashlib.sha256(fn.serialize().encode())
    # the machine too: a home folder shared by an x86-64 and an ARM machine keeps both libraries
    h.update("\0".join((cc, *FLAGS, ca.__version__, sys.platform, platform.machine())).encode())
    return h.hexdigest()[:24]


@contextlib.contextmanager
def _locked(path: Path):
    with open(path, "a+b") as fh:
        if fcntl is None:  # pragma: no cover
            yield
            return
        fcntl.flock(fh, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(fh, fcntl.LOCK_UN)


def _build(fn: ca.Function, name: str, library: Path, cc: str) -> None:
    """Generate C for ``fn`` (exported as ``name``) and compile it into ``library``, atomically."""
    with tempfile.TemporaryDirectory(dir=library.parent) as tmp:
        renamed = ca.Function(name, fn.sx_in(), fn.call(fn.sx_in()), fn.name_in(), fn.name_out())
        gen = ca.CodeGenerator(f"{name}.c", {"with_header": False})
        gen.add(renamed)
        gen.generate(tmp + os.sep)
        out = Path(tmp) / f"{name}.so"
        subprocess.run([cc, *FLAGS, str(Path(tmp) / f"{name}.c"), "-o", str(out)], check=True,
                       stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, timeout=TIMEOUT)
        os.replace(out, library)


def native(fn: ca.Function) -> ca.Function:
    """``fn`` compiled to machine code (from the cache, or compiled into it now), or ``fn`` itself where it cannot be.

    Parameters
    ----------
    fn : casadi.Function
        A function of SX expressions (an MX function is returned as it is).

    Returns
    -------
    casadi.Function
        The same inputs and outputs, evaluated by compiled code or, failing that, by ``fn``.
    """
    cc = compiler() if _enabled() else None
    if cc is None or not fn.is_a("SXFunction"):
        return fn
    with recording_interrupts() as caught:
        loaded = _native(fn, cc)
    if caught:  # Ctrl-C while CasADi generated or loaded code, which may have made it a RuntimeError
        raise KeyboardInterrupt
    if loaded.n_in() != fn.n_in() or loaded.n_out() != fn.n_out():  # pragma: no cover - a foreign file
        return fn
    return loaded


def _native(fn: ca.Function, cc: str) -> ca.Function:
    try:
        key = _key(fn, cc)
        name = f"st_{key}"  # a name of its own: libraries loaded side by side never share a symbol
        folder = cache_dir()  # (RuntimeError where no home folder can be found)
        library = folder / f"{name}.so"
        for attempt in range(2):
            if not library.exists():
                folder.mkdir(parents=True, exist_ok=True)
                with _locked(folder / f"{name}.lock"):
                    if not library.exists():  # another process may have compiled it meanwhile
                        _build(fn, name, library, cc)
            try:
                loaded = ca.external(name, str(library))
                break
            except RuntimeError:
                if attempt:
                    raise
                library.unlink(missing_ok=True)  # a damaged library (a disk full, say): compiled again
    except (OSError, RuntimeError, subprocess.SubprocessError):
        return fn
    return loaded
