"""Draw the architecture page's picture and table from the code, at every build.

The layers come from the import-linter contract in ``pyproject.toml`` (``[tool.importlinter]``), the
one place that says which stage may import which; each stage's job is the first line of its
docstring, and its modules are the files found in it. So the page cannot drift from the code: a
new subpackage appears here as soon as the contract names it, and the tests
(``tests/test_docs.py``) fail while it has no docstring or no paragraph on the page.

Writes ``docs/_generated/architecture.svg`` and ``docs/_generated/stages.md`` (git-ignored),
which ``docs/architecture.md`` includes.
"""

from __future__ import annotations

import ast
import textwrap
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
PACKAGE = ROOT / "src" / "skatetrace"
OUT = ROOT / "docs" / "_generated"

# The path of a figure through the stages, in the order a run takes it (drawing -> fit -> trace ->
# verify -> files and pictures); every name must be a layer of the contract (checked below).
PIPELINE = (
    ("drawings", "drawing → fit"),
    ("figures", "figure"),
    ("tracing", "trace"),
    ("verification", "verify"),
    ("pipeline", "rests, retries"),
    ("outputs", "files, pictures"),
)


def layers(pyproject: Path = ROOT / "pyproject.toml") -> list[list[str]]:
    """The contract's layers, top first; a layer of independent stages (``"a | b"``) is a list of names."""
    config = tomllib.loads(pyproject.read_text(encoding="utf-8"))["tool"]["importlinter"]
    contracts = [c for c in config["contracts"] if c.get("type") == "layers"]
    if len(contracts) != 1:
        raise ValueError(f"expected one layers contract in pyproject.toml, found {len(contracts)}")
    return [[name.strip() for name in layer.split("|")] for layer in contracts[0]["layers"]]


def source_of(stage: str) -> Path:
    """The file whose docstring describes ``stage``: its package's ``__init__.py`` or its module."""
    package = PACKAGE / stage / "__init__.py"
    return package if package.exists() else PACKAGE / f"{stage}.py"


def summary(stage: str) -> str:
    """The first line of the stage's docstring: its one job."""
    path = source_of(stage)
    doc = ast.get_docstring(ast.parse(path.read_text(encoding="utf-8")))
    if not doc:
        raise ValueError(f"{path.relative_to(ROOT)} has no docstring saying its job")
    return doc.strip().splitlines()[0].replace("``", "")


def modules(stage: str) -> list[str]:
    """The modules of a subpackage (none for a single module)."""
    folder = PACKAGE / stage
    if not folder.is_dir():
        return []
    return sorted(p.stem for p in folder.glob("*.py") if not p.stem.startswith("_"))


def stages_markdown(stack: list[list[str]]) -> str:
    """A table of every stage, top layer first: its job and its modules, linked to the API reference."""
    rows = ["| layer | stage | its job (the docstring's first line) | modules |", "|---|---|---|---|"]
    for depth, layer in enumerate(stack, 1):
        for stage in layer:
            mods = ", ".join(f"{{mod}}`~skatetrace.{stage}.{m}`" for m in modules(stage))
            job = summary(stage).replace("|", "\\|")
            rows.append(f"| {depth} | {{mod}}`skatetrace.{stage}` | {job} | {mods or '(one module)'} |")
    return "\n".join(rows) + "\n"


def draw(stack: list[list[str]], path: Path) -> None:
    """The layers as stacked boxes (imports point only down) with the path of a figure drawn across them."""
    import matplotlib

    matplotlib.use("Agg")
    matplotlib.rcParams["svg.fonttype"] = "none"  # text stays text: searchable, and the file small
    import matplotlib.pyplot as plt
    from matplotlib.patches import FancyArrowPatch, FancyBboxPatch

    names = {stage for layer in stack for stage in layer}
    missing = [stage for stage, _ in PIPELINE if stage not in names]
    if missing:
        raise ValueError(f"docs/_ext/architecture.py: pipeline stages {missing} are not layers of the contract")
    width, row = 10.0, 1.0
    fig, ax = plt.subplots(figsize=(8.2, 0.9 * len(stack) + 0.3))
    centres = {}
    for depth, layer in enumerate(stack):
        y = (len(stack) - 1 - depth) * row
        w = width / len(layer)
        for k, stage in enumerate(layer):
            x0 = k * w
            in_pipeline = any(stage == s for s, _ in PIPELINE)
            ax.add_patch(FancyBboxPatch((x0 + 0.06, y + 0.1), w - 0.12, row - 0.2,
                                        boxstyle="round,pad=0.02,rounding_size=0.08",
                                        facecolor="#dbe9f6" if in_pipeline else "#eeeeee",
                                        edgecolor="#3b6ea5" if in_pipeline else "#888888"))
            label = "skatetrace." + stage
            ax.text(x0 + 0.2, y + row - 0.27, label, fontsize=11, fontweight="bold", va="center")
            job = textwrap.fill(summary(stage), width=int(56 * w / width) + 4, max_lines=3, placeholder=" …")
            ax.text(x0 + 0.2, y + 0.4, job, fontsize=8.5, va="center", color="#333333", linespacing=1.15)
            centres[stage] = (x0 + w - 0.85, y + row - 0.27)
    # the path of a figure through the stages, bottom of the stack upwards, on the right
    previous = None
    for stage, step in PIPELINE:
        x, y = centres[stage]
        ax.text(x, y, step, fontsize=9, ha="center", va="center", color="#b03a2e", fontweight="bold",
                bbox=dict(boxstyle="round,pad=0.25", facecolor="white", edgecolor="#b03a2e"))
        if previous is not None:
            ax.add_patch(FancyArrowPatch(previous, (x, y), arrowstyle="-|>", mutation_scale=12,
                                         color="#b03a2e", shrinkA=11, shrinkB=11,
                                         connectionstyle="arc3,rad=-0.25"))
        previous = (x, y)
    ax.annotate("", xy=(-0.25, 0.1), xytext=(-0.25, len(stack) * row - 0.1),
                arrowprops=dict(arrowstyle="-|>", color="#555555"))
    ax.text(-0.45, len(stack) * row / 2, "imports point only down", rotation=90, ha="center", va="center",
            fontsize=8, color="#555555")
    ax.set_xlim(-0.7, width + 0.05)
    ax.set_ylim(0, len(stack) * row)
    ax.axis("off")
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, metadata={"Date": None} if path.suffix == ".svg" else None)
    plt.close(fig)


def generate(app=None) -> None:
    """Write the picture and the table (``builder-inited``)."""
    stack = layers()
    OUT.mkdir(parents=True, exist_ok=True)
    draw(stack, OUT / "architecture.svg")
    (OUT / "stages.md").write_text(stages_markdown(stack), encoding="utf-8")


def setup(app):
    app.connect("builder-inited", generate)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
