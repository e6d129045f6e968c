"""The classical compulsory ("school") figures, built exactly from circular arcs.

What the geometry is based on
-----------------------------
The general description of the compulsory figures, as summarised for instance in the English
Wikipedia's "Compulsory figures" article (section on terminology; the ISU's rule book itself was not
consulted):

- every figure is made of two or three circles (*lobes*) touching on one line, the *long axis*;
  circles are about three times the skater's height across, except for the *loop* figures, whose
  circles are about one height across with a teardrop loop about a blade length wide (here one blade
  wide and one and a half long);
- a three or a bracket sits halfway round its circle, on the long axis; a double three puts two
  threes that divide the circle into thirds; rockers and counters are turns where two circles touch,
  leading onto the other circle;
- the serpentine and the *change* figures are three-lobed: on each foot half the middle circle, a
  change of edge where the circles touch, and a full end circle (with the turns, for a change
  figure); the *paragraph* figures (and the one-foot eight) are two-lobed, both circles on one foot
  with a change of edge at the centre; the other foot then repeats the figure over the same tracing.

Official figure numbers are not used: the names are the usual English ones (:func:`school_names`).
The shapes of the turns (small arcs, below) and the start points are this module's own choices.

Conventions
-----------
- Lengths in metres. The long axis is the x axis. Two-lobed figures are centred where the circles
  touch (the origin) and start there; three-lobed figures are centred on the middle circle and start
  where it touches the left circle, ``(-R, 0)``.
- One :class:`~skatetrace.figures.figure.Curve` per figure, from the start back to it (closed). Every change
  of foot is a rest point, a cusp join with no pivot and no reversal (the skater steps from foot to
  foot at rest without turning). The figure starts and ends at rest at the start point.
- Turns are rest points where the blade reverses (``Join("cusp", 0, reverse=True)``). Each is drawn
  with small arcs of radius ``turn_radius`` (:data:`TURN_RADIUS`, half a blade, by default) tangent
  to the circles, so the tracing has a genuine cusp whose tangent lies along the radius: on the long
  axis for every turn but the double three's. A three's cusp points into its
  circle, a bracket's out of it; a rocker's cusp points into the circle it leaves, a counter's into
  the circle it leads onto.
- A loop is no rest point: three arcs (a transition arc, half a circle of radius ``blade / 2`` and a
  transition arc, all turning the same way as the circle) joined smoothly, crossing themselves on
  the long axis; the loop is one blade wide and one and a half blades long.
- A change of edge is an inflection: two arcs of opposite curvature joined smoothly.

Variants
--------
The path depends on the variant only through the sense in which the first circle is travelled:
clockwise for a right forward outside (RFO) start. A left foot, an inside edge and a backward start
each reverse it, and the reversed figure is the mirror image in the long axis (``y -> -y``). So
"left, inside" gives the same path as "right, outside". A backward start also makes the blade run
backwards, which a :class:`Curve` cannot express (its blade starts forwards): the pieces describe the
path of travel and ``figure.extra["school"]["start_direction"] == -1`` records the blade's direction.
The model is symmetric under ``(a, b, p2, xi2) -> -(a, b, p2, xi2)`` (PHYSICS.md; tracing.sections uses it
for every backward section), so the controls are those of the path skated forwards with the mass
mirrored through the contact point. The edges actually skated are in ``extra["school"]["sequence"]``.

Rest points and inflections per section (a section runs from rest to rest): every section has at
most one inflection except in the change bracket (two: the change of edge and the bracket's entry)
and the paragraph bracket (three: out of a bracket, the change of edge, into the next bracket); an
inflection is unavoidable where a bracket's cusp must point out of its circle.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

from ..dynamics.model import SleighParams
from ..errors import FigureFormatError
from .figure import SMOOTH, Curve, Figure, Join
from .geometry import Pose, Segment

__all__ = ["BLADE", "TURN_RADIUS", "DIRECTIONS", "EDGES", "FEET", "school_figure", "school_names"]

BLADE = 0.28
"""Default blade length in metres."""

TURN_RADIUS = 0.5
"""Default radius of a turn's arcs, in blade lengths (0.14 m for a 0.28 m blade)."""

