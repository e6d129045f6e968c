"""SVG drawings (a file, SVG text, or path data) read as a :class:`~skatetrace.drawings.curves.Drawing` of exact pieces.

The one module that knows SVG: it alone imports the SVG parsers (defusedxml and svgelements).

Reading
-------
The document is parsed first with defusedxml, which refuses DTDs that declare entities (an "XML bomb" expands a few
into gigabytes; plain text ones, as Illustrator writes, are inlined first by :mod:`.svg_entities`) and external
references (``<!ENTITY x SYSTEM "file:///etc/passwd">``). The same bytes then go to svgelements' ``SVG.parse``, which
expands ``<use>`` (``href`` or ``xlink:href``, of shapes, groups, symbols and other ``<use>``), applies ``<style>``
sheets (selectors ``*``, ``tag``, ``#id``, ``.class``, ``tag.class``) and ``style`` attributes with inheritance,
converts lengths in units (``mm``, ``cm``, ``in``, ``pt``, ``pc``, ``%``) to user units at 96 per inch, and composes
every transform, nested ``<svg>`` viewports included. Where svgelements departs from SVG, :mod:`.svg_style` and this
module correct it: a ``<symbol>`` (or a ``<marker>``, ``<mask>``) is drawn only through a ``<use>``, a ``<use>`` of a
``<symbol>`` with a ``viewBox`` maps it onto the ``<use>``'s width and height, a ``<switch>`` draws one child, a
nested ``<svg>`` without ``viewBox`` is moved to its ``x``, ``y``, visibility is read. ``<use>`` cycles and expansions
past ``MAX_ELEMENTS`` are refused.

Coordinates
-----------
SVG user units (the root's ``viewBox`` coordinates, after every group, ``<use>``, nested ``<svg>``
and element ``transform``) become model units one to one, with the y axis flipped (SVG's points
down the page): a loop drawn clockwise on screen is clockwise here too. The page size
(``width="210mm"``) is paper, not ice: it is in ``notes`` and otherwise ignored. Scale a drawing to
the ice with :meth:`Drawing.scaled_to` and a size from :func:`~skatetrace.drawings.lengths.parse_length`.

Exactness
---------
SVG segments become pieces with exact derivatives (:mod:`.svg_pieces`): ``L``/``H``/``V``/``Z`` lines become
:class:`~skatetrace.drawings.curves.LinePiece`, ``Q``/``T``/``C``/``S``
:class:`~skatetrace.drawings.curves.BezierPiece`, ``A``
:class:`~skatetrace.drawings.curves.EllipticArcPiece`. svgelements' geometry is taken untransformed, and the
composed affine transform (and the y flip) is applied to the parameters themselves: an affine map of a Bézier is the
Bézier of the mapped control points, and an affine map of an elliptic arc is an elliptic arc whose axes come from the
singular value decomposition of the map (svgelements' own arc transform keeps the axes perpendicular, which a rotated
ellipse under a non-uniform scale does not).

Degenerate input
----------------
Exactly zero-length segments are dropped, a zero-radius arc is a line (as SVG says), a Bézier with a
zero-length handle is kept (its derivative vanishes there), each with a note. An element of only
zero-length segments (it draws a point) or of zero size (``r="0"``, which SVG does not draw, as graph
layouts write for invisible nodes) is skipped with a note where anything else is drawn, and raises
where nothing is. Non-finite or huge (beyond ``MAX_COORD``) coordinates, a singular transform,
malformed XML, path data or transforms, refused XML and missing files raise
:class:`DrawingError` with the file, element or line and what would be accepted.
"""

from __future__ import annotations

import io
import math
import os
import warnings
import xml.etree.ElementTree as ET

import numpy as np
import svgelements as se
from defusedxml import DefusedXmlException, EntitiesForbidden, ExternalReferenceForbidden
from defusedxml.ElementTree import fromstring as _safe_fromstring

from .curves import Drawing, Path, Piece
from .files import file_stem, read_bytes, shorten
from .lengths import CLOSE_TOL, extent
from .svg_entities import inline_entities
from .svg_pieces import SAMPLES, is_zero_length, same_point, segment_notes, segment_points, svg_piece
from .svg_style import (MAX_ELEMENTS, Placed, Visibility, check_transforms, expand, local_tag,
                        styled_names, unapplied_rules, visibility)
