"""The options of the exact tracer (:class:`TraceOptions`), checked when they are made."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["BRIEF_PLACEMENTS", "LONG_SECTION", "SHORT_SECTION", "SPEED_RANGE", "TraceOptions"]

#: Accepted glide speeds (model length per time unit, or m/s).
SPEED_RANGE = (1e-6, 1e6)

# With TraceOptions.split_on_failure: where a section is given up to be split rather than searched
# on. Logged over 136 drawings and figures traced with the launch-glide-stop manoeuvres (the SVG
# corpus, 59 icons of nine sets, the 17 school figures, 6 generated curves; 1,977 sections,
# 2026-11-28): of the 518 sections of more than four pieces, 13 were searched again with the
# stops' fallbacks, which traced two (of 5 and 7 pieces; split instead, both drawings verify) and
# spent 61 s failing on the others (2.3 to 4 s on a section of 7 pieces, 8 to 12.6 s on one of
# 108 to 214). The 9 sections they traced in the school figures have two pieces, and are searched
# as before. Of the 43 sections of more than 32 pieces, two needed more than 64 placements (132
# on a section of 141 pieces, 196 on one of 100); one of 214 tried all 256 in 14 s and failed.
#: The most pieces of a section searched with the stops' full-accuracy fallbacks where the caller splits it.
SHORT_SECTION = 4
#: Sections of more pieces than this are searched briefly where the caller splits them ...
LONG_SECTION = 32
#: ... trying at most this many glide placements before one works.
BRIEF_PLACEMENTS = 64


@dataclass(frozen=True, slots=True, kw_only=True)
class TraceOptions:
    """Options of the exact tracer.

    Parameters
    ----------
    speed : float
        Glide speed along the blade (model length per time unit). Time scaling is a symmetry of
        the model, so this changes durations and rates, never the path of the mass.
    maneuver_length : float or None
        Arc length given to the launch and to the stop inside the glide segment. ``None`` chooses
        ``min(L/2, radius)`` on an arc and ``min(L/2, sqrt(I/(M+m)))`` on a line.
    glide_lateral : float or None
        Lateral position ``b`` of the mass while gliding on an arc. ``None`` (default) tries
        ``b = 0`` first, then positions on the side of the neighbouring curvature's singular point
        from which the jump of the control rates at a smooth join speeds the sleigh up rather than
        braking it (see :func:`trace_section`).
    residual_tol : float
        Largest accepted boundary-condition residual.
    singular_limit : float
        Closest allowed approach to the singular point, in units of ``sqrt(I/(M+m))``.
    excursion_limit : float
        Largest accepted distance of the mass from the contact point, in units of
        ``max(sqrt(I/(M+m)), section length)``. Beyond it a solution is numerically meaningless.
    rtol, atol : float
        Integration tolerances of the manoeuvres.
    placement : {"least-reach", "first"}
        Which of the glide placements that trace the section to keep: the one whose mass stays
        closest to the blade (default) or the first that works. Either is chosen among the
        placements whose stops need no full-accuracy fallback, where one works (see
        :func:`trace_section`).
    search : int
        With ``"least-reach"``: how many more placements to try after the first that works (in
        the order of :func:`trace_section`). Sections of a few pieces have fewer placements than
        this and are searched completely; a fitted drawing's long section is not.
    max_placements : int
        The most placements tried in a section before it is given up (none of them having
        worked). Of 700 sections of the SVG corpus and the school figures the latest first success
        came at placement 132 (a section of 141 pieces), and of 1,977 logged with unseen icons and
        generated curves at placement 196 (100 pieces of a handwritten curve); a section of
        hundreds of pieces (a zigzag read as one smooth curve) has thousands of placements, which
        all fail there, and would take minutes.
    split_on_failure : bool
        Whether the caller splits a section that fails with a rest at one of its smooth joins and
        traces the halves (:func:`skatetrace.trace_and_verify` with ``rests="auto"`` sets it). A
        section of more than :data:`SHORT_SECTION` pieces is then searched without the stops'
        full-accuracy fallbacks, and one of more than :data:`LONG_SECTION` gives up after
        :data:`BRIEF_PLACEMENTS` placements none of which worked: halves are traced in a fraction
        of the time such a failure takes. The trace of a section that is not given up is the same.
    reach : float or None
        Plan the mass's motion within this distance of the contact point
        (:func:`skatetrace.plan_figure`); None keeps the launch-glide-stop manoeuvres.
    objective : {"effort", "time"}
        What the plan minimises: the integral of the squared force on the mass, or the duration
        (which needs ``max_accel``).
    max_accel, max_mass_speed : float or None
        Optional bounds of the plan: the mass's acceleration on the ice, and its speed relative to
        the blade.
    reach_hint : bool
        With a reach: plan a section that has no motion within it on its own within a few larger
        reaches (1.5, 2, 3 and 5 times), to say which would do (``smallest_feasible_reach`` in its
        metrics). Each is one more program: a long section's can take a minute (a spiral of 60
        arcs, 65 s). False says only that the reach is too small (the command line's default
        reach, which falls back to the launch-glide-stop manoeuvres, does so).
    all_or_nothing : bool
        With a reach: where the sections' own programs leave one without a plan, plan no curve
        further (no linked program is solved, no curve finished): the others are reported
        ``NOT_PLANNED``, naming that section. For a caller that uses a plan only if every section
        has one (the command line's default reach falls back to the launch-glide-stop
        manoeuvres): a drawing of 22 sections spent 30 of its 60 s planning curves it then set aside.
    plan_budget : int or None
        With a reach: the most work the plan may take, IPOPT's iterations times the program's
        unknowns summed over its programs (:func:`skatetrace.planning.pool.spending`); past it the
        sections not yet planned are ``OVER_BUDGET``. None (default): no bound. The command
        line's default reach, a plan not asked for, has one (:data:`skatetrace.pipeline.DEFAULT_PLAN_BUDGET`).
    workers : int or None
        Processes in which independent work runs side by side: the planner's programs (the
        distinct sections' warm starts, the curves' linked programs) and the tracer's distinct
        sections. None uses every core this process may run on, up to 8; 1 runs them one after
        another. The plan and the trace are the same either way.
    """

    speed: float = 1.0
    maneuver_length: float | None = None
    glide_lateral: float | None = None
    residual_tol: float = 1e-10
    singular_limit: float = 1e-3
    excursion_limit: float = 20.0
    rtol: float = 1e-13
    atol: float = 1e-14
    placement: str = "least-reach"
    search: int = 16
    max_placements: int = 256
    split_on_failure: bool = False
    reach: float | None = None
    objective: str = "effort"
    max_accel: float | None = None
    max_mass_speed: float | None = None
    reach_hint: bool = True
    all_or_nothing: bool = False
    plan_budget: int | None = None
    workers: int | None = None

    def __post_init__(self) -> None:
        for name in ("speed", "maneuver_length", "glide_lateral", "residual_tol", "singular_limit", "excursion_limit",
                     "rtol", "atol"):
            value = getattr(self, name)
            if value is None and name in ("maneuver_length", "glide_lateral"):
                continue
            if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
                raise ValueError(f"{name} must be a number, got {value!r}")
            if not (abs(value) <= 1e300 and math.isfinite(value)):  # a huge int would overflow isfinite
                raise ValueError(f"{name} must be finite, got {value!r}")
        # Durations scale as 1 / speed; far outside this range they under- or overflow the
        # absolute time steps of the integrators (at 1e100 a replay divides by zero).
        if not (SPEED_RANGE[0] <= self.speed <= SPEED_RANGE[1]):
            raise ValueError(f"speed must lie between {SPEED_RANGE[0]:g} and {SPEED_RANGE[1]:g} (positive), "
                             f"got {self.speed!r}")
        if self.maneuver_length is not None and not (math.isfinite(self.maneuver_length) and self.maneuver_length > 0):
            raise ValueError(f"maneuver_length must be positive, got {self.maneuver_length!r}")
        if not (isinstance(self.search, int) and self.search >= 0):
            raise ValueError(f"search must be a whole number >= 0, got {self.search!r}")
        if not (isinstance(self.max_placements, int) and not isinstance(self.max_placements, bool)
                and self.max_placements >= 1):
            raise ValueError(f"max_placements must be a whole number >= 1, got {self.max_placements!r}")
        if self.plan_budget is not None and (isinstance(self.plan_budget, bool) or
                                             not isinstance(self.plan_budget, (int, np.integer)) or self.plan_budget < 0):
            raise ValueError(f"plan_budget must be a whole number >= 0, or None (no bound), got {self.plan_budget!r}")
        if self.workers is not None and not (isinstance(self.workers, (int, np.integer)) and not isinstance(self.workers, bool)
                                             and 1 <= self.workers <= 1024):
            raise ValueError(f"workers must be a whole number from 1 to 1024, or None (every core), got {self.workers!r}")
        for name in ("reach", "max_accel", "max_mass_speed"):
            value = getattr(self, name)
            if value is not None and (isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating))
                                      or not (math.isfinite(value) and value > 0)):
                raise ValueError(f"{name} must be a positive finite number or None, got {value!r}")
        for name in ("reach_hint", "all_or_nothing", "split_on_failure"):
            if not isinstance(getattr(self, name), (bool, np.bool_)):
                raise ValueError(f"{name} must be True or False, got {getattr(self, name)!r}")
        if self.objective not in ("effort", "time"):
            raise ValueError(f"objective must be 'effort' or 'time', got {self.objective!r}")
        if self.objective == "time" and self.reach is not None and self.max_accel is None:
            raise ValueError("objective='time' needs max_accel: without a bound on the mass's acceleration the "
                             "least time has no minimum (the mass could be thrown arbitrarily hard)")
        if self.placement not in ("least-reach", "first"):
            raise ValueError(f"placement must be 'least-reach' or 'first', got {self.placement!r}")
        for name in ("residual_tol", "singular_limit", "excursion_limit", "rtol", "atol"):
            if not getattr(self, name) > 0:
                raise ValueError(f"{name} must be positive, got {getattr(self, name)!r}")
