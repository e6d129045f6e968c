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
import re
from datetime import timedelta

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as hs

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


def test_no_section_traced_cli_exits_1_and_writes_every_file(tmp_path, capsys, monkeypatch):
    """The issue's own case, a single 1.3 mm line traced at --size 1.3mm, crashed: it is traced and
    verified now (its stop is bracketed below the ramps of the grid, 4fd1761). A line whose stop no
    ramp brackets is reported as data: exit 1, every file written."""
    from skatetrace.tracing import maneuver

    pts = tmp_path / "line.csv"
    pts.write_text("0,0\n1.3,0\n")
    assert main(["trace", str(pts), "--size", "1.3mm", "--reach", "none", "--out", str(tmp_path / "o"),
                 "--no-plots"]) == 0
    capsys.readouterr()
    monkeypatch.setattr(maneuver, "_brackets", lambda *args: iter(()))
    out = tmp_path / "out"
    # the launch-glide-stop tracer: the planner (the default in metres) does trace it, at 2e4 m/s^2
    assert main(["trace", str(pts), "--size", "1.3mm", "--reach", "none", "--out", str(out), "--no-plots"]) == 1
    captured = capsys.readouterr()
    assert "Traceback" not in captured.err and "FAILED" in captured.out
    result, report = _strict_json(out / "result.json"), _strict_json(out / "report.json")
    assert not result["success"] and result["message"]
    assert not report["success"] and report["sections"][0]["traced"] is False
    lines = (out / "controls.csv").read_text().splitlines()
    assert lines[0].startswith("piece,t,a,b") and len(lines) == 1  # the header alone: nothing was traced
    assert (out / "fit.json").exists()
    assert not (out / "viewer.html").exists() and "nothing to play" in captured.out
    assert "nothing was replayed" in captured.out and "max deviation" not in captured.out


# --- a memory cap: input that makes memory grow without bound fails the test, not the machine -------------

#: Address space each fuzz test may add to the process (issue 19 measured 18.9 GB within 20 s for one input).
MEMORY_CAP = 3 << 30


def _address_space() -> int | None:
    """This process's virtual size in bytes (Linux), or None where it cannot be read."""
    try:
        with open("/proc/self/status", encoding="ascii") as f:
            kb = next(int(line.split()[1]) for line in f if line.startswith("VmSize:"))
    except (OSError, StopIteration, ValueError):
        return None
    return kb * 1024


@pytest.fixture(autouse=True)
def memory_cap():
    """Limit the address space to what the process has now plus :data:`MEMORY_CAP` while each test
    runs (its forked workers inherit the limit): an allocation past it raises MemoryError, which
    the tests report as a crash. Skipped where the limit cannot be set (not Linux)."""
    resource = pytest.importorskip("resource")
    now = _address_space()
    soft, hard = resource.getrlimit(resource.RLIMIT_AS)
    if now is None:
        yield None
        return
    cap = now + MEMORY_CAP if hard == resource.RLIM_INFINITY else min(now + MEMORY_CAP, hard)
    resource.setrlimit(resource.RLIMIT_AS, (cap, hard))
    try:
        yield cap
    finally:
        resource.setrlimit(resource.RLIMIT_AS, (soft, hard))


def test_the_memory_cap_holds(memory_cap):
    if memory_cap is None:
        pytest.skip("no /proc/self/status: the address space cannot be measured")
    with pytest.raises(MemoryError):
        np.ones(MEMORY_CAP // 8 + (1 << 27))  # a little more than the cap allows


# --- shared strategies ------------------------------------------------------------------------------

FUZZ = settings(max_examples=150, deadline=timedelta(seconds=5), suppress_health_check=[HealthCheck.too_slow])
#: The command line runs whole traces: fewer examples.
FUZZ_CLI = settings(max_examples=30, deadline=timedelta(seconds=20),
                    suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])

EXTREMES = [0, -1, -0.0, 1e-300, 1e300, -1e300, 1e6, 1e308, 10**400, -10**400, 5e-324, math.nan, math.inf,
            -math.inf, True, False, "abc", "1", "", None, 2**63, 1e15, 1e-15, 1e9, 1e-9]
