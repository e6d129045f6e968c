"""Whether an SVG element is drawn: its ``display``, ``visibility``, ``stroke`` and ``fill``, as inherited.

A property is read from the element's ``style`` attribute (``"stroke:none; fill:#000"``), which wins
over its presentation attribute (``stroke="none"``), and otherwise from its nearest ancestor that sets
it (``inherit`` defers to the parent). ``display:none`` on an element or any ancestor hides it;
``visibility`` is inherited and a child may set it back to ``visible``. CSS in ``<style>`` sheets is
not applied (the element's own attributes and ``style`` are).

An element paints nothing when both its fill and its stroke are ``none`` (SVG's defaults: fill black,
stroke none), as the invisible bounding boxes of icon sets are (``<path d="M0 0h24v24H0z" fill="none"/>``).
"""

from __future__ import annotations

import xml.etree.ElementTree as ET

__all__ = ["Visibility", "visibility"]

_DEFAULTS = {"fill": "black", "stroke": "none", "visibility": "visible", "display": "inline"}


class Visibility:
    """How an element shows: ``hidden`` (``display:none`` or ``visibility`` hidden or collapsed),
    ``unpainted`` (fill and stroke both ``none``), or ``drawn``."""

    HIDDEN = "hidden"
    UNPAINTED = "unpainted"
    DRAWN = "drawn"


def _declared(element: ET.Element, name: str) -> str | None:
    """The value ``element`` itself sets for ``name`` (``style`` first), lower-cased, or None."""
    style = element.get("style") or ""
    for declaration in style.split(";"):
        key, _, value = declaration.partition(":")
        if key.strip().lower() == name and value.strip():
            return value.replace("!important", "").strip().lower()
    value = element.get(name)
    return value.strip().lower() if value is not None and value.strip() else None


def _inherited(chain: list[ET.Element], name: str) -> str:
    for element in chain:  # the element first, then its ancestors
        value = _declared(element, name)
        if value is not None and value != "inherit":
            return value
    return _DEFAULTS[name]


def visibility(element: ET.Element, parents: dict[ET.Element, ET.Element]) -> str:
    """The :class:`Visibility` of ``element``; ``parents`` maps every element to its parent."""
    chain = [element]
    while chain[-1] in parents:
        chain.append(parents[chain[-1]])
    if any(_declared(e, "display") == "none" for e in chain):
        return Visibility.HIDDEN
    if _inherited(chain, "visibility") in ("hidden", "collapse"):
        return Visibility.HIDDEN
    if _inherited(chain, "fill") == "none" and _inherited(chain, "stroke") == "none":
        return Visibility.UNPAINTED
    return Visibility.DRAWN
