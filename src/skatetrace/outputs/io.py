"""Writing results: ``result.json``, ``controls.csv``, ``report.json``, written atomically.

Every file is written to a temporary file in the same folder and then renamed, so an interrupted
run never leaves a half-written result behind. The file gets the permissions a plain ``open`` would
give it (``0o666`` less the process's umask), not the ``0600`` of the temporary file.

JSON is strict everywhere (:func:`dumps_json`): NaN and infinities are written as ``null``, never as
the bare ``NaN`` that JSON parsers other than Python's reject.

An output folder (:class:`OutputFolder`) is checked before any work and keeps a manifest,
``.skatetrace-manifest.json``, of the files skatetrace wrote there; a later run into the same folder
removes the files of that list it does not write again, so a folder never mixes two runs' files.
Files skatetrace did not write are never touched.
"""

from __future__ import annotations

import contextvars
import csv
import json
from dataclasses import asdict
import math
import os
import tempfile
from pathlib import Path, PurePosixPath
from typing import Any, Callable

import numpy as np

from ..dynamics.controls import ControlSchedule
from ..errors import SkatetraceError
from ..verification.feasibility import Feasibility
from ..tracing.sections import FigureTrace
from ..verification.verify import VerificationReport

__all__ = ["SCHEMA_VERSION", "CSV_COLUMNS", "MANIFEST", "atomic_write", "write_atomically", "dumps_json",
           "file_mode", "check_output_folder", "check_output_file", "OutputFolder", "adopt", "result_dict",
           "write_results", "load_result", "read_controls"]

SCHEMA_VERSION = "skatetrace.result/1"
CSV_COLUMNS = ("piece", "t", "a", "b", "adot", "bdot", "x", "y", "theta", "p1", "p2", "xi1", "xi2")

#: The list of files skatetrace wrote into an output folder (see :class:`OutputFolder`).
MANIFEST = ".skatetrace-manifest.json"
_MANIFEST_SCHEMA = "skatetrace.manifest/1"

# The output folders whose writes are being recorded (see OutputFolder), innermost last.
_RECORDERS: contextvars.ContextVar[tuple["OutputFolder", ...]] = contextvars.ContextVar("_RECORDERS", default=())


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


