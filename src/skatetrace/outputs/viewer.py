"""One self-contained HTML file that plays a traced figure back in a web browser.

:func:`write_viewer` turns a :class:`~skatetrace.outputs.playback.Playback` (the files ``skatetrace trace``
writes, read back by :func:`~skatetrace.outputs.playback.load_playback`) into a single HTML page that works
offline: the time series, downsampled and rounded, are embedded as JSON in a
``<script type="application/json">`` tag, and plain JavaScript draws them with SVG. The page has

* an animation of the figure: the target (grey), the blade's trace growing up to the current time,
  the skate as an oriented segment with a toe mark, the mass (the skater's centre of mass) with a
  short trail, the rests (cusps) and a clock;
* controls: play/pause, a playback-speed factor, a time slider that scrubs, a time readout;
* plots of the mass position ``a``, ``b``, the speed along the blade and the kinetic energies
  against time, each with a cursor at the current time (clicking a plot seeks);
* the figure's summary and its verification checks, failed checks marked.

The page loads nothing: no scripts, fonts, styles or images from anywhere, and its
Content-Security-Policy forbids any request. Its elements have stable ids (``#play``, ``#speed``,
``#view``, ``#slider``, ``#time``, ``#stage``, ``#skate`` with the skate's position on the stage
in ``data-x``/``data-y``, ``#mass``, ``#plot-ab``, ``#plot-speed``, ``#plot-energy``, ``#summary``,
``#checks``) and it exposes ``window.skatetrace`` with ``time()``, ``seek(t)``, ``playing()``,
``play()``, ``pause()``, ``duration()``, ``view([name])`` (``"figure"`` or ``"all"``: what the stage
fits) and ``screen(x, y)`` (a point on the ice in the stage's coordinates).

The page's HTML, CSS and JavaScript are the package data files ``web/viewer.html``,
``web/viewer.css`` and ``web/viewer.js``.
"""

from __future__ import annotations

import html
import json
import math
import re
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np

from .files import atomic_write, json_safe
from .playback import Playback, load_playback

__all__ = ["viewer_html", "write_viewer", "sample_rows", "default_speed", "SPEED_FACTORS"]

#: Playback-speed factors offered by the page (figure time per second of real time).
SPEED_FACTORS = (0.25, 0.5, 1.0, 2.0, 4.0, 8.0, 16.0)
#: Wall-clock time the whole figure should take at the default speed factor, in seconds.
TARGET_PLAY_SECONDS = 25.0
#: Significant digits kept for each embedded column (relative to the column's largest magnitude).
_DIGITS = {"t": 8, "x": 7, "y": 7, "theta": 7, "a": 6, "b": 6, "speed": 6, "ke_skate": 6, "ke_mass": 6}
#: Significant digits kept for the target figure's points, and how far (a fraction of the figure's
#: extent, about 0.03 pixels on the page) its simplified polylines may stray from the given ones.
_FIGURE_DIGITS = 6
_FIGURE_TOLERANCE = 5e-5
_WEB = ("web", "viewer.html"), ("web", "viewer.css"), ("web", "viewer.js")
_PLACEHOLDER = re.compile(r"\{\{([A-Z_]+)\}\}")


def sample_rows(playback: Playback, max_samples: int = 4000) -> np.ndarray:
    """Indices of the rows of ``playback`` that the viewer embeds, sorted.

    Keeps the first and last rows, both rows of every repeated time (a jump: a cusp, or a join
    where the rates jump) and the first row of every section (a rest), and fills up to
    ``max_samples`` rows with rows evenly spaced in time (the last row at or before each time, as
    :meth:`Playback.frame_rows` picks them).

    Parameters
    ----------
    playback : Playback
    max_samples : int
        At most this many rows are kept; at least 2.

    Returns
    -------
    ndarray of int
        Sorted, unique row indices; all rows if there are no more than ``max_samples``.

    Raises
    ------
    ValueError
        ``max_samples`` below 2.
    """
    if max_samples < 2:
        raise ValueError(f"the viewer needs at least 2 samples, got max_samples={max_samples}")
    n = playback.t.size
    if n <= max_samples:
        return np.arange(n)
    t = playback.t
    jumps = np.flatnonzero(np.diff(t) <= 0)
    starts = np.flatnonzero(np.diff(playback.section, prepend=playback.section[0] - 1) != 0)
    keep = np.unique(np.concatenate([[0, n - 1], jumps, jumps + 1, starts]))
    if keep.size >= max_samples:
        # No room beside the jumps: keep an evenly spread subset of them (ends included).
        return keep[np.unique(np.round(np.linspace(0, keep.size - 1, max_samples)).astype(int))]
    # Evenly spaced picks may land on rows already kept: top the budget up a few times.
    rows, n_even = keep, max_samples - keep.size
    for _ in range(4):
        merged = np.union1d(keep, playback.frame_rows(n_even))
        if merged.size > max_samples:
            break
        rows = merged
        if merged.size == max_samples:
            break
        n_even += max_samples - merged.size
    return rows


