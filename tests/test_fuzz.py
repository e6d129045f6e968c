"""Bad input never crashes (issue 13, section 6).

Every public entry point is treated as untrusted: figure JSON, SVG path data and documents, point
lists, command-line values and the option objects. Random input must give either a valid result or
skatetrace's own error (a ``SkatetraceError``, or a ``ValueError`` from an option object) with a
message; never another exception, a hang, or NaN in a file. The fuzz tests are bounded
(``max_examples``, ``deadline``) so the whole file runs in well under a minute; each crash they
found is kept as a plain regression case in the error tables below.
"""

from __future__ import annotations

import copy
import json
import math

import numpy as np
import pytest

import skatetrace as st
from skatetrace.cli import main
from skatetrace.errors import DrawingError, FigureFormatError, SkatetraceError


def _strict_json(path):
    """Parse ``path`` refusing NaN and infinities (Python's json accepts them by default)."""
    def bad(token):
        raise AssertionError(f"{path.name} holds {token}")

    return json.loads(path.read_text(), parse_constant=bad)


# --- a figure in which no section can be traced ---------------------------------------------------

def test_no_section_traced_is_reported_as_data():
    """Every section failing used to crash verify ("need at least one array to concatenate")."""
    fig = st.figure_from_dict({"name": "two lines", "curves": [{"pieces": [
        {"type": "line", "length": 1.0}, {"type": "line", "length": 2.0}], "joins": [{"type": "cusp"}]}]})
    # No mass may leave the contact point: every section is refused, whatever the arithmetic.
    options = st.TraceOptions(excursion_limit=1e-12)
    done = st.trace_and_verify(fig, options=options, rests="never")
    assert not done.success and done.status == "failed"
    assert not any(s.success for s in done.trace.sections) and len(done.trace.sections) == 2
    assert done.schedule.t.size == 0
    assert not done.report.success and done.report.message
    assert [s["traced"] for s in done.report.sections] == [False, False]
    assert math.isfinite(done.report.max_deviation)
    # rests="auto" has nothing to split (single-piece sections) and must return the same verdict
    auto = st.trace_and_verify(fig, options=options)
    assert not auto.success and not auto.rests


def test_no_section_traced_cli_exits_1_and_writes_every_file(tmp_path, capsys):
    """The issue's own case: a single 1.3 mm line traced at --size 1.3mm."""
    pts = tmp_path / "line.csv"
    pts.write_text("0,0\n1.3,0\n")
    out = tmp_path / "out"
    assert main(["trace", str(pts), "--size", "1.3mm", "--out", str(out), "--no-plots"]) == 1
    captured = capsys.readouterr()
    assert "Traceback" not in captured.err and "FAILED" in captured.out
    result, report = _strict_json(out / "result.json"), _strict_json(out / "report.json")
    assert not result["success"] and result["message"]
    assert not report["success"] and report["sections"][0]["traced"] is False
    lines = (out / "controls.csv").read_text().splitlines()
    assert lines[0].startswith("piece,t,a,b") and len(lines) == 1  # the header alone: nothing was traced
    assert (out / "fit.json").exists()
    assert not (out / "viewer.html").exists() and "nothing to play" in captured.out
