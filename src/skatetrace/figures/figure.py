"""Figures: ordered arcs, lines and spirals joined smoothly or at cusps, optionally repeated N-fold.

A :class:`Curve` is one stroke on the ice. Consecutive pieces meet at a :class:`Join`:

- ``smooth``: the sleigh keeps moving through the join (the tangent is continuous);
- ``cusp``: the sleigh comes to rest; the blade may then pivot by ``pivot`` radians, and/or
  ``reverse`` (move on backwards, drawing a true cusp with the tangent reversed, no rotation).

A curve may be repeated ``repeat`` times, copy ``k`` being the unit carried on by the same rigid
motion; ``closing`` is the join between copies and back to the start. A :class:`Figure` is a
collection of curves. The JSON form is documented in the user guide, ``docs/guide/figure-format.md`` (schema ``skatetrace.figure/1``).
"""

from __future__ import annotations

import json
import math
import reprlib
from dataclasses import dataclass, field
from pathlib import Path
from collections.abc import Iterable
from typing import Any

import numpy as np

from ..dynamics.model import SleighParams
from ..errors import FigureFormatError
from .geometry import Pose, Segment, Spiral, end_pose, rigid_motion_centre

__all__ = ["Join", "Curve", "Figure", "Placed", "Section", "SMOOTH", "figure_from_dict", "load_figure"]

SCHEMA = "skatetrace.figure/1"

#: Limits on a figure, so that untrusted input cannot ask for unbounded work or for numbers whose
#: layout overflows or rounds away. Pieces of all copies of all curves (a traced section each at most):
MAX_PIECES = 10_000
#: Piece lengths and radii (1 / |curvature|) lie in [MIN_LENGTH, MAX_LENGTH]; start coordinates
#: within MAX_LENGTH of the origin (in the figure's units: model units or metres).
MIN_LENGTH = 1e-9
MAX_LENGTH = 1e9
#: Largest turn of the heading along one arc (radians; about 160 000 full turns): beyond it the
#: heading's rounding error would move the arc's end by more than the verification tolerance.
MAX_ARC_TURN = 1e6
#: Largest turn of the heading along one spiral (radians): its layout integrates the heading on
#: cells of 0.2 rad each, so this bounds the work per spiral.
MAX_SPIRAL_TURN = 1e4
#: Model parameters M, m, I a figure (or the command line) may ask for: within this range every
#: built-in figure traces or fails as data; at 1e300 the tracer's integrator divides by zero.
PARAM_RANGE = (1e-6, 1e6)


def _is_real(value) -> bool:
    return isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, (bool, np.bool_))


@dataclass(frozen=True, slots=True)
class Join:
    """How two consecutive pieces meet. ``pivot`` in radians (positive turns left)."""

    kind: str = "cusp"
    pivot: float = 0.0
    reverse: bool = False

    def __post_init__(self) -> None:
        if self.kind not in ("smooth", "cusp"):
            raise FigureFormatError(f"join kind must be 'smooth' or 'cusp', got {self.kind!r}")
        if not (_is_real(self.pivot) and math.isfinite(self.pivot)):
            raise FigureFormatError(f"pivot must be finite (a number of radians), got {self.pivot!r}")
        # a pivot turns the blade at rest: a whole turn or more is no pivot of a figure (1e12 degrees
        # made the layout's headings lose every digit and the replay NaN)
        if not abs(self.pivot) <= 2.0 * math.pi:
            raise FigureFormatError(f"pivot must be an angle of at most a whole turn (-360 to 360 degrees, "
                                    f"-2 pi to 2 pi radians), got {math.degrees(self.pivot):.6g} degrees")
        if not isinstance(self.reverse, (bool, np.bool_)):
            raise FigureFormatError(f"reverse must be True or False, got {self.reverse!r}")
        if self.kind == "smooth" and (self.pivot != 0.0 or self.reverse):
            raise FigureFormatError("a smooth join cannot pivot or reverse; use a cusp")

    @property
    def is_cusp(self) -> bool:
        return self.kind == "cusp"

    def to_dict(self) -> dict[str, Any]:
        if self.kind == "smooth":
            return {"type": "smooth"}
        out: dict[str, Any] = {"type": "cusp", "pivot_deg": math.degrees(self.pivot)}
        if self.reverse:
            out["reverse"] = True
        return out