from ..errors import DrawingError

__all__ = ["read_svg", "parse_path_string", "SVG_SUFFIXES", "MAX_ELEMENTS"]

SVG_SUFFIXES = (".svg",)
"""File suffixes of SVG drawings (:func:`skatetrace.drawings.load.load_drawing` reads them with :func:`read_svg`)."""

_FLIP = np.array([[1.0, 0.0], [0.0, -1.0]])
_PPI = 96.0  # CSS pixels per inch: lengths in units become user units at this rate, as in SVG
_EXTENT = {"rect": "width and height > 0", "circle": "r > 0", "ellipse": "rx and ry > 0",
           "polyline": "points", "polygon": "points", "line": "x1, y1, x2, y2", "path": "d"}

# What svgelements raises on input it cannot read. Caught only around calls into it, and always
# re-raised as a DrawingError that says which file and element failed.
_LIBRARY_ERRORS = (ValueError, TypeError, ArithmeticError, AssertionError, IndexError, KeyError, AttributeError)


def read_svg(source: str | os.PathLike) -> Drawing:
    """Read the shapes of an SVG document as a drawing, one :class:`Path` per continuous subpath.

    Parameters
    ----------
    source : str or os.PathLike
        A file name, or the SVG text itself (a string containing ``<``).

    Returns
    -------
    Drawing
        In SVG user units (``unit="model"``) with the y axis pointing up. Paths are in document
        order, named by the element's ``id`` (``"id#2"`` for its second subpath) or by its tag and
        position (``"path-3"``); what a ``<use>`` draws is named after the ``<use>`` (its ``id``,
        or ``"use-4"``), its subpaths counted over all the shapes it draws. A subpath is
        ``closed`` when its end meets its start within ``CLOSE_TOL`` times the drawing's size.
        ``notes`` records the page size, what was skipped and why, dropped zero-length segments,
        zero-radius arcs, zero-length Bézier handles and svgelements' warnings.

    Raises
    ------
    DrawingError
        Missing or unreadable file, malformed XML, a DTD that declares entities or refers to external files, a
        ``<use>`` cycle or more than ``MAX_ELEMENTS`` elements after expanding ``<use>``, invalid ``transform`` or
        path data, a singular transform, an element made only of zero-length segments or of zero size, non-finite or
        huge coordinates, or a document without any drawable element.

    Notes
    -----
    Shapes read: ``path``, ``rect`` (also rounded), ``circle``, ``ellipse``, ``line``, ``polyline`` and ``polygon``,
    inside the root, ``<g>``, ``<a>``, ``<switch>`` (its first child without conditions), nested ``<svg>`` viewports
    and ``<use>`` clones (of shapes, groups, ``<symbol>``, other ``<use>``), with every ``transform``, ``x``/``y`` and
    viewport on the way. Lengths in units are user units at 96 per inch. ``<defs>``, ``<symbol>``, ``<marker>``,
    ``<mask>``, ``<clipPath>`` and ``<pattern>`` are never drawn by themselves. CSS from ``<style>`` sheets (selectors
    ``*``, ``tag``, ``#id``, ``.class``, ``tag.class``; others are named in ``notes``) and ``style`` attributes apply.
    Elements hidden by ``display:none`` or ``visibility:hidden`` (on them or inherited) are skipped, and so are
    elements that paint nothing (fill and stroke ``none``: the invisible frames of icon sets) where anything else is
    painted; ``notes`` lists what was skipped. A CSS ``transform`` applies like the attribute (without
    ``transform-origin``). Not read: text, images, clip paths and masks (the full shape is read), markers, external
    ``href`` (``other.svg#id``). An SVG without the SVG namespace declaration is read as if it had one.

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
    >>> clones = read_svg('''<svg xmlns="http://www.w3.org/2000/svg">
    ...   <defs><symbol id="dash"><path d="M 0 0 L 10 0"/></symbol></defs>
    ...   <use id="a" href="#dash" x="5"/><use id="b" href="#dash" y="20"/>
    ... </svg>''')
    >>> [(p.name, p.pieces[0].start.tolist(), p.pieces[0].end.tolist()) for p in clones.paths]
    [('a', [5.0, 0.0], [15.0, 0.0]), ('b', [0.0, -20.0], [10.0, -20.0])]
    """
    if isinstance(source, os.PathLike) or (isinstance(source, str) and "<" not in source):
        file_name = os.fspath(source)
        data: bytes | str = read_bytes(file_name, "SVG")
        origin, name = file_name, file_stem(file_name)
    elif isinstance(source, str):
        data, origin, name = source, "the SVG text", "svg"
    else:
        raise DrawingError(f"read_svg expects a file name or SVG text, got {type(source).__name__}")

    data, inlined = inline_entities(data)
    root = _parse_xml(data, origin)
    notes = [f"inlined the XML entities {', '.join(inlined)} of its DOCTYPE"] * bool(inlined) + list(_page_notes(root))
    check_transforms(root, origin)
    placed = expand(root, origin)
    document = _parse_svg(data, root, origin, notes)
    if not isinstance(document, se.Group):  # the root is not <svg> or <g>: svgelements draws nothing
        document, placed = se.SVG(), []
    shapes = list(_shapes(document))
    styled = styled_names(root)

    units: dict[int, int] = {}  # id of the element named (a shape, or the outermost <use>) -> its number
    for p in placed:
        if p.skipped is None:
            units.setdefault(id(_unit_of(p)), len(units) + 1)
    entries, unpainted, hidden, skipped, empty = [], [], [], [], []
    for p, shape, containers in _match(placed, shapes, styled):
        if p is not None and p.skipped is not None:
            skipped.append(f"{_describe(p.element)} ({p.skipped})")
            continue
        base, label = _names(p, shape, units)
        where = f"{origin}: {label}"
        try:
            if shape is None:  # svgelements dropped it: it has no extent
                if p.declared_hidden:
                    hidden.append(label)
                    continue
                if p.tag in ("path", "polyline", "polygon"):
                    notes.append(f"{where} is empty and was skipped")
                    continue
                _no_extent(where, p.tag, p.element.attrib)
            shown = visibility([document.values, *(c.values for c in containers), shape.values])
            if shown == Visibility.HIDDEN:
                hidden.append(label)
                continue
            segments = _segments(shape, p, where, notes)
        except _Nothing as exc:  # SVG draws nothing for it: an error only if nothing else is drawn
            empty.append((label, exc))
            continue
        if not any(not isinstance(s, se.Move) for s in segments):
            notes.append(f"{where} is empty and was skipped")
            continue
        matrix = _composed(shape, p, document, containers, where)
        if matrix is None:
            skipped.append(f"{label} (its <use> of a <symbol> has zero width or height)")
            continue
        _check_transform(matrix, where)
        A, b = _FLIP @ matrix[:2, :2], _FLIP @ matrix[:2, 2]
        unit = id(_unit_of(p)) if p is not None else id(shape)
        (entries if shown == Visibility.DRAWN else unpainted).append((unit, base, where, segments, A, b))
    if skipped:
        notes.append(f"{origin}: skipped {len(skipped)} element(s) that SVG does not draw by themselves: "
                     f"{', '.join(skipped[:5])}{' ...' if len(skipped) > 5 else ''}")
    if hidden:
        notes.append(f"{origin}: skipped {len(hidden)} hidden element(s) (display:none or visibility:hidden): "
                     f"{', '.join(hidden[:5])}{' ...' if len(hidden) > 5 else ''}")
    if unpainted and entries:
        notes.append(f"{origin}: skipped {len(unpainted)} element(s) that paint nothing (fill and stroke none): "
                     f"{', '.join(u[2].split(': ', 1)[-1] for u in unpainted[:5])}{' ...' if len(unpainted) > 5 else ''}")
    elif unpainted:
        notes.append(f"{origin}: nothing in the drawing is painted (fill and stroke none); its geometry is read anyway")
        entries = unpainted
    if empty and entries:
        notes.append(f"{origin}: skipped {len(empty)} element(s) of zero size, which SVG does not draw: "
                     f"{', '.join(label for label, _ in empty[:5])}{' ...' if len(empty) > 5 else ''}")
    elif empty:
        raise empty[0][1]
    if not entries and hidden:
        raise DrawingError(f"every drawable element of {origin} is hidden (display:none or visibility:hidden): "
                           f"{', '.join(hidden[:5])}")
    if not entries:
        hint = ""
        if local_tag(root.tag) != "svg":
            hint = f" (the root element is <{local_tag(root.tag)}>, not <svg>)"
        elif skipped:
            hint = f" (skipped {len(skipped)} element(s) that SVG does not draw by themselves, e.g. {skipped[0]})"
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
    if not any(not isinstance(s, se.Move) for s in segments):
        raise DrawingError(f"{where} draws nothing (a lone 'M' makes no segment): expected e.g. 'M 0 0 L 10 0'")
    return _assemble([(0, "path", where, segments, _FLIP, np.zeros(2))], name="path", source="path data",
                     notes=notes)


