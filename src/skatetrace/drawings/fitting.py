"""Arc-spline fitting: each run of a path replaced by a G1 chain of arcs and lines within a certified distance.

The chain, from a :class:`~skatetrace.drawings.curves.Path` to a :class:`~skatetrace.figures.figure.Figure`:

1. :func:`~skatetrace.drawings.splitting.split_path` cuts a path into *runs*, maximal
   tangent-continuous (G1) stretches, at corners and cusps, and each run into *spiral spans* at
   inflections and curvature extrema (:mod:`.spirals`). A span of constant curvature (a circle or a
   line) stays whole.
2. :func:`fit_path` (this module) replaces every run by a G1 chain of circular arcs and lines
   (:class:`~skatetrace.figures.geometry.Segment`): biarcs (:mod:`.biarcs`) interpolating the
   curve's points and unit tangents at breakpoints, the breakpoints chosen greedily (halve a span at
   its arc-length midpoint until its biarc is within ``tol``, then merge runs of whole spans into one
   biarc where that is certified and shorter: :meth:`_Fitter.merged`) or for the fewest arcs (a
   shortest path over candidate breakpoints, after Drysdale, Rote & Sturm). Every biarc carries a certified upper
   bound on its Hausdorff distance to the stretch of curve it replaces (:mod:`.certify`), so the
   bound of the whole fit is certified too. The results are :mod:`.fit_results`.
3. :func:`~skatetrace.drawings.to_figure.figure_from_fit` turns a fit into a figure.

Notation: s is arc length, t a piece's parameter in ``[0, 1]``, "size" the larger side of the
path's bounding box; the limits below are module constants.

References
----------
R. L. S. Drysdale, G. Rote, A. Sturm, "Approximation of an open polygonal curve with a minimum
number of circular arcs and biarcs", Comput. Geom. Theory Appl. (2008).
"""

from __future__ import annotations

import dataclasses
import math
import warnings
from typing import NamedTuple, Sequence

import numpy as np

from .biarcs import _biarc, _chain_poses, _straightened
from .certify import _FAIL, _Cert, _certify
from .corners import _wrap
from .curves import Drawing, Path, Piece, _col, _direction, _gl_lengths, curvature, piece_length
from .fit_results import DrawingFit, FitStatus, FittedRun, Knot, PathFit, Where, gathered
from .splitting import Run, _split
from ..errors import FitError
from ..figures.geometry import Pose, Segment
from ..progress import Channel

__all__ = ["fit_path", "fit_drawing", "reporting"]

MIN_SPAN = 1e-9  # relative to the size: a span shorter than this is not halved again (the fit then fails)
MAX_INTERVALS = 100_000  # biarcs per path before the fit gives up
MIN_DENSITY = 6  # candidate breakpoints per greedy biarc for the minimum-count fit
MIN_BUDGET = 30  # certificates per greedy biarc the minimum-count search may spend before keeping greedy's
MIN_PIECE_BUDGET = 100  # source pieces certified (over all its windows) per greedy biarc, likewise
MERGE_SPANS = 1024  # whole spans one biarc of the merge pass may replace at most
MERGE_MIN_SPANS = 32  # consecutive whole spans a stretch needs before the merge pass touches it


_Loc = tuple  # (span index within the run, t on that span's piece)

# A drawing's fit, piece by piece (see reporting).
_PROGRESS = Channel("fitting")
#: Spans fitted (or tried for merging) between two reports.
_REPORT_EVERY = 200


