"""The README is part of the product: one screen, its examples run as written, its set-up is what CI runs.

The user guide (docs/guide/) holds everything else; tests/test_guide.py holds the guide to the same rules.
"""

from __future__ import annotations

import contextlib
import io
import re
import shlex
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text(encoding="utf-8")


def blocks(text: str, lang: str) -> list[str]:
    """The fenced code blocks of ``text`` in language ``lang``."""
    return re.findall(rf"^```{lang}\n(.*?)^```", text, flags=re.MULTILINE | re.DOTALL)


def section(text: str, heading: str) -> str:
    """The section of ``text`` that starts with the level-2 ``heading``, up to the next level-2 heading."""
    rest = text[text.index(heading):]
    end = rest.find("\n## ", 4)
    return rest if end < 0 else rest[:end]


def run_block(code: str, name: str) -> str:
    """Run a Python block from the root of a clone, as a user would paste it; return what it printed."""
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        exec(compile(code, name, "exec"), {"__name__": "__readme__"})
    return out.getvalue()


MACHINE_DIGITS = re.compile(r"\d\.\d{2,}e-\d")


def _setup_commands() -> list[str]:
    """The commands of the first bash block after the "Set-up" heading, comments stripped."""
    block = blocks(README[README.index("## Set-up"):], "bash")[0]
    return [line.split("#")[0].strip() for line in block.splitlines() if line.strip()]


def _cli_examples() -> list[str]:
    """The commands of the README's "Command line" section, comments stripped."""
    block = blocks(section(README, "## Command line"), "bash")[0]
    return [line.split("#")[0].strip() for line in block.splitlines() if line.strip()]


def test_the_readme_has_one_api_example():
    assert len(blocks(README, "python")) == 1, "the README shows one API example; more go in docs/guide/"


@pytest.mark.slow
@pytest.mark.parametrize("index", range(len(blocks(README, "python"))))
def test_python_block_runs_as_written(index, monkeypatch):
    # From the root of a clone, as a user would paste it: relative paths such as examples/ resolve.
    monkeypatch.chdir(ROOT)
    printed = run_block(blocks(README, "python")[index], f"README.md python block {index}")
    assert printed.strip(), "every README example prints what it shows"


@pytest.mark.slow
def test_the_api_example_prints_what_its_comments_say(monkeypatch):
    monkeypatch.chdir(ROOT)
    code = blocks(README, "python")[0]
    lines = run_block(code, "README.md python block").splitlines()
    said = [c.strip() for c in re.findall(r"^print\(.*#(.*)$", code, flags=re.MULTILINE)]
    assert len(lines) == len(said), (lines, said)
    for line, comment in zip(lines, said):
        # A comment quotes the printed line's start (up to a colon or "...") exactly.
        shown = re.split(r":|\.\.\.", comment)[0].strip()
        assert line.startswith(shown), f"printed {line!r}, the comment says {comment!r}"


def test_python_blocks_print_what_their_comments_say():
    # Comments quote numbers only as rough magnitudes or bounds, never one machine's digits.
    for block in blocks(README, "python"):
        for comment in re.findall(r"#(.*)$", block, flags=re.MULTILINE):
            assert not MACHINE_DIGITS.search(comment), f"a machine's digits in a README comment: {comment}"


def test_setup_is_two_commands_and_ci_runs_the_test_command():
    cmds = _setup_commands()
    assert len(cmds) == 2, cmds
    main_job, tests = cmds
    assert "skatetrace trace double-flower" in main_job
    assert "[test]" not in main_job, "the main job must not need the test extras"
    assert "python -m pytest -q" in tests
    ci = (ROOT / ".ci" / "run").read_text(encoding="utf-8")
    # CI installs the test extras (and may add others, e.g. docs) and runs the README's test command.
    assert re.search(r'pip install -q -e "\.\[test(,[a-z0-9-]+)*\]"', ci), ci
    assert re.search(r"^python -m pytest -q\b", ci, flags=re.MULTILINE)


