"""The certificate: a proven upper bound of the Hausdorff distance between a chain of arcs and a curve.

:func:`_certify` bounds both directions of the distance between the arcs and lines of a chain and
the stretch of curve (a *window*: parameter ranges of one or more pieces) they replace: curve to
chain from the exact distances at curve samples and the curve's arc length between them, chain to
curve by covering every arc with the chords between samples, and by adaptive sampling
(:func:`_lipschitz_max`, :func:`_foot_points`) where chords do not cover it. Samples are added where
the bound is loose until it is within ``slack`` of the largest sampled distance, or proven above
the target. Arc-spline fitting (:mod:`.fitting`) certifies every biarc it keeps this way.
"""

from __future__ import annotations

import math
from typing import NamedTuple, Sequence

import numpy as np
from scipy.spatial import cKDTree

from .arc_distances import _chain_dist, _chord_max, _local, _swept
from .biarcs import _chain_poses
from .curves import Piece, _gl_lengths, _noisy
from ..figures.geometry import Pose, Segment, advance

__all__: list[str] = []

_TWO_PI = 2.0 * math.pi


class _Cert(NamedTuple):
    """A certificate: the bound, the largest sampled distance and where it is, and whether the bound is
    within the target."""

    bound: float  # certified upper bound of the Hausdorff distance
    sampled: float  # largest sampled distance
    x: float  # curve point where the largest sampled distance was found
    y: float
    piece: int
    t: float
    segment: int  # index (within the chain) of the segment nearest there
    ok: bool  # bound <= target


_FAIL = _Cert(math.inf, math.inf, math.nan, math.nan, -1, math.nan, 0, False)


class _Samples(NamedTuple):
    """Curve samples on one sub-span of a window (one piece's parameter range), in parameter order."""

    piece_index: int
    piece: Piece
    t: np.ndarray  # parameters, shape (n,)
    points: np.ndarray  # curve points, shape (2, n)
    dist: np.ndarray  # exact distance from each point to the chain, shape (n,)
    nearest: np.ndarray  # index (within the chain) of the segment nearest each point, shape (n,)
    gaps: np.ndarray  # arc length between consecutive samples (5-point Gauss-Legendre), shape (n - 1,)


class _Chords(NamedTuple):
    """Chords between consecutive samples of every sub-span, then bridges over the (rounding) gaps
    between consecutive sub-spans; the first ``n_real`` are chords, the rest bridges."""

    q0: np.ndarray  # start points, shape (2, m)
    q1: np.ndarray  # end points, shape (2, m)
    n_real: int
    length: np.ndarray  # chord lengths c_i
    arc: np.ndarray  # arc lengths g_i of curve they span, made safe against error (a bridge: its chord)
    curve_reach: np.ndarray  # e_i: every curve point between the ends is within this of the chord
    chord_reach: np.ndarray  # b_i: every chord point is within this of the curve
    f0: np.ndarray  # distance to the chain at the start of each chord (chords only)
    f1: np.ndarray  # and at its end
    finite: bool  # whether lengths and distances are all finite (else nothing can be certified)


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


def _sample_window(pieces: Sequence[Piece], window: Sequence[tuple[int, float, float]], poses: Sequence[Pose],
                   segs: Sequence[Segment]) -> list[_Samples]:
    """17 samples, equally spaced in ``t``, on every sub-span of the window, with their distances to the chain.

    The distances of all the window's samples are one call (a window of thousands of lines, as
    the fit's merge pass certifies, spent most of its time in per-piece calls).
    """
    ts = [np.linspace(ta, tb, 17) for _pi, ta, tb in window]
    pts = [pieces[pi].point(t) for (pi, _ta, _tb), t in zip(window, ts)]
    f_all, idx_all = _chain_dist(np.hstack(pts), poses, segs)
    subs = []
    for n, ((pi, _ta, _tb), t, p) in enumerate(zip(window, ts, pts)):
        piece = pieces[pi]
        part = slice(17 * n, 17 * n + 17)
        subs.append(_Samples(pi, piece, t, p, f_all[part], idx_all[part], _gl_lengths(piece, t[:-1], t[1:])))
    return subs


