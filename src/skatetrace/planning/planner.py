"""Bounded-reach planning of a whole figure: collocation for the shape, the exact finish for the guarantee.

For each curve, in skating order:

1. every section is posed in its travel frame (:class:`~skatetrace.planning.collocation.SectionSpec`),
   with the turn that carries the mass's position from the end of one section into the next
   (pivots and reversals);
2. a warm start: every distinct section planned on its own by IPOPT from a launch-glide-stop guess;
3. the whole curve as one multi-phase program from that start: the position of the mass on the
   ice continuous through every cusp (a hard constraint), the jump of its velocity (an impulse)
   penalised as the effort of delivering it over ``impulse_time``; its mesh then refined twice
   against the compiled integrator (:mod:`skatetrace.planning.mesh`);
4. the exact finish of every section (:func:`~skatetrace.planning.finish.finish_section`), each
   starting exactly where the previous one ended, and the reach checked between samples; where
   the exact motion leaves the reach, the curve is planned again inside a smaller one.

Sections come back as :class:`~skatetrace.tracing.sections.SectionTrace` objects (one phase per affine
piece of the control), so everything downstream (replay, outputs) treats them like any other.
A section that cannot be planned within the reach is returned as data (``TraceStatus.INFEASIBLE``,
with the smallest of a few larger reaches within which it plans on its own), a curve whose linked
program IPOPT cannot solve as ``TraceStatus.NOT_PLANNED``.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from ..dynamics.model import SleighParams
from ..figures.figure import Figure
from ..figures.geometry import end_pose
from ..tracing.maneuver import _singular_distances
from ..tracing.sections import FigureTrace, SectionTrace, TraceOptions, TraceStatus, _Phase, _with_metrics
from .collocation import PieceSpec, ProgramOptions, ProgramSolution, SectionSpec, solve_program
from .finish import RestState, finish_section
from .mesh import interval_errors, refined

__all__ = ["plan_figure", "curve_specs", "DURATION_PER_LENGTH", "TOP_SPEED"]

#: Each section lasts this many times its length over the glide speed (least effort at a given pace:
#: a launch and a stop each of a fifth of the section around a glide at the speed).
DURATION_PER_LENGTH = 1.25
#: The blade's speed stays below this multiple of the glide speed (the plausibility limit).
TOP_SPEED = 2.0
#: The plan keeps the mass's acceleration within this fraction of ``max_accel``.
_ACCEL_MARGIN = 0.9
#: The plan keeps the mass within this fraction of the reach, so that the exact finish (which
#: moves the motion by the collocation's error) stays within it.
_REACH_MARGIN = 0.98


def curve_specs(curve) -> tuple[list[SectionSpec], list]:
    """The sections of ``curve`` in their travel frames, and the sections themselves."""
    sections = curve.sections()
    specs = []
    prev_heading = None
    for sec in sections:
        pieces = tuple(PieceSpec(tuple(float(c) for c in (list(p.segment.coefficients) + [0.0] * 4)[:4]),
                                 float(p.segment.length)) for p in sec.pieces)
        turn = 0.0 if prev_heading is None else prev_heading - sec.pieces[0].start.heading
        length = sum(p.length for p in pieces)
        specs.append(SectionSpec(pieces, turn, DURATION_PER_LENGTH * length))
        last = sec.pieces[-1]
        prev_heading = end_pose(last.start, last.segment).heading
    return specs, sections


def _program_options(params: SleighParams, options: TraceOptions) -> ProgramOptions:
    tot = params.M + params.m
    v2 = options.speed ** 2
    return ProgramOptions(
        M=params.M / tot, m=params.m / tot, I=params.I / tot, reach=_REACH_MARGIN * options.reach,
        objective=options.objective,
        # the bound holds at the collocation points of the plan; the exact motion overshot it by up to
        # 5 % on the paper's arc (10.5 for 10), so the plan keeps 10 % inside it
        max_accel=None if options.max_accel is None else _ACCEL_MARGIN * options.max_accel / v2,
        max_rate=None if options.max_mass_speed is None else options.max_mass_speed / options.speed,
        # The mass's velocity may jump at a cusp, the impulse penalised as the effort of delivering it
        # within impulse_time: held continuous instead (school three at 0.49 m), the program moved the
        # same change of momentum into the few milliseconds after the cusp, where its mesh does not see
        # the effort (312 m/s^2, 6.4 kN in the exact motion, against 42 m/s^2 with the penalty).
        singular_clearance=0.15 * options.reach, continuous_velocity=False, impulse_time=0.1, tol=1e-6,
        top_speed=TOP_SPEED,
    )


def _rates(fn, X, spec: SectionSpec, at_end: bool):
    piece = spec.pieces[-1] if at_end else spec.pieces[0]
    s0 = spec.length - piece.length if at_end else 0.0
    x = X[:, -1] if at_end else X[:, 0]
    return np.asarray(fn["rates"](x, 0.0, list(piece.coefficients), s0)).ravel()


def _warm_start(specs, popts: ProgramOptions) -> tuple[ProgramSolution | None, int | None]:
    """Every section on its own, from a launch-glide-stop guess: the start of the linked program.

    Sections with the same pieces share one solve (school figures repeat theirs). Returns the
    guess, or None and the index of the first section that has no plan on its own.
    """
    solved: dict = {}
    for k, spec in enumerate(specs):
        if spec.pieces not in solved:
            sol = solve_program([dataclasses.replace(spec, turn=0.0)], popts)
            if not sol.success:
                return None, k
            solved[spec.pieces] = sol
    return _chain([solved[spec.pieces] for spec in specs], "warm start"), None


def _chain(sols: list[ProgramSolution], status: str) -> ProgramSolution:
    """Single-section solutions as the plan of the chain of their sections (not linked to each other)."""
    return ProgramSolution(success=True, status=status, message=status, times=tuple(s.times[0] for s in sols),
                           states=tuple(s.states[0] for s in sols), controls=tuple(s.controls[0] for s in sols),
                           meshes=tuple(s.meshes[0] for s in sols))


def _section_of(plan: ProgramSolution, k: int) -> ProgramSolution:
    """Section ``k`` of a chain's plan as a single-section solution (a guess for that section alone)."""
    return ProgramSolution(success=True, status="own start", message="own start", times=plan.times[k:k + 1],
                           states=plan.states[k:k + 1], controls=plan.controls[k:k + 1], meshes=plan.meshes[k:k + 1])


