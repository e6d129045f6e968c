"""Bounded-reach planning of a whole figure: collocation for the shape, the exact finish for the guarantee.

For each curve, in skating order:

1. every section is posed in its travel frame (:class:`~skatetrace.planning.collocation.SectionSpec`),
   with the turn that carries the mass's position from the end of one section into the next
   (pivots and reversals);
2. a warm start: the sections solved one after another by IPOPT from launch-glide-stop guesses,
   each starting where the previous one left the mass (if one cannot, it starts free);
3. the whole curve as one multi-phase program from that start: the position of the mass on the
   ice continuous through every cusp (a hard constraint), the jump of its velocity (an impulse)
   penalised as the effort of delivering it over ``impulse_time``;
4. the exact finish of every section (:func:`~skatetrace.planning.finish.finish_section`), each
   starting exactly where the previous one ended, and the reach checked between samples.

Sections come back as :class:`~skatetrace.tracing.sections.SectionTrace` objects (one phase per affine
piece of the control), so everything downstream (replay, outputs) treats them like any other.
A section that cannot be planned within the reach is returned as data (``TraceStatus.INFEASIBLE``).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from ..dynamics.model import SleighParams, curvature_coefficients
from ..figures.figure import Figure
from ..figures.geometry import end_pose
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
#: The plan keeps the mass within this fraction of the reach, so that the exact finish (which
#: moves the motion by the collocation's error) stays within it.
_REACH_MARGIN = 0.98


def curve_specs(curve, speed_scale: float = 1.0) -> tuple[list[SectionSpec], list]:
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
        max_accel=None if options.max_accel is None else options.max_accel / v2,
        max_rate=None if options.max_mass_speed is None else options.max_mass_speed / options.speed,
        singular_clearance=0.15 * options.reach, continuous_velocity=False, impulse_time=0.1,
        top_speed=TOP_SPEED,
    )


def _rates(fn, X, spec: SectionSpec, at_end: bool):
    piece = spec.pieces[-1] if at_end else spec.pieces[0]
    s0 = spec.length - piece.length if at_end else 0.0
    x = X[:, -1] if at_end else X[:, 0]
    return np.asarray(fn["rates"](x, 0.0, list(piece.coefficients), s0)).ravel()


def _warm_start(specs, popts) -> ProgramSolution | None:
    """Sections one after another, each from where the previous left the mass (else free)."""
    from .symbolic import sleigh_functions
    fn = sleigh_functions(popts.M, popts.m, popts.I)
    sols = []
    end = None
    for spec in specs:
        sol = None
        if end is not None:
            c, s = math.cos(spec.turn), math.sin(spec.turn)
            pos = (c * end[0] - s * end[1], s * end[0] + c * end[1])
            sol = solve_program([dataclasses.replace(spec, turn=0.0)], dataclasses.replace(popts, start_position=pos))
            if not sol.success:
                sol = None
        if sol is None:
            sol = solve_program([dataclasses.replace(spec, turn=0.0)], popts)
        if not sol.success:
            return None
        sols.append(sol)
        end = sol.states[0][2:4, -1]
    return ProgramSolution(success=True, status="warm start", message="warm start",
                           times=tuple(s.times[0] for s in sols), states=tuple(s.states[0] for s in sols),
                           controls=tuple(s.controls[0] for s in sols))


#: Largest defect of a collocation interval against the exact integration (relative, see
#: :mod:`skatetrace.planning.mesh`) before the plan is handed to the exact finish.
_MESH_TOL = 1e-5
_MESH_ROUNDS = 5


def _refine(plan: ProgramSolution, specs, popts) -> ProgramSolution:
    """Halve the intervals whose defect exceeds ``_MESH_TOL`` and solve again, a few rounds at most."""
    for _ in range(_MESH_ROUNDS):
        errors = interval_errors(plan, specs, popts.M, popts.m, popts.I, popts.reach)
        if max(float(np.max(e)) for e in errors) <= _MESH_TOL:
            break
        meshes, guess, _n = refined(plan, errors, _MESH_TOL)
        again = solve_program(specs, popts, guess=guess, meshes=meshes)
        if not again.success:
            break
        plan = again
    return plan


def plan_figure(figure: Figure, params: SleighParams | None = None, options: TraceOptions = TraceOptions(),
                progress=None) -> FigureTrace:
    """Plan and finish exactly every section of ``figure`` with the mass within ``options.reach``.

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
    done = 0
    for ci, curve in enumerate(figure.curves):
        specs, sections = curve_specs(curve)
        guess = _warm_start(specs, popts)
        plan = solve_program(specs, popts, guess=guess) if guess is not None else None
        plan = _refine(plan, specs, popts) if plan is not None and plan.success else plan
        prev_target = None
        for k, (spec, sec) in enumerate(zip(specs, sections)):
            if plan is None or not plan.success:
                why = ("no motion of the mass within the reach was found for a section on its own"
                       if plan is None else f"the planner did not converge ({plan.message})")
                tr = _failed(sec, ci, params, options, TraceStatus.INFEASIBLE,
                             f"reach {options.reach:.4g}: {why}")
            else:
                X, times, W = plan.states[k], plan.times[k], plan.controls[k]
                r0 = _rates(fn, X, spec, False)
                r1 = _rates(fn, X, spec, True)
                if prev_target is None:
                    start = RestState(float(X[2, 0]), float(X[3, 0]), float(r0[0]), float(r0[1]))
                else:
                    moved = prev_target.turned(spec.turn)
                    start = RestState(moved.a, moved.b, float(r0[0]), float(r0[1]))
                target = RestState(float(X[2, -1]), float(X[3, -1]), float(r1[0]), float(r1[1]))
                fin = finish_section(params, spec.pieces, times, X[5], start, target, X,
                                     rtol=options.rtol, atol=options.atol)
                tr = _section_trace(fin, sec, ci, params, options, spec)
                prev_target = fin.end if fin.success else target
            traces.append(tr)
            starts.append(t)
            t += tr.duration if tr.phases else 0.0
            done += 1
            if progress is not None:
                progress(done, total)
    return FigureTrace(figure=figure, params=params, options=options, sections=tuple(traces), start_times=tuple(starts))


