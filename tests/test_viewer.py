"""The self-contained HTML viewer (skatetrace.outputs.viewer): static checks, and a real browser.

The browser tests drive Debian's Chromium (``/usr/bin/chromium``) with Playwright for Python. They
are skipped where either is missing, unless ``SKATETRACE_REQUIRE_BROWSER=1`` (set by CI), which
makes a missing browser a failure.
"""

from __future__ import annotations

import dataclasses
import importlib.util
import io
import json
import math
import os
import re
from html.parser import HTMLParser
from pathlib import Path

import numpy as np
import pytest

from skatetrace.cli import main
from skatetrace.dynamics.model import SleighParams
from skatetrace.outputs.playback import Playback, load_playback
from skatetrace.outputs.viewer import SPEED_FACTORS, default_speed, sample_rows, viewer_html, write_viewer

CHROMIUM = "/usr/bin/chromium"
CHROMIUM_ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                 "--disable-background-networking", "--disable-component-update", "--disable-sync"]
WEIRD_NAME = 'a</script><b>"x"</b> & \'y\' {{DATA}} Ω ❄ <!-- \u2028'


# ---- data -----------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def traced(tmp_path_factory):
    """A small real figure in SI units: two circles, two sections, a rest between them."""
    out = tmp_path_factory.mktemp("circle-eight")
    assert main(["trace", "school:circle-eight", "--reach", "none", "--out", str(out), "--no-plots"]) == 0
    return out


@pytest.fixture(scope="module")
def playback(traced):
    return load_playback(traced)