#: Reaches tried, as multiples of the one asked for, to tell a user what would do instead.
_LARGER_REACHES = (1.5, 2.0, 3.0, 5.0)


def smallest_reach(spec: SectionSpec, popts: ProgramOptions) -> float | None:
    """The smallest of a few larger reaches (:data:`_LARGER_REACHES`) within which ``spec`` plans on its own.

    In the program's units (``popts.reach`` is the reach asked for, already inside the margin);
    None if none of them does.
    """
    for factor in _LARGER_REACHES:
        wider = dataclasses.replace(popts, reach=popts.reach * factor, singular_clearance=popts.singular_clearance * factor)
        if solve_program([dataclasses.replace(spec, turn=0.0)], wider).success:
            return popts.reach * factor
    return None


#: Largest defect of a collocation interval against the exact integration (relative, see
#: :mod:`skatetrace.planning.mesh`) before the plan is handed to the exact finish, and the rounds
#: of refinement allowed to reach it.
_MESH_TOL = 1e-5
_MESH_ROUNDS = 2


def _refine(plan: ProgramSolution, specs, popts: ProgramOptions) -> ProgramSolution:
    """Split the intervals whose defect exceeds ``_MESH_TOL`` and solve again, a few rounds at most."""
    for _ in range(_MESH_ROUNDS):
        errors = interval_errors(plan, specs, popts.M, popts.m, popts.I, popts.reach)
        if max(float(np.max(e)) for e in errors) <= _MESH_TOL:
            break
        meshes, guess, _n = refined(plan, errors, _MESH_TOL)
        again = solve_program(specs, dataclasses.replace(popts, mu_init=1e-4), guess=guess, meshes=meshes)
        if not again.success:
            break
        plan = again
    return plan