_leaf = hs.one_of(hs.sampled_from(EXTREMES), hs.floats(), hs.integers(), hs.text(max_size=5), hs.none())
#: Nested garbage: fresh lists and dicts each draw (never mutate a shared object).
GARBAGE = hs.recursive(_leaf, lambda inner: hs.one_of(
    hs.lists(inner, max_size=3),
    hs.dictionaries(hs.sampled_from(["type", "length", "radius", "x", "pieces"]), inner, max_size=3)), max_leaves=6)

FIGURES = [
    {"schema": "skatetrace.figure/1", "name": "flower", "params": {"M": 2, "m": 1, "I": 3},
     "curves": [{"name": "petals", "centre": [0, 0], "repeat": 8,
                 "pieces": [{"type": "arc", "radius": 1.2, "sweep_deg": 198}, {"type": "line", "length": 0.5}],
                 "joins": [{"type": "smooth"}], "closing_join": {"type": "cusp", "pivot_deg": -153}}]},
    {"curves": [{"start": {"x": 1, "y": 2, "heading_deg": 30},
                 "pieces": [{"type": "arc", "radius": 1.0, "length": 2.0, "turn": "right"},
                            {"type": "arc", "curvature": -0.5, "length": 1.0},
                            {"type": "spiral", "curvature": [0.1, 0.2, 0.0, 0.01], "length": 2.0}],
                 "joins": [{"type": "cusp", "reverse": True}, {"type": "smooth"}]}]},
]
KEYS = ["type", "length", "radius", "sweep_deg", "curvature", "turn", "repeat", "joins", "pieces", "closing_join",
        "centre", "start", "pivot_deg", "reverse", "heading_deg", "x", "y", "params", "M", "schema", "name"]


def _paths(obj, prefix=()):
    """Every place in a JSON value, as a tuple of keys and indices."""
    yield prefix
    if isinstance(obj, dict):
        for k, v in obj.items():
            yield from _paths(v, prefix + (k,))
    elif isinstance(obj, list):
        for i, v in enumerate(obj):
            yield from _paths(v, prefix + (i,))


@hs.composite
def mutated_figures(draw):
    """A valid figure dict with one to four random edits: a value replaced, a key dropped, garbage added."""
    data = copy.deepcopy(draw(hs.sampled_from(FIGURES)))
    for _ in range(draw(hs.integers(1, 4))):
        where = draw(hs.sampled_from(list(_paths(data))))
        op = draw(hs.sampled_from(["set", "delete", "add"]))
        if not where:
            if op == "set":
                data = draw(GARBAGE)
            continue
        parent = data
        for k in where[:-1]:
            parent = parent[k]
        key = where[-1]
        if op == "set":
            parent[key] = draw(hs.one_of(GARBAGE, hs.sampled_from(EXTREMES)))
        elif op == "delete":
            del parent[key]
        elif isinstance(parent[key], dict):
            parent[key][draw(hs.sampled_from(KEYS))] = draw(GARBAGE)
        elif isinstance(parent[key], list):
            parent[key].append(draw(GARBAGE))
    return data


def _check_figure(fig):
    """A figure that was accepted lays out finitely and writes strict JSON that reads back the same."""
    assert isinstance(fig, st.Figure)
    size = fig.size()
    assert math.isfinite(size) and size > 0
    text = json.dumps(fig.to_dict(), allow_nan=False)
    again = st.figure_from_dict(json.loads(text))
    assert [c.pieces for c in again.curves] == [c.pieces for c in fig.curves]
    for c in fig.curves:
        assert c.sections()
        gap = c.closure()["position_gap"]
        assert math.isfinite(gap)


# --- figure JSON ----------------------------------------------------------------------------------

@FUZZ
@given(mutated_figures())
def test_fuzz_figure_dict(data):
    try:
        fig = st.figure_from_dict(data)
    except FigureFormatError as exc:
        assert str(exc) and len(str(exc)) < 2000
        return
    _check_figure(fig)


