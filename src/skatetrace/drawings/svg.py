"""Any figure in: SVG drawings, point lists and parametric functions as a :class:`~skatetrace.drawings.curves.Drawing`.

Coordinates
-----------
SVG user units (the ``viewBox`` coordinates, after every group and element ``transform``) become
model units one to one, with the y axis flipped: SVG's y points down the page, ours points up, so
a drawing keeps its handedness (a loop drawn clockwise on screen is clockwise here too). The
page size (``width="210mm"``) is paper, not ice: it is recorded in the drawing's ``notes`` and
otherwise ignored. Scale a drawing to the ice with :meth:`Drawing.scaled_to` and a size from
:func:`parse_length`.

Exactness
---------
SVG segments become pieces with exact derivatives: ``L``/``H``/``V``/``Z`` lines become
:class:`LinePiece`, ``Q``/``T``/``C``/``S`` :class:`BezierPiece`, ``A`` :class:`EllipticArcPiece`.
The affine transforms (and the y flip) are applied to the parameters themselves: an affine map
of a Bézier is the Bézier of the mapped control points, and an affine map of an elliptic arc is
an elliptic arc whose axes come from the singular value decomposition of the map. svgpathtools
reads the XML, walks the groups, composes the transforms and parses the path data; its own arc
transform is not used because it chooses the wrong arc for some reflections (e.g.
``matrix(0 1 1 0)``) and fails on singular matrices.

Point lists become cubic splines through the points (scipy's ``CubicSpline`` on cumulative chord
length, periodic when closed; ``CubicHermiteSpline`` on an arc-length estimate when tangents are
given), split into pieces at corners (a point repeated on consecutive lines).

Degenerate input
----------------
Exactly zero-length segments are dropped (with a note); tiny ones are kept. A Bézier with a
zero-length handle is kept (its derivative vanishes at that end; a note says so). An element
made only of zero-length segments, non-finite or huge (beyond ``1e100``) coordinates, a singular
transform, malformed XML or path data, and missing files raise :class:`DrawingError` with the
file, element or line and what would be accepted.
"""

from __future__ import annotations

import io
import math
import os
import pathlib
import re
import warnings
import xml.etree.ElementTree as ET
from typing import Callable, Sequence

import numpy as np
from scipy.interpolate import CubicHermiteSpline, CubicSpline
from svgpathtools import Arc, CubicBezier, Document, Line, QuadraticBezier, parse_path
from svgpathtools.document import CONVERSIONS

from .curves import BezierPiece, Drawing, EllipticArcPiece, FunctionPiece, LinePiece, Path, Piece, SplinePiece
from ..errors import DrawingError

__all__ = [
    "read_svg", "parse_path_string", "read_points", "from_function", "parse_length", "load_drawing",
    "SVG_SUFFIXES", "POINT_SUFFIXES", "CLOSE_TOL", "MAX_COORD",
]

SVG_SUFFIXES = (".svg",)
POINT_SUFFIXES = (".csv", ".txt", ".dat")

CLOSE_TOL = 1e-9
"""Points closer than ``CLOSE_TOL`` times the drawing's size coincide (closure, repeated points)."""

MAX_COORD = 1e100
"""Largest coordinate accepted: beyond it, squares of lengths (curvature, areas) overflow."""

_SVG_NS = "{http://www.w3.org/2000/svg}"
_FLIP = np.array([[1.0, 0.0], [0.0, -1.0]])
_SAMPLES = np.linspace(0.0, 1.0, 17)

# What svgpathtools (and the XML parser under it) raises on input it cannot read. Caught only around
# calls into it, and always re-raised as a DrawingError that says which file and element failed.
_LIBRARY_ERRORS = (ValueError, TypeError, ArithmeticError, AssertionError, IndexError, KeyError, AttributeError)


