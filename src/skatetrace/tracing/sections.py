"""Exact tracing of figures: controls under which the full dynamics follows every piece.

Each section of a figure (pieces joined smoothly, from one cusp to the next) is traced from rest
to rest as *launch, glide, stop* (see :mod:`skatetrace.tracing.maneuver`):

1. a glide on the section's longest segment, the mass locked at ``(0, b_g)`` on an arc or
   ``(a_g, 0)`` on a line, at the requested speed;
2. a stop, integrated forwards from the glide through the rest of the section, whose ramp control
   and duration are found by Newton's method so that the speed vanishes exactly at the section's end;
3. a launch, the same integrated backwards from the glide to the section's start.

On a spiral (a piece whose curvature is a cubic of arc length, from exact mode) the mass cannot
be locked: there the apex is an instant at the piece's middle, and the launch runs straight into
the stop. The legs then carry the curvature polynomial, evaluated at the arc length reached.

The curvature condition holds by construction at every instant, so the blade follows the section
exactly; the length and the zero end speeds are the boundary conditions of the Newton solves.
A section traversed backwards (after a reversal) is solved forwards and mapped by the symmetry
``(a, b, p2, xi2) -> -(a, b, p2, xi2)`` of the model (the sleigh's mass centre sits on the blade).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field, replace
from enum import Enum
from typing import Any

import numpy as np

from ..dynamics.integrator import load as load_integrator
from ..dynamics.model import SleighParams, mass_energy, singular_point, velocities
from ..figures.figure import Figure, Section
from ..figures.geometry import travel
from ..processes import run_jobs
from .leg_motion import leg_motion
from .leg_motion import load as load_leg_motion
from .maneuver import ManeuverSolution, glide_state, solve_stop
from .mirror import mirrored_maneuver, same_legs
from .options import BRIEF_PLACEMENTS, LONG_SECTION, SHORT_SECTION, TraceOptions
from .placements import APEX_CLEARANCE, apex_singular_distance, auto_maneuver_length, glide_candidates, legs_from_apex
from .search import Attempt, outreaches, search_placements
from .shapes import ShapeIndex, exact_key

__all__ = ["TraceOptions", "TraceStatus", "SectionTrace", "FigureTrace", "trace_section", "trace_figure"]


class TraceStatus(Enum):
    """Outcome of tracing a section; the value is the message."""

    SUCCESS = "traced exactly"
    NO_STOP = "no stop manoeuvre could end the section at rest"
    NO_LAUNCH = "no launch manoeuvre could start the section from rest"
    SINGULAR = "the mass approached the singular set of the control law"
    RESIDUAL = "boundary conditions not met to the required tolerance"
    EXCURSION = "the mass would have to move implausibly far or the blade stall inside the section"
    INFEASIBLE = "no motion of the mass within the reach traces the section"
    NOT_PLANNED = "the planner did not converge on the curve"
    OVER_BUDGET = "the planner spent its budget before the section was planned"


@dataclass(frozen=True, slots=True)
class _Phase:
    kind: str  # "launch", "glide", "stop"
    t0: float  # section time (normalised, glide speed 1)
    t1: float
    maneuver: ManeuverSolution | None
    s0: float  # section arc length at the phase's start
    kappa: float = 0.0  # glide curvature
    segment: int | None = None  # piece where the phase starts (planned phases; else the glide's)


def _by_phase(tn: np.ndarray, phases, right: bool, end: float) -> list:
    """For each phase, what selects its times among ``tn`` (section times at unit speed), or None where none is its.

    On the right a phase has the times from its start to before its end (the last one its end too,
    and to a few ulps past it); on the left from after its start (the first one its start too)
    to its end. The times are put in order once (sampling asks for them in a few ordered runs),
    and each phase's found by bisection: a slice of them, or their indices. A mask over all the
    times per phase took a quarter of the evaluation of a planned section of 69 phases at 58,000
    times.
    """
    order = None if tn.size < 2 or np.all(tn[1:] >= tn[:-1]) else np.argsort(tn, kind="stable")
    ts = tn if order is None else tn[order]
    out, n = [], len(phases)
    for i, ph in enumerate(phases):
        if right:
            lo = np.searchsorted(ts, ph.t0, "left")
            hi = np.searchsorted(ts, end * (1 + 1e-14), "right") if i == n - 1 else np.searchsorted(ts, ph.t1, "left")
        else:
            lo = np.searchsorted(ts, ph.t0, "right")
            if i == 0:
                lo = min(lo, np.searchsorted(ts, 0.0, "left"))
            hi = np.searchsorted(ts, ph.t1, "right")
        if lo >= hi:
            out.append(None)
        else:
            out.append(slice(int(lo), int(hi)) if order is None else order[lo:hi])
    return out


@dataclass(frozen=True, slots=True, kw_only=True)
class SectionTrace:
    """Controls that trace one section exactly, with the solver's report.

    Times are local to the section and physical (scaled by ``speed``). Use :meth:`evaluate`
    for the state and controls at any time and :meth:`breakpoints` for the instants where the
    control rates may jump.
    """

    success: bool
    status: TraceStatus
    message: str
    curve_index: int
    section: Section
    params: SleighParams
    speed: float
    glide: dict[str, Any]
    phases: tuple[_Phase, ...] = ()
    residuals: dict[str, float] = field(default_factory=dict)
    metrics: dict[str, float] = field(default_factory=dict)
    nfev: int = 0

    @property
    def direction(self) -> int:
        return self.section.pieces[0].direction

    @property
    def duration(self) -> float:
        return self.phases[-1].t1 / self.speed if self.phases else math.nan

    @property
    def length(self) -> float:
        return self.section.length

    def breakpoints(self) -> np.ndarray:
        """Physical times of phase and segment boundaries (control rates may jump there)."""
        out = [0.0]
        for ph in self.phases:
            if ph.kind == "plan":
                # the joins inside a planned phase; its bounds are the phase's own (no rounded copies)
                out += [ph.t0 + leg.t1 for leg in ph.maneuver.legs[:-1]]
            elif ph.maneuver is not None:
                for leg in ph.maneuver.legs:
                    for t in (leg.t0, leg.t1):
                        out.append(self._section_time(ph, t))
            out.append(ph.t1)
        return np.unique(np.asarray(out)) / self.speed

    def _section_time(self, ph: _Phase, t_local: float) -> float:
        if ph.kind == "launch":
            return t_local - ph.maneuver.duration  # duration < 0: t in [tau, 0] -> [0, -tau]
        return ph.t0 + t_local

    def evaluate(self, t, side: str = "right", geometry: bool = True) -> dict[str, np.ndarray]:
        """State and controls at physical section times ``t`` (1-D array).

        Returns a dict of arrays: ``p1, p2, theta, x, y, a, b, adot, bdot, s, xi1, xi2`` and
        ``segment`` (index of the piece within the section). At a breakpoint, where the control
        rates jump, ``side="right"`` gives the limit from after it (the phase or leg that starts
        there) and ``side="left"`` the limit from before it. ``geometry=False`` leaves out
        ``theta, x, y`` (laying spirals out is the costly part, and sampling needs only controls).
        """
        if side not in ("left", "right"):
            raise ValueError(f"side must be 'left' or 'right', got {side!r}")
        if not self.phases:
            raise ValueError(f"this section was not traced ({self.message}); there is nothing to evaluate")
        right = side == "right"
        V = self.speed
        tn = np.atleast_1d(np.asarray(t, dtype=float)) * V
        end = self.phases[-1].t1
        if not np.all((tn >= 0.0) & (tn <= end * (1 + 1e-14))):
            raise ValueError(f"times must lie in the section's span [0, {self.duration:.6g}]")
        n = tn.size
        out = {k: np.empty(n) for k in ("p1", "p2", "a", "b", "adot", "bdot", "s")}
        # Which piece each time belongs to follows from the phase and leg, not from s: at a join
        # s is only known to the integration's accuracy.
        g = self.glide["segment"]
        seg = np.empty(n, dtype=int)
        for ph, sel in zip(self.phases, _by_phase(tn, self.phases, right, end)):
            if sel is None:
                continue
            if ph.kind == "glide":
                a, b = self.glide["a"], self.glide["b"]
                p = glide_state(self.params, ph.kappa, a, b, 1.0)
                out["p1"][sel], out["p2"][sel] = p[0], p[1]
                out["a"][sel], out["b"][sel] = a, b
                out["adot"][sel] = out["bdot"][sel] = 0.0
                out["s"][sel] = ph.s0 + (tn[sel] - ph.t0)
                seg[sel] = g
                continue
            man = ph.maneuver
            tl = tn[sel] + man.duration if ph.kind == "launch" else tn[sel] - ph.t0
            tl = np.clip(tl, min(0.0, man.duration), max(0.0, man.duration))
            vals = {k: np.empty(tl.size) for k in out}
            vseg = np.empty(tl.size, dtype=int)
            step = -1 if ph.kind == "launch" else 1
            # The legs in section-time order (reversed for a launch) cover [lo, hi] in local time
            # one after the other. At a shared boundary the leg on the requested side wins: on the
            # right the last leg starting at or before t, on the left the first ending at or after t.
            order = range(len(man.legs)) if ph.kind != "launch" else range(len(man.legs) - 1, -1, -1)
            legs = [man.legs[j] for j in order]
            g0 = g if ph.segment is None else ph.segment
            segidx = [g0 + step * j for j in order]
            los = np.array([min(leg.t0, leg.t1) for leg in legs])
            his = np.array([max(leg.t0, leg.t1) for leg in legs])
            eps = 1e-12 * max(1.0, abs(man.duration))  # section time -> local time loses a few ulps
            if right:
                which = np.searchsorted(los, tl + eps, side="right") - 1
            else:
                which = np.searchsorted(his, tl - eps, side="left")
            which = np.clip(which, 0, len(legs) - 1)
            for j in np.unique(which):
                leg, m = legs[j], which == j
                tj = np.clip(tl[m], los[j], his[j])
                y, ad, bd = leg_motion(self.params, man, leg, tj)
                for key, val in zip(("p1", "p2", "a", "b", "s", "adot", "bdot"), (*y, ad, bd)):
                    vals[key][m] = val
                vseg[m] = segidx[j]
            vals["s"] = ph.s0 + (vals["s"] - (man.end[4] if ph.kind == "launch" else 0.0))
            for k in out:
                out[k][sel] = vals[k]
            seg[sel] = vseg
        # physical scaling: momenta and rates scale with the speed
        for k in ("p1", "p2", "adot", "bdot"):
            out[k] *= V
        return self._finish(out, seg, geometry)

    def layout(self, s, segment) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The blade's ``(x, y, theta)`` at arc lengths ``s`` along the section on pieces ``segment``.

        ``s`` and ``segment`` are as :meth:`evaluate` returns them; the piece is given, not
        found from ``s``, since at a join ``s`` is known only to the integration's accuracy.
        """
        seg = np.asarray(segment)
        pieces = self.section.pieces
        ends = np.cumsum([p.segment.length for p in pieces])
        s = np.clip(np.asarray(s, dtype=float), 0.0, ends[-1])
        x, y, heading = np.empty_like(s), np.empty_like(s), np.empty_like(s)
        starts = np.concatenate([[0.0], ends[:-1]])
        for i, p in enumerate(pieces):
            m = seg == i
            if np.any(m):
                local = np.clip(s[m] - starts[i], 0.0, p.segment.length)
                xs, ys, hs = travel(p.start, p.segment, local)
                x[m], y[m], heading[m] = xs, ys, hs
        return x, y, heading + (math.pi if self.direction < 0 else 0.0)

    def _finish(self, out: dict[str, np.ndarray], seg: np.ndarray, geometry: bool = True) -> dict[str, np.ndarray]:
        d = self.direction
        if geometry:
            out["x"], out["y"], out["theta"] = self.layout(out["s"], seg)
        if d < 0:
            for k in ("a", "b", "adot", "bdot", "p2"):
                out[k] = -out[k]
        out["segment"] = seg
        xi1, xi2, _ = velocities(self.params, out["p1"], out["p2"], out["a"], out["b"], out["adot"], out["bdot"])
        out["xi1"], out["xi2"] = xi1, xi2
        return out

    def time_at_length(self, s):
        """Physical section time at which the blade has travelled ``s`` (scalar or 1-D array).

        A length reached at a breakpoint (a join, within 1e-12 of the section's length) gives that
        breakpoint. Others are found by bisection (the speed is positive inside a section), all
        at once, and a time within 1e-9 of a breakpoint is snapped onto it, so that evaluating
        there gives the state at the start of the next piece.
        """
        target = np.asarray(s, dtype=float)
        flat = np.atleast_1d(target).ravel()
        bps = self.breakpoints()
        # Lengths reached at a breakpoint (every join is one) need no search: the blade passes
        # them there, to the integration's accuracy.
        s_bp = self.evaluate(bps, geometry=False)["s"]
        k = _nearest(s_bp, flat)
        out = np.where(np.abs(s_bp[k] - flat) <= 1e-12 * max(1.0, self.length), bps[k], np.nan)
        todo = np.flatnonzero(np.isnan(out))
        if todo.size:
            lo, hi = np.zeros(todo.size), np.full(todo.size, self.duration)
            for _ in range(100):
                mid = 0.5 * (lo + hi)
                below = self.evaluate(mid, geometry=False)["s"] < flat[todo]
                lo, hi = np.where(below, mid, lo), np.where(below, hi, mid)
            near = bps[_nearest(bps, hi)]
            out[todo] = np.where(np.abs(near - hi) <= 1e-9 * max(1.0, self.duration), near, hi)
        return float(out[0]) if target.ndim == 0 else out.reshape(target.shape)

    def to_dict(self) -> dict[str, Any]:
        phases = []
        for ph in self.phases:
            d: dict[str, Any] = {"kind": ph.kind, "t0": ph.t0 / self.speed, "t1": ph.t1 / self.speed}
            if ph.maneuver is not None:
                man = ph.maneuver
                d.update(control="u = alpha * t (t from the glide, backwards for a launch)",
                         alpha=man.params[0] * self.speed**2,
                         duration=abs(man.duration) / self.speed,
                         legs=[{"curvature": list(leg.coefficients)} for leg in man.legs],
                         residuals=man.residuals, min_singular_distance=man.min_singular_distance)
            else:
                d.update(control="mass locked", kappa=ph.kappa)
            phases.append(d)
        return {
            "success": self.success, "status": self.status.name, "message": self.message,
            "curve": self.curve_index, "pieces": [p.index for p in self.section.pieces],
            "direction": self.direction, "speed": self.speed, "glide": self.glide,
            "phases": phases, "residuals": self.residuals, "metrics": self.metrics,
        }