@FUZZ
@given(hs.one_of(hs.binary(max_size=200), hs.text(max_size=200).map(str.encode),
                 mutated_figures().map(lambda d: json.dumps(d).encode())))
def test_fuzz_figure_file(tmp_path_factory, content):
    path = tmp_path_factory.mktemp("fig") / "fig.json"
    path.write_bytes(content)
    try:
        fig = st.load_figure(path)
    except FigureFormatError as exc:
        assert str(exc)
        return
    _check_figure(fig)


def _line(length):
    return {"type": "line", "length": length}


def _arc(radius, sweep):
    return {"type": "arc", "radius": radius, "sweep_deg": sweep}


def _one(*pieces, **curve):
    joins = [{"type": "cusp"}] * (len(pieces) - 1)
    return {"curves": [{"pieces": list(pieces), "joins": joins, **curve}]}


# Each row a crash (or a hang) found by the fuzz tests or by hand, with the error it gives now.
@pytest.mark.parametrize("data, match", [
    (_one(_arc(1, 90), repeat=10**9), r"1000000000 pieces.*at most 10000"),  # hung in layout
    (_one(*[_line(1)] * 100_000), r"100000 pieces.*at most 10000"),  # seconds before any error
    (_one(_arc(1e-300, 1e6)), r"length must lie between 1e-09 and 1e\+09"),
    (_one(_arc(1e300, 90)), r"length must lie between"),
    (_one(_line(1e308), _line(1e308)), r"length must lie between"),  # size was inf
    ({"curves": [{"start": {"x": -1e308}, "pieces": [_line(1)]}]}, r"within 1e\+09 of the origin"),
    (_one({"type": "arc", "curvature": 1e9, "length": 1e9}), r"radius must be at least|turn by at most"),
    (_one({"type": "arc", "curvature": 1e308, "length": 1e308}), r"length must lie"),  # math domain error
    (_one({"type": "spiral", "curvature": [1e6], "length": 1e6}), r"spiral may turn by at most"),  # MemoryError
    (_one({"type": "spiral", "curvature": [0, 0, 0, 1e300], "length": 1e3}), r"spiral may turn"),  # OverflowError
    ({"curves": [{"centre": [1e308, -1e308], "repeat": 2, "pieces": [_arc(1, 90)]}]}, r"within 1e\+09"),  # NaN layout
    ({"params": {"M": 2, "m": 1, "I": 1e300}, "curves": [{"pieces": [_arc(1, 90)]}]}, r"I must lie between"),
    ({"params": {"M": 10**400}, "curves": [{"pieces": [_arc(1, 90)]}]}, r"must lie between"),  # OverflowError
    (_one({"type": "line", "length": [1] * 10_000}), r"must be a finite number, got \[1, 1, 1, 1, 1, 1, \.\.\.\]"),
])
def test_figure_errors(data, match):
    with pytest.raises(FigureFormatError, match=match):
        st.figure_from_dict(data)


@pytest.mark.parametrize("content, match", [
    (b"\xff\xfe{}", r"not a text file in UTF-8"),  # UnicodeDecodeError
    (b"[" * 100_000 + b"]" * 100_000, r"nested too deeply"),  # RecursionError
])
def test_figure_file_errors(tmp_path, content, match):
    path = tmp_path / "fig.json"
    path.write_bytes(content)
    with pytest.raises(FigureFormatError, match=match):
        st.load_figure(path)


def test_figure_file_name_with_nul():
    with pytest.raises(FigureFormatError, match=r"no file name"):
        st.load_figure("fig\x00.json")  # ValueError: embedded null byte


