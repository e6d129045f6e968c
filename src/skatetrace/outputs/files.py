"""Files written atomically, with ordinary permissions, and JSON written strictly.

Every file is written to a temporary file in the same folder and then renamed, so an interrupted
run never leaves a half-written file behind. The file gets the permissions a plain ``open`` would
give it (``0o666`` less the process's umask), not the ``0600`` of the temporary file.

JSON is strict everywhere (:func:`dumps_json`): NaN and infinities are written as ``null``, never as
the bare ``NaN`` that JSON parsers other than Python's reject.

Whoever needs to know which files a run wrote (an :class:`~skatetrace.outputs.folder.OutputFolder`)
registers a callback with :func:`record_writes`; every atomic write calls it with the path written.
Whoever wants a run's files kept aside until the run is over (the same folder, to swap a run's files
in together) registers with :func:`stage_writes` where each file goes meanwhile; :func:`staged`
then tells where a file just written can be read.
"""

from __future__ import annotations

import contextlib
import contextvars
import json
import math
import os
import tempfile
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["atomic_write", "write_atomically", "temporary_pattern", "dumps_json", "json_safe", "file_mode",
           "record_writes", "stage_writes", "staged"]

# The callbacks told of every file written atomically (see record_writes), innermost last.
_RECORDERS: contextvars.ContextVar[tuple[Callable[[Path], None], ...]] = contextvars.ContextVar(
    "_RECORDERS", default=())
# Where files are written meanwhile (see stage_writes), innermost last.
_STAGES: contextvars.ContextVar[tuple[Callable[[Path], Path | None], ...]] = contextvars.ContextVar(
    "_STAGES", default=())


@contextlib.contextmanager
def record_writes(recorder: Callable[[Path], None]) -> Iterator[None]:
    """Within the ``with`` block, call ``recorder(path)`` after every file :func:`write_atomically` writes.

    Blocks nest (every active recorder is called); the registration is per thread and per task
    (a context variable).
    """
    token = _RECORDERS.set((*_RECORDERS.get(), recorder))
    try:
        yield
    finally:
        _RECORDERS.reset(token)


@contextlib.contextmanager
def stage_writes(stage: Callable[[Path], Path | None]) -> Iterator[None]:
    """Within the ``with`` block, :func:`write_atomically` writes ``path`` to ``stage(path)`` instead.

    ``stage`` returns None for a path it does not take (written where named). Recorders
    (:func:`record_writes`) are still told the path named, not the staged one. Blocks nest (the
    innermost that takes a path wins); the registration is per thread and per task.
    """
    token = _STAGES.set((*_STAGES.get(), stage))
    try:
        yield
    finally:
        _STAGES.reset(token)


def _target(path: Path) -> Path:
    for stage in reversed(_STAGES.get()):
        where = stage(path)
        if where is not None:
            return Path(where)
    return path


def staged(path: str | Path) -> Path:
    """Where the file written as ``path`` can be read now: its staged copy if it has one, else ``path``.

    For a command that reads back a file it wrote in the same run (the viewer reads ``result.json``
    and ``controls.csv``) while :func:`stage_writes` keeps the run's files aside.
    """
    path = Path(path)
    where = _target(path)
    return where if where != path and os.path.lexists(where) else path


def _umask() -> int:
    """The process's umask, read without changing it where the system allows (Linux: /proc)."""
    try:
        with open("/proc/self/status", encoding="ascii") as fh:
            for line in fh:
                if line.startswith("Umask:"):
                    return int(line.split()[1], 8)
    except (OSError, ValueError, IndexError):
        pass
    # Elsewhere the only way is to set it and put it back (process-wide, for an instant).
    old = os.umask(0o022)
    os.umask(old)
    return old


def file_mode() -> int:
    """The permissions a new file gets from ``open``: ``0o666`` less the umask (``0o644`` under umask 022)."""
    return 0o666 & ~_umask()


