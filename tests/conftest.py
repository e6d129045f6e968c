"""Suite-wide settings: what the quick subset (``python -m pytest -m "not slow"``) leaves out."""

import pytest


def pytest_collection_modifyitems(items):
    # Every test that drives the real browser (the viewer's Playwright tests) is slow: Chromium
    # starts, loads the page and plays it.
    for item in items:
        if "browser" in getattr(item, "fixturenames", ()):
            item.add_marker(pytest.mark.slow)
