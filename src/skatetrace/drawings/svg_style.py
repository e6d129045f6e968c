"""Which shapes of an SVG document are drawn: ``<use>`` expanded, ``<symbol>``, ``<switch>``, display and paint.

:mod:`.svg` reads a document twice, once as XML (defusedxml) and once with svgelements; this module
works on the XML tree and on svgelements' computed ``values`` (plain dicts), and imports neither parser.

:func:`expand` walks the XML tree in the order svgelements does, with every ``<use>`` followed by the
element it refers to (after the ``<use>``'s own children), and lists every shape element it meets
outside ``<defs>``, ``<clipPath>`` and ``<pattern>`` (svgelements keeps those out of its tree). It
says why SVG does not draw a shape by itself: it lies inside a ``<symbol>`` that is not the target
of a ``<use>``, inside a ``<marker>``, ``<mask>`` or other element that is only ever referenced, or
in a branch of a ``<switch>`` other than the chosen one (the first child without
``requiredExtensions`` or ``systemLanguage`` conditions: a reader has no extensions and no
language). ``<use>`` cycles and expansions beyond :data:`MAX_ELEMENTS` elements are refused.

:func:`visibility` reads svgelements' values, in which ``<style>`` sheets and ``style`` attributes
are already applied and inherited: ``display:none`` on an element or any ancestor hides it;
``visibility`` is inherited and a child may set it back to ``visible``; an element paints nothing
when its fill and its stroke are both ``none`` (SVG's defaults: fill black, stroke none), as the
invisible bounding boxes of icon sets are (``<path d="M0 0h24v24H0z" fill="none"/>``).
``inherit`` defers to the parent.
"""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET
from dataclasses import dataclass

from ..errors import DrawingError

__all__ = ["Visibility", "visibility", "Placed", "expand", "check_transforms", "local_tag", "styled_names",
           "unapplied_rules", "SHAPE_TAGS", "MAX_ELEMENTS"]

SHAPE_TAGS = ("path", "rect", "circle", "ellipse", "line", "polyline", "polygon")
"""The SVG elements read as geometry."""

MAX_ELEMENTS = 100_000
"""The most elements a document may expand to (``<use>`` clones counted): more is refused."""

_SVG_NS = "{http://www.w3.org/2000/svg}"
_XLINK_HREF = "{http://www.w3.org/1999/xlink}href"
_UNRENDERED = ("defs", "clipPath", "pattern")  # not in svgelements' tree at all
_REFERENCED_ONLY = ("symbol", "marker", "mask", "linearGradient", "radialGradient", "filter", "font",
                    "glyph", "missing-glyph", "hatch", "solidcolor")
_CONDITIONS = ("requiredExtensions", "systemLanguage")
_NON_GRAPHIC = ("desc", "title", "metadata")
_DEFAULTS = {"fill": "black", "stroke": "none", "visibility": "visible"}

_NUMBER = r"[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?"
_ONE_TRANSFORM = re.compile(r"\s*([A-Za-z]+)\s*\(([^()]*)\)\s*,?")
_ARGUMENT = re.compile(rf"\s*{_NUMBER}\s*,?")  # one at a time: a repeated group backtracks exponentially
_ARGUMENTS = {"matrix": (6,), "translate": (1, 2), "scale": (1, 2), "rotate": (1, 3), "skewX": (1,), "skewY": (1,)}
_CSS_BLOCK = re.compile(r"\{([^}]*)\}")
_CSS_RULE = re.compile(r"([^{}]*)\{[^}]*\}")
_CSS_COMMENT = re.compile(r"/\*.*?\*/", re.S)
# The selectors svgelements applies: *, tag, #id, .class, tag.class (one element, no combinator).
_SIMPLE_SELECTOR = re.compile(r"\*|[A-Za-z][\w-]*|#[\w-]+|[A-Za-z][\w-]*\.[\w-]+|\.[\w-]+")


class Visibility:
    """How an element shows: ``hidden`` (``display:none`` or ``visibility`` hidden or collapsed),
    ``unpainted`` (fill and stroke both ``none``), or ``drawn``."""

    HIDDEN = "hidden"
    UNPAINTED = "unpainted"
    DRAWN = "drawn"


def _clean(value) -> str | None:
    if value is None:
        return None
    value = str(value).replace("!important", "").strip().lower()
    return value or None


