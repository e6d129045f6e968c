"""Spiral spans: one smooth stretch of a piece cut where its curvature changes sign or turns.

A *spiral span* has curvature kappa of one sign and monotone in arc length s; :func:`_spiral_spans`
cuts a stretch ``t0 <= t <= t1`` of a piece at inflections (kappa changes sign) and at curvature
extrema (dkappa/ds = 0), trusting kappa only to within its rounding error. A stretch of constant
curvature (a circle or a line) stays whole. :mod:`.splitting` calls it on every cusp-free stretch
of a path.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from scipy.optimize import brentq, minimize_scalar

from .curves import Piece, _col, _noisy, curvature

__all__ = ["Span"]

SPLIT_MIN = 1e-6  # inflections/extrema closer than this (fraction of the range) to an end or each other merge


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