SMOOTH = Join("smooth")
REST = Join("cusp", 0.0)  # a stop at a smooth join: the path continues unchanged after it


@dataclass(frozen=True, slots=True)
class Placed:
    """A piece laid out on the ice: where it starts (travel direction) and which way the blade runs."""

    index: int  # position in the expanded curve
    segment: Segment | Spiral
    start: Pose  # start point and direction of travel
    direction: int  # +1 blade runs forwards, -1 backwards (after an odd number of reversals)
    join_before: Join | None  # None for the first piece


@dataclass(frozen=True, slots=True)
class Section:
    """A maximal run of pieces joined smoothly: traced from rest to rest."""

    pieces: tuple[Placed, ...]

    @property
    def segments(self) -> list[Segment | Spiral]:
        return [p.segment for p in self.pieces]

    @property
    def length(self) -> float:
        return sum(p.segment.length for p in self.pieces)


@dataclass(frozen=True, slots=True)
class Curve:
    """One stroke: pieces, the joins between them, and an optional N-fold repetition.

    A piece is a :class:`~skatetrace.figures.geometry.Segment` (arc or line) or a
    :class:`~skatetrace.figures.geometry.Spiral` (curvature a cubic of arc length).
    """

    pieces: tuple[Segment | Spiral, ...]
    joins: tuple[Join, ...] = ()
    repeat: int = 1
    closing: Join | None = None
    start: Pose = Pose(0.0, 0.0, 0.0)
    name: str = "curve"

    def __post_init__(self) -> None:
        if not self.pieces:
            raise FigureFormatError(f"curve {self.name!r} has no pieces")
        if not (isinstance(self.repeat, int) and not isinstance(self.repeat, bool) and self.repeat >= 1):
            raise FigureFormatError(f"curve {self.name!r}: repeat must be a whole number >= 1, got {self.repeat!r}")
        if len(self.pieces) * self.repeat > MAX_PIECES:
            raise FigureFormatError(f"curve {self.name!r}: {_count_pieces(len(self.pieces), self.repeat)}; at most "
                                    f"{MAX_PIECES} pieces are allowed in a figure")
        for i, seg in enumerate(self.pieces):
            _check_piece(seg, f"curve {self.name!r}, piece {i}")
        if not isinstance(self.joins, tuple) or not all(isinstance(j, Join) for j in self.joins):
            raise FigureFormatError(f"curve {self.name!r}: joins must be a tuple of Join, got {self.joins!r}")
        if len(self.joins) != len(self.pieces) - 1:
            raise FigureFormatError(
                f"curve {self.name!r}: {len(self.pieces)} pieces need {len(self.pieces) - 1} joins, "
                f"got {len(self.joins)}"
            )
        if self.closing is not None and not isinstance(self.closing, Join):
            raise FigureFormatError(f"curve {self.name!r}: the closing join must be a Join, got {self.closing!r}")
        if self.repeat > 1 and self.closing is None:
            raise FigureFormatError(f"curve {self.name!r}: a repeated curve needs a closing join")
        start = self.start
        if not (isinstance(start, tuple) and len(start) == 3
                and all(_is_real(v) and math.isfinite(v) for v in start)):
            raise FigureFormatError(f"curve {self.name!r}: start must be a Pose (x, y, heading) of finite numbers, "
                                    f"got {start!r}")
        if max(abs(start[0]), abs(start[1])) > MAX_LENGTH:
            raise FigureFormatError(f"curve {self.name!r}: the start ({start[0]:g}, {start[1]:g}) must lie within "
                                    f"{MAX_LENGTH:g} of the origin")

    def expanded(self) -> list[tuple[Segment | Spiral, Join | None]]:
        """All pieces of all copies, each with the join before it (``None`` first)."""
        out: list[tuple[Segment | Spiral, Join | None]] = []
        for copy in range(self.repeat):
            for i, seg in enumerate(self.pieces):
                if i > 0:
                    join = self.joins[i - 1]
                elif copy > 0:
                    join = self.closing
                else:
                    join = None
                out.append((seg, join))
        return out

    def layout(self) -> list[Placed]:
        """Place every piece on the ice."""
        pose, direction, placed = self.start, 1, []
        for i, (seg, join) in enumerate(self.expanded()):
            if join is not None:
                pose, direction = _apply_join(pose, direction, join)
            placed.append(Placed(i, seg, pose, direction, join))
            pose = end_pose(pose, seg)
        return placed

    def end_pose(self) -> tuple[Pose, int]:
        """Pose and blade direction after the last piece and, if repeated, the closing join."""
        last = self.layout()[-1]
        pose = end_pose(last.start, last.segment)
        direction = last.direction
        if self.closing is not None:
            pose, direction = _apply_join(pose, direction, self.closing)
        return pose, direction

    def sections(self) -> list[Section]:
        """Split at cusps into runs traced from rest to rest."""
        out: list[list[Placed]] = []
        for p in self.layout():
            if p.join_before is None or p.join_before.is_cusp:
                out.append([])
            out[-1].append(p)
        return [Section(tuple(s)) for s in out]

    def unit_centre(self) -> tuple[float, float] | None:
        """Centre of the rotation that carries one copy onto the next (``None`` if a translation)."""
        one = Curve(self.pieces, self.joins, 1, None, self.start, self.name)
        pose, _ = one.end_pose()
        if self.closing is not None:
            pose, _ = _apply_join(pose, 1, self.closing)
        return rigid_motion_centre(self.start, pose)

    def closure(self) -> dict[str, Any]:
        """How far the end of the curve is from its start (position and heading)."""
        pose, direction = self.end_pose()
        gap = math.hypot(pose.x - self.start.x, pose.y - self.start.y)
        dh = math.remainder(pose.heading - self.start.heading, 2 * math.pi)
        return {"position_gap": gap, "heading_gap": dh, "direction_restored": direction == 1,
                "closed": gap <= 1e-9 * max(1.0, self.size()) and abs(dh) <= 1e-9}

    def size(self) -> float:
        """Diameter of the curve's bounding box (its larger side)."""
        import numpy as np

        from .geometry import segment_points

        pts = np.hstack([segment_points(p.start, p.segment, 64) for p in self.layout()])
        return float(max(np.ptp(pts[0]), np.ptp(pts[1]), 1e-300))

    def merged(self, rel_tol: float = 1e-12) -> "Curve":
        """The same curve with consecutive pieces of equal curvature joined smoothly made into one.

        Arc fits of drawn circles come in several arcs of one radius; one piece traces faster and
        the same. Curvatures equal within ``rel_tol`` (relative to the larger) count as equal.
        Spirals are kept as they are.
        """
        pieces, joins = [self.pieces[0]], []
        for seg, join in zip(self.pieces[1:], self.joins):
            last = pieces[-1]
            if isinstance(seg, Spiral) or isinstance(last, Spiral):
                pieces.append(seg)
                joins.append(join)
                continue
            same = abs(seg.curvature - last.curvature) <= rel_tol * max(abs(seg.curvature), abs(last.curvature))
            if not join.is_cusp and same:
                pieces[-1] = Segment(last.curvature, last.length + seg.length)
            else:
                pieces.append(seg)
                joins.append(join)
        return Curve(tuple(pieces), tuple(joins), self.repeat, self.closing, self.start, self.name)

    def with_rests(self, before: Iterable[int]) -> "Curve":
        """The same curve with the sleigh brought to rest at the smooth joins before pieces ``before``.

        ``before`` are indices into :meth:`expanded` (the pieces of all copies). A rest is a cusp
        without a pivot: the path on the ice is unchanged, but the join becomes the boundary of two
        sections traced from rest to rest. The result lists all copies as pieces (``repeat = 1``,
        the closing join kept for :meth:`closure`).
        """
        before = set(before)
        if not before:
            return self
        items = self.expanded()
        for i in before:
            if not (0 < i < len(items)) or items[i][1] is None or items[i][1].is_cusp:
                raise FigureFormatError(f"curve {self.name!r}: piece {i} does not follow a smooth join")
        pieces = tuple(seg for seg, _ in items)
        joins = tuple(REST if i in before else join for i, (_, join) in enumerate(items) if i > 0)
        return Curve(pieces, joins, 1, self.closing, self.start, self.name)

    def centred_at(self, x: float, y: float) -> "Curve":
        """The same curve moved so that its repetition centre sits at ``(x, y)``."""
        c = self.unit_centre()
        if c is None:
            raise FigureFormatError(f"curve {self.name!r} has no rotation centre (its copies only translate)")
        return Curve(self.pieces, self.joins, self.repeat, self.closing,
                     Pose(self.start.x + x - c[0], self.start.y + y - c[1], self.start.heading), self.name)

    def to_dict(self) -> dict[str, Any]:
        out: dict[str, Any] = {
            "name": self.name,
            "start": {"x": self.start.x, "y": self.start.y, "heading_deg": math.degrees(self.start.heading)},
            "pieces": [_segment_to_dict(s) for s in self.pieces],
            "joins": [j.to_dict() for j in self.joins],
        }
        if self.repeat > 1:
            out["repeat"] = self.repeat
        if self.closing is not None:
            out["closing_join"] = self.closing.to_dict()
        return out