# ----------------------------------------------------------------------------------------------------
# SVG
# ----------------------------------------------------------------------------------------------------
def read_svg(source: str | os.PathLike) -> Drawing:
    """Read the paths of an SVG document as a drawing, one :class:`Path` per continuous subpath.

    Parameters
    ----------
    source : str or os.PathLike
        A file name, or the SVG text itself (a string containing ``<``).

    Returns
    -------
    Drawing
        In SVG user units (``unit="model"``) with the y axis pointing up. Paths are in document
        order, named by the element's ``id`` (``"id#2"`` for its second subpath) or by its tag and
        position (``"path-3"``). A subpath is ``closed`` when its end meets its start within
        ``CLOSE_TOL`` times the drawing's size. ``notes`` records the page size, dropped
        zero-length segments, zero-length Bézier handles and svgpathtools' warnings.

    Raises
    ------
    DrawingError
        Missing or unreadable file, malformed XML, invalid ``transform`` or path data, a singular
        transform, an element made only of zero-length segments, non-finite or huge coordinates,
        or a document without any drawable element.

    Notes
    -----
    Elements read (through svgpathtools' ``Document.paths``): ``path``, ``rect`` (also rounded),
    ``circle``, ``ellipse``, ``line``, ``polyline`` and ``polygon``, inside the root and nested
    ``<g>`` groups, with every ``transform`` on the way. Not read: ``<use>`` clones, ``<symbol>``,
    nested ``<svg>``, ``<a>`` and ``<switch>`` containers, text, clip paths, ``<defs>`` (never
    drawn by itself), CSS transforms, and ``display:none`` (hidden layers are read like visible
    ones). An SVG without the SVG namespace declaration is read as if it had one. An invalid
    ``transform`` attribute is an error with svgpathtools 1.8 or later; older versions skip it
    with a warning, which goes into ``notes``.

    Examples
    --------
    >>> svg = '''<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 100 100">
    ...   <g transform="translate(50,50)">
    ...     <path id="loop" d="M -20,0 a 20,20 0 0 1 40,0 a 20,20 0 0 1 -40,0 z"/>
    ...   </g>
    ... </svg>'''
    >>> drawing = read_svg(svg)
    >>> [(p.name, p.closed, len(p.pieces), type(p.pieces[0]).__name__) for p in drawing.paths]
    [('loop', True, 2, 'EllipticArcPiece')]
    >>> [round(v, 9) for v in drawing.bbox()]   # y flipped: the page's centre (50, 50) is (50, -50)
    [30.0, -70.0, 70.0, -30.0]
    """
    if isinstance(source, os.PathLike) or (isinstance(source, str) and "<" not in source):
        file_name = os.fspath(source)
        stream: io.IOBase = io.BytesIO(_read_bytes(file_name, "SVG"))
        origin, name = file_name, _stem(file_name)
    elif isinstance(source, str):
        stream, origin, name = io.StringIO(source), "the SVG text", "svg"
    else:
        raise DrawingError(f"read_svg expects a file name or SVG text, got {type(source).__name__}")

    document = _parse_document(stream, origin)
    root = document.tree.getroot()
    _adopt_svg_namespace(root)
    notes = list(_page_notes(root))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            # Empty path data for every element: we only want svgpathtools' walk of the groups and the
            # composed transform of each element, and parse and transform the geometry ourselves.
            found = document.paths(path_conversions={tag: _no_path_data for tag in CONVERSIONS})
        except _LIBRARY_ERRORS as exc:
            raise DrawingError(f"{origin}: a transform attribute cannot be read ({exc}); expected e.g. "
                               "'translate(10,20) rotate(30) scale(2) matrix(a,b,c,d,e,f)'") from exc
    notes.extend(f"{origin}: {message}" for message in dict.fromkeys(str(w.message) for w in caught))
    order = {id(element): k for k, element in enumerate(root.iter())}
    found.sort(key=lambda p: order.get(id(p.element), 0))

    entries = []
    for k, svg_path in enumerate(found, start=1):
        element = svg_path.element
        tag = _local_tag(element.tag)
        label = f"<{tag} id={element.get('id')!r}>" if element.get("id") else f"<{tag}> number {k}"
        where = f"{origin}: {label}"
        try:
            d = CONVERSIONS[tag](element)
        except _LIBRARY_ERRORS as exc:
            raise DrawingError(f"{where} cannot be turned into path data ({exc!r}); check its "
                               "geometry attributes (e.g. a circle needs cx, cy and r)") from exc
        segments = _parse_d(d, where, notes)
        if not segments:
            notes.append(f"{where} is empty and was skipped")
            continue
        matrix = np.asarray(svg_path.transform if svg_path.transform is not None else np.eye(3), float)
        _check_transform(matrix, where)
        A, b = _FLIP @ matrix[:2, :2], _FLIP @ matrix[:2, 2]
        entries.append((element.get("id") or f"{tag}-{k}", where, segments, A, b))
    if not entries:
        hint = "" if _local_tag(root.tag) == "svg" else f" (the root element is <{_local_tag(root.tag)}>, not <svg>)"
        raise DrawingError(f"no paths found in {origin}{hint}: expected <path>, <rect>, <circle>, <ellipse>, "
                           "<line>, <polyline> or <polygon> elements with some extent")
    return _assemble(entries, name=name, source=origin, notes=notes)