def _chords(subs: Sequence[_Samples]) -> _Chords:
    """The chords between samples and the ellipse bounds ``e_i``, ``b_i`` of the curve around them."""
    q0 = np.hstack([s.points[:, :-1] for s in subs] + [s.points[:, -1:] for s in subs[:-1]])
    q1 = np.hstack([s.points[:, 1:] for s in subs] + [s.points[:, :1] for s in subs[1:]])
    n_real = sum(s.t.size - 1 for s in subs)
    c = np.hypot(q1[0] - q0[0], q1[1] - q0[1])
    # Quadrature lengths, made safe against their own error (relative: 1e-13, or 1e-8 for a piece
    # whose derivatives are finite differences) and against rounding of the chords (absolute).
    g = np.concatenate([s.gaps * (1.0 + (1e-8 if _noisy(s.piece) else 1e-13)) for s in subs] + [c[n_real:]])
    g = np.maximum(g, c) + 1e-15 * (np.abs(q0).max(axis=0) + np.abs(q1).max(axis=0))
    e = np.sqrt((g - c) * g / 2.0)
    b = np.sqrt(np.maximum(g * g - c * c, 0.0)) / 2.0
    b[n_real:] = c[n_real:] / 2.0
    f0 = np.concatenate([s.dist[:-1] for s in subs])
    f1 = np.concatenate([s.dist[1:] for s in subs])
    finite = bool(np.all(np.isfinite(c)) and np.all(np.isfinite(g)) and np.all(np.isfinite(f0)))
    return _Chords(q0, q1, n_real, c, g, e, b, f0, f1, finite)


def _chord_circle_max(ch: _Chords, poses: Sequence[Pose], segs: Sequence[Segment]) -> list[tuple]:
    """Per segment: the exact maximum ``M_i`` over every chord of the distance to the segment's circle (or
    line), with the chord ends in the segment's frame, ``(M, u0, w0, u1, w1)``."""
    loc = []
    for p, (k, _) in zip(poses, segs):
        u0, w0 = _local(p, k, ch.q0[0], ch.q0[1])
        u1, w1 = _local(p, k, ch.q1[0], ch.q1[1])
        loc.append((_chord_max(abs(k), u0, w0, u1, w1), u0, w0, u1, w1))
    return loc


def _curve_to_chain(ch: _Chords, loc: list[tuple], a_el, segs: Sequence[Segment], eps_len: float) -> np.ndarray:
    """Bound of the distance from the curve to the chain along each chord (chords only, no bridges).

    The Lipschitz bound ``(f_i + f_{i+1} + g_i) / 2``, or ``M_i + e_i`` where both chord ends lie in
    one convex sector of an arc (an A-element of :func:`_elements`), whichever is smaller.
    """
    n_real = ch.n_real
    bound_a = 0.5 * (ch.f0 + ch.f1 + ch.arc[:n_real])
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
        bound_a = np.where(inside, np.minimum(bound_a, M[:n_real] + ch.curve_reach[:n_real] + pen), bound_a)
    return bound_a


def _chain_to_curve(ch: _Chords, loc: list[tuple], b_el, segs: Sequence[Segment], eps_len: float,
                    theta: float) -> tuple[float, list, np.ndarray]:
    """Bound of the distance from the chain's arc pieces (B-elements of :func:`_elements`) to the curve.

    An arc piece covered by the angle spans of chords (and bridges) is within the largest
    ``M_i + b_i`` of them. Returns that bound over the covered pieces, the pieces not covered (for
    :func:`_bound_uncovered`), and which chords' values exceed ``theta`` (to halve).
    """
    q0, q1 = ch.q0, ch.q1
    flagged = np.zeros(ch.length.size, dtype=bool)
    bound_b, uncovered = 0.0, []
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
            uncovered.append((j, p, sweep))
            continue
        val = M[idx] + ch.chord_reach[idx]
        bound_b = max(bound_b, float(np.max(val)) + 1e-3 * eps_len)
        flagged[idx[val > theta]] = True
    return bound_b, uncovered, flagged


def _halve(subs: Sequence[_Samples], refine: np.ndarray, poses: Sequence[Pose],
           segs: Sequence[Segment]) -> list[_Samples]:
    """The samples with a new one at the parameter midpoint of every chord flagged in ``refine``."""
    out = []
    start = 0
    for s in subs:
        m = s.t.size - 1
        r = np.nonzero(refine[start:start + m])[0]
        start += m
        if r.size == 0:
            out.append(s)
            continue
        t = s.t
        tm = 0.5 * (t[r] + t[r + 1])
        pm = s.piece.point(tm)
        fm, im = _chain_dist(pm, poses, segs)
        gl, gr = _gl_lengths(s.piece, t[r], tm), _gl_lengths(s.piece, tm, t[r + 1])
        gg = s.gaps.copy()
        gg[r] = gl
        out.append(s._replace(t=np.insert(t, r + 1, tm), points=np.insert(s.points, r + 1, pm, axis=1),
                              dist=np.insert(s.dist, r + 1, fm), nearest=np.insert(s.nearest, r + 1, im),
                              gaps=np.insert(gg, r + 1, gr)))
    return out


def _farthest(subs: Sequence[_Samples]) -> tuple[float, float, float, int, float, int]:
    """The largest sampled distance, where: ``(distance, x, y, piece, t, segment)`` (as in :class:`_Cert`)."""
    si = max(range(len(subs)), key=lambda i: float(np.max(subs[i].dist)))
    s = subs[si]
    i = int(np.argmax(s.dist))
    return (float(s.dist[i]), float(s.points[0, i]), float(s.points[1, i]), s.piece_index, float(s.t[i]),
            int(s.nearest[i]))


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