def reporting(report):
    """Within the ``with`` block, call ``report(stage, done, total)`` as :func:`fit_drawing` goes.

    ``stage`` is ``"splitting"`` (into runs and spans), ``"fitting"`` (greedy's biarcs) or
    ``"merging"`` (its merge pass), ``done`` of the
    drawing's ``total`` source pieces are behind it (reported every few hundred spans and at the end
    of each path: a drawing of 20,000 lines takes tens of seconds). Per thread and task, like
    :func:`skatetrace.planning.pool.reporting` (:class:`skatetrace.progress.Channel`).
    """
    return _PROGRESS.listening(report)


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

    def __init__(self, path: Path, scale: float, tol: float, where: tuple[int, int] | None = None):
        self.path, self.pieces, self.scale, self.tol = path, path.pieces, scale, tol
        # (pieces of the drawing before this path, the drawing's pieces): for reporting
        self.where = (0, len(path.pieces)) if where is None else where
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
        return (Segment(_straightened(k, L), L),)

    def report(self, stage: str, piece: int) -> None:
        """Report the drawing's pieces before this path's ``piece`` done."""
        _PROGRESS.report(stage, self.where[0] + piece, self.where[1])

    def greedy(self, geom: _RunGeom) -> list[_Interval]:
        """Halve each spiral span at its arc-length midpoint until every biarc is within ``tol``."""
        out: list[_Interval] = []
        min_len = MIN_SPAN * self.scale
        for k, sp in enumerate(geom.spans):
            if k % _REPORT_EVERY == 0:
                self.report("fitting", sp.piece)
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

    def merged(self, geom: _RunGeom, intervals: list[_Interval], least: int | None = None) -> list[_Interval]:
        """Consecutive whole spans replaced by one biarc wherever it is certified and has fewer segments.

        Greedy fits each span on its own, so a dense polyline (a circle drawn as 2,500 lines, a
        point list of a curve) comes out with a segment per source segment, however little it
        turns: 2,500 pieces to trace, each from rest to rest where it is a section of its own. Here,
        from each whole span on, the biarc over the next whole spans is tried over windows doubling
        in size (then halved back to the longest certified one), and kept where its certificate is
        within ``tol`` and it replaces more segments than it has. Only stretches of at least
        ``least`` (:data:`MERGE_MIN_SPANS`) whole spans in a row are merged: a drawing's few pieces
        are its author's (merged, an icon's short runs became long sections that the
        launch-glide-stop manoeuvres traced more slowly, with rests added where they failed), unless
        they do not fit as they are or make a whole smooth closed path (see :func:`_fit_runs`).
        Spans greedy had to halve are left as they are (their own fit is already as long as a
        biarc goes), and so are failed ones.
        Each try certifies every source piece of its window: about ``2 + log2(w)`` certifications of
        each piece for windows of ``w`` spans.
        """
        least = MERGE_MIN_SPANS if least is None else least
        n = len(intervals)
        whole = [iv.cert.ok and iv.a[0] == iv.b[0] and iv.a[1] == geom.spans[iv.a[0]].t0
                 and iv.b[1] == geom.spans[iv.b[0]].t1 for iv in intervals]
        if sum(whole) < max(least, 3):
            return intervals
        counts = np.concatenate([[0], np.cumsum([len(iv.segs) for iv in intervals])])
        # per whole span: where its stretch of whole spans in a row starts and ends (one past it)
        starts, ends = [0] * n, [0] * n
        for k in range(n):
            starts[k] = starts[k - 1] if k and whole[k - 1] else k
        for k in range(n - 1, -1, -1):
            ends[k] = ends[k + 1] if k + 1 < n and whole[k + 1] else k + 1
        out: list[_Interval] = []
        i, reported = 0, -_REPORT_EVERY
        while i < n:
            if i - reported >= _REPORT_EVERY:
                self.report("merging", geom.spans[intervals[i].a[0]].piece)
                reported = i
            last = min(ends[i], i + MERGE_SPANS) - 1  # the last whole span a biarc from i may cover
            first = int(np.searchsorted(counts, counts[i] + 3, side="left")) - 1  # covers 3 segments
            if not whole[i] or first > last or ends[i] - starts[i] < least:
                out.append(intervals[i])
                i += 1
                continue

            def attempt(j: int) -> _Interval | None:
                p0, p1 = geom.data(intervals[i].a), geom.data(intervals[j].b)
                segs = _biarc(*p0, *p1)
                if segs is None or len(segs) >= counts[j + 1] - counts[i]:
                    return None
                cert = self.certify(geom, intervals[i].a, intervals[j].b, p0, segs, tight=False)
                return _Interval(intervals[i].a, intervals[j].b, segs, cert) if cert.ok else None

            good, bad, j = None, None, first
            while True:
                got = attempt(j)
                if got is None:
                    bad = j
                    break
                good = (j, got)
                if j == last:
                    break
                j = min(last, i + 2 * (j - i + 1) - 1)
            if good is not None and bad is not None:
                lo, hi = good[0], bad  # lo certified, hi not
                while hi - lo > 1:
                    mid = (lo + hi) // 2
                    got = attempt(mid)
                    if got is None:
                        hi = mid
                    else:
                        lo, good = mid, (mid, got)
            if good is None:
                out.append(intervals[i])
                i += 1
                continue
            j, iv = good
            iv = iv._replace(cert=self.certify(geom, iv.a, iv.b, geom.data(iv.a), iv.segs))
            if not iv.cert.ok:  # refined towards the samples, a bound only ever tightens; kept in case
                out.append(intervals[i])
                i += 1
                continue
            out.append(iv)
            i = j + 1
        return out if len(out) < n else intervals

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
        # A certificate costs in proportion to the source pieces its window spans: over a dense
        # polyline (800 lines of a circle) the search's windows span hundreds, and 11,000
        # certificates took 150 s. The pieces certified are budgeted too.
        spent, piece_budget = [0], MIN_PIECE_BUDGET * len(greedy) + 100

        def feasible(i: int, j: int) -> bool:
            if (i, j) not in cache:
                if self.budget.certificates > budget or spent[0] > piece_budget:
                    raise _OverBudget()
                window = geom.window(cand[i], cand[j])
                if not window:
                    return False
                spent[0] += len(window)
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

    def chord(self, geom: _RunGeom) -> tuple["FittedRun", list[_Cert]] | None:
        """The whole run as one line from its start to its end, where that is certified within ``tol``."""
        a, b = (0, geom.spans[0].t0), (len(geom.spans) - 1, geom.spans[-1].t1)
        p0, p1 = geom.data(a), geom.data(b)
        ell = math.hypot(p1.x - p0.x, p1.y - p0.y)
        if not ell > 0:
            return None
        pose = Pose(p0.x, p0.y, math.atan2(p1.y - p0.y, p1.x - p0.x))
        line = (Segment(0.0, ell),)
        cert = self.certify(geom, a, b, pose, line)
        if not cert.ok:
            return None
        run = FittedRun(start=pose, segments=line, corner=None, hausdorff=cert.bound, curve_length=geom.length,
                        knots=(Knot(geom.spans[0].piece, a[1], 0),))
        return run, [cert]

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


