"""Output folders: checked before any work, and holding one run's files at a time.

An output folder (:class:`OutputFolder`) is checked before any work and keeps a manifest,
``.skatetrace-manifest.json``, of the files skatetrace wrote there. A run's files are written into a
staging folder inside it and moved into place together when the run is over, and the files of the
manifest the run did not write again are removed then: a folder never mixes two runs' files, and a
run killed on the way leaves the earlier run's files as they were. Files skatetrace did not write
are never touched.
"""

from __future__ import annotations

import contextlib
import errno
import json
import os
import shutil
import tempfile
from pathlib import Path, PurePosixPath
from typing import Any

from ..errors import SkatetraceError
from .files import atomic_write, dumps_json, record_writes, stage_writes, temporary_pattern

__all__ = ["MANIFEST", "STAGING_PREFIX", "check_finished", "check_output_folder", "check_output_file", "output_path",
           "OutputFolder", "adopt"]

#: The list of files skatetrace wrote into an output folder (see :class:`OutputFolder`).
MANIFEST = ".skatetrace-manifest.json"
_MANIFEST_SCHEMA = "skatetrace.manifest/1"
#: The name of a run's staging folder inside its output folder starts with this.
STAGING_PREFIX = ".skatetrace-run."
#: The temporary file of a manifest being written (``write_atomically``'s name for it): a run killed
#: in that instant leaves it beside the manifest.
_MANIFEST_PARTIAL = temporary_pattern(MANIFEST)



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
    try:
        if path.is_dir():
            return []
        exists = os.path.lexists(path)
    except OSError as exc:  # a name too long for the file system, say
        text = str(path)
        shown = text if len(text) <= 80 else f"{text[:60]}... ({len(text)} characters)"
        raise SkatetraceError(f"{label}: cannot use {shown} as a folder ({exc.strerror or exc}); give a shorter "
                              "name") from None
    if exists:
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
    return _check_folder(output_path(path, label, "folder"), label, subfolders)[0]


def output_path(path: str | Path, label: str, what: str = "file") -> Path:
    """``path`` as a Path; an empty or blank name (which a Path would read as the current folder) is refused.

    ``what`` ("file" or "folder") and ``label`` (the command-line option) word the message.
    """
    if isinstance(path, str) and not path.strip():
        hint = " (. for the current folder)" if what == "folder" else ""
        raise SkatetraceError(f"{label}: {path!r} names no {what}; give its name{hint}")
    return Path(path)


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
    path = output_path(path, label, "file")
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
    return {"command": data.get("command"), "files": [f for f in data["files"] if _safe_relative(f)],
            "complete": data.get("complete", True) is not False}


def _write_manifest(folder: Path, command: str | None, files, complete: bool = True) -> None:
    atomic_write(folder / MANIFEST, dumps_json({
        "schema": _MANIFEST_SCHEMA, "command": command,
        "note": "files skatetrace wrote here; the next run into this folder removes those it does not write again",
        "files": sorted(set(files)),
        # False while a run's files are moved into place: a run killed in that instant leaves it
        # so, and the commands that read the folder refuse its mix of two runs' files
        "complete": complete,
    }) + "\n")


def _remove_staging(folder: Path) -> None:
    """Remove what runs that were killed left: staging folders (never moved in), manifests half written."""
    try:
        leftovers = [p for p in folder.iterdir() if p.name.startswith(STAGING_PREFIX)]
        partial = list(folder.glob(_MANIFEST_PARTIAL))
    except OSError:
        return
    for p in leftovers:
        if p.is_dir() and not p.is_symlink():
            shutil.rmtree(p, ignore_errors=True)
    for p in partial:
        if p.is_file() and not p.is_symlink():
            p.unlink(missing_ok=True)


def check_finished(folder: str | Path) -> None:
    """Refuse a folder whose last run did not finish writing (its manifest says ``"complete": false``).

    Such a folder may hold files of two runs side by side (a new ``result.json`` beside an older
    ``controls.csv``). A folder without a manifest, or written before the flag existed, passes.

    Raises
    ------
    SkatetraceError
    """
    folder = Path(folder)
    folder = folder.parent if folder.suffix == ".json" else folder
    manifest = _read_manifest(folder)
    if manifest is not None and not manifest["complete"]:
        raise SkatetraceError(f"{folder} holds the files of a run that did not finish writing (interrupted or failed: "
                              f"its {MANIFEST} says so), perhaps beside an earlier run's: run "
                              f"'skatetrace {manifest['command'] or 'trace'}' into it again, or give another folder")


def _lock(path: Path, label: str):
    """An exclusive lock on the folder ``path`` (its own descriptor, so no file is added), or an error
    if another run holds it. Released when the descriptor is closed, or when the process ends."""
    try:
        import fcntl
    except ImportError:  # pragma: no cover - not POSIX: no lock
        return None
    try:
        fd = os.open(path, os.O_RDONLY)
    except OSError:  # a folder that cannot be opened for reading (but was written in): no lock
        return None
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError as exc:
        os.close(fd)
        if exc.errno in (errno.EWOULDBLOCK, errno.EAGAIN, errno.EACCES):
            raise SkatetraceError(f"{label}: another skatetrace run is writing into {path}; wait for it to finish, "
                                  "or give another folder") from None
        return None  # a file system without locks (some network ones): no lock, as before
    return fd


