"""Arc-spline fitting: a drawn curve, cut into smooth runs, approximated by G1 arcs and lines.

The chain, from a :class:`~skatetrace.drawings.curves.Path` to a :class:`~skatetrace.figures.figure.Figure`:

1. :func:`split_path` cuts a path into *runs*, maximal tangent-continuous (G1) stretches, at corners
   between pieces and at cusps inside a piece (where the parametric speed ``|r'(t)|`` vanishes), and
   each run into *spiral spans* at inflections (the signed curvature kappa changes sign) and at
   curvature extrema (dkappa/ds = 0). A span of constant curvature (a circle or a line) stays whole.
2. :func:`fit_path` replaces every run by a G1 chain of circular arcs and lines (:class:`Segment`):
   biarcs interpolating the curve's points and unit tangents at breakpoints (Meek & Walton), the
   breakpoints chosen greedily (halve a span at its arc-length midpoint until its biarc is within
   ``tol``) or for the fewest arcs (a shortest path over candidate breakpoints, after Drysdale, Rote &
   Sturm). Every biarc carries a certified upper bound on its Hausdorff distance to the stretch of
   curve it replaces, so the bound of the whole fit is certified too.
3. :func:`figure_from_fit` turns a fit into a :class:`~skatetrace.figures.figure.Figure`: one curve per path,
   smooth joins inside a run, and at each corner a cusp join that pivots the blade, or reverses it
   (a true cusp) when the travel direction turns by more than ``reverse_above_deg``.

Notation: kappa is signed curvature (positive turns left), s arc length, t a piece's parameter in
``[0, 1]``, "size" the larger side of the path's bounding box. Thresholds that decide what is rounding
(a tiny piece, a gap, a cusp) are relative to the size and listed as module constants below.

References
----------
D. S. Meek, D. J. Walton, "Approximation of discrete data by G1 arc splines", Computer-Aided Design
(1992); "Approximating smooth planar curves by arc splines", J. Comput. Appl. Math. 59 (1995) 221-231;
"Spiral arc spline approximation to a planar spiral", J. Comput. Appl. Math. 107 (1999) 21-30 (ways
of choosing a biarc's free parameter). R. L. S. Drysdale, G. Rote, A. Sturm, "Approximation of an open
polygonal curve with a minimum number of circular arcs and biarcs", Comput. Geom. Theory Appl. (2008).
"""

from __future__ import annotations

import dataclasses
import math
import warnings
from dataclasses import dataclass, field
from enum import Enum
from typing import NamedTuple, Sequence

import numpy as np
from scipy.optimize import brentq, minimize_scalar
from scipy.spatial import cKDTree

from .curves import AffinePiece, BezierPiece, Drawing, EllipticArcPiece, FunctionPiece, LinePiece, Path, Piece
from .curves import SplinePiece, curvature, piece_length
from ..errors import FitError
from ..figures.figure import SMOOTH, Curve, Figure, Join
from ..figures.geometry import Pose, Segment, advance

__all__ = [
    "Span", "Run", "split_path", "biarc", "Knot", "Where", "FittedRun", "FitStatus", "PathFit", "DrawingFit",
    "fit_path", "fit_drawing", "figure_from_fit", "corner_join",
]

# Relative to the path's size unless said otherwise.
TINY = 1e-10  # a piece, or the bit of a piece before a cusp, shorter than this is rounding: dropped
GAP = 1e-9  # consecutive pieces must meet within this
MIN_SPAN = 1e-9  # a span shorter than this is not halved again (the fit then fails, with a message)
CUSP_RADIUS = 1e-10  # a speed minimum whose radius bound |r'|^2/|r''| is below this is a cusp
SPLIT_MIN = 1e-6  # inflections/extrema closer than this (fraction of the range) to an end or each other merge
MAX_INTERVALS = 100_000  # biarcs per path before the fit gives up
MIN_DENSITY = 6  # candidate breakpoints per greedy biarc for the minimum-count fit
MIN_BUDGET = 30  # certificates per greedy biarc the minimum-count search may spend before keeping greedy's

_GL5 = np.polynomial.legendre.leggauss(5)
_TWO_PI = 2.0 * math.pi


# --------------------------------------------------------------------------------------------------
# Splitting
# --------------------------------------------------------------------------------------------------


class Span(NamedTuple):
    """A stretch ``t0 <= t <= t1`` of one piece of a path, with the travel directions used at its ends.

    ``kind`` is ``"spiral"`` (curvature monotone, one sign), ``"arc"`` or ``"line"`` (constant
    curvature). ``reason`` says why a span starts where it does: ``"start"`` of an open path, a
    ``"corner"`` between pieces, a ``"cusp"`` inside a piece, a smooth ``"join"`` of pieces, an
    ``"inflection"`` or a curvature ``"extremum"``.
    """

    piece: int
    t0: float
    t1: float
    heading0: float
    heading1: float
    kind: str
    reason: str


@dataclass(frozen=True, slots=True)
class Run:
    """A maximal tangent-continuous stretch of a path, cut into spiral spans.

    Attributes
    ----------
    spans : tuple of Span
        In travel order; consecutive spans share their end point and heading.
    corner : float or None
        Signed change of travel direction (radians, in ``(-pi, pi]``) at the corner before the run;
        about ``pi`` in magnitude at a cusp. ``None`` for the first run of an open path. For a closed
        path the first run's corner is where the path closes (``0.0`` if it closes smoothly).
    """

    spans: tuple[Span, ...]
    corner: float | None


def _wrap(a: float) -> float:
    """Angle in ``(-pi, pi]``."""
    r = math.remainder(a, _TWO_PI)
    return math.pi if r <= -math.pi else r


def _col(piece: Piece, fn: str, t: float) -> np.ndarray:
    return np.asarray(getattr(piece, fn)(float(t)), dtype=float)[:, 0]


def _noisy(piece: Piece) -> bool:
    """Whether a piece's second derivative is a finite difference (curvature then has ~1e-8 noise)."""
    if isinstance(piece, AffinePiece):
        return _noisy(piece.base)
    if isinstance(piece, FunctionPiece):
        return piece.d2fn is None
    return not isinstance(piece, (LinePiece, BezierPiece, EllipticArcPiece, SplinePiece))


def _bezier_end_direction(piece: Piece, t: float) -> np.ndarray | None:
    """Exact end tangent of a Bézier (also under affine maps): the first non-zero control difference."""
    if isinstance(piece, AffinePiece):
        v = _bezier_end_direction(piece.base, t)
        if v is None:
            return None
        w = np.asarray(piece.A, float) @ v
        n = math.hypot(w[0], w[1])
        return w / n if n > 0 and math.isfinite(n) else None
    if not isinstance(piece, BezierPiece):
        return None
    p = np.asarray(piece.control, float)
    extent = float(np.max(np.ptp(p, axis=0)))
    if not extent > 0:
        return None
    order = range(1, len(p)) if t == 0.0 else range(len(p) - 2, -1, -1)
    for k in order:
        v = p[k] - p[0] if t == 0.0 else p[-1] - p[k]
        n = math.hypot(v[0], v[1])
        if n > 1e-12 * extent:
            return v / n
    return None


def _direction(piece: Piece, t: float, side: int, vscale: float, cusp: bool = False) -> np.ndarray | None:
    """Unit travel direction leaving ``t`` (``side=+1``) or arriving at it (``side=-1``).

    Where ``r'`` vanishes (a zero-length Bézier handle, a cusp) it is the limit direction: the next
    non-zero Bézier control difference, else ``+-r''``, else a one-sided difference of points.
    """
    if t in (0.0, 1.0) and not cusp:
        v = _bezier_end_direction(piece, t)
        if v is not None:
            return v
    d1 = _col(piece, "d1", t)
    sp = math.hypot(d1[0], d1[1])
    if not cusp and sp > 1e-7 * vscale:
        return d1 / sp
    d2 = _col(piece, "d2", t)
    n2 = math.hypot(d2[0], d2[1])
    if n2 > 1e-7 * vscale:
        return side * d2 / n2
    p = _col(piece, "point", t)
    for h in (1e-6, 1e-4, 1e-2, 1e-1):
        t2 = min(max(t + side * h, 0.0), 1.0)
        if t2 == t:
            continue
        v = _col(piece, "point", t2) - p
        n = math.hypot(v[0], v[1])
        if n > 1e-12 * vscale:
            return side * v / n
    return None


def _cusps(piece: Piece, scale: float) -> list[float]:
    """Parameters in ``[0, 1]`` where the speed ``|r'|`` vanishes (to within rounding of the size)."""
    if isinstance(piece, LinePiece):
        return []
    t = np.linspace(0.0, 1.0, 1025)
    d = piece.d1(t)
    sp = np.hypot(d[0], d[1])
    top = float(np.max(sp))
    if not top > 0:
        return []
    left = np.concatenate([[np.inf], sp[:-1]])
    right = np.concatenate([sp[1:], [np.inf]])
    cand = np.nonzero((sp <= left) & (sp <= right) & (sp < 1e-2 * top))[0]
    out: list[float] = []

    def speed(x: float) -> float:
        v = _col(piece, "d1", x)
        return math.hypot(v[0], v[1])

    for i in cand:
        a, b = t[max(i - 1, 0)], t[min(i + 1, t.size - 1)]
        res = minimize_scalar(speed, bounds=(a, b), method="bounded", options={"xatol": 1e-14})
        ts, s = (float(res.x), float(res.fun)) if res.fun <= sp[i] else (float(t[i]), float(sp[i]))
        d2 = _col(piece, "d2", ts)
        n2 = math.hypot(d2[0], d2[1])
        if s == 0.0 or (n2 > 0 and s * s <= CUSP_RADIUS * scale * n2):
            if not out or ts - out[-1] > 1e-9:
                out.append(ts)
    return out


def _sign_changes(x: np.ndarray, v: np.ndarray, eps: float) -> list[tuple[float, float]]:
    """Brackets ``(lo, hi)`` where ``v`` changes sign; values within ``eps`` of zero count as zero."""
    s = np.where(np.abs(v) <= eps, 0, np.sign(v))
    nz = np.nonzero(s)[0]
    out = []
    for i, j in zip(nz[:-1], nz[1:]):
        if s[i] != s[j]:
            out.append((float(x[i]), float(x[j])))
    return out


def _kappa(piece: Piece, x: float) -> float:
    return float(curvature(piece, float(x))[0])


