"""SVG drawings (a file, SVG text, or path data) read as a :class:`~skatetrace.drawings.curves.Drawing` of exact pieces.

The one module that knows SVG: it alone imports the SVG parser (svgpathtools).

Coordinates
-----------
SVG user units (the ``viewBox`` coordinates, after every group and element ``transform``) become
model units one to one, with the y axis flipped: SVG's y points down the page, ours points up, so
a drawing keeps its handedness (a loop drawn clockwise on screen is clockwise here too). The
page size (``width="210mm"``) is paper, not ice: it is recorded in the drawing's ``notes`` and
otherwise ignored. Scale a drawing to the ice with :meth:`Drawing.scaled_to` and a size from
:func:`~skatetrace.drawings.lengths.parse_length`.

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

Degenerate input
----------------
Exactly zero-length segments are dropped (with a note); tiny ones are kept. A Bézier with a
zero-length handle is kept (its derivative vanishes at that end; a note says so). An element
made only of zero-length segments, non-finite or huge (beyond ``MAX_COORD``) coordinates, a singular
transform, malformed XML or path data, and missing files raise :class:`DrawingError` with the
file, element or line and what would be accepted.
"""

from __future__ import annotations

import io
import math
import os
import warnings
import xml.etree.ElementTree as ET

import numpy as np
from svgpathtools import Arc, CubicBezier, Document, Line, QuadraticBezier, parse_path
from svgpathtools.document import CONVERSIONS

from .curves import BezierPiece, Drawing, EllipticArcPiece, LinePiece, Path, Piece
from .files import file_stem, read_bytes, shorten
from .lengths import CLOSE_TOL, MAX_COORD, extent
from .svg_style import Visibility, visibility
from ..errors import DrawingError

__all__ = ["read_svg", "parse_path_string", "SVG_SUFFIXES"]

SVG_SUFFIXES = (".svg",)
"""File suffixes of SVG drawings (:func:`skatetrace.drawings.load.load_drawing` reads them with :func:`read_svg`)."""

_SVG_NS = "{http://www.w3.org/2000/svg}"
_FLIP = np.array([[1.0, 0.0], [0.0, -1.0]])
_SAMPLES = np.linspace(0.0, 1.0, 17)

# What svgpathtools (and the XML parser under it) raises on input it cannot read. Caught only around
# calls into it, and always re-raised as a DrawingError that says which file and element failed.
_LIBRARY_ERRORS = (ValueError, TypeError, ArithmeticError, AssertionError, IndexError, KeyError, AttributeError)


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
    drawn by itself), CSS transforms and ``<style>`` sheets. Elements hidden by ``display:none`` or
    ``visibility:hidden`` (on them or inherited) are skipped, and so are elements that paint
    nothing (fill and stroke ``none``: the invisible frames of icon sets) where anything else is
    painted (:mod:`~skatetrace.drawings.svg_style`); ``notes`` lists what was skipped. An SVG without the SVG namespace declaration is read as if it had one. An invalid
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
        stream: io.IOBase = io.BytesIO(read_bytes(file_name, "SVG"))
        origin, name = file_name, file_stem(file_name)
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

    parents = {child: parent for parent in root.iter() for child in parent}
    entries, unpainted, hidden = [], [], []
    for k, svg_path in enumerate(found, start=1):
        element = svg_path.element
        tag = _local_tag(element.tag)
        label = f"<{tag} id={element.get('id')!r}>" if element.get("id") else f"<{tag}> number {k}"
        where = f"{origin}: {label}"
        shown = visibility(element, parents)
        if shown == Visibility.HIDDEN:
            hidden.append(label)
            continue
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
        (entries if shown == Visibility.DRAWN else unpainted).append(
            (element.get("id") or f"{tag}-{k}", where, segments, A, b))
    if hidden:
        notes.append(f"{origin}: skipped {len(hidden)} hidden element(s) (display:none or visibility:hidden): "
                     f"{', '.join(hidden[:5])}{' ...' if len(hidden) > 5 else ''}")
    if unpainted and entries:
        notes.append(f"{origin}: skipped {len(unpainted)} element(s) that paint nothing (fill and stroke none): "
                     f"{', '.join(u[1].split(': ', 1)[-1] for u in unpainted[:5])}{' ...' if len(unpainted) > 5 else ''}")
    elif unpainted:
        notes.append(f"{origin}: nothing in the drawing is painted (fill and stroke none); its geometry is read anyway")
        entries = unpainted
    if not entries and hidden:
        raise DrawingError(f"every drawable element of {origin} is hidden (display:none or visibility:hidden): "
                           f"{', '.join(hidden[:5])}")
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
    where = f"path data {shorten(d)!r}"
    segments = _parse_d(d, where, notes)
    if not segments:
        raise DrawingError(f"{where} draws nothing (a lone 'M' makes no segment): expected e.g. 'M 0 0 L 10 0'")
    return _assemble([("path", where, segments, _FLIP, np.zeros(2))], name="path", source="path data", notes=notes)


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


def _parse_d(d: str, where: str, notes: list[str]) -> list:
    """svgpathtools segments of path data, its warnings appended to ``notes``."""
    if not d or not d.strip():
        return []
    if d.lstrip(" \t\r\n\f,")[:1] not in ("M", "m"):
        # SVG path data begins with a moveto; without one svgpathtools leaves segments without a start.
        raise DrawingError(f"{where}: the path data {shorten(d)!r} cannot be read (it does not begin with a "
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
            raise DrawingError(f"{where}: the path data {shorten(d)!r} cannot be read ({exc}); expected SVG "
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

    size = extent(np.hstack([p.point(_SAMPLES) for _, pieces in built for p in pieces]))
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



def _span(piece: Piece) -> float:
    return extent(piece.point(_SAMPLES))