def _plan_curve(specs, popts: ProgramOptions) -> tuple[ProgramSolution | None, int | None, tuple[str, ...]]:
    """The curve as one program from the sections planned on their own, its mesh then refined.

    Where IPOPT cannot solve the linked program (the serpentine at 0.5 m: 1000 iterations), the
    sections are planned one after another instead, each from where the previous one left the
    mass (:func:`_one_after_another`). Returns the plan, the index of a section that has no plan
    on its own (else None) and how each section meets the one before (:func:`_finish_curve`).
    """
    guess, bad = _warm_start(specs, popts)
    if guess is None:
        return None, bad, ()
    links = ("start",) + ("impulse",) * (len(specs) - 1)
    if len(specs) == 1:
        return _refine(guess, specs, popts), None, links
    linked = dataclasses.replace(popts, barrier="monotone")
    plan = solve_program(specs, linked, guess=guess)
    if plan.success:
        return _refine(plan, specs, linked), None, links
    plan, links = _one_after_another(specs, popts, guess)
    return plan, None, links


def _one_after_another(specs, popts: ProgramOptions, guess: ProgramSolution):
    """Each section from where the previous one's plan left the mass (position on the ice), else from its own start.

    Returns the plan and the links: ``"impulse"`` where a section starts where the previous one
    ended (its velocity may jump), ``"jump"`` where it could not and starts from its own plan
    (the mass's position jumps: reported, never hidden).
    """
    sols, links = [], []
    for k, spec in enumerate(specs):
        alone = [dataclasses.replace(spec, turn=0.0)]
        own = _section_of(guess, k)
        sol, opts = None, popts
        if sols:
            end = RestState(float(sols[-1].states[0][2, -1]), float(sols[-1].states[0][3, -1]), 0.0, 0.0)
            moved = end.turned(spec.turn)
            # the previous plan may end on the reach's boundary, a few 1e-9 outside in round-off
            inside = min(1.0, popts.reach / max(math.hypot(moved.a, moved.b), 1e-300))
            opts = dataclasses.replace(popts, start_position=(moved.a * inside, moved.b * inside))
            sol = solve_program(alone, opts, guess=own, meshes=own.meshes)
        if sol is not None and sol.success:
            links.append("impulse")
        else:
            sol, opts = own, popts
            links.append("start" if k == 0 else "jump")
        sols.append(_refine(sol, alone, opts))
    return _chain(sols, "one after another"), tuple(links)


def plan_figure(figure: Figure, params: SleighParams | None = None, options: TraceOptions = TraceOptions(),
                progress=None) -> FigureTrace:
    """Plan and finish exactly every section of ``figure`` with the mass within ``options.reach``.

    Each curve is one program (:func:`_plan_curve`); each section is then finished exactly from
    the exact end of the one before, the mass's position on the ice carried through the cusp
    (turned by its pivot or reversal) and, where the program made it continuous, its velocity.
    Each section's ``metrics`` say how it meets the one before: ``link`` (``"start"`` for a
    curve's first section, ``"impulse"`` where the mass's position is carried on and its velocity
    may jump, ``"jump"`` where even its position could not be: see :func:`_plan_curve`), the
    impulse on the mass in N s (``link_impulse``) and the jump of its position (``link_jump``,
    zero up to round-off unless ``"jump"``).
    Never raises for a figure that cannot be planned: the sections that fail say why.
    """
    if options.reach is None:
        raise ValueError("plan_figure needs options.reach (a distance); reach=None keeps the launch-glide-stop tracer")
    params = params or figure.params or SleighParams()
    popts = _program_options(params, options)
    from .symbolic import sleigh_functions
    fn = sleigh_functions(popts.M, popts.m, popts.I)
    traces, starts, t = [], [], 0.0
    total = sum(len(c.sections()) for c in figure.curves)
    for ci, curve in enumerate(figure.curves):
        specs, sections = curve_specs(curve)
        curve_opts = popts
        plan, bad, links = _plan_curve(specs, curve_opts)
        if plan is None:
            curve_traces = _infeasible_curve(specs, sections, bad, ci, params, options, popts)
        else:
            curve_traces = _finish_curve(plan, links, specs, sections, ci, params, options, fn)
        for _ in range(_MARGIN_ROUNDS):
            # The exact motion strays from the plan by the collocation's error: where it leaves the
            # reach, plan again inside a reach shrunk by the excess (the plan as the guess). Where an
            # exact finish stalls (multiple shooting stuck near 1e-9 on a nearly singular Jacobian:
            # circle eight at 0.5 m, condition 2e10), the same with the reach 1 % smaller: a nearby
            # plan, whose finish converges.
            worst = max((tr.metrics.get("reach", 0.0) for tr in curve_traces if tr.metrics), default=0.0)
            stalled = any(tr.status is TraceStatus.RESIDUAL for tr in curve_traces)
            if plan is None or not plan.success or not (worst > options.reach or stalled):
                break
            factor = options.reach / worst if worst > options.reach else 1.0
            shrunk = dataclasses.replace(curve_opts, reach=curve_opts.reach * factor * 0.99)
            if plan.status == "one after another":
                again, again_links = _one_after_another(specs, shrunk, plan)
            else:
                again = solve_program(specs, dataclasses.replace(shrunk, barrier="monotone", mu_init=1e-4), guess=plan,
                                      meshes=plan.meshes)
                again_links = links
            if not again.success:
                break
            plan, curve_opts, links = again, shrunk, again_links
            curve_traces = _finish_curve(plan, links, specs, sections, ci, params, options, fn)
        for tr in curve_traces:
            traces.append(tr)
            starts.append(t)
            t += tr.duration if tr.phases else 0.0
            if progress is not None:
                progress(len(traces), total)
    return FigureTrace(figure=figure, params=params, options=options, sections=tuple(traces), start_times=tuple(starts))