def _refine_inflection(piece: Piece, lo: float, hi: float) -> float:
    try:
        flo, fhi = _kappa(piece, lo), _kappa(piece, hi)
        if math.isfinite(flo) and math.isfinite(fhi) and flo * fhi < 0:
            return float(brentq(lambda x: _kappa(piece, x), lo, hi, xtol=1e-15))
    except (ValueError, RuntimeError):
        pass
    return 0.5 * (lo + hi)


def _refine_extremum(piece: Piece, lo: float, hi: float, h: float, rising: bool, a: float, b: float) -> float:
    """Root of dkappa/dt in ``[lo, hi]`` (brentq on a central difference), else the extremum of kappa."""

    def dk(x: float) -> float:
        return (_kappa(piece, x + h) - _kappa(piece, x - h)) / (2 * h)

    try:
        flo, fhi = dk(lo), dk(hi)
        if math.isfinite(flo) and math.isfinite(fhi) and flo * fhi < 0:
            return float(brentq(dk, lo, hi, xtol=1e-15))
    except (ValueError, RuntimeError):
        pass
    sign = -1.0 if rising else 1.0  # a maximum of kappa where it rose before, a minimum otherwise
    res = minimize_scalar(lambda x: sign * _kappa(piece, x), bounds=(max(a, lo - h), min(b, hi + h)),
                          method="bounded", options={"xatol": 1e-13})
    return float(res.x) if math.isfinite(res.fun) else 0.5 * (lo + hi)


def _spiral_spans(piece: Piece, index: int, a: float, b: float, h0: float, h1: float, reason: str,
                  length: float) -> list[Span]:
    """Cut ``piece`` on ``[a, b]`` at inflections and curvature extrema.

    Curvature is only trusted to within its rounding error at each grid point: derivatives carry an
    absolute error ``eta * (|r| + L)`` (``eta`` 1e-13, or 1e-7 for finite differences), which the
    cross product and ``|r'|^3`` turn into ``nk``, large where ``|r'|`` is small (near a cusp, or on a
    straight stretch where ``r'`` and ``r''`` are parallel). Curvature within ``nk`` of zero, and
    differences within their combined ``nk``, count as zero; a stretch is of constant curvature when
    all intervals ``kappa +- nk`` share a value (to 1e-9 relative).
    """
    t = np.linspace(a, b, 513)
    p, d1, d2 = piece.point(t), piece.d1(t), piece.d2(t)
    sp, n2 = np.hypot(d1[0], d1[1]), np.hypot(d2[0], d2[1])
    nd = (1e-7 if _noisy(piece) else 1e-13) * (float(np.max(np.abs(p))) + length)
    with np.errstate(all="ignore"):
        k = (d1[0] * d2[1] - d1[1] * d2[0]) / sp ** 3
        nk = nd * (sp + n2) / sp ** 3 + 3.0 * np.abs(k) * nd / sp
    fin = np.isfinite(k) & np.isfinite(nk) & (sp > 0)
    tf, kf, nkf = t[fin], k[fin], nk[fin]
    if kf.size < 8:
        return [Span(index, a, b, h0, h1, "spiral", reason)]
    scale_k = max(float(np.median(np.abs(kf))), 1.0 / length)
    if float(np.max(kf - nkf)) <= float(np.min(kf + nkf)) + 1e-9 * scale_k:
        straight = float(np.max(np.maximum(np.abs(kf) - nkf, 0.0))) * length <= 1e-9
        return [Span(index, a, b, h0, h1, "line" if straight else "arc", reason)]
    roots: list[tuple[float, str]] = []
    kz = np.where(np.abs(kf) <= nkf, 0.0, kf)
    for lo, hi in _sign_changes(tf, kz, 0.0):
        roots.append((_refine_inflection(piece, lo, hi), "inflection"))
    dk = np.diff(kf)
    dk = np.where(np.abs(dk) <= nkf[:-1] + nkf[1:], 0.0, dk)
    mid = 0.5 * (tf[:-1] + tf[1:])
    h = 1e-5 * (b - a)
    for lo, hi in _sign_changes(mid, dk, 0.0):
        rising = float(np.interp(lo, mid, dk)) > 0
        roots.append((_refine_extremum(piece, lo, hi, h, rising, a, b), "extremum"))
    # Arc length along the grid, to drop splits within rounding of an end or of each other.
    s = np.concatenate([[0.0], np.cumsum(0.5 * (sp[1:] + sp[:-1]) * np.diff(t))])
    total = float(s[-1]) if s[-1] > 0 else 1.0
    dt, ds = SPLIT_MIN * (b - a), SPLIT_MIN * total
    cuts: list[tuple[float, float, str]] = []
    for r, why in sorted(roots):
        if not (math.isfinite(r) and a + dt < r < b - dt):
            continue
        sr = float(np.interp(r, t, s))
        if sr <= ds or sr >= total - ds:
            continue
        if cuts and (r - cuts[-1][0] <= dt or sr - cuts[-1][1] <= ds):
            continue
        cuts.append((r, sr, why))
    spans = []
    t_prev, h_prev, why_prev = a, h0, reason
    for r, _, why in cuts:
        d1 = _col(piece, "d1", r)
        hr = math.atan2(d1[1], d1[0])
        spans.append(Span(index, t_prev, r, h_prev, hr, "spiral", why_prev))
        t_prev, h_prev, why_prev = r, hr, why
    spans.append(Span(index, t_prev, b, h_prev, h1, "spiral", why_prev))
    return spans


class _Prepared(NamedTuple):
    scale: float
    lengths: tuple[float, ...]


def _prepare(path: Path) -> _Prepared:
    """Validate a path's points; its size (larger bounding-box side) and piece lengths."""
    if not isinstance(path, Path):
        raise FitError(f"expected a skatetrace.drawings.curves.Path, got {type(path).__name__}")
    pts = []
    t = np.linspace(0.0, 1.0, 129)
    for i, p in enumerate(path.pieces):
        with np.errstate(all="ignore"):
            xy = np.asarray(p.point(t), dtype=float)
            d1 = np.asarray(p.d1(t), dtype=float)
            d2 = np.asarray(p.d2(t), dtype=float)
        if not (np.all(np.isfinite(xy)) and np.all(np.isfinite(d1)) and np.all(np.isfinite(d2))):
            raise FitError(f"path {path.name!r}, piece {i}: points or derivatives are not finite")
        pts.append(xy)
    xy = np.hstack(pts)
    scale = float(max(np.ptp(xy[0]), np.ptp(xy[1])))
    if not scale > 0:
        raise FitError(f"path {path.name!r} has zero extent: all its points coincide")
    if not (1e-100 < scale < 1e100) or float(np.max(np.abs(xy))) > 1e100:
        raise FitError(f"path {path.name!r}: size {scale:.3g} (coordinates up to {np.max(np.abs(xy)):.3g}) is "
                       "outside 1e-100..1e100; rescale the drawing")
    lengths = tuple(piece_length(p, 0.0, 1.0, 64) for p in path.pieces)
    if not all(math.isfinite(v) for v in lengths):
        raise FitError(f"path {path.name!r}: a piece has non-finite length")
    return _Prepared(scale, lengths)


class _Range(NamedTuple):
    piece: int
    a: float
    b: float
    cusp_a: bool
    cusp_b: bool


def _ranges(path: Path, prep: _Prepared) -> list[_Range]:
    """Pieces cut at their cusps, with pieces and bits of pieces below rounding dropped."""
    out = []
    for i, p in enumerate(path.pieces):
        if prep.lengths[i] <= TINY * prep.scale:
            continue
        cuts = [0.0, *(c for c in _cusps(p, prep.scale) if 0.0 < c < 1.0), 1.0]
        parts = []
        for a, b in zip(cuts[:-1], cuts[1:]):
            if b > a and piece_length(p, a, b, 32) > TINY * prep.scale:
                parts.append((a, b))
        for a, b in parts:
            out.append(_Range(i, a, b, a > 0.0, b < 1.0))
    if not out:
        raise FitError(f"path {path.name!r} has zero length")
    return out


def _split(path: Path, corner_tol_deg: float) -> tuple[list[Run], _Prepared]:
    if not (isinstance(corner_tol_deg, (int, float)) and math.isfinite(corner_tol_deg)
            and 0 <= corner_tol_deg < 180):
        raise FitError(f"corner_tol_deg must be in [0, 180) degrees, got {corner_tol_deg!r}")
    prep = _prepare(path)
    scale, pieces = prep.scale, path.pieces
    ranges = _ranges(path, prep)
    n = len(ranges)
    dirs_in, dirs_out = [], []
    for r in ranges:
        p, vscale = pieces[r.piece], max(prep.lengths[r.piece], 1e-300)
        chord = _col(p, "point", r.b) - _col(p, "point", r.a)
        cn = math.hypot(chord[0], chord[1])
        fallback = chord / cn if cn > 0 else np.array([1.0, 0.0])
        d_in = _direction(p, r.a, +1, vscale, r.cusp_a)
        d_out = _direction(p, r.b, -1, vscale, r.cusp_b)
        dirs_in.append(fallback if d_in is None else d_in)
        dirs_out.append(fallback if d_out is None else d_out)
    tol = math.radians(corner_tol_deg)
    # Junction j sits between range j-1 and range j; junction 0 is the closure of a closed path.
    corner: list[float | None] = [None] * n
    reason = ["start"] * n
    for j in range(0 if path.closed else 1, n):
        prev, cur = ranges[j - 1], ranges[j]
        end = _col(pieces[prev.piece], "point", prev.b)
        start = _col(pieces[cur.piece], "point", cur.a)
        gap = math.hypot(*(end - start))
        if gap > GAP * scale:
            where = "closes" if j == 0 else f"pieces {prev.piece} and {cur.piece} meet"
            raise FitError(f"path {path.name!r}: a gap of {gap:.3g} where the path {where} "
                           f"(allowed {GAP:g} of the size {scale:.3g}); join the pieces or open the path")
        u, v = dirs_out[j - 1], dirs_in[j]
        delta = _wrap(math.atan2(u[0] * v[1] - u[1] * v[0], u[0] * v[0] + u[1] * v[1]))
        same_piece = prev.piece == cur.piece and j > 0
        if abs(delta) <= tol:
            m = u + v
            m = m / math.hypot(m[0], m[1])
            dirs_out[j - 1], dirs_in[j] = m, m
            corner[j] = 0.0
            reason[j] = "join"
        else:
            corner[j] = delta
            reason[j] = "cusp" if same_piece else "corner"
    runs: list[list[Span]] = []
    corners: list[float | None] = []
    for j, r in enumerate(ranges):
        spans = _spiral_spans(pieces[r.piece], r.piece, r.a, r.b, math.atan2(dirs_in[j][1], dirs_in[j][0]),
                              math.atan2(dirs_out[j][1], dirs_out[j][0]), reason[j],
                              piece_length(pieces[r.piece], r.a, r.b, 64))
        if j == 0 or reason[j] != "join":
            runs.append(spans)
            corners.append(corner[j])
        else:
            runs[-1].extend(spans)
    if path.closed and reason[0] == "join":
        if len(runs) > 1:
            first = runs.pop(0)
            corners.pop(0)
            runs[-1].extend(first)
        else:
            corners[0] = 0.0
    return [Run(tuple(s), c) for s, c in zip(runs, corners)], prep