def parse_path_string(d: str) -> Drawing:
    """Read SVG path data (the ``d`` attribute) as a drawing, one :class:`Path` per continuous subpath.

    Parameters
    ----------
    d : str
        SVG path data, e.g. ``"M 0 0 C 10 0 10 10 20 10"``; absolute and relative commands.

    Returns
    -------
    Drawing
        In the path's own units (``unit="model"``), y axis flipped to point up as in
        :func:`read_svg`. Paths are named ``"path"`` (``"path#2"`` for the second subpath).

    Raises
    ------
    DrawingError
        Empty or malformed path data, only zero-length segments, non-finite or huge coordinates.

    Examples
    --------
    >>> drawing = parse_path_string("M 0 0 C 10 0 10 10 20 10 M 0 -5 l 5 0")
    >>> [(p.name, type(p.pieces[0]).__name__) for p in drawing.paths]
    [('path#1', 'BezierPiece'), ('path#2', 'LinePiece')]
    >>> drawing.paths[0].pieces[0].control   # y flipped
    ((0.0, 0.0), (10.0, 0.0), (10.0, -10.0), (20.0, -10.0))
    """
    if not isinstance(d, str):
        raise DrawingError(f"path data must be a string like 'M 0 0 L 10 0', got {type(d).__name__}")
    if not d.strip():
        raise DrawingError("the path data is empty: expected SVG path data such as 'M 0 0 L 10 0'")
    notes: list[str] = []
    where = f"path data {_shorten(d)!r}"
    segments = _parse_d(d, where, notes)
    if not segments:
        raise DrawingError(f"{where} draws nothing (a lone 'M' makes no segment): expected e.g. 'M 0 0 L 10 0'")
    return _assemble([("path", where, segments, _FLIP, np.zeros(2))], name="path", source="path data", notes=notes)


def _read_bytes(file_name: str, kind: str) -> bytes:
    try:
        with open(file_name, "rb") as handle:
            return handle.read()
    except FileNotFoundError:
        raise DrawingError(f"{kind} file not found: {file_name!r} (current directory {os.getcwd()!r})") from None
    except OSError as exc:
        raise DrawingError(f"cannot read {kind} file {file_name!r}: {exc.strerror or exc}") from exc
    except ValueError:  # a NUL character: no file can have that name
        raise DrawingError(f"{_shorten(repr(file_name))} is no file name (it holds a NUL character); give a "
                           f"{kind} file, or its text over more than one line") from None


def _stem(file_name: str) -> str:
    return os.path.splitext(os.path.basename(file_name))[0] or "drawing"