def _foot_points(q: np.ndarray, samples: Sequence[_Samples], tree: cKDTree,
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
    for wi, sp in enumerate(samples):
        pi, piece, t = sp.piece_index, sp.piece, sp.t
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


def _bound_uncovered(subs: Sequence[_Samples], uncovered: list, segs: Sequence[Segment], bound: float,
                     target: float, slack: float) -> float | None:
    """``bound`` raised by the arc pieces the chords do not cover, each sampled adaptively; ``None`` if a
    distance is not finite.

    Distances from those arc points go to true curve points (:func:`_foot_points`), so they are upper
    bounds; pieces after the bound exceeds ``target`` are not looked at.
    """
    offsets = np.concatenate([[0], np.cumsum([sp.t.size for sp in subs])])
    tree = cKDTree(np.hstack([sp.points for sp in subs]).T)
    for j, p0, sweep in uncovered:
        k = segs[j].curvature
        L = sweep / abs(k) if k != 0.0 else sweep

        def evb(sig, p0=p0, k=k):
            x, y, _ = advance(p0, k, sig)
            q = np.vstack([np.atleast_1d(x), np.atleast_1d(y)])
            d, fp, ft = _foot_points(q, subs, tree, offsets)
            return d, [fp, ft]

        sig = np.linspace(0.0, L, 17)
        _, f, _, b_el_bound = _lipschitz_max(sig, evb(sig), np.diff(sig), evb, lambda a, c: c - a,
                                             target, slack, 20000)
        if not np.all(np.isfinite(f)):
            return None
        bound = max(bound, b_el_bound)
        if bound > target:
            break
    return bound


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
    ``M_i`` of the circle distance over the chord
    (:func:`~skatetrace.drawings.arc_distances._chord_max`), so the curve stays within ``M_i + e_i``.
    Otherwise the distance, 1-Lipschitz in arc length, is at most ``(f_i + f_{i+1} + g_i) / 2`` from
    the exact distances ``f`` at the samples.

    Chain to curve: a point of an arc at swept angle ``a`` has, on every chord whose ends' angles
    bracket ``a``, a point on the same ray, at ``|q - c| - r <= M_i`` from it, so within ``M_i + b_i``
    of the curve; if the chords' angle spans cover the arc piece, its bound is the largest such value.
    Otherwise (no cover) the arc piece is sampled (:func:`_lipschitz_max`, :func:`_foot_points`).

    Chords whose bound exceeds ``min(target, max f + slack)`` are halved until none does (or ``cap``
    samples); a sample farther than ``target`` rejects at once. Both bounds are second order in the
    sample spacing, so a few dozen samples usually suffice.

    The steps: :func:`_sample_window`; then, until no chord needs halving, :func:`_chords`,
    :func:`_chord_circle_max`, :func:`_curve_to_chain`, :func:`_chain_to_curve` and :func:`_halve`;
    then :func:`_farthest` and, for arc pieces no chords cover, :func:`_bound_uncovered`.
    """
    if not window:
        return _FAIL
    poses = _chain_poses(pose, segs)[:-1]
    a_el, b_el = _elements(poses, segs)
    subs = _sample_window(pieces, window, poses, segs)
    eps_len = 1e-9 * max(sum(s.length for s in segs), 1e-300)
    for _ in range(64):
        ch = _chords(subs)
        if not ch.finite:
            return _FAIL
        loc = _chord_circle_max(ch, poses, segs)
        bound_a = _curve_to_chain(ch, loc, a_el, segs, eps_len)
        fmax = float(max(np.max(s.dist) for s in subs))
        if fmax > target:
            break  # a sample is farther than the target: rejected, whatever the bounds
        theta = min(target, fmax + slack)
        bound_b, uncovered, refine = _chain_to_curve(ch, loc, b_el, segs, eps_len, theta)
        refine[:ch.n_real] |= bound_a > theta
        refine[ch.n_real:] = False  # bridges span rounding gaps: nothing to halve
        if not np.any(refine) or sum(s.t.size for s in subs) >= cap * len(subs):
            break
        subs = _halve(subs, refine, poses, segs)
    best = _farthest(subs)
    if best[0] > target:
        return _Cert(max(best[0], float(np.max(bound_a)) if bound_a.size else best[0]), *best, False)
    bound = max(float(np.max(bound_a)) if bound_a.size else 0.0, bound_b, best[0])
    if bound > target or not uncovered:
        return _Cert(bound, *best, bound <= target)
    bound = _bound_uncovered(subs, uncovered, segs, bound, target, slack)
    if bound is None:
        return _FAIL
    return _Cert(bound, *best, bound <= target)