#: The files each command writes into its folder (checked before any work: none may be a folder).
_COMMAND_FILES = {
    "trace": ("result.json", "controls.csv", "report.json", "fit.json", "fit.png", "figure.png", "controls.png",
              "speed.png", "mass_path.png", "energies.png", "viewer.html"),
    "fit": ("fit.json", "fit.png"),
    "tradeoff": ("tradeoff.json", "tradeoff.png"),
    "reproduce": ("reproduction.json", "report.md", "report.html"),
}
# Folders written before manifests existed: recognised by their JSON's schema, with the names written then.
_LEGACY = (("result.json", "skatetrace.result/1", _COMMAND_FILES["trace"]),
           ("fit.json", "skatetrace.fit/1", _COMMAND_FILES["fit"]),
           ("reproduction.json", "skatetrace.reproduction/1", _COMMAND_FILES["reproduce"]))


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
    the folder goes into a staging folder inside it (:data:`STAGING_PREFIX`; :func:`staged` tells
    where a file just written can be read back) and is recorded. :meth:`finish` then moves the run's
    files into place, removes the owned files this run did not write, and leaves the manifest
    listing exactly this run's files. Other files (a user's notes) are never touched.

    A run killed before :meth:`finish` leaves the earlier run's files as they were (its staging
    folder is removed by the next run). While :meth:`finish` moves the files, the manifest says
    ``"complete": false``: a run killed in that instant leaves a folder that :func:`check_finished`
    (and so ``view``, ``animate`` and ``robustness``) refuses. The folder is locked from the check
    to :meth:`finish` or :meth:`discard` (or the process's end): a second run into it is refused at once.

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
        self.path = output_path(path, label, "folder")
        self.command = command
        self.created, self._started = _check_folder(self.path, label, subfolders)
        try:
            for name in _COMMAND_FILES.get(command, ()):
                if (self.path / name).is_dir():
                    raise SkatetraceError(f"{label}: {self.path / name} is a folder, and '{command}' writes a file of "
                                          "that name there: move it, or give another folder")
            self._lock = _lock(self.path, label)
        except SkatetraceError:
            _remove_created(self.created)
            raise
        self._abs = Path(os.path.abspath(self.path))
        if self._lock is not None:  # no other run is writing here: a staging folder left is a killed run's
            _remove_staging(self.path)
        manifest = _read_manifest(self.path)
        self.before: tuple[str, ...] = tuple(manifest["files"] if manifest is not None else _legacy_files(self.path))
        self.written: list[str] = []
        self._staging: Path | None = None
        self._recording: list[contextlib.ExitStack] = []

    def __enter__(self) -> "OutputFolder":
        stack = contextlib.ExitStack()
        stack.enter_context(stage_writes(self._stage))
        stack.enter_context(record_writes(self._record))
        self._recording.append(stack)
        return self

    def __exit__(self, *exc) -> None:
        self._recording.pop().close()

    def _stage(self, path: Path) -> Path | None:
        """Where this run writes the file ``path`` until :meth:`finish` (None: not in the folder)."""
        rel = _relative(self._abs, path)
        if rel is None or rel == MANIFEST or rel.split("/")[0].startswith(STAGING_PREFIX):
            return None
        if self._staging is None:
            self._staging = Path(tempfile.mkdtemp(prefix=STAGING_PREFIX, dir=self.path))
        return self._staging / rel

    def _record(self, path: Path) -> None:
        rel = _relative(self._abs, path)
        if rel is not None and rel != MANIFEST and rel not in self.written:
            self.written.append(rel)

    def _move_in(self) -> None:
        """Move the staged files into place (the manifest says ``"complete": false`` meanwhile)."""
        if self._staging is None:
            return
        _write_manifest(self.path, self.command, [*self.before, *self.written], complete=False)
        for rel in self.written:
            src = self._staging / rel
            if src.is_file():
                (self.path / rel).parent.mkdir(parents=True, exist_ok=True)
                os.replace(src, self.path / rel)

    def _drop_staging(self) -> None:
        if self._staging is not None:
            shutil.rmtree(self._staging, ignore_errors=True)
            self._staging = None

    def finish(self) -> list[str]:
        """Move this run's files into place, remove the owned files it did not write, and list its files.

        Returns the names removed (relative to the folder). A run that wrote nothing changes nothing.
        """
        if not self.written:
            self._drop_staging()
            self._unlock()
            return []
        try:
            self._move_in()
        finally:
            self._drop_staging()
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
        self._unlock()
        return removed

    def discard(self) -> None:
        """Drop this run's staged files and remove the folders the check created, if still empty.

        For a run stopped on the way (Ctrl-C): the folder keeps the earlier run's files as they were.
        """
        self._drop_staging()
        self._unlock()
        _remove_created(self.created)

    def __del__(self) -> None:  # a folder object let go of without finish() (a test, a caller's error)
        if getattr(self, "_staging", None) is not None:
            self._drop_staging()
        self._unlock()

    def _unlock(self) -> None:
        if getattr(self, "_lock", None) is not None:
            os.close(self._lock)
            self._lock = None


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
        _write_manifest(path.parent, manifest["command"], [*manifest["files"], path.name], manifest["complete"])
    return True