# --- the document -------------------------------------------------------------------------------------

def _parse_xml(data: bytes | str, origin: str) -> ET.Element:
    """The XML tree, parsed safely: entity declarations and external references are refused."""
    try:
        return _safe_fromstring(data, forbid_dtd=False, forbid_entities=True, forbid_external=True)
    except EntitiesForbidden as exc:
        where = f" refers to {exc.sysid!r}" if exc.sysid else " (nested entities can expand into gigabytes)"
        raise DrawingError(f"{origin} declares the XML entity {exc.name!r} in its DTD and is refused: entities are "
                           f"not read, since an entity{where} can read local files or expand without bound (an XML "
                           "bomb); remove the <!DOCTYPE ...> declarations and save the SVG again") from None
    except ExternalReferenceForbidden as exc:
        raise DrawingError(f"{origin} refers to the external resource {exc.sysid or exc.pubid!r} and is refused: "
                           "an SVG drawing is read self-contained; remove the reference") from None
    except DefusedXmlException as exc:
        raise DrawingError(f"{origin} is refused as unsafe XML ({exc}); remove its <!DOCTYPE ...> declarations") from None
    except ET.ParseError as exc:
        raise DrawingError(f"{origin} is not well-formed XML ({exc}); expected an SVG document") from exc


def _parse_svg(data: bytes | str, root: ET.Element, origin: str, notes: list[str]):
    """svgelements' document tree of the same bytes, its warnings appended to ``notes``."""
    stream = io.BytesIO(data) if isinstance(data, bytes) else io.StringIO(data)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            document = se.SVG.parse(stream, reify=False, ppi=_PPI, parse_display_none=True)
        except RecursionError:
            raise DrawingError(f"{origin} nests its elements too deeply to be read") from None
        except _LIBRARY_ERRORS as exc:
            for element in root.iter():  # the likely culprits: path data that svgelements fails on, or none
                if local_tag(element.tag) == "path" and element.get("d"):
                    _parse_d(element.get("d"), f"{origin}: {_describe(element)}", [])
                elif local_tag(element.tag) == "path" and element.get("d") is None:
                    raise DrawingError(f"{origin}: {_describe(element)} has no path data (no d attribute), which "
                                       "svgelements cannot read: give it its d, or remove it (is it drawn by a "
                                       "script? skatetrace does not run scripts)") from exc
            raise DrawingError(f"{origin} cannot be read by svgelements ({exc!r}); check its lengths (e.g. "
                               "width='10mm'), colours and path data") from exc
    box = document.viewbox if isinstance(document, se.SVG) else None
    if box is not None and not (document.width and document.height and box.width and box.height):
        # svgelements stops reading at an <svg> with an empty viewport and returns that element
        sizes = {key: document.values.get(key) for key in ("width", "height", "viewBox")}
        raise DrawingError(f"{origin}: an <svg> element has a viewBox and zero width or height ({sizes}; an "
                           "unreadable width counts as zero): SVG draws nothing inside it; give it a size or "
                           "remove its width and height")
    notes.extend(f"{origin}: {message}" for message in dict.fromkeys(str(w.message) for w in caught))
    return document


