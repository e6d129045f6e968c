"""Bounded-reach planning of a whole figure: collocation for the shape, the exact finish for the guarantee.

For each curve, in skating order:

1. every section is posed in its travel frame (:class:`~skatetrace.planning.collocation.SectionSpec`),
   with the turn that carries the mass's position from the end of one section into the next
   (pivots and reversals);
2. a warm start (:func:`_warm_start`): every distinct section planned on its own by IPOPT from a
   launch-glide-stop guess, the mass pinned on the blade's line ahead of the contact point at
   every cusp, so that the chain of sections is already continuous on the ice;
3. the whole curve as one multi-phase program from that chain: the position of the mass on the
   ice continuous through every cusp (a hard constraint), the jump of its velocity (an impulse)
   penalised as the effort of delivering it over ``impulse_time``; where IPOPT cannot solve it,
   the chain itself is the plan. A closed curve that repeats a unit of sections, as itself or
   mirrored (:func:`_period`), is solved as that unit (:func:`_linked_job`);
4. the exact finish of every section (:func:`~skatetrace.planning.finish.finish_section`), each
   starting exactly where the previous one ended, and the reach checked between samples; where
   a finish stalls, the plan's mesh is refined against the compiled integrator
   (:mod:`skatetrace.planning.mesh`), and where the exact motion leaves the reach, the curve is
   planned again inside a smaller one.

Sections come back as :class:`~skatetrace.tracing.sections.SectionTrace` objects (one phase per affine
piece of the control), so everything downstream (replay, outputs) treats them like any other.
A section that cannot be planned within the reach is returned as data (``TraceStatus.INFEASIBLE``,
with the smallest of a few larger reaches within which it plans on its own), a section whose exact
finish does not converge as ``TraceStatus.RESIDUAL``.
"""

from __future__ import annotations

import contextlib
import dataclasses
import math
import pickle

import numpy as np

from ..dynamics.model import SleighParams
from ..dynamics.presets import IMPULSE_TIME
from ..figures.figure import Figure
from ..figures.geometry import end_pose
from ..tracing.sections import FigureTrace, SectionTrace, TraceOptions, TraceStatus
from .collocation import PieceSpec, ProgramOptions, ProgramSolution, SectionSpec, program_too_large, program_unknowns
from .finish import _RESIDUAL_TOL, RestState, finish_section
from .mesh import interval_errors, refined
from .nlp import GiveUp
from .pool import BudgetSpent, charged_in_order, solve_programs, spending
from .traced import failed, link_metrics, section_trace

__all__ = ["plan_figure", "curve_specs", "figure_unknowns", "DURATION_PER_LENGTH", "TOP_SPEED"]

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


def figure_unknowns(figure: Figure, params: SleighParams | None, options: TraceOptions) -> int:
    """The unknowns of the programs that plan ``figure`` within ``options.reach``, a program per
    curve on its default mesh: what planning it costs (IPOPT's iterations grow dearer with it)."""
    popts = _program_options(params or figure.params or SleighParams(), options)
    return sum(program_unknowns(curve_specs(curve)[0], popts) for curve in figure.curves)


def _closing_turn(curve, sections) -> float | None:
    """The turn from a closed curve's end into its start (skated again from where it ends); None if it is open."""
    if not curve.closure()["closed"]:
        return None
    last = sections[-1].pieces[-1]
    return end_pose(last.start, last.segment).heading - sections[0].pieces[0].start.heading


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
        singular_clearance=0.15 * options.reach, continuous_velocity=False,
        impulse_time=IMPULSE_TIME * options.speed, tol=1e-6,  # in the program's time, a glide at speed 1
        top_speed=TOP_SPEED, iteration_budget=_SECTION_BUDGET,
    )


#: A section planned on its own gets at most this many IPOPT iterations over its unknowns (and at
#: most 500): the school figures' sections (at most 2,560 unknowns) keep their 500; a drawing's
#: section of 9,200 (the most a program may have) gets 166, where 500 took minutes.
_SECTION_BUDGET = 1_530_000


def _rates(fn, X, spec: SectionSpec, at_end: bool):
    piece = spec.pieces[-1] if at_end else spec.pieces[0]
    s0 = spec.length - piece.length if at_end else 0.0
    x = X[:, -1] if at_end else X[:, 0]
    return np.asarray(fn["rates"](x, 0.0, list(piece.coefficients), s0)).ravel()


#: Where the warm start puts the mass at a cusp: on the blade's line, this fraction of the reach
#: ahead of the contact point in the next section's direction of travel. The linked programs of
#: the circle eight and the three put it there (0.57-0.73 of the reach); sections planned with
#: free ends put it at opposite ends of the reach instead (behind at a start, ahead at a stop),
#: 0.98 m apart at 0.5 m, which the linked program then had to undo, or could not.
_CUSP_AHEAD = 0.6


