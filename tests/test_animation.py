"""Animations of traced figures (skatetrace.outputs.animation)."""

import matplotlib
import numpy as np
import pytest
from PIL import Image

from skatetrace.outputs import animation
from skatetrace.outputs.animation import AnimationOptions, animate, render_frame, render_rgb, save_still
from skatetrace.cli import main
from skatetrace.errors import SkatetraceError
from skatetrace.outputs.playback import load_playback

SMALL = AnimationOptions(fps=10, duration=2, size_px=(320, 240))


@pytest.fixture(scope="module")
def playback(tmp_path_factory):
    out = tmp_path_factory.mktemp("s-bend")
    # rests at the joins: several sections, so rests and jumps of the mass are drawn too
    assert main(["trace", "s-bend", "--rests", "joins", "--out", str(out), "--no-plots"]) == 0
    return load_playback(out)


def test_gif_has_the_frames_and_size_asked(playback, tmp_path):
    path = tmp_path / "s.gif"
    res = animate(playback, path, SMALL)
    assert res.path == path and path.is_file()
    assert (res.frames, res.width, res.height, res.fps) == (20, 320, 240, 10.0) and res.seconds_elapsed > 0
    with Image.open(path) as im:
        assert im.n_frames == round(SMALL.fps * SMALL.duration) and im.size == (320, 240)
        assert im.info["duration"] == 100
    assert [p.name for p in tmp_path.iterdir()] == ["s.gif"]   # no temporary file left over


def test_mp4_has_the_frames_and_size_asked(playback, tmp_path):
    imageio_ffmpeg = pytest.importorskip("imageio_ffmpeg")
    path = tmp_path / "s.mp4"
    calls = []
    res = animate(playback, path, AnimationOptions(fps=12, duration=1.5, size_px=(321, 239)),
                  progress=lambda done, total: calls.append((done, total)))
    # H.264 in yuv420p needs even sizes: rounded up
    assert (res.frames, res.width, res.height) == (18, 322, 240)
    assert imageio_ffmpeg.count_frames_and_secs(str(path))[0] == 18
    reader = imageio_ffmpeg.read_frames(str(path))
    meta = next(reader)
    assert tuple(meta["size"]) == (322, 240) and meta["fps"] == pytest.approx(12)
    frame = next(reader)
    assert len(frame) == 322 * 240 * 3
    reader.close()
    assert calls == [(k, 18) for k in range(1, 19)]
    assert matplotlib.rcParams["animation.ffmpeg_path"] == "ffmpeg"   # set for the writer only


def test_gif_at_the_defaults(playback, tmp_path):
    res = animate(playback, tmp_path / "d.gif")
    with Image.open(res.path) as im:
        assert im.n_frames == res.frames == round(25 * animation.MIN_SECONDS) and im.size == (800, 800)


def test_motion_between_rows_is_interpolated(playback):
    m = animation._Motion(playback)
    last = np.r_[np.diff(playback.t) > 0, True]     # the row after any jump at its time
    x, y = m.at(playback.t, "x", "y")
    np.testing.assert_array_equal(x[last], playback.x[last])
    # half-way between rows the contact point is on the way, near the average of its neighbours
    i = np.flatnonzero(np.diff(playback.t) > 0)
    xm, ym = m.at(0.5 * (playback.t[i] + playback.t[i + 1]), "x", "y")
    step = np.hypot(np.diff(playback.x)[i], np.diff(playback.y)[i])
    off = np.hypot(xm - 0.5 * (playback.x[i] + playback.x[i + 1]), ym - 0.5 * (playback.y[i] + playback.y[i + 1]))
    assert np.all(off <= 0.3 * step + 1e-12)


def test_default_duration_and_frames(playback):
    opts = AnimationOptions()
    # a short figure is slowed down to the shortest default video; frames follow from fps and duration
    assert playback.duration < animation.MIN_SECONDS
    assert opts.seconds(playback) == animation.MIN_SECONDS
    assert opts.frames(playback) == round(25 * animation.MIN_SECONDS)
    assert AnimationOptions(duration=3.3, fps=7).frames(playback) == 23