def _shapes(group, containers=()):
    """svgelements' shapes in document order, each with the groups, ``<use>`` and ``<svg>`` around it."""
    for item in group:
        if isinstance(item, se.Shape):
            yield item, containers
        elif isinstance(item, (se.Group, se.Use)):
            yield from _shapes(item, (*containers, item))


def _match(placed: list[Placed], shapes: list, styled: set[str]):
    """Pair svgelements' shapes with their elements in :func:`expand`'s list; ``(placed, None, ())`` for
    an element svgelements dropped (it has no extent), ``(None, shape, containers)`` for a shape that
    matches no element (not expected; read as drawn)."""
    j = 0
    for shape, containers in shapes:
        attributes = shape.values.get("attributes", {})
        tag = shape.values.get("tag")
        k = next((i for i in range(j, len(placed)) if placed[i].tag == tag and all(
            _same_attribute(key, attributes.get(key), value) for key, value in placed[i].element.attrib.items()
            if key not in styled)), None)
        if k is None:
            yield None, shape, containers
            continue
        for dropped in placed[j:k]:
            yield dropped, None, ()
        yield placed[k], shape, containers
        j = k + 1
    for dropped in placed[j:]:
        yield dropped, None, ()


def _same_attribute(key: str, parsed, given: str) -> bool:
    """svgelements' copy of an attribute is the element's own (a transform after those of its groups)."""
    return parsed.strip().endswith(given.strip()) if key == "transform" and isinstance(parsed, str) else parsed == given