def _nearest(values: np.ndarray, x: np.ndarray) -> np.ndarray:
    """For each of ``x``, the index of the nearest of ``values`` (the first of several equally near).

    ``np.argmin(np.abs(values[:, None] - x[None, :]), axis=0)``, without its ``values.size`` by
    ``x.size`` matrix where ``values`` increase: the nearest is then a neighbour of where ``x`` would
    be inserted (the rounded distance is monotone on each side), and the first index of its value.
    A section of 4,712 spirals asked for 4,711 lengths among 4,714 breakpoints: 0.7 s and 200 MB.
    """
    if values.size < 2 or np.any(np.diff(values) < 0.0):  # not in order (not seen): every pair compared
        return np.argmin(np.abs(values[:, None] - x[None, :]), axis=0)
    right = np.minimum(np.searchsorted(values, x, side="left"), values.size - 1)
    left = np.maximum(right - 1, 0)
    nearer = np.where(np.abs(values[left] - x) <= np.abs(values[right] - x), left, right)
    return np.searchsorted(values, values[nearer], side="left")


def trace_section(
    params: SleighParams, section: Section, options: TraceOptions = TraceOptions(), curve_index: int = 0
) -> SectionTrace:
    """Find controls that trace ``section`` exactly from rest to rest.

    The glide is placed on each segment in turn (longest first) and at each candidate mass position
    (:func:`glide_candidates`), until ``options.max_placements`` have been tried without success; an
    apex within :data:`~skatetrace.tracing.placements.APEX_CLEARANCE` singular limits of its
    curvature's singular point counts as tried and failed, unsolved. Of the placements whose stop
    and launch are both found and pass every check (the first that works and up to
    ``options.search`` tried after it), the one whose mass stays closest to the blade is kept (least
    largest ``|a|, |b|``, then least peak kinetic energy of the mass); with
    ``options.placement="first"`` the first is
    (:func:`~skatetrace.tracing.search.search_placements`). The search runs first with the stops'
    well-conditioned solves alone (``fallback=False`` of
    :func:`~skatetrace.tracing.maneuver.solve_stop`): a stop that only the full-accuracy fallbacks
    find has its speed grazing zero before the end, and those fallbacks are most of a long section's
    time where they fail. Only where no placement works without them is the search run again with
    them. With ``options.split_on_failure`` (the caller splits a section that fails) a section of
    several pieces is searched less: see :class:`~skatetrace.tracing.options.TraceOptions`. Never
    raises for a section that cannot be traced: the result has ``success=False`` and the reason.

    Raises
    ------
    ValueError
        If ``options.reach`` is set: that asks for a plan within the reach, which
        :func:`skatetrace.plan_figure` (or :func:`skatetrace.trace_and_verify`) makes; the
        launch-glide-stop manoeuvres traced here keep the mass within no reach.
    """
    if options.reach is not None:
        raise ValueError(f"launch-glide-stop tracing keeps the mass within no reach; options.reach={options.reach!r} "
                         f"asks for a plan: use skatetrace.plan_figure or skatetrace.trace_and_verify, or reach=None")
    segs = section.segments
    order = sorted(range(len(segs)), key=lambda i: -segs[i].length)
    kw = dict(rtol=options.rtol, atol=options.atol, singular_limit=options.singular_limit)
    clearance = APEX_CLEARANCE * options.singular_limit * params.length_scale

    def placements():
        for g in order:
            Lg = segs[g].length
            kg = float(segs[g].curvature_at(0.5 * Lg))
            ell = min(options.maneuver_length or auto_maneuver_length(params, kg, Lg), 0.5 * Lg)
            for glide_ab, steady in glide_candidates(params, segs, g, ell, options):
                yield g, kg, Lg, ell, glide_ab, steady

    def solved(placement, fallback: bool, bound: float) -> Attempt:
        """The section traced with the glide at ``placement`` (or its stop alone, where that reaches
        beyond ``bound``: see :class:`~skatetrace.tracing.search.Attempt`)."""
        g, kg, Lg, ell, glide_ab, steady = placement
        # an instant apex is no glide: the launch and the stop share the whole segment
        ell_g = ell if steady else 0.5 * Lg
        before, after = legs_from_apex(segs, g, ell_g)
        glide = {"segment": g, "a": glide_ab[0], "b": glide_ab[1], "length": Lg - 2.0 * ell_g,
                 "kappa": kg, "speed": options.speed}
        distance = apex_singular_distance(params, kg, glide_ab)
        if distance <= clearance:
            return Attempt(_near_singular(params, section, options, curve_index, glide, distance, clearance), 0)
        kwf = dict(kw, fallback=fallback)
        with np.errstate(divide="ignore", invalid="ignore"):
            stop = solve_stop(params, after, glide_ab, 1.0, **kwf)
            if not stop.success:
                trace = _assemble(params, section, options, curve_index, glide, before, stop, None, stop.nfev)
                return Attempt(trace, stop.nfev, stop.deferred)
            reach = _stop_reach(stop)
            if outreaches(reach, bound):  # this section cannot win: its launch is not solved
                return Attempt(None, stop.nfev, False, reach, stop.nfev)
            launch = _launch(params, before, after, glide_ab, stop, kwf)
        used = stop.nfev + launch.nfev
        trace = _assemble(params, section, options, curve_index, glide, before, stop, launch, used)
        return Attempt(trace, used, not trace.success and (stop.deferred or launch.deferred), reach, stop.nfev)

    # Well-conditioned placements first: every placement is solved without the stops' fallbacks
    # (see solve_stop), which serve stops whose speed grazes zero before the end and cost most of
    # a long section's time where they fail. Only a section that no placement traces without
    # them is searched again with them; the placements that failed for another reason are not
    # solved twice. A section that the caller splits where it fails is searched less (see
    # TraceOptions.split_on_failure): its halves are traced faster than its failure takes.
    brief = options.split_on_failure and len(segs) > SHORT_SECTION
    search = (replace(options, max_placements=min(options.max_placements, BRIEF_PLACEMENTS))
              if brief and len(segs) > LONG_SECTION else options)
    done = quick = search_placements(placements(), lambda placement, bound: solved(placement, False, bound), search,
                                     {})
    if quick.best is None and quick.deferred and not brief:
        full = search_placements(placements(), lambda placement, bound: solved(placement, True, bound), options,
                                 quick.settled)
        done = replace(full, nfev=quick.nfev + full.nfev)
    if done.best is not None:
        return replace(done.best, nfev=done.nfev)
    attempts, first_failure = done.attempts, done.first_failure
    total = sum(1 for _ in placements()) if attempts >= search.max_placements else attempts
    if brief:
        tried = (f"tried {attempts} of its {total:,} glide placements without the stops' full-accuracy fallbacks, "
                 f"to be split by a rest (TraceOptions.split_on_failure)")
    elif total == attempts:
        tried = f"tried {attempts} glide placements: every segment as the glide, every candidate mass position"
    else:
        tried = (f"gave up after {attempts} of its {total:,} glide placements (the longest of its {len(segs)} pieces "
                 f"as the glide first; TraceOptions.max_placements): a section this long rarely starts and stops with "
                 f"one glide: split it with corners, or with rests at its smooth joins (--rests joins)")
    return SectionTrace(
        success=False, status=first_failure.status,
        message=first_failure.message + f" ({tried})",
        curve_index=curve_index, section=section, params=params, speed=options.speed, glide=first_failure.glide,
        residuals=first_failure.residuals, metrics=first_failure.metrics, nfev=done.nfev,
    )  # no phases: controls that failed a check are not handed on to be written or replayed