@pytest.mark.parametrize("build, exc, match", [
    (lambda: st.Curve((st.Segment(0.0, 1.0),), repeat=True), FigureFormatError, r"repeat must be a whole number"),
    (lambda: st.Curve((st.Segment(0.0, 1.0),), start=st.Pose(math.nan, 0, 0)), FigureFormatError, r"finite"),
    (lambda: st.Curve((st.Segment(0.0, 1.0), st.Segment(0.0, 1.0)), ("smooth",)), FigureFormatError,
     r"joins must be a tuple of Join"),
    (lambda: st.Join("cusp", "90"), FigureFormatError, r"pivot must be finite"),
    (lambda: st.Figure("f", ("curve",)), FigureFormatError, r"curves must be Curve objects"),
])
def test_figure_constructor_errors(build, exc, match):
    with pytest.raises(exc, match=match):
        build()


# --- drawings: SVG path data, SVG documents, point lists, lengths -----------------------------------

NUMBER = hs.one_of(hs.floats(allow_nan=True, allow_infinity=True).map(repr), hs.integers(-10**6, 10**6).map(str),
                   hs.sampled_from(["nan", "inf", "-inf", "1e308", "1e-320", "1e999", "-0", "0", ".", "-", "1e",
                                    "0x10", ""]))


@hs.composite
def path_data(draw):
    parts = []
    for _ in range(draw(hs.integers(0, 8))):
        parts.append(draw(hs.sampled_from(list("MmLlHhVvCcSsQqTtAaZz"))))
        parts += draw(hs.lists(NUMBER, max_size=8))
    return draw(hs.sampled_from([" ", ",", ""])).join(parts)


TRANSFORM = hs.one_of(hs.just(""), hs.builds(
    lambda f, args: f"{f}({' '.join(args)})",
    hs.sampled_from(["matrix", "translate", "scale", "rotate", "skewX", "skewY", "bogus"]),
    hs.lists(NUMBER, max_size=7)))


@hs.composite
def svg_documents(draw):
    elements = []
    for _ in range(draw(hs.integers(0, 4))):
        kind = draw(hs.sampled_from(["path", "rect", "circle", "ellipse", "line", "polyline", "polygon", "g"]))
        transform = draw(TRANSFORM)
        attrs = f' transform="{transform}"' if transform else ""
        n = lambda: draw(NUMBER)  # noqa: E731
        if kind in ("path", "g"):
            attrs += f' d="{draw(path_data())}"'
        elif kind == "rect":
            attrs += f' x="{n()}" y="{n()}" width="{n()}" height="{n()}" rx="{n()}"'
        elif kind in ("circle", "ellipse"):
            attrs += f' cx="{n()}" cy="{n()}" r="{n()}" rx="{n()}" ry="{n()}"'
        elif kind == "line":
            attrs += f' x1="{n()}" y1="{n()}" x2="{n()}" y2="{n()}"'
        else:
            attrs += f' points="{" ".join(draw(hs.lists(NUMBER, max_size=8)))}"'
        elements.append(f'<g{transform and f" transform={chr(34)}{transform}{chr(34)}"}><path{attrs}/></g>'
                        if kind == "g" else f"<{kind}{attrs}/>")
    view = draw(hs.sampled_from(["", ' viewBox="0 0 10 10"', ' width="10mm" height="abc"', ' viewBox="nan 0 0 0"']))
    return f'<svg xmlns="http://www.w3.org/2000/svg"{view}>' + "".join(elements) + "</svg>"


@hs.composite
def point_lists(draw):
    lines = []
    for _ in range(draw(hs.integers(0, 12))):
        if draw(hs.integers(0, 6)) == 0:
            lines.append("")  # a blank line starts a new path
        else:
            sep = draw(hs.sampled_from([",", " ", "\t", ";", ", "]))
            lines.append(sep.join(draw(hs.lists(NUMBER, min_size=1, max_size=5))))
    if draw(hs.booleans()):
        lines.insert(0, "x,y")
    if draw(hs.booleans()) and lines:  # duplicates: a repeated point marks a corner
        lines.append(lines[-1])
    return "\n".join(lines) + draw(hs.sampled_from(["", "\n", "\r\n"]))


def _check_drawing(read, source):
    try:
        drawing = read(source)
    except DrawingError as exc:
        assert str(exc)
        return
    assert isinstance(drawing, st.Drawing) and drawing.paths
    size = drawing.size()
    assert math.isfinite(size) and size > 0