def _parse_document(stream: io.IOBase, origin: str) -> Document:
    try:
        try:
            return Document(stream, strict_transform_parsing=True)
        except TypeError:  # svgpathtools < 1.8 has no strict mode: invalid transforms are skipped
            stream.seek(0)
            return Document(stream)
    except ET.ParseError as exc:
        raise DrawingError(f"{origin} is not well-formed XML ({exc}); expected an SVG document") from exc


def _adopt_svg_namespace(root: ET.Element) -> None:
    """Put un-namespaced elements in the SVG namespace (svgpathtools only finds ``svg:`` tags)."""
    if isinstance(root.tag, str) and not root.tag.startswith("{"):
        for element in root.iter():
            if isinstance(element.tag, str) and not element.tag.startswith("{"):
                element.tag = _SVG_NS + element.tag


def _local_tag(tag) -> str:
    return tag.rsplit("}", 1)[-1] if isinstance(tag, str) else str(tag)


def _page_notes(root: ET.Element):
    page = {key: root.get(key) for key in ("width", "height", "viewBox") if root.get(key)}
    if page:
        described = ", ".join(f"{key}={value!r}" for key, value in page.items())
        yield f"coordinates are SVG user units (page {described}), y flipped to point up"


def _no_path_data(element) -> str:
    return ""


def _shorten(text: str, n: int = 60) -> str:
    text = " ".join(text.split())
    return text if len(text) <= n else text[: n - 3] + "..."


def _parse_d(d: str, where: str, notes: list[str]) -> list:
    """svgpathtools segments of path data, its warnings appended to ``notes``."""
    if not d or not d.strip():
        return []
    if d.lstrip(" \t\r\n\f,")[:1] not in ("M", "m"):
        # SVG path data begins with a moveto; without one svgpathtools leaves segments without a start.
        raise DrawingError(f"{where}: the path data {_shorten(d)!r} cannot be read (it does not begin with a "
                           "moveto, 'M' or 'm'); expected SVG path commands such as 'M 0,0 c 10,0 10,10 20,10 z'")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            path = parse_path(d)
        except AssertionError as exc:
            # svgpathtools' Arc asserts distinct end points (zero radii are already turned into lines).
            raise DrawingError(f"{where}: an elliptical arc ('A'/'a') ends where it starts; SVG draws nothing "
                               "for it but svgpathtools cannot represent it: delete that arc command") from exc
        except _LIBRARY_ERRORS as exc:
            raise DrawingError(f"{where}: the path data {_shorten(d)!r} cannot be read ({exc}); expected SVG "
                               "path commands such as 'M 0,0 c 10,0 10,10 20,10 z'") from exc
    for message in dict.fromkeys(str(w.message) for w in caught):
        notes.append(f"{where}: {message}")
    return list(path)


def _check_transform(matrix: np.ndarray, where: str) -> None:
    """Refuse a composed SVG transform ``[[a, c, e], [b, d, f], [0, 0, 1]]`` that is not invertible."""
    A = matrix[:2, :2]
    scale = float(np.abs(A).max()) if np.all(np.isfinite(A)) else math.nan
    det = float(np.linalg.det(A)) if math.isfinite(scale) else math.nan
    if not (math.isfinite(det) and abs(det) > 1e-12 * scale * scale):
        (a, c, e), (b, d, f) = matrix[0], matrix[1]
        raise DrawingError(f"{where}: its transform matrix({a:g}, {b:g}, {c:g}, {d:g}, {e:g}, {f:g}) is singular "
                           f"(determinant {det:g}): it would flatten the drawing onto a line or a point; "
                           "fix the transform attribute of the element or of its groups")


def _is_zero_length(segment) -> bool:
    if isinstance(segment, Arc):
        return segment.start == segment.end
    return all(p == segment.start for p in segment.bpoints())


def _xy(A: np.ndarray, b: np.ndarray, z: complex) -> tuple[float, float]:
    p = A @ np.array([z.real, z.imag]) + b
    return float(p[0]) + 0.0, float(p[1]) + 0.0  # + 0.0: no -0.0 from the y flip