def synthetic(n: int = 6001, name: str = "synthetic", summary: dict | None = None) -> Playback:
    """Three sections on a circle with a cusp (heading and mass jump) and a curve change (position jump)."""
    t = np.concatenate([np.linspace(0, 1, n // 3), np.linspace(1, 2, n // 3), np.linspace(2, 3, n - 2 * (n // 3))])
    section = np.repeat([0, 1, 2], [n // 3, n // 3, n - 2 * (n // 3)])
    phi = np.pi * t / 3
    x, y = np.cos(phi) + (section == 2) * 5.0, np.sin(phi)  # the third section starts elsewhere
    theta = phi + np.pi / 2 + np.pi * (section == 1)
    a, b = 0.5 * np.sin(3 * phi) * (1 - 2 * (section == 1)), 0.2 * np.cos(phi)
    c, s = np.cos(theta), np.sin(theta)
    speed = np.sin(np.pi * (t - np.floor(np.minimum(t, 2.999999))))
    rest_rows = np.array([0, n // 3, 2 * (n // 3), n - 1])
    zeros = np.zeros(n)
    return Playback(
        name=name, unit="model", params=SleighParams(M=2.0, m=1.0, I=3.0), t=t, x=x, y=y, theta=theta, a=a, b=b,
        adot=zeros, bdot=zeros, mass_x=x + a * c - b * s, mass_y=y + a * s + b * c, speed=speed, omega=zeros,
        ke_skate=speed**2, ke_mass=0.5 * speed**2, section=section,
        figure=[np.vstack([np.cos(np.linspace(0, np.pi, 300)), np.sin(np.linspace(0, np.pi, 300))])],
        rests=np.vstack([x[rest_rows], y[rest_rows]]), rest_times=t[rest_rows],
        summary=summary if summary is not None else {
            "figure": name, "success": True, "status": "success", "message": "all 3 sections traced exactly",
            "duration": 3.0, "sections": 3, "params": {"M": 2.0, "m": 1.0, "I": 3.0}, "unit": "model",
            "verification": {"status": "passed", "message": "all checks passed", "max_deviation": 1e-9,
                             "tolerance": 1e-6, "figure_size": 1.0, "max_cusp_speed": 1e-12}},
    )


class _Page(HTMLParser):
    """The start tags (with attributes) of a page and the text of its JSON data script."""

    def __init__(self):
        super().__init__(convert_charrefs=True)
        self.tags: list[tuple[str, dict]] = []
        self.data_text = ""
        self.title = ""
        self._in: str | None = None

    def handle_starttag(self, tag, attrs):
        attrs = dict(attrs)
        self.tags.append((tag, attrs))
        if tag == "script" and attrs.get("id") == "skatetrace-data":
            self._in = "data"
        elif tag in ("title", "h1"):
            self._in = tag

    def handle_endtag(self, tag):
        self._in = None

    def handle_data(self, data):
        if self._in == "data":
            self.data_text += data
        elif self._in == "title":
            self.title += data


def parse(text: str) -> tuple[_Page, dict]:
    page = _Page()
    page.feed(text)
    page.close()
    return page, json.loads(page.data_text)


# ---- without a browser ----------------------------------------------------------------------

def test_sample_rows_keeps_ends_jumps_and_rests():
    pb = synthetic()
    rows = sample_rows(pb, 500)
    assert rows.size <= 500 and rows.size > 450
    assert np.all(np.diff(rows) > 0) and rows[0] == 0 and rows[-1] == pb.t.size - 1
    jumps = np.flatnonzero(np.diff(pb.t) == 0)
    assert jumps.size == 2 and set(jumps) | set(jumps + 1) <= set(rows)
    starts = np.flatnonzero(np.diff(pb.section, prepend=-1) != 0)
    assert set(starts) <= set(rows)
    # evenly spread in time: no gap much wider than the even spacing
    assert np.max(np.diff(pb.t[rows])) < 2.5 * pb.duration / 500
    np.testing.assert_array_equal(sample_rows(pb, 10**6), np.arange(pb.t.size))
    tiny = sample_rows(pb, 3)
    assert tiny.size <= 3 and tiny[0] == 0 and tiny[-1] == pb.t.size - 1
    with pytest.raises(ValueError, match="at least 2"):
        sample_rows(pb, 1)


def test_default_speed_plays_in_about_25_seconds():
    assert default_speed(108.78) == 4.0  # the double flower: 27 s
    assert default_speed(19.39) == 1.0
    assert default_speed(6.96) == 0.25
    assert default_speed(1000.0) == 40.0 and default_speed(0.5) == 0.02  # beyond the list
    assert default_speed(0.0) == 1.0 and default_speed(math.nan) == 1.0
    for d in (3.0, 20.0, 100.0, 300.0):
        assert 10 <= d / default_speed(d) <= 60


def test_page_is_self_contained_with_embedded_data(playback, tmp_path):
    path = write_viewer(playback, tmp_path / "sub" / "viewer.html", max_samples=1500)
    assert path == tmp_path / "sub" / "viewer.html" and path.is_file()
    text = path.read_text(encoding="utf-8")
    assert text.startswith("<!DOCTYPE html>")
    page, data = parse(text)
    tags = [t for t, _ in page.tags]
    # nothing to fetch: no external scripts, styles, images, fonts or frames
    for tag, attrs in page.tags:
        for key in ("src", "href", "xlink:href", "action", "data", "poster", "srcset"):
            value = (attrs.get(key) or "").strip().lower()
            assert not value.startswith(("http:", "https:", "//", "ftp:")), (tag, key, value)
        assert not (tag == "script" and attrs.get("src")), attrs
    assert "link" not in tags and "iframe" not in tags and "img" not in tags
    assert not re.search(r"""(src|href)\s*=\s*["']?\s*(https?:)?//""", text, re.IGNORECASE)
    assert "@import" not in text and not re.search(r"url\(\s*['\"]?(https?:)?//", text)
    assert any(t == "meta" and a.get("http-equiv") == "Content-Security-Policy" and "default-src 'none'" in a["content"]
               for t, a in page.tags)
    # stable ids for scripts and tests
    ids = {a.get("id") for _, a in page.tags}
    assert {"play", "speed", "view", "slider", "time", "stage", "plot-ab", "plot-speed", "plot-energy",
            "summary", "checks", "skatetrace-data"} <= ids
    assert ("input", "range") in {(t, a.get("type")) for t, a in page.tags}
    # the data: downsampled, rounded, complete
    assert data["name"] == playback.name == "circle-eight-RFO" and data["unit"] == "m"
    assert data["rows"] == playback.t.size and data["samples"] <= 1500
    series = data["series"]
    assert set(series) >= {"t", "x", "y", "theta", "a", "b", "speed", "ke_skate", "ke_mass"}
    assert all(len(v) == data["samples"] for v in series.values())
    rows = sample_rows(playback, 1500)
    runs = data["section_runs"]
    sections = np.repeat([s for _, s in runs], np.diff([r for r, _ in runs] + [data["samples"]]))
    np.testing.assert_array_equal(sections, playback.section[rows])
    t = np.array(series["t"])
    assert t[0] == pytest.approx(playback.t[0]) and t[-1] == pytest.approx(playback.t[-1], abs=1e-6)
    assert np.all(np.diff(t) >= 0)
    np.testing.assert_allclose(series["x"], playback.x[rows], atol=1e-5 * data["bounds"][1])
    np.testing.assert_allclose(series["b"], playback.b[rows], atol=1e-5 * np.abs(playback.b).max())
    assert max(len(repr(v)) for col in series.values() for v in col) <= 13  # rounded
    assert len(data["figure"]) == len(playback.figure) and data["rests"]["t"] == pytest.approx(playback.rest_times.tolist())
    assert data["default_speed"] == default_speed(playback.duration) and set(SPEED_FACTORS) <= set(data["speeds"])
    # two views: everything (the mass too), and the figure with the blade's path
    assert data["views"]["all"] == pytest.approx(list(playback.bounds()))
    fig = data["views"]["figure"]
    assert fig[0] <= playback.x.min() and fig[1] >= playback.x.max() and fig[2] <= playback.y.min()
    assert fig[1] - fig[0] <= data["views"]["all"][1] - data["views"]["all"][0]
    assert data["summary"]["verification"]["status"] == "passed"
    # the summary and the checks as tables
    assert "circle-eight-RFO" in page.title and 'class="check pass"' in text and "FAILED" not in text
    assert path.stat().st_size < 400_000


def test_writes_into_a_folder_and_reads_a_folder(traced, tmp_path):
    path = write_viewer(traced, tmp_path, max_samples=200)
    assert path == tmp_path / "viewer.html"
    _, data = parse(path.read_text(encoding="utf-8"))
    assert data["samples"] <= 200 and data["name"] == "circle-eight-RFO"


def test_escapes_hostile_names():
    pb = synthetic(name=WEIRD_NAME)
    pb = dataclasses.replace(pb, summary={**pb.summary, "figure": WEIRD_NAME, "message": "<i>bold</i> & more"})
    text = viewer_html(pb, max_samples=300)
    # exactly two scripts, each closed once: the name cannot end the data script early
    assert len(re.findall(r"<script\b", text, re.IGNORECASE)) == 2
    assert len(re.findall(r"</script", text, re.IGNORECASE)) == 2
    assert "<!--" not in text.split("<body>", 1)[1]
    assert "<b>" not in text and "<i>bold" not in text
    assert set(re.findall(r"\{\{(\w+)\}\}", text)) == {"DATA"}  # only the name's own, never filled in
    page, data = parse(text)
    assert data["name"] == WEIRD_NAME and data["summary"]["figure"] == WEIRD_NAME
    assert WEIRD_NAME in page.title
    assert "b" not in [t for t, _ in page.tags] and "&lt;i&gt;bold&lt;/i&gt; &amp; more" in text
    assert text.isascii() or "Ω" in text  # unicode is kept, escaped or verbatim


def test_failed_checks_are_marked_and_non_finite_values_survive():
    pb = synthetic(summary={
        "figure": "bad", "success": True, "status": "success", "message": "ok", "duration": 3.0, "sections": 3,
        "params": {"M": 2.0, "m": 1.0, "I": 3.0}, "unit": "model",
        "verification": {"status": "failed", "message": "deviation inf exceeds 1e-06; speed at a cusp above ...",
                         "max_deviation": math.inf, "tolerance": 1e-6, "figure_size": 1.0,
                         "max_cusp_speed": 0.3}})
    pb = dataclasses.replace(pb, speed=np.where(pb.t > 2.5, np.nan, pb.speed))
    text = viewer_html(pb, max_samples=300)
    page, data = parse(text)
    assert data["summary"]["verification"]["max_deviation"] == "inf"
    assert None in data["series"]["speed"]
    assert len(re.findall(r'class="check fail"', text)) == 3  # deviation, cusp speed, verification
    assert "✘ FAILED" in text and 'class="badge fail"' in text


def test_not_verified_figures_say_so():
    pb = synthetic()
    pb = dataclasses.replace(pb, summary={k: v for k, v in pb.summary.items() if k != "verification"})
    text = viewer_html(pb, max_samples=100)
    assert "not verified" in text and 'class="badge unknown"' in text and "FAILED" not in text


# ---- in a browser ---------------------------------------------------------------------------

def _browser_missing() -> str | None:
    if not Path(CHROMIUM).exists():
        return f"{CHROMIUM} not found (Debian package 'chromium')"
    if importlib.util.find_spec("playwright") is None:
        return "the Python package 'playwright' is not installed"
    return None


def _unavailable(reason: str):
    if os.environ.get("SKATETRACE_REQUIRE_BROWSER") == "1":
        pytest.fail(f"SKATETRACE_REQUIRE_BROWSER=1 but the browser tests cannot run: {reason}", pytrace=False)
    pytest.skip(reason)


@pytest.fixture(scope="module")
def browser():
    reason = _browser_missing()
    if reason:
        _unavailable(reason)
    from playwright.sync_api import Error, sync_playwright

    with sync_playwright() as pw:
        try:
            b = pw.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS, timeout=30_000)
        except Error as exc:
            _unavailable(f"{CHROMIUM} does not start under Playwright: {exc}")
        try:
            yield b
        finally:
            b.close()


@pytest.fixture(scope="module")
def page_file(playback, tmp_path_factory):
    return write_viewer(playback, tmp_path_factory.mktemp("viewer") / "viewer.html")


class Opened:
    """A page of the viewer, with everything it logged and requested."""

    def __init__(self, browser, path: Path):
        self.url = path.resolve().as_uri()
        self.errors: list[str] = []
        self.requests: list[str] = []
        self.page = browser.new_page(viewport={"width": 1280, "height": 1000})
        self.page.on("console", lambda m: self.errors.append(f"console: {m.text}") if m.type == "error" else None)
        self.page.on("pageerror", lambda e: self.errors.append(f"page error: {e}"))
        self.page.on("request", lambda r: self.requests.append(r.url))
        self.page.goto(self.url)
        self.page.wait_for_function("window.skatetrace !== undefined", timeout=10_000)

    def time(self) -> float:
        return float(self.page.text_content("#time"))

    def skate(self) -> tuple:
        return self.page.eval_on_selector(
            "#skate", "e => [e.getAttribute('data-x'), e.getAttribute('data-y'), e.getAttribute('transform')]")

    def assert_clean(self):
        assert self.errors == []
        assert self.requests == [self.url]


@pytest.fixture
def opened(browser, page_file):
    o = Opened(browser, page_file)
    yield o
    o.page.close()


def test_browser_loads_without_errors_or_requests(opened, playback):
    opened.assert_clean()
    p = opened.page
    assert p.evaluate("window.skatetrace.time()") == pytest.approx(playback.t[0])
    assert p.evaluate("window.skatetrace.playing()") is False
    assert opened.time() == pytest.approx(playback.t[0])
    assert float(p.get_attribute("#slider", "max")) == pytest.approx(playback.t[-1], abs=1e-6)
    assert p.evaluate("window.skatetrace.duration()") == pytest.approx(playback.duration, abs=1e-6)
    assert p.eval_on_selector("#speed", "s => Number(s.value)") == default_speed(playback.duration)
    assert p.eval_on_selector_all("#speed option", "os => os.map(o => Number(o.value))") == sorted(
        set(SPEED_FACTORS) | {default_speed(playback.duration)})
    assert p.text_content("#title") == playback.name
    # the drawing is there: target, trace pieces, rests, plots with cursors
    assert p.eval_on_selector_all("#figure polyline", "ps => ps.length") == len(playback.figure)
    assert p.eval_on_selector_all("#rests circle", "cs => cs.length") == playback.rests.shape[1]
    assert p.eval_on_selector_all(".plot .plot-cursor", "cs => cs.length") == 3
    assert p.eval_on_selector_all(".plot polyline", "ps => ps.length") == 6  # a, b; speed; 3 energies


def test_play_advances_and_pause_stops(opened):
    p = opened.page
    t0 = opened.time()
    p.click("#play")
    assert p.get_attribute("#play", "data-state") == "playing" and p.evaluate("window.skatetrace.playing()")
    p.wait_for_timeout(600)
    t1 = opened.time()
    assert t1 > t0
    before = opened.skate()
    p.wait_for_timeout(200)
    assert opened.skate() != before  # the skater moves while playing
    p.click("#play")
    assert p.get_attribute("#play", "data-state") == "paused" and not p.evaluate("window.skatetrace.playing()")
    t2 = opened.time()
    p.wait_for_timeout(400)
    assert opened.time() == t2 and t2 >= t1
    opened.assert_clean()


def test_slider_scrubs_and_moves_the_skater(opened, playback):
    p = opened.page
    start = opened.skate()
    target = playback.t[0] + 0.4 * playback.duration
    p.eval_on_selector("#slider", "(s, v) => { s.value = String(v); s.dispatchEvent(new Event('input', {bubbles: true})); }",
                       target)
    assert opened.time() == pytest.approx(target, abs=0.01)
    assert p.evaluate("window.skatetrace.time()") == pytest.approx(target, abs=1e-6)
    moved = opened.skate()
    assert moved[:2] != start[:2] and moved[2] != start[2]
    # at a row's time the skate is drawn at the contact point and the mass where the data put it
    data = p.evaluate("window.skatetrace.data.series")
    row = len(data["t"]) // 3
    p.evaluate(f"window.skatetrace.seek({data['t'][row]})")
    sx, sy = p.evaluate(f"window.skatetrace.screen({data['x'][row]}, {data['y'][row]})")
    skate = opened.skate()
    assert (float(skate[0]), float(skate[1])) == pytest.approx((sx, sy), abs=0.02)
    th, a, b = data["theta"][row], data["a"][row], data["b"][row]
    mx, my = p.evaluate(f"window.skatetrace.screen({data['x'][row] + a * math.cos(th) - b * math.sin(th)}, "
                        f"{data['y'][row] + a * math.sin(th) + b * math.cos(th)})")
    cx, cy = p.eval_on_selector("#mass", "m => [Number(m.getAttribute('cx')), Number(m.getAttribute('cy'))]")
    assert (cx, cy) == pytest.approx((mx, my), abs=0.05)
    moved = opened.skate()
    # seek through the API, and to the end
    p.evaluate(f"window.skatetrace.seek({playback.t[-1]})")
    assert opened.time() == pytest.approx(playback.t[-1], abs=0.01)
    assert opened.skate() != moved
    assert "section 2 of 2" in p.text_content("#clock")
    # the plot cursors follow
    cursor = p.eval_on_selector("#plot-speed .plot-cursor", "c => Number(c.getAttribute('x1'))")
    assert cursor == pytest.approx(480 - 12, abs=0.5)
    opened.assert_clean()


def test_views_fit_the_figure_or_everything(opened, browser, tmp_path):
    p = opened.page
    assert p.get_attribute("#stage", "data-view") == "all"  # the circle eight's mass stays near: fit all
    p.evaluate("window.skatetrace.seek(1.0)")
    before = opened.skate()
    p.select_option("#view", "figure")
    assert p.get_attribute("#stage", "data-view") == "figure" and opened.skate()[:2] != before[:2]
    assert opened.time() == pytest.approx(1.0)
    opened.assert_clean()
    # the synthetic mass strays 10 figure sizes away: the figure is fitted by default
    far = synthetic()
    far = dataclasses.replace(far, a=far.a * 40, mass_x=far.x + 40 * (far.mass_x - far.x))
    o = Opened(browser, write_viewer(far, tmp_path / "far.html", max_samples=300))
    try:
        assert o.page.get_attribute("#stage", "data-view") == "figure"
        assert o.page.evaluate("window.skatetrace.view('all')") == "all"
        o.assert_clean()
    finally:
        o.page.close()


def test_clicking_a_plot_seeks(opened, playback):
    p = opened.page
    box = p.locator("#plot-energy").bounding_box()
    # the plot area runs from 50 to 468 of the 480 units of the plot's width
    frac = 0.75
    p.mouse.click(box["x"] + box["width"] * (50 + frac * 418) / 480, box["y"] + box["height"] * 0.5)
    assert p.evaluate("window.skatetrace.time()") == pytest.approx(playback.t[0] + frac * playback.duration,
                                                                   rel=0.02)
    opened.assert_clean()


def test_screenshot_is_not_blank(opened, playback):
    from PIL import Image

    p = opened.page
    p.evaluate(f"window.skatetrace.seek({playback.t[0] + 0.6 * playback.duration})")
    img = Image.open(io.BytesIO(p.screenshot())).convert("RGB")
    assert img.size == (1280, 1000)
    colours = img.getcolors(maxcolors=1 << 20)
    assert len(colours) > 200
    background = max(colours)[1]
    pixels = np.asarray(img).reshape(-1, 3)
    assert np.mean(np.any(pixels != background, axis=1)) > 0.3
    # the stage itself shows the figure: blue of the trace, orange of the mass
    stage = np.asarray(Image.open(io.BytesIO(p.locator("#stage").screenshot())).convert("RGB"))
    stage = stage.reshape(-1, 3).astype(int)
    blue = np.sum((stage[:, 2] > 150) & (stage[:, 0] < 80))
    orange = np.sum((stage[:, 0] > 200) & (stage[:, 1] > 90) & (stage[:, 1] < 160) & (stage[:, 2] < 80))
    assert blue > 200 and orange > 20


def test_hostile_name_shows_as_text(browser, tmp_path):
    pb = synthetic(name=WEIRD_NAME)
    pb = dataclasses.replace(pb, summary={**pb.summary, "figure": WEIRD_NAME})
    o = Opened(browser, write_viewer(pb, tmp_path / "weird.html", max_samples=500))
    try:
        o.assert_clean()
        assert o.page.text_content("#title") == WEIRD_NAME
        assert o.page.title().startswith(WEIRD_NAME)
        assert o.page.evaluate("window.skatetrace.data.name") == WEIRD_NAME
        # three sections, one of them after a jump of the contact point: two pieces of trace
        assert o.page.eval_on_selector_all("#trace path", "ps => ps.length") == 2
        o.page.evaluate("window.skatetrace.seek(2.5)")
        assert o.time() == pytest.approx(2.5)
        o.assert_clean()
    finally:
        o.page.close()


def test_the_planners_reach_is_a_circle_around_the_blade(browser, tmp_path):
    pb = synthetic()
    pb = dataclasses.replace(pb, summary={**pb.summary, "reach": 0.6})
    o = Opened(browser, write_viewer(pb, tmp_path / "reach.html", max_samples=500))
    try:
        o.assert_clean()
        # inside the skate's group, centred on the contact point: it moves and turns with the blade
        r = float(o.page.eval_on_selector("#skate #reach", "c => c.getAttribute('r')"))
        blade = o.page.eval_on_selector("#skate .blade", "l => [l.getAttribute('x1'), l.getAttribute('x2')]")
        assert r > 0 and o.page.eval_on_selector("#skate #reach", "c => [c.getAttribute('cx'), c.getAttribute('cy')]") == ["0", "0"]
        assert "reach" in o.page.text_content("body") and float(blade[1]) > float(blade[0])
        # scaled like the mass's offset: at the start the mass sits at |(a, b)| = 0.2 from the contact point
        sx, sy = (float(v) for v in o.skate()[:2])
        mx, my = (float(v) for v in o.page.eval_on_selector("#mass", "c => [c.getAttribute('cx'), c.getAttribute('cy')]"))
        assert r / math.hypot(mx - sx, my - sy) == pytest.approx(0.6 / math.hypot(pb.a[0], pb.b[0]), rel=0.02)
    finally:
        o.page.close()
    plain = Opened(browser, write_viewer(synthetic(), tmp_path / "plain.html", max_samples=500))
    try:
        assert plain.page.query_selector("#reach") is None  # no planner, no circle
    finally:
        plain.page.close()


def test_the_cusps_are_reported_beside_the_feasibility_checks():
    from skatetrace.outputs.viewer import _feasibility_rows

    rows = _feasibility_rows({"checks": [], "status": "feasible", "feasible": True, "info": {
        "peak_force_on_mass": 854.0, "force_unit": "N", "max_cusp_mass_speed": 4.6, "max_cusp_impulse": 35.9,
        "impulse_unit": "N s"}})
    shown = {r["name"]: r["value"] for r in rows}
    assert shown["peak force on the mass"] == "854 N" and shown["impulse on the mass at a cusp"] == "35.9 N s"
    assert shown["mass speed at a cusp (relative to the stopped blade)"] == "4.6"