@dataclass(frozen=True, slots=True)
class Figure:
    """A named collection of curves, with optional model parameters and provenance."""

    name: str
    curves: tuple[Curve, ...]
    params: SleighParams | None = None
    description: str = ""
    provenance: str = ""
    extra: dict = field(default_factory=dict, compare=False)

    def __post_init__(self) -> None:
        if not self.curves:
            raise FigureFormatError(f"figure {self.name!r} has no curves")
        if not all(isinstance(c, Curve) for c in self.curves):
            raise FigureFormatError(f"figure {self.name!r}: curves must be Curve objects")
        total = sum(len(c.pieces) * c.repeat for c in self.curves)
        if total > MAX_PIECES:
            raise FigureFormatError(f"figure {self.name!r} has {total} pieces (all copies of all curves); "
                                    f"at most {MAX_PIECES} are allowed")

    def size(self) -> float:
        """Larger side of the bounding box of the whole figure."""
        import numpy as np

        from .geometry import segment_points

        pts = np.hstack([segment_points(p.start, p.segment, 64) for c in self.curves for p in c.layout()])
        return float(max(np.ptp(pts[0]), np.ptp(pts[1]), 1e-300))

    def to_dict(self) -> dict[str, Any]:
        out: dict[str, Any] = {"schema": SCHEMA, "name": self.name}
        if self.description:
            out["description"] = self.description
        if self.provenance:
            out["provenance"] = self.provenance
        if self.params is not None:
            out["params"] = self.params.to_dict()
        out["curves"] = [c.to_dict() for c in self.curves]
        return out