def _cusp_pins(specs, reach: float, closing_turn: float | None = 0.0) -> list[tuple]:
    """Per section, the mass's position at its start and end in the warm start.

    At every cusp :data:`_CUSP_AHEAD` of the reach ahead of the contact point, and so at the
    curve's own start and end too, as if the curve were skated again (``closing_turn`` from its
    end to its start: 0 or None for an open curve). Left free there, the ends went where the replay is
    ill-conditioned: the rocker's and the bracket's final rests replayed at 3e-7 and 7e-8 of
    their fastest motion, against 7e-9 and 8e-9 pinned.
    """
    ahead = _CUSP_AHEAD * reach
    pins = []
    for k in range(len(specs)):
        turn = specs[k + 1].turn if k + 1 < len(specs) else (closing_turn or 0.0)
        # the next section's start carried back through the cusp: (a, b)_end = R(-turn) (ahead, 0)
        pins.append(((ahead, 0.0), (ahead * math.cos(turn), -ahead * math.sin(turn))))
    return pins


def _pin_key(q, sign, reach: float):
    """A pin to 10 digits of the reach (+0.0 for -0.0), mirrored by ``sign``; None for a free end.

    Pins of mirrored sections come from one cos and sin and differ by round-off (3.6e-17
    against -3.6e-17 on the paragraph three).
    """
    return None if q is None else tuple(round(v / reach, 10) + 0.0 for v in (q[0], sign * q[1]))


def _warm_key(spec: SectionSpec, start, end, reach: float, guessed: bool = False):
    """What makes two warm-start programs the same up to a mirror, and the mirror's sign."""
    key, sign = _shape_key(spec)
    return (key, _pin_key(start, sign, reach), _pin_key(end, sign, reach), guessed), sign


def _warm_options(popts: ProgramOptions, start, end) -> ProgramOptions:
    return dataclasses.replace(popts, start_position=start, end_position=end, closing_turn=None)


#: A warm start from the launch-glide-stop guess still 1e-3 off its constraints after 200 IPOPT
#: iterations is given up for its fallbacks (free ends, then pinned again). Of 325 warm starts
#: (the school figures at 1.5-2.0 m, 57 drawings) those that converged were within 2e-5 by then;
#: those it gives up failed after 352-500 (negative-scale with --reach: 9.2 -> 5.6 s, the same
#: plan). A plan's budget counts it at its cap (``ProgramSolution.work``): counted as run, the work
#: saved went to later programs, one at a time, and plans that spent the budget took longer.
#: One past 200 iterations, within 1e-5 of its constraints at each of the last 51 iterates and its
#: objective down by less than 1 % over them, stalls instead: its last iterate is kept where it is
#: feasible (as at IPOPT's iteration limit). Of 269 such warm starts (the school figures at 1.5-1.9
#: m, the 57 corpus drawings at 6 m; 2026-11-29) this stopped three, all of which had crawled on to
#: the limit of 500 without converging, their barrier at its least: feather-aperture's circle
#: (1,508 unknowns, at 200; the drawing is now planned, where the budget ran out before), the
#: circle eight's for a 1.9 m skater (1,432, at 389; its plan's effort 2.03e5 -> 1.56e5) and one
#: of ionicons-bicycle's (691, at 200). Every other warm start took the same path. (Within 1e-6,
#: the circle eight's, 1e-6 to 5e-4 off now and then, ran on.)
_WARM_GIVE_UP = GiveUp(200, 1e-3, window=50, decrease=0.01, feasible=1e-5)


def _warm_job(spec: SectionSpec, popts: ProgramOptions, start, end, guess: ProgramSolution | None = None) -> tuple:
    """The warm-start program of one section, pinned at ``start``/``end`` (None: free), as a job of
    :func:`~skatetrace.planning.pool.solve_programs`; from ``guess`` (a free plan pulled onto the pins).
    From the launch-glide-stop guess it is given up where it goes nowhere (:data:`_WARM_GIVE_UP`)."""
    opts = _warm_options(popts, start, end)
    opts = _linked_options(opts) if guess is not None else dataclasses.replace(opts, give_up=_WARM_GIVE_UP)
    return [dataclasses.replace(spec, turn=0.0)], opts, guess, None if guess is None else guess.meshes


def _cached(solved: dict, spec: SectionSpec, start, end, reach: float, guessed: bool = False) -> ProgramSolution:
    """A solved warm-start program of ``solved`` (keyed by :func:`_warm_key`), mirrored to ``spec``'s side."""
    key, sign = _warm_key(spec, start, end, reach, guessed)
    sol, solved_sign = solved[key]
    return sol if sign == solved_sign or not sol.success else _mirrored(sol)