def _launch(params: SleighParams, before, after, glide_ab, stop: ManeuverSolution, kw) -> ManeuverSolution:
    """The launch over ``before`` to the apex ``glide_ab`` whose stop over ``after`` is ``stop`` (found).

    With the mass at ``a = 0`` and the same curve on both sides of the apex the launch is the
    stop reversed in time (:func:`~skatetrace.tracing.mirror.mirrored_maneuver`), exactly: it is not
    solved a second time.
    """
    if glide_ab[0] == 0.0 and same_legs(before, after):
        return mirrored_maneuver(stop, before)
    return solve_stop(params, before, glide_ab, 1.0, backward=True, **kw)


def _near_singular(params, section, options, curve_index, glide, distance, clearance) -> SectionTrace:
    """The failure of a placement whose apex is ``distance`` (within ``clearance``) from its curvature's singular
    point, not solved.

    See :data:`~skatetrace.tracing.placements.APEX_CLEARANCE`: its manoeuvres would start where the
    control rates grow without bound, and the weak ramps' integrations crawl there.
    """
    a, b, kappa = glide["a"], glide["b"], glide["kappa"]
    message = (f"the glide's mass position ({a:.6g}, {b:.6g}) is "
               f"{distance:.3g} from the singular point "
               f"(0, {singular_point(params, kappa)[1]:.6g}) of its curvature {kappa:.6g}, within {APEX_CLEARANCE:g} "
               f"singular limits ({clearance:.3g}): not solved")
    return SectionTrace(success=False, status=TraceStatus.SINGULAR, message=message, curve_index=curve_index,
                        section=section, params=params, speed=options.speed, glide=glide, nfev=0)