def test_the_quick_subset_named_in_the_readme_exists():
    assert 'python -m pytest -q -m "not slow"' in README
    config = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
    assert any(m.startswith("slow:") for m in config["tool"]["pytest"]["ini_options"]["markers"])


def test_every_dependency_is_justified_in_the_readme():
    config = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
    deps = config["project"]["dependencies"] + [d for extra in config["project"]["optional-dependencies"].values()
                                                for d in extra]
    deps_section = section(README, "## Dependencies")
    for dep in deps:
        name = re.split(r"[<>=!~\[ ;]", dep, maxsplit=1)[0]
        line = re.search(rf"^- {re.escape(name)}\b.*$", deps_section, flags=re.MULTILINE | re.IGNORECASE)
        assert line, f"{name}: justify it in one line of the README's Dependencies"
        assert re.search(r">=\s*\d", dep), f"{dep}: pin a lower bound"
    for line in deps_section.splitlines():
        assert not line.startswith("  "), f"one line per dependency; the long reasons go in the guide: {line!r}"


def test_the_readme_is_one_screen_besides_its_dependencies():
    before = README[:README.index("## Dependencies")]
    assert before.count("\n") <= 60, f"{before.count(chr(10))} lines: move details to docs/guide/"


def test_the_documentation_section_says_how_to_build_and_open_the_site():
    docs = section(README, "## Documentation")
    commands = [c.strip() for c in blocks(docs, "bash")[0].splitlines() if c.strip()]
    assert commands == ['pip install -e ".[docs]"', "python -m sphinx -W -b html docs docs/_build/html"]
    assert "docs/_build/html/index.html" in docs


def test_the_readmes_links_lead_to_files_that_exist():
    links = re.findall(r"\]\(([^)#\s]+)\)", README)
    assert "docs/guide/index.md" in links and "docs/double-flower.png" in links
    for link in links:
        assert (ROOT / link).exists(), f"README links to {link}, which does not exist"


def test_the_cli_examples_are_three_valid_commands():
    from skatetrace.cli import build_parser

    cmds = _cli_examples()
    assert len(cmds) == 3, cmds
    for cmd in cmds:
        words = shlex.split(cmd)
        assert words[0] == "skatetrace", cmd
        build_parser().parse_args(words[1:])  # exits 2 on an unknown option or a missing argument
        for word in words:
            if word.startswith("examples/"):
                assert (ROOT / word).is_file(), f"{cmd}: {word} does not exist"


@pytest.mark.slow
def test_the_cli_examples_run_after_the_main_job(tmp_path):
    # In a scratch folder with the clone's examples/, the set-up's main job first: `animate out/` reads it.
    (tmp_path / "examples").symlink_to(ROOT / "examples")
    main_job = _setup_commands()[0].split("&&")[1].strip()
    for cmd in [main_job, *_cli_examples()]:
        words = shlex.split(cmd)
        proc = subprocess.run([sys.executable, "-m", "skatetrace", *words[1:]], cwd=tmp_path,
                              capture_output=True, text=True)
        assert proc.returncode == 0, f"{cmd}: exit {proc.returncode}\n{proc.stderr[-2000:]}"
    assert (tmp_path / "flower.gif").stat().st_size > 0
    assert (tmp_path / "eight" / "controls.csv").is_file() and (tmp_path / "three" / "report.json").is_file()


def test_the_main_job_does_not_import_the_test_extras(tmp_path):
    # The core must run without pytest, hypothesis, Playwright or imageio-ffmpeg installed: a
    # module set to None in sys.modules cannot be imported.
    code = ("import sys; sys.modules.update({m: None for m in ('pytest', 'hypothesis', 'playwright', "
            "'imageio_ffmpeg')}); from skatetrace.cli import main; "
            "sys.exit(main(['trace', 'line', '--out', sys.argv[1]]))")
    proc = subprocess.run([sys.executable, "-c", code, str(tmp_path / "o")], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert (tmp_path / "o" / "viewer.html").is_file() and (tmp_path / "o" / "figure.png").is_file()