def _unit_of(p: Placed) -> ET.Element:
    """The element a shape is named after: the outermost ``<use>`` that draws it, or itself."""
    uses = p.uses
    return uses[0] if uses else p.element


def _describe(element: ET.Element, number: int | None = None) -> str:
    tag, ident = local_tag(element.tag), element.get("id")
    if ident:
        return f"<{tag} id={ident!r}>"
    return f"<{tag}> number {number}" if number is not None else f"<{tag}>"


def _names(p: Placed | None, shape, units: dict[int, int]) -> tuple[str, str]:
    """The base name of the shape's paths and its label in messages."""
    if p is None:
        ident = shape.values.get("id")
        tag = shape.values.get("tag", "shape")
        return ident or tag, f"<{tag} id={ident!r}>" if ident else f"<{tag}>"
    unit = _unit_of(p)
    k = units.get(id(unit), 0)
    base = unit.get("id") or f"{local_tag(unit.tag)}-{k}"
    label = _describe(unit, k)
    if unit is not p.element:
        label = f"{_describe(p.element)} in {label}"
    return base, label


def _page_notes(root: ET.Element):
    page = {key: root.get(key) for key in ("width", "height", "viewBox") if root.get(key)}
    if page:
        described = ", ".join(f"{key}={value!r}" for key, value in page.items())
        yield f"coordinates are SVG user units (page {described}), y flipped to point up"
    yield from unapplied_rules(root)


# --- transforms --------------------------------------------------------------------------------------

def _matrix(m) -> np.ndarray:
    """svgelements' ``Matrix`` (``x' = a x + c y + e``, ``y' = b x + d y + f``) as a 3x3 array."""
    m = se.Matrix(m)
    return np.array([[m.a, m.c, m.e], [m.b, m.d, m.f], [0.0, 0.0, 1.0]], dtype=float)


def _length(text, relative: float) -> float | None:
    """A length attribute in user units (``%`` of ``relative``), or None if missing or unreadable."""
    if text is None or not str(text).strip():
        return None
    try:
        value = se.Length(text).value(ppi=_PPI, relative_length=relative)
    except _LIBRARY_ERRORS:
        return None
    return float(value) if isinstance(value, (int, float)) and math.isfinite(value) else None


def _viewport(svg) -> tuple[float, float]:
    """Width and height of the user space an svgelements ``<svg>`` sets up (for ``%`` lengths)."""
    if svg.viewbox is not None and svg.viewbox.width is not None:
        return float(svg.viewbox.width), float(svg.viewbox.height)
    sizes = [v if isinstance(v, (int, float)) else 1000.0 for v in (svg.width, svg.height)]
    return float(sizes[0]), float(sizes[1])