def _arc_piece(arc: Arc, A: np.ndarray, b: np.ndarray, where: str) -> EllipticArcPiece:
    """The exact image under ``x -> A x + b`` of svgpathtools' arc.

    svgpathtools: ``point(t) = c + R(phi) (rx cos th, ry sin th)``, ``th = radians(theta + t delta)``.
    The image is ``A c + b + M (cos th, sin th)`` with ``M = A R(phi) diag(rx, ry)``. Write
    ``M = U S V^T`` with ``U`` and ``V`` rotations (the reflection, if any, goes into the sign
    ``s`` of the second singular value); then ``V^T (cos th, sin th) = (cos(th - a), sin(th - a))``
    and a negative second radius is the same ellipse run with the angle negated.
    """
    phi = math.radians(arc.rotation)
    R = np.array([[math.cos(phi), -math.sin(phi)], [math.sin(phi), math.cos(phi)]])
    M = A @ R @ np.diag([arc.radius.real, arc.radius.imag])
    if not np.all(np.isfinite(M)):
        raise DrawingError(f"{where}: an elliptical arc's radii overflow under its transform; rescale the drawing")
    U, singular, Vt = np.linalg.svd(M)
    su, sv = np.sign(np.linalg.det(U)), np.sign(np.linalg.det(Vt))
    U = U @ np.diag([1.0, su])
    Vt = np.diag([1.0, sv]) @ Vt
    sign = float(su * sv)
    alpha = math.atan2(Vt[0, 1], Vt[0, 0])
    return EllipticArcPiece(
        centre=_xy(A, b, arc.center), rx=float(singular[0]), ry=float(singular[1]),
        rotation=math.atan2(U[1, 0], U[0, 0]),
        theta0=sign * (math.radians(arc.theta) - alpha), dtheta=sign * math.radians(arc.delta),
    )


def _svg_piece(segment, A: np.ndarray, b: np.ndarray, where: str) -> Piece:
    def finite(numbers) -> bool:
        return all(math.isfinite(z.real) and math.isfinite(z.imag) for z in numbers)

    if isinstance(segment, Arc):
        given = [segment.start, segment.end]
        if finite(given) and not finite([segment.radius, segment.center, complex(segment.theta, segment.delta)]):
            ends = f"{_xy(np.eye(2), np.zeros(2), segment.start)} to {_xy(np.eye(2), np.zeros(2), segment.end)}"
            raise DrawingError(f"{where}: the elliptical arc from {ends} cannot be evaluated in double precision "
                               "(svgpathtools finds no finite centre and radii): give it radii of a size comparable "
                               "to the distance between its end points")
    else:
        given = segment.bpoints()
    if not finite(given):
        raise DrawingError(f"{where}: non-finite coordinates (NaN or infinity); check the numbers in its path data")
    with np.errstate(all="ignore"):  # overflow shows up as non-finite samples, checked next
        if isinstance(segment, Line):
            piece = LinePiece(_xy(A, b, segment.start), _xy(A, b, segment.end))
        elif isinstance(segment, (QuadraticBezier, CubicBezier)):
            piece = BezierPiece(tuple(_xy(A, b, z) for z in segment.bpoints()))
        else:
            piece = _arc_piece(segment, A, b, where)
        _check_samples(piece, where)
    return piece


def _handle_notes(segment, label: str):
    """Notes on Bézier handles of zero length: the derivative vanishes at that end."""
    if isinstance(segment, (QuadraticBezier, CubicBezier)):
        p = segment.bpoints()
        kind = "cubic" if len(p) == 4 else "quadratic"
        for end, (a, c) in (("start (t=0)", (p[0], p[1])), ("end (t=1)", (p[-1], p[-2]))):
            if a == c:
                yield (f"{label}: {kind} Bézier with a zero-length handle at its {end}: its derivative "
                       "vanishes there and the tangent is only the limit direction")