@FUZZ
@given(path_data())
def test_fuzz_path_data(d):
    from skatetrace.drawings.svg import parse_path_string

    _check_drawing(parse_path_string, d)
    _check_drawing(st.read_svg, f'<svg xmlns="http://www.w3.org/2000/svg"><path d="{d}"/></svg>')


@FUZZ
@given(svg_documents())
def test_fuzz_svg_documents(doc):
    _check_drawing(st.read_svg, doc)


@FUZZ
@given(hs.one_of(point_lists(), hs.text(max_size=100)))
def test_fuzz_point_lists(text):
    _check_drawing(st.read_points, text)


@FUZZ
@given(hs.one_of(hs.text(max_size=12), hs.builds(lambda a, b: a + b, NUMBER,
                                                 hs.sampled_from(["m", "cm", "mm", "ft", "in", "", "km", " m"]))))
def test_fuzz_lengths(text):
    try:
        value, unit = st.parse_length(text)
    except DrawingError as exc:
        assert str(exc)
        return
    assert math.isfinite(value) and value > 0 and unit in ("m", "model")


@pytest.mark.parametrize("read, source, match", [
    ("path", "Z", r"does not begin with a moveto"),  # AttributeError inside svgpathtools
    ("path", "L 1 1", r"does not begin with a moveto"),
    ("svg", '<svg xmlns="http://www.w3.org/2000/svg"><path d="z m 0 0 l 1 1"/></svg>', r"moveto"),
    ("length", "5e-324 mm", r"which is 0 in metres"),  # returned 0.0 m
    ("points", "\x00", r"no file name"),  # ValueError: embedded null byte
    ("svg", "a\x00b", r"no file name"),
])
def test_drawing_errors(read, source, match):
    from skatetrace.drawings.svg import parse_path_string

    fn = {"path": parse_path_string, "svg": st.read_svg, "length": st.parse_length, "points": st.read_points}[read]
    with pytest.raises(DrawingError, match=match):
        fn(source)


def test_fitting_a_degenerate_bezier_and_duplicates_is_clean():
    """A cubic whose control points coincide with its ends, and a point list with repeated points."""
    for drawing in (st.read_svg('<svg xmlns="http://www.w3.org/2000/svg"><path d="M 0 0 C 0 0 10 0 10 0"/></svg>'),
                    st.read_points("0,0\n0,0\n1,0\n1,0\n1,1\n")):
        res = st.resolve(drawing, size=6)
        assert res.fit.success and math.isfinite(res.fit.hausdorff)


@pytest.mark.parametrize("kwargs, match", [
    ({"size": "1e9"}, r"between 1e-06 and 1e\+06"),
    ({"size": 6, "tol": 1e-12}, r"below 1e-08 of the figure's size"),  # ran for minutes
])
def test_resolve_errors(kwargs, match):
    drawing = st.read_points("0,0\n1,0\n1,1\n")
    with pytest.raises(SkatetraceError, match=match):
        st.resolve(drawing, **kwargs)


# --- option objects -------------------------------------------------------------------------------

@pytest.mark.parametrize("build, exc, match", [
    (lambda: st.SleighParams(M=math.nan), ValueError, r"`M` \(sleigh mass\) must be a positive finite number"),
    (lambda: st.SleighParams(m=-1), ValueError, r"`m` .* must be a positive"),
    (lambda: st.SleighParams(I="3"), TypeError, r"`I` .* must be a number"),
    (lambda: st.TraceOptions(speed="abc"), ValueError, r"speed must be a number"),  # was math's TypeError
    (lambda: st.TraceOptions(speed=1e300), ValueError, r"speed must lie between"),  # ZeroDivisionError in replay
    (lambda: st.TraceOptions(speed=0), ValueError, r"speed must lie between"),
    (lambda: st.TraceOptions(rtol=math.nan), ValueError, r"rtol must be finite"),
    (lambda: st.TraceOptions(glide_lateral=math.inf), ValueError, r"glide_lateral must be finite"),
    (lambda: st.skater_params(height=math.nan), ValueError, r"height must be a positive number"),
    (lambda: st.skater_params(body_mass="60"), ValueError, r"body_mass must be a positive number"),
    (lambda: st.school_figure("three", height=0), ValueError, r"height must be a positive length"),
    (lambda: st.school_figure("three", height=1e300), ValueError, r"height must lie between"),
    (lambda: st.school_figure("three", edge=None), ValueError, r"unknown edge None"),
    (lambda: st.school_figure([]), ValueError, r"unknown school figure \[\]"),  # TypeError: unhashable
    (lambda: st.pattern([]), ValueError, r"unknown figure \[\]"),  # TypeError: unhashable
])
def test_option_errors(build, exc, match):
    with pytest.raises(exc, match=match):
        build()