def _declared(element: ET.Element, name: str) -> str | None:
    """The value ``element`` itself sets for ``name`` (its ``style`` first), cleaned, or None."""
    for declaration in (element.get("style") or "").split(";"):
        key, _, value = declaration.partition(":")
        if key.strip().lower() == name and _clean(value):
            return _clean(value)
    return _clean(element.get(name))


def _computed(chain: list[dict], name: str) -> str:
    for values in reversed(chain):  # the element first, then its ancestors
        value = _clean(values.get(name))
        if value is not None and value != "inherit":
            return value
    return _DEFAULTS[name]


def visibility(chain: list[dict]) -> str:
    """The :class:`Visibility` of a shape from svgelements' ``values`` of the document, its groups and itself.

    Parameters
    ----------
    chain : list of dict
        The ``values`` of the root, of each group or ``<use>`` around the shape, and of the shape, in
        that order (each already holds what it inherits, with ``<style>`` sheets applied).
    """
    if any(_clean(values.get("display")) == "none" for values in chain):
        return Visibility.HIDDEN
    if _computed(chain, "visibility") in ("hidden", "collapse"):
        return Visibility.HIDDEN
    if _computed(chain, "fill") == "none" and _computed(chain, "stroke") == "none":
        return Visibility.UNPAINTED
    return Visibility.DRAWN


def local_tag(tag) -> str:
    """The tag without the SVG namespace (other namespaces are kept, as svgelements keeps them)."""
    if not isinstance(tag, str):
        return str(tag)
    return tag[len(_SVG_NS):] if tag.startswith(_SVG_NS) else tag


@dataclass(frozen=True, eq=False)
class Placed:
    """One occurrence of a shape element in the expanded document.

    ``chain`` holds its ancestors in the expanded tree, the root first; a ``<use>`` is the parent of
    the element it draws. ``skipped`` says why SVG does not draw it by itself, or is None.
    """

    element: ET.Element
    chain: tuple
    skipped: str | None

    @property
    def tag(self) -> str:
        return local_tag(self.element.tag)

    @property
    def declared_hidden(self) -> bool:
        """Hidden by a ``display`` or ``visibility`` attribute or ``style`` of its own or of an ancestor
        (without ``<style>`` sheets: for shapes svgelements drops, whose values are not known)."""
        for element in (*self.chain, self.element):
            if _declared(element, "display") == "none":
                return True
        states = [_declared(e, "visibility") for e in (*self.chain, self.element)]
        state = next((v for v in reversed(states) if v not in (None, "inherit")), "visible")
        return state in ("hidden", "collapse")

    @property
    def uses(self) -> tuple:
        """The ``<use>`` elements it is drawn through, the outermost first."""
        return tuple(e for e in self.chain if local_tag(e.tag) == "use")


def _href(element: ET.Element) -> str | None:
    url = element.get(_XLINK_HREF)
    return element.get("href", url)  # svgelements: href wins over xlink:href


def _chosen(switch: ET.Element) -> ET.Element | None:
    for child in switch:
        if isinstance(child.tag, str) and local_tag(child.tag) not in _NON_GRAPHIC:
            if not any((child.get(name) or "").strip() for name in _CONDITIONS):
                return child
    return None


def _describe(element: ET.Element) -> str:
    tag, ident = local_tag(element.tag), element.get("id")
    return f"<{tag} id={ident!r}>" if ident else f"<{tag}>"