def default_speed(duration: float) -> float:
    """The playback-speed factor that plays a figure of ``duration`` in about 25 s of real time.

    One of :data:`SPEED_FACTORS` (the one nearest on a log scale), or, for a figure so short or so
    long that none of them comes within a factor of two, the exact factor rounded to two
    significant digits.
    """
    if not math.isfinite(duration) or duration <= 0:
        return 1.0
    ideal = duration / TARGET_PLAY_SECONDS
    best = min(SPEED_FACTORS, key=lambda f: abs(math.log(f / ideal)))
    if abs(math.log(best / ideal)) <= math.log(2.0):
        return best
    return float(f"{ideal:.2g}")


def _round_list(values: np.ndarray, digits: int, scale: float | None = None) -> list:
    """``values`` as a JSON-ready list, rounded to ``digits`` significant digits of ``scale``.

    ``scale`` defaults to the largest finite magnitude in ``values``; values far below it round
    to 0, which keeps near-zero noise (1e-16) out of the file. Non-finite values become ``None``.
    """
    v = np.asarray(values, dtype=float)
    finite = np.isfinite(v)
    if scale is None:
        scale = float(np.max(np.abs(v[finite]))) if finite.any() else 0.0
    decimals = digits - 1 - math.floor(math.log10(scale)) if scale > 0 else 0
    out: list = []
    for x, ok in zip(v.tolist(), finite.tolist()):
        if not ok:
            out.append(None)
            continue
        r = round(x, decimals) + 0.0  # + 0.0 turns -0.0 into 0.0
        out.append(int(r) if r.is_integer() and abs(r) < 1e15 else r)
    return out


def _nonfinite_name(x: float) -> str:
    return "nan" if math.isnan(x) else ("inf" if x > 0 else "-inf")


def _jsonable(obj: Any) -> Any:
    """``obj`` with numpy scalars made Python ones, non-finite floats made strings, other objects text."""
    return json_safe(obj, nonfinite=_nonfinite_name, other=str)


def _simplify(points: np.ndarray, tolerance: float) -> np.ndarray:
    """The columns of a ``(2, k)`` polyline that keep it within ``tolerance`` (Douglas-Peucker)."""
    k = points.shape[1]
    if k <= 2:
        return points
    pts = points.T
    keep = np.zeros(k, dtype=bool)
    keep[[0, k - 1]] = True
    stack = [(0, k - 1)]
    while stack:
        i, j = stack.pop()
        if j - i < 2:
            continue
        seg = pts[j] - pts[i]
        rel = pts[i + 1:j] - pts[i]
        length = math.hypot(seg[0], seg[1])
        if length > 0:
            dist = np.abs(seg[0] * rel[:, 1] - seg[1] * rel[:, 0]) / length
        else:
            dist = np.hypot(rel[:, 0], rel[:, 1])
        m = int(np.argmax(dist))
        if dist[m] > tolerance:
            keep[i + 1 + m] = True
            stack += [(i, i + 1 + m), (i + 1 + m, j)]
    return points[:, keep]


def _units(unit: str) -> dict[str, str]:
    if unit == "m":
        return {"length": "m", "time": "s", "speed": "m/s", "energy": "J", "mass": "kg", "inertia": "kg m²",
                "label": "SI (metres, seconds)"}
    return {"length": "", "time": "", "speed": "", "energy": "", "mass": "", "inertia": "",
            "label": "model units (the paper's)"}


def _number(x: Any, fmt: str = ".4g") -> str:
    if isinstance(x, bool) or x is None:
        return "–" if x is None else str(x)
    if isinstance(x, (int, float, np.integer, np.floating)):
        x = float(x)
        if math.isnan(x):
            return "NaN"
        if math.isinf(x):
            return "∞" if x > 0 else "−∞"
        return re.sub(r"e([+-])0*(\d)", lambda m: "e" + m.group(1).replace("+", "") + m.group(2), format(x, fmt))
    return str(x)