def _check_tol(tol) -> float:
    if isinstance(tol, bool) or not isinstance(tol, (int, float, np.floating)) or not (math.isfinite(tol) and tol > 0):
        raise FitError(f"tol must be a positive finite distance, got {tol!r}")
    return float(tol)


def _check_method(method) -> str:
    if method not in ("greedy", "min"):
        raise FitError(f"method must be 'greedy' or 'min', got {method!r}")
    return method


def fit_path(path: Path, tol: float, *, method: str = "greedy", corner_tol_deg: float = 0.5,
             soft_corners: bool = True) -> PathFit:
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
        See :func:`~skatetrace.drawings.splitting.split_path`.
    soft_corners : bool
        Also join smoothly where a sharper turn between short pieces can be rounded within half of
        ``tol`` (up to :data:`~skatetrace.drawings.splitting.SOFT_MAX_DEG`): a circle drawn as a
        polygon of a few hundred sides is then one run, not a corner at every vertex.

    Returns
    -------
    PathFit
        ``success`` False (with a warning) when a span could not be fitted before reaching
        ``MIN_SPAN`` times the size; the runs then still hold the best fit found and its honest bound.

    Raises
    ------
    FitError
        Invalid ``tol``, ``method`` or ``corner_tol_deg``, or a path that cannot be split (see
        :func:`~skatetrace.drawings.splitting.split_path`).

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
    return _fit_path(path, tol, method, corner_tol_deg, soft_corners)