def expand(root: ET.Element, origin: str) -> list[Placed]:
    """Every shape element svgelements draws, in its order, with what SVG itself draws marked.

    Raises
    ------
    DrawingError
        A ``<use>`` that draws itself (directly or through other ``<use>`` elements), more than
        :data:`MAX_ELEMENTS` elements after expansion, or nesting too deep to walk.
    """
    ids = {}
    for element in root.iter():
        if "id" in element.attrib:
            ids[element.attrib["id"]] = element  # the last one wins, as in svgelements
    placed: list[Placed] = []
    count = 0
    switches = {}

    def walk(element, chain, skipped, unrendered, expanding):
        nonlocal count
        count += 1
        if count > MAX_ELEMENTS:
            raise DrawingError(f"{origin} expands to more than {MAX_ELEMENTS} elements (its <use> elements clone "
                               "clones of clones...): refused, as reading it would take too long")
        tag = local_tag(element.tag)
        parent = chain[-1] if chain else None
        parent_tag = local_tag(parent.tag) if parent is not None else None
        unrendered = unrendered or tag in _UNRENDERED
        if skipped is None:
            if tag in _REFERENCED_ONLY and not (tag == "symbol" and parent_tag == "use"):
                skipped = f"inside {_describe(element)}, drawn only through a <use>" if tag == "symbol" else \
                    f"inside {_describe(element)}, which SVG never draws by itself"
            elif parent_tag == "switch":
                if parent not in switches:
                    switches[parent] = _chosen(parent)
                if switches[parent] is not element:
                    skipped = f"in a branch of {_describe(parent)} that is not chosen"
        if tag in SHAPE_TAGS and not unrendered:
            placed.append(Placed(element, chain, skipped))
        inner = (*chain, element)
        for child in element:
            if isinstance(child.tag, str):
                walk(child, inner, skipped, unrendered, expanding)
        if tag == "use":
            url = _href(element)
            target = ids.get(url[1:]) if url else None
            if target is not None:
                if element in expanding:
                    raise DrawingError(f"{origin}: {_describe(element)} (href={url!r}) draws itself through <use> "
                                       "references, without end; SVG draws nothing for such a cycle: remove the "
                                       "reference")
                walk(target, inner, skipped, unrendered, expanding | {element})

    try:
        walk(root, (), None, False, frozenset())
    except RecursionError:
        raise DrawingError(f"{origin} nests its elements (or <use> references) too deeply to be read") from None
    return placed


def check_transforms(root: ET.Element, origin: str) -> None:
    """Refuse a ``transform`` attribute anywhere in the document that is not an SVG transform list.

    svgelements skips or fails on such attributes; an SVG viewer would ignore them, which moves
    the drawing silently.
    """
    for element in root.iter():
        text = element.get("transform")
        if text is None or not text.strip():
            continue
        position, ok = 0, True
        while ok and text[position:].strip():
            match = _ONE_TRANSFORM.match(text, position)
            ok = bool(match) and match.group(1) in _ARGUMENTS and _count(match.group(2)) in _ARGUMENTS[match.group(1)]
            position = match.end() if match else position
        if not ok:
            raise DrawingError(f"{origin}: a transform attribute cannot be read ({_describe(element)} has "
                               f"transform={text!r}); expected e.g. 'translate(10,20) rotate(30) scale(2) "
                               "matrix(a,b,c,d,e,f)'")


def _count(arguments: str) -> int | None:
    """How many numbers ``arguments`` holds (separated by spaces or a comma), None if anything else."""
    position, count = 0, 0
    while arguments[position:].strip():
        match = _ARGUMENT.match(arguments, position)
        if not match:
            return None
        position, count = match.end(), count + 1
    return count


def styled_names(root: ET.Element) -> set[str]:
    """Names of the properties that any ``<style>`` sheet or ``style`` attribute sets in the document."""
    names = set()
    for element in root.iter():
        texts = [element.get("style") or ""]
        if local_tag(element.tag) == "style":
            texts = _CSS_BLOCK.findall(element.text or "")
        for text in texts:
            names.update(d.split(":", 1)[0].strip() for d in text.split(";") if ":" in d)
    return names


def unapplied_rules(root: ET.Element) -> list[str]:
    """A note naming the ``<style>`` selectors that are not applied (descendant, child, attribute ones), if any.

    svgelements applies rules whose selector is ``*``, ``tag``, ``#id``, ``.class`` or ``tag.class``;
    a rule such as ``g.hidden path {display: none}`` is skipped, so what it would hide or restyle is
    read as if it were not there. The note says so rather than tracing silently what SVG would not draw.
    """
    skipped = []
    for element in root.iter():
        if local_tag(element.tag) != "style":
            continue
        for head in _CSS_RULE.findall(_CSS_COMMENT.sub("", element.text or "")):
            for selector in (part.strip() for part in head.split(",")):
                if selector and not selector.startswith("@") and not _SIMPLE_SELECTOR.fullmatch(selector):
                    skipped.append(" ".join(selector.split()))
    unique = list(dict.fromkeys(skipped))
    if not unique:
        return []
    shown = ", ".join(repr(x) for x in unique[:5])
    more = f" and {len(unique) - 5} more" if len(unique) > 5 else ""
    return [f"<style> rules with the selectors {shown}{more} are not applied (only *, tag, #id, .class and "
            "tag.class are): shapes they would hide or restyle are read as if the rules were absent; give them a "
            "class or a style attribute, or pick paths with --path ID"]
