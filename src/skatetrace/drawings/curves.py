"""Plane curves as the user draws them, before any arc fitting.

A :class:`Path` is a sequence of smooth parametric pieces, each defined on ``t`` in ``[0, 1]`` with
exact first and second derivatives where they are known (lines, Béziers, elliptic arcs, splines
through points) and central differences otherwise (a Python function). Consecutive pieces meet
end to start; where their tangents differ there is a corner. A :class:`Drawing` is a set of paths
in one coordinate system. Nothing here knows about arcs, fitting or mechanics.

Every piece evaluates vectorised: ``point(t)``, ``d1(t)`` and ``d2(t)`` take an array of ``t`` and
return arrays of shape ``(2, len(t))``.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field, replace
from typing import Callable, Sequence

import numpy as np

_GL5 = np.polynomial.legendre.leggauss(5)

__all__ = [
    "Piece", "LinePiece", "BezierPiece", "EllipticArcPiece", "FunctionPiece", "SplinePiece", "AffinePiece",
    "ShiftedEndPiece", "Path", "Drawing", "curvature", "piece_length",
]


def _t(t) -> np.ndarray:
    return np.atleast_1d(np.asarray(t, dtype=float))


class Piece:
    """Interface of a smooth piece on ``t`` in ``[0, 1]``."""

    def point(self, t) -> np.ndarray:  # pragma: no cover - interface
        raise NotImplementedError

    def d1(self, t) -> np.ndarray:  # pragma: no cover - interface
        raise NotImplementedError

    def d2(self, t) -> np.ndarray:  # pragma: no cover - interface
        raise NotImplementedError

    @property
    def start(self) -> np.ndarray:
        return self.point(0.0)[:, 0]

    @property
    def end(self) -> np.ndarray:
        return self.point(1.0)[:, 0]


@dataclass(frozen=True, slots=True)
class LinePiece(Piece):
    """Straight segment from ``p0`` to ``p1``."""

    p0: tuple[float, float]
    p1: tuple[float, float]

    def point(self, t):
        t = _t(t)
        a, b = np.asarray(self.p0, float), np.asarray(self.p1, float)
        return a[:, None] + (b - a)[:, None] * t

    def d1(self, t):
        t = _t(t)
        return np.repeat((np.asarray(self.p1, float) - np.asarray(self.p0, float))[:, None], t.size, axis=1)

    def d2(self, t):
        return np.zeros((2, _t(t).size))


@dataclass(frozen=True, slots=True)
class BezierPiece(Piece):
    """Bézier curve of degree ``len(control) - 1`` (1 to 3 in SVG) through Bernstein polynomials."""

    control: tuple[tuple[float, float], ...]

    def __post_init__(self) -> None:
        if len(self.control) < 2:
            raise ValueError("a Bézier piece needs at least two control points")

    def _eval(self, pts: np.ndarray, t: np.ndarray) -> np.ndarray:
        n = len(pts) - 1
        if n < 0:
            return np.zeros((2, t.size))
        out = np.zeros((2, t.size))
        for i, p in enumerate(pts):
            out += np.outer(p, math.comb(n, i) * t ** i * (1 - t) ** (n - i))
        return out

    def point(self, t):
        return self._eval(np.asarray(self.control, float), _t(t))

    def d1(self, t):
        p = np.asarray(self.control, float)
        n = len(p) - 1
        return self._eval(n * np.diff(p, axis=0), _t(t))

    def d2(self, t):
        p = np.asarray(self.control, float)
        n = len(p) - 1
        if n < 2:
            return np.zeros((2, _t(t).size))
        return self._eval(n * (n - 1) * np.diff(p, n=2, axis=0), _t(t))


@dataclass(frozen=True, slots=True)
class EllipticArcPiece(Piece):
    """``centre + R(rotation) (rx cos(th), ry sin(th))`` with ``th = theta0 + t * dtheta``."""

    centre: tuple[float, float]
    rx: float
    ry: float
    rotation: float
    theta0: float
    dtheta: float

    def _frame(self):
        c, s = math.cos(self.rotation), math.sin(self.rotation)
        return np.array([[c, -s], [s, c]])

    def _local(self, t, order):
        th = self.theta0 + _t(t) * self.dtheta
        k = self.dtheta ** order
        funcs = [(np.cos, np.sin), (lambda x: -np.sin(x), np.cos), (lambda x: -np.cos(x), lambda x: -np.sin(x))]
        fx, fy = funcs[order]
        return k * np.vstack([self.rx * fx(th), self.ry * fy(th)])

    def point(self, t):
        return np.asarray(self.centre, float)[:, None] + self._frame() @ self._local(t, 0)

    def d1(self, t):
        return self._frame() @ self._local(t, 1)

    def d2(self, t):
        return self._frame() @ self._local(t, 2)


@dataclass(frozen=True, slots=True)
class FunctionPiece(Piece):
    """A user's ``fn(u) -> (x, y)`` on ``u`` in ``[u0, u1]``, mapped to ``t`` in ``[0, 1]``.

    ``fn`` must accept a numpy array of ``u`` and return two arrays (or an array of shape
    ``(2, n)``). Derivatives ``d1``/``d2`` of ``fn`` with respect to ``u`` may be given; otherwise
    they are central differences with a step suited to double precision.
    """

    fn: Callable
    u0: float = 0.0
    u1: float = 1.0
    dfn: Callable | None = None
    d2fn: Callable | None = None

    def _u(self, t):
        return self.u0 + _t(t) * (self.u1 - self.u0)

    @staticmethod
    def _call(f, u) -> np.ndarray:
        out = np.asarray(f(u), dtype=float)
        if out.shape == (2,) and u.size == 1:
            out = out[:, None]
        if out.shape != (2, u.size):
            raise ValueError(f"a parametric curve must return x and y of shape (2, n); got {out.shape}")
        return out

    def point(self, t):
        return self._call(self.fn, self._u(t))

    def d1(self, t):
        u, k = self._u(t), self.u1 - self.u0
        if self.dfn is not None:
            return k * self._call(self.dfn, u)
        h = 1e-5 * max(1.0, abs(k))
        return k * (self._call(self.fn, u + h) - self._call(self.fn, u - h)) / (2 * h)

    def d2(self, t):
        u, k = self._u(t), self.u1 - self.u0
        if self.d2fn is not None:
            return k * k * self._call(self.d2fn, u)
        h = 1e-4 * max(1.0, abs(k))
        return k * k * (self._call(self.fn, u + h) - 2 * self._call(self.fn, u) + self._call(self.fn, u - h)) / h ** 2


@dataclass(frozen=True, slots=True)
class SplinePiece(Piece):
    """A scipy piecewise polynomial ``spline(u) -> (n, 2)`` on ``[u0, u1]`` (e.g. CubicSpline)."""

    spline: object
    u0: float
    u1: float

    def _ev(self, t, nu):
        u = self.u0 + _t(t) * (self.u1 - self.u0)
        return np.asarray(self.spline(u, nu), dtype=float).T * (self.u1 - self.u0) ** nu

    def point(self, t):
        return self._ev(t, 0)

    def d1(self, t):
        return self._ev(t, 1)

    def d2(self, t):
        return self._ev(t, 2)


@dataclass(frozen=True, slots=True)
class AffinePiece(Piece):
    """``A @ base(t) + b``: any piece under an affine map (SVG transforms, scaling, y flip)."""

    base: Piece
    A: tuple[tuple[float, float], tuple[float, float]]
    b: tuple[float, float] = (0.0, 0.0)

    def point(self, t):
        return np.asarray(self.A, float) @ self.base.point(t) + np.asarray(self.b, float)[:, None]

    def d1(self, t):
        return np.asarray(self.A, float) @ self.base.d1(t)

    def d2(self, t):
        return np.asarray(self.A, float) @ self.base.d2(t)


@dataclass(frozen=True, slots=True)
class ShiftedEndPiece(Piece):
    """``base`` with its end moved by ``delta`` (and its start by ``start_delta``, default kept):
    ``base(t) + w(t) delta + (1 - w(t)) start_delta``, where ``w = 10 t^3 - 15 t^4 + 6 t^5`` has zero
    slope and curvature at both ends, so the tangents and curvatures there are the base's. No point
    moves by more than the larger of ``|delta|`` and ``|start_delta|``."""

    base: Piece
    delta: tuple[float, float]
    start_delta: tuple[float, float] = (0.0, 0.0)

    def _shift(self, t, w, constant: bool):
        end, start = np.asarray(self.delta, float), np.asarray(self.start_delta, float)
        out = np.outer(end - start, w(_t(t)))
        return out + start[:, None] if constant else out

    def point(self, t):
        return self.base.point(t) + self._shift(t, lambda u: u**3 * (10.0 - 15.0 * u + 6.0 * u**2), True)

    def d1(self, t):
        return self.base.d1(t) + self._shift(t, lambda u: 30.0 * u**2 * (1.0 - u) ** 2, False)

    def d2(self, t):
        return self.base.d2(t) + self._shift(t, lambda u: 60.0 * u * (1.0 - u) * (1.0 - 2.0 * u), False)


def curvature(piece: Piece, t) -> np.ndarray:
    """Signed curvature ``(x' y'' - y' x'') / |r'|^3`` (positive turns left); NaN where ``r' = 0``."""
    d1, d2 = piece.d1(t), piece.d2(t)
    sp = np.hypot(d1[0], d1[1])
    with np.errstate(all="ignore"):
        k = (d1[0] * d2[1] - d1[1] * d2[0]) / sp ** 3
    return np.where(sp > 0, k, np.nan)


@functools.lru_cache(maxsize=8)
def _gauss_legendre(n: int) -> tuple[np.ndarray, np.ndarray]:
    """Gauss-Legendre nodes and weights on ``n`` nodes (an eigenvalue problem: ~1 ms at 64, so kept)."""
    return np.polynomial.legendre.leggauss(n)


def piece_length(piece: Piece, t0: float = 0.0, t1: float = 1.0, n: int = 64) -> float:
    """Arc length between ``t0`` and ``t1`` by Gauss-Legendre quadrature on ``n`` nodes."""
    x, w = _gauss_legendre(n)
    t = 0.5 * (t1 - t0) * x + 0.5 * (t1 + t0)
    d = piece.d1(t)
    return float(0.5 * (t1 - t0) * np.sum(w * np.hypot(d[0], d[1])))


def _gl_lengths(piece: Piece, ta: np.ndarray, tb: np.ndarray) -> np.ndarray:
    """Arc length of each interval ``[ta, tb]`` by 5-point Gauss-Legendre."""
    x, w = _GL5
    mid, half = 0.5 * (ta + tb), 0.5 * (tb - ta)
    tt = (mid[:, None] + half[:, None] * x[None, :]).ravel()
    d = piece.d1(tt)
    sp = np.hypot(d[0], d[1]).reshape(-1, x.size)
    return np.abs(half) * (sp @ w)


def _col(piece: Piece, fn: str, t: float) -> np.ndarray:
    """``piece.point``, ``d1`` or ``d2`` (named by ``fn``) at one parameter ``t``, shape ``(2,)``."""
    return np.asarray(getattr(piece, fn)(float(t)), dtype=float)[:, 0]


def _noisy(piece: Piece) -> bool:
    """Whether a piece's second derivative is a finite difference (curvature then has ~1e-8 noise)."""
    if isinstance(piece, AffinePiece):
        return _noisy(piece.base)
    if isinstance(piece, FunctionPiece):
        return piece.d2fn is None
    return not isinstance(piece, (LinePiece, BezierPiece, EllipticArcPiece, SplinePiece))


