"""An animation of a traced figure, drawn from its result files (never solving again).

:func:`animate` writes a GIF (Pillow) or an MP4 (ffmpeg, H.264) of a :class:`~skatetrace.outputs.playback.Playback`:
the target figure in light grey, the blade's trace growing over it, the skate as a short segment along the
heading with a mark at its toe, the moving mass (the skater's centre of mass) as a dot with a fading trail
and a thin line to the contact point, the places where the skater is at rest (cusps, section starts, the
end; filled once passed), a clock and the section number. :func:`render_frame`, :func:`render_rgb` and
:func:`save_still` draw a single frame, e.g. for a README.

The state between the rows of ``controls.csv`` is interpolated with cubic Hermite polynomials using the rates
the rows carry (the blade moves along its heading at ``speed`` and turns at ``omega``; the mass moves at
``adot``, ``bdot`` in the body frame), so the motion is smooth even where the rows are sparse. A repeated time
is a jump (a new curve, a pivot at a cusp): the trace and the trail are broken there, never bridged.

Frames are drawn by blitting: the parts that never change (target figure, rest markers, frame, title) are
rendered once and each frame draws only the moving artists over them, so a frame costs a few milliseconds.
"""

from __future__ import annotations

import math
import time as _time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import matplotlib
import numpy as np
from matplotlib.animation import FFMpegWriter, PillowWriter
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.collections import LineCollection
from matplotlib.colors import to_rgba
from matplotlib.figure import Figure
from matplotlib.patches import Circle
from PIL import Image

from ..errors import SkatetraceError
from .files import write_atomically
from .playback import Playback

__all__ = ["AnimationOptions", "AnimationResult", "animate", "render_frame", "render_rgb", "save_still",
           "SUFFIXES", "STILL_SUFFIXES", "MIN_SECONDS", "MAX_SECONDS"]

#: File suffixes :func:`animate` writes, by writer.
SUFFIXES = (".gif", ".mp4")
#: File suffixes :func:`save_still` writes.
STILL_SUFFIXES = (".png",)
#: Default video length: the figure's own duration (real time) clamped to this range of seconds.
MIN_SECONDS, MAX_SECONDS = 8.0, 30.0

_SKATE_FRACTION = 0.04     # skate length, as a fraction of the figure's size
_SKATE_MIN_FRACTION = 0.03  # ... and at least this fraction of the picture's size
_TRACE_SAMPLES = 3000      # the growing trace is drawn from at most this many samples (plus rests and jumps)
_TRAIL_SAMPLES = 60        # points along the mass's fading trail
_TRAIL_CAP = 0.1           # the trail covers at most this fraction of the video
_MAX_PIXELS = 8192
#: The most frames a video may have: an hour at 25 fps (each frame is drawn in some tens of milliseconds).
MAX_FRAMES = 90_000

_TARGET, _TRACE, _SKATE, _TOE, _MASS, _LINK = "0.83", "#1f5fa8", "#1a1a1a", "#d62728", "#f28e1c", "0.45"
_REST, _PASSED = "0.55", "#d62728"


def _positive(name: str, value, *, allow_none: bool = False) -> None:
    if value is None and allow_none:
        return
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise ValueError(f"AnimationOptions.{name} must be a number, got {value!r}")
    if not math.isfinite(value) or value <= 0:
        raise ValueError(f"AnimationOptions.{name} must be a positive finite number, got {value!r}")