EDGES = ("outside", "inside")
DIRECTIONS = ("forward", "backward")
FEET = ("right", "left")

_REVERSE = Join("cusp", 0.0, True)
_STEP = Join("cusp", 0.0, False)  # change of foot at rest

_SOURCE = ("General description of the compulsory figures (e.g. English Wikipedia, 'Compulsory figures', "
           "terminology): circles about 3 heights across (loops: about 1 height, loop about a blade wide), "
           "turns on the long axis, double threes dividing the circle into thirds; turn shapes (small arcs) "
           "are skatetrace's own choice")


# --------------------------------------------------------------------------------------------------
# Turns: small arcs that replace part of a circle
# --------------------------------------------------------------------------------------------------
@dataclass(frozen=True, slots=True)
class _Turn:
    """A turn or loop on a circle of radius ``R``, as arcs relative to the circle's sense.

    ``pieces`` are ``(curvature, sweep)`` with the curvature's sign relative to the circle's sense
    (positive: turning the same way); ``joins`` go between them. The turn replaces ``eat_in``
    radians of the circle before its point and ``eat_out`` radians of the circle after it (of the
    next circle if ``changes_circle``).
    """

    name: str
    pieces: tuple[tuple[float, float], ...]
    joins: tuple[Join, ...]
    eat_in: float
    eat_out: float
    reverses: bool = True
    changes_circle: bool = False


def _three_turn(R: float, rho: float) -> _Turn:
    """Cusp pointing to the centre: two arcs of radius ``rho`` inside the circle, tangent to it.

    The arc's centre lies ``R - rho`` from the circle's centre and ``rho`` from the radius through
    the cusp, so the tangent point is ``asin(rho / (R - rho))`` before the cusp's radius; the arc
    turns from the circle's tangent to the radius (a quarter turn more).
    """
    th = math.asin(rho / (R - rho))
    return _Turn("three", ((1.0 / rho, th + math.pi / 2), (1.0 / rho, th + math.pi / 2)), (_REVERSE,), th, th)


def _bracket_turn(R: float, rho: float) -> _Turn:
    """Cusp pointing away from the centre: two counter-curved arcs outside the circle, tangent to it."""
    th = math.asin(rho / (R + rho))
    return _Turn("bracket", ((-1.0 / rho, math.pi / 2 - th), (-1.0 / rho, math.pi / 2 - th)), (_REVERSE,), th, th)


def _rocker_turn(R: float, rho: float) -> _Turn:
    """Cusp where two circles touch, pointing into the circle left; the exit arc curves the same way.

    Entry arc (radius ``rho``) inside the first circle with the cusp at ``c = sqrt(R^2 - 2 R rho)``
    from its centre; exit arc (radius ``rho_out``) outside the second circle, tangent to it:
    ``(2R - c)^2 + rho_out^2 = (R + rho_out)^2``.
    """
    c = math.sqrt(R * R - 2.0 * R * rho)
    th = math.atan2(rho, c)
    rho_out = ((2.0 * R - c) ** 2 - R * R) / (2.0 * R)
    a = math.atan2(rho_out, 2.0 * R - c)
    return _Turn("rocker", ((1.0 / rho, th + math.pi / 2), (1.0 / rho_out, math.pi / 2 - a)), (_REVERSE,), th, a,
                 changes_circle=True)


def _counter_turn(R: float, rho: float) -> _Turn:
    """Cusp where two circles touch, pointing into the circle entered; both arcs counter-curved.

    Entry arc outside the first circle, cusp at ``c = sqrt(R^2 + 2 R rho)``; exit arc inside the
    second circle: ``(2R - c)^2 + rho_out^2 = (R - rho_out)^2``.
    """
    c = math.sqrt(R * R + 2.0 * R * rho)
    th = math.atan2(rho, c)
    rho_out = (R * R - (2.0 * R - c) ** 2) / (2.0 * R)
    a = math.atan2(rho_out, 2.0 * R - c)
    return _Turn("counter", ((-1.0 / rho, math.pi / 2 - th), (-1.0 / rho_out, math.pi / 2 + a)), (_REVERSE,), th, a,
                 changes_circle=True)