#: Rounds of planning again inside a smaller reach when the exact motion leaves it or a finish stalls.
_MARGIN_ROUNDS = 2
#: Collocation intervals per shooting segment of the exact finish, longest first: over long
#: segments the integration's round-off, grown by the sleigh's instability, holds the continuity
#: residuals near 1e-9 (circle eight at 3); shorter ones reach 1e-10.
_STRIDES = (2, 1)


def _finish_curve(plan, links, specs, sections, ci, params, options, fn) -> list[SectionTrace]:
    """Each section of a planned curve finished exactly from the exact end of the one before.

    ``links[k]`` says how section ``k`` meets the one before: ``"start"`` (a curve's first
    section), ``"continuous"`` (the mass's position and velocity carried on), ``"impulse"`` (its
    position carried on, its velocity as planned) or ``"jump"`` (both as planned).
    """
    out = []
    arrived = None  # the exact end of the previous section, in this section's frame
    for k, (spec, sec) in enumerate(zip(specs, sections)):
        if arrived is not None:
            arrived = arrived.turned(spec.turn)
        if not plan.success:
            out.append(_failed(sec, ci, params, options, TraceStatus.NOT_PLANNED,
                               f"reach {options.reach:.4g}: IPOPT found no plan of the whole curve ({plan.message}), "
                               "although each section has one on its own"))
            continue
        X, times = plan.states[k], plan.times[k]
        r0, r1 = _rates(fn, X, spec, False), _rates(fn, X, spec, True)
        planned = RestState(float(X[2, 0]), float(X[3, 0]), float(r0[0]), float(r0[1]))
        kind = "start" if arrived is None and k == 0 else links[k]
        if arrived is None and kind in ("continuous", "impulse"):
            kind = "jump"  # the section before could not be finished: this one starts as planned
        start = {"start": planned, "jump": planned, "continuous": arrived,
                 "impulse": dataclasses.replace(planned, a=arrived.a, b=arrived.b) if arrived else None}[kind]
        target = RestState(float(X[2, -1]), float(X[3, -1]), float(r1[0]), float(r1[1]))
        for stride in _STRIDES:
            fin = finish_section(params, spec.pieces, times, X[5], start, target, X, stride=stride,
                                 rtol=options.rtol, atol=options.atol)
            if fin.success:
                break
        out.append(_section_trace(fin, sec, ci, params, options, spec, _link_metrics(kind, arrived, start, params,
                                                                                     options)))
        arrived = fin.end if fin.success else None
    return out


