"""A traced figure read back from its result files, ready to be drawn frame by frame.

The animation (:mod:`skatetrace.outputs.animation`) and the HTML viewer (:mod:`skatetrace.outputs.viewer`) draw
from the files ``skatetrace trace`` writes (``result.json``, ``controls.csv``, ``report.json``),
never by solving again. :func:`load_playback` reads them into a :class:`Playback`: the blade's
contact point and heading, the mass in the body frame and on the ice, speeds and energies on the
time grid of ``controls.csv``, the target figure as polylines, and where the skater comes to rest.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..dynamics.model import SleighParams, mass_energy
from ..errors import SkatetraceError
from ..figures.geometry import segment_points
from .results import read_result_folder

__all__ = ["Playback", "load_playback"]


@dataclass(frozen=True, slots=True, kw_only=True)
class Playback:
    """Everything a drawing of the traced figure needs, on one time grid.

    Attributes
    ----------
    name, unit : str
        The figure's name; ``"m"`` (metres and seconds) or ``"model"`` (the paper's units).
    params : SleighParams
    t : ndarray, shape (n,)
        Time, non-decreasing; a repeated time marks a jump (of the rates at a smooth join, of the
        mass position and heading at a cusp).
    x, y, theta : ndarray
        Blade contact point and heading (the direction the blade points, radians).
    a, b, adot, bdot : ndarray
        Mass position in the body frame (``a`` along the blade) and its rates.
    mass_x, mass_y : ndarray
        Mass position on the ice.
    speed, omega : ndarray
        Speed along the blade (xi2) and angular velocity (xi1).
    ke_skate, ke_mass : ndarray
        Kinetic energies of the sleigh and of the moving mass; ``ke_total`` is their sum.
    section : ndarray of int
        Section of each row (sections run from rest to rest).
    figure : list of ndarray
        The target figure: one ``(2, k)`` polyline per placed piece.
    rests : ndarray, shape (2, r)
        Where the skater is at rest: the start of every section and the end of the last.
    rest_times : ndarray, shape (r,)
    summary : dict
        Figure name, trace status and message, duration, the planner's ``reach`` (None without
        one), and the verification checks
        (``report.json``'s status, message, deviation, tolerance, cusp speed) if present, and
        ``feasibility`` and ``verdict`` (the second verdict: could a skater do it) where the report has them.
    """

    name: str
    unit: str
    params: SleighParams
    t: np.ndarray
    x: np.ndarray
    y: np.ndarray
    theta: np.ndarray
    a: np.ndarray
    b: np.ndarray
    adot: np.ndarray
    bdot: np.ndarray
    mass_x: np.ndarray
    mass_y: np.ndarray
    speed: np.ndarray
    omega: np.ndarray
    ke_skate: np.ndarray
    ke_mass: np.ndarray
    section: np.ndarray
    figure: list = field(default_factory=list)
    rests: np.ndarray = field(default_factory=lambda: np.zeros((2, 0)))
    rest_times: np.ndarray = field(default_factory=lambda: np.zeros(0))
    summary: dict = field(default_factory=dict)

    @property
    def ke_total(self) -> np.ndarray:
        return self.ke_skate + self.ke_mass

    @property
    def duration(self) -> float:
        return float(self.t[-1] - self.t[0])

    def bounds(self, margin: float = 0.05) -> tuple[float, float, float, float]:
        """``(xmin, xmax, ymin, ymax)`` enclosing the figure, the blade's path and the mass."""
        xs = np.concatenate([self.x, self.mass_x] + [p[0] for p in self.figure])
        ys = np.concatenate([self.y, self.mass_y] + [p[1] for p in self.figure])
        x0, x1, y0, y1 = float(xs.min()), float(xs.max()), float(ys.min()), float(ys.max())
        pad = margin * max(x1 - x0, y1 - y0, 1e-12)
        return x0 - pad, x1 + pad, y0 - pad, y1 + pad

    def frame_rows(self, n: int) -> np.ndarray:
        """Row indices of ``n`` frames evenly spaced in time (the last row at or before each time)."""
        if n < 1:
            raise ValueError(f"a playback needs at least one frame, got {n}")
        times = np.linspace(self.t[0], self.t[-1], n)
        return np.clip(np.searchsorted(self.t, times, side="right") - 1, 0, self.t.size - 1)


def _read_json(path: Path, what: str) -> dict[str, Any]:
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except OSError as exc:
        raise SkatetraceError(f"cannot read {what} {str(path)!r}: {exc.strerror}") from None
    except json.JSONDecodeError as exc:
        raise SkatetraceError(f"{path}: not valid JSON ({exc.msg} at line {exc.lineno})") from None


def load_playback(source: str | Path, columns: dict[str, np.ndarray] | None = None) -> Playback:
    """Read a traced figure from the output folder of ``skatetrace trace`` (or its ``result.json``).

    ``columns``: the folder's controls already in memory, as
    :func:`~skatetrace.outputs.results.read_controls` reads them (at least ``t``, ``x``, ``y``,
    ``theta``, ``a``, ``b``, ``adot``, ``bdot``, ``xi1`` and ``xi2``); ``controls.csv`` is then not
    read (:func:`~skatetrace.outputs.results.read_result_folder`).

    Raises
    ------
    SkatetraceError
        A missing or unreadable ``result.json`` or ``controls.csv``, or files that do not match.
    """
    folder, result, cols = read_result_folder(source, columns)
    controls_path = folder / "controls.csv"
    if cols["t"].size < 2:
        raise SkatetraceError(f"{controls_path} holds fewer than two rows: nothing to play")
    p = result["params"]
    params = SleighParams(M=p["M"], m=p["m"], I=p["I"])
    t, x, y, th = cols["t"], cols["x"], cols["y"], cols["theta"]
    a, b, ad, bd, xi1, xi2 = cols["a"], cols["b"], cols["adot"], cols["bdot"], cols["xi1"], cols["xi2"]
    c, s = np.cos(th), np.sin(th)
    starts = np.array([sec["start_time"] for sec in result["sections"]], dtype=float)
    section = np.clip(np.searchsorted(starts, t, side="right") - 1, 0, max(len(starts) - 1, 0))
    # A section's first row is the one at its start time after the previous section's last row.
    first = np.flatnonzero(np.diff(section, prepend=-1) != 0)
    rest_rows = np.concatenate([first, [t.size - 1]])
    figure = [segment_points(pl.start, pl.segment, max(16, min(400, int(64 * (1 + abs(pl.segment.turn))))))
              for curve in result["figure"].curves for pl in curve.layout()]
    summary: dict[str, Any] = {
        "figure": result["figure"].name, "success": result["success"], "status": result["status"],
        "message": result["message"], "duration": float(t[-1] - t[0]), "sections": len(result["sections"]),
        "params": p, "unit": result.get("unit", "model"),
        # the planner's reach (None for the launch-glide-stop manoeuvres): the viewer draws it
        "reach": (result.get("options") or {}).get("reach"),
    }
    report_path = folder / "report.json"
    if report_path.is_file():
        rep = _read_json(report_path, "the verification report")
        summary["verification"] = {k: rep.get(k) for k in ("status", "message", "max_deviation", "tolerance",
                                                            "figure_size", "max_cusp_speed")}
        if isinstance(rep.get("feasibility"), dict):
            summary["feasibility"] = rep["feasibility"]
            summary["verdict"] = rep.get("verdict")
    unit = summary["unit"]
    return Playback(
        name=result["figure"].name, unit=unit, params=params, t=t, x=x, y=y, theta=th, a=a, b=b, adot=ad, bdot=bd,
        mass_x=x + a * c - b * s, mass_y=y + a * s + b * c, speed=xi2, omega=xi1,
        ke_skate=0.5 * params.M * xi2**2 + 0.5 * params.I * xi1**2,
        ke_mass=mass_energy(params, xi1, xi2, a, b, ad, bd), section=section, figure=figure,
        rests=np.vstack([x[rest_rows], y[rest_rows]]), rest_times=t[rest_rows], summary=summary,
    )