def _loop_turn(R: float, width: float, length: float) -> _Turn:
    """A teardrop loop inside the circle, symmetric about the radius, ``width`` by ``length``.

    Half a circle of radius ``rho = width / 2`` (centre on the radius, ``d`` from the circle's
    centre) between two transition arcs of radius ``rt``, each tangent inside the circle and outside
    the half circle's ends. The transition arcs cross on the radius at ``rho + sqrt(2 rho rt - rho^2)``
    from the loop's inner end, which is ``length`` when ``rt = ((length - rho)^2 + rho^2) / (2 rho)``;
    tangency gives ``d^2 = (R - rho)(R + rho - 2 rt)``.
    """
    rho = 0.5 * width
    rt = ((length - rho) ** 2 + rho * rho) / (2.0 * rho)
    d2 = (R - rho) * (R + rho - 2.0 * rt)
    if not (d2 > rho * rho):
        raise FigureFormatError(
            f"a loop {width:.3g} m wide and {length:.3g} m long does not fit in a circle of radius {R:.3g} m; "
            "use a taller skater or a shorter blade")
    bh = math.atan2(rt - rho, math.sqrt(d2))
    g = math.pi / 2 + bh
    return _Turn("loop", ((1.0 / rt, g), (1.0 / rho, math.pi), (1.0 / rt, g)), (SMOOTH, SMOOTH), bh, bh,
                 reverses=False)


# --------------------------------------------------------------------------------------------------
# The path builder
# --------------------------------------------------------------------------------------------------
class _Path:
    """Pieces and joins of one figure, with the skater's foot, blade direction and edge.

    ``sense`` is the way the current circle is travelled (+1 left, -1 right); ``direction`` the
    blade's (+1 forwards).
    """

    def __init__(self, sense: int, direction: int, foot: str) -> None:
        self.pieces: list[Segment] = []
        self.joins: list[Join] = []
        self.pending: Join | None = None
        self.sense, self.direction, self.foot = sense, direction, foot
        self.words = [self.edge()]

    def edge(self) -> str:
        """Edge code, e.g. ``RFO``: a right forward edge turning right (clockwise) is an outside edge."""
        outside = (self.sense < 0) ^ (self.foot == "L") ^ (self.direction < 0)
        return self.foot + ("F" if self.direction > 0 else "B") + ("O" if outside else "I")

    def add(self, curvature: float, sweep: float) -> None:
        if not sweep > 1e-9:
            raise FigureFormatError(f"turns too large for their circle (an arc would sweep {sweep:.3g} rad); "
                                    "use a smaller turn_radius or blade")
        if self.pieces:
            self.joins.append(self.pending or SMOOTH)
        self.pieces.append(Segment(curvature, sweep / abs(curvature)))
        self.pending = None

    def circle(self, R: float, sweep: float, turns=(), eat_start: float = 0.0, eat_end: float = 0.0) -> None:
        """``sweep`` radians of a circle of radius ``R``, with ``(angle, turn)`` at swept angles."""
        at = eat_start
        for phi, turn in turns:
            self.add(self.sense / R, phi - turn.eat_in - at)
            self.turn(turn)
            at = phi + turn.eat_out
        self.add(self.sense / R, sweep - eat_end - at)

    def turn(self, turn: _Turn) -> None:
        for i, (k, sweep) in enumerate(turn.pieces):
            if i:
                self.pending = turn.joins[i - 1]
            self.add(self.sense * k, sweep)
        before = self.edge()
        self.direction = -self.direction if turn.reverses else self.direction
        self.sense = -self.sense if turn.changes_circle else self.sense
        self.words += [turn.name] + ([self.edge()] if self.edge() != before else [])

    def change_edge(self) -> None:
        self.sense = -self.sense
        self.pending = SMOOTH
        self.words += ["change", self.edge()]

    def change_foot(self, new_circle: bool) -> None:
        self.pending = _STEP
        self.foot = "L" if self.foot == "R" else "R"
        if new_circle:
            self.sense = -self.sense
        self.words += ["|", self.edge()]