def _fit_path(path: Path, tol, method, corner_tol_deg, soft: bool, where: tuple[int, int] | None = None) -> PathFit:
    """:func:`fit_path`, reporting progress as the pieces ``where[0]:`` of a drawing of ``where[1]`` pieces."""
    tol = _check_tol(tol)
    method = _check_method(method)
    try:
        before, total = (0, None) if where is None else where

        def split_progress(piece: int) -> None:
            _PROGRESS.report("splitting", before + piece, len(path.pieces) if total is None else total)

        runs, prep = _split(path, corner_tol_deg, tol, progress=split_progress, soft=soft)
        return _fit_runs(path, runs, prep.scale, tol, method, where)
    except ArithmeticError as exc:  # overflow in a user's piece, say; never a wrong answer
        raise FitError(f"path {path.name!r}: numerical failure while fitting ({exc})") from exc


def _fit_runs(path: Path, runs: list[Run], scale: float, tol: float, method: str,
              where: tuple[int, int] | None = None) -> PathFit:
    fitter = _Fitter(path, scale, tol, where)
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
                # A closed path that is one smooth run (a dot, a ring, a circle drawn as four
                # cubics) is merged whatever its length: each quarter of such a circle has three
                # curvature extrema, 16 spiral spans fitted by 32 arcs whatever the tolerance
                # (Adwaita's dots at 6 m: 25 to 28 pieces a dot after the fit, 4 merged).
                smooth_loop = path.closed and len(runs) == 1 and run.corner == 0.0
                merged = fitter.merged(geom, greedy, 3 if smooth_loop else None)
                fr, certs = fitter.realise(geom, merged, free_start, free_end)
                if merged is not greedy and fr.hausdorff > tol:
                    # laid out one after another, the merged biarcs may drift from where they were
                    # certified (a snapped line, say) beyond the tolerance, where greedy's own may not
                    alone = fitter.realise(geom, greedy, free_start, free_end)
                    if alone[0].hausdorff < fr.hausdorff:
                        fitter.notes.append("spans merged drifted beyond the tolerance when laid out; kept greedy's")
                        (fr, certs), merged = alone, greedy
                if fr.hausdorff > tol:
                    # a short stretch of lines with small kinks, each line laid out along the one
                    # before, may drift beyond the tolerance where one biarc over them does not
                    every = fitter.merged(geom, greedy, 3)
                    if every is not greedy:
                        tried = fitter.realise(geom, every, free_start, free_end)
                        if tried[0].hausdorff < fr.hausdorff:
                            fitter.notes.append("laid out as drawn, a run drifted beyond the tolerance; merged its spans")
                            (fr, certs), merged = tried, every
                if free_start and free_end and len(fr.segments) > 1:
                    # A run between two corners is a section of its own, traced from rest to rest; where
                    # its chord is within the tolerance of it, one line is the section most easily
                    # traced: the 0.1 mm between a hairpin's tip and a corner of simple-icons' opentofu at
                    # 6 m / 1 mm, fitted by three arcs of a tenth of a millimetre, was one no launch fits
                    (fr, certs) = fitter.chord(geom) or (fr, certs)
                greedy = merged
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
        warnings.warn(message, RuntimeWarning, stacklevel=4)
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
        warnings.warn(message, RuntimeWarning, stacklevel=4)
    return PathFit(
        success=success, status=status, message=message, runs=tuple(fitted), hausdorff=hausdorff,
        hausdorff_sampled=max((c.sampled for cs in certs_all for c in cs), default=0.0), where=where,
        n_arcs=len(segs) - n_lines, n_lines=n_lines, curve_length=sum(r.curve_length for r in fitted),
        spline_length=float(sum(s.length for s in segs)), tol=tol, method=method, greedy_count=gcount,
        min_count=mcount if method == "min" else None, certificates=fitter.budget.certificates,
        closed=path.closed, name=path.name, size=scale)


def fit_drawing(drawing: Drawing, tol: float, *, method: str = "greedy", corner_tol_deg: float = 0.5,
                soft_corners: bool = True) -> DrawingFit:
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
    total = sum(len(p.pieces) for p in drawing.paths)
    before = np.concatenate([[0], np.cumsum([len(p.pieces) for p in drawing.paths])]).astype(int).tolist()
    fits = tuple(_fit_path(p, tol, method, corner_tol_deg, soft_corners, (before[i], total))
                 for i, p in enumerate(drawing.paths))
    _PROGRESS.report("fitting", total, total)
    return gathered(fits, name=drawing.name, tol=tol)