def _assemble(params, section, options, curve_index, glide, before, stop, launch, nfev) -> SectionTrace:
    base = dict(curve_index=curve_index, section=section, params=params, speed=options.speed, glide=glide, nfev=nfev)
    if not stop.legs:
        return SectionTrace(success=False, status=TraceStatus.NO_STOP, message=stop.message, **base)
    if launch is None or not launch.legs:
        return SectionTrace(success=False, status=TraceStatus.NO_LAUNCH if launch else TraceStatus.SINGULAR,
                            message=launch.message if launch else stop.message, **base)
    glide_len = glide["length"]
    kg = glide["kappa"]
    s_launch = sum(ell_ for _, ell_ in before)
    t_l = -launch.duration
    phases = (
        _Phase("launch", 0.0, t_l, launch, 0.0),
        _Phase("glide", t_l, t_l + glide_len, None, s_launch, kg),
        _Phase("stop", t_l + glide_len, t_l + glide_len + stop.duration, stop, s_launch + glide_len),
    )
    residuals = {
        "launch_start_speed": abs(launch.residuals["end_speed"]) * options.speed,
        "stop_end_speed": abs(stop.residuals["end_speed"]) * options.speed,
        "length": abs(launch.residuals["length"]) + abs(stop.residuals["length"]),
    }
    worst = max(residuals.values())
    singular = min(launch.min_singular_distance, stop.min_singular_distance)
    if not (launch.success and stop.success):
        status, msg = TraceStatus.SINGULAR, (launch.message if not launch.success else stop.message)
    elif worst > options.residual_tol:
        status, msg = TraceStatus.RESIDUAL, f"largest residual {worst:.3g} > {options.residual_tol:.3g}"
    else:
        status, msg = TraceStatus.SUCCESS, TraceStatus.SUCCESS.value
    trace = SectionTrace(
        success=status is TraceStatus.SUCCESS, status=status, message=msg, phases=phases,
        residuals=residuals, **base,
    )
    return _with_metrics(trace, singular, options, _step_samples(trace))