@dataclass(frozen=True, slots=True, kw_only=True)
class AnimationOptions:
    """How an animation is drawn and timed.

    Parameters
    ----------
    fps : float
        Frames per second of the video.
    duration : float or None
        Length of the video in seconds. ``None``: the figure's own duration (real time, a model time
        unit counting as a second) clamped to [``MIN_SECONDS``, ``MAX_SECONDS``]. The video has
        ``round(fps * duration)`` frames (at least one), evenly spaced over the figure's time.
    size_px : (int, int)
        Width and height in pixels. An MP4 needs even sizes: odd ones are rounded up by one pixel.
    dpi : float
        Dots per inch: with ``size_px`` it sets how large text and lines are (at 100 dpi, 800 x 800 px
        is a figure of 8 x 8 inches).
    trail : float
        Length of the mass's fading trail in seconds of video (the motion of the last ``trail``
        seconds watched, but at most a tenth of the video); 0 draws no trail.

    Raises
    ------
    ValueError
        A number that is not positive and finite, a size that is not two whole numbers of pixels, or a
        video of no frames.
    """

    fps: float = 25.0
    duration: float | None = None
    size_px: tuple[int, int] = (800, 800)
    dpi: float = 100.0
    trail: float = 1.5

    def __post_init__(self) -> None:
        _positive("fps", self.fps)
        _positive("duration", self.duration, allow_none=True)
        _positive("dpi", self.dpi)
        if isinstance(self.trail, bool) or not isinstance(self.trail, (int, float, np.integer, np.floating)) \
                or not math.isfinite(self.trail) or self.trail < 0:
            raise ValueError(f"AnimationOptions.trail must be a number of seconds >= 0, got {self.trail!r}")
        size = self.size_px
        try:
            ok = len(size) == 2 and all(isinstance(v, (int, np.integer)) and not isinstance(v, bool)
                                        for v in size)
        except TypeError:
            ok = False
        if not ok:
            raise ValueError(f"AnimationOptions.size_px must be (width, height) in whole pixels, got {size!r}")
        if not all(16 <= v <= _MAX_PIXELS for v in size):
            raise ValueError(f"AnimationOptions.size_px must be between 16 and {_MAX_PIXELS} pixels each way, "
                             f"got {tuple(size)!r}")
        object.__setattr__(self, "size_px", (int(size[0]), int(size[1])))
        if self.duration is not None and round(self.fps * self.duration) < 1:
            raise ValueError(f"a video of {self.duration:g} s at {self.fps:g} fps has no frames: "
                             "give a longer duration or a higher fps")
        # refused up front where the count is known without the figure (frames() checks it again with it)
        if self.duration is not None:
            _check_frames(self.fps, self.duration)
        elif self.fps * MIN_SECONDS > MAX_FRAMES:  # the default length is at least MIN_SECONDS
            raise ValueError(f"{self.fps:g} fps is more than a video of at least {MIN_SECONDS:g} s can have within "
                             f"{MAX_FRAMES:,} frames: give a lower fps")

    def seconds(self, playback: Playback) -> float:
        """Length of the video of ``playback`` in seconds."""
        if self.duration is not None:
            return float(self.duration)
        return float(np.clip(playback.duration, MIN_SECONDS, MAX_SECONDS))

    def frames(self, playback: Playback) -> int:
        """Number of frames of the video of ``playback``: ``round(fps * seconds)``, at least one.

        Raises ValueError beyond :data:`MAX_FRAMES`.
        """
        seconds = self.seconds(playback)
        _check_frames(self.fps, seconds)
        return max(1, round(self.fps * seconds))


def _check_frames(fps: float, seconds: float) -> None:
    """Refuse a video of more than :data:`MAX_FRAMES` frames, naming the count."""
    if fps * seconds > MAX_FRAMES:
        raise ValueError(f"a video of {seconds:g} s at {fps:g} fps would have {fps * seconds:.3g} frames, more than "
                         f"the {MAX_FRAMES:,} allowed: give a shorter duration or a lower fps")


@dataclass(frozen=True, slots=True)
class AnimationResult:
    """What :func:`animate` wrote.

    Attributes
    ----------
    path : Path
    frames, width, height : int
        Frame count and frame size in pixels (the MP4 size is the requested one rounded up to even).
    fps : float
    seconds_elapsed : float
        Wall-clock time taken to draw and write the file.
    """

    path: Path
    frames: int
    width: int
    height: int
    fps: float
    seconds_elapsed: float


# ----------------------------------------------------------------------------------------------------------
# The motion between rows


