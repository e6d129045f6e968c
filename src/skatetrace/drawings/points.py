"""Point lists (CSV or whitespace columns, from a file or text) as smooth spline paths.

Point lists become cubic splines through the points (scipy's ``CubicSpline`` on cumulative chord
length, periodic when closed; ``CubicHermiteSpline`` on an arc-length estimate when tangents are
given), split into pieces at corners (a point repeated on consecutive lines). Coordinates are the
file's own, as model units. Malformed lines, non-finite or huge (beyond ``MAX_COORD``) values, zero
tangents, too few points and missing files raise :class:`DrawingError` naming the file and line.
"""

from __future__ import annotations

import math
import os
import re
from typing import Sequence

import numpy as np
from scipy.interpolate import CubicHermiteSpline, CubicSpline

from .curves import Drawing, LinePiece, Path, Piece, SplinePiece
from .files import file_stem, read_bytes
from .lengths import CLOSE_TOL, MAX_COORD, extent
from ..errors import DrawingError

__all__ = ["read_points", "POINT_SUFFIXES"]

POINT_SUFFIXES = (".csv", ".txt", ".dat")
"""File suffixes of point lists (:func:`skatetrace.drawings.load.load_drawing` reads them with :func:`read_points`)."""

_FIELDS = re.compile(r"[,\s]+")


def read_points(source: str | os.PathLike, *, closed: bool | None = None) -> Drawing:
    """Read point lists (CSV or whitespace columns) as smooth spline paths.

    Parameters
    ----------
    source : str or os.PathLike
        A file name, or the text itself (a string containing a line break).
        Each line holds ``x, y`` or ``x, y, tx, ty`` (a tangent, any length), separated by commas
        and/or white space. A header line may come first; ``#`` starts a comment; a blank line
        ends a path and starts the next. A point repeated on consecutive lines marks a corner;
        with tangents, the first copy carries the incoming and the second the outgoing tangent.
    closed : bool, optional
        ``None`` (default): a path is closed when its first and last points coincide. ``True``:
        every path is closed (joined back to its first point if needed). ``False``: all open.

    Returns
    -------
    Drawing
        In the file's units (``unit="model"``), named after the file. Each path is one
        :class:`SplinePiece` per run between corners (a :class:`LinePiece` for two points without
        tangents) on ``t`` in ``[0, 1]``. Without tangents: a cubic spline (periodic if closed
        without corners, not-a-knot otherwise) with knots at the cumulative chord length,
        normalised. With tangents: a cubic Hermite spline whose derivative at each point is the unit
        tangent times the run's estimated length, its knots at cumulative arc-length estimates
        (each chord lengthened by ``(phi/2) / sin(phi/2)``, ``phi`` the turn between the tangents
        at its ends: exact for a circular arc; in each interval's own parameter, this is the unit
        tangent scaled by the local chord length, corrected for the turn). A closed path with
        corners starts at its first corner.

    Raises
    ------
    DrawingError
        Missing file; a line that is not numbers (naming it); 3 or more than 4 columns, or a
        column count that changes; non-finite or huge values; a zero tangent; a path with fewer
        than 2 distinct points (3 for a closed path without tangents).

    Examples
    --------
    >>> text = '''x, y
    ... 0, 0
    ... 1, 1
    ... 2, 0
    ... 2, 0
    ... 3, 1
    ... '''
    >>> drawing = read_points(text)
    >>> path = drawing.paths[0]
    >>> [type(p).__name__ for p in path.pieces], path.closed   # a corner at (2, 0)
    (['SplinePiece', 'LinePiece'], False)
    >>> path.pieces[0].point([0.0, 1.0]).T.tolist()
    [[0.0, 0.0], [2.0, 0.0]]
    """
    if closed not in (None, True, False):
        raise DrawingError(f"closed must be None, True or False, got {closed!r}")
    text, origin, name = _read_text(source)
    blocks = _point_blocks(text, origin)
    all_points = np.vstack([block[1][:, :2] for block in blocks])
    largest = float(np.abs(all_points).max())
    if largest > MAX_COORD:
        raise DrawingError(f"{origin}: coordinates reach {largest:.3g}, beyond the supported {MAX_COORD:.0e}: "
                           "rescale the points")
    size = extent(all_points.T)
    if not size > 0:
        raise DrawingError(f"{origin}: all points coincide; expected at least 2 distinct points")
    tol = CLOSE_TOL * size
    notes: list[str] = []
    paths = []
    for k, (lines, rows) in enumerate(blocks, start=1):
        label = name if len(blocks) == 1 else f"{name}#{k}"
        where = f"{origin}, lines {lines[0]}-{lines[-1]}"
        paths.append(_points_path(rows, lines, closed, tol, label, where, notes))
    return Drawing(tuple(paths), name=name, source=origin, unit="model", notes=tuple(notes))