def write_atomically(path: str | Path, write: Callable[[Path], None]) -> None:
    """Have ``write(tmp)`` write a temporary file next to ``path``, then rename it onto ``path``.

    The temporary name keeps ``path``'s suffix (writers that choose a format by it still can). On
    any failure, an interrupt included, the temporary file is removed and ``path`` is untouched.
    The file ends with the permissions of :func:`file_mode` (the temporary file is created ``0600``).
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.stem}.", suffix=f".partial{path.suffix.lower()}", dir=path.parent)
    os.close(fd)
    try:
        write(Path(tmp))
        os.chmod(tmp, file_mode())
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise
    for folder in _RECORDERS.get():
        folder._record(path)


def atomic_write(path: str | Path, data: str | bytes) -> None:
    """Write ``data`` (text as UTF-8) to ``path`` through a temporary file and an atomic rename."""
    if isinstance(data, bytes):
        write_atomically(path, lambda tmp: tmp.write_bytes(data))
    else:
        write_atomically(path, lambda tmp: tmp.write_text(data, encoding="utf-8", newline=""))


def _clean(obj: Any) -> Any:
    """JSON-safe copy: numpy scalars and arrays to Python, non-finite floats to None."""
    if isinstance(obj, dict):
        return {str(k): _clean(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_clean(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return _clean(obj.tolist())
    if isinstance(obj, (np.floating, float)):
        v = float(obj)
        return v if math.isfinite(v) else None
    if isinstance(obj, (np.integer,)):
        return int(obj)
    if isinstance(obj, np.bool_):
        return bool(obj)
    return obj


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
    return json.dumps(_clean(obj), indent=indent, allow_nan=False)


_STATE_KEYS = ("p1", "p2", "theta", "x", "y", "a", "b", "adot", "bdot", "xi1", "xi2")


def result_dict(trace: FigureTrace) -> dict[str, Any]:
    """Everything needed to understand and reproduce a traced figure, as plain data.

    Per section: its pieces, each with the time it starts and the state there; the phases with
    their controls; the join (cusp, pivot) before it; residuals, metrics and status.
    """
    sections = []
    for sec, t0 in zip(trace.sections, trace.start_times):
        d = sec.to_dict()
        d["start_time"] = t0
        pieces = []
        starts = np.cumsum([0.0] + [p.segment.length for p in sec.section.pieces[:-1]])
        if sec.phases:
            times = sec.time_at_length(starts)
            times[0] = 0.0
            states = sec.evaluate(times)
        for i, p in enumerate(sec.section.pieces):
            entry: dict[str, Any] = {"index": p.index, "curvature": p.segment.coefficients[0],
                                     "length": p.segment.length, "direction": p.direction}
            if not p.segment.constant:
                entry["curvature"] = None
                entry["curvature_coefficients"] = list(p.segment.coefficients)
            if sec.phases:
                entry["start_time"] = t0 + float(times[i])
                entry["initial_state"] = {k: float(states[k][i]) for k in _STATE_KEYS}
            pieces.append(entry)
        d["pieces"] = pieces
        join = sec.section.pieces[0].join_before
        d["join_before"] = join.to_dict() if join is not None else None
        sections.append(d)
    curves = []
    for c in trace.figure.curves:
        centre = c.unit_centre() if c.repeat > 1 or c.closing is not None else None
        curves.append({"name": c.name, "closure": c.closure(), "repeat_centre": centre})
    return _clean({
        "schema": SCHEMA_VERSION,
        "success": trace.success, "status": trace.status, "message": trace.message,
        "params": trace.params.to_dict(),
        "options": asdict(trace.options),  # every setting of the tracer, so that a run can be repeated
        "figure": trace.figure.to_dict(),
        "curves": curves,
        "duration": trace.duration,
        "sections": sections,
    })


def _csv_text(schedule: ControlSchedule, states: dict[str, np.ndarray]) -> str:
    """``controls.csv``: floats as their shortest round-trip ``repr``, one column at a time."""
    cols = {"piece": schedule.piece, "t": schedule.t, "a": schedule.a, "b": schedule.b,
            "adot": schedule.adot, "bdot": schedule.bdot, **states}
    text = [list(map(str, np.asarray(cols["piece"], dtype=int).tolist()))]
    text += [list(map(repr, np.asarray(cols[k], dtype=float).tolist())) for k in CSV_COLUMNS[1:]]
    return "\n".join([",".join(CSV_COLUMNS), *map(",".join, zip(*text))]) + "\n"


def write_results(out: str | Path, trace: FigureTrace, schedule: ControlSchedule,
                  states: dict[str, np.ndarray], report: VerificationReport | None, unit: str = "model",
                  feasibility: Feasibility | None = None) -> list[Path]:
    """Write ``result.json``, ``controls.csv`` and (if given) ``report.json`` into ``out``.

    ``unit`` (``"m"`` or ``"model"``) is recorded in ``result.json`` for the readers of the files.
    ``feasibility`` (:class:`~skatetrace.verification.feasibility.Feasibility`), the second verdict, goes into
    ``report.json`` beside the verification, with both verdicts in one line under ``"verdict"``.
    """
    out = Path(out)
    written = []
    atomic_write(out / "result.json", dumps_json({**result_dict(trace), "unit": unit}))
    written.append(out / "result.json")
    atomic_write(out / "controls.csv", _csv_text(schedule, states))
    written.append(out / "controls.csv")
    if report is not None:
        data = {"schema": "skatetrace.report/1", **report.to_dict()}
        if feasibility is not None:
            data["verdict"] = feasibility.verdict(bool(report.success and trace.success))
            data["feasibility"] = feasibility.to_dict()
        atomic_write(out / "report.json", dumps_json(data))
        written.append(out / "report.json")
    return written


def load_result(path: str | Path) -> dict[str, Any]:
    """Read ``result.json``; its ``"figure"`` entry is returned as a :class:`~skatetrace.Figure`."""
    from ..figures.figure import figure_from_dict

    path = Path(path)
    data = json.loads(path.read_text(encoding="utf-8"))
    if data.get("schema") != SCHEMA_VERSION:
        raise ValueError(f"{path}: expected schema {SCHEMA_VERSION!r}, got {data.get('schema')!r}")
    data["figure"] = figure_from_dict(data["figure"])
    return data


def read_controls(path: str | Path) -> dict[str, np.ndarray]:
    """Read ``controls.csv`` back into columns (``piece`` as int)."""
    path = Path(path)
    with path.open(encoding="utf-8", newline="") as fh:
        rows = list(csv.reader(fh))
    if not rows or tuple(rows[0]) != CSV_COLUMNS:
        raise ValueError(f"{path}: expected header {','.join(CSV_COLUMNS)}")
    data = np.array(rows[1:], dtype=float).reshape(-1, len(CSV_COLUMNS))
    out = {k: data[:, i] for i, k in enumerate(CSV_COLUMNS)}
    out["piece"] = out["piece"].astype(int)
    return out


# ----------------------------------------------------------------------------------------------------------
# Output folders: checked before any work; the files of an earlier run that this run does not write removed


def _nearest_existing(path: Path) -> Path:
    for p in (path, *path.parents):
        if os.path.lexists(p):
            return p
    return Path(".")


def _try_write_in(folder: Path, label: str) -> int:
    """Write and remove a temporary file in ``folder``; returns its time stamp (ns, the file system's clock)."""
    try:
        fd, tmp = tempfile.mkstemp(prefix=".skatetrace-check.", dir=folder)
    except OSError as exc:
        raise SkatetraceError(f"cannot write in folder {folder} ({exc.strerror or exc}): {label} must be a "
                              "folder you may write in") from None
    try:
        return os.fstat(fd).st_mtime_ns
    finally:
        os.close(fd)
        os.unlink(tmp)


def _remove_created(created: list[Path]) -> None:
    for p in reversed(created):
        try:
            p.rmdir()
        except OSError:
            break


def _make_folder(path: Path, label: str) -> list[Path]:
    """Create ``path`` and missing parents (returned, outermost first); clear errors if it cannot be."""
    if path.is_dir():
        return []
    if os.path.lexists(path):
        raise SkatetraceError(f"{label}: {path} is a file, not a folder; give the name of a folder (it is "
                              "created if missing)")
    anchor = _nearest_existing(path.parent)
    if not anchor.is_dir():
        raise SkatetraceError(f"{label}: cannot create folder {path}: {anchor} is a file, not a folder")
    created = [p for p in reversed(path.parents) if not os.path.lexists(p)] + [path]
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        _remove_created(created)
        raise SkatetraceError(f"{label}: cannot create folder {path} ({exc.strerror or exc}); choose a folder "
                              f"under one you may write in") from None
    return created


def check_output_folder(path: str | Path, *, label: str = "--out", subfolders: tuple[str, ...] = ()) -> list[Path]:
    """Make sure files can be written into the folder ``path``, before any work is done.

    The folder (and missing parents) is created, and a temporary file is written in it and removed.

    Parameters
    ----------
    path : str or Path
    label : str
        How the messages name the folder (the command-line option).
    subfolders : tuple of str
        Folders inside ``path`` that will be written into too: each must not be a file.

    Returns
    -------
    list of Path
        The folders created (outermost first), so that a caller that fails later can remove them.

    Raises
    ------
    SkatetraceError
        ``path`` is a file, lies under a file, or cannot be created or written in. Nothing is changed then.
    """
    return _check_folder(Path(path), label, subfolders)[0]


def _check_folder(path: Path, label: str, subfolders: tuple[str, ...]) -> tuple[list[Path], int]:
    created = _make_folder(path, label)
    try:
        stamp = _try_write_in(path, label)
        for sub in subfolders:
            p = path / sub
            if os.path.lexists(p) and not p.is_dir():
                raise SkatetraceError(f"{label}: {p} is a file, but skatetrace writes its {sub} into a folder of "
                                      f"that name; move the file away or choose another folder")
            if p.is_dir():
                _try_write_in(p, label)
    except BaseException:
        _remove_created(created)
        raise
    return created, stamp


def check_output_file(path: str | Path, *, label: str = "-o", suffixes: tuple[str, ...] = (),
                      create_parent: bool = True) -> list[Path]:
    """Make sure the file ``path`` can be written, before any work is done.

    Parameters
    ----------
    path : str or Path
    label : str
        How the messages name the file (the command-line option).
    suffixes : tuple of str
        The accepted suffixes (lower case, with the dot); empty: any.
    create_parent : bool
        Create the folder if missing (else it must exist).

    Returns
    -------
    list of Path
        The folders created (outermost first).

    Raises
    ------
    SkatetraceError
        A suffix not accepted (the message lists every accepted one), a folder in place of the file, or a
        folder that is missing, a file, or not writable.
    """
    path = Path(path)
    if suffixes and path.suffix.lower() not in suffixes:
        accepted = ", ".join(suffixes[:-1]) + (" or " if len(suffixes) > 1 else "") + suffixes[-1]
        raise SkatetraceError(f"{label}: cannot write {str(path)!r}: the file name must end in {accepted} "
                              f"(got {path.suffix or 'no suffix'!r})")
    if path.is_dir():
        raise SkatetraceError(f"{label}: {path} is a folder; give the name of a file to write")
    parent = path.parent
    if not create_parent and not parent.is_dir():
        if os.path.lexists(parent):
            raise SkatetraceError(f"{label}: cannot write {path}: {parent} is a file, not a folder")
        raise SkatetraceError(f"{label}: cannot write {path}: folder {parent} does not exist")
    created = _make_folder(parent, label)
    try:
        _try_write_in(parent, label)
    except BaseException:
        _remove_created(created)
        raise
    return created


def _safe_relative(name: Any) -> bool:
    if not isinstance(name, str) or not name or "\\" in name:
        return False
    p = PurePosixPath(name)
    return not p.is_absolute() and ".." not in p.parts and name != MANIFEST


def _read_manifest(folder: Path) -> dict[str, Any] | None:
    """The folder's manifest, or None if there is none (or it is not one of skatetrace's)."""
    p = folder / MANIFEST
    try:
        data = json.loads(p.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    if not isinstance(data, dict) or data.get("schema") != _MANIFEST_SCHEMA or not isinstance(data.get("files"), list):
        return None
    return {"command": data.get("command"), "files": [f for f in data["files"] if _safe_relative(f)]}


def _write_manifest(folder: Path, command: str | None, files) -> None:
    atomic_write(folder / MANIFEST, dumps_json({
        "schema": _MANIFEST_SCHEMA, "command": command,
        "note": "files skatetrace wrote here; the next run into this folder removes those it does not write again",
        "files": sorted(set(files)),
    }) + "\n")


# Folders written before manifests existed: recognised by their JSON's schema, with the names written then.
_TRACE_FILES = ("result.json", "controls.csv", "report.json", "fit.json", "fit.png", "figure.png", "controls.png",
                "speed.png", "mass_path.png", "energies.png", "viewer.html")
_LEGACY = (("result.json", "skatetrace.result/1", _TRACE_FILES),
           ("fit.json", "skatetrace.fit/1", ("fit.json", "fit.png")),
           ("reproduction.json", "skatetrace.reproduction/1", ("reproduction.json", "report.md", "report.html")))


def _legacy_files(folder: Path) -> list[str]:
    owned: list[str] = []
    for name, schema, names in _LEGACY:
        try:
            data = json.loads((folder / name).read_text(encoding="utf-8"))
        except (OSError, ValueError):
            continue
        if isinstance(data, dict) and data.get("schema") == schema:
            owned += [n for n in names if (folder / n).is_file()]
            if name == "reproduction.json" and (folder / "figures").is_dir():
                owned += [f"figures/{p.name}" for p in (folder / "figures").glob("*.png")
                          if p.name.split("-")[0] in ("main", "point", "length")]
    return owned


def _relative(folder: Path, path: Path) -> str | None:
    try:
        return Path(os.path.abspath(path)).relative_to(folder).as_posix()
    except ValueError:
        return None


class OutputFolder:
    """An output folder: checked before any work, and holding one run's files at a time.

    Skatetrace owns the files it wrote into the folder, as listed in the folder's manifest
    (:data:`MANIFEST`; for a folder written before manifests existed, the names a trace, fit or
    reproduction writes, if its ``result.json``, ``fit.json`` or ``reproduction.json`` is
    skatetrace's). Within ``with folder:`` every file written through :func:`write_atomically` under
    the folder is recorded (and added to the manifest at once, so an interrupted run's files stay
    known); :meth:`finish` then removes the owned files this run did not write and leaves the
    manifest listing exactly this run's files. Other files (a user's notes) are never touched.

    Parameters
    ----------
    path : str or Path
    command : str
        The command writing it, recorded in the manifest.
    label : str
        How error messages name the folder.
    subfolders : tuple of str
        Folders inside it that will be written into (checked too).

    Raises
    ------
    SkatetraceError
        From :func:`check_output_folder`.
    """

    def __init__(self, path: str | Path, command: str, *, label: str = "--out",
                 subfolders: tuple[str, ...] = ()) -> None:
        self.path = Path(path)
        self.command = command
        self.created, self._started = _check_folder(self.path, label, subfolders)
        self._abs = Path(os.path.abspath(self.path))
        manifest = _read_manifest(self.path)
        self.before: tuple[str, ...] = tuple(manifest["files"] if manifest is not None else _legacy_files(self.path))
        self.written: list[str] = []
        self._tokens: list[contextvars.Token] = []

    def __enter__(self) -> "OutputFolder":
        self._tokens.append(_RECORDERS.set((*_RECORDERS.get(), self)))
        return self

    def __exit__(self, *exc) -> None:
        _RECORDERS.reset(self._tokens.pop())

    def _record(self, path: Path) -> None:
        rel = _relative(self._abs, path)
        if rel is None or rel == MANIFEST or rel in self.written:
            return
        self.written.append(rel)
        if rel not in self.before:
            _write_manifest(self.path, self.command, [*self.before, *self.written])

    def finish(self) -> list[str]:
        """Remove the owned files this run did not write; list this run's files in the manifest.

        Returns the names removed (relative to the folder). A run that wrote nothing changes nothing.
        """
        if not self.written:
            return []
        removed = []
        for rel in sorted(set(self.before) - set(self.written)):
            p = self.path / rel
            try:
                fresh = p.stat().st_mtime_ns > self._started
            except OSError:
                continue
            if fresh:  # written during this run, if not through write_atomically: this run's, so kept
                self.written.append(rel)
                continue
            if not p.is_file():
                continue
            try:
                p.unlink()
            except OSError:
                continue
            removed.append(rel)
            for parent in (self.path / rel).parents:  # a subfolder (figures/) left empty goes too
                if parent == self.path or not parent.is_relative_to(self.path):
                    break
                try:
                    parent.rmdir()
                except OSError:
                    break
        _write_manifest(self.path, self.command, self.written)
        return removed

    def discard(self) -> None:
        """Remove the folders the check created, if still empty (a run that failed before writing)."""
        _remove_created(self.created)


def adopt(path: str | Path) -> bool:
    """Add a file skatetrace wrote to the manifest of its folder, if the folder has one.

    For a file written into a run's folder later (``skatetrace view`` writing ``viewer.html``): it is
    then that run's, and the next run into the folder replaces or removes it. Returns whether it was added.
    """
    path = Path(path)
    manifest = _read_manifest(path.parent)
    if manifest is None:
        return False
    if path.name not in manifest["files"]:
        _write_manifest(path.parent, manifest["command"], [*manifest["files"], path.name])
    return True