#: Where each integration step of a manoeuvre is looked at for the section's peaks: its two ends
#: and seven points between. Over 790 sections (300 arcs, the double flower, 40 corpus drawings)
#: the peaks came within 0.7 % of those from 128 points a step (2e-4 for |adot|, 5e-5 for the
#: reach), where 4001 times evenly spread missed up to 70 % of |adot| and 25 % of |bdot|.
_STEP_FRACTIONS = np.linspace(0.0, 1.0, 9)


def _stop_reach(stop: ManeuverSolution) -> float:
    """The largest ``|a|, |b|`` of the mass where the stop's integration steps begin.

    Those states are among its section's own samples (:data:`_STEP_FRACTIONS` begins at 0, where
    the dense output is the step's initial state exactly), but for a time that rounds to another's
    in the section, whose state is the same to rounding: no section through this stop reaches
    less, beyond that rounding (:func:`~skatetrace.tracing.search.outreaches`).
    """
    return max(float(np.max(np.abs(leg.sol.y_old[:, 2:4]))) for leg in stop.legs)


def _step_samples(trace: SectionTrace) -> dict[str, np.ndarray]:
    """The motion of a launch-glide-stop section where its peaks are, in time order, without positions or layout.

    The glide at its two ends (the mass is locked there) and every integration step of the launch
    and the stop at :data:`_STEP_FRACTIONS`, each distinct time once, the section's start first and
    its end last, as :meth:`SectionTrace.evaluate` gives them (``s`` and ``segment`` left at 0).
    The steps crowd where the motion changes fast: near the ends, where the blade comes to rest,
    the rates rise and fall within a fraction of the spacing of 4001 times evenly spread, which
    also cost 1 ms a section (half of a single arc's trace); this costs a fifth to a half of that.
    """
    params, V = trace.params, trace.speed
    times, rows = [], []
    for ph in trace.phases:
        man = ph.maneuver
        if man is None:
            a, b = trace.glide["a"], trace.glide["b"]
            p1, p2 = glide_state(params, ph.kappa, a, b, 1.0)
            times.append(np.array([ph.t0, ph.t1]))
            rows.append(np.array([[p1, p1], [p2, p2], [a, a], [b, b], [0.0, 0.0], [0.0, 0.0]]))
            continue
        for leg in man.legs:
            sol = leg.sol
            tl = np.clip((sol.t_old[:, None] + sol.h[:, None] * _STEP_FRACTIONS).ravel(),
                         min(leg.t0, leg.t1), max(leg.t0, leg.t1))
            y, adot, bdot = leg_motion(params, man, leg, tl)
            times.append(trace._section_time(ph, tl))
            rows.append(np.vstack([y[:4], adot, bdot]))
    t, first = np.unique(np.concatenate(times), return_index=True)
    p1, p2, a, b, adot, bdot = np.hstack(rows)[:, first]
    out = {"p1": p1 * V, "p2": p2 * V, "a": a, "b": b, "adot": adot * V, "bdot": bdot * V, "s": np.zeros(t.size)}
    return trace._finish(out, np.zeros(t.size, dtype=int), geometry=False)