_REPR = reprlib.Repr()
_REPR.maxstring, _REPR.maxother, _REPR.maxlevel = 60, 60, 3


def _show(value: Any) -> str:
    """``repr(value)`` cut short: untrusted input may be huge or deeply nested."""
    return _REPR.repr(value)


def _count_pieces(n: int, repeat: int) -> str:
    if repeat == 1:
        return f"{n} pieces"
    return f"{n} piece{'s' if n != 1 else ''} repeated {repeat} times make {n * repeat} pieces"


def _check_piece(seg, where: str) -> None:
    """Raise :class:`FigureFormatError` unless ``seg`` is a piece within the figure limits."""
    if not isinstance(seg, (Segment, Spiral)):
        raise FigureFormatError(f"{where}: expected a Segment or a Spiral, got {type(seg).__name__}")
    length = seg.length
    if not (_is_real(length) and math.isfinite(length) and length > 0):
        raise FigureFormatError(f"{where}: length must be positive and finite, got {length!r}")
    if not MIN_LENGTH <= length <= MAX_LENGTH:
        raise FigureFormatError(f"{where}: length must lie between {MIN_LENGTH:g} and {MAX_LENGTH:g}, got {length!r}")
    coeffs = seg.coefficients
    if len(coeffs) != 4 or not all(_is_real(c) and math.isfinite(c) for c in coeffs):
        raise FigureFormatError(f"{where}: curvature must be finite numbers, got {coeffs!r}")
    if isinstance(seg, Segment):
        k = abs(seg.curvature)
        if k > 1.0 / MIN_LENGTH:
            raise FigureFormatError(f"{where}: radius must be at least {MIN_LENGTH:g} (|curvature| at most "
                                    f"{1.0 / MIN_LENGTH:g}), got curvature {seg.curvature!r}")
        if 0.0 < k < 1.0 / MAX_LENGTH:
            raise FigureFormatError(f"{where}: radius must be at most {MAX_LENGTH:g} (use a line), got curvature "
                                    f"{seg.curvature!r}")
        if k * length > MAX_ARC_TURN:
            raise FigureFormatError(f"{where}: an arc may turn by at most {MAX_ARC_TURN:g} rad "
                                    f"({math.degrees(MAX_ARC_TURN):.3g} degrees), got {k * length:.3g} rad")
        return
    # A spiral: its largest |curvature| over the piece, computed in a way that cannot overflow to
    # NaN first (each term bounded before the polynomial is evaluated).
    bound = sum(abs(c) * length**j for j, c in enumerate(coeffs))
    if not (math.isfinite(bound) and bound * length <= MAX_SPIRAL_TURN):
        kmax = seg.max_abs_curvature() if math.isfinite(bound) else math.inf
        if not (math.isfinite(kmax) and kmax * length <= MAX_SPIRAL_TURN and kmax <= 1.0 / MIN_LENGTH):
            raise FigureFormatError(f"{where}: a spiral may turn by at most {MAX_SPIRAL_TURN:g} rad and its "
                                    f"|curvature| be at most {1.0 / MIN_LENGTH:g}; curvature {list(coeffs)!r} over "
                                    f"length {length!r} reaches {kmax:.3g}")
    elif bound > 1.0 / MIN_LENGTH:
        kmax = seg.max_abs_curvature()
        if kmax > 1.0 / MIN_LENGTH:
            raise FigureFormatError(f"{where}: a spiral's |curvature| must be at most {1.0 / MIN_LENGTH:g}, "
                                    f"got up to {kmax:.3g}")


