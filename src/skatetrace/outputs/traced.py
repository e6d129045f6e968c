"""A traced figure read back from its result files as sections and references, for the studies that replay it.

``skatetrace trace`` writes the figure it traced (with the rests it added) to ``result.json`` and
the sampled controls, with the solver's states along them, to ``controls.csv``. :func:`load_traced`
turns them back into what the replays of :mod:`skatetrace.feedback` need, without solving again:
the model's parameters, the figure's sections (its pieces laid out on the ice) and one
:class:`~skatetrace.feedback.reference.Reference` per traced section, built from the rows
(:func:`~skatetrace.feedback.reference.references`).

A section's rows are told apart by time, as files written before ``controls.csv`` had a
``section`` column need: they run from its start time to its end (the next section's start, or the
figure's duration), the row at the end being its last; the next section's first row repeats that
time. Where the column is there, it must agree.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..dynamics.controls import ControlSchedule
from ..dynamics.model import SleighParams
from ..errors import SkatetraceError
from ..feedback.export import laws_from_dict
from ..feedback.lqr import TrackingLaw
from ..feedback.reference import Reference, references
from ..figures.figure import Figure, Section
from .results import read_result_folder

__all__ = ["TracedFigure", "load_feedback", "load_traced"]


@dataclass(frozen=True, slots=True, kw_only=True)
class TracedFigure:
    """A traced figure as its result files hold it, ready to be replayed.

    Attributes
    ----------
    folder : Path
        The output folder of ``skatetrace trace`` it was read from.
    name, unit : str
        The figure's name; ``"m"`` (metres and seconds) or ``"model"`` (the paper's units).
    params : SleighParams
        The model the figure was traced for.
    figure : Figure
        The figure traced, with the rests ``trace`` added.
    size : float
        The figure's size (:meth:`~skatetrace.figures.figure.Figure.size`), in its units.
    sections : tuple of Section
        Every section in skating order, traced or not.
    references : tuple of Reference or None
        One per section; ``None`` where the section was not traced (no rows).
    start_times : tuple of float
        Each section's start in the figure's time.
    """

    folder: Path
    name: str
    unit: str
    params: SleighParams
    figure: Figure
    size: float
    sections: tuple[Section, ...]
    references: tuple[Reference | None, ...]
    start_times: tuple[float, ...] = ()

    @property
    def traced(self) -> int:
        """How many sections have a reference (were traced)."""
        return sum(r is not None for r in self.references)


def _section_rows(t: np.ndarray, piece: np.ndarray, sections, traced, starts, duration: float,
                  path: Path) -> np.ndarray:
    """The section of every row of ``controls.csv`` (see the module's notes)."""
    labels = np.full(t.size, -1, dtype=int)
    ends = [*starts[1:], duration]
    cursor = 0
    for si, (section, has_rows, end) in enumerate(zip(sections, traced, ends)):
        if not has_rows:
            continue
        # the section's last row is the first at its end (up to round-off, as distinct_steps counts it)
        last = cursor + int(np.searchsorted(t[cursor:], end - 1e-12 * max(1.0, abs(end)), side="left"))
        rows = slice(cursor, last + 1)
        own = {p.index for p in section.pieces}
        if last >= t.size or last - cursor < 1 or not set(np.unique(piece[rows]).tolist()) <= own:
            raise SkatetraceError(f"{path} does not match result.json: the rows of section {si} (from t = "
                                  f"{starts[si]:.9g} to {end:.9g}, pieces {sorted(own)}) are not there; "
                                  "trace the figure again")
        labels[rows] = si
        cursor = last + 1
    if cursor != t.size:
        raise SkatetraceError(f"{path} does not match result.json: {t.size - cursor} rows after the last "
                              "traced section's end; trace the figure again")
    return labels


def _sections(figure: Figure, records: list, path: Path) -> list[Section]:
    """The figure's sections, checked against ``result.json``'s own list (curve and pieces of each)."""
    laid = [(ci, s) for ci, c in enumerate(figure.curves) for s in c.sections()]
    listed = [(int(r["curve"]), [int(p["index"]) for p in r["pieces"]]) for r in records]
    found = [(ci, [p.index for p in s.pieces]) for ci, s in laid]
    if listed != found:
        raise SkatetraceError(f"{path}: its sections {listed} are not those of its figure {found}; "
                              "trace the figure again")
    return [s for _, s in laid]


def load_traced(source: str | Path) -> TracedFigure:
    """Read a traced figure from the output folder of ``skatetrace trace`` (or its ``result.json``).

    Parameters
    ----------
    source : str or Path
        The folder, or its ``result.json``.

    Returns
    -------
    TracedFigure
        With one reference per traced section, from the rows of ``controls.csv``.

    Raises
    ------
    SkatetraceError
        A missing or unreadable ``result.json`` or ``controls.csv``, or files that do not match
        (the message names the file).
    """
    folder, result, cols = read_result_folder(source)
    result_path, controls_path = folder / "result.json", folder / "controls.csv"
    try:
        figure = result["figure"]
        params = SleighParams(**{k: result["params"][k] for k in ("M", "m", "I")})
        records = result["sections"]
        sections = _sections(figure, records, result_path)
        traced = [bool(r.get("phases")) for r in records]
        starts = [float(r["start_time"]) for r in records]
        duration = float(result["duration"])
        unit = str(result.get("unit", "model"))
    except (KeyError, TypeError, ValueError, AttributeError) as exc:
        raise SkatetraceError(f"cannot read the results in {result_path}: {type(exc).__name__} {exc}") from None
    labels = _section_rows(cols["t"], cols["piece"], sections, traced, starts, duration, controls_path)
    if "section" in cols and not np.array_equal(cols["section"], labels):
        raise SkatetraceError(f"{controls_path} does not match result.json: its section column is not the sections "
                              "its times fall in; trace the figure again")
    try:
        schedule = ControlSchedule(t=cols["t"], a=cols["a"], b=cols["b"], adot=cols["adot"], bdot=cols["bdot"],
                                   section=labels, piece=cols["piece"])
    except ValueError as exc:
        raise SkatetraceError(f"cannot read the results in {controls_path}: {exc}") from None
    states = {k: cols[k] for k in ("p1", "p2", "theta", "x", "y")}
    refs = references(sections, schedule, states, starts, params)
    return TracedFigure(folder=folder, name=figure.name, unit=unit, params=params, figure=figure, size=figure.size(),
                        sections=tuple(sections), references=tuple(refs), start_times=tuple(starts))


def load_feedback(traced: TracedFigure) -> list[TrackingLaw | None]:
    """The tracking laws in ``feedback.json`` beside a traced figure's files (one per section).

    Written by ``skatetrace robustness``; with :meth:`~skatetrace.feedback.lqr.TrackingLaw.controller`
    each is state feedback for :func:`skatetrace.simulate`.

    Raises
    ------
    SkatetraceError
        A missing or unreadable ``feedback.json``, or one that is not the law of these files (the
        message names the file and what does not match).
    """
    path = traced.folder / "feedback.json"
    if not path.is_file():
        raise SkatetraceError(f"{path} not found: 'skatetrace robustness {traced.folder}' writes it")
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
        return laws_from_dict(data, traced.references, traced.params)
    except (OSError, ValueError, RecursionError) as exc:
        raise SkatetraceError(f"cannot read the tracking laws in {path}: {exc}") from None