def _presolved(curves: list[tuple[list[SectionSpec], ProgramOptions]], workers: int | None) -> dict:
    """The warm-start programs of every curve (:func:`_warm_start`), each distinct one solved once.

    Solved side by side (:func:`~skatetrace.planning.pool.solve_programs`) in up to three batches,
    as :func:`_warm_start` would one after another: the sections pinned at the cusps; then, for
    those with no pinned plan, the same sections with free ends; then, from each free plan, the
    section pinned again. (One after another, octicons-infinity's two sections without a pinned
    plan took 14 s.) Returns the cache :func:`_warm_start` reads, keyed like it. A curve with a
    section too large to plan (:func:`~skatetrace.planning.collocation.program_too_large`) is left
    out: the three turn in exact mode spent 88 s on the programs of four sections beside its
    fifth, refused.
    """
    todo = []  # (spec, options, start pin, end pin, the curve's index) of every section of a curve that can be planned
    for ci, (specs, popts) in enumerate(curves):
        if any(program_too_large([spec], popts) for spec in specs):
            continue  # the curve cannot be planned (:func:`_warm_start` stops at that section): nothing to solve
        for spec, (start, end) in zip(specs, _cusp_pins(specs, popts.reach, popts.closing_turn)):
            todo.append((spec, popts, start, end, ci))
    solved: dict = {}

    def batch(stage: str, wanted) -> None:
        jobs: dict = {}
        for spec, popts, start, end, guess in wanted:
            key, sign = _warm_key(spec, start, end, popts.reach, guess is not None)
            if key not in solved and key not in jobs:
                jobs[key] = (_warm_job(spec, popts, start, end, guess), sign)
        if not jobs:
            return
        sols = solve_programs([job for job, _sign in jobs.values()], workers, stage)
        solved.update({key: (sol, sign) for (key, (_job, sign)), sol in zip(jobs.items(), sols)})

    batch("warm starts", [(spec, popts, start, end, None) for spec, popts, start, end, _ci in todo])
    unpinned = [(spec, popts, start, end, ci) for spec, popts, start, end, ci in todo
                if not _cached(solved, spec, start, end, popts.reach).success]
    batch("warm starts with free ends", [(spec, popts, None, None, None) for spec, popts, _s, _e, _ci in unpinned])
    again, stopped = [], set()
    for spec, popts, start, end, ci in unpinned:
        free = _cached(solved, spec, None, None, popts.reach)
        if not free.success:
            stopped.add(ci)  # :func:`_warm_start` stops at this section: the curve's later ones are not needed
        elif ci not in stopped:
            again.append((spec, popts, start, end, free))
    batch("warm starts pinned again", again)
    return solved


def _warm_start(specs, popts: ProgramOptions, solved: dict | None = None
                ) -> tuple[ProgramSolution | None, int | None, tuple[bool, ...]]:
    """Every section on its own, the mass pinned at the cusps (:data:`_CUSP_AHEAD`): the start of the linked program.

    Pinned at the same place on both sides of every cusp, the sections chain with the mass's
    position on the ice continuous; only its velocity may jump. A section that cannot be planned
    pinned is planned with free ends. Sections with the same pieces and pins, or mirrored ones,
    share one solve: school figures repeat and mirror theirs. Returns the guess and, per section,
    whether its start continues the previous section's end (False for the first); or None and
    the index of the first section that has no plan on its own. ``solved`` is a cache of the
    programs already solved (:func:`_presolved`), filled with those solved here.
    """
    solved = {} if solved is None else solved

    def solve(spec, start, end, guess=None):
        key, sign = _warm_key(spec, start, end, popts.reach, guess is not None)
        if key not in solved:  # with guess: a free plan of the same section, pulled onto the pins
            solved[key] = (solve_programs([_warm_job(spec, popts, start, end, guess)], 1, "warm starts")[0], sign)
        return _cached(solved, spec, start, end, popts.reach, guess is not None)

    large = next((k for k, spec in enumerate(specs) if program_too_large([spec], popts)), None)
    if large is not None:
        return None, large, ()
    sols, pinned = [], []
    for k, (spec, (start, end)) in enumerate(zip(specs, _cusp_pins(specs, popts.reach, popts.closing_turn))):
        sol, on_pins = solve(spec, start, end), True
        if not sol.success:
            # IPOPT may not find the pinned plan from the launch-glide-stop guess (paragraph three's
            # second circle, 500 iterations) but from the plan with free ends (9 s); else the free plan
            sol, on_pins = solve(spec, None, None), False
            if sol.success:
                again = solve(spec, start, end, guess=sol)
                if again.success:
                    sol, on_pins = again, True
        if not sol.success:
            return None, k, ()
        sols.append(sol)
        pinned.append(on_pins)
    continues = tuple(k > 0 and pinned[k - 1] and pinned[k] for k in range(len(specs)))
    return _chain(sols, "warm start"), None, continues


def _shape_key(spec: SectionSpec) -> tuple[tuple, int]:
    """What makes two sections the same program up to a mirror (to 12 digits), and the mirror's sign.

    The sign is that of the first non-zero curvature coefficient: a section and its mirror image
    have the same key and opposite signs.
    """
    coefficients = [c for p in spec.pieces for c in p.coefficients]
    sign = next((1 if c > 0 else -1 for c in coefficients if c != 0.0), 1)
    key = tuple((tuple(float(f"{sign * c:.12g}") for c in p.coefficients), float(f"{p.length:.12g}"))
                for p in spec.pieces)
    return key, sign