def _apply_join(pose: Pose, direction: int, join: Join) -> tuple[Pose, int]:
    heading = pose.heading + join.pivot + (math.pi if join.reverse else 0.0)
    return Pose(pose.x, pose.y, heading), (-direction if join.reverse else direction)


def _segment_to_dict(seg: Segment | Spiral) -> dict[str, Any]:
    if isinstance(seg, Spiral):
        return {"type": "spiral", "curvature": [float(c) for c in seg.coefficients], "length": seg.length}
    if seg.curvature == 0.0:
        return {"type": "line", "length": seg.length}
    return {"type": "arc", "curvature": seg.curvature, "length": seg.length}


def _number(d: dict, key: str, where: str) -> float:
    value = d[key]
    if isinstance(value, int) and not isinstance(value, bool) and abs(value) > 1e300:
        raise FigureFormatError(f"{where}: {key!r} is too large, got {_show(value)}")
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise FigureFormatError(f"{where}: {key!r} must be a finite number, got {_show(value)}")
    return float(value)


def _spiral_from_dict(d: dict, where: str) -> Spiral:
    coeffs = d.get("curvature")
    if not (isinstance(coeffs, list) and 1 <= len(coeffs) <= 4):
        raise FigureFormatError(f"{where}: a spiral needs 'curvature', a list of 1 to 4 polynomial coefficients "
                                f"[c0, c1, c2, c3] of arc length from its start, got {_show(coeffs)}")
    values = [_number({"curvature": c}, "curvature", where) for c in coeffs]
    if "length" not in d:
        raise FigureFormatError(f"{where}: a spiral needs a 'length'")
    length = _number(d, "length", where)
    if not length > 0:
        raise FigureFormatError(f"{where}: length must be positive, got {_show(length)}")
    return Spiral(tuple(values + [0.0] * (4 - len(values))), length)


