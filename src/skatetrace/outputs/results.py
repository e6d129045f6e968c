"""The result files of a trace: ``result.json``, ``controls.csv`` and ``report.json``, written and read.

``result.json`` (schema :data:`SCHEMA_VERSION`) holds everything needed to understand and
reproduce the traced figure, ``controls.csv`` (columns :data:`CSV_COLUMNS`) the sampled controls
with the states along them, ``report.json`` the verification and the feasibility verdict. Every
file is written atomically and as strict JSON (:mod:`skatetrace.outputs.files`).
"""

from __future__ import annotations

import contextlib
import csv
import itertools
import json
from dataclasses import asdict
from pathlib import Path
from typing import Any, Callable

import numpy as np
import orjson

from ..dynamics.controls import ControlSchedule
from ..errors import SkatetraceError
from ..processes import map_forked, worker_count
from ..progress import Channel
from ..tracing.sections import FigureTrace
from ..verification.feasibility import Feasibility
from ..verification.verify import VerificationReport
from .files import atomic_write, dumps_json, json_safe, write_atomically

__all__ = ["SCHEMA_VERSION", "CSV_COLUMNS", "CONTROLS_SCHEMA", "LEGACY_CSV_COLUMNS", "result_dict", "write_results",
           "reporting", "load_result", "read_controls", "read_result_folder"]

SCHEMA_VERSION = "skatetrace.result/1"
CSV_COLUMNS = ("piece", "t", "a", "b", "adot", "bdot", "x", "y", "theta", "p1", "p2", "xi1", "xi2", "curve",
               "section")
#: The columns before ``curve`` and ``section`` were added (``result.json``'s ``controls_schema`` absent); still read.
LEGACY_CSV_COLUMNS = CSV_COLUMNS[:13]
#: Recorded in ``result.json`` as ``controls_schema``: the version of ``controls.csv``'s columns.
CONTROLS_SCHEMA = "skatetrace.controls/2"
_INT_COLUMNS = ("piece", "curve", "section")


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
            # the first piece starts the section: no search for it (most sections are one piece)
            times = np.concatenate([[0.0], sec.time_at_length(starts[1:])]) if starts.size > 1 else np.zeros(1)
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
    return json_safe({
        "schema": SCHEMA_VERSION,
        "success": trace.success, "status": trace.status, "message": trace.message,
        "params": trace.params.to_dict(),
        "options": asdict(trace.options),  # every setting of the tracer, so that a run can be repeated
        "figure": trace.figure.to_dict(),
        "curves": curves,
        "duration": trace.duration,
        "sections": sections,
    })


#: Rows of ``controls.csv`` from which its text is formatted in several processes (a planned school
#: figure had 400,000 rows: 2.8 s of ``repr`` in one; orjson formats them some ten times faster).
_SPLIT_ROWS = 50_000
#: Rows one process formats at a time. The file is written as each round of chunks comes back, so
#: that memory holds a round's text, not the file's (a zigzag of 2,000 lines has 3.9 million rows, a
#: gigabyte of text).
_CHUNK_ROWS = 100_000

#: The fewest rows a run of one piece must have on average for a chunk of ``controls.csv`` to be
#: formatted run by run (:func:`_write_csv`); else it is formatted row by row, the same text.
_RUN_ROWS = 8

_PROGRESS = Channel("writing")


def reporting(report: Callable[[str, int, int], None]) -> contextlib.AbstractContextManager[None]:
    """Within the ``with`` block, call ``report("writing controls.csv", done, total)`` as its rows are written.

    Reported after each round of chunks (:data:`_CHUNK_ROWS` rows a process), per thread and task,
    like :func:`skatetrace.planning.pool.reporting` (:class:`skatetrace.progress.Channel`).
    """
    return _PROGRESS.listening(report)


def _column_text(values: np.ndarray) -> list[bytes]:
    """``values`` (1-D) as text: integers in decimal, floats in the shortest decimal that reads back
    as the same double (orjson's; it writes ``1e-7`` where ``repr`` writes ``1e-07``), and where a
    float is not finite, as ``repr`` writes it (``nan``, ``inf``), which orjson cannot."""
    if values.size == 0:
        return []
    if values.dtype.kind == "f" and not np.all(np.isfinite(values)):
        return [repr(v).encode() for v in values.tolist()]
    return orjson.dumps(np.ascontiguousarray(values), option=orjson.OPT_SERIALIZE_NUMPY)[1:-1].split(b",")


def _group_text(table: np.ndarray) -> list[bytes]:
    """The rows of ``table`` (2-D, one kind) as text, each row's values joined by commas (:func:`_column_text`)."""
    if table.dtype.kind == "f" and not np.all(np.isfinite(table)):
        return list(map(b",".join, zip(*(_column_text(c) for c in table.T))))
    return orjson.dumps(np.ascontiguousarray(table), option=orjson.OPT_SERIALIZE_NUMPY)[2:-2].split(b"],[")