@dataclass(frozen=True, slots=True)
class _Sizes:
    height: float
    blade: float
    turn_radius: float

    @property
    def big(self) -> float:
        """Radius of the circles of the eight-type figures: diameter three heights."""
        return 1.5 * self.height

    @property
    def small(self) -> float:
        """Radius of the loop figures' circles: diameter one height."""
        return 0.5 * self.height

    def three(self, R: float) -> _Turn:
        return _three_turn(R, self.turn_radius)

    def bracket(self, R: float) -> _Turn:
        return _bracket_turn(R, self.turn_radius)

    def loop(self, R: float) -> _Turn:
        return _loop_turn(R, self.blade, 1.5 * self.blade)


def _two_lobes(p: _Path, R: float, turns=()) -> None:
    """An eight: one circle per foot, the second the mirror image of the first in the transverse axis."""
    p.circle(R, 2 * math.pi, turns)
    p.change_foot(new_circle=True)
    p.circle(R, 2 * math.pi, turns)


def _three_lobes(p: _Path, R: float, turns=(), connector: _Turn | None = None) -> None:
    """Per foot: half the middle circle, a change of edge (or ``connector`` turn), a full end circle.

    The second foot's half is the first's turned half a turn about the figure's centre.
    """
    for foot in range(2):
        if foot:
            p.change_foot(new_circle=True)
        if connector is None:
            p.circle(R, math.pi)
            p.change_edge()
            p.circle(R, 2 * math.pi, turns)
        else:
            p.circle(R, math.pi, eat_end=connector.eat_in)
            p.turn(connector)
            p.circle(R, 2 * math.pi, turns, eat_start=connector.eat_out)


def _one_foot(p: _Path, R: float, turns=()) -> None:
    """Per foot: a circle, a change of edge at the centre, the other circle; the second foot retraces."""
    for foot in range(2):
        if foot:
            p.change_foot(new_circle=False)
        p.circle(R, 2 * math.pi, turns)
        p.change_edge()
        p.circle(R, 2 * math.pi, turns)


def _halfway(turn: _Turn) -> list:
    return [(math.pi, turn)]


def _thirds(turn: _Turn) -> list:
    return [(2 * math.pi / 3, turn), (4 * math.pi / 3, turn)]


# --------------------------------------------------------------------------------------------------
# The figures
# --------------------------------------------------------------------------------------------------
def _circle_eight(p: _Path, s: _Sizes) -> None:
    """Circle eight: two circles about three heights across, one on each foot, the same edge."""
    _two_lobes(p, s.big)


def _serpentine(p: _Path, s: _Sizes) -> None:
    """Serpentine: three circles; per foot half the middle one, a change of edge, a full end circle."""
    _three_lobes(p, s.big)


def _three(p: _Path, s: _Sizes) -> None:
    """Three: a circle eight with a three turn halfway round each circle, on the long axis."""
    _two_lobes(p, s.big, _halfway(s.three(s.big)))


def _double_three(p: _Path, s: _Sizes) -> None:
    """Double three: a circle eight with two three turns per circle dividing it into thirds.

    The two cusps of a circle are mirror images in the long axis, at 120 and 240 degrees from the
    centre, so they are not on the long axis.
    """
    _two_lobes(p, s.big, _thirds(s.three(s.big)))


def _loop(p: _Path, s: _Sizes) -> None:
    """Loop: two circles about one height across, each with a loop halfway round, on the long axis."""
    _two_lobes(p, s.small, _halfway(s.loop(s.small)))


def _bracket(p: _Path, s: _Sizes) -> None:
    """Bracket: a circle eight with a bracket halfway round each circle, on the long axis."""
    _two_lobes(p, s.big, _halfway(s.bracket(s.big)))


def _rocker(p: _Path, s: _Sizes) -> None:
    """Rocker: three circles; per foot half the middle one, a rocker onto the end circle, a full circle."""
    _three_lobes(p, s.big, connector=_rocker_turn(s.big, s.turn_radius))


def _counter(p: _Path, s: _Sizes) -> None:
    """Counter: three circles; per foot half the middle one, a counter onto the end circle, a full circle."""
    _three_lobes(p, s.big, connector=_counter_turn(s.big, s.turn_radius))


def _one_foot_eight(p: _Path, s: _Sizes) -> None:
    """One-foot eight: both circles on one foot with a change of edge at the centre, then the other foot."""
    _one_foot(p, s.big)