def _float(x: Any) -> float | None:
    try:
        return float(x)
    except (TypeError, ValueError):
        return None


def _checks(summary: dict[str, Any], units: dict[str, str]) -> list[dict[str, Any]]:
    """The verification checks shown in the page's table: name, value, limit, passed (or None)."""
    ver = summary.get("verification")
    rows: list[dict[str, Any]] = [{
        "name": "trace", "value": str(summary.get("status", "–")), "limit": str(summary.get("message", "")),
        "passed": None if summary.get("success") is None else bool(summary.get("success")),
    }]
    if not isinstance(ver, dict):
        rows.append({"name": "verification", "value": "not verified", "limit": "no report.json",
                     "passed": None})
        return rows
    status = str(ver.get("status", "–"))
    message = str(ver.get("message") or "")
    unit = f" {units['length']}" if units["length"] else ""
    dev, tol = _float(ver.get("max_deviation")), _float(ver.get("tolerance"))
    size = _float(ver.get("figure_size"))
    dev_ok = None if dev is None or tol is None else bool(dev <= tol)  # NaN compares False
    rel = (f" ({_number(tol / size, '.2g')} × figure size {_number(size)}{unit})"
           if size and tol is not None and math.isfinite(size) and size > 0 else "")
    rows.append({"name": "max deviation from the figure", "value": _number(dev, ".3e") + unit,
                 "limit": f"≤ {_number(tol, '.3e')}{unit}{rel}", "passed": dev_ok})
    cusp = _float(ver.get("max_cusp_speed"))
    cusp_ok = None if cusp is None else bool(math.isfinite(cusp) and not (status == "failed" and "cusp" in message))
    rows.append({"name": "max speed at a rest (cusp)", "value": _number(cusp, ".3e"),
                 "limit": "≤ 1e-8 × the section's fastest motion", "passed": cusp_ok})
    rows.append({"name": "verification", "value": status, "limit": message,
                 "passed": status == "passed" if status in ("passed", "failed") else None})
    return rows + _feasibility_rows(summary.get("feasibility"))


def _feasibility_rows(feas: Any) -> list[dict[str, Any]]:
    """The feasibility checks (could a skater do it?) as rows of the checks table."""
    if not isinstance(feas, dict):
        return [{"name": "humanly feasible", "value": "not assessed", "limit": "no feasibility in report.json",
                 "passed": None, "kind": "feasibility"}]
    rows = []
    for c in feas.get("checks") or []:
        if not isinstance(c, dict):
            continue
        unit = f" {c['unit']}" if c.get("unit") else ""
        sign = "≥" if c.get("name") == "singular_approach" else "≤"
        where = "" if c.get("section") is None else f" (worst in section {c['section']}" + \
            ("" if c.get("time") is None else f", t = {_number(c.get('time'))}") + ")"
        title = str(c.get("title") or str(c.get("name", "")).replace("_", " "))
        rows.append({"name": f"feasible: {title}", "value": _number(c.get("value"), ".3g") + unit,
                     "limit": f"{sign} {_number(c.get('limit'), '.3g')}{unit}{where}",
                     "passed": None if c.get("passed") is None else bool(c["passed"]), "kind": "feasibility"})
    info = feas.get("info") if isinstance(feas.get("info"), dict) else {}
    force, impulse = info.get("force_unit", ""), info.get("impulse_unit", "")
    for key, name, unit in (("peak_force_on_mass", "peak force on the mass", force),
                            ("max_cusp_mass_speed", "mass speed at a cusp (relative to the stopped blade)", ""),
                            ("max_cusp_impulse", "impulse on the mass at a cusp", impulse)):
        if key in info:  # measured, without a limit: reported beside the checks
            rows.append({"name": name, "value": _number(info[key], ".3g") + (f" {unit}" if unit else ""),
                         "limit": "reported", "passed": None, "kind": "feasibility"})
    rows.append({"name": "humanly feasible", "value": str(feas.get("status", "–")),
                 "limit": str((feas.get("limits") or {}).get("assumptions", "")),
                 "passed": None if feas.get("feasible") is None else bool(feas["feasible"]), "kind": "feasibility"})
    return rows