def _composed(shape, p: Placed | None, document, containers, where: str) -> np.ndarray | None:
    """The shape's transform into the root's user units, as svgelements composes it, corrected.

    Each correction ``T`` belongs right after a container whose composed transform is ``P``:
    ``P T P^-1 M`` puts it there; the innermost goes first. Corrections: a ``<use>`` of a
    ``<symbol>`` with a ``viewBox`` (its viewport), a nested ``<svg>`` without ``viewBox`` (its
    ``x``, ``y``) and the root's viewport, taken off again (the page size is not the drawing's).
    None if a ``<use>`` of a ``<symbol>`` draws nothing (zero width or height).
    """
    try:
        matrix = _matrix(shape.transform)
        corrections = []  # (P, T), the outermost first
        box = document.viewbox_transform if document.viewbox is not None else ""
        own, full = document.values.get("transform"), shape.values.get("transform")
        prefix = f"{own} {box}" if own else box
        if box and isinstance(full, str) and full.startswith(prefix):
            # svgelements' transform list begins with the root's viewport: read it without, no rounding
            rest = se.Matrix(f"{own or ''} {full[len(prefix):]}")
            rest.render(ppi=_PPI, width=_viewport(document)[0], height=_viewport(document)[1])
            if all(isinstance(v, (int, float)) for v in (rest.a, rest.b, rest.c, rest.d, rest.e, rest.f)):
                matrix, box = _matrix(rest), ""
        if box:
            V = _matrix(box)
            if abs(np.linalg.det(V[:2, :2])) > 0:
                corrections.append((_matrix(document.transform), np.linalg.inv(V)))
        if p is not None:
            xml = [e for e in p.chain[1:] if local_tag(e.tag) in ("g", "svg", "use")]
            if len(xml) == len(containers):
                viewport = _viewport(document)
                for element, container in zip(xml, containers):
                    tag = local_tag(element.tag)
                    if tag == "svg" and isinstance(container, se.SVG):
                        if container.viewbox is None and (container.x or container.y):
                            T = _matrix(f"translate({container.x}, {container.y})")
                            corrections.append((_matrix(container.transform), T))
                        viewport = _viewport(container)
                    elif tag == "use":
                        target = p.chain[p.chain.index(element) + 1] if element is not p.chain[-1] else p.element
                        if local_tag(target.tag) == "symbol" and target.get("viewBox"):
                            T = _symbol_viewport(element, target, viewport)
                            if T is None:
                                return None
                            corrections.append((_matrix(container.transform), T))
        for P, T in reversed(corrections):
            if abs(np.linalg.det(P[:2, :2])) > 0:
                matrix = P @ T @ np.linalg.solve(P, matrix)
    except _LIBRARY_ERRORS as exc:
        raise DrawingError(f"{where}: its transform cannot be composed ({exc!r}); check the transform, x, y, "
                           "width, height and viewBox attributes on the way to it") from exc
    return matrix


def _symbol_viewport(use: ET.Element, symbol: ET.Element, viewport: tuple[float, float]) -> np.ndarray | None:
    """The transform that maps a ``<symbol>``'s ``viewBox`` onto the viewport its ``<use>`` sets up."""
    box = se.Viewbox(symbol.get("viewBox"), symbol.get("preserveAspectRatio"))
    if not box.width or not box.height or box.width <= 0 or box.height <= 0:
        return np.eye(3)  # an unusable viewBox is ignored
    width = _length(use.get("width"), viewport[0])
    width = _length(symbol.get("width"), viewport[0]) if width is None else width
    height = _length(use.get("height"), viewport[1])
    height = _length(symbol.get("height"), viewport[1]) if height is None else height
    width = viewport[0] if width is None else width  # SVG's default: 100%
    height = viewport[1] if height is None else height
    if not (width > 0 and height > 0):
        return None
    text = se.Viewbox.viewbox_transform(0.0, 0.0, width, height, box.x, box.y, box.width, box.height,
                                        box.preserve_aspect_ratio)
    return _matrix(text)