def _subpaths(segments: list) -> list[list]:
    """Runs of segments each starting exactly where the previous one ends (what svgpathtools'
    ``Path.continuous_subpaths`` does); a new ``M`` elsewhere starts a new run."""
    runs = [[segments[0]]]
    for previous, segment in zip(segments, segments[1:]):
        if segment.start == previous.end:
            runs[-1].append(segment)
        else:
            runs.append([segment])
    return runs


def _check_samples(piece: Piece, where: str) -> None:
    with np.errstate(all="ignore"):
        values = np.hstack([piece.point(_SAMPLES), piece.d1(_SAMPLES), piece.d2(_SAMPLES)])
    if not np.all(np.isfinite(values)):
        raise DrawingError(f"{where}: non-finite coordinates (NaN or infinity); check the numbers in its path data "
                           "and transforms")
    largest = float(np.abs(values[:, : _SAMPLES.size]).max())
    if largest > MAX_COORD:
        raise DrawingError(f"{where}: coordinates reach {largest:.3g}, beyond the supported {MAX_COORD:.0e}: "
                           "rescale the drawing")


def _assemble(entries, *, name: str, source: str, notes: list[str]) -> Drawing:
    """Paths from ``(base name, where, svgpathtools segments, A, b)`` entries."""
    built = []  # (name, pieces)
    for base, where, segments, A, b in entries:
        runs = _subpaths(segments)
        kept_runs = []
        for r, run in enumerate(runs, start=1):
            label = base if len(runs) == 1 else f"{base}#{r}"
            pieces = []
            for i, segment in enumerate(run, start=1):
                if _is_zero_length(segment):
                    notes.append(f"{where}: {label} segment {i} has zero length and was dropped")
                    continue
                piece = _svg_piece(segment, A, b, f"{where}, {label} segment {i}")
                notes.extend(_handle_notes(segment, f"{where}: {label} piece {len(pieces) + 1}"))
                pieces.append(piece)
            if pieces:
                kept_runs.append((label, pieces))
            else:
                notes.append(f"{where}: subpath {label} has only zero-length segments and was dropped")
        if not kept_runs:
            raise DrawingError(f"{where} has only zero-length segments (it draws a point, not a curve): "
                               "remove it or give it some extent")
        built.extend(kept_runs)

    size = _extent(np.hstack([p.point(_SAMPLES) for _, pieces in built for p in pieces]))
    if not size > 0:
        raise DrawingError(f"{source}: all points of the drawing coincide; expected a curve with some extent")
    paths = []
    for label, pieces in built:
        closed = bool(np.hypot(*(pieces[-1].end - pieces[0].start)) <= CLOSE_TOL * size)
        paths.append(Path(tuple(pieces), closed=closed, name=label))
    for label, pieces in built:
        short = [k for k, p in enumerate(pieces, start=1) if _span(p) <= CLOSE_TOL * size]
        if short:
            notes.append(f"{label}: piece(s) {short} are shorter than {CLOSE_TOL:g} of the drawing's size "
                         "(kept; they may come from a rounding error before a 'z')")
    return Drawing(tuple(paths), name=name, source=source, unit="model", notes=tuple(notes))


def _extent(points: np.ndarray) -> float:
    return float(max(np.ptp(points[0]), np.ptp(points[1])))


def _span(piece: Piece) -> float:
    return _extent(piece.point(_SAMPLES))


# ----------------------------------------------------------------------------------------------------
# Point lists
# ----------------------------------------------------------------------------------------------------
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
    size = _extent(all_points.T)
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
        data = _read_bytes(file_name, "point list")
        try:
            return data.decode("utf-8-sig"), file_name, _stem(file_name)
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
    return u