def temporary_pattern(path: str | Path) -> str:
    """The glob pattern of the temporary files :func:`write_atomically` writes next to ``path``.

    A process killed between writing one and renaming it onto ``path`` leaves it there.
    """
    prefix, suffix = _temporary_affixes(Path(path))
    return f"{prefix}*{suffix}"


def _temporary_affixes(path: Path) -> tuple[str, str]:
    """The prefix and suffix of :func:`write_atomically`'s temporary file for ``path`` (its suffix kept)."""
    return f".{path.stem}.", f".partial{path.suffix.lower()}"


def write_atomically(path: str | Path, write: Callable[[Path], None]) -> None:
    """Have ``write(tmp)`` write a temporary file next to ``path``, then rename it onto ``path``.

    The temporary name keeps ``path``'s suffix (writers that choose a format by it still can). On
    any failure, an interrupt included, the temporary file is removed and ``path`` is untouched.
    The file ends with the permissions of :func:`file_mode` (the temporary file is created ``0600``).
    Within :func:`stage_writes` the file goes where the stage says instead.
    """
    path = Path(path)
    target = _target(path)
    target.parent.mkdir(parents=True, exist_ok=True)
    prefix, suffix = _temporary_affixes(path)
    fd, tmp = tempfile.mkstemp(prefix=prefix, suffix=suffix, dir=target.parent)
    os.close(fd)
    try:
        write(Path(tmp))
        os.chmod(tmp, file_mode())
        os.replace(tmp, target)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise
    for recorder in _RECORDERS.get():
        recorder(path)


def atomic_write(path: str | Path, data: str | bytes) -> None:
    """Write ``data`` (text as UTF-8) to ``path`` through a temporary file and an atomic rename."""
    if isinstance(data, bytes):
        write_atomically(path, lambda tmp: tmp.write_bytes(data))
    else:
        write_atomically(path, lambda tmp: tmp.write_text(data, encoding="utf-8", newline=""))


def json_safe(obj: Any, *, nonfinite: Callable[[float], Any] | None = None,
              other: Callable[[Any], Any] | None = None) -> Any:
    """JSON-safe copy: numpy scalars and arrays made Python ones, non-finite floats replaced.

    Parameters
    ----------
    obj : Any
        Nested dicts, lists, tuples, numpy arrays and scalars.
    nonfinite : callable, optional
        What a NaN or an infinity becomes, from its value; default ``None`` (JSON ``null``).
    other : callable, optional
        What a value JSON cannot hold (a set, an object) becomes; default: left as it is, so that
        ``json.dumps`` refuses it.

    Examples
    --------
    >>> json_safe({"a": np.float64(float("inf")), 1: (np.int64(2), np.bool_(True))})
    {'a': None, '1': [2, True]}
    """
    if isinstance(obj, dict):
        return {str(k): json_safe(v, nonfinite=nonfinite, other=other) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [json_safe(v, nonfinite=nonfinite, other=other) for v in obj]
    if isinstance(obj, np.ndarray):
        return json_safe(obj.tolist(), nonfinite=nonfinite, other=other)
    if isinstance(obj, (bool, np.bool_)):
        return bool(obj)
    if isinstance(obj, (int, np.integer)):
        return int(obj)
    if isinstance(obj, (np.floating, float)):
        v = float(obj)
        if math.isfinite(v):
            return v
        return None if nonfinite is None else nonfinite(v)
    if other is None or obj is None or isinstance(obj, str):
        return obj
    return other(obj)


def dumps_json(obj: Any, *, indent: int | None = 2) -> str:
    """``obj`` as strict JSON: numpy values made Python ones, NaN and infinities written as ``null``.

    Raises
    ------
    TypeError
        A value JSON cannot represent (a set, an object).

    Examples
    --------
    >>> dumps_json({"a": float("nan"), "b": [np.float64(1.5), float("inf")]}, indent=None)
    '{"a": null, "b": [1.5, null]}'
    """
    return json.dumps(json_safe(obj), indent=indent, allow_nan=False)