@FUZZ
@given(hs.sampled_from(["speed", "residual_tol", "singular_limit", "excursion_limit", "rtol", "atol",
                        "maneuver_length", "glide_lateral"]), hs.one_of(hs.sampled_from(EXTREMES), hs.floats()))
def test_fuzz_trace_options(name, value):
    try:
        st.TraceOptions(**{name: value})
    except ValueError as exc:
        assert name in str(exc)


@FUZZ
@given(hs.sampled_from(["height", "blade", "edge", "direction", "foot", "turn_radius"]),
       hs.one_of(hs.sampled_from(EXTREMES), hs.floats(), hs.text(max_size=8)))
def test_fuzz_school_figure(name, value):
    try:
        fig = st.school_figure("three", **{name: value})
    except ValueError as exc:
        assert str(exc)
        return
    assert math.isfinite(fig.size())


# --- command-line values --------------------------------------------------------------------------

BAD_NUMBERS = ["-1", "0", "nan", "inf", "-inf", "abc", "", "1e400", "1e300", "1e-300"]
NUMERIC_OPTIONS = ["--speed", "--M", "--m", "--I", "--verify-tol", "--height", "--body-mass", "--blade"]


@pytest.fixture
def no_heavy_work(monkeypatch):
    """Fail the test if a trace or a fit starts: bad values must be refused before."""
    import skatetrace.pipeline
    import skatetrace.drawings.sources

    def refuse(*args, **kwargs):
        raise AssertionError("heavy work started for a bad value")

    monkeypatch.setattr(skatetrace.pipeline, "trace_and_verify", refuse)
    monkeypatch.setattr(skatetrace.drawings.sources, "resolve", refuse)


@pytest.mark.parametrize("option", NUMERIC_OPTIONS)
@pytest.mark.parametrize("value", ["-1", "0", "nan", "inf", "abc", "1e300"])
def test_cli_bad_numbers_exit_2_before_work(option, value, tmp_path, capsys, no_heavy_work):
    out = tmp_path / "out"
    assert main(["trace", "circle", "--out", str(out), option, value]) == 2
    err = capsys.readouterr().err
    assert err.startswith("skatetrace: error:") and option.lstrip("-").replace("-", "") in err.replace("-", "")
    assert not out.exists()


@pytest.mark.parametrize("args, match", [
    (["trace", "circle", "--speed", "1e300"], r"--speed must be a positive number between"),  # ZeroDivisionError in the replay
    (["trace", "circle", "--speed", "1e-300"], r"--speed must be a positive number between"),  # "Maximum allowed size exceeded"
    (["trace", "circle", "--I", "1e300"], r"--I must be a positive number between"),  # ZeroDivisionError in the tracer
    (["trace", "circle", "--verify-tol", "nan"], r"--verify-tol must be a positive finite"),  # NaN passed verify
    (["trace", "circle", "--rests", "bogus"], r"argument --rests: invalid choice"),  # was argparse's usage text
    (["trace", "circle", "--workers", "0"], r"--workers must be a whole number from 1 to 1024"),
    (["trace", "circle", "--size", "-3m"], r"--size: a length must be positive"),  # was "expected one argument"
    (["trace", "circle", "--speed", "-1"], r"--speed must be a positive number"),
    (["trace", "circle", "--workers", "2.5"], r"argument --workers: invalid int value"),
    (["trace", "circle", "--size", "abc"], r"--size: cannot read the length 'abc'"),  # was ignored
    (["fit", "line.csv", "--tol", "1e-12", "--size", "6"], r"below 1e-08"),
    (["bogus"], r"invalid choice"),
])
def test_cli_errors(args, match, tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "line.csv").write_text("0,0\n1,0\n1,1\n")
    assert main([*args, "--out", str(tmp_path / "out")] if args[0] != "bogus" else args) == 2
    err = capsys.readouterr().err
    assert err.startswith("skatetrace: error:") and re.search(match, err), err