def _summary_rows(playback: Playback, units: dict[str, str]) -> list[tuple[str, str]]:
    s = playback.summary
    p = s.get("params") or {}
    if not p:
        p = {"M": playback.params.M, "m": playback.params.m, "I": playback.params.I}
    mu, iu = (f" {units['mass']}", f" {units['inertia']}") if units["mass"] else ("", "")
    params = ", ".join(f"{k} = {_number(v)}{iu if k == 'I' else mu}" for k, v in p.items())
    tu = f" {units['time']}" if units["time"] else ""
    return [
        ("figure", str(s.get("figure", playback.name))),
        ("sections", _number(s.get("sections", int(playback.section.max()) + 1 if playback.section.size else 0))),
        ("duration", f"{_number(s.get('duration', playback.duration), '.4f')}{tu}"),
        ("parameters", params),
        ("units", units["label"]),
    ] + ([("reach", f"{_number(s['reach'])}{' ' + units['length'] if units.get('length') else ''} (the planner's; "
                    "circle around the blade)")] if isinstance(s.get("reach"), (int, float)) else [])


def _tables_html(playback: Playback, units: dict[str, str]) -> tuple[str, str]:
    """The summary and verification tables, HTML-escaped."""
    e = html.escape
    summary = "\n".join(f'<tr><th scope="row">{e(k)}</th><td>{e(v)}</td></tr>'
                        for k, v in _summary_rows(playback, units))
    rows = []
    for c in _checks(playback.summary, units):
        if c.get("kind") == "feasibility":  # a second verdict, not a failure of the controls
            state = {True: ("pass", "✔ within"), False: ("warn", "⚠ beyond"), None: ("unknown", "–")}[c["passed"]]
        else:
            state = {True: ("pass", "✔ passed"), False: ("fail", "✘ FAILED"), None: ("unknown", "–")}[c["passed"]]
        rows.append(f'<tr class="check {state[0]}"><th scope="row">{e(c["name"])}</th><td>{e(c["value"])}</td>'
                    f'<td>{e(c["limit"])}</td><td class="result">{e(state[1])}</td></tr>')
    return summary, "\n".join(rows)


def _overall(summary: dict[str, Any]) -> tuple[str, str]:
    """CSS class and text of the status badge next to the title."""
    ver = summary.get("verification")
    if isinstance(ver, dict) and ver.get("status") in ("passed", "failed"):
        feas = summary.get("feasibility")
        verdict = summary.get("verdict")
        if ver["status"] == "passed" and isinstance(feas, dict) and isinstance(verdict, str):
            # Both verdicts: exact for the model, and whether a skater could do it.
            return ("pass", verdict) if feas.get("feasible") else ("warn", verdict)
        return ("pass", "verified") if ver["status"] == "passed" else ("fail", verdict or "verification failed")
    if summary.get("success") is False:
        return "fail", str(summary.get("status", "failed"))
    return "unknown", "not verified"


def _figure_bounds(playback: Playback, margin: float = 0.05) -> tuple[float, float, float, float]:
    """``(xmin, xmax, ymin, ymax)`` enclosing the target figure and the blade's path (not the mass)."""
    xs = np.concatenate([playback.x] + [np.asarray(p[0], dtype=float) for p in playback.figure])
    ys = np.concatenate([playback.y] + [np.asarray(p[1], dtype=float) for p in playback.figure])
    xs, ys = xs[np.isfinite(xs)], ys[np.isfinite(ys)]
    if xs.size == 0 or ys.size == 0:
        return playback.bounds(margin)
    x0, x1, y0, y1 = float(xs.min()), float(xs.max()), float(ys.min()), float(ys.max())
    pad = margin * max(x1 - x0, y1 - y0, 1e-12)
    return x0 - pad, x1 + pad, y0 - pad, y1 + pad


