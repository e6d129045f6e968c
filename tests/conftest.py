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
def forking(monkeypatch):
    """Forking allowed (:func:`skatetrace.processes.can_fork`) whatever else runs in the test process."""
    from skatetrace import processes

    monkeypatch.setattr(processes, "can_fork", lambda: True)


@pytest.fixture
def small_program():
    """A function that solves a program of two unknowns with IPOPT (its optimum ``(1, -2)``) and returns its solution.

    For the tests of what surrounds every solve (:mod:`skatetrace.planning.blas`, :mod:`skatetrace.planning.heap`).
    """
    import numpy as np

    from skatetrace.planning.nlp import SparseProgram

    def solve() -> np.ndarray:
        prog = SparseProgram(2)
        prog.minimize((prog.x[0] - 1.0) ** 2 + (prog.x[1] + 2.0) ** 2)
        prog.constrain(prog.x[0] + prog.x[1], -5.0, 5.0)
        res = prog.solve({"print_time": False, "ipopt.print_level": 0, "ipopt.sb": "yes"})
        assert res.success
        return res.x

    return solve


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


@pytest.fixture
def mocked_plans(monkeypatch):
    """Plans and their verdicts mocked in :mod:`skatetrace.pipeline`: call it with ``plan_verifies``
    (and ``unbounded_verifies``, default True). A "plan" is then the launch-glide-stop trace with
    ``options.reach`` kept, so that the mocked verification tells the two apart and fails the one
    it is told to; the call returns the options of every trace made from then on."""
    import dataclasses

    import skatetrace.pipeline as pipeline
    from skatetrace import processes
    from skatetrace.tracing.sections import trace_figure
    from skatetrace.verification.verify import verify as real_verify

    def mock(*, plan_verifies: bool, unbounded_verifies: bool = True) -> list:
        made = []

        def plan(figure, params, options, progress=None):
            made.append(options)
            return dataclasses.replace(trace_figure(figure, params, dataclasses.replace(options, reach=None)),
                                       options=options)

        def verify(trace, schedule, rel_tol):
            report = real_verify(trace, schedule, rel_tol=rel_tol)
            if (plan_verifies if trace.options.reach is not None else unbounded_verifies):
                return report
            return dataclasses.replace(report, success=False, status="failed",
                                       message="deviation 8e-06 exceeds 6e-06")

        def trace(figure, params, options, progress=None, cache=None):
            made.append(options)
            return trace_figure(figure, params, options, progress=progress, cache=cache)

        monkeypatch.setattr(pipeline, "plan_figure", plan)
        # the launch-glide-stop trace made here, where ``made`` sees it (not beside the plan, in a child)
        monkeypatch.setattr(pipeline, "Background", lambda fn, workers=None, idle=False: processes.Background(fn, 1))
        monkeypatch.setattr(pipeline, "verify", verify)
        monkeypatch.setattr(pipeline, "trace_figure", trace)
        return made

    return mock