def test_cli_slow_speed_does_not_exhaust_memory(tmp_path):
    """--speed 1e-6 made the replay ask for 4 GiB of samples; its density is now bounded."""
    out = tmp_path / "out"
    assert main(["trace", "circle", "--speed", "1e-6", "--out", str(out), "--no-plots", "--no-viewer"]) in (0, 1)
    report = _strict_json(out / "report.json")
    assert report["max_deviation"] is not None


CLI_VALUES = hs.one_of(hs.sampled_from(BAD_NUMBERS + ["1", "2", "0.5", "1e-3", "3"]),
                       hs.floats(allow_nan=True, allow_infinity=True).map(repr), hs.text(max_size=4))


@FUZZ_CLI
@given(figure=hs.sampled_from(["line", "circle", "no-such-figure", "school:nope", "missing.json", "bad.json",
                               "bad.svg", "pts.csv"]),
       options=hs.lists(hs.tuples(hs.sampled_from(NUMERIC_OPTIONS + ["--size", "--tol", "--exact", "--edge",
                                                                      "--rests", "--fit"]), CLI_VALUES),
                        max_size=3))
def test_fuzz_cli(tmp_path_factory, capsys, figure, options):
    folder = tmp_path_factory.mktemp("cli")
    (folder / "bad.json").write_text('{"curves": [{"pieces": [{"type": "arc", "radius": -1}]}]}')
    (folder / "bad.svg").write_text("<svg><path d='Z'/></svg>")
    (folder / "pts.csv").write_text("0,0\n1,0\n1,1\n0,1\n")
    argv = ["trace", str(folder / figure) if "." in figure else figure, "--out", str(folder / "out"),
            "--no-plots", "--no-viewer"]
    for option, value in options:
        argv += [f"{option}={value}"]  # '=' so that values such as '-1' are not read as options
    capsys.readouterr()
    code = main(argv)
    captured = capsys.readouterr()
    assert code in (0, 1, 2)
    assert "Traceback" not in captured.err
    if code == 2:
        assert captured.err.startswith("skatetrace: error:"), captured.err
    else:
        for name in ("result.json", "report.json"):
            _strict_json(folder / "out" / name)
        assert "nan" not in (folder / "out" / "controls.csv").read_text().lower()


# --- extreme but valid values never put NaN in a file ---------------------------------------------

@pytest.mark.parametrize("figure", [
    _one(_arc(1e-6, 90)),  # tiny: fails verification (deviation at round-off of a micro-figure)
    _one(_line(1e6)),  # long: the replay's samples are bounded
    _one(_arc(1, 1e5)),  # 278 turns of a circle, glided
    {"params": {"M": 1e-6, "m": 1e6, "I": 1e-6}, "curves": [{"pieces": [_arc(1, 90)]}]},
])
def test_extreme_figures_trace_or_fail_cleanly(figure, tmp_path):
    path = tmp_path / "fig.json"
    path.write_text(json.dumps(figure))
    out = tmp_path / "out"
    assert main(["trace", str(path), "--out", str(out), "--no-plots", "--no-viewer"]) in (0, 1)
    _strict_json(out / "result.json")
    _strict_json(out / "report.json")
    lines = (out / "controls.csv").read_text().splitlines()[1:]  # none where nothing was traced
    rows = np.loadtxt(lines, delimiter=",", ndmin=2) if lines else np.empty((0, 0))
    assert np.all(np.isfinite(rows))