def _read_text(source) -> tuple[str, str, str]:
    if isinstance(source, os.PathLike) or (isinstance(source, str) and "\n" not in source):
        file_name = os.fspath(source)
        data = read_bytes(file_name, "point list")
        try:
            return data.decode("utf-8-sig"), file_name, file_stem(file_name)
        except UnicodeDecodeError as exc:
            raise DrawingError(f"{file_name!r} is not a UTF-8 text file ({exc.reason} at byte {exc.start}); "
                               "expected lines of 'x, y' or 'x, y, tx, ty'") from exc
    if isinstance(source, str):
        return source, "the point text", "points"
    raise DrawingError(f"read_points expects a file name or text, got {type(source).__name__}")


def _point_blocks(text: str, origin: str) -> list[tuple[list[int], np.ndarray]]:
    """Blank-line separated blocks of rows: (line numbers, array of shape (n, 2 or 4))."""
    blocks: list[tuple[list[int], list[list[float]]]] = []
    current: tuple[list[int], list[list[float]]] = ([], [])
    columns, columns_line, header_allowed = None, 0, True
    for number, raw in enumerate(text.splitlines(), start=1):
        content = raw.split("#", 1)[0].strip()
        if not content:
            if not raw.strip() and current[0]:
                blocks.append(current)
                current = ([], [])
            continue
        fields = [f for f in _FIELDS.split(content) if f]
        try:
            values = [float(f) for f in fields]
        except ValueError:
            if header_allowed:
                header_allowed = False
                continue
            raise DrawingError(f"{origin}, line {number}: cannot read {content!r} as numbers; expected "
                               "'x, y' or 'x, y, tx, ty' (a header is allowed only before the first point)") from None
        header_allowed = False
        if len(values) not in (2, 4):
            raise DrawingError(f"{origin}, line {number}: {len(values)} values in {content!r}; expected 2 (x, y) "
                               "or 4 (x, y, tx, ty)")
        if columns is None:
            columns, columns_line = len(values), number
        elif len(values) != columns:
            raise DrawingError(f"{origin}, line {number}: {len(values)} values, but line {columns_line} has "
                               f"{columns}: every point needs the same columns (x, y or x, y, tx, ty)")
        if not all(math.isfinite(v) for v in values):
            raise DrawingError(f"{origin}, line {number}: {content!r} is not finite; expected ordinary numbers")
        if columns == 4 and values[2] == 0.0 and values[3] == 0.0:
            raise DrawingError(f"{origin}, line {number}: the tangent (0, 0) has no direction; give a non-zero "
                               "(tx, ty) or leave the tangent columns out")
        current[0].append(number)
        current[1].append(values)
    if current[0]:
        blocks.append(current)
    if not blocks:
        raise DrawingError(f"no points found in {origin}: expected lines of 'x, y' or 'x, y, tx, ty'")
    return [(lines, np.array(rows, dtype=float)) for lines, rows in blocks]


