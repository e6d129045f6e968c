"""The simple XML entities of an SVG's DOCTYPE (as Adobe Illustrator writes them), inlined before it is parsed.

Illustrator's SVG export declares the namespaces as entities in an internal DTD subset and uses them
in attributes::

    <!DOCTYPE svg PUBLIC "-//W3C//DTD SVG 1.1//EN" "http://www.w3.org/Graphics/SVG/1.1/DTD/svg11.dtd" [
        <!ENTITY ns_svg "http://www.w3.org/2000/svg">
        <!ENTITY ns_xlink "http://www.w3.org/1999/xlink">
    ]>
    <svg xmlns="&ns_svg;" xmlns:xlink="&ns_xlink;" ...>

The safe parser (defusedxml) refuses every entity declaration, since nested ones expand without bound
(an XML bomb) and external ones read files. :func:`inline_entities` replaces the references of such a
document by their values and drops the DOCTYPE, but only where every declaration is a plain
internal text (no ``&``, ``<`` or quotes inside, so no entity refers to another), there are at most
:data:`MAX_ENTITIES` of them, and the document grows by at most :data:`MAX_GROWTH`. Anything else is
left as it is, for the parser to refuse with its reason.
"""

from __future__ import annotations

import re

__all__ = ["MAX_ENTITIES", "MAX_GROWTH", "MAX_VALUE", "inline_entities"]

#: The most entities a DOCTYPE may declare to be inlined, the longest value, and how many
#: characters inlining may add to the document in all.
MAX_ENTITIES = 64
MAX_VALUE = 1024
MAX_GROWTH = 1 << 20

_DOCTYPE = re.compile(r"<!DOCTYPE\s[^\[>]*\[(?P<subset>.*?)\]\s*>", re.DOTALL)
_DECLARATION = re.compile(r"""<!ENTITY\s+(?P<name>[A-Za-z_][\w.\-]*)\s+(?:"(?P<v1>[^"&<']*)"|'(?P<v2>[^'&<"]*)')\s*>""")
_COMMENT = re.compile(r"<!--.*?-->", re.DOTALL)


def inline_entities(data: bytes | str) -> tuple[bytes | str, list[str]]:
    """``data`` with the simple entities of its DOCTYPE inlined (see the module docstring), and their names.

    Returns ``data`` unchanged, and no names, where there is no internal DTD subset, or where it
    holds anything but plain internal entities within the limits.
    """
    text = data
    if isinstance(data, bytes):
        try:
            text = data.decode("utf-8-sig")
        except UnicodeDecodeError:
            return data, []
    match = _DOCTYPE.search(text)
    if match is None:
        return data, []
    subset = _COMMENT.sub("", match.group("subset"))
    values: dict[str, str] = {}

    def take(m: re.Match) -> str:
        values.setdefault(m.group("name"), m.group("v1") if m.group("v1") is not None else m.group("v2"))
        return ""

    rest = _DECLARATION.sub(take, subset)  # what is left must be blank: nothing but these declarations
    if rest.strip() or not values or len(values) > MAX_ENTITIES or any(len(v) > MAX_VALUE for v in values.values()):
        return data, []
    body = text[match.end():]
    refs = re.compile("&(" + "|".join(re.escape(name) for name in values) + ");")
    growth = sum(len(values[m.group(1)]) for m in refs.finditer(body))
    if growth > MAX_GROWTH:
        return data, []
    out = text[:match.start()] + refs.sub(lambda m: values[m.group(1)], body)
    return (out.encode("utf-8") if isinstance(data, bytes) else out), sorted(values)