def test_frames_are_drawn_and_move(playback, tmp_path):
    t0, t1 = playback.t[0], playback.t[-1]
    early = render_rgb(playback, t0 + 0.3 * (t1 - t0), SMALL)
    late = render_rgb(playback, t0 + 0.8 * (t1 - t0), SMALL)
    assert early.shape == (240, 320, 3) and early.dtype == np.uint8
    background = np.all(early == 255, axis=2)
    assert 0.02 < 1 - background.mean() < 0.6                      # drawn, but not filled
    assert len(np.unique(early.reshape(-1, 3), axis=0)) > 30       # target, trace, skate, mass, text...
    assert (np.any(early != late, axis=2)).sum() > 200             # the skater and the mass moved
    # the still is the same picture as the array, written as PNG
    path = save_still(playback, tmp_path / "still.png", time=t0 + 0.3 * (t1 - t0), options=SMALL)
    with Image.open(path) as im:
        assert im.size == (320, 240)
        np.testing.assert_array_equal(np.asarray(im.convert("RGB")), early)
    assert save_still(playback, tmp_path / "default.png").is_file()
    fig = render_frame(playback, None, SMALL)
    assert tuple(fig.canvas.get_width_height()) == (320, 240)


def test_gif_frames_follow_the_clock(playback, tmp_path):
    # the first frame is the start, the last the end: every rest is marked as passed by then
    path = tmp_path / "s.gif"
    animate(playback, path, AnimationOptions(fps=4, duration=1, size_px=(200, 160)))
    with Image.open(path) as im:
        im.seek(0)
        first = np.asarray(im.convert("RGB"))
        im.seek(im.n_frames - 1)
        last = np.asarray(im.convert("RGB"))
    opts = AnimationOptions(fps=4, duration=1, size_px=(200, 160))
    start = render_rgb(playback, playback.t[0], opts)
    end = render_rgb(playback, playback.t[-1], opts)
    # a GIF has at most 256 colours: compare with the drawn frames loosely
    assert np.abs(first.astype(int) - start).mean() < 3 and np.abs(last.astype(int) - end).mean() < 3
    assert np.abs(first.astype(int) - last).mean() > 1


@pytest.mark.parametrize("kwargs, match", [
    ({"fps": 0}, "fps must be a positive"),
    ({"fps": -5}, "fps must be a positive"),
    ({"fps": float("nan")}, "fps must be a positive"),
    ({"fps": "25"}, "fps must be a number"),
    ({"duration": 0}, "duration must be a positive"),
    ({"dpi": -1}, "dpi must be a positive"),
    ({"trail": -1}, "trail must be a number of seconds >= 0"),
    ({"size_px": (800,)}, "size_px must be"),
    ({"size_px": (800.5, 600)}, "whole pixels"),
    ({"size_px": "800x600"}, "whole pixels"),
    ({"size_px": (8, 600)}, "between 16 and"),
    ({"fps": 1, "duration": 0.4}, "has no frames"),
    # issue 19: an absurd video is refused up front, naming the number of frames and the limit
    ({"duration": 1e9}, r"2\.5e\+10 frames, more than the 90,000 allowed"),
    ({"fps": 1e9}, r"1e\+09 fps .* within 90,000 frames"),
])
def test_bad_options_are_clear_errors(kwargs, match):
    with pytest.raises(ValueError, match=match):
        AnimationOptions(**kwargs)


def test_the_longest_video_allowed_is_accepted():
    assert AnimationOptions(fps=25, duration=animation.MAX_FRAMES / 25).duration == animation.MAX_FRAMES / 25


def test_the_frame_bound_holds_at_the_default_length_too(playback):
    """Without --duration the video lasts the figure's own time (8 to 30 s): an fps that the 8 s floor
    allows may still make too many frames for a longer figure, which frames() refuses before any is drawn."""
    from types import SimpleNamespace

    fps = animation.MAX_FRAMES / animation.MIN_SECONDS  # allowed up front: exactly the bound at 8 s
    opts = AnimationOptions(fps=fps)
    assert playback.duration < animation.MIN_SECONDS and opts.frames(playback) == animation.MAX_FRAMES
    with pytest.raises(ValueError, match=r"a video of 20 s at 11250 fps would have 2\.25e\+05 frames, more than the "
                                         r"90,000 allowed"):
        opts.frames(SimpleNamespace(duration=20.0))  # a figure of 20 s plays in 20 s
    # a short explicit video at a high rate is within the bound: not refused
    assert AnimationOptions(fps=1e6, duration=0.01).frames(playback) == 10_000


