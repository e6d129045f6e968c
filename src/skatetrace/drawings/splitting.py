"""Splitting a path into smooth runs: cut at corners between pieces and cusps inside them.

:func:`split_path` cuts a :class:`~skatetrace.drawings.curves.Path` into *runs*, maximal
tangent-continuous (G1) stretches, at corners between pieces and at cusps inside a piece (where the
parametric speed ``|r'(t)|`` vanishes), and each run into spiral spans (:mod:`.spirals`) at
inflections and curvature extrema. Arc-spline fitting (:mod:`.fitting`) and exact fitting
(:mod:`.exact`) both start here.

Notation: kappa is signed curvature (positive turns left), t a piece's parameter in ``[0, 1]``,
"size" the larger side of the path's bounding box. Thresholds that decide what is rounding (a tiny
piece, a gap, a cusp) are relative to the size and listed as module constants below.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from scipy.optimize import minimize_scalar

from .corners import _wrap
from .curves import LinePiece, Path, Piece, _col, _direction, curvature, piece_length
from .spirals import Span, _spiral_spans
from ..errors import FitError

__all__ = ["Run", "split_path"]

# Relative to the path's size.
TINY = 1e-10  # a piece, or the bit of a piece before a cusp, shorter than this is rounding: dropped
GAP = 1e-9  # consecutive pieces must meet within this
CUSP_RADIUS = 1e-10  # a speed minimum whose radius bound |r'|^2/|r''| is below this is a cusp
# Relative to the fit's tolerance: a speed minimum whose radius bound is below TIP_RADIUS times
# the tolerance, where the curve turns by TIP_TURN_DEG or more (over the stretch within TIP_REACH
# tolerances of the tip), is a cusp too: a tip too tight to skate, whose rounding lies within the
# tolerance. Near the tip the curve is a hairpin whatever it does further out (its velocity
# r'(t_s) + r''(t - t_s) swings from -r'' to +r''), so it is cut as a reversal. A quarter, not an
# eighth: the Rust documentation's favicon has a tip of radius 0.126 mm at 6 m / 1 mm, which the
# fit followed with arcs of a millimetre turning back and forth, a section no stop fits. 120, not
# 150 degrees: the petals of simple-icons' CorelDRAW logo end in tips of 0.19 mm turning by 143
# degrees across 1 mm, fitted the same way (in 2,558 icons drawn at random from nine npm icon sets
# and the corpus, the only other tip between the two is opentofu's). A quarter turn is not a tip
# (a rounded corner of a square).
TIP_RADIUS = 1 / 4
TIP_REACH = 1.0
TIP_TURN_DEG = 120.0
# Relative to the fit's tolerance: where a stretch's end tangent and its chord across the ball of
# radius HOOK_REACH tolerances about that end differ by more than HOOK_DEG, the end hooks inside the
# ball: the chord's direction is the end's, and the spans inside the ball are one (their splits at
# the hook's curvature extrema would make the fit follow it). Ionicons' logo-vk has a cubic whose
# first handle, 6 mm long at 6 m, points back against its travel: the curve leaves its start at
# 121 degrees to the path before it and turns back through 125 degrees within a tenth of a
# millimetre, 0.04 mm aside; the fit made the join a reversal followed by arcs of 0.4 mm radius that
# no launch fits (the drawing failed after four rounds of rests). Taken by its chord, the join is a
# corner of 18 degrees. A smooth end turns away from its chord by about HOOK_REACH * tol / (2 r),
# beyond HOOK_DEG only at radii of curvature below the tolerance.
HOOK_REACH = 1.0
HOOK_DEG = 30.0
# The arc fit (``soft``): a join turning by delta between pieces of lengths l1, l2 is also smooth
# where the fit can round it well within the tolerance, delta <= SOFT_SHARE * tol / min(l1, l2): the
# chain through it then bends by delta over a piece, off by about l * delta / 8 (half the
# tolerance). Never above SOFT_MAX_DEG: a turn sharper than that is a corner the drawing meant.
# A circle drawn as 189 lines (vpype-circle-3cm.svg, joins of 1.9 degrees) is a circle, not 189
# stops.
SOFT_SHARE = 4.0
SOFT_MAX_DEG = 5.0


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


def _leaving(piece: Piece, t: float, toward: float, reach: float) -> float | None:
    """The first parameter from ``t`` toward ``toward`` where the curve is ``reach`` away from ``r(t)``
    (on a grid, then bisected), or None where it stays closer."""
    p = _col(piece, "point", t)
    grid = np.linspace(t, toward, 257)
    xy = np.asarray(piece.point(grid), dtype=float)
    out = np.flatnonzero(np.hypot(xy[0] - p[0], xy[1] - p[1]) >= reach)
    if not out.size:
        return None
    lo, hi = grid[out[0] - 1], grid[out[0]]
    for _ in range(40):
        mid = 0.5 * (lo + hi)
        q = _col(piece, "point", mid)
        if math.hypot(q[0] - p[0], q[1] - p[1]) >= reach:
            hi = mid
        else:
            lo = mid
    return hi


def _turn_across(piece: Piece, t: float, reach: float) -> float:
    """How far the curve turns (radians, unsigned) between where it leaves the ball of radius ``reach`` about ``r(t)``.

    On each side the parameter where the distance from ``r(t)`` first reaches ``reach`` (bisected
    on a grid), or the piece's end if it stays inside. The turn is the total change of the
    tangent's direction along the way (the integral of the curvature), not the angle between the
    two end tangents, which folds back above pi: a tip that loops past a reversal, 220 degrees,
    would read as 140. Directions are followed on grids that close in geometrically on ``t``, where
    they turn fastest, so that no step between samples turns by pi or more.
    """
    ends = []
    for toward in (0.0, 1.0):
        u = _leaving(piece, t, toward, reach)
        ends.append(toward if u is None else u)
    steps = np.concatenate([[0.0], np.geomspace(1e-12, 1.0, 600)])
    grid = np.concatenate([t + (ends[0] - t) * steps[::-1], t + (ends[1] - t) * steps[1:]])
    v = np.asarray(piece.d1(grid), dtype=float)
    speed = np.hypot(v[0], v[1])
    if not (speed[0] > 0 and speed[-1] > 0):
        return 0.0
    keep = speed > 0  # a sample at a zero speed has no direction
    heading = np.arctan2(v[1][keep], v[0][keep])
    turns = np.diff(heading)
    turns = (turns + math.pi) % (2 * math.pi) - math.pi
    return abs(float(np.sum(turns)))


def _hook(piece: Piece, t: float, toward: float, direction: np.ndarray, reach: float
          ) -> tuple[np.ndarray, float | None]:
    """Whether the end ``t`` of a stretch running to ``toward`` hooks within ``reach`` (:data:`HOOK_DEG`).

    Returns ``(direction, None)`` where it does not; else the chord's direction across the ball of
    radius ``reach`` about ``r(t)`` (the travel direction: arriving at ``t`` where ``toward < t``) and
    the parameter where the curve leaves the ball. A line never hooks; nor does an end whose
    curvature is below ``1 / reach`` (its chord across the ball turns from its tangent by about
    ``reach * kappa / 2``, under :data:`HOOK_DEG` while the curvature keeps its order there): they
    are not looked at, so a polyline of thousands of lines pays nothing.
    """
    if isinstance(piece, LinePiece):
        return direction, None
    if abs(float(curvature(piece, float(t))[0])) * reach < 1.0:  # (NaN at a zero speed: looked at)
        return direction, None
    u = _leaving(piece, t, toward, reach)
    if u is None:
        return direction, None
    chord = _col(piece, "point", u) - _col(piece, "point", t)
    chord = (chord if toward > t else -chord) / math.hypot(chord[0], chord[1])
    cos = float(np.clip(chord[0] * direction[0] + chord[1] * direction[1], -1.0, 1.0))
    return (chord, u) if math.acos(cos) > math.radians(HOOK_DEG) else (direction, None)


def _one_span(spans: list[Span], first: int, last: int) -> list[Span]:
    """``spans[first..last]`` (of one piece) made one span, the others kept."""
    a, b = spans[first], spans[last]
    return [*spans[:first], Span(a.piece, a.t0, b.t1, a.heading0, b.heading1, "spiral", a.reason), *spans[last + 1:]]


def _cusps(piece: Piece, scale: float, tip: float = 0.0) -> list[float]:
    """Parameters in ``[0, 1]`` where the speed ``|r'|`` vanishes (to within rounding of the size).

    With ``tip > 0`` (a length), also the tips of hairpins whose radius bound is at most ``tip``
    (see :data:`TIP_RADIUS`).
    """
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
    tight = False  # without a tip length, only the speed's own minima (a zero speed is one of them)
    if tip > 0:
        with np.errstate(all="ignore"):
            d2 = piece.d2(t)
            tight = sp * sp <= tip * np.hypot(d2[0], d2[1])
    cand = np.nonzero((sp <= left) & (sp <= right) & ((sp < 1e-2 * top) | tight))[0]
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
        cusp = s == 0.0 or (n2 > 0 and s * s <= CUSP_RADIUS * scale * n2)
        if not cusp and n2 > 0 and s * s <= tip * n2:
            cusp = _turn_across(piece, ts, tip / TIP_RADIUS * TIP_REACH) >= math.radians(TIP_TURN_DEG)
        if cusp and (not out or ts - out[-1] > 1e-9):
            out.append(ts)
    return out


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


def _ranges(path: Path, prep: _Prepared, tip: float = 0.0) -> list[_Range]:
    """Pieces cut at their cusps (and hairpin tips tighter than ``tip``), bits below rounding dropped."""
    out = []
    for i, p in enumerate(path.pieces):
        if prep.lengths[i] <= TINY * prep.scale:
            continue
        cuts = [0.0, *(c for c in _cusps(p, prep.scale, tip) if 0.0 < c < 1.0), 1.0]
        parts = []
        for a, b in zip(cuts[:-1], cuts[1:]):
            if b > a and piece_length(p, a, b, 32) > TINY * prep.scale:
                parts.append((a, b))
        for a, b in parts:
            out.append(_Range(i, a, b, a > 0.0, b < 1.0))
    if not out:
        raise FitError(f"path {path.name!r} has zero length")
    return out


def _split(path: Path, corner_tol_deg: float, tol: float = 0.0, progress=None,
           soft: bool = False) -> tuple[list[Run], _Prepared]:
    """:func:`split_path`, and the path's size; ``tol`` (the fit's tolerance) makes hairpins tighter than it cusps.

    ``progress(piece)``, if given, is called every few hundred pieces split (a path of 20,000 lines
    takes seconds). ``soft`` (the arc fit's) also joins smoothly where the turn can be rounded well
    within ``tol`` (:data:`SOFT_SHARE`, :data:`SOFT_MAX_DEG`).
    """
    if not (isinstance(corner_tol_deg, (int, float)) and math.isfinite(corner_tol_deg)
            and 0 <= corner_tol_deg < 180):
        raise FitError(f"corner_tol_deg must be in [0, 180) degrees, got {corner_tol_deg!r}")
    prep = _prepare(path)
    scale, pieces = prep.scale, path.pieces
    ranges = _ranges(path, prep, TIP_RADIUS * tol)
    n = len(ranges)
    dirs_in, dirs_out, hooks = [], [], []
    for r in ranges:
        p, vscale = pieces[r.piece], max(prep.lengths[r.piece], 1e-300)
        chord = _col(p, "point", r.b) - _col(p, "point", r.a)
        cn = math.hypot(chord[0], chord[1])
        fallback = chord / cn if cn > 0 else np.array([1.0, 0.0])
        d_in = _direction(p, r.a, +1, vscale, r.cusp_a)
        d_out = _direction(p, r.b, -1, vscale, r.cusp_b)
        d_in, d_out = (fallback if d_in is None else d_in), (fallback if d_out is None else d_out)
        hook_in = hook_out = None
        # a fitter's: a piece's end that hooks within its tolerance is taken by its chord (not a cusp's
        # or a tip's, whose reversal is meant)
        if tol > 0 and not r.cusp_a:
            d_in, hook_in = _hook(p, r.a, r.b, d_in, HOOK_REACH * tol)
        if tol > 0 and not r.cusp_b:
            d_out, hook_out = _hook(p, r.b, r.a, d_out, HOOK_REACH * tol)
        dirs_in.append(d_in)
        dirs_out.append(d_out)
        hooks.append((hook_in, hook_out))
    lengths = [piece_length(pieces[r.piece], r.a, r.b, 64) for r in ranges]
    fit_tol, tol = tol, math.radians(corner_tol_deg)
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
        rounded = soft and abs(delta) <= min(math.radians(SOFT_MAX_DEG),
                                             SOFT_SHARE * fit_tol / max(min(lengths[j - 1], lengths[j]), 1e-300))
        if abs(delta) <= tol or (rounded and not same_piece):
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
        if progress is not None and j % 200 == 0:
            progress(r.piece)
        spans = _spiral_spans(pieces[r.piece], r.piece, r.a, r.b, math.atan2(dirs_in[j][1], dirs_in[j][0]),
                              math.atan2(dirs_out[j][1], dirs_out[j][0]), reason[j], lengths[j])
        hook_in, hook_out = hooks[j]
        if hook_in is not None:  # the spans inside the hook's ball, one
            spans = _one_span(spans, 0, next(k for k, sp in enumerate(spans) if sp.t1 >= hook_in))
        if hook_out is not None:
            spans = _one_span(spans, next(k for k in range(len(spans) - 1, -1, -1) if spans[k].t0 <= hook_out),
                              len(spans) - 1)
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
    cusp turns by about ``pi``. The fitters (not this function, which has no tolerance) also cut
    hairpin tips tighter than their tolerance (:data:`TIP_RADIUS`, :data:`TIP_TURN_DEG`). Spiral
    spans: sign changes of kappa and of its grid differences on 513 points per stretch, ignoring
    values within their rounding error (see :func:`~skatetrace.drawings.spirals._spiral_spans`),
    refined by brentq (on kappa, and on a central difference of kappa, with a bounded minimisation
    of kappa as fall-back); splits within ``SPLIT_MIN`` of an end or of each other are dropped.

    Examples
    --------
    >>> from skatetrace.drawings.curves import BezierPiece, FunctionPiece
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
