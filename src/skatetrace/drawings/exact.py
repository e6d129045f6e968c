"""Exact mode: a drawing's smooth runs as curvature splines (cubic curvature in arc length).

The engine traces exactly any curve whose signed curvature is a cubic polynomial of arc length on
each piece (:class:`~skatetrace.figures.geometry.Spiral`), as well as arcs and lines
(:class:`~skatetrace.figures.geometry.Segment`). This module turns a :class:`~skatetrace.drawings.curves.Path` into
such pieces, without the arc approximation of :mod:`skatetrace.drawings.fitting`:

1. The path is cut into tangent-continuous *runs* and spiral *spans* exactly as for arc fitting
   (:func:`skatetrace.drawings.fitting.split_path`).
2. A span of constant curvature ("arc" or "line") becomes one Segment of the span's curvature and
   length. A "spiral" span becomes a chain of Spirals: its curvature kappa(s) is sampled at knots
   uniform in arc length s (arc length of the source by adaptive 5-point Gauss-Legendre, knots
   found by inverting s(t) with safeguarded Newton steps to rounding) and interpolated by a
   not-a-knot cubic spline; each spline interval is one Spiral. Curvature is therefore continuous,
   with a continuous derivative, inside a span; it may jump where spans of different source pieces
   meet (a G1 join of two Béziers, say), as it does on the source. Two refinements of that rule:
   a spline through points (:class:`~skatetrace.drawings.curves.SplinePiece`, whose curvature or its slope
   jumps at the data points) has its spans cut at its breakpoints too; and at a cusp end of a span,
   where the curvature is unbounded, the end interval is not interpolated but continues the spline
   (two derivatives) with the source's exact turn over it.
3. Each run is laid out piece after piece with :func:`skatetrace.figures.geometry.travel` from its start
   pose: the first run from the source's start point and direction, every later run from the end
   of the previous run's layout with the source's direction after the corner, as a figure's cusp
   join places it. The laid-out curve is what :func:`figure_from_exact` hands to the engine.

Deviation. For each run, ``X_exact(s)`` (the layout) and ``X_src(s)`` (the source at arc length
``s`` from the run's start) are both unit-speed curves over the same length, so every point of either
is within ``e(s) = |X_exact(s) - X_src(s)|`` of the other: ``sup_s e(s)`` is an upper bound of the
Hausdorff distance between them. ``e`` is Lipschitz with constant at most the heading difference
``|dtheta(s)|`` (``|u - v| <= |angle(u, v)|`` for unit vectors), so with ``e`` and ``dtheta``
sampled at spacing ``g_i`` (at least 16 samples per piece) the reported ``deviation`` is
``max_i e_i + g_i * max(|dtheta_i|, |dtheta_{i+1}|)``. It is a measured bound, not a certificate:
it relies on the heading difference varying little between samples (it changes by a tiny fraction
of itself there) and on quadrature and rounding of order 1e-15 of the size. Errors carry forward
along a run, so the bound measures the laid-out figure, not each piece on its own.

Refinement. A spiral span starts with ``max(2, ceil(|turn| / 0.25), ceil(8 L_span / L_run))``
intervals. While a run's deviation exceeds its share of ``tol`` (``tol`` times the fraction of the
path's length up to the run's end, so that the start offset carried into later runs leaves them
room), the spans that contribute most (their own heading error integrated over the span, plus the
heading error at their end times the rest of the run) get their intervals doubled. The error of
a smooth span falls like ``h^4`` in the knot spacing ``h`` (only like ``sqrt(h)`` next to a cusp).
Refinement stops before ``max_pieces`` (``MAX_PIECES``) pieces per path, or when more knots stop
helping: what remains comes from arcs, lines, kinks within ``corner_tol_deg`` or a carried offset,
the deviation is down to rounding (``ROUNDING`` of the size or coordinates), or it stopped falling
(curvature noise of a finite-difference piece). If the deviation is then above ``tol`` the fit fails
with a message naming the path, the bound and ``tol``, and keeps the best layout found (no exception).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import Enum
from typing import NamedTuple, Sequence

import numpy as np
from scipy.interpolate import CubicSpline

from .corners import _wrap, corner_join
from .curves import AffinePiece, Drawing, Path, Piece, SplinePiece, _gl_lengths, _noisy, curvature
from ..errors import FitError
from ..figures.figure import Figure, Join
from .fitting import _check_tol
from .spirals import Span
from .splitting import Run, _direction, _split
from .to_figure import _check_reverse, _figure_curves
from ..figures.geometry import Pose, Segment, Spiral, end_pose, shifted_polynomial, travel

__all__ = [
    "MAX_PIECES", "ExactStatus", "ExactWhere", "ExactRun", "ExactPathFit", "ExactDrawingFit", "fit_exact_path",
    "fit_exact_drawing", "figure_from_exact",
]

MAX_PIECES = 20_000  # pieces per path before refinement gives up
SAMPLES = 16  # deviation samples per piece (per half radian of turn, for long arcs)
START_TURN = 0.25  # radians of turn per spline interval to start with
START_DENSITY = 8  # spline intervals per run length to start with
ROUNDING = 1e-14  # relative to the larger of the size and the coordinates: a deviation this small is rounding

_TWO_PI = 2.0 * math.pi


class ExactStatus(Enum):
    """Outcome of an exact-mode fit; the value is the message."""

    SUCCESS = "every run is within the tolerance (measured)"
    PIECE_LIMIT = "the curvature spline reached the piece limit before the deviation was within the tolerance"
    UNREFINABLE = "more spline knots no longer reduce the deviation"


class ExactWhere(NamedTuple):
    """Where the largest sampled distance was found: the source point ``(x, y)`` and its run."""

    x: float
    y: float
    run: int


@dataclass(frozen=True, slots=True, kw_only=True)
class ExactRun:
    """One run of a path as Segments and Spirals laid out tangentially from ``start``.

    Attributes
    ----------
    start : Pose
        Start point and travel direction of the layout.
    pieces : tuple of Segment or Spiral
        Laid out one after the other with :func:`skatetrace.figures.geometry.end_pose`.
    corner : float or None
        As :attr:`skatetrace.drawings.fitting.Run.corner`, recomputed from the laid-out directions: the signed
        turn of travel direction at the corner before this run.
    deviation : float
        Measured upper bound of ``sup_s |X_exact(s) - X_src(s)|`` over the run (see the module
        docstring), hence of the Hausdorff distance between the layout and the run of source curve.
    sampled : float
        Largest sampled ``|X_exact(s) - X_src(s)|``.
    curve_length : float
        Length of the run of source curve (the pieces have the same total length, up to rounding).
    """

    start: Pose
    pieces: tuple
    corner: float | None
    deviation: float
    sampled: float
    curve_length: float

    @property
    def length(self) -> float:
        return float(sum(p.length for p in self.pieces))

    def poses(self) -> list[Pose]:
        """Start pose of every piece, then the end pose (``len(pieces) + 1`` poses)."""
        out = [self.start]
        for p in self.pieces:
            out.append(end_pose(out[-1], p))
        return out

    def join(self, reverse_above_deg: float = 90.0) -> Join | None:
        """The figure join at the corner before this run; see :func:`skatetrace.drawings.fitting.corner_join`."""
        return corner_join(self.corner, reverse_above_deg)


@dataclass(frozen=True, slots=True, kw_only=True)
class ExactPathFit:
    """A path as curvature splines, one G1 chain of Segments and Spirals per run.

    Attributes
    ----------
    success, status, message
        ``success`` is every run's ``deviation <= tol``; otherwise ``message`` names the path, the bound
        reached and ``tol``.
    runs : tuple of ExactRun
        On failure, the best layout found (every run present).
    deviation : float
        Largest run deviation (measured upper bound of the Hausdorff distance to the path).
    sampled : float
        Largest sampled distance.
    where : ExactWhere or None
        Where ``sampled`` was found.
    n_spirals, n_arcs, n_lines : int
    curve_length, length : float
        Length of the source path (as split) and of the pieces.
    tol, closed, name, size
        ``size`` is the larger side of the path's bounding box.
    """

    success: bool
    status: ExactStatus
    message: str
    runs: tuple[ExactRun, ...]
    deviation: float
    sampled: float
    where: ExactWhere | None
    n_spirals: int
    n_arcs: int
    n_lines: int
    curve_length: float
    length: float
    tol: float
    closed: bool
    name: str
    size: float

    @property
    def n_pieces(self) -> int:
        return self.n_spirals + self.n_arcs + self.n_lines


@dataclass(frozen=True, slots=True, kw_only=True)
class ExactDrawingFit:
    """Every path of a drawing in exact mode; the deviation and counts are over all paths."""

    success: bool
    message: str
    paths: tuple[ExactPathFit, ...]
    deviation: float
    n_spirals: int
    n_arcs: int
    n_lines: int
    worst_path: int
    name: str = ""

    @property
    def status(self) -> ExactStatus:
        bad = [p.status for p in self.paths if not p.success]
        return bad[0] if bad else ExactStatus.SUCCESS


# --------------------------------------------------------------------------------------------------
# One span of source curve: arc length, its inverse, and its pieces
# --------------------------------------------------------------------------------------------------


def _clean(c) -> tuple[float, float, float, float]:
    out = tuple(float(v) for v in c)
    return out if all(math.isfinite(v) for v in out) else (0.0, 0.0, 0.0, 0.0)


def _wrap_array(a: np.ndarray) -> np.ndarray:
    return np.remainder(a + math.pi, _TWO_PI) - math.pi


class _Samples(NamedTuple):
    sigs: tuple[np.ndarray, ...]  # per piece: arc lengths from the piece's start
    s: np.ndarray  # all samples: arc length from the span's start
    x: np.ndarray  # source point and travel direction there
    y: np.ndarray
    heading: np.ndarray


class _SpanGeom:
    """A span of one source piece parametrised by arc length."""

    def __init__(self, piece: Piece, span: Span, where: str):
        self.piece, self.span = piece, span
        self.t_tab, self.s_tab = self._table()
        self.length = float(self.s_tab[-1])
        if not (math.isfinite(self.length) and self.length >= 0):
            raise FitError(f"{where}: piece {span.piece} has non-finite arc length on [{span.t0}, {span.t1}]")
        self.turn = self._turn()
        self.piecewise = _breakpoints(piece).size > 0
        self.cusps = (False, False) if not self.spiral else (self._cusp_end(span.t0), self._cusp_end(span.t1))
        self._pieces: dict[int, tuple] = {}
        self._samples: dict[int, _Samples] = {}

    def _table(self) -> tuple[np.ndarray, np.ndarray]:
        """Breakpoints in ``t`` and arc lengths to them, adaptive so that each length is exact to rounding."""
        piece, a, b = self.piece, self.span.t0, self.span.t1
        edges = np.linspace(a, b, 65)
        lo, hi = edges[:-1], edges[1:]
        total = float(np.sum(_gl_lengths(piece, lo, hi)))
        done_t, done_len = [], []
        for _ in range(30):
            mid = 0.5 * (lo + hi)
            whole = _gl_lengths(piece, lo, hi)
            left, right = _gl_lengths(piece, lo, mid), _gl_lengths(piece, mid, hi)
            halves = left + right
            ok = (np.abs(whole - halves) <= 1e-13 * halves + 1e-16 * total) | ~np.isfinite(halves)
            ok |= (hi - lo) <= 1e-12 * (b - a)
            done_t += [lo[ok], mid[ok]]
            done_len += [left[ok], right[ok]]
            if np.all(ok) or lo.size > 1 << 15:
                done_t += [lo[~ok], mid[~ok]]
                done_len += [left[~ok], right[~ok]]
                break
            lo, hi = np.concatenate([lo[~ok], mid[~ok]]), np.concatenate([mid[~ok], hi[~ok]])
        t = np.concatenate(done_t)
        ln = np.concatenate(done_len)
        order = np.argsort(t, kind="stable")
        t_tab = np.append(t[order], b)
        s_tab = np.concatenate([[0.0], np.cumsum(ln[order])])
        return t_tab, s_tab

    def _turn(self) -> float:
        """Total signed turn of the span (integral of the curvature), by Gauss-Legendre on the table."""
        x, w = np.polynomial.legendre.leggauss(5)
        lo, hi = self.t_tab[:-1], self.t_tab[1:]
        tt = (0.5 * (lo + hi))[:, None] + (0.5 * (hi - lo))[:, None] * x[None, :]
        d1, d2 = self.piece.d1(tt.ravel()), self.piece.d2(tt.ravel())
        with np.errstate(all="ignore"):
            k = (d1[0] * d2[1] - d1[1] * d2[0]) / (d1[0] ** 2 + d1[1] ** 2)
        k = np.where(np.isfinite(k), k, 0.0).reshape(tt.shape)
        return float(np.sum(0.5 * (hi - lo) * (k @ w)))

    def t_at(self, s) -> np.ndarray:
        """Parameter ``t`` at arc lengths ``s`` from the span's start (safeguarded Newton, to rounding)."""
        s = np.clip(np.asarray(s, dtype=float), 0.0, self.length)
        tt, ss = self.t_tab, self.s_tab
        j = np.clip(np.searchsorted(ss, s, side="right") - 1, 0, tt.size - 2)
        lo, hi = tt[j].copy(), tt[j + 1].copy()
        t = np.clip(np.interp(s, ss, tt), lo, hi)
        tol_s = 1e-15 * max(self.length, 1e-300)
        active = np.ones(s.size, dtype=bool)
        for _ in range(60):
            idx = np.nonzero(active)[0]
            if idx.size == 0:
                break
            ti = t[idx]
            f = ss[j[idx]] + _gl_lengths(self.piece, tt[j[idx]], ti) - s[idx]
            d = self.piece.d1(ti)
            sp = np.hypot(d[0], d[1])
            lo[idx] = np.where(f < 0, ti, lo[idx])
            hi[idx] = np.where(f > 0, ti, hi[idx])
            with np.errstate(all="ignore"):
                tn = ti - f / sp
            bad = ~np.isfinite(tn) | (tn < lo[idx]) | (tn > hi[idx])
            tn = np.where(bad, 0.5 * (lo[idx] + hi[idx]), tn)
            conv = (np.abs(f) <= tol_s) | ~np.isfinite(f)
            t[idx] = np.where(conv, ti, tn)
            small = np.abs(tn - ti) <= 4e-16 * np.maximum(np.abs(ti), 1.0)
            active[idx] = ~conv & ~small & (hi[idx] - lo[idx] > 4e-16 * np.maximum(np.abs(hi[idx]), 1.0))
        return t

    def source(self, s: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Source points and travel directions at arc lengths ``s`` from the span's start."""
        t = self.t_at(s)
        p, d = self.piece.point(t), self.piece.d1(t)
        heading = np.arctan2(d[1], d[0])
        bad = ~(np.hypot(d[0], d[1]) > 0)
        if self.cusps[0]:  # the limit direction at a cusp end (r' there is zero, or rounding)
            heading = np.where(t == self.span.t0, self.span.heading0, heading)
        if self.cusps[1]:
            heading = np.where(t == self.span.t1, self.span.heading1, heading)
        for i in np.nonzero(bad)[0]:  # a cusp end: the limit direction
            side = +1 if t[i] - self.span.t0 <= self.span.t1 - t[i] else -1
            v = _direction(self.piece, float(t[i]), side, max(self.length, 1e-300), True)
            heading[i] = (self.span.heading0 if side > 0 else self.span.heading1) if v is None \
                else math.atan2(v[1], v[0])
        return p[0], p[1], heading

    @property
    def spiral(self) -> bool:
        return self.span.kind == "spiral" and self.length > 0

    def _cusp_end(self, t: float) -> bool:
        """Whether the speed vanishes at this end (a cusp): the curvature is unbounded there."""
        d1, d2 = self.piece.d1(t), self.piece.d2(t)
        sp, n2 = math.hypot(d1[0, 0], d1[1, 0]), math.hypot(d2[0, 0], d2[1, 0])
        mean = self.length / max(self.span.t1 - self.span.t0, 1e-300)
        return not (sp > 1e-6 * mean) or not math.isfinite(float(curvature(self.piece, t)[0])) or \
            (n2 > 0 and sp * sp <= 1e-6 * self.length * n2)

    def initial(self, run_length: float) -> int:
        if not self.spiral:
            return 1
        n0 = 2 + self.cusps[0] + self.cusps[1]  # a cusp end's interval is not part of the spline
        return int(max(n0, math.ceil(abs(self.turn) / START_TURN), math.ceil(self.length / run_length * START_DENSITY)))

    def pieces(self, n: int) -> tuple:
        """The span as one Segment, or as ``n`` Spirals of a not-a-knot cubic spline of curvature.

        At a cusp end the curvature is unbounded (like ``1 / sqrt(s)``) and is not a knot: the spline
        covers the other intervals, and the end interval is a cubic that continues it with two
        continuous derivatives and turns by exactly the source's turn over that interval.
        """
        if n not in self._pieces:
            L = self.length
            if L <= 0:
                out: tuple = ()
            elif not self.spiral:
                k = 0.0
                if self.span.kind == "arc":
                    k = float(curvature(self.piece, self.t_at(np.array([0.5 * L])))[0])
                    k = k if math.isfinite(k) else 0.0
                out = (Segment(k, L),)
            else:
                out = self._spline(n)
            self._pieces[n] = out
        return self._pieces[n]

    def _spline(self, n: int) -> tuple:
        L, (c0, c1) = self.length, self.cusps
        n = max(n, 2 + c0 + c1)
        s = np.linspace(0.0, L, n + 1)
        t = self.t_at(s)
        t[0], t[-1] = self.span.t0, self.span.t1
        if self.piecewise:  # a spline piece evaluates its right-hand polynomial at a breakpoint: stay inside
            w = self.span.t1 - self.span.t0
            t[0] += min(max(1e-13 * w, 4.0 * np.spacing(abs(t[0]))), 0.25 * w)
            t[-1] -= min(max(1e-13 * w, 4.0 * np.spacing(abs(t[-1]))), 0.25 * w)
        lo, hi = int(c0), n - int(c1)  # knots lo..hi carry the spline
        with np.errstate(all="ignore"):
            k = np.asarray(curvature(self.piece, t[lo:hi + 1]), dtype=float)
        fin = np.isfinite(k)
        if not np.all(fin):
            k = np.interp(s[lo:hi + 1], s[lo:hi + 1][fin], k[fin]) if np.any(fin) else np.zeros_like(k)
        spl = CubicSpline(s[lo:hi + 1], k, bc_type="not-a-knot")
        c = spl.c  # highest power first, in s - s_i
        out = [Spiral((float(c[3, i]), float(c[2, i]), float(c[1, i]), float(c[0, i])), float(s[lo + i + 1] - s[lo + i]))
               for i in range(hi - lo)]
        if c0:
            h = float(s[1])
            turn = self._turn_between(self.span.heading0, t[1], +1)
            a, b, cc = (float(spl(s[1], nu)) for nu in range(3))
            d = 4.0 * (turn - a * h + b * h * h / 2.0 - cc / 2.0 * h ** 3 / 3.0) / h ** 4
            # kappa(h - u) = a - b u + cc/2 u^2 + d u^3, written in sigma = h - u
            out.insert(0, Spiral(_clean(shifted_polynomial((a, -b, cc / 2.0, d), h, -1.0)), h))
        if c1:
            h = float(L - s[-2])
            turn = self._turn_between(self.span.heading1, t[-2], -1)
            a, b, cc = (float(spl(s[-2], nu)) for nu in range(3))
            d = 4.0 * (turn - a * h - b * h * h / 2.0 - cc / 2.0 * h ** 3 / 3.0) / h ** 4
            out.append(Spiral(_clean((a, b, cc / 2.0, d)), h))
        return tuple(out)

    def _turn_between(self, cusp_heading: float, t: float, side: int) -> float:
        """Signed turn of the source from a cusp end (``side`` +1: the start) to ``t`` (or back)."""
        d1 = self.piece.d1(float(t))[:, 0]
        other = math.atan2(d1[1], d1[0])
        return _wrap(other - cusp_heading) if side > 0 else _wrap(cusp_heading - other)

    def samples(self, n: int) -> _Samples:
        """Deviation samples of the span cut into ``n`` pieces, with the source there."""
        if n not in self._samples:
            sigs, ss, off = [], [], 0.0
            for p in self.pieces(n):
                m = SAMPLES * max(1, math.ceil(abs(p.turn) / 0.5))
                sig = np.linspace(0.0, p.length, m + 1)
                sigs.append(sig)
                ss.append(off + sig)
                off += p.length
            s = np.concatenate(ss) if ss else np.zeros(0)
            x, y, h = self.source(s) if s.size else (s, s, s)
            self._samples[n] = _Samples(tuple(sigs), s, x, y, h)
        return self._samples[n]


# --------------------------------------------------------------------------------------------------
# One run: layout, deviation, refinement
# --------------------------------------------------------------------------------------------------


class _Eval(NamedTuple):
    pieces: tuple
    end: Pose
    deviation: float
    sampled: float
    where: tuple[float, float]
    offset: float  # distance of the layout's start from the source's
    own: np.ndarray  # per span: its contribution to the deviation (heading error, integrated)
    fixed: float  # contributions no refinement removes: kinks at smooth joins, arcs and lines, offset


def _breakpoints(piece: Piece) -> np.ndarray:
    """Parameters in ``(0, 1)`` where a piecewise-polynomial piece (a spline through points) changes polynomial."""
    if isinstance(piece, AffinePiece):
        return _breakpoints(piece.base)
    x = getattr(getattr(piece, "spline", None), "x", None) if isinstance(piece, SplinePiece) else None
    if x is None or piece.u1 == piece.u0:
        return np.zeros(0)
    t = (np.asarray(x, dtype=float) - piece.u0) / (piece.u1 - piece.u0)
    return np.unique(t[(t > 0.0) & (t < 1.0)])


def _subspans(piece: Piece, span: Span) -> list[Span]:
    """A spiral span cut at the piece's own breakpoints, where its curvature (or its derivative) may jump."""
    if span.kind != "spiral":
        return [span]
    w = span.t1 - span.t0
    cuts = [float(t) for t in _breakpoints(piece) if span.t0 + 1e-9 * w < t < span.t1 - 1e-9 * w]
    if not cuts:
        return [span]
    out, t_prev, h_prev = [], span.t0, span.heading0
    for t in cuts:
        d = piece.d1(t)[:, 0]
        h = math.atan2(d[1], d[0]) if math.hypot(d[0], d[1]) > 0 else h_prev
        out.append(span._replace(t0=t_prev, t1=t, heading0=h_prev, heading1=h))
        t_prev, h_prev = t, h
    out.append(span._replace(t0=t_prev, heading0=h_prev, reason="join"))
    out[1:-1] = [sp._replace(reason="join") for sp in out[1:-1]]
    return out


class _RunGeom:
    def __init__(self, pieces: Sequence[Piece], run: Run, where: str):
        self.run = run
        self.spans = [_SpanGeom(pieces[sp.piece], sub, where) for sp in run.spans
                      for sub in _subspans(pieces[sp.piece], sp)]
        self.length = float(sum(g.length for g in self.spans))
        self.noisy = any(_noisy(g.piece) for g in self.spans)

    def initial(self) -> list[int]:
        return [g.initial(max(self.length, 1e-300)) for g in self.spans]

    def evaluate(self, start: Pose, ns: Sequence[int]) -> _Eval:
        pose = start
        pieces: list = []
        ex, ey, eh, s_all, sx, sy, sh = [], [], [], [], [], [], []
        bounds = []  # per span: first and one-past-last sample index
        count, off = 0, 0.0
        for g, n in zip(self.spans, ns):
            smp = g.samples(n)
            for p, sig in zip(g.pieces(n), smp.sigs):
                x, y, th = (np.asarray(v, dtype=float) for v in travel(pose, p, sig))
                ex.append(x)
                ey.append(y)
                eh.append(th)
                # The last sample is at the piece's length: end_pose(pose, p), without evaluating it twice.
                pose = Pose(float(x[-1]), float(y[-1]), float(th[-1]))
                pieces.append(p)
            s_all.append(off + smp.s)
            sx.append(smp.x)
            sy.append(smp.y)
            sh.append(smp.heading)
            bounds.append((count, count + smp.s.size))
            count += smp.s.size
            off += g.length
        ex, ey, eh = np.concatenate(ex), np.concatenate(ey), np.concatenate(eh)
        s, sx, sy, sh = np.concatenate(s_all), np.concatenate(sx), np.concatenate(sy), np.concatenate(sh)
        e = np.hypot(ex - sx, ey - sy)
        e = np.where(np.isfinite(e), e, math.inf)
        dth = np.abs(_wrap_array(eh - sh))
        dth = np.where(np.isfinite(dth), dth, math.inf)
        gaps = np.maximum(np.diff(s), 0.0)
        with np.errstate(all="ignore"):
            allowance = np.where(gaps > 0, gaps * np.maximum(dth[:-1], dth[1:]), 0.0)
            dev = float(np.max(np.concatenate([e, e[:-1] + allowance])))
        if not math.isfinite(dev):
            dev = math.inf
        i = int(np.argmax(e))
        # Each span's own share (linearised): its heading error relative to its start, integrated over the
        # span, plus the heading error it ends with, carried over the rest of the run.
        own = np.zeros(len(self.spans))
        fixed = float(e[0])
        dth_signed = _wrap_array(eh - sh)
        for k, (a, b) in enumerate(bounds):
            if b - a < 2:
                continue
            r = np.abs(_wrap_array(dth_signed[a:b] - dth_signed[a]))
            rest = self.length - float(s[b - 1])
            inside = float(np.sum(gaps[a:b - 1] * np.maximum(r[:-1], r[1:])))
            own[k] = inside + float(r[-1]) * max(rest, 0.0)
            if k > 0 and bounds[k - 1][1] > bounds[k - 1][0]:  # a kink at the smooth join before the span
                kink = abs(float(_wrap_array(dth_signed[a] - dth_signed[bounds[k - 1][1] - 1])))
                fixed += kink * (self.length - float(s[a]))
            if not self.spans[k].spiral:
                fixed += own[k]
                own[k] = 0.0
        own = np.where(np.isfinite(own), own, math.inf)
        fixed = fixed if math.isfinite(fixed) else math.inf
        return _Eval(tuple(pieces), pose, dev, float(np.max(e)), (float(sx[i]), float(sy[i])), float(e[0]),
                     own, fixed)

    def kink_deg(self) -> float:
        """Largest turn of the source's direction where two spans of the run meet (degrees)."""
        worst = 0.0
        for g0, g1 in zip(self.spans[:-1], self.spans[1:]):
            h0 = g0.source(np.array([g0.length]))[2][0]
            h1 = g1.source(np.array([0.0]))[2][0]
            worst = max(worst, abs(_wrap(float(h1 - h0))))
        return math.degrees(worst)


class _RunResult(NamedTuple):
    ev: _Eval
    ns: list[int]
    failed: ExactStatus | None
    why: str = ""


def _refine(geom: _RunGeom, start: Pose, target: float, tol: float, budget: int, floor: float,
            refine: bool) -> _RunResult:
    """Double the intervals of the spans that contribute most until the run's deviation is within ``target``.

    Stops, keeping the best layout found, when the next doubling would exceed ``budget`` pieces, when what
    is left cannot be reduced by knots (arcs, lines, kinks, a carried offset), when the deviation is down
    to ``floor`` (rounding), or when it stops falling (halving at least once in 3 doublings for a piece
    with finite-difference curvature, 5 otherwise). That is a failure only if the deviation exceeds ``tol``.
    """
    ns = geom.initial()
    ev = geom.evaluate(start, ns)
    best = _RunResult(ev, list(ns), None)
    mark, rounds = ev.deviation, 0
    patience = 3 if geom.noisy else 5
    while refine and ev.deviation > target:
        spiral = [k for k, g in enumerate(geom.spans) if g.spiral]
        room = target - ev.fixed
        stop, why = None, ""
        if not spiral or room <= 0.0:
            stop, why = ExactStatus.UNREFINABLE, (f"arcs, lines, kinks at smooth joins and the offset carried "
                                                  f"from earlier runs already account for {ev.fixed:.3g}")
        elif best.ev.deviation <= floor:
            stop, why = ExactStatus.UNREFINABLE, f"the deviation is down to rounding ({floor:.3g})"
        elif rounds >= patience:
            stop, why = ExactStatus.UNREFINABLE, f"the deviation stopped falling over {patience} doublings"
        else:
            order = sorted(spiral, key=lambda k: -ev.own[k])
            remaining = float(sum(ev.own[k] for k in spiral))
            chosen = []
            for k in order:
                if chosen and remaining <= 0.5 * room:
                    break
                chosen.append(k)
                remaining -= float(ev.own[k])
            new = list(ns)
            for k in chosen:
                new[k] = 2 * ns[k]
            if sum(new) > budget:
                stop, why = ExactStatus.PIECE_LIMIT, "the next doubling would exceed the limit"
        if stop is not None:
            return best._replace(failed=stop, why=why) if best.ev.deviation > tol else best
        ns = new
        ev = geom.evaluate(start, ns)
        if ev.deviation < best.ev.deviation:
            best = _RunResult(ev, list(ns), None)
        if ev.deviation <= 0.5 * mark:
            mark, rounds = ev.deviation, 0
        else:
            rounds += 1
    return best


# --------------------------------------------------------------------------------------------------
# Public functions
# --------------------------------------------------------------------------------------------------


def fit_exact_path(path: Path, tol: float, *, corner_tol_deg: float = 0.5,
                   max_pieces: int = MAX_PIECES) -> ExactPathFit:
    """A path as G1 chains of Segments and Spirals (curvature splines), within a measured deviation ``tol``.

    Parameters
    ----------
    path : skatetrace.drawings.curves.Path
    tol : float
        Largest allowed deviation (see the module docstring), in the path's units.
    corner_tol_deg : float
        See :func:`skatetrace.drawings.fitting.split_path`. A kink of up to this much at a smooth join inside a
        run stays in the run; the layout keeps its direction there, so the kink costs about its angle
        times the rest of the run: lower ``corner_tol_deg`` (make it a corner) for tight ``tol``.
    max_pieces : int
        Refinement stops before the path would need more pieces than this.

    Returns
    -------
    ExactPathFit
        ``success`` False (status ``PIECE_LIMIT``) when a run's deviation stayed above ``tol`` at
        ``max_pieces`` pieces, or (``UNREFINABLE``) when more knots cannot reduce it: curvature noise
        of a finite-difference piece, a kink at a smooth join, or a ``tol`` below rounding (about
        1e-14 of the size or of the coordinates). The runs then hold the best layout found and
        ``message`` names the path, the run, the bound reached and ``tol``.

    Raises
    ------
    FitError
        Invalid ``tol``, ``corner_tol_deg`` or ``max_pieces``, or a path that cannot be split (see
        :func:`skatetrace.drawings.fitting.split_path`).

    Examples
    --------
    >>> from skatetrace.drawings.curves import EllipticArcPiece
    >>> quarter = Path((EllipticArcPiece((0.0, 0.0), 2.0, 2.0, 0.0, 0.0, np.pi / 2),))
    >>> fit = fit_exact_path(quarter, 1e-9)
    >>> fit.success, [(round(p.curvature, 12), round(p.length, 12)) for p in fit.runs[0].pieces]
    (True, [(0.5, 3.14159265359)])
    >>> ellipse = Path((EllipticArcPiece((0.0, 0.0), 2.0, 1.0, 0.0, 0.0, np.pi / 2),))
    >>> fit = fit_exact_path(ellipse, 1e-6)
    >>> fit.success, fit.deviation <= 1e-6, fit.n_spirals > 0, fit.n_arcs + fit.n_lines
    (True, True, True, 0)
    """
    tol = _check_tol(tol)
    if isinstance(max_pieces, bool) or not isinstance(max_pieces, (int, np.integer)) or max_pieces < 1:
        raise FitError(f"max_pieces must be a whole number >= 1, got {max_pieces!r}")
    try:
        runs, prep = _split(path, corner_tol_deg)
        with np.errstate(all="ignore"):
            return _fit_runs(path, runs, prep.scale, tol, int(max_pieces))
    except ArithmeticError as exc:  # overflow in a user's piece, say; never a wrong answer
        raise FitError(f"path {path.name!r}: numerical failure in exact mode ({exc})") from exc


def _fit_runs(path: Path, runs: list[Run], scale: float, tol: float, max_pieces: int) -> ExactPathFit:
    geoms = [_RunGeom(path.pieces, run, f"path {path.name!r}") for run in runs]
    floor = ROUNDING * max(scale, float(np.max(np.abs(path.points(65)))))
    total = max(sum(g.length for g in geoms), 1e-300)
    results: list[_RunResult] = []
    starts: list[Pose] = []
    used, done = 0, 0.0
    failure: tuple[int, ExactStatus, str] | None = None
    for r, (geom, run) in enumerate(zip(geoms, runs)):
        sp0 = run.spans[0]
        if r == 0:
            x, y, _ = geom.spans[0].source(np.array([0.0]))
            start = Pose(float(x[0]), float(y[0]), float(sp0.heading0))
        else:
            prev = results[-1].ev.end
            start = Pose(prev.x, prev.y, float(sp0.heading0))
        # The run's share of tol: the fraction of the path's length up to its end, so that the offset it
        # carries into the next run leaves that one room (more if an earlier run used more than its share).
        sx, sy, _ = geom.spans[0].source(np.array([0.0]))
        offset = math.hypot(start.x - float(sx[0]), start.y - float(sy[0]))
        done += geom.length
        target = min(tol, max(tol * done / total, offset + tol * geom.length / total))
        res = _refine(geom, start, target, tol, max_pieces - used, floor, failure is None)
        if res.failed is not None and failure is None:
            failure = (r, res.failed, res.why)
        used += len(res.ev.pieces)
        results.append(res)
        starts.append(start)
    # Corners from the directions actually laid out.
    out: list[ExactRun] = []
    for r, (run, res, geom) in enumerate(zip(runs, results, geoms)):
        corner = run.corner
        if corner is not None and corner != 0.0 and (r > 0 or path.closed):
            corner = _wrap(starts[r].heading - results[r - 1].ev.end.heading)
        out.append(ExactRun(start=starts[r], pieces=res.ev.pieces, corner=corner, deviation=res.ev.deviation,
                            sampled=res.ev.sampled, curve_length=geom.length))
    pieces = [p for r in out for p in r.pieces]
    n_spirals = sum(1 for p in pieces if isinstance(p, Spiral))
    n_lines = sum(1 for p in pieces if isinstance(p, Segment) and p.curvature == 0.0)
    n_arcs = len(pieces) - n_spirals - n_lines
    deviation = max(r.deviation for r in out)
    worst = max(range(len(out)), key=lambda r: out[r].sampled)
    where = ExactWhere(*results[worst].ev.where, worst)
    success = failure is None and deviation <= tol
    if success:
        status = ExactStatus.SUCCESS
        message = (f"{len(pieces)} pieces ({n_spirals} spirals, {n_arcs} arcs, {n_lines} lines) in {len(out)} runs, "
                   f"deviation <= {deviation:.3g} (tol {tol:.3g})")
    else:
        r, status, why = failure if failure is not None else (
            max(range(len(out)), key=lambda i: out[i].deviation), ExactStatus.PIECE_LIMIT, "")
        message = (f"path {path.name!r}: {status.value}: run {r} reached a deviation bound of "
                   f"{out[r].deviation:.3g} > tol {tol:.3g} with {len(out[r].pieces)} pieces "
                   f"({len(pieces)} in the path, limit {max_pieces})" + (f"; {why}" if why else ""))
        if geoms[r].noisy:
            message += "; its curvature is a finite difference (noise about 1e-8 relative): give exact derivatives"
        kink = geoms[r].kink_deg()
        if kink > 1e-9:
            message += (f"; a smooth join inside the run turns by {kink:.3g} degrees: lower corner_tol_deg "
                        "to make it a corner")
    return ExactPathFit(success=success, status=status, message=message, runs=tuple(out), deviation=deviation,
                        sampled=max(r.sampled for r in out), where=where, n_spirals=n_spirals, n_arcs=n_arcs,
                        n_lines=n_lines, curve_length=float(sum(g.length for g in geoms)),
                        length=float(sum(p.length for p in pieces)), tol=tol, closed=path.closed, name=path.name,
                        size=scale)


def fit_exact_drawing(drawing: Drawing, tol: float, *, corner_tol_deg: float = 0.5,
                      max_pieces: int = MAX_PIECES) -> ExactDrawingFit:
    """Every path of a drawing in exact mode (see :func:`fit_exact_path`); ``tol`` in the drawing's units.

    ``max_pieces`` applies to each path.

    Examples
    --------
    >>> from skatetrace.drawings.curves import EllipticArcPiece, LinePiece
    >>> quarter = EllipticArcPiece((0.0, 0.0), 2.0, 1.0, 0.0, 0.0, np.pi / 2)
    >>> stem = LinePiece((0.0, 1.0), (-1.0, 1.0))
    >>> fit = fit_exact_drawing(Drawing((Path((quarter, stem)),)), 1e-9)
    >>> fit.success, fit.n_spirals > 10, fit.n_lines, fit.deviation <= 1e-9
    (True, True, 1, True)
    """
    if not isinstance(drawing, Drawing):
        raise FitError(f"expected a skatetrace.drawings.curves.Drawing, got {type(drawing).__name__}")
    tol = _check_tol(tol)
    fits = tuple(fit_exact_path(p, tol, corner_tol_deg=corner_tol_deg, max_pieces=max_pieces) for p in drawing.paths)
    worst = max(range(len(fits)), key=lambda i: fits[i].deviation)
    bad = [f"path {i} ({f.name!r}): {f.message}" for i, f in enumerate(fits) if not f.success]
    message = (f"{len(fits)} paths, deviation <= {fits[worst].deviation:.3g} (tol {tol:.3g})" if not bad
               else "; ".join(bad))
    return ExactDrawingFit(success=not bad, message=message, paths=fits, deviation=fits[worst].deviation,
                           n_spirals=sum(f.n_spirals for f in fits), n_arcs=sum(f.n_arcs for f in fits),
                           n_lines=sum(f.n_lines for f in fits), worst_path=worst, name=drawing.name)


def figure_from_exact(fit: ExactPathFit | ExactDrawingFit, *, name: str, params=None,
                      reverse_above_deg: float = 90.0) -> Figure:
    """A :class:`~skatetrace.figures.figure.Figure` from an exact-mode fit: one curve per path.

    Pieces of a run are joined smoothly; at corners the joins of
    :func:`skatetrace.drawings.fitting.corner_join` (a cusp that pivots, or reverses above
    ``reverse_above_deg``); a closed path's curve gets the closing join. Laid out with
    :meth:`Curve.layout`, the pieces reproduce the fit's layout (as :func:`skatetrace.drawings.fitting.figure_from_fit`).

    Raises
    ------
    FitError
        If the fit did not succeed, or ``reverse_above_deg`` is not in ``[0, 180]``.
    """
    _check_reverse(reverse_above_deg)
    if not isinstance(fit, (ExactPathFit, ExactDrawingFit)):
        raise FitError(f"expected an ExactPathFit or ExactDrawingFit, got {type(fit).__name__}")
    paths = fit.paths if isinstance(fit, ExactDrawingFit) else (fit,)
    if not fit.success:
        raise FitError(f"cannot make a figure from a failed fit: {fit.message}")
    curves = _figure_curves(paths, reverse_above_deg, lambda run: run.pieces)
    tols = sorted({p.tol for p in paths})
    deviation = max(p.deviation for p in paths)
    return Figure(name, tuple(curves), params, provenance=(
        "exact-mode curvature spline (Segments and Spirals with curvature cubic in arc length) within a "
        f"measured deviation of {deviation:.3g} from the drawing (tol {', '.join(f'{t:.3g}' for t in tols)})"),
        extra={"exact": {"tol": tols[-1], "deviation": deviation, "n_spirals": sum(p.n_spirals for p in paths),
                         "n_arcs": sum(p.n_arcs for p in paths), "n_lines": sum(p.n_lines for p in paths)}})
