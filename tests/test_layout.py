"""The package's layout: stages that import only downward, modules that each say their one job."""

import ast
import shutil
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "src" / "skatetrace"
CONTRACT = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["tool"]["importlinter"]
#: A module longer than this most likely holds two concepts: split it (the issue that set the layout
#: found 1.7k-line modules holding four).
MAX_LINES = 800


def _lint_imports(root: Path) -> subprocess.CompletedProcess:
    """import-linter's command on the package under ``root/src``, with ``root/pyproject.toml``'s contract."""
    code = "import sys; from importlinter.cli import lint_imports_command; sys.exit(lint_imports_command())"
    return subprocess.run([sys.executable, "-c", code, "--config", str(root / "pyproject.toml"), "--no-cache"],
                          cwd=root, capture_output=True, text=True, env={"PYTHONPATH": str(root / "src"),
                                                                         "PATH": "/usr/bin:/bin"})


def _modules() -> list[Path]:
    return sorted(p for p in PACKAGE.rglob("*.py") if "__pycache__" not in p.parts)


def test_the_stages_import_only_downward():
    proc = _lint_imports(ROOT)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert "1 kept, 0 broken" in proc.stdout


@pytest.mark.parametrize("lower, upper", [("dynamics/model.py", "..outputs import plotting"),
                                          ("figures/geometry.py", "..pipeline import trace_and_verify"),
                                          ("drawings/curves.py", "..tracing import sections")])
def test_an_upward_import_breaks_the_contract(tmp_path, lower, upper):
    shutil.copytree(PACKAGE, tmp_path / "src" / "skatetrace", ignore=shutil.ignore_patterns("__pycache__"))
    shutil.copy(ROOT / "pyproject.toml", tmp_path / "pyproject.toml")
    module = tmp_path / "src" / "skatetrace" / lower
    module.write_text(module.read_text(encoding="utf-8") + f"\nfrom {upper}  # noqa: E402\n", encoding="utf-8")
    proc = _lint_imports(tmp_path)
    assert proc.returncode == 1, proc.stdout + proc.stderr
    assert "BROKEN" in proc.stdout and "skatetrace." + lower[:-3].replace("/", ".") in proc.stdout


def test_the_contract_names_every_part_of_the_package():
    # A new subpackage or top-level module must take its place in the layers, or it escapes the check.
    (contract,) = CONTRACT["contracts"]
    assert contract["type"] == "layers" and contract["containers"] == ["skatetrace"]
    layered = {name.strip() for layer in contract["layers"] for name in layer.split("|")}
    parts = {p.stem for p in PACKAGE.glob("*.py") if p.stem not in ("__init__", "__main__")}
    parts |= {p.parent.name for p in PACKAGE.glob("*/__init__.py")}
    assert layered == parts


@pytest.mark.parametrize("path", _modules(), ids=lambda p: p.relative_to(PACKAGE).as_posix())
def test_every_module_opens_with_a_docstring_saying_its_job(path):
    doc = ast.get_docstring(ast.parse(path.read_text(encoding="utf-8")))
    assert doc, f"{path.relative_to(ROOT)} has no module docstring"
    first = doc.splitlines()[0]
    assert first.strip() and len(first) <= 120 and first.rstrip()[-1] in ".:?)`", first


@pytest.mark.parametrize("path", _modules(), ids=lambda p: p.relative_to(PACKAGE).as_posix())
def test_no_module_is_too_big_to_hold_one_concept(path):
    lines = len(path.read_text(encoding="utf-8").splitlines())
    assert lines <= MAX_LINES, f"{path.relative_to(ROOT)} has {lines} lines (at most {MAX_LINES}): split it"