def split_path(path: Path, *, corner_tol_deg: float = 0.5) -> list[Run]:
    """Cut a path into tangent-continuous runs, and each run into spiral spans.

    Parameters
    ----------
    path : skatetrace.drawings.curves.Path
    corner_tol_deg : float
        Consecutive pieces whose unit tangents differ by at most this (degrees) join smoothly; the
        fit then uses the mean direction on both sides, so the arc spline stays G1 there.

    Returns
    -------
    list of Run

    Raises
    ------
    FitError
        If the path has zero length or extent, non-finite points, or pieces that do not meet.

    Notes
    -----
    Corners: at a piece end where ``r'`` vanishes (a zero-length Bézier handle) the tangent is the
    limit direction (the next non-zero control-point difference, else ``r''``). Cusps inside a piece:
    local minima of ``|r'|`` on a 1025-point grid refined by bounded Brent minimisation; a minimum is a
    cusp when ``|r'|^2 / |r''|`` (a lower bound of the radius of curvature there) is below
    ``CUSP_RADIUS`` times the size. Its two sides have limit directions ``-r''`` and ``+r''``, so a true
    cusp turns by about ``pi``. Spiral spans: sign changes of kappa and of its grid differences on 513
    points per stretch, ignoring values within their rounding error (see :func:`_spiral_spans`),
    refined by brentq (on kappa, and on a central difference of kappa, with a bounded minimisation
    of kappa as fall-back); splits within ``SPLIT_MIN`` of an end or of each other are dropped.

    Examples
    --------
    >>> from skatetrace.drawings.curves import FunctionPiece
    >>> sine = FunctionPiece(lambda u: (u, np.sin(u)), 0.0, 2 * np.pi,
    ...                      lambda u: (np.ones_like(u), np.cos(u)), lambda u: (np.zeros_like(u), -np.sin(u)))
    >>> [run] = split_path(Path((sine,)))
    >>> [(round(s.t0 * 2 * np.pi, 6), s.reason) for s in run.spans]
    [(0.0, 'start'), (1.570796, 'extremum'), (3.141593, 'inflection'), (4.712389, 'extremum')]
    >>> vee = Path((BezierPiece(((0.0, 0.0), (1.0, 0.0), (0.5, 0.0))),))   # out and back: a cusp
    >>> [round(abs(r.corner or 0.0), 9) for r in split_path(vee)]
    [0.0, 3.141592654]
    """
    return _split(path, corner_tol_deg)[0]


# --------------------------------------------------------------------------------------------------
# Arcs: construction and exact distances
# --------------------------------------------------------------------------------------------------


def _biarc(x0: float, y0: float, h0: float, x1: float, y1: float, h1: float) -> tuple[Segment, ...] | None:
    """Equal-chord biarc from ``(x0, y0)`` heading ``h0`` to ``(x1, y1)`` heading ``h1``; ``None`` if undefined."""
    dx, dy = x1 - x0, y1 - y0
    d = math.hypot(dx, dy)
    if not (d > 0 and math.isfinite(d)):
        return None
    phi = math.atan2(dy, dx)
    alpha, beta = _wrap(h0 - phi), _wrap(h1 - phi)
    omega = 0.25 * (alpha - beta)
    cos_w = math.cos(omega)
    if cos_w < 1e-8:
        return None
    chord = 0.5 * d / cos_w
    segs = []
    for gamma in (-0.5 * (3 * alpha + beta), 0.5 * (alpha + 3 * beta)):
        half = 0.5 * gamma
        sinc = math.sin(half) / half if half != 0.0 else 1.0  # chord / length of the arc
        if sinc < 1e-8:
            return None
        segs.append(Segment(2.0 * math.sin(0.5 * gamma) / chord, chord / sinc))
    (k1, l1), (k2, l2) = segs
    if abs(k1 - k2) * (l1 + l2) ** 2 <= 1e-12 * (l1 + l2):
        k = (k1 * l1 + k2 * l2) / (l1 + l2)  # keeps the total turn, hence the end heading
        return (Segment(0.0 if abs(k) * (l1 + l2) <= 1e-13 else k, l1 + l2),)
    return tuple(Segment(0.0 if abs(k) * ln <= 1e-13 else k, ln) for k, ln in segs)


def biarc(start: Pose, end: Pose) -> tuple[Segment, ...]:
    """The equal-chord biarc from ``start`` to ``end`` (G1 Hermite interpolation by two arcs).

    Parameters
    ----------
    start, end : Pose
        Points and travel directions (radians) to interpolate.

    Returns
    -------
    tuple of Segment
        Two segments, or one when both arcs lie on one circle (or line). Laid out from ``start`` with
        :func:`skatetrace.figures.geometry.advance` they end at ``end``.

    Raises
    ------
    FitError
        If the points coincide or the directions make the biarc unbounded (both pointing back along
        the chord).

    Notes
    -----
    The biarcs interpolating given G1 Hermite data form a one-parameter family; their join points lie
    on a circle through both end points. We take the join point where that circle crosses the
    perpendicular bisector of the chord, so both arcs have the same chord (the *equal-chord* biarc,
    one of the standard choices discussed by Meek & Walton). With the chord at angle phi and the end
    directions at ``alpha = h0 - phi`` and ``beta = h1 - phi`` (wrapped to ``(-pi, pi]``), the arcs
    turn by ``-(3 alpha + beta)/2`` and ``(alpha + 3 beta)/2``; both chords are ``d / (2 cos w)`` with
    ``w = (alpha - beta)/4``, so neither arc is ever shorter than half the chord ``d``. For data read
    from a circle the two arcs lie on that circle and are merged into one. Fitting does not rely on an
    a-priori error bound: every biarc's distance to the curve is certified numerically.

    Examples
    --------
    >>> segs = biarc(Pose(1.0, 0.0, np.pi / 2), Pose(0.0, 1.0, np.pi))   # a quarter of the unit circle
    >>> [(round(s.curvature, 12), round(s.length, 12)) for s in segs]
    [(1.0, 1.570796326795)]
    >>> [len(biarc(Pose(0.0, 0.0, 0.0), Pose(1.0, 1.0, a))) for a in (0.0, np.pi / 2)]
    [2, 1]
    """
    out = _biarc(float(start[0]), float(start[1]), float(start[2]), float(end[0]), float(end[1]), float(end[2]))
    if out is None:
        raise FitError(f"no bounded biarc from {tuple(start)} to {tuple(end)}: the points coincide or both "
                       "directions point back along the chord")
    return out


def _chain_poses(pose: Pose, segs: Sequence[Segment]) -> list[Pose]:
    """Start pose of each segment, and the end pose."""
    out = [pose]
    for k, L in segs:
        out.append(Pose(*(float(v) for v in advance(out[-1], k, L))))
    return out


def _seg_dist(pts: np.ndarray, pose: Pose, k: float, L: float) -> np.ndarray:
    """Exact distance from points (shape ``(2, n)``) to an arc or a line, well conditioned for tiny ``k``.

    Same result as :func:`skatetrace.figures.geometry.distance_to_segment`, which goes through the centre and
    loses all digits when the radius dwarfs the distances (``k`` of 1e-14 on a unit drawing).
    """
    x0, y0, th = pose
    c, s = math.cos(th), math.sin(th)
    dx, dy = pts[0] - x0, pts[1] - y0
    u, v = c * dx + s * dy, -s * dx + c * dy
    ex, ey, _ = advance(pose, k, L)
    ends = np.minimum(np.hypot(dx, dy), np.hypot(pts[0] - float(ex), pts[1] - float(ey)))
    if k == 0.0:
        return np.where((u >= 0) & (u <= L), np.abs(v), ends)
    ak, w = abs(k), math.copysign(1.0, k) * v
    swept = np.mod(np.arctan2(ak * u, 1.0 - ak * w), _TWO_PI)
    rho = np.hypot(ak * u, 1.0 - ak * w)  # |k| times the distance to the centre
    radial = np.abs(ak * (u * u + w * w) - 2.0 * w) / (rho + 1.0)
    return np.where(swept <= ak * L, radial, ends)


def _chain_dist(pts: np.ndarray, poses: Sequence[Pose], segs: Sequence[Segment]) -> tuple[np.ndarray, np.ndarray]:
    d = np.vstack([_seg_dist(pts, p, k, L) for p, (k, L) in zip(poses, segs)])
    idx = np.argmin(d, axis=0)
    return d[idx, np.arange(d.shape[1])], idx


# --------------------------------------------------------------------------------------------------
# Certificates
# --------------------------------------------------------------------------------------------------


class _Cert(NamedTuple):
    bound: float  # certified upper bound of the Hausdorff distance
    sampled: float  # largest sampled distance
    x: float  # curve point where the largest sampled distance was found
    y: float
    piece: int
    t: float
    segment: int  # index (within the chain) of the segment nearest there
    ok: bool  # bound <= target


_FAIL = _Cert(math.inf, math.inf, math.nan, math.nan, -1, math.nan, 0, False)


def _gl_lengths(piece: Piece, ta: np.ndarray, tb: np.ndarray) -> np.ndarray:
    """Arc length of each interval ``[ta, tb]`` by 5-point Gauss-Legendre."""
    x, w = _GL5
    mid, half = 0.5 * (ta + tb), 0.5 * (tb - ta)
    tt = (mid[:, None] + half[:, None] * x[None, :]).ravel()
    d = piece.d1(tt)
    sp = np.hypot(d[0], d[1]).reshape(-1, x.size)
    return np.abs(half) * (sp @ w)


