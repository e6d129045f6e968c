"""One span of source curve as a curvature spline: its arc length, the inverse, and its Segments or Spirals.

Step 2 of exact mode (:mod:`skatetrace.drawings.exact`). A span of constant curvature becomes one
Segment. A spiral span is parametrised by arc length (adaptive 5-point Gauss-Legendre; ``t(s)`` by
safeguarded Newton steps to rounding), its curvature sampled at knots that crowd where it turns
fast (:meth:`SpanGeom._knots`) and interpolated by a not-a-knot cubic spline, one Spiral per
interval. A spline through points is cut
at its breakpoints (:func:`subspans`); at a cusp end, where the curvature is unbounded, the end
interval continues the spline with the source's exact turn over it. :class:`SpanGeom` also gives
the source's points and directions at the deviation samples.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from scipy.interpolate import CubicSpline

from .curves import AffinePiece, Piece, SplinePiece, curvature
from ..errors import FitError
from .corners import _wrap
from .curves import _direction, _gl_lengths
from .spirals import Span
from ..figures.geometry import Segment, Spiral, shifted_polynomial

__all__ = ["SpanGeom", "subspans", "SAMPLES", "START_TURN", "START_DENSITY"]

SAMPLES = 16  # deviation samples per piece (per half radian of turn, for long arcs)
START_TURN = 0.25  # radians of turn per spline interval to start with
START_DENSITY = 8  # spline intervals per run length to start with
GRADING = 0.5  # the largest growth of the knots' spacing per unit length (see SpanGeom._knots)
#: A spline piece that turns more than this (radians, its largest curvature times its length) overshoots:
#: a source span between two extrema of its curvature turns by less than a turn or two.
OVERSHOOT = 1e4


def _clean(c) -> tuple[float, float, float, float]:
    out = tuple(float(v) for v in c)
    return out if all(math.isfinite(v) for v in out) else (0.0, 0.0, 0.0, 0.0)


class _Samples(NamedTuple):
    sigs: tuple[np.ndarray, ...]  # per piece: arc lengths from the piece's start
    s: np.ndarray  # all samples: arc length from the span's start
    x: np.ndarray  # source point and travel direction there
    y: np.ndarray
    heading: np.ndarray


class SpanGeom:
    """A span of one source piece parametrised by arc length."""

    def __init__(self, piece: Piece, span: Span, where: str):
        self.piece, self.span = piece, span
        self.t_tab, self.s_tab = self._table()
        self.length = float(self.s_tab[-1])
        if not (math.isfinite(self.length) and self.length >= 0):
            raise FitError(f"{where}: piece {span.piece} has non-finite arc length on [{span.t0}, {span.t1}]")
        self.turn, self._turned = self._turns()
        self.piecewise = _breakpoints(piece).size > 0
        self.cusps = (False, False) if not self.spiral else (self._cusp_end(span.t0), self._cusp_end(span.t1))
        self._pieces: dict[int, tuple] = {}
        self._overshoots: dict[int, bool] = {}
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

    def _turns(self) -> tuple[float, np.ndarray]:
        """The span's total signed turn (integral of the curvature), and the absolute turn over each
        interval of the table, by Gauss-Legendre on the table."""
        x, w = np.polynomial.legendre.leggauss(5)
        lo, hi = self.t_tab[:-1], self.t_tab[1:]
        tt = (0.5 * (lo + hi))[:, None] + (0.5 * (hi - lo))[:, None] * x[None, :]
        d1, d2 = self.piece.d1(tt.ravel()), self.piece.d2(tt.ravel())
        with np.errstate(all="ignore"):
            k = (d1[0] * d2[1] - d1[1] * d2[0]) / (d1[0] ** 2 + d1[1] ** 2)
        k = np.where(np.isfinite(k), k, 0.0).reshape(tt.shape)
        return float(np.sum(0.5 * (hi - lo) * (k @ w))), 0.5 * (hi - lo) * (np.abs(k) @ w)

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

    def overshoots(self, n: int) -> bool:
        """Whether a piece of the span cut into ``n`` turns by more than :data:`OVERSHOOT` radians."""
        if n not in self._overshoots:
            self._overshoots[n] = any(isinstance(p, Spiral) and p.max_abs_curvature() * p.length > OVERSHOOT
                                      for p in self.pieces(n))
        return self._overshoots[n]

    def _spline(self, n: int) -> tuple:
        L, (c0, c1) = self.length, self.cusps
        n = max(n, 2 + c0 + c1)
        s = self._knots(n)
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

    def _knots(self, n: int) -> np.ndarray:
        """``n + 1`` knots in arc length: denser where the span turns fast, in a mesh that grows gently.

        The density of knots is the mean of a uniform one and one proportional to the absolute
        curvature (equal turn between knots); the spacing is then kept from growing by more than
        :data:`GRADING` times the distance (each interval at most about 1.7 times its neighbour), since
        a cubic spline through knots of very unequal spacing overshoots between them (a quadratic
        Bezier's hairpin tip took half the knots and left the next interval 1e4 times longer).
        """
        ds = np.diff(self.s_tab)
        mid = self.s_tab[:-1] + 0.5 * ds
        turned = float(np.sum(self._turned))
        # knots per unit length: half spread evenly, half by the turn (where there is one)
        rho = np.full(ds.size, 1.0 / self.length)
        if turned > 0.0:
            with np.errstate(all="ignore"):
                bent = np.where(ds > 0.0, self._turned / np.where(ds > 0.0, ds, 1.0), 0.0) / turned
            rho = 0.5 * (rho + bent)
        h = 1.0 / (n * rho)
        h = np.minimum(h, np.minimum.accumulate(h - GRADING * mid) + GRADING * mid)
        h = np.minimum(h, (np.minimum.accumulate((h + GRADING * mid)[::-1]) - GRADING * mid[::-1])[::-1])
        u = np.concatenate([[0.0], np.cumsum(ds / h)])
        s = np.interp(np.linspace(0.0, u[-1], n + 1), u, self.s_tab)
        s[0], s[-1] = 0.0, self.length
        return s

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


def _breakpoints(piece: Piece) -> np.ndarray:
    """Parameters in ``(0, 1)`` where a piecewise-polynomial piece (a spline through points) changes polynomial."""
    if isinstance(piece, AffinePiece):
        return _breakpoints(piece.base)
    x = getattr(getattr(piece, "spline", None), "x", None) if isinstance(piece, SplinePiece) else None
    if x is None or piece.u1 == piece.u0:
        return np.zeros(0)
    t = (np.asarray(x, dtype=float) - piece.u0) / (piece.u1 - piece.u0)
    return np.unique(t[(t > 0.0) & (t < 1.0)])


def subspans(piece: Piece, span: Span) -> list[Span]:
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