def _change_three(p: _Path, s: _Sizes) -> None:
    """Change three: a serpentine whose end circles have a three turn halfway round, on the long axis."""
    _three_lobes(p, s.big, _halfway(s.three(s.big)))


def _change_double_three(p: _Path, s: _Sizes) -> None:
    """Change double three: a serpentine whose end circles have two threes dividing them into thirds."""
    _three_lobes(p, s.big, _thirds(s.three(s.big)))


def _change_loop(p: _Path, s: _Sizes) -> None:
    """Change loop: a serpentine on circles one height across, a loop halfway round each end circle."""
    _three_lobes(p, s.small, _halfway(s.loop(s.small)))


def _change_bracket(p: _Path, s: _Sizes) -> None:
    """Change bracket: a serpentine whose end circles have a bracket halfway round, on the long axis."""
    _three_lobes(p, s.big, _halfway(s.bracket(s.big)))


def _paragraph_three(p: _Path, s: _Sizes) -> None:
    """Paragraph three: a one-foot eight with a three turn halfway round each circle."""
    _one_foot(p, s.big, _halfway(s.three(s.big)))


def _paragraph_double_three(p: _Path, s: _Sizes) -> None:
    """Paragraph double three: a one-foot eight with two threes per circle dividing it into thirds."""
    _one_foot(p, s.big, _thirds(s.three(s.big)))


def _paragraph_loop(p: _Path, s: _Sizes) -> None:
    """Paragraph loop: a one-foot eight on circles one height across with a loop halfway round each."""
    _one_foot(p, s.small, _halfway(s.loop(s.small)))


def _paragraph_bracket(p: _Path, s: _Sizes) -> None:
    """Paragraph bracket: a one-foot eight with a bracket halfway round each circle."""
    _one_foot(p, s.big, _halfway(s.bracket(s.big)))


_FIGURES: dict[str, tuple[Callable[[_Path, _Sizes], None], int, bool]] = {
    # name: (builder, number of lobes, on the small circles of the loop figures)
    "circle-eight": (_circle_eight, 2, False),
    "serpentine": (_serpentine, 3, False),
    "three": (_three, 2, False),
    "double-three": (_double_three, 2, False),
    "loop": (_loop, 2, True),
    "bracket": (_bracket, 2, False),
    "rocker": (_rocker, 3, False),
    "counter": (_counter, 3, False),
    "one-foot-eight": (_one_foot_eight, 2, False),
    "change-three": (_change_three, 3, False),
    "change-double-three": (_change_double_three, 3, False),
    "change-loop": (_change_loop, 3, True),
    "change-bracket": (_change_bracket, 3, False),
    "paragraph-three": (_paragraph_three, 2, False),
    "paragraph-double-three": (_paragraph_double_three, 2, False),
    "paragraph-loop": (_paragraph_loop, 2, True),
    "paragraph-bracket": (_paragraph_bracket, 2, False),
}


def school_names() -> list[str]:
    """Names of the school figures, simplest first (the usual order of the classical schedule).

    >>> school_names()[:4]
    ['circle-eight', 'serpentine', 'three', 'double-three']
    """
    return list(_FIGURES)


def _choice(value, valid: tuple[str, ...], what: str) -> str:
    key = value.strip().lower() if isinstance(value, str) else value
    if key not in valid:
        raise FigureFormatError(f"unknown {what} {value!r}; valid {what}s are {', '.join(valid)}")
    return key