def _lipschitz_max(x, first, gaps, evaluate, gap_fn, target, slack, cap):
    """Adaptive sampling of a 1-Lipschitz function (in arc length) until its maximum is bounded.

    ``evaluate(x) -> (values, extra arrays)``; ``first`` is its result at the initial samples ``x``,
    ``gaps`` the arc lengths between them. Between samples ``x_i, x_{i+1}`` (``g_i`` apart) the
    function cannot exceed ``(f_i + f_{i+1} + g_i) / 2``. Intervals whose bound exceeds
    ``min(target, max f + slack)`` are halved until none does, a sample exceeds ``target`` (no
    certificate possible), or ``cap`` samples. Returns ``(x, f, extra, bound)``.
    """
    f, extra = first
    while True:
        u = 0.5 * (f[:-1] + f[1:] + gaps)
        fmax = float(np.max(f))
        if fmax > target:
            break
        bad = u > min(target, fmax + slack)
        if not np.any(bad) or x.size >= cap:
            break
        idx = np.nonzero(bad)[0]
        xm = 0.5 * (x[idx] + x[idx + 1])
        fm, em = evaluate(xm)
        gl, gr = gap_fn(x[idx], xm), gap_fn(xm, x[idx + 1])
        x = np.insert(x, idx + 1, xm)
        f = np.insert(f, idx + 1, fm)
        extra = [np.insert(e, idx + 1, n) for e, n in zip(extra, em)]
        gaps = gaps.copy()
        gaps[idx] = gl
        gaps = np.insert(gaps, idx + 1, gr)
    bound = float(max(np.max(0.5 * (f[:-1] + f[1:] + gaps)) if gaps.size else 0.0, np.max(f)))
    return x, f, extra, bound