def _mirrored(sol: ProgramSolution) -> ProgramSolution:
    """The plan of the mirror image of a single section: ``p1`` and ``b`` change sign, the rest is kept.

    Mirroring the ice (``y -> -y``) turns every curvature, the heading's rate, the angular
    momentum ``p1`` and the mass's lateral offset ``b`` to their opposites and keeps ``p2``, ``a``,
    the arc length and the free control ``u`` (:mod:`skatetrace.planning.symbolic`); the effort,
    the reach and the clearance from the mirrored singular point are unchanged.
    """
    states = sol.states[0].copy()
    states[[0, 3]] *= -1.0
    return dataclasses.replace(sol, states=(states,))


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
        wider = dataclasses.replace(popts, reach=popts.reach * factor, singular_clearance=popts.singular_clearance * factor,
                                    closing_turn=None)
        if solve_programs([([dataclasses.replace(spec, turn=0.0)], wider, None, None)], 1, "larger reaches")[0].success:
            return popts.reach * factor
    return None


#: Largest defect of a collocation interval against the exact integration (relative, see
#: :mod:`skatetrace.planning.mesh`) that a plan whose exact finish stalls is refined to.
_MESH_TOL = 1e-5
#: The linked program starts from a feasible chain (the warm start): a small barrier parameter
#: takes a third to a half fewer iterations (circle eight 38 against 137; 1e-5 and 1e-6 did worse
#: over the school figures at 1.7 and 1.9 m, 2026-11-29), and a program that has not converged in
#: this many iterations is left for the chain (or kept where its last iterate is feasible). The
#: school figures' converge in 17 to 104 within 0.5 m; one that does not crawls (bootstrap-bezier2's
#: curve of 16 sections still lowered its effort by 0.1 % per ten iterations at 300, after 88 s).
_LINKED_MU = 1e-4
_LINKED_ITER = 150
#: A larger linked program gets fewer iterations: at most this many over its unknowns (and at
#: least a quarter of ``_LINKED_ITER``). IPOPT's time an iteration grows with the program, and a
#: drawing's big program spends most of its iterations crawling: fontawesome-feather's curve of 7
#: sections lowered its effort from 124 to 51 in 46 iterations and to 45 in 150 (37 s), still not
#: converged. The school figures' (at most 3,860 unknowns, 104 iterations) are not touched.
_LINKED_BUDGET = 575_000
#: Within a plan's budget (:func:`~skatetrace.planning.pool.spending`) the linked programs, which
#: only improve the chain, spend at most this share of what the warm starts left (a drawing's ran
#: on until nothing was left to finish the chain with); the school figures' use at most 0.63 of it.
_LINKED_SHARE = 0.75


def _linked_options(popts: ProgramOptions) -> ProgramOptions:
    return dataclasses.replace(popts, barrier="monotone", mu_init=_LINKED_MU, max_iter=_LINKED_ITER,
                               iteration_budget=_LINKED_BUDGET, give_up=None)  # it starts from a plan


def _same_turn(x: float, y: float) -> bool:
    """Whether two turns are the same angle (to 1e-9 rad, modulo a full turn)."""
    return abs(math.remainder(x - y, 2.0 * math.pi)) <= 1e-9


