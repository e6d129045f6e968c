"""Suite-wide settings: what the quick subset (``python -m pytest -m "not slow"``) leaves out, and
hypothesis's profile.

On CI (``CI=true``) hypothesis draws its examples from a fixed seed (``derandomize``), so that a
submission's CI never turns red on a new random draw; fuzzing with fresh draws happens on every
developer's run (``--hypothesis-seed`` repeats one), where what it finds becomes a regression test.
"""

import os

import pytest
from hypothesis import settings

settings.register_profile("ci", derandomize=True, print_blob=True)
if os.environ.get("CI"):
    settings.load_profile("ci")


def pytest_collection_modifyitems(items):
    # Every test that drives the real browser (the viewer's Playwright tests) is slow: Chromium
    # starts, loads the page and plays it.
    for item in items:
        if "browser" in getattr(item, "fixturenames", ()):
            item.add_marker(pytest.mark.slow)


@pytest.fixture
def pools_made(monkeypatch):
    """The worker counts of the process pools :mod:`skatetrace.processes` starts, forking allowed
    whatever else runs in the test process: a test of side-by-side work asserts the pool was used."""
    from skatetrace import processes

    made = []
    real = processes.ProcessPoolExecutor

    def spy(*args, **kwargs):
        made.append(kwargs["max_workers"])
        return real(*args, **kwargs)

    monkeypatch.setattr(processes, "ProcessPoolExecutor", spy)
    monkeypatch.setattr(processes, "can_fork", lambda: True)
    return made