def _points_path(rows: np.ndarray, lines: list[int], closed: bool | None, tol: float, label: str,
                 where: str, notes: list[str]) -> Path:
    points = rows[:, :2]
    tangents = None
    if rows.shape[1] == 4:  # unit tangents; scaled by their largest component first so that hypot cannot overflow
        tangents = rows[:, 2:4] / np.abs(rows[:, 2:4]).max(axis=1)[:, None]
        tangents /= np.hypot(tangents[:, 0], tangents[:, 1])[:, None]
    # Groups of consecutive coincident points: one point each, a corner if repeated.
    groups = [[0]]
    for i in range(1, len(points)):
        if np.hypot(*(points[i] - points[i - 1])) <= tol:
            groups[-1].append(i)
        else:
            groups.append([i])
    Q = [points[g[0]] for g in groups]
    corner = [len(g) > 1 for g in groups]
    t_in = [tangents[g[0]] if tangents is not None else None for g in groups]
    t_out = [tangents[g[-1]] if tangents is not None else None for g in groups]
    line_of = [lines[g[0]] for g in groups]
    if len(Q) < 2:
        raise DrawingError(f"{where}: a path needs at least 2 distinct points, got {len(Q)}")

    coincide = len(Q) >= 3 and np.hypot(*(Q[-1] - Q[0])) <= tol
    is_closed = coincide if closed is None else closed
    if is_closed and coincide:  # the last point is the first again: merge them
        corner[0] = corner[0] or corner[-1]
        t_in[0] = t_in[-1]
        for seq in (Q, corner, t_in, t_out, line_of):
            seq.pop()
    n = len(Q)
    if is_closed and n < (2 if tangents is not None else 3):
        raise DrawingError(f"{where}: a closed path needs at least 3 distinct points "
                           f"(2 with tangents), got {n}")

    if is_closed:
        corners = [i for i in range(n) if corner[i]]
        if not corners:
            order = list(range(n)) + [0]
            return Path((_spline_piece(order, Q, t_in, t_out, periodic=True),), closed=True, name=label)
        start = corners[0]
        if start != 0:
            notes.append(f"{where}: closed path {label} starts at its first corner, line {line_of[start]}")
        order = list(range(start, n)) + list(range(0, start)) + [start]
        cuts = [k for k in range(1, len(order) - 1) if corner[order[k]]]
    else:
        order = list(range(n))
        cuts = [k for k in range(1, n - 1) if corner[k]]
    bounds = [0, *cuts, len(order) - 1]
    pieces = tuple(_spline_piece(order[a: b + 1], Q, t_in, t_out, periodic=False) for a, b in zip(bounds, bounds[1:]))
    return Path(pieces, closed=bool(is_closed), name=label)


def _spline_piece(run: Sequence[int], Q, t_in, t_out, *, periodic: bool) -> Piece:
    """A piece through ``Q[run]``: the run's ends take their outgoing/incoming tangent."""
    pts = np.array([Q[i] for i in run], dtype=float)
    if periodic:
        pts[-1] = pts[0]  # exactly, as scipy's periodic condition demands
    chords = np.hypot(*np.diff(pts, axis=0).T)
    if t_in[run[0]] is None:
        if len(run) == 2:
            return LinePiece((float(pts[0, 0]), float(pts[0, 1])), (float(pts[1, 0]), float(pts[1, 1])))
        u = _normalised_cumsum(chords)
        return SplinePiece(CubicSpline(u, pts, bc_type="periodic" if periodic else "not-a-knot"), 0.0, 1.0)
    tangents = np.array([t_out[run[0]], *(t_in[i] for i in run[1:])])
    if periodic:
        tangents[-1] = tangents[0]
    # Arc-length steps: a chord subtending a turn phi between its end tangents is an arc
    # chord * (phi/2) / sin(phi/2) long if circular; with these steps unit tangents are the exact
    # speed of a circle, where plain chords would make the Hermite cubics run short.
    half = 0.5 * np.arccos(np.clip(np.sum(tangents[:-1] * tangents[1:], axis=1), -1.0, 1.0))
    steps = chords * np.where(half > 1e-8, half / np.sin(np.maximum(half, 1e-8)), 1.0)
    u = _normalised_cumsum(steps)
    return SplinePiece(CubicHermiteSpline(u, pts, float(steps.sum()) * tangents), 0.0, 1.0)


def _normalised_cumsum(steps: np.ndarray) -> np.ndarray:
    """Knots ``0 = u0 < u1 < ... < un = 1`` spaced like ``steps`` (normalised: any scale of input)."""
    u = np.concatenate([[0.0], np.cumsum(steps / steps.sum())])
    u[-1] = 1.0
    if not np.all(np.diff(u) > 0.0):
        # a step lost in the rounding of the run's total (1e3 beside 1e12): scipy would refuse the knots
        raise DrawingError(f"two consecutive points are {float(np.min(steps)):.3g} apart on a run "
                           f"{float(steps.sum()):.3g} long: too close to tell apart in double precision; remove the "
                           "repeated point or rescale the coordinates")
    return u
