"""Writing results: ``result.json``, ``controls.csv``, ``report.json``, written atomically.

Every file is written to a temporary file in the same folder and then renamed, so an interrupted
run never leaves a half-written result behind.
"""

from __future__ import annotations

import csv
import json
from dataclasses import asdict
import math
import os
import tempfile
from pathlib import Path
from typing import Any, Callable

import numpy as np

from .controls import ControlSchedule
from .tracing import FigureTrace
from .verify import VerificationReport

__all__ = ["SCHEMA_VERSION", "CSV_COLUMNS", "atomic_write", "write_atomically", "result_dict", "write_results", "load_result",
           "read_controls"]

SCHEMA_VERSION = "skatetrace.result/1"
CSV_COLUMNS = ("piece", "t", "a", "b", "adot", "bdot", "x", "y", "theta", "p1", "p2", "xi1", "xi2")


def write_atomically(path: str | Path, write: Callable[[Path], None]) -> None:
    """Have ``write(tmp)`` write a temporary file next to ``path``, then rename it onto ``path``.

    The temporary name keeps ``path``'s suffix (writers that choose a format by it still can). On
    any failure, an interrupt included, the temporary file is removed and ``path`` is untouched.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.stem}.", suffix=f".partial{path.suffix.lower()}", dir=path.parent)
    os.close(fd)
    try:
        write(Path(tmp))
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


def atomic_write(path: str | Path, data: str | bytes) -> None:
    """Write ``data`` (text as UTF-8) to ``path`` through a temporary file and an atomic rename."""
    if isinstance(data, bytes):
        write_atomically(path, lambda tmp: tmp.write_bytes(data))
    else:
        write_atomically(path, lambda tmp: tmp.write_text(data, encoding="utf-8", newline=""))


def _clean(obj: Any) -> Any:
    """JSON-safe copy: numpy scalars to Python, non-finite floats to None."""
    if isinstance(obj, dict):
        return {str(k): _clean(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_clean(v) for v in obj]
    if isinstance(obj, (np.floating, float)):
        v = float(obj)
        return v if math.isfinite(v) else None
    if isinstance(obj, (np.integer,)):
        return int(obj)
    if isinstance(obj, np.bool_):
        return bool(obj)
    return obj


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
                  states: dict[str, np.ndarray], report: VerificationReport | None, unit: str = "model") -> list[Path]:
    """Write ``result.json``, ``controls.csv`` and (if given) ``report.json`` into ``out``.

    ``unit`` (``"m"`` or ``"model"``) is recorded in ``result.json`` for the readers of the files.
    """
    out = Path(out)
    written = []
    atomic_write(out / "result.json", json.dumps({**result_dict(trace), "unit": unit}, indent=2, allow_nan=False))
    written.append(out / "result.json")
    atomic_write(out / "controls.csv", _csv_text(schedule, states))
    written.append(out / "controls.csv")
    if report is not None:
        atomic_write(out / "report.json", json.dumps(_clean({"schema": "skatetrace.report/1", **report.to_dict()}),
                                                     indent=2, allow_nan=False))
        written.append(out / "report.json")
    return written


def load_result(path: str | Path) -> dict[str, Any]:
    """Read ``result.json``; its ``"figure"`` entry is returned as a :class:`~skatetrace.Figure`."""
    from .figure import figure_from_dict

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