def _with_metrics(trace: SectionTrace, singular: float, options: TraceOptions, v=None) -> SectionTrace:
    """``trace`` with its ``metrics``: peaks of the mass's motion and the least speed inside, from ``v``.

    ``v`` is the motion (as :meth:`SectionTrace.evaluate` gives it) at times from the section's
    start to its end, both included, in order; by default at 4001 times evenly spread and the
    breakpoints. A section whose mass goes beyond ``options.excursion_limit`` or whose blade
    stops inside it fails (:attr:`TraceStatus.EXCURSION`).
    """
    if v is None:
        t = np.unique(np.concatenate([np.linspace(0.0, trace.duration, 4001), trace.breakpoints()]))
        v = trace.evaluate(t, geometry=False)  # the metrics need no layout of the blade's path
    ke = mass_energy(trace.params, v["xi1"], v["xi2"], v["a"], v["b"], v["adot"], v["bdot"])
    metrics = {
        "duration": trace.duration,
        "length": trace.length,
        "peak_abs_adot": float(np.max(np.abs(v["adot"]))),
        "peak_abs_bdot": float(np.max(np.abs(v["bdot"]))),
        "peak_mass_kinetic_energy": float(np.max(ke)),
        "max_abs_a": float(np.max(np.abs(v["a"]))),
        "max_abs_b": float(np.max(np.abs(v["b"]))),
        "min_singular_distance": float(singular),
        "min_speed_inside": float(np.min(np.abs(v["xi2"][1:-1]))) if v["xi2"].size > 2 else 0.0,
    }
    status, message = trace.status, trace.message
    reach = max(metrics["max_abs_a"], metrics["max_abs_b"])
    limit = options.excursion_limit * max(trace.params.length_scale, trace.length)
    interior = v["xi2"][1:-1] * trace.direction
    if trace.success and (reach > limit or np.any(interior <= 0.0)):
        status = TraceStatus.EXCURSION
        message = (f"mass reaches {reach:.3g} from the contact point (limit {limit:.3g})" if reach > limit
                   else "the blade comes to rest inside the section")
    return SectionTrace(
        success=status is TraceStatus.SUCCESS, status=status, message=message, curve_index=trace.curve_index,
        section=trace.section, params=trace.params, speed=trace.speed, glide=trace.glide,
        phases=trace.phases, residuals=trace.residuals, metrics=metrics, nfev=trace.nfev,
    )


