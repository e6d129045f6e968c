"""The package's public names, imported on first use."""

import importlib
import subprocess
import sys

import pytest

import skatetrace


@pytest.mark.parametrize("name", skatetrace.__all__)
def test_every_public_name_is_its_modules_object(name):
    value = getattr(skatetrace, name)
    module = importlib.import_module(value.__module__) if hasattr(value, "__module__") else None
    if module is not None and hasattr(module, name):
        assert getattr(module, name) is value
    assert name in dir(skatetrace)


def test_unknown_names_raise_attribute_error():
    with pytest.raises(AttributeError, match="no attribute 'nope'"):
        skatetrace.nope  # noqa: B018


def test_functions_named_like_their_modules_stay_functions():
    importlib.import_module("skatetrace.verification.verify")
    importlib.import_module("skatetrace.dynamics.simulate")
    from skatetrace import simulate, verify

    assert callable(verify) and callable(simulate)
    assert skatetrace.verify is verify and skatetrace.simulate is simulate


def test_import_does_not_load_the_drawing_readers_solve_ivp_or_plotting():
    code = ("import sys, skatetrace.cli; "
            "print(' '.join(m for m in ('svgelements', 'defusedxml', 'scipy.interpolate', 'scipy.integrate', 'matplotlib') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.strip()
    assert out == ""


def test_version_is_the_distributions():
    from importlib.metadata import PackageNotFoundError, version

    try:
        installed = version("skatetrace")
    except PackageNotFoundError:
        pytest.skip("not installed (a source checkout on sys.path)")
    assert skatetrace.__version__ == installed


def test_python_m_skatetrace_runs_the_command_line():
    proc = subprocess.run([sys.executable, "-m", "skatetrace", "--version"], capture_output=True, text=True)
    assert proc.returncode == 0 and proc.stdout == f"skatetrace {skatetrace.__version__}\n"
    proc = subprocess.run([sys.executable, "-m", "skatetrace", "animate", ".", "-o", "x.avi"], capture_output=True,
                          text=True)
    assert proc.returncode == 2 and proc.stderr.startswith("skatetrace: error: -o: ")
