"""Could a person make these controls?  The plausibility verdict beside the verification.

*Verified* means the controls are exact for the model: replayed through the full equations they
keep the blade on the figure.  *Feasible* means a skater could perform them.  The two are
independent, and skatetrace reports both.  This module measures, from the exported controls (the
rows of ``controls.csv``, so that what is reported is what a user gets), what a skater would have
to do, and compares it with limits of the human body:

- **reach**: the largest distance of the moving mass from the blade's contact point;
- **mass speed**: the largest speed of the mass relative to the body, ``|(a', b')|``;
- **mass acceleration** and **force**: the largest acceleration of the mass on the ice, and the
  force ``m |acc|`` that moves it (finite differences of its velocity on the ice, between jumps);
- **jump at a cusp**: how far the mass's position on the ice jumps where the sleigh stops and
  pivots (the paper's idealised impulse: the mass is teleported);
- **blade speed**: the fastest the blade moves, against the glide speed;
- **singular approach**: the closest the mass comes to the singular point ``(0, -kappa I / M)`` of
  the control law, where the control rates grow without bound.

The peak kinetic energy of the mass and the largest jump of its velocity at a smooth join (an
impulse) are reported beside them.

Limits (:class:`HumanLimits`)
-----------------------------
For a skater of height ``H`` and body mass ``W`` (SI units, :meth:`HumanLimits.for_skater`):

- reach ``0.5 H``: the moving mass stands for the arms, the free leg and the head (34 % of the
  body, :mod:`skatetrace.dynamics.presets`); with the skating leg under the trunk, even fully stretched
  limbs keep their common centre of mass within about half the height of the blade (Winter's
  segment lengths: leg 0.53 H, arm 0.44 H, and a segment's centre of mass lies at 0.43-0.57 of
  its length);
- mass speed ``7 m/s`` relative to the body: about the fastest swing of a whole leg's centre of
  mass in sprinting or kicking (foot speeds of 15-25 m/s; Lees & Nolan 1998), averaged with arms
  swung as in a jump, over the moving segments;
- force on the mass ``W g`` (one body weight; acceleration ``W g / m``, about 29 m/s² for the
  default skater): the body accelerates its own limbs through the shoulders and hips with forces
  of the order of its weight (peak ground reaction forces of jumps are 2-3 body weights for the
  whole body);
- jump at a cusp ``0.05 H``: a mass cannot be teleported; a short pivot tolerates a shift of a few
  centimetres;
- blade speed ``2 x`` the glide speed: a skater gliding at a steady speed does not double it within
  a figure;
- singular approach ``0.01 x`` the reach limit.

In model units (the paper's dimensionless ``M = 2, m = 1, I = 3``) there is no height, so
:meth:`HumanLimits.for_model` takes the paper's scale: its double flower (13.32 model units across)
skated at the scale of a school figure (a circle eight is two circles three heights across, six
heights in all) by the default skater (1.7 m, 60 kg), so one height is 2.22 model units, and one
model unit of speed is the school glide of 2 m/s.  It converts the limits above into model units
and says so in :attr:`HumanLimits.assumptions`, with how the paper's sleigh compares with a person
at that scale (its radius of gyration is about nine times a person's).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..dynamics.controls import ControlSchedule, distinct_steps
from ..dynamics.model import SleighParams, mass_energy, mass_velocity
from ..dynamics.presets import IMPULSE_TIME

__all__ = ["CHECK_TITLES", "PAPER_FIGURE_SIZE", "HumanLimits", "FeasibilityCheck", "Feasibility", "assess_feasibility", "exported_peaks"]

_G = 9.81  # m/s^2
#: The default skater of :func:`~skatetrace.dynamics.presets.skater_params`.
_HEIGHT, _BODY_MASS = 1.7, 60.0
#: Limits per unit of height, or absolute (SI), with the reasons in the module docstring.
_REACH_PER_HEIGHT = 0.5
_MASS_SPEED = 7.0  # m/s, relative to the body
_FORCE_PER_WEIGHT = 1.0
_JUMP_PER_HEIGHT = 0.05
_BLADE_SPEED_RATIO = 2.0
_SINGULAR_PER_REACH = 0.01
_SCHOOL_SPEED = 2.0  # m/s, the glide speed of the school figures
_FIGURE_HEIGHTS = 6.0  # a circle eight is about six skater heights across
#: Size (larger side) of the paper's double flower, in model units: the scale of the model units.
PAPER_FIGURE_SIZE = 13.32


def _positive(name: str, value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)) \
            or not math.isfinite(value) or value <= 0:
        raise ValueError(f"{name} must be a positive finite number, got {value!r}")
    return float(value)


@dataclass(frozen=True, slots=True, kw_only=True)
class HumanLimits:
    """What a skater's body can do, in the figure's units.

    Parameters
    ----------
    reach : float
        Largest distance of the moving mass from the blade's contact point (length).
    mass_speed : float
        Largest speed of the mass relative to the body (length / time).
    mass_acceleration : float
        Largest acceleration of the mass on the ice (length / time²); the force limit is
        ``m * mass_acceleration``.
    cusp_jump : float
        Largest jump of the mass's position on the ice at a cusp (length).
    blade_speed_ratio : float
        Largest blade speed as a multiple of the glide speed.
    singular_distance : float
        Closest allowed approach of the mass to the singular point of the control law (length).
    unit : {"m", "model"}
        Units of the limits: metres and seconds, or the paper's model units.
    assumptions : str
        Who the skater is and how the limits were set, for the reports.
    """

    reach: float
    mass_speed: float
    mass_acceleration: float
    cusp_jump: float
    blade_speed_ratio: float = _BLADE_SPEED_RATIO
    singular_distance: float
    unit: str = "m"
    assumptions: str = ""

    def __post_init__(self) -> None:
        for name in ("reach", "mass_speed", "mass_acceleration", "cusp_jump", "blade_speed_ratio",
                     "singular_distance"):
            _positive(name, getattr(self, name))
        if self.unit not in ("m", "model"):
            raise ValueError(f"unit must be 'm' or 'model', got {self.unit!r}")

    @classmethod
    def for_skater(cls, height: float = _HEIGHT, body_mass: float = _BODY_MASS,
                   moving_mass: float | None = None) -> "HumanLimits":
        """Limits of a skater ``height`` m tall weighing ``body_mass`` kg, in metres and seconds.

        ``moving_mass`` (kg) is the model's ``m``, which turns the force limit (one body weight)
        into an acceleration; default the :func:`~skatetrace.dynamics.presets.skater_params` share.

        Examples
        --------
        >>> lim = HumanLimits.for_skater(1.7)
        >>> round(lim.reach, 3), lim.mass_speed, round(lim.mass_acceleration, 1)
        (0.85, 7.0, 28.7)
        """
        from ..dynamics.presets import MOVING_FRACTION

        height, body_mass = _positive("height", height), _positive("body_mass", body_mass)
        m = MOVING_FRACTION * body_mass if moving_mass is None else _positive("moving_mass", moving_mass)
        reach = _REACH_PER_HEIGHT * height
        acc = _FORCE_PER_WEIGHT * body_mass * _G / m
        text = (f"a skater {height:g} m tall weighing {body_mass:g} kg, moving {m:.3g} kg (arms, free leg, head): "
                f"reach {_REACH_PER_HEIGHT:g} x height, mass speed {_MASS_SPEED:g} m/s relative to the body, force on "
                f"the mass {_FORCE_PER_WEIGHT:g} body weight, jump at a cusp {_JUMP_PER_HEIGHT:g} x height, blade "
                f"speed {_BLADE_SPEED_RATIO:g} x the glide speed")
        return cls(reach=reach, mass_speed=_MASS_SPEED, mass_acceleration=acc, cusp_jump=_JUMP_PER_HEIGHT * height,
                   singular_distance=_SINGULAR_PER_REACH * reach, unit="m", assumptions=text)

    @classmethod
    def for_model(cls, height: float | None = None, speed_unit: float = _SCHOOL_SPEED,
                  params: SleighParams | None = None) -> "HumanLimits":
        """Limits in the paper's model units, at the scale of the paper's figure.

        The model units have no physical size, so the paper's own figure sets it: the double
        flower (:data:`PAPER_FIGURE_SIZE` = 13.32 model units across) is taken to be skated at the
        scale of a school figure, six heights across (a circle eight is two circles three heights
        across), by the default skater (1.7 m, 60 kg): one height is ``height`` = 2.22 model units.
        One model unit of speed stands for ``speed_unit`` m/s (default 2 m/s, the school figures'
        glide; the paper glides at about 1). The SI limits of :meth:`for_skater` are converted with
        those scales. ``params`` adds to the assumptions how the sleigh compares with a person.

        Examples
        --------
        >>> lim = HumanLimits.for_model()
        >>> round(lim.reach, 2), round(lim.mass_speed, 2)   # model units
        (1.11, 3.5)
        """
        height = PAPER_FIGURE_SIZE / _FIGURE_HEIGHTS if height is None else _positive("height", height)
        speed_unit = _positive("speed_unit", speed_unit)
        si = cls.for_skater()
        metres = _HEIGHT / height  # metres per model length
        v = speed_unit  # (m/s) per model speed
        acc = v * v / metres  # (m/s^2) per model acceleration
        text = (f"model units at the paper's scale: its double flower ({PAPER_FIGURE_SIZE:g} across) skated as a "
                f"school figure, six heights across, so one height of a 1.7 m, 60 kg skater = {height:.3g} model "
                f"units ({metres:.3g} m per unit), and one unit of speed = {v:g} m/s; that skater's limits "
                f"converted: reach {si.reach / metres:.3g}, mass speed {si.mass_speed / v:.3g} relative to the body, "
                f"mass acceleration {si.mass_acceleration / acc:.3g} (force one body weight), jump at a cusp "
                f"{si.cusp_jump / metres:.3g}, blade speed {_BLADE_SPEED_RATIO:g} x the glide speed")
        if params is not None:
            from ..dynamics.presets import skater_params

            person = skater_params().length_scale / _HEIGHT  # radius of gyration per height
            ratio = params.length_scale / (height * person)
            text += (f"; the sleigh's radius of gyration sqrt(I/(M+m)) = {params.length_scale:.3g} is {ratio:.2g} x "
                     f"that of a person at this scale ({person:.3g} x height)")
        return cls(reach=si.reach / metres, mass_speed=si.mass_speed / v, mass_acceleration=si.mass_acceleration / acc,
                   cusp_jump=si.cusp_jump / metres, singular_distance=si.singular_distance / metres, unit="model",
                   assumptions=text)

    def to_dict(self) -> dict[str, Any]:
        return {"reach": self.reach, "mass_speed": self.mass_speed, "mass_acceleration": self.mass_acceleration,
                "cusp_jump": self.cusp_jump, "blade_speed_ratio": self.blade_speed_ratio,
                "singular_distance": self.singular_distance, "unit": self.unit, "assumptions": self.assumptions}


#: What each check measures, for tables.
CHECK_TITLES = {
    "reach": "reach: mass from the blade",
    "mass_speed": "mass speed relative to the body",
    "mass_acceleration": "mass acceleration on the ice",
    "cusp_jump": "jump of the mass on the ice at a cusp",
    "blade_speed": "blade speed",
    "singular_approach": "closest approach to the singular point",
}


@dataclass(frozen=True, slots=True, kw_only=True)
class FeasibilityCheck:
    """One measured quantity against its human limit; ``time`` and ``section`` say where it peaks.

    ``time`` is ``None`` where it is not known (the singular approach is the tracer's, per section).
    """

    name: str
    description: str  # with "{value}" where the number goes
    value: float
    limit: float
    unit: str
    passed: bool
    time: float | None = None
    section: int | None = None

    @property
    def ratio(self) -> float:
        """How many times the limit the value is (> 1: beyond it); for the singular approach, its inverse."""
        if self.name == "singular_approach":
            return self.limit / self.value if self.value > 0 else math.inf
        return self.value / self.limit

    def phrase(self) -> str:
        """A short sentence for a person: ``mass 32.6 m from the blade (limit 0.85 m)``."""
        u = f" {self.unit}" if self.unit else ""
        text = self.description.format(value=f"{self.value:.3g}{u}")
        return f"{text} (limit {'≥ ' if self.name == 'singular_approach' else ''}{self.limit:.3g}{u})"

    @property
    def title(self) -> str:
        """What the check measures, without its number (:data:`CHECK_TITLES`)."""
        return CHECK_TITLES.get(self.name, self.name.replace("_", " "))

    def to_dict(self) -> dict[str, Any]:
        """Plain data; a value that is not finite (nothing measured) is ``None``, as strict JSON wants."""
        return {"name": self.name, "title": self.title, "description": self.description,
                "ratio": _finite(self.ratio), "value": _finite(self.value), "limit": self.limit, "unit": self.unit, "passed": self.passed, "time": self.time, "section": self.section}


@dataclass(frozen=True, slots=True, kw_only=True)
class Feasibility:
    """The plausibility verdict: could a skater make these controls?

    ``success`` (``feasible``) is true when every check passes; ``message`` names the checks that
    fail, in the order of ``checks`` (reach, mass speed, acceleration, jump at a cusp, blade speed,
    singular approach), with their numbers.  ``info`` holds figures reported without a limit.
    """

    feasible: bool
    status: str
    message: str
    checks: tuple[FeasibilityCheck, ...]
    limits: HumanLimits
    info: dict[str, Any] = field(default_factory=dict)

    @property
    def success(self) -> bool:
        return self.feasible

    def verdict(self, verified: bool | None) -> str:
        """Both verdicts in one line, e.g. ``verified · not humanly feasible: mass 32.6 m from the blade``."""
        first = {True: "verified", False: "verification failed", None: "not verified"}[verified]
        if self.feasible:
            return f"{first} · humanly feasible"
        if not self.checks or self.status == "not assessed":
            return f"{first} · feasibility not assessed: {self.message}"
        return f"{first} · not humanly feasible: {self.failed()[0].phrase()}"

    def failed(self) -> list[FeasibilityCheck]:
        """The checks that fail, in the order of :attr:`checks` (reach first: the headline)."""
        return [c for c in self.checks if not c.passed]

    def to_dict(self) -> dict[str, Any]:
        return {"feasible": self.feasible, "status": self.status, "message": self.message,
                "checks": [c.to_dict() for c in self.checks], "limits": self.limits.to_dict(),
                "info": dict(self.info)}


def _finite(x: float) -> float | None:
    return float(x) if math.isfinite(x) else None


def _mass_on_ice(a, b, theta, x, y, xi1, xi2, adot, bdot):
    """Position and velocity of the moving mass on the ice (PHYSICS.md, Energies)."""
    c, s = np.cos(theta), np.sin(theta)
    u, w = mass_velocity(xi1, xi2, a, b, adot, bdot)  # in the body frame
    return x + a * c - b * s, y + a * s + b * c, u * c - w * s, u * s + w * c


def _argmax(values: np.ndarray) -> int | None:
    if values.size == 0 or not np.any(np.isfinite(values)):
        return None
    return int(np.nanargmax(values))


def exported_peaks(schedule: ControlSchedule, states: dict[str, np.ndarray], params: SleighParams,
                   n_sections: int) -> list[dict[str, float]]:
    """Per section, the peaks of the exported rows: largest ``|a|, |b|, |a'|, |b'|`` and mass energy.

    Returns one dict per section (empty for a section with no rows), with the keys of the
    tracer's metrics: ``max_abs_a, max_abs_b, peak_abs_adot, peak_abs_bdot, peak_mass_kinetic_energy``.
    """
    ke = mass_energy(params, states["xi1"], states["xi2"], schedule.a, schedule.b, schedule.adot, schedule.bdot)
    cols = {"max_abs_a": np.abs(schedule.a), "max_abs_b": np.abs(schedule.b), "peak_abs_adot": np.abs(schedule.adot),
            "peak_abs_bdot": np.abs(schedule.bdot), "peak_mass_kinetic_energy": ke}
    out: list[dict[str, float]] = [{} for _ in range(n_sections)]
    if schedule.t.size == 0:
        return out
    order = np.argsort(schedule.section, kind="stable")
    sec = schedule.section[order]
    bounds = np.flatnonzero(np.diff(sec)) + 1
    for idx in np.split(order, bounds):
        k = int(schedule.section[idx[0]])
        if 0 <= k < n_sections:
            out[k] = {name: float(np.max(v[idx])) for name, v in cols.items()}
    return out


def _effort(m: float, t: np.ndarray, acc: np.ndarray, cut: np.ndarray) -> float:
    """The integral of ``(m acc)^2`` over the rows, by the trapezoidal rule within each stretch between jumps."""
    total = 0.0
    for i0, i1 in zip(np.concatenate([[0], cut]), np.concatenate([cut, [t.size]])):
        f = (m * acc[i0:i1]) ** 2
        total += float(np.sum(0.5 * (f[1:] + f[:-1]) * np.diff(t[i0:i1])))
    return total


def assess_feasibility(trace, schedule: ControlSchedule, states: dict[str, np.ndarray],
                       limits: HumanLimits) -> Feasibility:
    """Measure what the exported controls ask of a skater and compare it with ``limits``.

    Parameters
    ----------
    trace : FigureTrace
        The traced figure (parameters, glide speed, the tracer's closest singular approach).
    schedule, states : ControlSchedule, dict
        The exported rows, as :func:`~skatetrace.verification.verify.schedule_from_trace` returns them (the
        content of ``controls.csv``).
    limits : HumanLimits
        In the figure's units.

    Returns
    -------
    Feasibility
    """
    params = trace.params
    t, sec = schedule.t, schedule.section
    a, b, adot, bdot = schedule.a, schedule.b, schedule.adot, schedule.bdot
    x, y, th, xi1, xi2 = (states[k] for k in ("x", "y", "theta", "xi1", "xi2"))
    X, Y, VX, VY = _mass_on_ice(a, b, th, x, y, xi1, xi2, adot, bdot)
    n = t.size
    L = "m" if limits.unit == "m" else "model units"
    V = "m/s" if limits.unit == "m" else "model units"
    A = "m/s²" if limits.unit == "m" else "model units"
    F = "N" if limits.unit == "m" else "model units"
    E = "J" if limits.unit == "m" else "model units"

    def at(i):
        return (None, None) if i is None else (float(t[i]), int(sec[i]))

    checks = []

    def add(name, description, values, limit, unit, *, smallest=False, scale=1.0):
        i = _argmax(-values if smallest else values)
        value = (float(values[i]) if i is not None else (math.inf if smallest else 0.0)) * scale
        passed = value >= limit if smallest else value <= limit
        checks.append(FeasibilityCheck(name=name, description=description, value=value, limit=limit * 1.0,
                                       unit=unit, passed=bool(passed), time=at(i)[0], section=at(i)[1]))

    add("reach", "mass {value} from the blade", np.hypot(a, b), limits.reach, L)
    add("mass_speed", "mass moves at {value} relative to the body", np.hypot(adot, bdot), limits.mass_speed, V)

    # Acceleration on the ice, by finite differences within each stretch between jumps (a repeated
    # time marks a jump of the rates at a smooth join, or of everything at a cusp). Two rows
    # closer than the times' round-off are such a jump too, sampled from both sides at times
    # apart by 4e-13 (the paragraph bracket's plan, at a piece's end: a difference quotient read
    # 1.8e13 m/s^2 there), and so is a change of section.
    acc = np.zeros(n)
    cut = np.flatnonzero(~distinct_steps(t) | (np.diff(sec) != 0)) + 1
    for i0, i1 in zip(np.concatenate([[0], cut]), np.concatenate([cut, [n]])):
        if i1 - i0 >= 3:
            tt = t[i0:i1]
            acc[i0:i1] = np.hypot(np.gradient(VX[i0:i1], tt, edge_order=2), np.gradient(VY[i0:i1], tt, edge_order=2))
    add("mass_acceleration", "mass accelerates at {value} on the ice", acc, limits.mass_acceleration, A)

    # Jumps at repeated times: of the mass's position at a cusp (same curve: the blade is where it
    # was), of its velocity at a smooth join.
    size = max(float(np.ptp(x)) if n else 0.0, float(np.ptp(y)) if n else 0.0, 1e-300)
    jumps = np.zeros(n)
    dv = np.zeros(n)
    dv_cusp = np.zeros(n)
    cusp_speed = 0.0
    curve_of = np.array([s.curve_index for s in trace.sections], dtype=int)
    for i in cut:
        j = i - 1
        same_place = math.hypot(x[i] - x[j], y[i] - y[j]) <= 1e-6 * size
        if sec[i] != sec[j]:
            if same_place and curve_of[sec[i]] == curve_of[sec[j]]:
                jumps[i] = math.hypot(X[i] - X[j], Y[i] - Y[j])
                dv_cusp[i] = math.hypot(VX[i] - VX[j], VY[i] - VY[j])
                cusp_speed = max(cusp_speed, math.hypot(adot[i], bdot[i]), math.hypot(adot[j], bdot[j]))
        else:
            dv[i] = math.hypot(VX[i] - VX[j], VY[i] - VY[j])
    add("cusp_jump", "mass jumps {value} on the ice at a cusp", jumps, limits.cusp_jump, L)

    glide = float(trace.options.speed)
    add("blade_speed", "blade runs at {value}", np.abs(xi2) / glide, limits.blade_speed_ratio, "x the glide speed")

    singular = np.array([s.metrics.get("min_singular_distance", math.inf) for s in trace.sections] or [math.inf])
    k = int(np.argmin(singular))
    value = float(singular[k])
    checks.append(FeasibilityCheck(
        name="singular_approach", description="mass passes {value} from the singular point", value=value,
        limit=limits.singular_distance, unit=L, passed=bool(value >= limits.singular_distance),
        time=None, section=k if trace.sections and math.isfinite(value) else None))  # the tracer keeps no time

    ke = mass_energy(params, xi1, xi2, a, b, adot, bdot)
    info = {"peak_mass_kinetic_energy": float(np.max(ke)) if n else 0.0, "energy_unit": E,
            "peak_force_on_mass": float(params.m * np.max(acc)) if n else 0.0,
            "force_limit": float(params.m * limits.mass_acceleration), "force_unit": F,
            "max_mass_velocity_jump_at_join": float(np.max(dv)) if n else 0.0, "glide_speed": glide,
            # at the cusps: the jump of the mass's velocity on the ice as an impulse (momentum), and
            # the mass's speed relative to the stopped blade (it carries the angular momentum there)
            "max_cusp_impulse": float(params.m * np.max(dv_cusp)) if n else 0.0,
            "max_cusp_mass_speed": float(cusp_speed), "impulse_unit": "N s" if limits.unit == "m" else "model units",
            # the least-effort planner's objective, measured on the rows: the integral of |m acc|^2,
            # and the impulses at the cusps as the effort of delivering each within IMPULSE_TIME
            "effort": _effort(params.m, t, acc, cut),
            "cusp_effort": float(np.sum((params.m * dv_cusp) ** 2) / IMPULSE_TIME) if n else 0.0,
            "rows": n}
    failed = [c for c in checks if not c.passed]
    if n == 0:
        # nothing measured, nothing passed: a check of no motion against a limit would read "ok"
        return Feasibility(feasible=False, status="not assessed", message="no controls to assess (nothing was traced)",
                           checks=(), limits=limits, info=info)
    if not failed:
        return Feasibility(feasible=True, status="feasible", message="every check within human limits",
                           checks=tuple(checks), limits=limits, info=info)
    message = "not humanly feasible: " + "; ".join(c.phrase() for c in failed)
    return Feasibility(feasible=False, status="not feasible", message=message, checks=tuple(checks), limits=limits,
                       info=info)