@dataclass(frozen=True, slots=True)
class Path:
    """Pieces joined end to start. ``closed`` if the last piece ends where the first starts."""

    pieces: tuple[Piece, ...]
    closed: bool = False
    name: str = "path"

    def __post_init__(self) -> None:
        if not self.pieces:
            raise ValueError(f"path {self.name!r} is empty: it has no pieces")

    def points(self, n: int = 64) -> np.ndarray:
        """``n`` points per piece, shape ``(2, m)``."""
        return np.hstack([p.point(np.linspace(0.0, 1.0, n)) for p in self.pieces])

    def transformed(self, A, b=(0.0, 0.0)) -> "Path":
        A = tuple(tuple(float(v) for v in row) for row in A)
        b = tuple(float(v) for v in b)
        return Path(tuple(AffinePiece(p, A, b) for p in self.pieces), self.closed, self.name)

    def length(self) -> float:
        return sum(piece_length(p) for p in self.pieces)


@dataclass(frozen=True, slots=True)
class Drawing:
    """Paths in one coordinate system, with where they came from and what one unit means."""

    paths: tuple[Path, ...]
    name: str = "drawing"
    source: str = ""
    unit: str = "model"  # "model" (the sleigh's units) or "m"
    notes: tuple[str, ...] = field(default=())

    def __post_init__(self) -> None:
        if not self.paths:
            raise ValueError(f"drawing {self.name!r} has no paths")

    def bbox(self) -> tuple[float, float, float, float]:
        pts = np.hstack([p.points(129) for p in self.paths])
        return float(pts[0].min()), float(pts[1].min()), float(pts[0].max()), float(pts[1].max())

    def size(self) -> float:
        x0, y0, x1, y1 = self.bbox()
        return max(x1 - x0, y1 - y0)

    def selected(self, names) -> "Drawing":
        """Only the paths named in ``names``: an element's ``id`` picks all its subpaths (``id``,
        ``id#2``, ...), a subpath's own name (``id#2``) that one.

        Raises
        ------
        ValueError
            A name that matches no path (the message lists the names there are).
        """
        names = list(dict.fromkeys(str(n) for n in names))

        def element(p: Path) -> str:
            return p.name.split("#", 1)[0]

        def named(p: Path, n: str) -> bool:
            return n in (p.name, element(p))

        keep = [p for p in self.paths if any(named(p, n) for n in names)]
        missing = [n for n in names if not any(named(p, n) for p in self.paths)]
        if missing:
            there = sorted(dict.fromkeys(element(p) for p in self.paths))
            raise ValueError(f"no path named {', '.join(map(repr, missing))} in {self.name!r}; its paths are "
                             f"{', '.join(there[:20])}{' ...' if len(there) > 20 else ''}")
        return replace(self, paths=tuple(keep), notes=(*self.notes, f"kept the paths {', '.join(names)} of "
                                                                   f"{len(self.paths)}"))

    def closed_within(self, gap: float) -> tuple["Drawing", dict[str, float]]:
        """Every open path whose end is closer than ``gap`` to its start, closed exactly.

        The last piece's end is moved onto the start (:class:`ShiftedEndPiece`: its tangent and
        curvature at both ends unchanged), where that keeps its speed above half of its smallest;
        no point of the drawing moves by more than the path's own gap, which is returned by name.
        """
        out, moved = [], {}
        for p in self.paths:
            last = p.pieces[-1]
            delta = np.asarray(p.pieces[0].start, float) - np.asarray(last.end, float)
            d = float(np.hypot(*delta))
            if p.closed or not (0.0 < d < gap):
                out.append(p)
                continue
            t = np.linspace(0.0, 1.0, 65)
            speed = np.hypot(*last.d1(t))
            shifted = ShiftedEndPiece(last, (float(delta[0]), float(delta[1])))
            if np.min(np.hypot(*shifted.d1(t))) < 0.5 * np.min(speed):
                out.append(p)
                continue
            out.append(Path((*p.pieces[:-1], shifted), True, p.name))
            moved[p.name] = d
        return (replace(self, paths=tuple(out)) if moved else self), moved

    def absorbed(self, limit: float, corner_deg: float) -> tuple["Drawing", dict[str, float]]:
        """Every piece shorter than ``limit`` with a corner at both ends absorbed into its neighbours.

        Such a piece is a section of its own, rest to rest within a millimetre or so (a
        closing line of a millimetre in an icon scaled to metres). Its ends are merged at its
        midpoint: the previous piece's end and the next piece's start move there
        (:class:`ShiftedEndPiece`: their tangents and curvatures at both ends kept), so no point
        of the drawing moves by more than half the piece's length. An open path's first or last
        piece shorter than ``limit / 2`` with a corner at its inner end is dropped: every point of
        it lies within its length of that end, which stays. The largest move is returned per path,
        with the paths changed. A join turning by more than ``corner_deg`` degrees is a corner.
        Left as they are: a piece next to one absorbed or dropped, a path of one piece (or of two,
        for absorbing), and a piece whose absorption would fold a neighbour (its speed below half
        its smallest).
        """
        out, moved = [], {}
        for p in self.paths:
            path, half = _absorbed(p, limit, corner_deg)
            out.append(path)
            if half > 0.0:
                moved[p.name] = half
        return (replace(self, paths=tuple(out)) if moved else self), moved

    def scaled_to(self, size: float, unit: str | None = None) -> "Drawing":
        """Uniformly scaled about the bounding-box centre so that its larger side is ``size``, moved to the origin."""
        if not (size > 0 and math.isfinite(size)):
            raise ValueError(f"size must be a positive length, got {size!r}")
        cur = self.size()
        if not cur > 0:
            raise ValueError(f"drawing {self.name!r} has zero extent: all its points coincide")
        x0, y0, x1, y1 = self.bbox()
        k = size / cur
        A = ((k, 0.0), (0.0, k))
        b = (-k * 0.5 * (x0 + x1), -k * 0.5 * (y0 + y1))
        return Drawing(tuple(p.transformed(A, b) for p in self.paths), self.name, self.source,
                       unit if unit is not None else self.unit, self.notes)