@dataclass(frozen=True, slots=True, kw_only=True)
class FigureTrace:
    """Traced sections of a whole figure, in skating order, with the time each one starts."""

    figure: Figure
    params: SleighParams
    options: TraceOptions
    sections: tuple[SectionTrace, ...]
    start_times: tuple[float, ...]

    @property
    def success(self) -> bool:
        return all(s.success for s in self.sections)

    @property
    def status(self) -> str:
        return "success" if self.success else "failed"

    @property
    def message(self) -> str:
        bad = [s for s in self.sections if not s.success]
        if not bad:
            return f"all {len(self.sections)} sections traced exactly"
        return "; ".join(f"curve {s.curve_index} pieces {_indices(s.section.pieces)}: {s.message}" for s in bad)

    @property
    def duration(self) -> float:
        if not self.sections:
            return 0.0
        last = self.sections[-1]
        return self.start_times[-1] + (last.duration if last.phases else 0.0)


def _indices(pieces) -> str:
    """The pieces' indices for a message: ``[3, 4, 5]``, or ``[1824..5356]`` for a long consecutive run."""
    idx = [p.index for p in pieces]
    if len(idx) > 4 and idx == list(range(idx[0], idx[0] + len(idx))):
        return f"[{idx[0]}..{idx[-1]}]"
    return str(idx)


