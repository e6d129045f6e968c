"""The ``skatetrace-public-api`` directive: ``skatetrace.__all__`` as tables, one per module.

Each name links to the page where its module documents it, and ``skatetrace.NAME`` in any
reference resolves there too (:func:`resolve_public_name`), so the public API's list is built from
``__all__`` at every build and never goes stale. Modules are shown in the order a user meets
them; a module not in that order comes last, so a new export is never left out.
"""

from __future__ import annotations

import importlib

from docutils import nodes
from docutils.statemachine import StringList
from sphinx.util.docutils import SphinxDirective

ORDER = ("pipeline", "figures", "drawings", "dynamics", "tracing", "verification", "errors")


def public_api() -> dict[str, list[str]]:
    """``{module: [names]}`` for every name of ``skatetrace.__all__``, grouped by defining module."""
    package = importlib.import_module("skatetrace")
    groups: dict[str, list[str]] = {}
    for name in package.__all__:
        groups.setdefault(home(name), []).append(name)

    def rank(module: str) -> tuple[int, str]:
        stage = module.split(".")[1]
        return (ORDER.index(stage) if stage in ORDER else len(ORDER), module)

    return {module: sorted(groups[module], key=str.lower) for module in sorted(groups, key=rank)}


class PublicApi(SphinxDirective):
    has_content = False

    def run(self):
        lines = []
        for module, names in public_api().items():
            doc = importlib.import_module(module).__doc__ or ""
            lines += [f".. rubric:: :mod:`{module}`", ""]
            summary = doc.strip().splitlines()[0] if doc.strip() else ""
            if summary:
                lines += [summary, ""]
            # the names relative to their module, so that the summaries' short references resolve
            lines += [f".. currentmodule:: {module}", "", ".. autosummary::", "   :nosignatures:", ""]
            lines += [f"   {name}" for name in names]
            lines += [""]
        lines += [".. currentmodule:: None", ""]
        container = nodes.container()
        self.state.nested_parse(StringList(lines, source="skatetrace.__all__"), self.content_offset, container)
        return container.children


def home(name: str) -> str | None:
    """The module that defines the public name ``name`` (``None`` if it is not public)."""
    package = importlib.import_module("skatetrace")
    if name not in package.__all__:
        return None
    lazy = package._MODULE_OF.get(name)
    return f"skatetrace.{lazy}" if lazy else getattr(package, name).__module__


def resolve_public_name(app, env, node, contnode):
    """Let ``:func:`skatetrace.trace_and_verify``` link to where its module documents it.

    The public API is spelled ``skatetrace.NAME`` in prose and tutorials, but each object is
    documented once, in its module's page; this maps the one spelling onto the other.
    """
    if node.get("refdomain") != "py":
        return None
    parts = node.get("reftarget", "").split(".")
    if len(parts) < 2 or parts[0] != "skatetrace":
        return None
    module = home(parts[1])
    if module is None:
        return None
    target = ".".join([module, *parts[1:]])
    domain = env.get_domain("py")
    found = domain.resolve_xref(env, node["refdoc"], app.builder, node["reftype"], target, node, contnode)
    if found is None:  # e.g. :func: written for a class: any object of that name will do
        hits = domain.resolve_any_xref(env, node["refdoc"], app.builder, target, node, contnode)
        found = hits[0][1] if hits else None
    return found


def setup(app):
    app.add_directive("skatetrace-public-api", PublicApi)
    app.connect("missing-reference", resolve_public_name)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