def _length(value, what: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not (0 < value <= 1e300 and math.isfinite(value)):
        raise FigureFormatError(f"{what} must be a positive length in metres, got {value!r}")
    if not _LENGTH_RANGE[0] <= value <= _LENGTH_RANGE[1]:
        raise FigureFormatError(f"{what} must lie between {_LENGTH_RANGE[0]:g} and {_LENGTH_RANGE[1]:g} m, got {value!r}")
    return float(value)


#: Heights, blades and turn radii accepted (metres): far outside, the figure's pieces would leave
#: the limits of :mod:`skatetrace.figures.figure` and the message would name a piece instead of the cause.
_LENGTH_RANGE = (1e-3, 1e3)


def school_figure(name: str, *, height: float = 1.7, blade: float = BLADE, edge: str = "outside",
                  direction: str = "forward", foot: str = "right", turn_radius: float | None = None,
                  params: SleighParams | None = None) -> Figure:
    """A school figure sized for a skater, built exactly from arcs (see the module docstring).

    Parameters
    ----------
    name : str
        One of :func:`school_names` (case, spaces and underscores are forgiven: ``"Circle eight"``).
    height : float
        Skater's height in m: circles are ``3 * height`` across (``height`` for loop figures).
    blade : float
        Blade length in m (default 0.28): a loop is ``blade`` wide and ``1.5 * blade`` long.
    edge, direction, foot : str
        The first edge skated: ``"outside"``/``"inside"``, ``"forward"``/``"backward"``,
        ``"right"``/``"left"``. Each of inside, backward and left mirrors the path in the long axis;
        backward also starts the blade backwards (recorded in ``extra``, see the module docstring).
    turn_radius : float, optional
        Radius in m of the small arcs that draw a turn's cusp; default ``TURN_RADIUS * blade``
        (0.14 m for a 0.28 m blade).
    params : SleighParams, optional
        Stored with the figure; default :func:`skatetrace.dynamics.presets.skater_params` for ``height``
        (SI units, matching the figure's metres).

    Returns
    -------
    Figure
        One closed curve starting at rest at the start point. ``extra["school"]`` holds the
        variant, the circle radius ``radius``, ``start_direction`` and the skated ``sequence``.

    Raises
    ------
    FigureFormatError
        For an unknown name or variant (the message lists the valid ones) or sizes that do not fit.

    Examples
    --------
    >>> fig = school_figure("three", height=1.7)
    >>> fig.name, fig.extra["school"]["sequence"]
    ('three-RFO', 'RFO three RBI | LBI three LFO')
    >>> fig.curves[0].closure()["closed"]
    True
    >>> school_figure("three", edge="inside").extra["school"]["sequence"]
    'RFI three RBO | LBO three LFI'
    """
    key = name.strip().lower().replace(" ", "-").replace("_", "-") if isinstance(name, str) else name
    if not isinstance(key, str) or key not in _FIGURES:
        raise FigureFormatError(f"unknown school figure {name!r}; valid names are {', '.join(_FIGURES)}")
    edge = _choice(edge, EDGES, "edge")
    direction = _choice(direction, DIRECTIONS, "direction")
    foot = _choice(foot, FEET, "foot")
    height = _length(height, "height")
    blade = _length(blade, "blade")
    turn_radius = TURN_RADIUS * blade if turn_radius is None else _length(turn_radius, "turn_radius")
    sizes = _Sizes(height, blade, turn_radius)
    build, lobes, loops = _FIGURES[key]
    R = sizes.small if loops else sizes.big
    if not loops and not turn_radius < R / 3:
        raise FigureFormatError(f"turn_radius {turn_radius:.3g} m is too large for circles of radius "
                                f"{R:.3g} m; keep it below a third of the radius")

    backward, left, inside = direction == "backward", foot == "left", edge == "inside"
    sense = 1 if (backward ^ left ^ inside) else -1  # -1: the first circle is travelled clockwise
    path = _Path(sense, -1 if backward else 1, "L" if left else "R")
    build(path, sizes)
    start = Pose(0.0 if lobes == 2 else -R, 0.0, -sense * math.pi / 2)
    code = path.words[0]
    curve = Curve(tuple(path.pieces), tuple(path.joins), start=start, name=f"{key}-{code}")
    sequence = " ".join(path.words)
    note = ""
    if backward:
        note = (" The blade runs backwards from the start; the curve's pieces are the path of travel "
                "(extra['school']['start_direction'] = -1).")
    if params is None:
        from ..dynamics.presets import skater_params

        params = skater_params(height=height)
    doc = (build.__doc__ or "").split("\n\n")[0].strip()
    return Figure(
        f"{key}-{code}", (curve,), params,
        f"{doc} Skated {sequence}; circles {2 * R:.3g} m across (skater {height:g} m, blade {blade:g} m).{note}",
        _SOURCE,
        extra={"school": {"name": key, "height": height, "blade": blade, "turn_radius": turn_radius,
                          "radius": R, "lobes": lobes, "edge": edge, "direction": direction, "foot": foot,
                          "start_direction": -1 if backward else 1, "sequence": sequence}},
    )
