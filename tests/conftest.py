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