def _segment_from_dict(d: Any, where: str) -> Segment | Spiral:
    if not isinstance(d, dict) or "type" not in d:
        raise FigureFormatError(f"{where}: expected an object with 'type' ('arc', 'line' or 'spiral'), got {_show(d)}")
    kind = d["type"]
    if kind == "spiral":
        return _spiral_from_dict(d, where)
    if kind == "line":
        length = _number(d, "length", where) if "length" in d else None
        if length is None or length <= 0:
            raise FigureFormatError(f"{where}: a line needs a positive 'length', got {_show(d.get('length'))}")
        return Segment(0.0, length)
    if kind != "arc":
        raise FigureFormatError(f"{where}: piece type must be 'arc', 'line' or 'spiral', got {_show(kind)}")
    if "curvature" in d:
        k = _number(d, "curvature", where)
        if k == 0.0:
            raise FigureFormatError(f"{where}: an arc needs non-zero curvature; use a line")
        if "length" not in d:
            raise FigureFormatError(f"{where}: an arc given by curvature needs a 'length'")
        length = _number(d, "length", where)
    else:
        if "radius" not in d:
            raise FigureFormatError(f"{where}: an arc needs 'radius' (or 'curvature')")
        r = _number(d, "radius", where)
        if r <= 0:
            raise FigureFormatError(f"{where}: radius must be positive, got {_show(r)}; turn right with a negative sweep")
        if "sweep_deg" in d:
            sweep = math.radians(_number(d, "sweep_deg", where))
            if sweep == 0.0:
                raise FigureFormatError(f"{where}: sweep_deg must be non-zero")
            k, length = math.copysign(1.0 / r, sweep), r * abs(sweep)
        elif "length" in d:
            length = _number(d, "length", where)
            turn = d.get("turn", "left")
            if turn not in ("left", "right"):
                raise FigureFormatError(f"{where}: turn must be 'left' or 'right', got {_show(turn)}")
            k = 1.0 / r if turn == "left" else -1.0 / r
        else:
            raise FigureFormatError(f"{where}: an arc needs 'sweep_deg' or 'length'")
    if not length > 0:
        raise FigureFormatError(f"{where}: length must be positive, got {_show(length)}")
    return Segment(k, length)


def _join_from_dict(d: Any, where: str) -> Join:
    if not isinstance(d, dict) or d.get("type") not in ("smooth", "cusp"):
        raise FigureFormatError(f"{where}: a join is {{'type': 'smooth'}} or {{'type': 'cusp', ...}}, got {_show(d)}")
    if d["type"] == "smooth":
        if set(d) - {"type"}:
            raise FigureFormatError(f"{where}: a smooth join cannot pivot or reverse; use a cusp, got {_show(d)}")
        return SMOOTH
    pivot = math.radians(_number(d, "pivot_deg", where)) if "pivot_deg" in d else 0.0
    reverse = d.get("reverse", False)
    if not isinstance(reverse, bool):
        raise FigureFormatError(f"{where}: reverse must be true or false, got {_show(reverse)}")
    try:
        return Join("cusp", pivot, reverse)
    except FigureFormatError as exc:
        raise FigureFormatError(f"{where}: {exc}") from None


