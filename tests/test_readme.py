"""The README is part of the product: its Python blocks run as written, its set-up is what CI runs."""

from __future__ import annotations

import contextlib
import io
import re
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text(encoding="utf-8")


def _blocks(lang: str) -> list[str]:
    return re.findall(rf"^```{lang}\n(.*?)^```", README, flags=re.MULTILINE | re.DOTALL)


def _setup_commands() -> list[str]:
    """The commands of the first bash block after the "Set-up" heading, comments stripped."""
    section = README[README.index("## Set-up"):]
    block = re.search(r"^```bash\n(.*?)^```", section, flags=re.MULTILINE | re.DOTALL).group(1)
    return [line.split("#")[0].strip() for line in block.splitlines() if line.strip()]


def test_the_readme_has_python_blocks():
    assert len(_blocks("python")) >= 2


@pytest.mark.slow
@pytest.mark.parametrize("index", range(len(_blocks("python"))))
def test_python_block_runs_as_written(index, monkeypatch):
    # From the root of a clone, as a user would paste it: relative paths such as examples/ resolve.
    code = _blocks("python")[index]
    monkeypatch.chdir(ROOT)
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        exec(compile(code, f"README.md python block {index}", "exec"), {"__name__": "__readme__"})
    assert out.getvalue().strip(), "every README example prints what it shows"


def test_python_blocks_print_what_their_comments_say():
    # Comments quote numbers only as rough magnitudes or bounds, never one machine's digits.
    for block in _blocks("python"):
        for comment in re.findall(r"#(.*)$", block, flags=re.MULTILINE):
            assert not re.search(r"\d\.\d{2,}e-\d", comment), f"a machine's digits in a README comment: {comment}"


def test_setup_is_two_commands_and_ci_runs_the_test_command():
    cmds = _setup_commands()
    assert len(cmds) == 2, cmds
    main_job, tests = cmds
    assert "skatetrace trace double-flower" in main_job
    assert "[test]" not in main_job, "the main job must not need the test extras"
    assert "python -m pytest -q" in tests
    ci = (ROOT / ".ci" / "run").read_text(encoding="utf-8")
    assert 'pip install -q -e ".[test]"' in ci and re.search(r"^python -m pytest -q\b", ci, flags=re.MULTILINE)


def test_the_quick_subset_named_in_the_readme_exists():
    assert 'python -m pytest -q -m "not slow"' in README
    config = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
    assert any(m.startswith("slow:") for m in config["tool"]["pytest"]["ini_options"]["markers"])


def test_every_dependency_is_justified_in_the_readme():
    config = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
    deps = config["project"]["dependencies"] + [d for extra in config["project"]["optional-dependencies"].values()
                                                for d in extra]
    section = README[README.index("## Dependencies"):]
    section = section[:section.index("\n## ", 4)] if "\n## " in section[4:] else section
    for dep in deps:
        name = re.split(r"[<>=!~\[ ;]", dep, maxsplit=1)[0]
        assert re.search(rf"^- {re.escape(name)}\b", section, flags=re.MULTILINE | re.IGNORECASE), name
        assert re.search(r">=\s*\d", dep), f"{dep}: pin a lower bound"


def test_the_main_job_does_not_import_the_test_extras(tmp_path):
    # The core must run without pytest, hypothesis, Playwright or imageio-ffmpeg installed: a
    # module set to None in sys.modules cannot be imported.
    code = ("import sys; sys.modules.update({m: None for m in ('pytest', 'hypothesis', 'playwright', "
            "'imageio_ffmpeg')}); from skatetrace.cli import main; "
            "sys.exit(main(['trace', 'line', '--out', sys.argv[1]]))")
    proc = subprocess.run([sys.executable, "-c", code, str(tmp_path / "o")], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert (tmp_path / "o" / "viewer.html").is_file() and (tmp_path / "o" / "figure.png").is_file()


def test_the_examples_table_is_the_scripts_output():
    # The README's measured figures come from bench/measure_examples.py, never by hand.
    import importlib.util
    import json

    spec = importlib.util.spec_from_file_location("measure_examples", ROOT / "bench" / "measure_examples.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    data = json.loads((ROOT / "bench" / "examples.json").read_text(encoding="utf-8"))
    block = README[README.index(module.BEGIN) + len(module.BEGIN):README.index(module.END)]
    assert block.strip() == module.render(data).strip()
    assert {r["name"] for r in data["rows"]} == set(module.EXAMPLES)


def test_bounds_round_up_to_one_digit():
    import importlib.util

    spec = importlib.util.spec_from_file_location("measure_examples", ROOT / "bench" / "measure_examples.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    assert [module._bound(x) for x in (3.39e-9, 1e-9, 9.01e-10, 0.0253, 2.0, None)] == \
        ["4e-9", "1e-9", "1e-9", "0.03", "2", "–"]