def _period(specs, popts: ProgramOptions) -> tuple[int, int] | None:
    """The shortest unit a closed curve repeats, and whether each repeat is its mirror image (-1) or itself (1).

    Sections ``k`` and ``k + p`` must be the same program up to that mirror (:func:`_shape_key`)
    and meet the section before by the same turn (mirrored), the curve's closing turn standing for
    the turn into section 0; None where no unit shorter than the curve does (or the curve is open).
    """
    n = len(specs)
    if popts.closing_turn is None or n < 2:
        return None
    keys = [_shape_key(spec) for spec in specs]
    turns = [popts.closing_turn] + [spec.turn for spec in specs[1:]]
    for p in range(1, n // 2 + 1):
        if n % p:
            continue
        mirror = keys[p][1] * keys[0][1]
        if all(keys[k][0] == keys[(k + p) % n][0] and keys[k][1] * keys[(k + p) % n][1] == mirror
               and _same_turn(turns[(k + p) % n], mirror * turns[k]) for k in range(n)):
            return p, mirror
    return None


def _sections_of(plan: ProgramSolution, ks) -> ProgramSolution:
    """The sections ``ks`` of a plan (each mirrored where ``ks`` gives it as ``(k, True)``), as a chain of their own."""
    out = []
    for k in ks:
        k, flip = k if isinstance(k, tuple) else (k, False)
        one = _section_of(plan, k)
        out.append(_mirrored(one) if flip else one)
    return dataclasses.replace(_chain(out, plan.status), success=plan.success, status=plan.status,
                               message=plan.message, objective=plan.objective, iterations=plan.iterations)


def _job_key(job: tuple) -> bytes:
    """What makes two programs the same: sections and options to 12 digits (as the warm starts are
    shared, :func:`_shape_key`: strokes drawn alike differ in round-off once scaled), the guess's
    nodes and the meshes. The plan is only the start of each curve's exact finish, which is its own."""
    specs, popts, guess, meshes = job

    def g(v: float) -> float:
        return float(f"{v:.12g}")

    sections = tuple((tuple((tuple(g(c) for c in pc.coefficients), g(pc.length)) for pc in spec.pieces), g(spec.turn),
                      g(spec.duration)) for spec in specs)
    turn = popts.closing_turn
    popts = dataclasses.replace(popts, closing_turn=None if turn is None else g(turn))
    return pickle.dumps((sections, popts, guess.times, guess.states, guess.controls, meshes))


def _linked_job(specs, popts: ProgramOptions, guess: ProgramSolution, meshes):
    """The linked program of a curve as a job for :func:`~skatetrace.planning.pool.solve_programs`, and how to read its answer.

    A closed curve that repeats a unit of sections (:func:`_period`: every school figure skates
    the same sections on the other foot, mirrored) is solved as that unit, its last section
    linked to the (mirror image of the) first: by the symmetry, a stationary point of the unit's
    program is one of the whole curve's, at a fraction of the cost (the paragraph double three's
    ten sections in five). Returns the job and a function that makes the whole curve's plan of
    the job's answer.
    """
    period = _period(specs, popts)
    if period is None:
        return (specs, popts, guess, meshes), lambda sol: sol
    p, mirror = period
    unit = dataclasses.replace(popts, closing_turn=specs[p % len(specs)].turn, closing_mirror=mirror < 0)
    job = (specs[:p], unit, _sections_of(guess, range(p)), meshes[:p])

    def whole(sol: ProgramSolution) -> ProgramSolution:
        if len(sol.states) != p:
            return sol
        return _sections_of(sol, [(k % p, mirror < 0 and (k // p) % 2 == 1) for k in range(len(specs))])
    return job, whole


def _plan_curves(curves: list[tuple[list[SectionSpec], ProgramOptions]], workers: int | None,
                 all_or_nothing: bool = False
                 ) -> list[tuple[ProgramSolution | None, int | None, tuple[str, ...], bool, ProgramSolution | None]]:
    """Each curve as one program from its warm start (:func:`_warm_start`), else the warm start itself.

    Returns per curve: the plan, the index of a section that has no plan on its own (else None),
    how each section meets the one before (:func:`_finish_curve`), whether the plan is the
    linked program's, and the linked program's last iterate where it ran out of iterations
    (else None: see :func:`_unconverged`). Where IPOPT cannot solve the linked program, the warm
    start's chain is the plan: the mass's position on the ice is continuous wherever both
    sections were planned pinned at the cusp (``"impulse"``), and jumps where one could not be
    (``"jump"``: reported, never hidden). The distinct warm-start programs of all curves, then
    the curves' linked programs, are solved side by side in ``workers`` processes
    (:mod:`skatetrace.planning.pool`). With ``all_or_nothing``, no linked program is solved once
    a curve has a section without a plan of its own (:attr:`TraceOptions.all_or_nothing`).
    """
    solved = _presolved(curves, workers)
    warm = [_warm_start(specs, popts, solved) for specs, popts in curves]
    unplanned = all_or_nothing and any(guess is None for guess, _bad, _c in warm)
    linking = [i for i, ((specs, _popts), (guess, _bad, _c)) in enumerate(zip(curves, warm))
               if guess is not None and len(specs) > 1 and not unplanned]
    jobs = [_linked_job(curves[i][0], _linked_options(curves[i][1]), warm[i][0], warm[i][0].meshes) for i in linking]
    # Curves drawn alike (the same sections, pins and guess: a row of identical strokes) are the
    # same program: each distinct one is solved once (15 identical strokes took 15 solves).
    distinct: dict[bytes, tuple] = {}
    keys = [_job_key(job) for job, _whole in jobs]
    for key, (job, _whole) in zip(keys, jobs):
        distinct.setdefault(key, job)
    sols = solve_programs(list(distinct.values()), workers, "linked programs", share=_LINKED_SHARE)
    solved = dict(zip(distinct, sols))
    linked = {i: whole(solved[key]) for i, (_job, whole), key in zip(linking, jobs, keys)}
    out = []
    for i, (specs, _popts) in enumerate(curves):
        guess, bad, continues = warm[i]
        if guess is None:
            out.append((None, bad, (), False, None))
        elif i in linked and linked[i].success:
            out.append((linked[i], None, ("start",) + ("impulse",) * (len(specs) - 1), True, None))
        else:
            links = tuple("start" if k == 0 else ("impulse" if c else "jump") for k, c in enumerate(continues))
            ran_out = i in linked and linked[i].status == "Maximum_Iterations_Exceeded" \
                and len(linked[i].states) == len(specs)
            out.append((guess, None, links, False, linked[i] if ran_out else None))
    return out


def _unconverged(candidate: ProgramSolution, specs, sections, ci, params, options, fn) -> list[SectionTrace] | None:
    """A linked program's last iterate (out of iterations) finished exactly, if every section finishes within the reach.

    Such a program may still be crawling towards its optimum far below the chain's effort (the
    paragraph double three skated backwards for a 1.6 m skater: 26 against the chain's 85 after
    150 iterations, its constraints met to 2e-3). The plan is only the exact finish's start: where
    the finish converges and the certified reach holds, the exact motion carries every guarantee
    of a converged plan; else None, and the chain is the plan.
    """
    traces = _finish_curve(candidate, ("start",) + ("impulse",) * (len(specs) - 1), specs, sections, ci, params,
                           options, fn, whole=True)
    return traces if all(tr.success for tr in traces) else None


def _replan(plan: ProgramSolution, specs, popts: ProgramOptions, links, linked: bool, guess=None,
            meshes=None, workers: int | None = 1) -> ProgramSolution:
    """The program that made ``plan`` solved again with ``popts`` (or on ``meshes``), from ``guess`` (default the plan).

    A linked plan is solved again as one program; a chain section by section, each pinned where
    the plan has the mass continuous through a cusp (``links``): the sections' programs side by
    side in ``workers`` processes, each distinct one once (a drawing repeats its sections, and
    sections with the same pieces, pins, guess and mesh are the same program: feather-settings
    solved 114 programs for 39 sections, many of them the same).
    """
    guess = plan if guess is None else guess
    meshes = plan.meshes if meshes is None else meshes
    if linked:
        job, whole = _linked_job(specs, _linked_options(popts), guess, meshes)
        return whole(solve_programs([job], 1, "programs again")[0])
    jobs: dict[bytes, tuple] = {}
    keys = []
    for k, spec in enumerate(specs):
        X = guess.states[k]
        start = (float(X[2, 0]), float(X[3, 0])) if links[k] == "impulse" else None
        end = (float(X[2, -1]), float(X[3, -1])) if k + 1 < len(specs) and links[k + 1] == "impulse" else None
        opts = dataclasses.replace(popts, mu_init=_LINKED_MU, start_position=start, end_position=end, closing_turn=None)
        job = ([dataclasses.replace(spec, turn=0.0)], opts, _section_of(guess, k), meshes[k:k + 1])
        key = pickle.dumps((job[0], opts, guess.times[k], X, guess.controls[k], meshes[k]))
        jobs.setdefault(key, job)
        keys.append(key)
    solved = dict(zip(jobs, solve_programs(list(jobs.values()), workers, "programs again")))
    sols = [solved[key] for key in keys]
    failed = next((sol for sol in sols if not sol.success), None)
    return failed if failed is not None else _chain(sols, "warm start")


def _refine(plan: ProgramSolution, specs, popts: ProgramOptions, links, linked: bool,
            workers: int | None = 1) -> ProgramSolution | None:
    """The plan on a mesh refined where its defect exceeds ``_MESH_TOL``; None if no interval does, or IPOPT fails."""
    errors = interval_errors(plan, specs, popts.M, popts.m, popts.I, popts.reach)
    if max(float(np.max(e)) for e in errors) <= _MESH_TOL:
        return None
    meshes, guess, _n = refined(plan, errors, _MESH_TOL)
    again = _replan(plan, specs, popts, links, linked, guess=guess, meshes=meshes, workers=workers)
    return again if again.success else None


def plan_figure(figure: Figure, params: SleighParams | None = None, options: TraceOptions = TraceOptions(),
                progress=None) -> FigureTrace:
    """Plan and finish exactly every section of ``figure`` with the mass within ``options.reach``.

    Each curve is one program (:func:`_plan_curves`); each section is then finished exactly from
    the exact end of the one before, the mass's position on the ice carried through the cusp
    (turned by its pivot or reversal) and, where the program made it continuous, its velocity.
    Each section's ``metrics`` say how it meets the one before: ``link`` (``"start"`` for a
    curve's first section, ``"impulse"`` where the mass's position is carried on and its velocity
    may jump, ``"jump"`` where even its position could not be: see :func:`_plan_curves`), the
    impulse on the mass in N s (``link_impulse``) and the jump of its position (``link_jump``,
    zero up to round-off unless ``"jump"``).
    With ``options.plan_budget``, the programs' IPOPT work is bounded (:func:`~skatetrace.planning.pool.spending`):
    once it is spent, no further program is solved, and the sections of the curves not yet
    finished are ``OVER_BUDGET``, saying so (the curves finished before are kept).
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
    curves = []
    for curve in figure.curves:
        specs, sections = curve_specs(curve)
        curves.append((specs, sections, dataclasses.replace(popts, closing_turn=_closing_turn(curve, sections))))
    spent = None  # why the budget stopped the planning (options.plan_budget), once it has
    # without a budget of its own, the plan counts against a caller's (pool.spending), if any
    with contextlib.nullcontext() if options.plan_budget is None else spending(int(options.plan_budget)):
        try:
            plans = _plan_curves([(specs, curve_opts) for specs, _sections, curve_opts in curves], options.workers,
                                 options.all_or_nothing)
        except BudgetSpent as exc:
            plans, spent = [(None, None, (), False, None)] * len(curves), str(exc)
        # all or nothing: where a curve has a section without a plan, no curve is finished
        stop = next((f"reach {options.reach:.4g}: not planned: section {bad} of curve {ci} has no motion within the "
                     "reach (all or nothing)" for ci, (plan, bad, *_rest) in enumerate(plans) if plan is None),
                    None) if options.all_or_nothing and spent is None else None
        # the curves side by side, their programs charged in order: the same as one after another
        done, spent = ([], spent) if spent is not None else charged_in_order(
            lambda ci: _planned_curve(curves[ci], plans[ci], ci, params, options, fn, stop), range(len(curves)),
            options.workers)
        for ci, (_specs, sections, _opts) in enumerate(curves):
            curve_traces = done[ci] if ci < len(done) else [
                failed(sec, ci, params, options, TraceStatus.OVER_BUDGET, f"reach {options.reach:.4g}: not planned: "
                       f"{spent}") for sec in sections]
            for tr in curve_traces:
                traces.append(tr)
                starts.append(t)
                t += tr.duration if tr.phases else 0.0
                if progress is not None:
                    progress(len(traces), total)
    return FigureTrace(figure=figure, params=params, options=options, sections=tuple(traces), start_times=tuple(starts))


def _planned_curve(curve, entry, ci, params, options, fn, stop: str | None) -> list[SectionTrace]:
    """A curve of :func:`plan_figure` finished (``entry``: its entry of :func:`_plan_curves`).

    ``stop`` says why no curve is finished (all or nothing), if anything does. Raises
    :class:`~skatetrace.planning.pool.BudgetSpent` where its programs spend the plan's budget.
    """
    (specs, sections, curve_opts), (plan, bad, links, linked, candidate) = curve, entry
    try:
        if stop is not None and plan is not None:
            return [failed(sec, ci, params, options, TraceStatus.NOT_PLANNED, stop) for sec in sections]
        if plan is None:
            return _infeasible_curve(specs, sections, bad, ci, params, options, curve_opts)
        traces = None if candidate is None else _unconverged(candidate, specs, sections, ci, params, options, fn)
        if traces is not None:
            return traces
        return _mended(plan, links, linked, specs, sections, ci, params, options, curve_opts, fn)
    except (ArithmeticError, ValueError, np.linalg.LinAlgError) as exc:
        # A plan whose exact motion diverges can reach numbers that the finish or the mesh
        # refinement refuse (an infinite defect raised OverflowError on a corpus drawing under
        # the default reach, vivus-hi-there). The curve is reported as not planned, with the
        # error, and the other curves are still planned (the command line then falls back to
        # the launch-glide-stop manoeuvres), instead of the whole run ending in a traceback.
        why = f"reach {options.reach:.4g}: the planner failed on this curve ({type(exc).__name__}: {exc})"
        return [failed(sec, ci, params, options, TraceStatus.NOT_PLANNED, why) for sec in sections]


def _mended(plan, links, linked, specs, sections, ci, params, options, popts, fn) -> list[SectionTrace]:
    """The curve's plan finished exactly, then planned again where the exact motion falls short.

    Where an exact finish stalls (multiple shooting stuck near 1e-9 on a nearly singular
    Jacobian, or the blade coming to rest inside a section), the plan is first refined where its
    collocation errs; where the exact motion leaves the reach (it strays from the plan by the
    collocation's error), or the finish still stalls, it is planned again inside a reach shrunk
    by the excess (and by 1 %: a nearby plan, whose finish converges), the plan as the guess.
    """
    traces = _finish_curve(plan, links, specs, sections, ci, params, options, fn)
    curve_opts, refinable = popts, True
    for _ in range(_MARGIN_ROUNDS):
        worst = max((tr.metrics.get("reach", 0.0) for tr in traces if tr.metrics), default=0.0)
        stalled = any(tr.status in (TraceStatus.RESIDUAL, TraceStatus.EXCURSION) for tr in traces)
        if not (worst > options.reach or stalled):
            break
        again = None
        if stalled and refinable:
            refinable = False
            again = _refine(plan, specs, curve_opts, links, linked, options.workers)
        if again is None:
            factor = options.reach / worst if worst > options.reach else 1.0
            shrunk = dataclasses.replace(curve_opts, reach=curve_opts.reach * factor * 0.99)
            again = _replan(plan, specs, shrunk, links, linked, workers=options.workers)
            if not again.success:
                break
            curve_opts = shrunk
        plan = again
        traces = _finish_curve(plan, links, specs, sections, ci, params, options, fn)
    return traces


#: Rounds of planning again (refined, or inside a smaller reach) when the exact motion leaves the reach or a finish stalls.
_MARGIN_ROUNDS = 3
#: Collocation intervals per shooting segment of the exact finish, longest first: over long
#: segments the integration's round-off, grown by the sleigh's instability, holds the continuity
#: residuals near 1e-9 (circle eight at 3); shorter ones reach 1e-10.
_STRIDES = (2, 1)
#: Where the finest stride misses the finish's tolerance narrowly (:func:`_narrow`), the miss is the
#: integrations' round-off grown by the sleigh's instability, another draw of which often lands
#: within it: the finish is solved again with the integrations' tolerances scaled by these factors.
#: Of 11 such misses on six drawings at 6 m (1.3e-10 to 6e-10), 5 finished at twice the tolerances
#: and 1 more at a quarter, where each had cost a refined mesh and a program again (phosphor-infinity: 2.6 s).
_REROLLS = (2.0, 0.25)


def _narrow(fin) -> bool:
    """Whether a failed finish missed its tolerance by less than a factor of ten."""
    worst = max((abs(v) for v in fin.residuals.values()), default=math.inf)
    return not fin.success and worst <= 10.0 * _RESIDUAL_TOL


def _finish_curve(plan, links, specs, sections, ci, params, options, fn, whole: bool = False) -> list[SectionTrace]:
    """Each section of a planned curve (``plan``: a successful one) finished exactly from the exact end of the one before.

    ``links[k]`` says how section ``k`` meets the one before: ``"start"`` (a curve's first
    section), ``"continuous"`` (the mass's position and velocity carried on), ``"impulse"`` (its
    position carried on, its velocity as planned) or ``"jump"`` (both as planned). With
    ``whole`` (a caller that keeps the curve only whole), the sections end with the first that fails.
    """
    out = []
    arrived = None  # the exact end of the previous section, in this section's frame
    for k, (spec, sec) in enumerate(zip(specs, sections)):
        if arrived is not None:
            arrived = arrived.turned(spec.turn)
        X, times = plan.states[k], plan.times[k]
        r0, r1 = _rates(fn, X, spec, False), _rates(fn, X, spec, True)
        planned = RestState(float(X[2, 0]), float(X[3, 0]), float(r0[0]), float(r0[1]))
        kind = "start" if arrived is None and k == 0 else links[k]
        if arrived is None and kind in ("continuous", "impulse"):
            kind = "jump"  # the section before could not be finished: this one starts as planned
        start = {"start": planned, "jump": planned, "continuous": arrived,
                 "impulse": dataclasses.replace(planned, a=arrived.a, b=arrived.b) if arrived else None}[kind]
        target = RestState(float(X[2, -1]), float(X[3, -1]), float(r1[0]), float(r1[1]))
        def finished(stride, factor=1.0):
            return finish_section(params, spec.pieces, times, X[5], start, target, X, stride=stride,
                                  rtol=options.rtol * factor, atol=options.atol * factor)

        for stride in _STRIDES:
            fin = finished(stride)
            if fin.success:
                break
        for factor in _REROLLS if _narrow(fin) else ():
            again = finished(_STRIDES[-1], factor)
            if again.success:
                fin = again
                break
        out.append(section_trace(fin, sec, ci, params, options, spec, link_metrics(kind, arrived, start, params,
                                                                                   options)))
        arrived = fin.end if fin.success else None
        if whole and not out[-1].success:
            break  # heroicons' paper airplane: 0.87 -> 0.27 s on a last iterate whose first section fails
    return out


def _infeasible_curve(specs, sections, bad: int, ci, params, options, popts) -> list[SectionTrace]:
    """Every section of a curve failed, the one without a plan of its own saying which reach would do
    (or that its program is too large to build)."""
    refused = program_too_large([specs[bad]], popts)
    if refused is not None:
        other = f"section {bad} of this curve cannot be planned"
        return [failed(sec, ci, params, options, TraceStatus.NOT_PLANNED,
                       f"reach {options.reach:.4g}: not planned: " + (refused if k == bad else other))
                for k, sec in enumerate(sections)]
    searched = options.reach_hint
    wider = smallest_reach(specs[bad], popts) if searched else None
    scale = options.reach / popts.reach  # the program's reach is inside the margin
    hint = ("" if not searched else f"; on its own it plans within {wider * scale:.4g}" if wider is not None else
            f"; on its own it plans within none of {', '.join(f'{f * options.reach:.4g}' for f in _LARGER_REACHES)}")
    out = []
    for k, sec in enumerate(sections):
        msg = (f"reach {options.reach:.4g}: no motion of the mass within the reach traces this section{hint}"
               if k == bad else f"reach {options.reach:.4g}: not planned, section {bad} of this curve has no motion "
                                f"within the reach")
        tr = failed(sec, ci, params, options, TraceStatus.INFEASIBLE, msg)
        if k == bad and searched:
            tr = dataclasses.replace(tr, metrics={"smallest_feasible_reach": None if wider is None else wider * scale})
        out.append(tr)
    return out