def trace_figure(figure: Figure, params: SleighParams | None = None, options: TraceOptions = TraceOptions(),
                 progress=None, cache: dict | None = None) -> FigureTrace:
    """Trace every section of every curve of ``figure``.

    Sections that are the same up to a rigid motion (the same curvatures and lengths, up to
    round-off: :mod:`~skatetrace.tracing.shapes`) are solved once.
    A section that fails is reported and the others are still traced.

    Parameters
    ----------
    params : SleighParams, optional
        Defaults to the figure's own parameters, else the paper's ``M = 2, m = 1, I = 3``.
    progress : callable, optional
        Called as ``progress(done, total)`` after each section.
    cache : dict, optional
        Solved sections by shape; pass the same dict to several calls to reuse them.

    Raises
    ------
    ValueError
        If ``options.reach`` is set (see :func:`trace_section`).
    """
    params = params or figure.params or SleighParams()
    cache = {} if cache is None else cache
    traces, starts, t = [], [], 0.0
    all_sections = [(ci, sec) for ci, curve in enumerate(figure.curves) for sec in curve.sections()]
    shapes = ShapeIndex(cache)
    keys = [shapes.find(exact_key(params, sec, options)) for _, sec in all_sections]
    todo = {}  # the distinct sections not solved yet, in skating order
    for (ci, sec), key in zip(all_sections, keys):
        if key not in cache and key not in todo:
            todo[key] = (params, sec, options, ci)
    solved = _solve_sections(list(todo.values()), options.workers)
    pending = iter(todo)
    for done, ((ci, sec), key) in enumerate(zip(all_sections, keys), 1):
        while key not in cache:  # the next distinct section is this one: wait for it
            cache[next(pending)] = next(solved)
        proto = cache[key]
        tr = SectionTrace(
            success=proto.success, status=proto.status, message=proto.message, curve_index=ci, section=sec,
            params=params, speed=proto.speed, glide=proto.glide, phases=proto.phases,
            residuals=proto.residuals, metrics=proto.metrics, nfev=proto.nfev,
        )
        traces.append(tr)
        starts.append(t)
        t += tr.duration if tr.phases else 0.0
        if progress is not None:
            progress(done, len(all_sections))
    return FigureTrace(figure=figure, params=params, options=options, sections=tuple(traces), start_times=tuple(starts))


#: A pool of worker processes costs some tens of milliseconds to start and to hand the sections
#: over: sections are traced here while they, and the rest at the pace so far, take at most this
#: long (seconds); the rest in a pool.
_POOL_WORTH = 0.05
#: The most sections handed to a worker at a time (:func:`skatetrace.processes.run_jobs`).
_CHUNK = 16


def _trace_job(job) -> SectionTrace:
    params, section, options, curve_index = job
    return trace_section(params, section, options, curve_index)


def _solve_sections(jobs: list, workers: int | None):
    """The traces of ``jobs`` (``trace_section``'s arguments), yielded in order as each is known.

    The integrator is loaded (or compiled) here first, so that forked workers share it and the
    times below are the sections' own. A section of one piece takes milliseconds; one of several
    pieces, whose glide must be placed, takes from 0.03 to 8 s (measured over the corpus
    drawings: 2 to 6 ms for 241 sections of one piece, 27 ms to 8 s for 111 of more, 0.6 s at the
    median). Where two sections or more have several pieces, they go to worker processes
    (:func:`skatetrace.processes.run_jobs`), those of the most pieces first, so that the last to
    finish is not a long one started late (fontawesome-person-skating's section of 31 pieces, 6 s,
    was fifteenth of 21); but a section of more pieces than all the others together is traced here
    first, where its glide-placement search goes on side by side (:func:`trace_section`;
    nanosvg-drawing's section of 141 pieces, 5 s here against 8 s in a worker). Else sections are
    traced here while they have taken at most ``_POOL_WORTH`` seconds and the rest would, at the
    pace of those traced so far (a figure of a few distinct sections is done here; of a thousand
    arcs, only the first), and the rest in worker processes.
    Each section is traced by the same code either way: the traces do not depend on ``workers``
    or on the order.
    """
    if not jobs:
        return
    load_integrator()
    load_leg_motion()
    pieces = [len(job[1].pieces) for job in jobs]
    if sum(p > 1 for p in pieces) >= 2:
        order = sorted(range(len(jobs)), key=lambda k: -pieces[k])  # stable: ties in skating order
        known = {}
        if pieces[order[0]] > sum(pieces[k] for k in order[1:]):
            known[order[0]] = _trace_job(jobs[order[0]])
            order = order[1:]
        solved = zip(order, run_jobs(_trace_job, [jobs[k] for k in order], workers))
        for k in range(len(jobs)):
            while k not in known:
                j, trace = next(solved)
                known[j] = trace
            yield known.pop(k)
        return
    started = time.perf_counter()
    here = 0
    while here < len(jobs):
        taken = time.perf_counter() - started
        if here and (taken > _POOL_WORTH or taken / here * (len(jobs) - here) > _POOL_WORTH):
            break
        yield _trace_job(jobs[here])
        here += 1
    rest = jobs[here:]
    # handed over _CHUNK at a time where there are many: one by one, a section of one piece (2 to 6
    # ms) cost about as much again to send to a worker and back
    yield from run_jobs(_trace_job, rest, workers, chunk=max(1, min(_CHUNK, len(rest) // _CHUNK)))
