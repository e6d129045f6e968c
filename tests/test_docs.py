"""The documentation's sources keep up with the code (fast: no Sphinx build).

The full build (``python -m sphinx -W --keep-going -b html docs docs/_build/html``) runs in CI
after the tests; these checks catch, in a second, what would otherwise only show there or not at
all: a subcommand missing from the CLI reference, a tutorial that is not valid Python or not a
gallery page, a stage without a docstring or a paragraph on the architecture page.
"""

from __future__ import annotations

import ast
import re
import tomllib
from pathlib import Path

import pytest
from scripts import load_script

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
PACKAGE = ROOT / "src" / "skatetrace"


def _architecture():
    """The build-time generator of the architecture page, ``docs/_ext/architecture.py``."""
    return load_script(DOCS / "_ext" / "architecture.py", "docs_architecture")


def _subpackages() -> list[str]:
    return sorted(p.parent.name for p in PACKAGE.glob("*/__init__.py"))


def _gallery() -> list[Path]:
    return sorted((DOCS / "gallery").glob("*.py"))


# --- CLI reference -------------------------------------------------------------------------------

def test_cli_reference_is_generated_from_build_parser():
    text = (DOCS / "cli.rst").read_text(encoding="utf-8")
    directive = re.search(r"^\.\. argparse::\n((?:   .*\n)+)", text, re.M)
    assert directive, "docs/cli.rst must document the parser with sphinx-argparse's '.. argparse::'"
    options = dict(re.findall(r"^   :(\w+):\s*(.*)$", directive.group(1), re.M))
    assert options.get("module") == "skatetrace.cli.commands" and options.get("func") == "build_parser"
    # options that would leave subcommands out of the page
    assert not {"nosubcommands", "path"} & set(options), options


def test_cli_reference_lists_every_subcommand():
    sphinxarg = pytest.importorskip("sphinxarg.parser", reason="sphinx-argparse is in the docs extra")
    from skatetrace.cli.commands import build_parser

    parser = build_parser()
    subparsers = next(a for a in parser._actions if a.__class__.__name__ == "_SubParsersAction")
    commands = set(subparsers.choices)
    assert {"trace", "fit", "animate", "view", "figures", "reproduce"} <= commands
    documented = {child["name"] for child in sphinxarg.parse_parser(parser).get("children", [])}
    assert documented == commands


# --- tutorials -----------------------------------------------------------------------------------

def test_gallery_has_the_five_tutorials():
    names = [p.stem for p in _gallery()]
    assert len(names) >= 5, names
    for topic in ("double_flower", "school_figure", "svg", "paper", "pandas"):
        assert any(topic in n for n in names), f"no tutorial about {topic!r} in docs/gallery: {names}"
    assert (DOCS / "gallery" / "GALLERY_HEADER.rst").is_file()


@pytest.mark.parametrize("script", _gallery(), ids=lambda p: p.name)
def test_gallery_script_is_a_valid_page(script: Path):
    source = script.read_text(encoding="utf-8")
    tree = ast.parse(source, filename=str(script))  # valid Python
    compile(tree, str(script), "exec")
    doc = ast.get_docstring(tree)
    assert doc, f"{script.name}: sphinx-gallery needs a docstring with the page's title"
    title, underline = doc.splitlines()[:2]
    assert title.strip() and set(underline) == {"="} and len(underline) >= len(title), \
        f"{script.name}: the docstring must open with a title underlined by '='"
    # every tutorial runs from a fresh clone: it writes only to a temporary folder and reads no
    # file outside the repository
    assert not re.search(r"""["'](/\w|~/|[A-Za-z]:\\)""", source), f"{script.name} names an absolute path"
    code = "\n".join(line for line in source.splitlines() if not line.lstrip().startswith("#"))
    if re.search(r"write_text|write_results|savefig|open\(|--out", code):
        assert "tempfile" in code, f"{script.name} writes files: it must write them to a temporary folder"


def test_gallery_output_is_ignored_by_git():
    ignored = (ROOT / ".gitignore").read_text(encoding="utf-8").split()
    for generated in ("/docs/_build/", "/docs/tutorials/", "/docs/generated/", "/docs/_generated/"):
        assert generated in ignored, f"{generated} (written by the docs build) must be git-ignored"


# --- architecture --------------------------------------------------------------------------------

def test_every_subpackage_is_a_layer_and_on_the_architecture_page():
    arch = _architecture()
    layers = {name for layer in arch.layers(ROOT / "pyproject.toml") for name in layer}
    page = (DOCS / "architecture.md").read_text(encoding="utf-8")
    for name in _subpackages():
        assert name in layers, f"skatetrace.{name} is not a layer of [tool.importlinter] in pyproject.toml"
        assert f"- **`{name}`**:" in page, f"docs/architecture.md has no paragraph on skatetrace.{name}"
    for name in layers:
        assert arch.source_of(name).is_file(), f"layer {name!r} of the import contract is not in the package"


def test_every_stage_has_a_docstring_saying_its_job():
    arch = _architecture()
    for layer in arch.layers():
        for stage in layer:
            job = arch.summary(stage)
            assert job.endswith(".") and len(job) > 20, f"skatetrace.{stage}: {job!r}"


def test_architecture_table_lists_every_stage_and_module(tmp_path):
    arch = _architecture()
    table = arch.stages_markdown(arch.layers())
    for name in _subpackages():
        assert f"{{mod}}`skatetrace.{name}`" in table
        for module in PACKAGE.joinpath(name).glob("*.py"):
            if not module.stem.startswith("_"):
                assert f"skatetrace.{name}.{module.stem}`" in table, module


def test_architecture_generator_refuses_an_unknown_pipeline_stage(tmp_path):
    arch = _architecture()
    pyproject = tmp_path / "pyproject.toml"
    config = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
    layers = config["tool"]["importlinter"]["contracts"][0]["layers"]
    pyproject.write_text("[tool.importlinter]\nroot_package = 'skatetrace'\n[[tool.importlinter.contracts]]\n"
                         "name = 'x'\ntype = 'layers'\ncontainers = ['skatetrace']\nlayers = "
                         + repr([layer for layer in layers if "verification" not in layer]).replace("'", '"') + "\n")
    with pytest.raises(ValueError, match="verification"):
        arch.draw(arch.layers(pyproject), tmp_path / "architecture.svg")