def _foot_points(q: np.ndarray, samples: list[tuple[int, Piece, np.ndarray, np.ndarray]], tree: cKDTree,
                 offsets: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Upper bounds of the distances from points ``q`` (shape ``(2, m)``) to the curve window.

    Nearest curve sample (k-d tree), then Newton steps on ``(r(t) - q) . r'(t) = 0`` inside the
    sample's neighbouring interval; every distance evaluated is to a true curve point, so the minimum
    kept is an upper bound of the distance to the curve (and close to it). Returns distances, and the
    piece index and ``t`` of the nearest point found.
    """
    dist, flat = tree.query(q.T)
    dist = np.asarray(dist, float)
    w = np.searchsorted(offsets, flat, side="right") - 1
    best_piece = np.empty(q.shape[1], dtype=int)
    best_t = np.empty(q.shape[1])
    for wi, (pi, piece, t, _) in enumerate(samples):
        m = np.nonzero(w == wi)[0]
        if m.size == 0:
            continue
        j = flat[m] - offsets[wi]
        lo, hi = t[np.maximum(j - 1, 0)], t[np.minimum(j + 1, t.size - 1)]
        tt = t[j].copy()
        best_piece[m], best_t[m] = pi, tt
        qq = q[:, m]
        d_best = dist[m]
        for _ in range(4):
            c, c1, c2 = piece.point(tt), piece.d1(tt), piece.d2(tt)
            r = c - qq
            g = np.sum(r * c1, axis=0)
            gp = np.sum(c1 * c1, axis=0) + np.sum(r * c2, axis=0)
            gp = np.where(gp > 0, gp, np.sum(c1 * c1, axis=0))
            with np.errstate(all="ignore"):
                step = np.where(gp > 0, -g / gp, 0.0)
            tt = np.clip(tt + np.nan_to_num(step), lo, hi)
            p = piece.point(tt)
            dn = np.hypot(p[0] - qq[0], p[1] - qq[1])
            better = dn < d_best
            d_best = np.where(better, dn, d_best)
            best_t[m] = np.where(better, tt, best_t[m])
        dist[m] = d_best
    return dist, best_piece, best_t


def _local(pose: Pose, k: float, x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Coordinates of points in a segment's start frame: ``u`` along the heading, ``w`` towards the centre."""
    c, s = math.cos(pose[2]), math.sin(pose[2])
    dx, dy = x - pose[0], y - pose[1]
    v = -s * dx + c * dy
    return c * dx + s * dy, (-v if k < 0 else v)


def _phi(ak: float, u: np.ndarray, w: np.ndarray) -> np.ndarray:
    """Signed distance to the circle (positive outside), or minus the signed distance to the line if ``ak == 0``.

    ``(|p - c|^2 - r^2) / (|p - c| + r)`` multiplied through by ``|k|``: no cancellation for huge radii.
    """
    return (ak * (u * u + w * w) - 2.0 * w) / (np.hypot(ak * u, 1.0 - ak * w) + 1.0)


def _chord_max(ak: float, u0, w0, u1, w1) -> np.ndarray:
    """Exact maximum over each chord ``[q0, q1]`` of the distance to a circle (or line).

    The signed distance ``|q - c| - r`` is convex along a segment: its maximum is at an end, its minimum
    at the point of the segment nearest the centre.
    """
    p0, p1 = _phi(ak, u0, w0), _phi(ak, u1, w1)
    lo = np.minimum(p0, p1)
    if ak > 0:
        du, dw = u1 - u0, w1 - w0
        with np.errstate(all="ignore"):
            lam = (-u0 * du * ak + (1.0 - ak * w0) * dw) / (ak * (du * du + dw * dw))
        lam = np.clip(np.nan_to_num(lam, nan=0.0, posinf=1.0, neginf=0.0), 0.0, 1.0)
        lo = np.minimum(lo, _phi(ak, u0 + lam * du, w0 + lam * dw))
    return np.maximum(np.maximum(p0, p1), -lo)


def _swept(ak: float, u: np.ndarray, w: np.ndarray) -> np.ndarray:
    """Angle turned from the segment's start to a point's radial direction, in ``(-pi, pi]``; ``u`` on a line."""
    return np.arctan2(ak * u, 1.0 - ak * w) if ak > 0 else u


def _elements(poses: Sequence[Pose], segs: Sequence[Segment]):
    """Sectors on which the distance to the chain is the distance to one circle, and arc pieces to cover.

    A-elements ``(segment, lo, hi)``: a convex sector (swept angle ``lo..hi`` of at most 0.9 pi, or the
    whole plane for a full turn; a slab ``lo <= u <= hi`` for a line). B-elements ``(segment, pose,
    sweep)``: pieces of at most pi/2 of each arc (a line whole).
    """
    a_el, b_el = [], []
    for j, (p, (k, L)) in enumerate(zip(poses, segs)):
        ak = abs(k)
        turn = ak * L
        if k == 0.0:
            a_el.append((j, 0.0, L))
            b_el.append((j, p, L))
            continue
        if turn >= _TWO_PI:
            a_el.append((j, 0.0, math.inf))
        elif turn <= 0.9 * math.pi:
            a_el.append((j, 0.0, turn))
        else:
            n = math.ceil(turn / (0.45 * math.pi))
            step = turn / n
            a_el.extend((j, i * step, min((i + 2) * step, turn)) for i in range(n - 1))
        n = max(1, math.ceil(turn / (0.5 * math.pi)))
        step = turn / n
        for i in range(n):
            start = Pose(*(float(v) for v in advance(p, k, i * step / ak)))
            b_el.append((j, start, step))
    return a_el, b_el


def _certify(pieces: Sequence[Piece], window: Sequence[tuple[int, float, float]], pose: Pose,
             segs: Sequence[Segment], target: float, slack: float, cap: int = 4000) -> _Cert:
    """Certified upper bound of the Hausdorff distance between a chain of segments and a curve window.

    The window is sampled at ``C_i``; between samples the curve has arc length ``g_i`` (5-point
    Gauss-Legendre) and chord ``c_i``, so it lies in the ellipse with foci ``C_i, C_{i+1}`` and major
    axis ``g_i``: every curve point there is within ``e_i = sqrt((g_i - c_i) g_i / 2)`` of the chord,
    and every chord point within ``b_i = sqrt(g_i^2 - c_i^2) / 2`` of the curve (the curve projects
    onto the whole chord).

    Curve to chain: if both chord ends lie in one convex sector of an arc (where the distance to the
    arc is the distance to its circle), the distance along the chord is at most the exact maximum
    ``M_i`` of the circle distance over the chord (:func:`_chord_max`), so the curve stays within
    ``M_i + e_i``. Otherwise the distance, 1-Lipschitz in arc length, is at most
    ``(f_i + f_{i+1} + g_i) / 2`` from the exact distances ``f`` at the samples.

    Chain to curve: a point of an arc at swept angle ``a`` has, on every chord whose ends' angles
    bracket ``a``, a point on the same ray, at ``|q - c| - r <= M_i`` from it, so within ``M_i + b_i``
    of the curve; if the chords' angle spans cover the arc piece, its bound is the largest such value.
    Otherwise (no cover) the arc piece is sampled (:func:`_lipschitz_max`, :func:`_foot_points`).

    Chords whose bound exceeds ``min(target, max f + slack)`` are halved until none does (or ``cap``
    samples); a sample farther than ``target`` rejects at once. Both bounds are second order in the
    sample spacing, so a few dozen samples usually suffice.
    """
    if not window:
        return _FAIL
    poses = _chain_poses(pose, segs)[:-1]
    a_el, b_el = _elements(poses, segs)
    subs = []
    for pi, ta, tb in window:
        piece = pieces[pi]
        t = np.linspace(ta, tb, 17)
        p = piece.point(t)
        f, idx = _chain_dist(p, poses, segs)
        subs.append([pi, piece, t, p, f, idx, _gl_lengths(piece, t[:-1], t[1:])])
    eps_len = 1e-9 * max(sum(s.length for s in segs), 1e-300)
    for _ in range(64):
        # Chords of every sub-span, then bridges over the (rounding) gaps between sub-spans.
        q0 = np.hstack([s[3][:, :-1] for s in subs] + [s[3][:, -1:] for s in subs[:-1]])
        q1 = np.hstack([s[3][:, 1:] for s in subs] + [s[3][:, :1] for s in subs[1:]])
        n_real = sum(s[2].size - 1 for s in subs)
        c = np.hypot(q1[0] - q0[0], q1[1] - q0[1])
        # Quadrature lengths, made safe against their own error (relative: 1e-13, or 1e-8 for a piece
        # whose derivatives are finite differences) and against rounding of the chords (absolute).
        g = np.concatenate([s[6] * (1.0 + (1e-8 if _noisy(s[1]) else 1e-13)) for s in subs] + [c[n_real:]])
        g = np.maximum(g, c) + 1e-15 * (np.abs(q0).max(axis=0) + np.abs(q1).max(axis=0))
        e = np.sqrt((g - c) * g / 2.0)
        b = np.sqrt(np.maximum(g * g - c * c, 0.0)) / 2.0
        b[n_real:] = c[n_real:] / 2.0
        f0 = np.concatenate([s[4][:-1] for s in subs])
        f1 = np.concatenate([s[4][1:] for s in subs])
        if not (np.all(np.isfinite(c)) and np.all(np.isfinite(g)) and np.all(np.isfinite(f0))):
            return _FAIL
        loc = []  # per segment: (M, u0, w0, u1, w1)
        for p, (k, _) in zip(poses, segs):
            u0, w0 = _local(p, k, q0[0], q0[1])
            u1, w1 = _local(p, k, q1[0], q1[1])
            loc.append((_chord_max(abs(k), u0, w0, u1, w1), u0, w0, u1, w1))
        bound_a = 0.5 * (f0 + f1 + g[:n_real])
        for j, lo, hi in a_el:
            # The sector is widened by eps_len (in length) so that the window's own end points, on its
            # boundary up to rounding, fall inside; a point that far outside is at most eps_len times
            # max(1, |k| |q - c|) farther from the arc than from its circle.
            k = segs[j].curvature
            M, u0, w0, u1, w1 = loc[j]
            u0, w0, u1, w1 = u0[:n_real], w0[:n_real], u1[:n_real], w1[:n_real]
            if math.isinf(hi):
                inside, pen = np.ones(n_real, dtype=bool), 0.0
            elif k == 0.0:
                lo_, hi_ = lo - eps_len, hi + eps_len
                inside = (u0 >= lo_) & (u0 <= hi_) & (u1 >= lo_) & (u1 <= hi_)
                pen = eps_len
            else:
                ak = abs(k)
                widen = eps_len * ak
                s0 = np.mod(_swept(ak, u0, w0) - lo + widen, _TWO_PI)
                s1 = np.mod(_swept(ak, u1, w1) - lo + widen, _TWO_PI)
                inside = (s0 <= hi - lo + 2 * widen) & (s1 <= hi - lo + 2 * widen)
                pen = eps_len * np.maximum(1.0, np.maximum(np.hypot(ak * u0, 1 - ak * w0), np.hypot(ak * u1, 1 - ak * w1)))
            bound_a = np.where(inside, np.minimum(bound_a, M[:n_real] + e[:n_real] + pen), bound_a)
        refine = np.zeros(c.size, dtype=bool)
        fmax = float(max(np.max(s[4]) for s in subs))
        if fmax > target:
            break
        theta = min(target, fmax + slack)
        refine[:n_real] |= bound_a > theta
        bound_b, fallback = 0.0, []
        for j, p, sweep in b_el:
            k = segs[j].curvature
            ak = abs(k)
            M = loc[j][0]
            u0, w0 = _local(p, k, q0[0], q0[1])
            u1, w1 = _local(p, k, q1[0], q1[1])
            s0, s1 = _swept(ak, u0, w0), _swept(ak, u1, w1)
            lo, hi = np.minimum(s0, s1), np.maximum(s0, s1)
            ok = np.isfinite(lo) & np.isfinite(hi) & (lo <= sweep) & (hi >= 0.0)
            if ak > 0:
                ok &= hi - lo <= 0.5 * math.pi
            idx = np.nonzero(ok)[0]
            tol_cov = 1e-3 * eps_len * (ak if ak > 0 else 1.0)
            reach = 0.0
            covered = idx.size > 0
            for i in idx[np.argsort(lo[idx], kind="stable")]:
                if lo[i] > reach + tol_cov:
                    covered = False
                    break
                reach = max(reach, hi[i])
            if not covered or reach < sweep - tol_cov:
                fallback.append((j, p, sweep))
                continue
            val = M[idx] + b[idx]
            bound_b = max(bound_b, float(np.max(val)) + 1e-3 * eps_len)
            refine[idx[val > theta]] = True
        refine[n_real:] = False
        if not np.any(refine) or sum(s[2].size for s in subs) >= cap * len(subs):
            break
        # Halve the flagged chords, sub-span by sub-span.
        start = 0
        for s in subs:
            m = s[2].size - 1
            r = np.nonzero(refine[start:start + m])[0]
            start += m
            if r.size == 0:
                continue
            t = s[2]
            tm = 0.5 * (t[r] + t[r + 1])
            pm = s[1].point(tm)
            fm, im = _chain_dist(pm, poses, segs)
            gl, gr = _gl_lengths(s[1], t[r], tm), _gl_lengths(s[1], tm, t[r + 1])
            s[2] = np.insert(t, r + 1, tm)
            s[3] = np.insert(s[3], r + 1, pm, axis=1)
            s[4] = np.insert(s[4], r + 1, fm)
            s[5] = np.insert(s[5], r + 1, im)
            gg = s[6].copy()
            gg[r] = gl
            s[6] = np.insert(gg, r + 1, gr)
    # Where the largest exact (sampled) distance is.
    si = max(range(len(subs)), key=lambda i: float(np.max(subs[i][4])))
    s = subs[si]
    i = int(np.argmax(s[4]))
    best = (float(s[4][i]), float(s[3][0, i]), float(s[3][1, i]), s[0], float(s[2][i]), int(s[5][i]))
    if best[0] > target:
        return _Cert(max(best[0], float(np.max(bound_a)) if bound_a.size else best[0]), *best, False)
    bound = max(float(np.max(bound_a)) if bound_a.size else 0.0, bound_b, best[0])
    if bound > target or not fallback:
        return _Cert(bound, *best, bound <= target)
    # Arc pieces the chords do not cover: sample them (distances to true curve points, upper bounds).
    samples = [(sp[0], sp[1], sp[2], sp[3]) for sp in subs]
    offsets = np.concatenate([[0], np.cumsum([sp[2].size for sp in subs])])
    tree = cKDTree(np.hstack([sp[3] for sp in subs]).T)
    for j, p0, sweep in fallback:
        k = segs[j].curvature
        L = sweep / abs(k) if k != 0.0 else sweep

        def evb(sig, p0=p0, k=k):
            x, y, _ = advance(p0, k, sig)
            q = np.vstack([np.atleast_1d(x), np.atleast_1d(y)])
            d, fp, ft = _foot_points(q, samples, tree, offsets)
            return d, [fp, ft]

        sig = np.linspace(0.0, L, 17)
        _, f, _, b_el_bound = _lipschitz_max(sig, evb(sig), np.diff(sig), evb, lambda a, c: c - a,
                                             target, slack, 20000)
        if not np.all(np.isfinite(f)):
            return _FAIL
        bound = max(bound, b_el_bound)
        if bound > target:
            break
    return _Cert(bound, *best, bound <= target)


# --------------------------------------------------------------------------------------------------
# Runs: locations, windows, greedy and minimum-count breakpoints
# --------------------------------------------------------------------------------------------------

_Loc = tuple  # (span index within the run, t on that span's piece)


class _Interval(NamedTuple):
    a: _Loc
    b: _Loc
    segs: tuple[Segment, ...]
    cert: _Cert


class _RunGeom:
    """A run's spans with an arc-length table, the curve data at any location, and windows."""

    def __init__(self, pieces: Sequence[Piece], run: Run):
        self.pieces = pieces
        self.spans = run.spans
        self.tabs = []
        offs = [0.0]
        for sp in run.spans:
            t = np.linspace(sp.t0, sp.t1, 65)
            s = np.concatenate([[0.0], np.cumsum(_gl_lengths(pieces[sp.piece], t[:-1], t[1:]))])
            self.tabs.append((t, s))
            offs.append(offs[-1] + float(s[-1]))
        self.offsets = np.array(offs)
        self.length = float(offs[-1])

    def s(self, loc: _Loc) -> float:
        k, t = loc
        tt, ss = self.tabs[k]
        return float(self.offsets[k] + np.interp(t, tt, ss))

    def loc_at(self, s: float) -> _Loc:
        k = int(np.clip(np.searchsorted(self.offsets, s, side="right") - 1, 0, len(self.spans) - 1))
        tt, ss = self.tabs[k]
        return (k, float(np.interp(s - self.offsets[k], ss, tt)))

    def heading(self, loc: _Loc) -> float:
        k, t = loc
        sp = self.spans[k]
        if t == sp.t0:
            return sp.heading0
        if t == sp.t1:
            return sp.heading1
        piece = self.pieces[sp.piece]
        d = _col(piece, "d1", t)
        if math.hypot(d[0], d[1]) > 0:
            return math.atan2(d[1], d[0])
        v = _direction(piece, t, +1, 1.0, True)
        return sp.heading0 if v is None else math.atan2(v[1], v[0])

    def data(self, loc: _Loc) -> Pose:
        k, t = loc
        x, y = _col(self.pieces[self.spans[k].piece], "point", t)
        return Pose(float(x), float(y), self.heading(loc))

    def window(self, a: _Loc, b: _Loc) -> list[tuple[int, float, float]]:
        (ka, ta), (kb, tb) = a, b
        sp = self.spans
        if ka == kb:
            return [(sp[ka].piece, ta, tb)]
        out = [(sp[ka].piece, ta, sp[ka].t1)]
        out += [(sp[k].piece, sp[k].t0, sp[k].t1) for k in range(ka + 1, kb)]
        out.append((sp[kb].piece, sp[kb].t0, tb))
        return [w for w in out if w[2] > w[1]]

    def window_length(self, a: _Loc, b: _Loc) -> float:
        return sum(piece_length(self.pieces[p], t0, t1, 32) for p, t0, t1 in self.window(a, b))


class _Budget:
    """Counts certificates and biarcs for one path (the ``nfev`` of a fit)."""

    def __init__(self) -> None:
        self.certificates = 0
        self.intervals = 0


class _Fitter:
    """Everything one path's fit needs, without globals."""

    def __init__(self, path: Path, scale: float, tol: float):
        self.path, self.pieces, self.scale, self.tol = path, path.pieces, scale, tol
        self.slack = tol / 8.0
        self.budget = _Budget()
        self.failures: list[str] = []
        self.notes: list[str] = []

    def certify(self, geom: _RunGeom, a: _Loc, b: _Loc, pose: Pose, segs, tight: bool = True) -> _Cert:
        """Certificate within ``tol``; ``tight`` refines until the bound is within ``tol/8`` of the samples."""
        self.budget.certificates += 1
        if segs is None:
            return _FAIL
        return _certify(self.pieces, geom.window(a, b), pose, segs, self.tol, self.slack if tight else math.inf)

    def edge(self, geom: _RunGeom, a: _Loc, b: _Loc, exact: bool = False) -> _Interval:
        """Biarc (or, for a whole constant-curvature span, the exact arc) between two locations, certified."""
        p0, p1 = geom.data(a), geom.data(b)
        if exact:
            segs = self._exact_arc(geom, a, p0, p1)
            cert = self.certify(geom, a, b, p0, segs)
            if cert.ok:
                return _Interval(a, b, segs, cert)
        segs = _biarc(*p0, *p1)
        return _Interval(a, b, segs, self.certify(geom, a, b, p0, segs))

    def _exact_arc(self, geom: _RunGeom, a: _Loc, p0: Pose, p1: Pose) -> tuple[Segment]:
        """One arc (or line) for a whole span of constant curvature.

        It leaves ``p0`` along its direction and passes exactly through ``p1`` (so runs meet end to
        start); only an arc turning by 1.5 pi or more, whose chord says too little, takes the curve's
        mean curvature and length instead.
        """
        sp = geom.spans[a[0]]
        piece = self.pieces[sp.piece]
        L = piece_length(piece, sp.t0, sp.t1, 64)
        k = 0.0
        if sp.kind == "arc":
            kk = curvature(piece, np.linspace(sp.t0, sp.t1, 33))
            k = float(np.median(kk[np.isfinite(kk)])) if np.any(np.isfinite(kk)) else 0.0
        d = math.hypot(p1.x - p0.x, p1.y - p0.y)
        if abs(k) * L < 1.5 * math.pi and d > 0:
            half = _wrap(math.atan2(p1.y - p0.y, p1.x - p0.x) - p0.heading)
            sinc = math.sin(half) / half if half != 0.0 else 1.0
            if sinc > 0.5:
                k, L = 2.0 * math.sin(half) / d, d / sinc
        if abs(k) * L <= 1e-13:
            k = 0.0
        return (Segment(k, L),)

    def greedy(self, geom: _RunGeom) -> list[_Interval]:
        """Halve each spiral span at its arc-length midpoint until every biarc is within ``tol``."""
        out: list[_Interval] = []
        min_len = MIN_SPAN * self.scale
        for k, sp in enumerate(geom.spans):
            stack = [((k, sp.t0), (k, sp.t1))]
            while stack:
                a, b = stack.pop()
                self.budget.intervals += 1
                if self.budget.intervals > MAX_INTERVALS:
                    raise _TooMany()
                whole = a[1] == sp.t0 and b[1] == sp.t1 and sp.kind != "spiral"
                iv = self.edge(geom, a, b, exact=whole)
                if iv.cert.ok:
                    out.append(iv)
                    continue
                if geom.window_length(a, b) <= min_len:
                    self.failures.append(f"piece {sp.piece}, t in [{a[1]:.9g}, {b[1]:.9g}]: bound "
                                         f"{iv.cert.bound:.3g} > tol after halving to {min_len:.3g}")
                    out.append(iv if iv.segs is not None else self._fallback(geom, a, b))
                    continue
                tm = geom.loc_at(0.5 * (geom.s(a) + geom.s(b)))[1]
                if not a[1] < tm < b[1]:
                    tm = 0.5 * (a[1] + b[1])
                if not a[1] < tm < b[1]:
                    self.failures.append(f"piece {sp.piece}, t = {a[1]!r}: span cannot be halved")
                    out.append(iv if iv.segs is not None else self._fallback(geom, a, b))
                    continue
                stack.append(((k, tm), b))
                stack.append((a, (k, tm)))
        return out

    def _fallback(self, geom: _RunGeom, a: _Loc, b: _Loc) -> _Interval:
        """A failed, unsplittable stretch: a biarc is undefined, so keep a line along the start direction."""
        p0, p1 = geom.data(a), geom.data(b)
        L = max(math.hypot(p1.x - p0.x, p1.y - p0.y), MIN_SPAN * self.scale)
        segs = (Segment(0.0, L),)
        return _Interval(a, b, segs, self.certify(geom, a, b, p0, segs)._replace(ok=False))

    def minimum(self, geom: _RunGeom, greedy: list[_Interval]) -> list[_Interval]:
        """Fewest arcs over candidate breakpoints: greedy's plus ``MIN_DENSITY`` per greedy biarc.

        Edge ``i -> j`` when the biarc between candidates ``i`` and ``j`` is certified within ``tol``,
        weight its number of segments; shortest path by dynamic programming. Which ``j`` each ``i``
        reaches is found by a two-pointer sweep (a sub-window of a feasible window is assumed feasible
        while sweeping); every edge of the chosen path is certified before it is used, infeasible ones
        are removed and the path recomputed. Greedy's own edges are always in the graph, so the result
        never has more segments than greedy's.
        """
        if len(greedy) < 2 or any(not iv.cert.ok for iv in greedy):
            return greedy
        # Candidates in arc-length order: greedy's breakpoints, and uniform ones not within rounding of them.
        eps = 1e-12 * max(geom.length, 1e-300)
        items = [(geom.s(x), 0, g, x) for g, x in enumerate([greedy[0].a] + [iv.b for iv in greedy])]
        n_uni = int(np.clip(MIN_DENSITY * len(greedy), 8, 2000))
        items += [(float(v), 1, -1, geom.loc_at(float(v))) for v in np.linspace(0.0, geom.length, n_uni + 1)[1:-1]]
        items.sort(key=lambda it: (it[0], it[1]))
        cand: list[_Loc] = []
        keep_g: dict[int, int] = {}
        last_s, last_greedy = -math.inf, False
        for sv, uniform, g, loc in items:
            if sv - last_s <= eps and (uniform or not last_greedy):
                if uniform:
                    continue
                cand.pop()  # a greedy breakpoint replaces a uniform one at the same place
            if not uniform:
                keep_g[g] = len(cand)
            cand.append(loc)
            last_s, last_greedy = sv, not uniform
        m = len(cand)
        cache: dict[tuple[int, int], _Interval] = {}
        loose: set[tuple[int, int]] = set()
        for g, iv in enumerate(greedy):
            cache[(keep_g[g], keep_g[g + 1])] = iv
        data = [geom.data(c) for c in cand]

        budget = self.budget.certificates + MIN_BUDGET * len(greedy) + 100

        def feasible(i: int, j: int) -> bool:
            if (i, j) not in cache:
                if self.budget.certificates > budget:
                    raise _OverBudget()
                if not geom.window(cand[i], cand[j]):
                    return False
                segs = _biarc(*data[i], *data[j])
                # Feasibility only: refine until the bound is below tol, not until it is tight.
                cert = self.certify(geom, cand[i], cand[j], data[i], segs, tight=False)
                cache[(i, j)] = _Interval(cand[i], cand[j], segs, cert)
                loose.add((i, j))
            return cache[(i, j)].cert.ok

        try:
            return self._shortest(geom, greedy, cand, data, cache, loose, feasible)
        except _OverBudget:
            self.notes.append(f"minimum-count search over {m} candidates stopped at its budget; kept greedy's")
            return greedy

    def _shortest(self, geom, greedy, cand, data, cache, loose, feasible) -> list[_Interval]:
        """Reach of each candidate (two-pointer sweep), then the shortest certified path (see :meth:`minimum`)."""
        m = len(cand)
        reach = list(range(m))
        j = 1
        for i in range(m - 1):
            j = max(j, i + 1)
            if feasible(i, j):
                while j + 1 < m and feasible(i, j + 1):
                    j += 1
            else:
                j -= 1
                while j > i and not feasible(i, j):
                    j -= 1
            reach[i] = j
            j = max(j, i + 1)
        weights: dict[tuple[int, int], int] = {}

        def weight(i: int, j: int) -> int:
            if (i, j) not in weights:
                iv = cache.get((i, j))
                segs = iv.segs if iv is not None else _biarc(*data[i], *data[j])
                weights[(i, j)] = len(segs) if segs is not None else 10 ** 9
            return weights[(i, j)]

        banned: set[tuple[int, int]] = set()
        gsum = sum(len(iv.segs) for iv in greedy)
        for _ in range(50):
            cost = [math.inf] * m
            back = [-1] * m
            cost[0] = 0.0
            known: dict[int, set[int]] = {}  # certified edges beyond the sweep's reach (greedy's, say)
            for (a, b), iv in cache.items():
                if iv.cert.ok:
                    known.setdefault(a, set()).add(b)
            for i in range(m - 1):
                if cost[i] == math.inf:
                    continue
                for j in sorted(known.get(i, set()).union(range(i + 1, reach[i] + 1))):
                    if (i, j) in banned:
                        continue
                    c = cost[i] + weight(i, j)
                    if c < cost[j]:
                        cost[j], back[j] = c, i
            if cost[m - 1] >= gsum:
                return greedy
            path = [m - 1]
            while path[-1] != 0:
                path.append(back[path[-1]])
            path.reverse()
            bad = [(i, j) for i, j in zip(path[:-1], path[1:]) if not feasible(i, j)]
            if not bad:
                out = []
                for i, j in zip(path[:-1], path[1:]):
                    iv = cache[(i, j)]
                    if (i, j) in loose:  # the bound to report: refine as greedy's are
                        iv = iv._replace(cert=self.certify(geom, iv.a, iv.b, data[i], iv.segs))
                    out.append(iv)
                return out
            banned.update(bad)
        return greedy

    def realise(self, geom: _RunGeom, intervals: list[_Interval], free_start: bool, free_end: bool
                ) -> tuple["FittedRun", list[_Cert]]:
        """Lay the intervals' segments out from the run's start, snapping near-straight biarcs to lines.

        A biarc is replaced by one line along the current direction when that line is certified within
        ``tol`` and the next biarc, refitted from the line's end, is too (and the count does not grow).
        Where the run's start direction is free (after a corner, or at the start of an open path) the
        first line may follow the chord instead; the last interval is only replaced when the line ends
        on the run's end point (and direction, unless the end is free too). Laying segments out from the
        previous segment's end can shift a biarc from its ideal start by rounding; that shift (position,
        plus heading times length) is added to its bound.
        """
        start = geom.data(intervals[0].a)
        pose = start
        segs_out: list[Segment] = []
        certs: list[_Cert] = []
        knots: list[Knot] = []
        carry: _Interval | None = None
        n = len(intervals)
        for j, iv in enumerate(intervals):
            knots.append(Knot(geom.spans[iv.a[0]].piece, iv.a[1], len(segs_out)))
            if carry is not None:
                segs, cert = carry.segs, carry.cert
                carry = None
            else:
                ideal = geom.data(iv.a)
                drift = (math.hypot(pose.x - ideal.x, pose.y - ideal.y)
                         + abs(_wrap(pose.heading - ideal.heading)) * sum(s.length for s in iv.segs))
                segs, cert = iv.segs, iv.cert._replace(bound=iv.cert.bound + drift)
            if cert.ok and any(s.curvature != 0.0 for s in segs):
                snapped = self._snap(geom, pose, iv, intervals[j + 1] if j + 1 < n else None, segs,
                                     chord=j == 0 and free_start, free_end=free_end)
                if snapped is not None:
                    (segs, cert, pose), carry = snapped
                    if j == 0:
                        start = pose
            certs.append(cert._replace(segment=len(segs_out) + cert.segment))
            segs_out.extend(segs)
            pose = _chain_poses(pose, segs)[-1]
        run = FittedRun(start=start, segments=tuple(segs_out), corner=None,
                        hausdorff=max(c.bound for c in certs), curve_length=geom.length, knots=tuple(knots))
        return run, certs

    def _snap(self, geom, pose, iv, nxt, segs, chord, free_end):
        L = sum(s.length for s in segs)
        if max(abs(s.curvature) for s in segs) * L * L > self.tol:
            return None
        target = geom.data(iv.b)
        dx, dy = target.x - pose.x, target.y - pose.y
        if chord:
            ell = math.hypot(dx, dy)
            pose = Pose(pose.x, pose.y, math.atan2(dy, dx))
        else:
            ell = dx * math.cos(pose.heading) + dy * math.sin(pose.heading)
        if not ell > 0:
            return None
        line = (Segment(0.0, ell),)
        lcert = self.certify(geom, iv.a, iv.b, pose, line)
        if not lcert.ok:
            return None
        end = _chain_poses(pose, line)[-1]
        if nxt is None:
            exact = (math.hypot(end.x - target.x, end.y - target.y) <= 1e-12 * self.scale
                     and (free_end or abs(_wrap(end.heading - target.heading)) <= 1e-12))
            return ((line, lcert, pose), None) if exact else None
        segs2 = _biarc(*end, *geom.data(nxt.b))
        if segs2 is None or 1 + len(segs2) > len(segs) + len(nxt.segs):
            return None
        c2 = self.certify(geom, nxt.a, nxt.b, end, segs2)
        if not c2.ok:
            return None
        return (line, lcert, pose), _Interval(nxt.a, nxt.b, segs2, c2)


class _TooMany(Exception):
    pass


class _OverBudget(Exception):
    pass


# --------------------------------------------------------------------------------------------------
# Results
# --------------------------------------------------------------------------------------------------


class Knot(NamedTuple):
    """Where a biarc (or line) of a fitted run starts on the path: ``piece``, ``t``, and its first segment."""

    piece: int
    t: float
    segment: int


class Where(NamedTuple):
    """Where the largest sampled distance between a fit and its curve was found.

    ``x, y`` is the curve point (on ``piece`` at parameter ``t``); ``run`` and ``segment`` locate the
    nearest fitted segment; ``distance`` is the sampled distance there.
    """

    x: float
    y: float
    piece: int
    t: float
    run: int
    segment: int
    distance: float


def corner_join(corner: float | None, reverse_above_deg: float = 90.0) -> Join | None:
    """The figure join for a run's ``corner`` (as :attr:`Run.corner`); ``None`` if there is none.

    ``0.0`` is a smooth join. Otherwise a cusp join: if ``|corner|`` exceeds ``reverse_above_deg``
    the blade reverses (a true cusp) and pivots by ``remainder(corner - pi, 2 pi)``, else it pivots
    by ``corner``; either way the travel direction after the join has turned by ``corner``.

    Examples
    --------
    >>> corner_join(None) is None, corner_join(0.0) == SMOOTH
    (True, True)
    >>> j = corner_join(0.75 * math.pi)
    >>> j.kind, round(math.degrees(j.pivot), 9), j.reverse
    ('cusp', -45.0, True)
    """
    if corner is None:
        return None
    if corner == 0.0:
        return SMOOTH
    if abs(corner) > math.radians(reverse_above_deg):
        return Join("cusp", math.remainder(corner - math.pi, _TWO_PI), True)
    return Join("cusp", corner)


@dataclass(frozen=True, slots=True, kw_only=True)
class FittedRun:
    """One run replaced by arcs and lines joined tangentially.

    Attributes
    ----------
    start : Pose
        Start point and travel direction (the curve's).
    segments : tuple of Segment
        Laid out one after the other from ``start`` (G1 by construction).
    corner : float or None
        As :attr:`Run.corner`: the signed turn of travel direction at the corner before this run.
    hausdorff : float
        Certified upper bound of the Hausdorff distance between these segments and the run.
    curve_length : float
        Length of the run of curve.
    knots : tuple of Knot
        Curve locations where each biarc (or line) starts.
    """

    start: Pose
    segments: tuple[Segment, ...]
    corner: float | None
    hausdorff: float
    curve_length: float
    knots: tuple[Knot, ...] = ()

    @property
    def length(self) -> float:
        return float(sum(s.length for s in self.segments))

    def poses(self) -> list[Pose]:
        """Start pose of every segment, then the end pose (``len(segments) + 1`` poses)."""
        return _chain_poses(self.start, self.segments)

    def join(self, reverse_above_deg: float = 90.0) -> Join | None:
        """The figure join at the corner before this run (``None`` if there is none); see :func:`corner_join`."""
        return corner_join(self.corner, reverse_above_deg)


class FitStatus(Enum):
    """Outcome of fitting a path; the value is the message."""

    SUCCESS = "every run is within the tolerance (certified)"
    SUBDIVISION_LIMIT = "a span could not be fitted within the tolerance before reaching the minimum span length"
    TOO_MANY_ARCS = "the fit needed more biarcs than the limit"


@dataclass(frozen=True, slots=True, kw_only=True)
class PathFit:
    """A path approximated by G1 arc splines, one per run, with a certified distance.

    Attributes
    ----------
    success, status, message
        ``success`` is ``hausdorff <= tol``; otherwise ``status``/``message`` say what failed where.
    runs : tuple of FittedRun
    hausdorff : float
        Certified upper bound of the Hausdorff distance between the arc splines (each run laid out
        from its own start) and the path, the largest over all runs.
    hausdorff_sampled : float
        Largest exact distance from a sampled curve point to its arcs: a lower bound of the largest
        distance from the curve to the fit, and within ``tol / 8`` of ``hausdorff`` when the fit
        succeeds.
    where : Where or None
        Where ``hausdorff_sampled`` was found.
    n_arcs, n_lines : int
        Segments of non-zero and of zero curvature.
    curve_length, spline_length : float
    greedy_count, min_count : int, int or None
        Segments used by the greedy fit, and by the minimum-count fit (``None`` unless ``method="min"``).
        The result uses the smaller.
    certificates : int
        Number of biarc certificates computed (the cost of the fit).
    """

    success: bool
    status: FitStatus
    message: str
    runs: tuple[FittedRun, ...]
    hausdorff: float
    hausdorff_sampled: float
    where: Where | None
    n_arcs: int
    n_lines: int
    curve_length: float
    spline_length: float
    tol: float
    method: str
    greedy_count: int
    min_count: int | None
    certificates: int
    closed: bool
    name: str
    size: float

    @property
    def n_segments(self) -> int:
        return self.n_arcs + self.n_lines


@dataclass(frozen=True, slots=True, kw_only=True)
class DrawingFit:
    """Every path of a drawing fitted; the bound and counts are over all paths."""

    success: bool
    message: str
    paths: tuple[PathFit, ...]
    hausdorff: float
    hausdorff_sampled: float
    n_arcs: int
    n_lines: int
    worst_path: int
    name: str = ""
    extra: dict = field(default_factory=dict, compare=False)

    @property
    def status(self) -> FitStatus:
        bad = [p.status for p in self.paths if not p.success]
        return bad[0] if bad else FitStatus.SUCCESS


# --------------------------------------------------------------------------------------------------
# Public fitting functions
# --------------------------------------------------------------------------------------------------


def _check_tol(tol) -> float:
    if isinstance(tol, bool) or not isinstance(tol, (int, float, np.floating)) or not (math.isfinite(tol) and tol > 0):
        raise FitError(f"tol must be a positive finite distance, got {tol!r}")
    return float(tol)


def _check_method(method) -> str:
    if method not in ("greedy", "min"):
        raise FitError(f"method must be 'greedy' or 'min', got {method!r}")
    return method


def fit_path(path: Path, tol: float, *, method: str = "greedy", corner_tol_deg: float = 0.5) -> PathFit:
    """Approximate a path by G1 arc splines within a certified Hausdorff distance ``tol``.

    Parameters
    ----------
    path : skatetrace.drawings.curves.Path
    tol : float
        Largest allowed Hausdorff distance, in the path's units.
    method : {"greedy", "min"}
        ``"greedy"`` halves spiral spans at their arc-length midpoint until each biarc is within
        ``tol``. ``"min"`` then looks for fewer arcs over candidate breakpoints (a shortest path) and
        keeps whichever of the two uses fewer segments.
    corner_tol_deg : float
        See :func:`split_path`.

    Returns
    -------
    PathFit
        ``success`` False (with a warning) when a span could not be fitted before reaching
        ``MIN_SPAN`` times the size; the runs then still hold the best fit found and its honest bound.

    Raises
    ------
    FitError
        Invalid ``tol``, ``method`` or ``corner_tol_deg``, or a path that cannot be split (see
        :func:`split_path`).

    Notes
    -----
    Certificate: for each biarc and the stretch of curve it replaces, the distance from a curve point
    to the biarc is a 1-Lipschitz function of the curve's arc length, and the distance from a biarc
    point to the curve a 1-Lipschitz function of the biarc's. Sampling either at arc-length gaps
    ``g_i`` bounds it between samples by ``(f_i + f_{i+1} + g_i) / 2``; gaps are halved adaptively
    until that bound is within ``tol / 8`` of the largest sample (or above ``tol``: rejected). The
    first direction uses exact distances to arcs, the second distances to true curve points (nearest
    sample refined by Newton steps), which can only over-estimate. Hence ``hausdorff`` is an upper
    bound, up to the accuracy of the 5-point Gauss-Legendre arc lengths of the gaps and to rounding,
    and at most about ``tol / 8`` above the sampled maximum.

    Examples
    --------
    >>> from skatetrace.drawings.curves import EllipticArcPiece
    >>> quarter = Path((EllipticArcPiece((0.0, 0.0), 2.0, 2.0, 0.0, 0.0, np.pi / 2),))
    >>> fit = fit_path(quarter, 1e-6)
    >>> fit.success, [(round(s.curvature, 12), round(s.length, 12)) for s in fit.runs[0].segments]
    (True, [(0.5, 3.14159265359)])
    >>> ellipse = Path((EllipticArcPiece((0.0, 0.0), 2.0, 1.0, 0.0, 0.0, np.pi / 2),))
    >>> fit = fit_path(ellipse, 1e-3)
    >>> fit.success, fit.hausdorff <= 1e-3, fit.n_arcs
    (True, True, 10)
    """
    tol = _check_tol(tol)
    method = _check_method(method)
    try:
        runs, prep = _split(path, corner_tol_deg)
        return _fit_runs(path, runs, prep.scale, tol, method)
    except ArithmeticError as exc:  # overflow in a user's piece, say; never a wrong answer
        raise FitError(f"path {path.name!r}: numerical failure while fitting ({exc})") from exc


def _fit_runs(path: Path, runs: list[Run], scale: float, tol: float, method: str) -> PathFit:
    fitter = _Fitter(path, scale, tol)
    fitted: list[FittedRun] = []
    certs_all: list[list[_Cert]] = []
    gcount, mcount = 0, 0
    status = FitStatus.SUCCESS
    with np.errstate(all="ignore"):
        try:
            for r, run in enumerate(runs):
                # A run's end directions are free where a corner (or the end of an open path) follows.
                nxt = runs[r + 1].corner if r + 1 < len(runs) else (runs[0].corner if path.closed else None)
                free_start, free_end = run.corner != 0.0, nxt != 0.0
                geom = _RunGeom(path.pieces, run)
                greedy = fitter.greedy(geom)
                fr, certs = fitter.realise(geom, greedy, free_start, free_end)
                gcount += len(fr.segments)
                if method == "min":
                    best = fitter.minimum(geom, greedy)
                    if best is not greedy:
                        fm, cm = fitter.realise(geom, best, free_start, free_end)
                        if len(fm.segments) < len(fr.segments):
                            fr, certs = fm, cm
                    mcount += len(fr.segments)
                fitted.append(fr)
                certs_all.append(certs)
        except _TooMany:
            status = FitStatus.TOO_MANY_ARCS
    # Corners from the directions actually laid out (a snapped line may have turned a run's end).
    for r, run in enumerate(runs[:len(fitted)]):
        corner = run.corner
        if corner is not None and corner != 0.0 and (r > 0 or path.closed) and fitted:
            prev_end = fitted[r - 1].poses()[-1]
            corner = _wrap(fitted[r].start.heading - prev_end.heading)
        fitted[r] = dataclasses.replace(fitted[r], corner=corner)
    if status is FitStatus.TOO_MANY_ARCS:
        message = f"path {path.name!r}: {status.value} ({MAX_INTERVALS}); loosen tol (was {tol:.3g})"
        warnings.warn(message, RuntimeWarning, stacklevel=3)
        return PathFit(success=False, status=status, message=message, runs=(), hausdorff=math.inf,
                       hausdorff_sampled=math.inf, where=None, n_arcs=0, n_lines=0,
                       curve_length=sum(g.curve_length for g in fitted), spline_length=0.0, tol=tol, method=method,
                       greedy_count=0, min_count=None, certificates=fitter.budget.certificates,
                       closed=path.closed, name=path.name, size=scale)
    hausdorff = max(r.hausdorff for r in fitted)
    worst = max(((c.sampled, ri, c) for ri, cs in enumerate(certs_all) for c in cs if math.isfinite(c.sampled)),
                default=None, key=lambda v: v[0])
    where = None if worst is None else Where(worst[2].x, worst[2].y, worst[2].piece, worst[2].t, worst[1],
                                             worst[2].segment, worst[2].sampled)
    segs = [s for r in fitted for s in r.segments]
    n_lines = sum(1 for s in segs if s.curvature == 0.0)
    success = hausdorff <= tol and not fitter.failures
    if success:
        message = f"{len(segs)} segments in {len(fitted)} runs, Hausdorff distance <= {hausdorff:.3g} (tol {tol:.3g})"
        message += "".join(f"; {note}" for note in fitter.notes)
    else:
        status = FitStatus.SUBDIVISION_LIMIT
        message = f"path {path.name!r}: {status.value}: " + "; ".join(fitter.failures[:3] or [
            f"bound {hausdorff:.3g} > tol {tol:.3g}"])
        warnings.warn(message, RuntimeWarning, stacklevel=3)
    return PathFit(
        success=success, status=status, message=message, runs=tuple(fitted), hausdorff=hausdorff,
        hausdorff_sampled=max((c.sampled for cs in certs_all for c in cs), default=0.0), where=where,
        n_arcs=len(segs) - n_lines, n_lines=n_lines, curve_length=sum(r.curve_length for r in fitted),
        spline_length=float(sum(s.length for s in segs)), tol=tol, method=method, greedy_count=gcount,
        min_count=mcount if method == "min" else None, certificates=fitter.budget.certificates,
        closed=path.closed, name=path.name, size=scale)


def fit_drawing(drawing: Drawing, tol: float, *, method: str = "greedy", corner_tol_deg: float = 0.5) -> DrawingFit:
    """Fit every path of a drawing (see :func:`fit_path`); ``tol`` is in the drawing's units.

    Examples
    --------
    >>> from skatetrace.drawings.curves import LinePiece
    >>> zig = Path((LinePiece((0.0, 0.0), (1.0, 0.0)), LinePiece((1.0, 0.0), (1.0, 1.0))))
    >>> fit = fit_drawing(Drawing((zig,)), 1e-3)
    >>> fit.success, fit.n_lines, [None if r.corner is None else round(math.degrees(r.corner), 9)
    ...                            for r in fit.paths[0].runs]
    (True, 2, [None, 90.0])
    """
    if not isinstance(drawing, Drawing):
        raise FitError(f"expected a skatetrace.drawings.curves.Drawing, got {type(drawing).__name__}")
    tol = _check_tol(tol)
    method = _check_method(method)
    fits = tuple(fit_path(p, tol, method=method, corner_tol_deg=corner_tol_deg) for p in drawing.paths)
    worst = max(range(len(fits)), key=lambda i: fits[i].hausdorff)
    bad = [f"path {i} ({f.name!r}): {f.message}" for i, f in enumerate(fits) if not f.success]
    success = not bad
    message = (f"{len(fits)} paths, Hausdorff distance <= {fits[worst].hausdorff:.3g} (tol {tol:.3g})"
               if success else "; ".join(bad))
    return DrawingFit(success=success, message=message, paths=fits, hausdorff=fits[worst].hausdorff,
                      hausdorff_sampled=max(f.hausdorff_sampled for f in fits),
                      n_arcs=sum(f.n_arcs for f in fits), n_lines=sum(f.n_lines for f in fits),
                      worst_path=worst, name=drawing.name)


def figure_from_fit(fit: PathFit | DrawingFit, *, name: str, params=None, reverse_above_deg: float = 90.0) -> Figure:
    """A :class:`~skatetrace.figures.figure.Figure` from a fit: one curve per path.

    Parameters
    ----------
    fit : PathFit or DrawingFit
        A successful fit.
    name : str
    params : SleighParams, optional
    reverse_above_deg : float
        At a corner whose travel direction turns by ``delta`` (in ``(-pi, pi]``), a cusp join: if
        ``|delta|`` exceeds this, the blade reverses (a true cusp) and pivots by
        ``remainder(delta - pi, 2 pi)``; otherwise it pivots by ``delta``. Either way the travel
        direction after the join is the curve's.

    Returns
    -------
    Figure
        Segments of a run joined smoothly; a closed path's curve gets the closing join (smooth, or the
        corner where it closes). Laid out with :meth:`Curve.layout`, the pieces reproduce the fit.

    Raises
    ------
    FitError
        If the fit did not succeed.

    Examples
    --------
    >>> from skatetrace.drawings.curves import LinePiece
    >>> vee = Path((LinePiece((0.0, 0.0), (1.0, 0.0)), LinePiece((1.0, 0.0), (0.0, 0.5))))
    >>> fig = figure_from_fit(fit_path(vee, 1e-3), name="vee")
    >>> [(j.kind, round(math.degrees(j.pivot), 6), j.reverse) for j in fig.curves[0].joins]
    [('cusp', -26.565051, True)]
    """
    _check_reverse(reverse_above_deg)
    paths = fit.paths if isinstance(fit, DrawingFit) else (fit,)
    if not fit.success:
        raise FitError(f"cannot make a figure from a failed fit: {fit.message}")
    curves = _figure_curves(paths, reverse_above_deg, lambda run: run.segments)
    tols = sorted({p.tol for p in paths})
    return Figure(name, tuple(curves), params, provenance=(
        f"arc-spline fit ({paths[0].method}) within a certified Hausdorff distance of "
        f"{max(p.hausdorff for p in paths):.3g} (tol {', '.join(f'{t:.3g}' for t in tols)})"),
        extra={"fit": {"tol": tols[-1], "hausdorff": max(p.hausdorff for p in paths),
                       "n_arcs": sum(p.n_arcs for p in paths), "n_lines": sum(p.n_lines for p in paths)}})


def _check_reverse(reverse_above_deg) -> None:
    if not (isinstance(reverse_above_deg, (int, float)) and 0 <= reverse_above_deg <= 180):
        raise FitError(f"reverse_above_deg must be in [0, 180], got {reverse_above_deg!r}")


def _figure_curves(paths, reverse_above_deg: float, pieces_of) -> list[Curve]:
    """One curve per fitted path: a run's pieces (``pieces_of(run)``) joined smoothly, a
    :func:`corner_join` before every later run, and for a closed path the first run's join as closing."""
    curves = []
    for pf in paths:
        pieces: list = []
        joins: list[Join] = []
        for i, run in enumerate(pf.runs):
            items = tuple(pieces_of(run))
            if i > 0:
                joins.append(corner_join(run.corner, reverse_above_deg))
            joins.extend([SMOOTH] * (len(items) - 1))
            pieces.extend(items)
        closing = corner_join(pf.runs[0].corner, reverse_above_deg) if pf.closed else None
        curves.append(Curve(tuple(pieces), tuple(joins), 1, closing, pf.runs[0].start, pf.name))
    return curves