def _write_csv(path: Path, schedule: ControlSchedule, states: dict[str, np.ndarray], curve_of_section) -> None:
    """Write ``controls.csv`` to ``path``: floats in their shortest round-trip form (:func:`_column_text`).

    ``piece`` counts within a curve, so each row also names its ``curve`` (``curve_of_section``:
    the curve of every section) and ``section`` (in skating order over the figure). From
    :data:`_SPLIT_ROWS` rows on, the text is formatted in chunks side by side
    (:func:`~skatetrace.processes.map_forked`), a round of chunks at a time: the same text.
    """
    section = np.asarray(schedule.section, dtype=int)
    curve = np.asarray(curve_of_section, dtype=int)[section] if section.size else section
    cols = {"piece": schedule.piece, "t": schedule.t, "a": schedule.a, "b": schedule.b,
            "adot": schedule.adot, "bdot": schedule.bdot, **states, "curve": curve, "section": section}
    # the columns in runs of one kind (piece; t to xi2; curve and section), each formatted as a
    # table, each row's text at once, not value by value
    groups = [np.column_stack([np.asarray(cols[k], dtype=np.int64 if ints else np.float64) for k in run])
              for ints, run in itertools.groupby(CSV_COLUMNS, lambda k: k in _INT_COLUMNS)]
    assert [g.dtype.kind for g in groups] == ["i", "f", "i"], "controls.csv: integers, floats, integers"
    n = int(section.size)

    def rows(bounds: tuple[int, int]) -> bytes:
        lo, hi = bounds
        if hi <= lo:
            return b""
        head, floats, tail = (g[lo:hi] for g in groups)
        # runs of rows of one piece, curve and section: their floats formatted as one table and the
        # integers spliced in between its rows (a few operations a run, not one a row)
        ends = np.flatnonzero(np.any(np.diff(np.concatenate([head, tail], axis=1), axis=0) != 0, axis=1)) + 1
        if (ends.size + 1) * _RUN_ROWS > hi - lo or not np.all(np.isfinite(floats)):
            return b"\n".join(map(b",".join, zip(*(_group_text(g) for g in (head, floats, tail))))) + b"\n"
        text = []
        for a, b in zip([0, *ends.tolist()], [*ends.tolist(), hi - lo]):
            before = b"".join(b"%d," % v for v in head[a].tolist())
            after = b"".join(b",%d" % v for v in tail[a].tolist()) + b"\n"
            table = orjson.dumps(floats[a:b], option=orjson.OPT_SERIALIZE_NUMPY)[2:-2]
            text += (before, table.replace(b"],[", after + before), after)
        return b"".join(text)

    step = min(_CHUNK_ROWS, -(-n // 2)) if n >= _SPLIT_ROWS else max(n, 1)
    chunks = [(lo, min(lo + step, n)) for lo in range(0, n, step)]
    per_round = max(1, worker_count(len(chunks), None))
    with open(path, "wb") as f:
        f.write(",".join(CSV_COLUMNS).encode() + b"\n")
        for k in range(0, len(chunks), per_round):
            batch = chunks[k:k + per_round]
            f.writelines(map_forked(rows, batch))
            _PROGRESS.report("writing controls.csv", batch[-1][1], n)


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
    atomic_write(out / "result.json", dumps_json({**result_dict(trace), "unit": unit,
                                                  "controls_schema": CONTROLS_SCHEMA}))
    written.append(out / "result.json")
    curves = [s.curve_index for s in trace.sections]
    write_atomically(out / "controls.csv", lambda tmp: _write_csv(tmp, schedule, states, curves))
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
    """Read ``controls.csv`` back into columns (``piece``, ``curve`` and ``section`` as int).

    A file written before ``curve`` and ``section`` were added (:data:`LEGACY_CSV_COLUMNS`) is read
    without them.
    """
    path = Path(path)
    with path.open(encoding="utf-8", newline="") as fh:
        rows = list(csv.reader(fh))
    header = tuple(rows[0]) if rows else ()
    if header not in (CSV_COLUMNS, LEGACY_CSV_COLUMNS):
        raise ValueError(f"{path}: expected header {','.join(CSV_COLUMNS)}")
    short = next((i for i, row in enumerate(rows[1:], start=2) if len(row) != len(header)), None)
    if short is not None:  # a file cut short (a run killed while writing) ends in a partial row
        raise ValueError(f"{path}: line {short} has {len(rows[short - 1])} of the {len(header)} columns: the file is "
                         "cut short or edited; trace the figure again")
    data = np.array(rows[1:], dtype=float).reshape(-1, len(header))
    out = {k: data[:, i] for i, k in enumerate(header)}
    for k in _INT_COLUMNS:
        if k in out:
            if not np.all(np.isfinite(out[k])) or np.any(out[k] != np.round(out[k])):
                raise ValueError(f"{path}: column {k!r} must hold whole numbers")
            out[k] = out[k].astype(int)
    return out


def read_result_folder(source: str | Path, columns: dict[str, np.ndarray] | None = None
                       ) -> tuple[Path, dict[str, Any], dict[str, np.ndarray]]:
    """The output folder of ``skatetrace trace`` (or its ``result.json``): the folder, the result and the controls.

    ``columns``, if given, are the controls already in memory, as :func:`read_controls` would read
    them from the folder's ``controls.csv`` (its floats round-trip exactly): they are returned
    instead, and the file is not read. The command line builds its viewer so, from the rows it
    has just written (a planned drawing's 370,000 rows took 3 s to read back).

    Returns
    -------
    (Path, dict, dict)
        The folder, :func:`load_result`'s dict and :func:`read_controls`'s columns.

    Raises
    ------
    SkatetraceError
        A missing or unreadable ``result.json`` or ``controls.csv`` (the message names the file).
    """
    source = Path(source)
    folder = source.parent if source.suffix == ".json" else source
    result_path, controls_path = folder / "result.json", folder / "controls.csv"
    for p in (result_path,) if columns is not None else (result_path, controls_path):
        if not p.is_file():
            raise SkatetraceError(f"{p} not found: give the output folder of 'skatetrace trace' "
                                  "(it holds result.json and controls.csv)")
    try:
        result = load_result(result_path)
    except (OSError, ValueError, KeyError, TypeError, AttributeError) as exc:
        raise SkatetraceError(f"cannot read the results in {result_path}: {exc}") from None
    if columns is not None:
        return folder, result, columns
    try:
        cols = read_controls(controls_path)
    except (OSError, ValueError) as exc:
        raise SkatetraceError(f"cannot read the results in {controls_path}: {exc}") from None
    return folder, result, cols
