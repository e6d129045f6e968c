"""CasADi functions compiled to machine code by the system's C compiler, kept in a cache on disk.

IPOPT spends about half of a plan's time evaluating the collocation blocks' derivatives (the
Hessian of one interval is some 20,000 instructions of CasADi's virtual machine, run for every
interval at every iteration). :func:`native` generates C for such a function, compiles it once
with ``cc -O1`` into a shared library named by a hash of the function, and loads it as a CasADi
external: eleven times faster for the Hessian, the same numbers (CasADi's generated code performs
the virtual machine's operations in its order; the tests compare them).

Compiling the Hessian with ``-O1`` takes about 3 s, on a plan's path the first time a skater is
planned. So a function not yet in the cache is first compiled with ``-O0`` (0.65 s; its code 2.7
times slower than ``-O1``'s, and the same numbers, since neither level reorders or contracts
floating-point operations), loaded at once, and compiled with ``-O1`` by a background job at the
lowest priority, which outlives the run if it must; a later plan finds the ``-O1`` library and
loads it instead. Measured from a cold command line with an empty cache (two runs each): the
paragraph double three's first run 6.9-7.2 s -> 5.1-5.4 s, the three's 5.0-5.3 -> 3.2-3.3 s; the
runs after them the same as before (4.1-4.2 s and 2.2 s). The job stays in the run's session:
a session of its own would be a scheduling group of its own on Linux, where its priority no
longer yields to the run's (the three's first run then took 5.2 s).

The cache is ``$SKATETRACE_CACHE_DIR/casadi-<version>`` or ``~/.cache/skatetrace/casadi-<version>``;
a library is written under a temporary name and renamed into place, and locks keep two processes
(the planner's workers) from compiling the same function at once, in the run or in the
background. The masses and the planner's options are constants of the blocks, so each skater
compiles once, and every later plan for that skater loads the library. (Made inputs instead, they
would serve every skater, but change the expressions' rounding, and IPOPT's path with it: plans
would move.)

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
import time
from pathlib import Path

import casadi as ca

from ..processes import recording_interrupts

try:
    import fcntl
except ImportError:  # pragma: no cover - platforms without POSIX locks: two processes may compile alike
    fcntl = None

__all__ = ["native", "cache_dir", "compiler"]

#: Optimisation of the generated code: -O1 evaluates the Hessian block 2.7 times faster than -O0
#: (3.9 against 10.3 us an interval; the virtual machine some 45 us), and compiling it takes 2.9 s,
#: against 0.65 s. Neither level reorders or contracts floating-point operations: the same numbers.
FLAGS = ("-O1", "-ffp-contract=off", "-shared", "-fPIC")
#: The first build, loaded at once while :data:`FLAGS`' compiles in the background.
QUICK_FLAGS = ("-O0", "-ffp-contract=off", "-shared", "-fPIC")
#: A compiler that takes longer than this is abandoned (the function stays interpreted).
TIMEOUT = 120.0
#: A job's folder older than this (seconds) is a job's that was killed before it could remove it.
STALE = 3600.0


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
    h.update("\0".join((cc, *FLAGS, *QUICK_FLAGS, ca.__version__, sys.platform, platform.machine())).encode())
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


def _generate(fn: ca.Function, name: str, folder: str) -> Path:
    """Write C for ``fn``, exported as ``name``, into ``folder``; returns the file."""
    renamed = ca.Function(name, fn.sx_in(), fn.call(fn.sx_in()), fn.name_in(), fn.name_out())
    gen = ca.CodeGenerator(f"{name}.c", {"with_header": False})
    gen.add(renamed)
    gen.generate(folder + os.sep)
    return Path(folder) / f"{name}.c"


def _build(fn: ca.Function, name: str, library: Path, cc: str) -> None:
    """Generate C for ``fn`` (exported as ``name``) and compile it with :data:`QUICK_FLAGS` into ``library``."""
    with tempfile.TemporaryDirectory(dir=library.parent) as tmp:
        source = _generate(fn, name, tmp)
        out = Path(tmp) / f"{name}.so"
        subprocess.run([cc, *QUICK_FLAGS, str(source), "-o", str(out)], check=True,
                       stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, timeout=TIMEOUT)
        os.replace(out, library)


def _sweep(folder: Path) -> None:
    """Remove the folders killed jobs left in the cache, older than :data:`STALE`."""
    now = time.time()
    for path in folder.glob("tmp*"):
        with contextlib.suppress(OSError):
            if path.is_dir() and now - path.stat().st_mtime > STALE:
                shutil.rmtree(path, ignore_errors=True)


def _upgrade(fn: ca.Function, name: str, library: Path, cc: str) -> bool:
    """Compile ``fn`` with :data:`FLAGS` into ``library`` in a background job; whether one was started.

    Not where the library is there, another process is compiling it (its lock is taken), or
    there is no shell to run the job. The job holds the lock (inherited) until it ends, renames
    its library into place where the compiler succeeds, and removes its folder. It runs at the
    lowest priority for at most :data:`TIMEOUT`, ignores Ctrl-C, and outlives this process if it
    must: the shell that starts it ends at once (waited for), so no child is left to this process
    (a job killed leaves its folder, which a later job sweeps away, and the next plan for the skater
    starts another).
    """
    sh = shutil.which("sh")
    if fcntl is None or sh is None:  # pragma: no cover - not POSIX
        return False
    with open(library.parent / f"{name}.lock", "a+b") as lock:  # the job keeps its own copy, and the lock
        try:
            fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            return False  # compiling now, in another process
        if library.exists():
            return False
        _sweep(library.parent)
        tmp = tempfile.mkdtemp(dir=library.parent)
        try:
            source = _generate(fn, name, tmp)
            out = Path(tmp) / f"{name}.so"
            command = [cc, *FLAGS, str(source), "-o", str(out)]
            for prefix in (["timeout", str(int(TIMEOUT))], ["nice", "-n", "19"]):
                if shutil.which(prefix[0]):
                    command = prefix + command
            job = '("$@" && mv -f "$SKATETRACE_OUT" "$SKATETRACE_LIBRARY"; rm -rf "$SKATETRACE_TMP")'
            env = dict(os.environ, SKATETRACE_OUT=str(out), SKATETRACE_LIBRARY=str(library), SKATETRACE_TMP=tmp)
            subprocess.run([sh, "-c", f'trap "" INT; {job} &', "sh", *command], env=env, pass_fds=(lock.fileno(),),
                           stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                           check=True, timeout=TIMEOUT)
            return True
        except BaseException:
            shutil.rmtree(tmp, ignore_errors=True)
            raise


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
        library, quick = folder / f"{name}.so", folder / f"{name}-quick.so"
        for attempt in range(2):
            path = library
            if not library.exists():
                path = quick
                if not quick.exists():
                    folder.mkdir(parents=True, exist_ok=True)
                    with _locked(folder / f"{name}-quick.lock"):
                        if not quick.exists():  # another process may have compiled it meanwhile
                            _build(fn, f"{name}_quick", quick, cc)
                with contextlib.suppress(OSError, RuntimeError, subprocess.SubprocessError):
                    _upgrade(fn, name, library, cc)  # for the next plan: this one goes on with the quick build
            try:
                loaded = ca.external(name if path == library else f"{name}_quick", str(path))
                break
            except RuntimeError:
                if attempt:
                    raise
                path.unlink(missing_ok=True)  # a damaged library (a disk full, say): compiled again
    except (OSError, RuntimeError, subprocess.SubprocessError):
        return fn
    return loaded