def _data(playback: Playback, max_samples: int) -> dict[str, Any]:
    rows = sample_rows(playback, max_samples)
    pb = playback
    xmin, xmax, ymin, ymax = bounds = pb.bounds()
    extent = max(xmax - xmin, ymax - ymin, 1e-12)
    series: dict[str, Any] = {}
    for name, digits in _DIGITS.items():
        col = np.asarray(getattr(pb, name), dtype=float)[rows]
        scale = extent if name in ("x", "y") else None
        series[name] = _round_list(col, digits, scale)
    # sections as runs: [first embedded row, section] wherever the section changes
    sec = np.asarray(pb.section)[rows]
    changes = np.flatnonzero(np.diff(sec, prepend=sec[0] - 1) != 0)
    sections = [[int(r), int(sec[r])] for r in changes]
    figure = []
    for poly in pb.figure:
        pts = _simplify(np.asarray(poly, dtype=float), _FIGURE_TOLERANCE * extent)
        figure.append([_round_list(pts[0], _FIGURE_DIGITS, extent), _round_list(pts[1], _FIGURE_DIGITS, extent)])
    duration = pb.duration
    speed = default_speed(duration)
    speeds = sorted(set(SPEED_FACTORS) | {speed})
    units = _units(pb.unit)
    n_sections = int(pb.summary.get("sections", int(np.max(pb.section)) + 1 if pb.section.size else 0))
    return {
        "schema": "skatetrace.viewer/1",
        "name": pb.name,
        "unit": pb.unit,
        "units": units,
        "params": _jsonable({"M": pb.params.M, "m": pb.params.m, "I": pb.params.I}),
        "rows": int(pb.t.size),
        "samples": int(rows.size),
        "t0": float(pb.t[0]),
        "duration": duration,
        "sections": n_sections,
        "bounds": _jsonable(list(bounds)),
        "views": {"all": _jsonable(list(bounds)), "figure": _jsonable(list(_figure_bounds(pb)))},
        "speeds": speeds,
        "default_speed": speed,
        "series": series,
        "section_runs": sections,
        "figure": figure,
        "rests": {"x": _round_list(pb.rests[0], 7, extent), "y": _round_list(pb.rests[1], 7, extent),
                  "t": _round_list(pb.rest_times, 9)},
        "summary": _jsonable(pb.summary),
    }


def _script_json(data: dict[str, Any]) -> str:
    """``data`` as JSON safe inside a ``<script>`` element (no ``<``, ``>``, ``&``; ASCII only)."""
    text = json.dumps(data, ensure_ascii=True, allow_nan=False, separators=(",", ":"))
    return text.replace("<", "\\u003c").replace(">", "\\u003e").replace("&", "\\u0026")


def _web_file(*parts: str) -> str:
    return resources.files(__package__).joinpath(*parts).read_text(encoding="utf-8")


def viewer_html(playback: Playback | str | Path, *, max_samples: int = 4000) -> str:
    """The viewer page for ``playback`` as one HTML document.

    Parameters
    ----------
    playback : Playback, or str or Path
        A loaded playback, or the output folder of ``skatetrace trace`` (read with
        :func:`~skatetrace.outputs.playback.load_playback`).
    max_samples : int
        The most rows of the time series embedded (see :func:`sample_rows`).

    Returns
    -------
    str
        A complete HTML document that needs no network and no other file.

    Raises
    ------
    ValueError
        ``max_samples`` below 2.
    SkatetraceError
        ``playback`` names a folder whose result files are missing or unreadable.
    """
    if not isinstance(playback, Playback):
        playback = load_playback(playback)
    template, css, js = (_web_file(*p) for p in _WEB)
    if re.search(r"</script|<!--", js, re.IGNORECASE) or re.search(r"</style", css, re.IGNORECASE):
        raise RuntimeError("the viewer's script or style sheet would close its own element")
    units = _units(playback.unit)
    summary_rows, check_rows = _tables_html(playback, units)
    badge_class, badge_text = _overall(playback.summary)
    parts = {
        "TITLE": html.escape(f"{playback.name} · skatetrace viewer"),
        "NAME": html.escape(playback.name),
        "BADGE_CLASS": badge_class,
        "BADGE": html.escape(badge_text),
        "CSS": css,
        "JS": js,
        "DATA": _script_json(_data(playback, max_samples)),
        "SUMMARY_ROWS": summary_rows,
        "CHECK_ROWS": check_rows,
    }
    # One pass: text substituted in is never searched for placeholders again.
    return _PLACEHOLDER.sub(lambda m: parts[m.group(1)], template)


def write_viewer(playback: Playback | str | Path, path: str | Path, *, max_samples: int = 4000) -> Path:
    """Write the viewer page for ``playback`` to ``path`` and return the file's path.

    Parameters
    ----------
    playback : Playback, or str or Path
        A loaded playback, or the output folder of ``skatetrace trace``.
    path : str or Path
        The HTML file to write (parent folders are created); an existing folder gets a
        ``viewer.html`` in it.
    max_samples : int
        The most rows of the time series embedded (see :func:`sample_rows`).

    Returns
    -------
    Path
        The file written (UTF-8).
    """
    path = Path(path)
    if path.is_dir():
        path = path / "viewer.html"
    text = viewer_html(playback, max_samples=max_samples)
    atomic_write(path, text.encode("utf-8", errors="replace"))  # a lone surrogate becomes "?"
    return path