def _as_points(seq: Sequence) -> np.ndarray:
    return np.asarray(seq, dtype=float)


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


def _end_direction(piece: Piece, t: float, side: int) -> np.ndarray:
    """:func:`_direction` at an end of a whole piece, else (nowhere defined) its chord, as :mod:`.splitting` takes it."""
    v = _direction(piece, t, side, max(piece_length(piece), 1e-300))
    return v if v is not None else _col(piece, "point", 1.0) - _col(piece, "point", 0.0)


def _turn_deg(before: Piece, after: Piece) -> float:
    """How far the tangent turns (degrees, unsigned) from the end of ``before`` to the start of ``after``.

    An end where the derivative vanishes turns by its limit direction's angle: read from the zero
    vector, it was 0, and a 0.3 mm line before such a Bézier (phosphor's phone-incoming, at 6 m) was
    taken for part of a smooth run, never absorbed, where the fit made a corner.
    """
    a, b = _end_direction(before, 1.0, -1), _end_direction(after, 0.0, +1)
    return abs(math.degrees(math.atan2(a[0] * b[1] - a[1] * b[0], float(a @ b))))


def _min_speed(piece: Piece) -> float:
    return float(np.min(np.hypot(*piece.d1(np.linspace(0.0, 1.0, 65)))))