def test_bad_paths_and_folders_are_clear_errors(playback, tmp_path):
    with pytest.raises(ValueError, match=r"must end in \.gif or \.mp4 \(got '\.avi'\)"):
        animate(playback, tmp_path / "x.avi", SMALL)
    with pytest.raises(ValueError, match="must end in"):
        animate(playback, tmp_path / "noext", SMALL)
    with pytest.raises(SkatetraceError, match="does not exist"):
        animate(playback, tmp_path / "missing" / "x.gif", SMALL)
    with pytest.raises(ValueError, match=r"\.png"):
        save_still(playback, tmp_path / "x.jpg")
    with pytest.raises(ValueError, match="time must be finite"):
        render_rgb(playback, float("inf"), SMALL)
    with pytest.raises(ValueError, match=r"cannot write an animation .*must end in \.gif or \.mp4 .*\.png by save_still"):
        animate(playback, tmp_path / "x.png", SMALL)
    # the animation's input is the playback: a missing folder fails while loading it
    with pytest.raises(SkatetraceError, match="result.json not found"):
        animate(load_playback(tmp_path / "nothing-here"), tmp_path / "x.gif", SMALL)
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("suffix", [".gif", ".mp4"])
def test_failure_leaves_no_file(playback, tmp_path, monkeypatch, suffix):
    if suffix == ".mp4":
        pytest.importorskip("imageio_ffmpeg")
    writer = animation._GifWriter if suffix == ".gif" else animation._MP4Writer
    grab = writer.grab_frame
    count = []

    def failing(self, **kwargs):
        count.append(1)
        if len(count) == 5:
            raise RuntimeError("disk full")
        return grab(self, **kwargs)

    monkeypatch.setattr(writer, "grab_frame", failing)
    target = tmp_path / f"out{suffix}"
    with pytest.raises(RuntimeError, match="disk full"):
        animate(playback, target, SMALL)
    assert list(tmp_path.iterdir()) == []
    # an existing file is left as it was
    target.write_bytes(b"old")
    count.clear()
    with pytest.raises(RuntimeError, match="disk full"):
        animate(playback, target, SMALL)
    assert target.read_bytes() == b"old" and list(tmp_path.iterdir()) == [target]


def test_progress_that_raises_stops_cleanly(playback, tmp_path):
    def stop(done, total):
        if done == 3:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        animate(playback, tmp_path / "x.gif", SMALL, progress=stop)
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("where", [-0.5, 1.5, 100.0])
def test_a_time_outside_the_clock_is_refused_not_clamped(playback, tmp_path, where):
    t0, t1 = float(playback.t[0]), float(playback.t[-1])
    time = t0 + where * (t1 - t0)
    with pytest.raises(ValueError, match=rf"outside the figure's clock: give a time from {t0:.6g} to {t1:.6g}"):
        render_rgb(playback, time, SMALL)
    with pytest.raises(ValueError, match="outside the figure's clock"):
        save_still(playback, tmp_path / "x.png", time=time, options=SMALL)
    assert list(tmp_path.iterdir()) == []
    # the ends themselves are frames
    assert render_rgb(playback, t1, SMALL).shape == (240, 320, 3)
    assert render_rgb(playback, t0, SMALL).shape == (240, 320, 3)


def test_the_planners_reach_is_drawn_around_the_blade(playback):
    import dataclasses

    t = playback.t[0] + 0.4 * (playback.t[-1] - playback.t[0])
    plain = render_rgb(playback, t, SMALL)
    planned = dataclasses.replace(playback, summary={**playback.summary, "reach": 0.5})
    fig = render_frame(planned, t, SMALL)
    circles = [p for p in fig.axes[0].patches if isinstance(p, matplotlib.patches.Circle)]
    assert len(circles) == 1 and circles[0].get_radius() == 0.5
    # centred on the contact point at that time
    m = animation._Motion(planned)
    x, y = (float(v[0]) for v in m.pose(np.array([t]))[:2])
    assert circles[0].center == pytest.approx((x, y))
    assert (np.any(render_rgb(planned, t, SMALL) != plain, axis=2)).sum() > 50  # and it shows