class _Motion:
    """Cubic Hermite interpolation of the playback's state at any time, with its jumps."""

    def __init__(self, pb: Playback) -> None:
        self.pb = pb
        t = np.asarray(pb.t, dtype=float)
        self.t = t
        self.t0, self.t1 = float(t[0]), float(t[-1])
        c, s = np.cos(pb.theta), np.sin(pb.theta)
        self._cols = {
            "x": (pb.x, pb.speed * c), "y": (pb.y, pb.speed * s), "theta": (pb.theta, pb.omega),
            "a": (pb.a, pb.adot), "b": (pb.b, pb.bdot),
        }
        # A jump: rows at one time whose contact point (a new curve) or mass (a pivot at a cusp) differ.
        same = np.flatnonzero(np.diff(t) == 0)
        scale = max(np.ptp(pb.x), np.ptp(pb.y), np.ptp(pb.mass_x), np.ptp(pb.mass_y), 1e-12)

        def jumps(*cols):
            step = np.max([np.abs(np.diff(v)[same]) for v in cols], axis=0) if same.size else np.zeros(0)
            return np.unique(t[same[step > 1e-9 * scale]])

        self.mass_jumps = jumps(pb.mass_x, pb.mass_y)
        self.blade_jumps = jumps(pb.x, pb.y)

    def rows(self, times: np.ndarray) -> np.ndarray:
        """Last row at or before each time (the state after a jump at that time)."""
        return np.clip(np.searchsorted(self.t, times, side="right") - 1, 0, self.t.size - 1)

    def at(self, times, *names: str) -> list[np.ndarray]:
        times = np.clip(np.asarray(times, dtype=float), self.t0, self.t1)
        i = self.rows(times)
        j = np.minimum(i + 1, self.t.size - 1)
        h = self.t[j] - self.t[i]
        s = np.where(h > 0, (times - self.t[i]) / np.where(h > 0, h, 1.0), 0.0)
        s2, s3 = s * s, s * s * s
        h00, h10, h01, h11 = 2 * s3 - 3 * s2 + 1, s3 - 2 * s2 + s, 3 * s2 - 2 * s3, s3 - s2
        out = []
        for name in names:
            v, dv = self._cols[name]
            out.append(h00 * v[i] + h10 * h * dv[i] + h01 * v[j] + h11 * h * dv[j])
        return out

    def pose(self, times):
        """Contact point, heading and the mass on the ice at the given times."""
        x, y, th, a, b = self.at(times, "x", "y", "theta", "a", "b")
        c, s = np.cos(th), np.sin(th)
        return x, y, th, x + a * c - b * s, y + a * s + b * c

    def mass_piece(self, times) -> np.ndarray:
        """Index of the stretch between the mass's jumps each time falls in."""
        return np.searchsorted(self.mass_jumps, times, side="right")

    def trace_path(self, n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The blade's path sampled for drawing: times, x, y (NaN breaks where it jumps), ordered by time."""
        pb, tj = self.pb, self.blade_jumps
        ts = np.unique(np.concatenate([np.linspace(self.t0, self.t1, n), pb.rest_times]))
        x, y = self.at(ts, "x", "y")
        # at a jump: the point before it (the first row at its time), a break, the point after it (the last)
        first = np.searchsorted(self.t, tj, side="left")
        last = np.searchsorted(self.t, tj, side="right") - 1
        gap = np.full(tj.size, np.nan)
        xj = np.column_stack([pb.x[first], gap, pb.x[last]]).ravel()
        yj = np.column_stack([pb.y[first], gap, pb.y[last]]).ravel()
        ts, x, y = np.concatenate([ts, np.repeat(tj, 3)]), np.concatenate([x, xj]), np.concatenate([y, yj])
        order = np.concatenate([np.full(ts.size - xj.size, 3), np.tile([0, 1, 2], tj.size)])
        k = np.lexsort((order, ts))
        return ts[k], x[k], y[k]


# ----------------------------------------------------------------------------------------------------------
# The scene


def _figure_size(pb: Playback) -> float:
    if pb.figure:
        xs = np.concatenate([p[0] for p in pb.figure])
        ys = np.concatenate([p[1] for p in pb.figure])
        size = max(np.ptp(xs), np.ptp(ys))
        if size > 0:
            return float(size)
    x0, x1, y0, y1 = pb.bounds(margin=0.0)
    return max(x1 - x0, y1 - y0, 1e-12)


class _Scene:
    """A matplotlib figure of the playback whose moving artists are updated in place."""

    def __init__(self, pb: Playback, options: AnimationOptions, width: int, height: int) -> None:
        self.pb, self.options = pb, options
        self.width, self.height = width, height
        self.motion = m = _Motion(pb)
        self.video_seconds = options.seconds(pb)
        dpi = float(options.dpi)
        # a quarter pixel more than asked so that rounding down to whole pixels lands on the size asked
        self.fig = fig = Figure(figsize=((width + 0.25) / dpi, (height + 0.25) / dpi), dpi=dpi,
                                facecolor="white")
        self.canvas = FigureCanvasAgg(fig)
        k = float(np.clip(min(width, height) / dpi / 8.0, 0.45, 3.0))   # text and line scale
        title_px = 14 * k * dpi / 72
        top = 1 - 2.0 * title_px / height
        pad = 6 * k / 72 * dpi
        fig.text(0.5, 1 - 0.5 * title_px / height, pb.name, ha="center", va="top", fontsize=14 * k,
                 fontweight="bold")
        box = (pad / width, pad / height, 1 - 2 * pad / width, top - pad / height)
        self.ax = ax = fig.add_axes(box)
        # the bounds widened one way to the axes' shape, so that equal scales fill the frame
        x0, x1, y0, y1 = pb.bounds()
        cx, cy, dx, dy = (x0 + x1) / 2, (y0 + y1) / 2, x1 - x0, y1 - y0
        shape = (box[3] * height) / (box[2] * width)
        dx, dy = max(dx, dy / shape), max(dy, dx * shape)
        ax.set_xlim(cx - dx / 2, cx + dx / 2)
        ax.set_ylim(cy - dy / 2, cy + dy / 2)
        ax.set_aspect("equal", adjustable="box")
        ax.set_xticks([])
        ax.set_yticks([])
        for sp in ax.spines.values():
            sp.set_color("0.8")
            sp.set_linewidth(0.8 * k)
        # static: the target figure and where the skater rests
        if pb.figure:
            xs = np.concatenate([np.append(p[0], np.nan) for p in pb.figure])
            ys = np.concatenate([np.append(p[1], np.nan) for p in pb.figure])
            ax.plot(xs, ys, "-", color=_TARGET, lw=4.5 * k, solid_capstyle="round", zorder=1)
        ax.plot(pb.rests[0], pb.rests[1], "o", mfc="white", mec=_REST, mew=1.0 * k, ms=5.5 * k, zorder=3)
        unit = "m" if pb.unit == "m" else "model units"
        reach = "   dashed: reach" if isinstance(pb.summary.get("reach"), (int, float)) else ""
        ax.text(0.015, 0.012, f"grey: target   blue: blade   orange: mass   circles: rests{reach} ({unit})",
                transform=ax.transAxes, fontsize=7.5 * k, color="0.45", ha="left", va="bottom")
        # moving
        self.trace_t, self.trace_x, self.trace_y = m.trace_path(_TRACE_SAMPLES)
        self.trace, = ax.plot([], [], "-", color=_TRACE, lw=1.7 * k, zorder=2, solid_joinstyle="round")
        self.passed, = ax.plot([], [], "o", color=_PASSED, ms=5.5 * k, mec=_PASSED, zorder=3.5)
        self.trail = LineCollection([], linewidths=2.2 * k, zorder=5, capstyle="butt")
        ax.add_collection(self.trail, autolim=False)
        self.trail_rgba = np.tile(to_rgba(_MASS), (_TRAIL_SAMPLES - 1, 1))
        self.trail_alpha = np.linspace(0.0, 0.85, _TRAIL_SAMPLES - 1) ** 1.5
        self.link, = ax.plot([], [], "-", color=_LINK, lw=0.9 * k, zorder=4)
        # the planner's reach: a dashed circle around the contact point that the mass stays inside
        reach = pb.summary.get("reach")
        self.reach = None
        if isinstance(reach, (int, float)) and math.isfinite(reach) and reach > 0:
            self.reach = Circle((0.0, 0.0), float(reach), fill=False, ls=(0, (4, 3)), lw=1.0 * k, color=_MASS,
                                alpha=0.7, zorder=4)
            ax.add_patch(self.reach)
        self.mass, = ax.plot([], [], "o", color=_MASS, ms=10 * k, mec="0.15", mew=0.8 * k, zorder=6)
        self.skate, = ax.plot([], [], "-", color=_SKATE, lw=3.2 * k, solid_capstyle="butt", zorder=7)
        self.toe, = ax.plot([], [], "o", color=_TOE, ms=3.6 * k, mec="none", zorder=8)
        text = dict(transform=ax.transAxes, fontsize=11 * k, va="top", family="monospace", zorder=9)
        self.clock = ax.text(0.015, 0.985, "", ha="left", **text)
        self.section = ax.text(0.985, 0.985, "", ha="right", **text)
        self.moving = sorted([self.trace, self.passed, self.trail, self.link, self.mass, self.skate, self.toe,
                              self.clock, self.section] + ([self.reach] if self.reach is not None else []),
                             key=lambda a: a.get_zorder())
        # 4% of the figure, but never shorter than 3% of the picture (the mass may roam far from the figure)
        self.half = 0.5 * max(_SKATE_FRACTION * _figure_size(pb), _SKATE_MIN_FRACTION * max(dx, dy))
        self.trail_span = min(options.trail, _TRAIL_CAP * self.video_seconds) * (m.t1 - m.t0) / self.video_seconds
        # enough decimals that the clock changes from one frame to the next
        step = (m.t1 - m.t0) / max(options.frames(pb) - 1, 1)
        self.decimals = int(np.clip(math.ceil(-math.log10(step)) if step > 0 else 1, 1, 4))
        self.n_sections = int(pb.section.max()) + 1 if pb.section.size else 1
        self._background = None

    # -- state

    def update(self, time: float) -> None:
        m, pb = self.motion, self.pb
        time = float(np.clip(time, m.t0, m.t1))
        x, y, th, mx, my = (float(v[0]) for v in m.pose(np.array([time])))
        k = int(np.searchsorted(self.trace_t, time, side="right"))
        self.trace.set_data(np.append(self.trace_x[:k], x), np.append(self.trace_y[:k], y))
        done = pb.rest_times <= time + 1e-12 * max(1.0, abs(time))
        self.passed.set_data(pb.rests[0][done], pb.rests[1][done])
        c, s = math.cos(th), math.sin(th)
        self.skate.set_data([x - self.half * c, x + self.half * c], [y - self.half * s, y + self.half * s])
        self.toe.set_data([x + self.half * c], [y + self.half * s])
        self.mass.set_data([mx], [my])
        self.link.set_data([x, mx], [y, my])
        if self.reach is not None:
            self.reach.set_center((x, y))
        if self.trail_span > 0 and time > m.t0:
            ts = np.linspace(max(m.t0, time - self.trail_span), time, _TRAIL_SAMPLES)
            _, _, _, tx, ty = m.pose(ts)
            pts = np.column_stack([tx, ty])
            segs = np.stack([pts[:-1], pts[1:]], axis=1)
            piece = m.mass_piece(ts)
            rgba = self.trail_rgba.copy()
            rgba[:, 3] = np.where(piece[:-1] == piece[1:], self.trail_alpha, 0.0)
            self.trail.set_segments(segs)
            self.trail.set_color(rgba)
        else:
            self.trail.set_segments([])
        elapsed = time - m.t0
        self.clock.set_text(f"t = {elapsed:.{self.decimals}f} {'s' if pb.unit == 'm' else '(model time)'}")
        sec = int(pb.section[m.rows(np.array([time]))[0]]) + 1
        self.section.set_text(f"section {sec}/{self.n_sections}")

    def frame_time(self, index: int, frames: int) -> float:
        m = self.motion
        return m.t0 + (m.t1 - m.t0) * (index / (frames - 1) if frames > 1 else 0.0)

    # -- pixels

    def rgba(self) -> memoryview:
        """The current frame as RGBA bytes (height x width x 4), drawing only the moving artists."""
        canvas = self.canvas
        if self._background is None:
            for a in self.moving:
                a.set_visible(False)
            canvas.draw()
            self._background = canvas.copy_from_bbox(self.fig.bbox)
            for a in self.moving:
                a.set_visible(True)
        canvas.restore_region(self._background)
        for a in self.moving:
            self.ax.draw_artist(a)
        return canvas.buffer_rgba()

    def rgb(self) -> np.ndarray:
        buf = np.asarray(self.rgba())
        return np.array(buf[:, :, :3])


def _check_time(pb: Playback, time) -> float:
    """``time`` on the playback's clock, which must be within it (a frame is never drawn at another time)."""
    t0, t1 = float(pb.t[0]), float(pb.t[-1])
    if time is None:
        return t0 + 0.6 * (t1 - t0)
    try:
        time = float(time)
    except (TypeError, ValueError):
        raise ValueError(f"time must be a number, got {time!r}") from None
    if not math.isfinite(time):
        raise ValueError(f"time must be finite, got {time!r}")
    slack = 5e-6 * max(1.0, abs(t0), abs(t1))  # what printing the range to 6 digits may round
    if not t0 - slack <= time <= t1 + slack:
        raise ValueError(f"time {time:g} is outside the figure's clock: give a time from {t0:.6g} to {t1:.6g}")
    return min(max(time, t0), t1)


def render_frame(playback: Playback, time: float | None = None,
                 options: AnimationOptions = AnimationOptions()) -> Figure:
    """The animation's frame at a time, as a matplotlib figure (not attached to pyplot).

    Parameters
    ----------
    playback : Playback
    time : float or None
        Time on the playback's clock (``playback.t``), within its range; ``None``: 60% of the way
        through.
    options : AnimationOptions
        Size, dpi and trail (the trail's length depends on the video's duration).

    Returns
    -------
    matplotlib.figure.Figure
        With an Agg canvas: ``fig.savefig(...)`` works.

    Raises
    ------
    ValueError
        A time that is not a number or lies outside the playback's clock (the message gives its range).
    """
    scene = _Scene(playback, options, *options.size_px)
    scene.update(_check_time(playback, time))
    return scene.fig


def render_rgb(playback: Playback, time: float | None = None,
               options: AnimationOptions = AnimationOptions()) -> np.ndarray:
    """The animation's frame at a time as an RGB array of shape ``(height, width, 3)``, dtype uint8.

    See :func:`render_frame` for the parameters.
    """
    scene = _Scene(playback, options, *options.size_px)
    scene.update(_check_time(playback, time))
    return scene.rgb()


# ----------------------------------------------------------------------------------------------------------
# Writing files


class _GifWriter(PillowWriter):
    """Pillow's GIF writer fed with the scene's blitted frames, each reduced to one shared palette."""

    def __init__(self, scene: _Scene, **kwargs) -> None:
        super().__init__(**kwargs)
        self.scene = scene
        self._palette = None

    def grab_frame(self, **savefig_kwargs):
        s = self.scene
        im = Image.frombuffer("RGBA", (s.width, s.height), bytes(s.rgba()), "raw", "RGBA", 0, 1).convert("RGB")
        if self._palette is None:
            self._palette = self._make_palette()
        self._frames.append(im.quantize(palette=self._palette, dither=Image.Dither.NONE))

    def finish(self):
        # Hand the frames to Pillow one by one, letting go of each: Pillow keeps its own copies.
        frames, self._frames = self._frames, []

        def rest():
            for i in range(1, len(frames)):
                frame, frames[i] = frames[i], None
                yield frame

        frames[0].save(self.outfile, format="GIF", save_all=True, append_images=rest(),
                       duration=int(1000 / self.fps), loop=0)

    def _make_palette(self) -> Image.Image:
        """A palette from a sample frame late in the figure, where every colour of the scene is drawn."""
        s = self.scene   # (each frame updates every moving artist: no need to put the scene back)
        s.update(s.motion.t0 + 0.75 * (s.motion.t1 - s.motion.t0))
        sample = Image.frombuffer("RGBA", (s.width, s.height), bytes(s.rgba()), "raw", "RGBA", 0, 1)
        colors = np.array(sample.convert("RGB").quantize(colors=256, method=Image.Quantize.MEDIANCUT,
                                                         dither=Image.Dither.NONE).getpalette(), dtype=np.uint8)
        colors = colors.reshape(-1, 3)
        # The background exactly white: the median cut may average it with near-whites, and Pillow maps
        # colours through a cache of small boxes, where a near-white may take white's place. So: make the
        # entry nearest white white, then whiten whatever white still maps to.
        colors[np.argmin(np.abs(colors.astype(int) - 255).sum(axis=1))] = 255
        palette = Image.new("P", (1, 1))
        white = Image.new("RGB", (1, 1), (255, 255, 255))
        for _ in range(len(colors)):
            palette.putpalette(np.concatenate([colors.ravel(), np.zeros(768 - colors.size, np.uint8)]).tolist())
            index = white.quantize(palette=palette, dither=Image.Dither.NONE).getpixel((0, 0))
            if colors[index].min() == 255:
                break
            colors[index] = 255
        return palette


class _MP4Writer(FFMpegWriter):
    """ffmpeg's H.264 writer fed with the scene's blitted frames (raw RGBA down the pipe)."""

    def __init__(self, scene: _Scene, **kwargs) -> None:
        super().__init__(**kwargs)
        self.scene = scene

    def grab_frame(self, **savefig_kwargs):
        self._proc.stdin.write(self.scene.rgba())


def _ffmpeg_exe() -> str:
    try:
        import imageio_ffmpeg
    except ImportError:
        raise SkatetraceError("writing MP4 needs the imageio-ffmpeg package (pip install imageio-ffmpeg); "
                              "or write a .gif") from None
    try:
        return imageio_ffmpeg.get_ffmpeg_exe()
    except RuntimeError as exc:
        raise SkatetraceError(f"no ffmpeg binary found for writing MP4: {exc}") from None


def _target(path) -> tuple[Path, str]:
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in SUFFIXES:
        raise ValueError(f"cannot write an animation to {str(path)!r}: the file name must end in "
                         f"{' or '.join(SUFFIXES)} (got {path.suffix or 'no suffix'!r}); one frame is written "
                         f"as {' or '.join(STILL_SUFFIXES)} by save_still")
    if not path.parent.is_dir():
        raise SkatetraceError(f"cannot write {path}: folder {path.parent} does not exist")
    return path, suffix


def animate(playback: Playback, path, options: AnimationOptions = AnimationOptions(),
            progress: Callable[[int, int], None] | None = None) -> AnimationResult:
    """Write an animation of a traced figure to a GIF or MP4 file.

    Parameters
    ----------
    playback : Playback
        From :func:`skatetrace.outputs.playback.load_playback`.
    path : str or Path
        Output file, ending in ``.gif`` (Pillow) or ``.mp4`` (ffmpeg from ``imageio-ffmpeg``, H.264,
        yuv420p). Written to a temporary file in the same folder and renamed when complete.
    options : AnimationOptions
    progress : callable, optional
        Called as ``progress(done, total)`` after each frame is drawn (``done`` from 1 to ``total``).

    Returns
    -------
    AnimationResult

    Raises
    ------
    ValueError
        A suffix other than ``.gif`` or ``.mp4``.
    SkatetraceError
        The output folder does not exist, or no ffmpeg for MP4.
    """
    start = _time.perf_counter()
    path, suffix = _target(path)
    width, height = options.size_px
    if suffix == ".mp4":
        width, height = width + width % 2, height + height % 2
    frames = options.frames(playback)
    scene = _Scene(playback, options, width, height)
    fps = float(options.fps)

    def run(writer, tmp: Path) -> None:
        with writer.saving(scene.fig, str(tmp), options.dpi):
            for i in range(frames):
                scene.update(scene.frame_time(i, frames))
                writer.grab_frame()
                if progress is not None:
                    progress(i + 1, frames)

    if suffix == ".gif":
        def write(tmp: Path) -> None:
            run(_GifWriter(scene, fps=fps), tmp)
    else:
        exe = _ffmpeg_exe()

        def write(tmp: Path) -> None:
            writer = _MP4Writer(scene, fps=fps, codec="libx264",
                                extra_args=["-pix_fmt", "yuv420p", "-preset", "fast", "-tune", "animation",
                                            "-crf", "20", "-movflags", "+faststart"])
            with matplotlib.rc_context({"animation.ffmpeg_path": exe}):
                run(writer, tmp)

    write_atomically(path, write)
    return AnimationResult(path=path, frames=frames, width=width, height=height, fps=fps,
                           seconds_elapsed=_time.perf_counter() - start)


def save_still(playback: Playback, path, time: float | None = None,
               options: AnimationOptions = AnimationOptions()) -> Path:
    """Write the animation's frame at a time to a PNG (e.g. for a README).

    Parameters
    ----------
    playback : Playback
    path : str or Path
        Output file ending in ``.png``; written atomically.
    time : float or None
        Time on the playback's clock; ``None``: 60% of the way through.
    options : AnimationOptions

    Returns
    -------
    Path
    """
    path = Path(path)
    if path.suffix.lower() not in STILL_SUFFIXES:
        raise ValueError(f"a still is written as PNG: the file name must end in .png, got {str(path)!r} (an "
                         f"animation, {' or '.join(SUFFIXES)}, is written by animate)")
    if not path.parent.is_dir():
        raise SkatetraceError(f"cannot write {path}: folder {path.parent} does not exist")
    rgb = render_rgb(playback, time, options)
    write_atomically(path, lambda tmp: Image.fromarray(rgb).save(tmp, format="PNG"))
    return path
