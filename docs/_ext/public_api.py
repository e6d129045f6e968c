"""The ``skatetrace-public-api`` directive: ``skatetrace.__all__`` as tables, one per module.

Each name links to the page where its module documents it, so the public API's list is built from
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
        lazy = package._MODULE_OF.get(name)
        module = f"skatetrace.{lazy}" if lazy else getattr(package, name).__module__
        groups.setdefault(module, []).append(name)

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
            lines += [f".. rubric:: From :mod:`{module}`", ""]
            summary = doc.strip().splitlines()[0] if doc.strip() else ""
            if summary:
                lines += [summary, ""]
            lines += [".. autosummary::", "   :nosignatures:", ""]
            lines += [f"   ~{module}.{name}" for name in names]
            lines += [""]
        container = nodes.container()
        self.state.nested_parse(StringList(lines, source="skatetrace.__all__"), self.content_offset, container)
        return container.children


def setup(app):
    app.add_directive("skatetrace-public-api", PublicApi)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