# ----------------------------------------------------------------------------------------------------
# Parametric curves
# ----------------------------------------------------------------------------------------------------
def from_function(fn: Callable, u0: float, u1: float, *, closed: bool = False, dfn: Callable | None = None,
                  d2fn: Callable | None = None, name: str = "function") -> Drawing:
    """A parametric curve ``u -> (x, y)`` on ``[u0, u1]`` as a one-piece drawing.

    Parameters
    ----------
    fn : callable
        ``fn(u) -> (x, y)`` for a numpy array ``u``; returns two arrays or one of shape ``(2, n)``.
    u0, u1 : float
        Parameter interval (``u1 < u0`` runs the curve backwards).
    closed : bool
        Whether the curve is closed; then ``fn(u1)`` must equal ``fn(u0)`` within ``CLOSE_TOL``
        of the curve's size.
    dfn, d2fn : callable, optional
        Exact first and second derivatives with respect to ``u`` (same shapes); otherwise central
        differences, which evaluate ``fn`` slightly outside ``[u0, u1]``.
    name : str
        Name of the drawing and of its path.

    Returns
    -------
    Drawing
        One :class:`Path` with one :class:`FunctionPiece`, ``unit="model"``.

    Raises
    ------
    DrawingError
        ``fn`` (or a derivative) fails, does not accept arrays, returns the wrong shape or
        non-finite values on a test grid; an empty interval; a curve with no extent; ``closed``
        but not closing.

    Examples
    --------
    >>> import numpy as np
    >>> circle = from_function(lambda u: (np.cos(u), np.sin(u)), 0.0, 2 * np.pi, closed=True,
    ...                        dfn=lambda u: (-np.sin(u), np.cos(u)), name="circle")
    >>> round(circle.paths[0].length(), 9)
    6.283185307
    """
    if not callable(fn):
        raise DrawingError(f"{name}: fn must be a function u -> (x, y), got {type(fn).__name__}")
    for label, f in (("dfn", dfn), ("d2fn", d2fn)):
        if f is not None and not callable(f):
            raise DrawingError(f"{name}: {label} must be a function u -> (x', y') or None, got {type(f).__name__}")
    try:
        u0, u1 = float(u0), float(u1)
    except (TypeError, ValueError):
        raise DrawingError(f"{name}: u0 and u1 must be numbers, got {u0!r} and {u1!r}") from None
    if not (math.isfinite(u0) and math.isfinite(u1) and u0 != u1):
        raise DrawingError(f"{name}: the parameter interval [u0, u1] must be finite and not empty, "
                           f"got [{u0!r}, {u1!r}]")
    piece = FunctionPiece(fn, u0, u1, dfn, d2fn)
    grid = np.linspace(0.0, 1.0, 33)
    for what, method in (("fn", piece.point), ("its derivative", piece.d1), ("its second derivative", piece.d2)):
        try:
            with np.errstate(all="ignore"):
                values = method(grid)
        except Exception as exc:  # the user's own function may raise anything; say which and where
            raise DrawingError(f"{name}: evaluating {what} on u in [{u0:g}, {u1:g}] failed ({exc}); fn must "
                               "accept a numpy array u and return x and y arrays, shape (2, len(u))") from exc
        if not np.all(np.isfinite(values)):
            hint = "" if what == "fn" else " (give dfn/d2fn if fn is undefined just outside [u0, u1])"
            raise DrawingError(f"{name}: {what} is not finite somewhere on u in [{u0:g}, {u1:g}]{hint}")
        if what == "fn":
            largest = float(np.abs(values).max())
            if largest > MAX_COORD:
                raise DrawingError(f"{name}: coordinates reach {largest:.3g}, beyond the supported "
                                   f"{MAX_COORD:.0e}: rescale the curve")
            size = _extent(values)
    if not size > 0:
        raise DrawingError(f"{name}: fn is constant on [{u0:g}, {u1:g}]: the curve is a single point")
    gap = float(np.hypot(*(piece.end - piece.start)))
    if closed and gap > CLOSE_TOL * size:
        raise DrawingError(f"{name}: closed=True but fn(u1) = {tuple(piece.end.round(12))} differs from "
                           f"fn(u0) = {tuple(piece.start.round(12))} by {gap:.3g}; fix the interval or pass closed=False")
    return Drawing((Path((piece,), closed=bool(closed), name=name),), name=name, source="function", unit="model")