def figure_from_dict(data: Any) -> Figure:
    """Build a :class:`Figure` from its JSON form, with messages that name the faulty field."""
    if not isinstance(data, dict):
        raise FigureFormatError(f"a figure is a JSON object, got {type(data).__name__}")
    schema = data.get("schema", SCHEMA)
    if schema != SCHEMA:
        raise FigureFormatError(f"unsupported figure schema {_show(schema)}; expected {SCHEMA!r}")
    curves_in = data.get("curves")
    if not isinstance(curves_in, list) or not curves_in:
        raise FigureFormatError("a figure needs a non-empty list 'curves'")
    params = None
    if "params" in data:
        p = data["params"]
        if not isinstance(p, dict) or set(p) - {"M", "m", "I"}:
            raise FigureFormatError(f"'params' must be an object with keys M, m, I; got {_show(p)}")
        try:
            params = SleighParams(**p)
        except (TypeError, ValueError) as exc:
            raise FigureFormatError(f"'params': {exc}") from None
        except OverflowError:  # an integer too large for a float
            raise FigureFormatError(f"'params': M, m and I must lie between {PARAM_RANGE[0]:g} and "
                                    f"{PARAM_RANGE[1]:g}, got {_show(p)}") from None
        for key, value in params.to_dict().items():
            if not PARAM_RANGE[0] <= value <= PARAM_RANGE[1]:
                raise FigureFormatError(f"'params': {key} must lie between {PARAM_RANGE[0]:g} and {PARAM_RANGE[1]:g}, "
                                        f"got {value!r}")
    curves, total = [], 0
    for ci, c in enumerate(curves_in):
        where = f"curves[{ci}]"
        if not isinstance(c, dict):
            raise FigureFormatError(f"{where}: expected an object, got {_show(c)}")
        pieces_in = c.get("pieces")
        if not isinstance(pieces_in, list) or not pieces_in:
            raise FigureFormatError(f"{where}: needs a non-empty list 'pieces'")
        repeat = c.get("repeat", 1)
        if isinstance(repeat, bool) or not isinstance(repeat, int) or repeat < 1:
            raise FigureFormatError(f"{where}: repeat must be a whole number >= 1, got {_show(repeat)}")
        # the size limit is checked before any piece is read, so a huge list costs no time
        total += len(pieces_in) * repeat
        if total > MAX_PIECES:
            raise FigureFormatError(f"{where}: {_count_pieces(len(pieces_in), repeat)}, {total} in the figure so "
                                    f"far; at most {MAX_PIECES} pieces are allowed in a figure")
        pieces = tuple(_segment_from_dict(p, f"{where}.pieces[{i}]") for i, p in enumerate(pieces_in))
        joins_in = c.get("joins", [{"type": "cusp"}] * (len(pieces) - 1))
        if not isinstance(joins_in, list):
            raise FigureFormatError(f"{where}: 'joins' must be a list")
        if len(joins_in) != len(pieces) - 1:
            raise FigureFormatError(f"{where}: {len(pieces)} pieces need {len(pieces) - 1} joins, "
                                    f"got {len(joins_in)}")
        joins = tuple(_join_from_dict(j, f"{where}.joins[{i}]") for i, j in enumerate(joins_in))
        closing = _join_from_dict(c["closing_join"], f"{where}.closing_join") if "closing_join" in c else None
        if repeat > 1 and closing is None:
            closing = Join("cusp")
        start_in = c.get("start", {})
        if not isinstance(start_in, dict):
            raise FigureFormatError(f"{where}: 'start' must be an object with x, y, heading_deg")
        start = Pose(
            _number(start_in, "x", where) if "x" in start_in else 0.0,
            _number(start_in, "y", where) if "y" in start_in else 0.0,
            math.radians(_number(start_in, "heading_deg", where)) if "heading_deg" in start_in else 0.0,
        )
        curve = Curve(pieces, joins, repeat, closing, start, _text(c.get("name", f"curve{ci}")))
        if "centre" in c:
            cen = c["centre"]
            if not (isinstance(cen, list) and len(cen) == 2):
                raise FigureFormatError(f"{where}: 'centre' must be [x, y]")
            cxy = {"x": cen[0], "y": cen[1]}
            curve = curve.centred_at(_number(cxy, "x", f"{where}.centre"), _number(cxy, "y", f"{where}.centre"))
        curves.append(curve)
    return Figure(_text(data.get("name", "figure")), tuple(curves), params,
                  _text(data.get("description", "")), _text(data.get("provenance", "")))


def _text(value: Any) -> str:
    """A name or note as text that every output can write: a lone surrogate (JSON allows ``\\ud800``) as U+FFFD.

    Kept, it failed the first UTF-8 write after the result files were written (exit 2).
    """
    return str(value).encode("utf-16-le", "surrogatepass").decode("utf-16-le", "replace")


def load_figure(path: str | Path) -> Figure:
    """Read a figure from a JSON file."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8-sig")  # a byte-order mark is read as SVG and CSV files read it
    except OSError as exc:
        raise FigureFormatError(f"cannot read figure file {str(path)!r}: {exc.strerror}") from None
    except UnicodeDecodeError as exc:
        raise FigureFormatError(f"{path}: not a text file in UTF-8 (byte {exc.start}); a figure is JSON text") from None
    except ValueError:  # a NUL character in the name
        raise FigureFormatError(f"{_show(str(path))} is no file name (it holds a NUL character)") from None
    try:
        data = json.loads(text)
    except json.JSONDecodeError as exc:
        raise FigureFormatError(f"{path}: not valid JSON ({exc.msg} at line {exc.lineno}, column {exc.colno})") from None
    except RecursionError:
        raise FigureFormatError(f"{path}: JSON nested too deeply to be a figure") from None
    return figure_from_dict(data)