def _check_transform(matrix: np.ndarray, where: str) -> None:
    """Refuse a composed SVG transform ``[[a, c, e], [b, d, f], [0, 0, 1]]`` that is not invertible or overflows."""
    A = matrix[:2, :2]
    scale = float(np.abs(A).max()) if np.all(np.isfinite(A)) else math.nan
    det = float(A[0, 0]) * float(A[1, 1]) - float(A[0, 1]) * float(A[1, 0]) if math.isfinite(scale) else math.nan
    if not (math.isfinite(det) and abs(det) > 1e-12 * scale * scale):
        (a, c, e), (b, d, f) = matrix[0], matrix[1]
        raise DrawingError(f"{where}: its transform matrix({a:g}, {b:g}, {c:g}, {d:g}, {e:g}, {f:g}) " + (
            f"is singular (determinant {det:g}): it would flatten the drawing onto a line or a point" if math.isfinite(det)
            else "scales beyond floating point (its determinant overflows)") + "; fix the transform of it or its groups")


# --- segments ----------------------------------------------------------------------------------------

def _segments(shape, p: Placed | None, where: str, notes: list[str]) -> list:
    """svgelements' untransformed segments of a shape; a path's data is read strictly.

    svgelements gives a circle without ``r``, and a rect without ``width`` or ``height``, a size of
    1 (SVG: 0, not drawn), an ellipse without ``ry`` a ``ry`` of 1 (SVG 2: ``auto``, equal to
    ``rx``), and builds circles and ellipses from ``cos`` and ``sin`` (ends off by 1e-16); here
    they follow SVG, with arcs from exact end points.
    """
    if isinstance(shape, se.Path):
        d = p.element.get("d") if p is not None else shape.values.get("d")
        return _parse_d(d or "", where, notes)
    own = shape.values.get("attributes", {})
    tag = shape.values.get("tag", "shape")
    try:
        if isinstance(shape, (se.Circle, se.Ellipse)):
            rx, ry = float(shape.rx), float(shape.ry)
            rx, ry = (rx if "rx" in own or tag == "circle" else ry), (ry if "ry" in own or tag == "circle" else rx)
            if ("r" not in own if tag == "circle" else not ("rx" in own or "ry" in own)) or not (rx > 0 and ry > 0):
                _no_extent(where, tag, own)
            cx, cy = float(shape.cx), float(shape.cy)
            corners = [(cx + rx, cy), (cx, cy + ry), (cx - rx, cy), (cx, cy - ry), (cx + rx, cy)]
            segments = [se.Move(None, corners[0])]
            for start, end in zip(corners, corners[1:]):
                segments.append(se.Arc(start, rx, ry, 0.0, False, True, end))
                segments[-1].svg_parameters = (rx, ry, 0.0, False, True)
            return segments
        if isinstance(shape, se.Rect) and not ("width" in own and "height" in own):
            _no_extent(where, tag, own)
        return list(shape.segments(transformed=False))
    except _LIBRARY_ERRORS as exc:
        raise DrawingError(f"{where} cannot be turned into path data ({exc!r}); check its geometry attributes "
                           "(e.g. a circle needs cx, cy and r)") from exc


class _Nothing(DrawingError):
    """An element SVG draws nothing for (a zero size, a point): skipped where anything else is drawn."""


def _no_extent(where: str, tag: str, attributes) -> None:
    shown = {k: v for k, v in attributes.items() if k in ("x", "y", "width", "height", "cx", "cy", "r", "rx", "ry")}
    raise _Nothing(f"{where} has no extent: its size is zero, missing or unreadable ({shown or 'none given'}); "
                       f"SVG draws nothing for it: give it {_EXTENT.get(tag, 'a size')} or remove it")