#: Pieces shorter than this share of the absorption limit are rounding (a ``z`` after an end that
#: missed the start by 1e-16): absorbed first, so that they keep no neighbour from being absorbed.
_ROUNDING_SHARE = 1e-6


def _absorbed(path: Path, limit: float, corner_deg: float) -> tuple[Path, float]:
    """:meth:`Drawing.absorbed` on one path: the path and the largest distance a point of it moved.

    The pieces of rounding go first (octicons' versions-16 closes a path with a line of 3e-16 m at
    6 m after a first line of 0.375 mm, which their neighbourhood kept as a section of its own).
    """
    if len(path.pieces) < 2 or not limit > 0.0:
        return path, 0.0
    lengths = [piece_length(pc) for pc in path.pieces]
    clean, noise = _absorbed_once(path, lengths, _ROUNDING_SHARE * limit, corner_deg)
    if clean is not path:  # the neighbours of the rounding moved: their lengths again
        lengths = [piece_length(pc) for pc in clean.pieces]
    out, moved = _absorbed_once(clean, lengths, limit, corner_deg)
    return out, max(noise, moved)


def _absorbed_once(path: Path, lengths: list[float], limit: float, corner_deg: float) -> tuple[Path, float]:
    """One pass of :func:`_absorbed`: the pieces shorter than ``limit``, shortest first (``lengths`` theirs)."""
    pieces = list(path.pieces)
    n = len(pieces)
    if n < 2:
        return path, 0.0
    start = [np.zeros(2) for _ in range(n)]  # how far each kept piece's start and end move
    end = [np.zeros(2) for _ in range(n)]
    gone: dict[int, float] = {}  # the pieces absorbed or dropped, and how far that moves the drawing
    for i in sorted(range(n), key=lambda k: lengths[k]):
        if lengths[i] >= limit:
            break
        if not path.closed and i in (0, n - 1):
            # an open path's end piece: dropped, where it is short enough and turns a corner into the rest
            inner = 1 if i == 0 else n - 2
            turn = _turn_deg(pieces[0], pieces[1]) if i == 0 else _turn_deg(pieces[n - 2], pieces[n - 1])
            if lengths[i] < 0.5 * limit and inner not in gone and turn > corner_deg:
                gone[i] = lengths[i]
            continue
        prev, nxt = (i - 1) % n, (i + 1) % n
        if n < 3 or gone.keys() & {prev, nxt}:
            continue  # a neighbour of an absorbed piece (a piece shared by two absorbed moves at both ends)
        if min(_turn_deg(pieces[prev], pieces[i]), _turn_deg(pieces[i], pieces[nxt])) <= corner_deg:
            continue  # smooth at one end: part of a run, which the fit spans
        mid = 0.5 * (_col(pieces[i], "point", 0.0) + _col(pieces[i], "point", 1.0))
        shifted_end = mid - _col(pieces[i], "point", 0.0)
        shifted_start = mid - _col(pieces[i], "point", 1.0)
        trial_prev = ShiftedEndPiece(pieces[prev], tuple(end[prev] + shifted_end), tuple(start[prev]))
        trial_next = ShiftedEndPiece(pieces[nxt], tuple(end[nxt]), tuple(start[nxt] + shifted_start))
        if (_min_speed(trial_prev) < 0.5 * _min_speed(pieces[prev])
                or _min_speed(trial_next) < 0.5 * _min_speed(pieces[nxt])):
            continue
        end[prev] = end[prev] + shifted_end
        start[nxt] = start[nxt] + shifted_start
        gone[i] = 0.5 * lengths[i]
    if not gone:
        return path, 0.0
    kept = []
    for k, pc in enumerate(pieces):
        if k in gone:
            continue
        moved = bool(np.any(start[k]) or np.any(end[k]))
        kept.append(ShiftedEndPiece(pc, tuple(map(float, end[k])), tuple(map(float, start[k]))) if moved else pc)
    return Path(tuple(kept), path.closed, path.name), max(gone.values())