def _infeasible_curve(specs, sections, bad: int, ci, params, options, popts) -> list[SectionTrace]:
    """Every section of a curve failed, the one without a plan of its own saying which reach would do."""
    wider = smallest_reach(specs[bad], popts)
    scale = options.reach / popts.reach  # the program's reach is inside the margin
    hint = (f"; on its own it plans within {wider * scale:.4g}" if wider is not None else
            f"; on its own it plans within none of {', '.join(f'{f * options.reach:.4g}' for f in _LARGER_REACHES)}")
    out = []
    for k, sec in enumerate(sections):
        msg = (f"reach {options.reach:.4g}: no motion of the mass within the reach traces this section{hint}"
               if k == bad else f"reach {options.reach:.4g}: not planned, section {bad} of this curve has no motion "
                                f"within the reach")
        tr = _failed(sec, ci, params, options, TraceStatus.INFEASIBLE, msg)
        if k == bad:
            tr = dataclasses.replace(tr, metrics={"smallest_feasible_reach": None if wider is None else wider * scale})
        out.append(tr)
    return out


def _link_metrics(link: str, arrived: RestState | None, start: RestState, params: SleighParams,
                  options: TraceOptions) -> dict:
    """How the section meets the previous one: the kind, the impulse on the mass (N s) and the jump of its position."""
    if arrived is None:  # a curve's first section, or one after a section that could not be finished
        unknown = 0.0 if link == "start" else math.nan
        return {"link": link, "link_impulse": unknown, "link_jump": unknown}
    dv = math.hypot(start.adot - arrived.adot, start.bdot - arrived.bdot) * options.speed
    return {"link": link, "link_impulse": float(params.m * dv),
            "link_jump": float(math.hypot(start.a - arrived.a, start.b - arrived.b))}


def _failed(sec, ci, params, options, status, message) -> SectionTrace:
    return SectionTrace(success=False, status=status, message=message, curve_index=ci, section=sec, params=params,
                        speed=options.speed, glide={"segment": 0, "a": math.nan, "b": math.nan, "length": 0.0,
                                                    "kappa": math.nan, "speed": options.speed})


def _section_trace(fin, sec, ci, params, options, spec, link: dict) -> SectionTrace:
    if not fin.success:
        return _failed(sec, ci, params, options, TraceStatus.RESIDUAL, fin.message)
    phases = tuple(_Phase("plan", t0, t1, man, s0, 0.0, j) for t0, t1, man, s0, j in fin.intervals)
    glide = {"segment": 0, "a": fin.start.a, "b": fin.start.b, "length": 0.0,
             "kappa": spec.pieces[0].coefficients[0], "speed": options.speed, "planned": True}
    residuals = {k: abs(v) for k, v in fin.residuals.items()}
    trace = SectionTrace(success=True, status=TraceStatus.SUCCESS, message="planned and finished exactly",
                         curve_index=ci, section=sec, params=params, speed=options.speed, glide=glide, phases=phases,
                         residuals=residuals, nfev=fin.nfev)
    trace = _with_metrics(trace, _singular_distance(trace), options)
    reach = _certified_reach(trace)
    metrics = dict(trace.metrics, reach=reach, **link)
    if trace.success and reach > options.reach:
        return dataclasses.replace(trace, success=False, status=TraceStatus.INFEASIBLE, metrics=metrics,
                                   message=f"the exact motion reaches {reach:.4g} > reach {options.reach:.4g}")
    return dataclasses.replace(trace, metrics=metrics)


def _samples(trace: SectionTrace, n: int = 20001):
    """``n`` times spread over the section, its breakpoints among them, and the motion there."""
    t = np.unique(np.concatenate([np.linspace(0.0, trace.duration, n), trace.breakpoints()]))
    return t, trace.evaluate(t, geometry=False)


def _singular_distance(trace: SectionTrace) -> float:
    """Closest approach of the mass to the singular point, leg by leg as the tracer measures it."""
    return min(_singular_distances(trace.params, ph.maneuver.legs)[0] for ph in trace.phases)


def _certified_reach(trace: SectionTrace) -> float:
    """Largest distance of the mass from the contact point, bounded between the samples.

    Between samples ``dt`` apart the distance changes at most at the mass's speed relative to the
    blade, so it exceeds the larger sampled end by at most ``dt / 2`` times that speed's maximum
    over the interval; the larger speed at the two ends stands for it with half as much again.
    """
    t, v = _samples(trace)
    r = np.hypot(v["a"], v["b"])
    speed = np.hypot(v["adot"], v["bdot"])
    dt = np.diff(t)
    bound = np.maximum(r[:-1], r[1:]) + 0.5 * dt * np.maximum(speed[:-1], speed[1:]) * 1.5
    return float(max(np.max(r), np.max(bound) if bound.size else 0.0))