# ----------------------------------------------------------------------------------------------------
# Lengths and files
# ----------------------------------------------------------------------------------------------------
_UNITS = {"m": 1.0, "cm": 0.01, "mm": 0.001, "um": 1e-6, "\u00b5m": 1e-6, "\u03bcm": 1e-6, "ft": 0.3048,
          "in": 0.0254, "u": None, "": None}
_LENGTH = re.compile(r"\s*([+-]?(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][+-]?\d+)?)\s*([A-Za-z\u00b5\u03bc]*)\s*")
_LENGTH_FORMS = "'6m', '6 m', '600cm', '6000mm', '20ft', '240in', '6' or '6u' (model units)"


def parse_length(text: str) -> tuple[float, str]:
    """A length such as ``"6m"`` or ``"20ft"`` as ``(value, unit)``, physical lengths in metres.

    Parameters
    ----------
    text : str
        A positive number with an optional unit: ``m``, ``cm``, ``mm``, ``um`` (or ``µm``, micrometres,
        for exact mode's tolerances), ``ft``, ``in``; ``u`` or no unit for model units. Space between number and unit is allowed; case is ignored.

    Returns
    -------
    (float, str)
        ``(metres, "m")`` for a physical unit, ``(value, "model")`` otherwise.

    Raises
    ------
    DrawingError
        Not a number with a known unit, zero, negative or not finite; the message lists the
        accepted forms.

    Examples
    --------
    >>> parse_length("600cm"), parse_length("6 m"), parse_length("6")
    ((6.0, 'm'), (6.0, 'm'), (6.0, 'model'))
    """
    if not isinstance(text, str):
        raise DrawingError(f"a length must be text such as {_LENGTH_FORMS}; got {type(text).__name__}")
    match = _LENGTH.fullmatch(text)
    unit = match.group(2).lower() if match else None
    if match is None or unit not in _UNITS:
        raise DrawingError(f"cannot read the length {text!r}: expected a positive number with an optional unit, "
                           f"e.g. {_LENGTH_FORMS}")
    value = float(match.group(1))
    if not (value > 0 and math.isfinite(value)):
        raise DrawingError(f"a length must be positive and finite, got {text!r}; e.g. {_LENGTH_FORMS}")
    factor = _UNITS[unit]
    if factor is None:
        return value, "model"
    if not value * factor > 0:  # underflow, e.g. "5e-324mm"
        raise DrawingError(f"a length must be positive, got {text!r}, which is 0 in metres; e.g. {_LENGTH_FORMS}")
    return value * factor, "m"


def load_drawing(path: str | os.PathLike) -> Drawing:
    """Read a drawing file, its type chosen by the suffix.

    Parameters
    ----------
    path : str or os.PathLike
        ``.svg`` (:func:`read_svg`), or ``.csv``, ``.txt``, ``.dat`` (:func:`read_points`);
        the suffix's case is ignored.

    Returns
    -------
    Drawing

    Raises
    ------
    DrawingError
        An unsupported suffix (the message lists the supported ones), or any error of the reader.

    Examples
    --------
    >>> load_drawing("figure.dxf")
    Traceback (most recent call last):
    ...
    skatetrace.errors.DrawingError: cannot load 'figure.dxf': unsupported file type '.dxf'; supported: .svg (SVG drawing), .csv, .txt, .dat (point lists)
    """
    if not isinstance(path, (str, os.PathLike)):
        raise DrawingError(f"load_drawing expects a file name, got {type(path).__name__}")
    file_name = os.fspath(path)
    suffix = os.path.splitext(file_name)[1].lower()
    if suffix in SVG_SUFFIXES:
        return read_svg(pathlib.Path(file_name))
    if suffix in POINT_SUFFIXES:
        return read_points(pathlib.Path(file_name))
    raise DrawingError(f"cannot load {file_name!r}: unsupported file type {suffix or '(no suffix)'!r}; supported: "
                       f"{', '.join(SVG_SUFFIXES)} (SVG drawing), {', '.join(POINT_SUFFIXES)} (point lists)")
