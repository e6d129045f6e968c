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
    bound: float  # certified upper bound of the Hausdorff distance
    sampled: float  # largest sampled distance
    x: float  # curve point where the largest sampled distance was found
    y: float
    piece: int
    t: float
    segment: int  # index (within the chain) of the segment nearest there
    ok: bool  # bound <= target


_FAIL = _Cert(math.inf, math.inf, math.nan, math.nan, -1, math.nan, 0, False)


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
    ``M_i`` of the circle distance over the chord
    (:func:`~skatetrace.drawings.arc_distances._chord_max`), so the curve stays within ``M_i + e_i``. Otherwise the distance, 1-Lipschitz in arc length, is at most
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