def _parse_d(d: str, where: str, notes: list[str]) -> list:
    """svgelements' segments of path data (``Move`` included), its warnings appended to ``notes``."""
    if not d or not d.strip():
        return []
    if d.lstrip(" \t\r\n\f,")[:1] not in ("M", "m"):
        raise DrawingError(f"{where}: the path data {shorten(d)!r} cannot be read (it does not begin with a "
                           "moveto, 'M' or 'm'); expected SVG path commands such as 'M 0,0 c 10,0 10,10 20,10 z'")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            segments = list(_PathData(d))
            complete = all(isinstance(v, (int, float)) for s in segments for q in segment_points(s) for v in (q.x, q.y))
        except _LIBRARY_ERRORS:
            complete = False
    if not complete:
        raise DrawingError(f"{where}: the path data {shorten(d)!r} cannot be read (a command lacks numbers or "
                           "has a number it cannot read); expected SVG path commands such as "
                           "'M 0,0 c 10,0 10,10 20,10 z'")
    for message in dict.fromkeys(str(w.message) for w in caught):
        notes.append(f"{where}: {message}")
    return segments


class _PathData(se.Path):
    """svgelements' path that keeps each arc's SVG parameters ``(rx, ry, rotation, large, sweep)``.

    svgelements turns them into a centre at once, through ``sqrt`` of a difference that vanishes
    for a half ellipse (radii too small, scaled up to fit): its centre is then off by about 1e-8
    of the radius. :func:`_arc_geometry` works from the parameters instead.
    """

    def arc(self, *arc_args, relative=False, **kwargs):
        first = len(self)
        se.Path.arc(self, *arc_args, relative=relative, **kwargs)
        for k, segment in enumerate(list(self)[first:]):
            segment.svg_parameters = tuple(arc_args[6 * k: 6 * k + 5])
        return self


def _subpaths(segments: list) -> list[list]:
    """Runs of segments each starting exactly where the previous one ends; a new ``M`` elsewhere
    starts a new run. ``Move`` is dropped, and so is a ``Z`` that is already at its start."""
    drawn = [s for s in segments if not isinstance(s, se.Move)
             and not (isinstance(s, se.Close) and same_point(s.start, s.end))]
    runs = [[drawn[0]]] if drawn else []
    for previous, segment in zip(drawn, drawn[1:]):
        if same_point(segment.start, previous.end):
            runs[-1].append(segment)
        else:
            runs.append([segment])
    return runs


def _assemble(entries, *, name: str, source: str, notes: list[str]) -> Drawing:
    """Paths from ``(unit, base name, where, svgelements segments, A, b)`` entries; the subpaths of
    the entries of one unit (the shapes one ``<use>`` draws) are numbered together."""
    runs_of = [_subpaths(segments) for _, _, _, segments, _, _ in entries]
    total: dict = {}
    for (unit, *_), runs in zip(entries, runs_of):
        total[unit] = total.get(unit, 0) + len(runs)
    counted: dict = {}
    built, points = [], []  # (name, pieces); the elements that draw a point
    for (unit, base, where, _, A, b), runs in zip(entries, runs_of):
        kept_runs = []
        for run in runs:
            counted[unit] = counted.get(unit, 0) + 1
            label = base if total[unit] == 1 else f"{base}#{counted[unit]}"
            pieces = []
            for i, segment in enumerate(run, start=1):
                if is_zero_length(segment):
                    notes.append(f"{where}: {label} segment {i} has zero length and was dropped")
                    continue
                piece = svg_piece(segment, A, b, f"{where}, {label} segment {i}")
                notes.extend(segment_notes(segment, f"{where}: {label} piece {len(pieces) + 1}"))
                pieces.append(piece)
            if pieces:
                kept_runs.append((label, pieces))
            else:
                notes.append(f"{where}: subpath {label} has only zero-length segments and was dropped")
        if not kept_runs:
            points.append(where)
        built.extend(kept_runs)
    if not built:
        raise DrawingError(f"{points[0]} has only zero-length segments (it draws a point, not a curve): "
                           "remove it or give it some extent")
    if points:
        notes.append(f"skipped {len(points)} element(s) of only zero-length segments (each draws a point, not a "
                     f"curve): {', '.join(points[:5])}{' ...' if len(points) > 5 else ''}")

    size = extent(np.hstack([p.point(SAMPLES) for _, pieces in built for p in pieces]))
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
    return extent(piece.point(SAMPLES))
