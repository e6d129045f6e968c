"""The user guide (docs/guide/*.md) is part of the product: its examples run as written, its links and
module names are current, its measured table is the script's output, and every page is in its toctree.

The Sphinx build (warnings as errors) checks the pages' MyST syntax; these tests check what it does not,
and run without Sphinx installed.
"""

from __future__ import annotations

import importlib
import json
import re
from pathlib import Path

import pytest
from scripts import load_script

from test_readme import MACHINE_DIGITS, README, blocks, run_block

ROOT = Path(__file__).resolve().parents[1]
GUIDE = ROOT / "docs" / "guide"
PAGES = {p.name: p.read_text(encoding="utf-8") for p in sorted(GUIDE.glob("*.md"))}
PYTHON_BLOCKS = [(name, i) for name, text in PAGES.items() for i in range(len(blocks(text, "python")))]


def _measure_examples():
    return load_script(ROOT / "bench" / "measure_examples.py")


def test_the_guide_has_its_pages_and_examples():
    assert {"index.md", "command-line.md", "python-api.md", "paper.md", "inputs.md", "outputs.md",
            "figure-format.md", "feasibility.md", "examples.md", "performance.md", "limits.md"} <= set(PAGES)
    assert len(PYTHON_BLOCKS) >= 2


@pytest.mark.slow
@pytest.mark.parametrize(("page", "index"), PYTHON_BLOCKS, ids=[f"{p}-{i}" for p, i in PYTHON_BLOCKS])
def test_python_block_runs_as_written(page, index, monkeypatch):
    # From the root of a clone, as a user would paste it: relative paths such as examples/ resolve.
    monkeypatch.chdir(ROOT)
    printed = run_block(blocks(PAGES[page], "python")[index], f"docs/guide/{page} python block {index}")
    assert printed.strip(), "every example in the guide prints what it shows"


def test_python_block_comments_carry_no_machine_digits():
    # Comments quote numbers only as rough magnitudes or bounds, never one machine's digits.
    for page, text in PAGES.items():
        for block in blocks(text, "python"):
            for comment in re.findall(r"#(.*)$", block, flags=re.MULTILINE):
                assert not MACHINE_DIGITS.search(comment), f"{page}: a machine's digits in a comment: {comment}"


def test_the_index_toctree_lists_every_page_once():
    toctree = re.search(r"^```\{toctree\}\n(.*?)^```", PAGES["index.md"], flags=re.MULTILINE | re.DOTALL).group(1)
    entries = [line.strip() for line in toctree.splitlines() if line.strip() and not line.startswith(":")]
    assert sorted(entries) == sorted(name.removesuffix(".md") for name in PAGES if name != "index.md")
    assert len(entries) == len(set(entries))


@pytest.mark.parametrize("page", sorted(PAGES))
def test_a_page_has_one_title_and_no_skipped_heading_level(page):
    text = re.sub(r"^```.*?^```", "", PAGES[page], flags=re.MULTILINE | re.DOTALL)  # not inside code
    levels = [len(h) for h in re.findall(r"^(#+) ", text, flags=re.MULTILINE)]
    assert levels and levels[0] == 1 and levels.count(1) == 1, f"{page}: one '# ' title first, got {levels}"
    for before, after in zip(levels, levels[1:]):
        assert after <= before + 1, f"{page}: heading level jumps from {before} to {after}"


@pytest.mark.parametrize("page", sorted(PAGES))
def test_a_pages_links_lead_to_files_that_exist(page):
    for link in re.findall(r"\]\(([^)\s]+)\)", PAGES[page]):
        if re.match(r"[a-z]+://", link):
            continue
        # Anchors need a Sphinx setting (heading anchors) that the build may not have: link to pages.
        assert "#" not in link, f"{page}: link to a page, not an anchor: {link}"
        assert (GUIDE / link).resolve().is_file(), f"{page} links to {link}, which does not exist"


@pytest.mark.parametrize("page", sorted(PAGES))
def test_every_code_block_names_its_language(page):
    # A bare fence is highlighted as Python by Sphinx, which warns (an error with -W) on text it cannot lex.
    fences = re.findall(r"^```(.*)$", PAGES[page], flags=re.MULTILINE)
    assert len(fences) % 2 == 0, f"{page}: an unclosed code block"
    opening = fences[::2]
    assert all(f.strip() for f in opening), f"{page}: a code block without a language"


def _named_objects(text: str) -> set[str]:
    """Dotted names ``skatetrace.x.y`` in a text (schemas such as ``skatetrace.figure/1`` excluded)."""
    return set(re.findall(r"\bskatetrace(?:\.[A-Za-z_]\w*)+(?![\w/.])", text))


def _resolves(dotted: str) -> bool:
    parts = dotted.split(".")
    for n in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:n]))
        except ImportError:
            continue
        try:
            for attr in parts[n:]:
                obj = getattr(obj, attr)
        except AttributeError:
            return False
        return True
    return False


def test_the_modules_and_functions_named_exist():
    # The guide names today's modules (e.g. skatetrace.pipeline, skatetrace.outputs.results), not old ones.
    named = {name: page for page, text in [*PAGES.items(), ("README.md", README)] for name in _named_objects(text)}
    assert "skatetrace.outputs.results.load_result" in named
    missing = sorted(f"{name} (in {page})" for name, page in named.items() if not _resolves(name))
    assert not missing, f"named but not importable: {missing}"
    assert not _resolves("skatetrace.rests"), "the check must tell a moved module (skatetrace.rests) from a current one"


def test_the_examples_table_is_the_scripts_output():
    # The guide's measured figures come from bench/measure_examples.py, never by hand.
    module = _measure_examples()
    assert module.PAGE == GUIDE / "examples.md"
    data = json.loads((ROOT / "bench" / "examples.json").read_text(encoding="utf-8"))
    text = PAGES["examples.md"]
    block = text[text.index(module.BEGIN) + len(module.BEGIN):text.index(module.END)]
    assert block.strip() == module.render(data).strip()
    assert {r["name"] for r in data["rows"]} == set(module.EXAMPLES)


def test_render_only_rewrites_the_table_without_measuring(tmp_path):
    module = _measure_examples()
    page = tmp_path / "examples.md"
    page.write_text(f"# Examples\n\nbefore\n{module.BEGIN}\nstale table\n{module.END}\nafter\n", encoding="utf-8")
    module.render_only(page=page)
    data = json.loads((ROOT / "bench" / "examples.json").read_text(encoding="utf-8"))
    assert page.read_text(encoding="utf-8") == \
        f"# Examples\n\nbefore\n{module.BEGIN}\n{module.render(data)}\n{module.END}\nafter\n"
    page.write_text("# no markers\n", encoding="utf-8")
    with pytest.raises(SystemExit, match="markers"):
        module.render_only(page=page)


def test_bounds_round_up_to_one_digit():
    module = _measure_examples()
    assert [module._bound(x) for x in (3.39e-9, 1e-9, 9.01e-10, 0.0253, 2.0, None)] == \
        ["4e-9", "1e-9", "1e-9", "0.03", "2", "–"]
