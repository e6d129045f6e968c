"""One run of a path in exact mode: its spans laid out as one chain, the measured deviation, and knot refinement.

Step 3 of exact mode and its error control (:mod:`skatetrace.drawings.exact`, which defines the
deviation). :class:`RunGeom` lays the spans' pieces (:mod:`.exact_spans`) out one after the other
from a start pose and measures the deviation bound against the source at the same arc length;
:func:`refine` doubles the intervals of the spans that contribute most until the run is within its
target, or stops and says why.
"""

from __future__ import annotations

import math
from typing import NamedTuple, Sequence

import numpy as np

from .curves import Piece
from .exact_results import ExactStatus
from .exact_spans import SpanGeom, subspans
from .corners import _wrap
from .curves import _noisy
from .splitting import Run
from ..figures.geometry import Pose, travel

__all__ = ["RunGeom", "RunResult", "refine"]

_TWO_PI = 2.0 * math.pi


def _wrap_array(a: np.ndarray) -> np.ndarray:
    return np.remainder(a + math.pi, _TWO_PI) - math.pi


class _Eval(NamedTuple):
    pieces: tuple
    end: Pose
    deviation: float
    sampled: float
    where: tuple[float, float]
    offset: float  # distance of the layout's start from the source's
    own: np.ndarray  # per span: its contribution to the deviation (heading error, integrated)
    fixed: float  # contributions no refinement removes: kinks at smooth joins, arcs and lines, offset


class RunGeom:
    """A run of a path as its spans (:class:`~skatetrace.drawings.exact_spans.SpanGeom`), laid out and measured together."""

    def __init__(self, pieces: Sequence[Piece], run: Run, where: str):
        self.run = run
        self.spans = [SpanGeom(pieces[sp.piece], sub, where) for sp in run.spans
                      for sub in subspans(pieces[sp.piece], sp)]
        self.length = float(sum(g.length for g in self.spans))
        self.noisy = any(_noisy(g.piece) for g in self.spans)

    def initial(self) -> list[int]:
        return [g.initial(max(self.length, 1e-300)) for g in self.spans]

    def evaluate(self, start: Pose, ns: Sequence[int]) -> _Eval:
        wild = [g.overshoots(n) for g, n in zip(self.spans, ns)]
        if any(wild):
            # a spline that overshoots wildly between its knots: not laid out (its samples and cells would
            # run to billions), nor kept as a layout to draw; its spans are refined first
            return _Eval((), start, math.inf, math.inf, (start.x, start.y), 0.0, np.where(wild, math.inf, 0.0), 0.0)
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


class RunResult(NamedTuple):
    """The best layout :func:`refine` found: its evaluation, intervals per span, and why it stopped short."""

    ev: _Eval
    ns: list[int]
    failed: ExactStatus | None
    why: str = ""


def refine(geom: RunGeom, start: Pose, target: float, tol: float, budget: int, floor: float,
            refine: bool) -> RunResult:
    """Double the intervals of the spans that contribute most until the run's deviation is within ``target``.

    Stops, keeping the best layout found, when the next doubling would exceed ``budget`` pieces, when what
    is left cannot be reduced by knots (arcs, lines, kinks, a carried offset), when the deviation is down
    to ``floor`` (rounding), or when it stops falling (halving at least once in 3 doublings for a piece
    with finite-difference curvature, 5 otherwise). That is a failure only if the deviation exceeds ``tol``.
    """
    ns = geom.initial()
    ev = geom.evaluate(start, ns)
    best = RunResult(ev, list(ns), None)
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
            best = RunResult(ev, list(ns), None)
        if ev.deviation <= 0.5 * mark:
            mark, rounds = ev.deviation, 0
        else:
            rounds += 1
    return best