def _failed(sec, ci, params, options, status, message) -> SectionTrace:
    return SectionTrace(success=False, status=status, message=message, curve_index=ci, section=sec, params=params,
                        speed=options.speed, glide={"segment": 0, "a": math.nan, "b": math.nan, "length": 0.0,
                                                    "kappa": math.nan, "speed": options.speed})


def _section_trace(fin, sec, ci, params, options, spec) -> SectionTrace:
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
    metrics = dict(trace.metrics, reach=reach)
    if trace.success and reach > options.reach:
        return dataclasses.replace(trace, success=False, status=TraceStatus.INFEASIBLE, metrics=metrics,
                                   message=f"the exact motion reaches {reach:.4g} > reach {options.reach:.4g}")
    return dataclasses.replace(trace, metrics=metrics)


def _samples(trace: SectionTrace, n: int = 20001):
    t = np.unique(np.concatenate([np.linspace(0.0, trace.duration, n), trace.breakpoints()]))
    return t, trace.evaluate(t, geometry=False)


def _singular_distance(trace: SectionTrace) -> float:
    _t, v = _samples(trace, 4001)
    kap = np.array([trace.section.pieces[j].segment.curvature_at(0.0) for j in v["segment"]])
    return float(np.min(np.hypot(v["a"], v["b"] + kap * trace.params.I / trace.params.M)))


def _certified_reach(trace: SectionTrace) -> float:
    """Largest distance of the mass from the contact point, bounded between the samples.

    Between samples ``dt`` apart the distance changes at most at the mass's speed relative to the
    blade, so it exceeds the larger sampled end by at most ``dt / 2`` times that speed's maximum.
    """
    t, v = _samples(trace)
    r = np.hypot(v["a"], v["b"])
    speed = np.hypot(v["adot"], v["bdot"])
    dt = np.diff(t)
    bound = np.maximum(r[:-1], r[1:]) + 0.5 * dt * np.maximum(speed[:-1], speed[1:]) * 1.5
    return float(max(np.max(r), np.max(bound) if bound.size else 0.0))
