"""The pipeline: trace a figure, verify it by replay, rest at smooth joins where a replay strays, judge feasibility.

:func:`trace_and_verify` is the main entry of the library (``skatetrace trace`` calls it): it joins
the stages below it, tracing (:mod:`skatetrace.tracing`) and verification
(:mod:`skatetrace.verification`), and returns a :class:`VerifiedTrace` holding the trace, its
control schedule, the verification report and the plausibility verdict.

A section is traced from rest to rest by one launch, one glide and one stop, so on a section of
many pieces the launch or the stop runs through several of them. The full dynamics amplifies
small errors of the controls along such a manoeuvre (a sleigh moving with its mass far behind
the contact point is unstable), and the independent replay of a long section may stray from the
figure by more than verification allows although the trace itself is exact. A *rest* at a
smooth join (a cusp without pivot, :data:`~skatetrace.figures.figure.REST`: the path on the ice is the
same) splits the section in two, each with shorter manoeuvres.

:func:`trace_and_verify` traces and verifies a figure and, with ``rests="auto"``, where a
section fails (not traced, replay too far from the figure, or not at rest at its ends) adds a
rest at the smooth join nearest the middle of it, and where its replay strayed, of every section
before it on its curve (the replay carries errors from one section into the next), then traces
and verifies again, until everything passes or no such section has a smooth join left. A part of
a section that failed to trace which fails to trace again is also rested at its middle by count of
pieces. Since a failing section is split, the tracer gives up a long one sooner
(:attr:`~skatetrace.tracing.options.TraceOptions.split_on_failure`); where the rounds end with
such a section failed, it is searched in full once more. ``rests="never"`` traces the figure as
given, ``rests="joins"`` rests at every smooth join.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, replace
from typing import Any, Iterable

import numpy as np

from .dynamics.controls import ControlSchedule
from .dynamics.model import SleighParams
from .figures.figure import Figure, Section
from .planning.planner import figure_unknowns, plan_figure
from .processes import Background
from .tracing.options import LONG_SECTION
from .tracing.sections import FigureTrace, TraceOptions, TraceStatus, trace_figure
from .verification.feasibility import Feasibility, HumanLimits, assess_feasibility, exported_peaks
from .verification.verify import (VerificationReport, check_rel_tol, reporting, resampled, schedule_from_trace,
                                  verify, verify_within)

__all__ = ["DEFAULT_PLAN_PIECES", "DEFAULT_PLAN_UNKNOWNS", "REST_POLICIES", "DefaultReachTrace", "ReachPoint",
           "ReachSweep", "VerifiedTrace", "add_rests", "middle_join", "sweep_reach", "too_large_to_plan",
           "trace_and_verify", "trace_within_default_reach"]

REST_POLICIES = ("auto", "never", "joins")


@dataclass(frozen=True, slots=True, kw_only=True)
class VerifiedTrace:
    """A traced figure with its controls and its verification.

    ``figure`` is the figure as traced: the input with the rests of ``rests`` added, as
    ``(curve index, piece index)`` of the piece after each rest. ``rounds`` counts the
    trace-and-verify passes. ``feasibility`` is the second verdict: could a skater make these
    controls (:mod:`skatetrace.verification.feasibility`)?  ``success`` is the first one only: traced and
    verified, exact for the model. ``note`` says why adding rests stopped early, if it did.
    """

    figure: Figure
    trace: FigureTrace
    schedule: ControlSchedule
    states: dict[str, np.ndarray]
    report: VerificationReport
    rests: tuple[tuple[int, int], ...]
    rounds: int
    feasibility: Feasibility | None = None
    note: str = ""

    @property
    def success(self) -> bool:
        return self.trace.success and self.report.success

    @property
    def status(self) -> str:
        return "success" if self.success else "failed"

    @property
    def message(self) -> str:
        rests = f"; {len(self.rests)} rest(s) added at smooth joins" if self.rests else ""
        if self.success:
            return f"traced and verified{rests}"
        note = f"; {self.note}" if self.note else ""
        return (self.trace.message if not self.trace.success else self.report.message) + rests + note

    @property
    def verdict(self) -> str:
        """Both verdicts in a line: ``verified · not humanly feasible: mass 32.6 m from the blade (...)``."""
        verified = self.report.success and self.trace.success
        if self.feasibility is None:
            return "verified" if verified else "verification failed"
        return self.feasibility.verdict(verified)


#: Rounds of rests in a row that verify no more of the figure than the rounds before them, after which
#: ``rests="auto"`` stops (a round that leaves a long section failed is not counted: see
#: :func:`trace_and_verify`).
_BARREN_ROUNDS = 2


def middle_join(section: Section) -> int | None:
    """Index of the piece after the smooth join nearest the middle of ``section`` (by arc length).

    ``None`` if the section is a single piece.
    """
    if len(section.pieces) < 2:
        return None
    half, acc, best = 0.5 * section.length, 0.0, None
    for before, after in zip(section.pieces[:-1], section.pieces[1:]):
        acc += before.segment.length
        if best is None or abs(acc - half) < best[0]:
            best = (abs(acc - half), after.index)
    return best[1]


#: Where a section that failed to trace lies within one that failed to trace the round before,
#: ``rests="auto"`` splits it at its middle join by count of pieces too, where that is more than
#: this share of its pieces away from its middle by length (:func:`_split_joins`).
_COUNT_SPLIT = 0.25


def _split_joins(section: Section, again: bool) -> list[int]:
    """Pieces after which ``rests="auto"`` rests a failing ``section``: the middle by length, ``again`` by count too.

    The join nearest the middle by arc length (:func:`middle_join`) halves the manoeuvres, which is
    what a replay that strayed needs, and is all a section gets the first time it fails. ``again``
    says that the section was not traced and lies within one that was not traced the round before:
    halving its length did not help, and the failure is likely some stretch of it, such as a tight
    loop drawn as many short pieces. Split by length alone, such a stretch is only peeled of its long
    neighbours, a round each; so such a section is also rested at its middle join by count of pieces,
    where that is more than :data:`_COUNT_SPLIT` of its pieces away, which cuts into the stretch.
    Empty for a single piece.
    """
    middle = middle_join(section)
    if middle is None:
        return []
    pieces = section.pieces
    by_count = pieces[len(pieces) // 2].index
    if again and abs(by_count - middle) > _COUNT_SPLIT * len(pieces):
        return [middle, by_count]
    return [middle]


def _span(sec) -> tuple[int, int, int]:
    """A traced section's curve and the indices of its first and last pieces."""
    return sec.curve_index, sec.section.pieces[0].index, sec.section.pieces[-1].index


def _within(sec, spans) -> bool:
    """Whether the section ``sec`` lies within one of the ``spans`` (:func:`_span`)."""
    curve, first, last = _span(sec)
    return any(c == curve and lo <= first and last <= hi for c, lo, hi in spans)


def add_rests(figure: Figure, where: Iterable[tuple[int, int]]) -> Figure:
    """``figure`` with rests at the smooth joins before the pieces ``where`` = ``(curve, piece)``."""
    by_curve: dict[int, set[int]] = {}
    for ci, pi in where:
        by_curve.setdefault(ci, set()).add(pi)
    if not by_curve:
        return figure
    curves = tuple(c.with_rests(by_curve.get(ci, ())) for ci, c in enumerate(figure.curves))
    return Figure(figure.name, curves, figure.params, figure.description, figure.provenance, dict(figure.extra))


def _all_smooth_joins(figure: Figure) -> list[tuple[int, int]]:
    return [(ci, p.index) for ci, c in enumerate(figure.curves) for p in c.layout()
            if p.join_before is not None and not p.join_before.is_cusp]


def _to_split(sections, passed: list[bool]) -> list:
    """The ``sections`` (of a trace, with whether each was traced and its replay ``passed``) that
    ``rests="auto"`` splits: those that failed, and every section of a curve up to its last one
    whose replay strayed.

    The replay carries each section's end state into the next, so a replay may stray for an
    error made before it. A section that could not be traced has no replay: the next starts
    where the figure places it (:func:`~skatetrace.verification.verify.replay`), and the sections
    before it, whose replays passed, are kept.
    """
    last_stray: dict[int, int] = {}
    for k, (sec, ok) in enumerate(zip(sections, passed)):
        if sec.success and not ok:
            last_stray[sec.curve_index] = k
    return [sec for k, (sec, ok) in enumerate(zip(sections, passed))
            if not ok or k <= last_stray.get(sec.curve_index, -1)]


def _searched_in_full(result: VerifiedTrace, params, rel_tol: float, cache: dict, progress) -> VerifiedTrace:
    """``result`` traced and verified once more where sections of several pieces failed a search cut short
    for splitting (:attr:`TraceOptions.split_on_failure`), now that they are not split further.

    Those sections are searched in full, so that none is left failed for want of the search it
    would have had without the rests. The sections traced are taken from ``cache`` (a search cut
    short gives the same trace where it finds one).
    """
    trace = result.trace
    if result.success or not trace.options.split_on_failure or all(
            sec.success or len(sec.section.pieces) == 1 for sec in trace.sections):
        return result
    full = replace(trace.options, split_on_failure=False)
    known = {(key[0], full, key[2]): sec for key, sec in cache.items() if sec.success or len(key[2]) == 1}
    trace = trace_figure(result.figure, params, full, progress=progress, cache=known)
    schedule, states, report = _sampled_and_verified(trace, rel_tol)
    return replace(result, trace=trace, schedule=schedule, states=states, report=report, rounds=result.rounds + 1)


def _passed(result: VerifiedTrace) -> list[bool]:
    """Whether each section of ``result`` was traced and its replay passed."""
    return [sec.success and checks.get("passed", False)
            for sec, checks in zip(result.trace.sections, result.report.sections)]


def _verified_length(result: VerifiedTrace) -> float:
    """How much of the traced figure ``result`` traced and verified (the sum of those sections' lengths)."""
    return sum(sec.section.length for sec, ok in zip(result.trace.sections, _passed(result)) if ok)


def _rested_throughout(result: VerifiedTrace, figure: Figure, params, options: TraceOptions, rel_tol: float,
                       cache: dict, progress) -> VerifiedTrace:
    """``result`` traced and verified once more with a rest at every smooth join of the sections it leaves failing.

    The last resort of ``rests="auto"``, once its rests in the middle of failing sections have run
    out of rounds or stopped helping: those sections (and, where a replay strayed, the sections
    before them on its curve, :func:`_to_split`) are cut into their pieces, which a single
    manoeuvre each traces. Kept where that verifies more of the figure than ``result``. A random
    path of two cubic Béziers, a quadratic and two lines left seven millimetre-long arcs of radius
    down to 1.4 mm failed after ten rounds (19 s); rested at every join, they traced and verified.
    """
    new = [(sec.curve_index, piece.index) for sec in _to_split(result.trace.sections, _passed(result))
           for piece in sec.section.pieces[1:]]
    if not new:
        return result
    rests = tuple(result.rests) + tuple(new)
    current = add_rests(figure, rests)
    trace = trace_figure(current, params, options, progress=progress, cache=cache)
    schedule, states, report = _sampled_and_verified(trace, rel_tol)
    again = VerifiedTrace(figure=current, trace=trace, schedule=schedule, states=states, report=report, rests=rests,
                          rounds=result.rounds + 1)
    if again.success or _verified_length(again) > _verified_length(result):
        return again
    return replace(result, rounds=again.rounds,
                   note=f"a rest at each of the {len(new)} smooth joins of the sections left failing verified no more")


def trace_and_verify(figure: Figure, params: SleighParams | None = None, options: TraceOptions = TraceOptions(),
                     *, rests: str = "auto", rel_tol: float = 1e-6, max_rounds: int = 8,
                     limits: HumanLimits | None = None, progress=None) -> VerifiedTrace:
    """Trace ``figure``, replay its controls through the full dynamics, and add rests if needed.

    Parameters
    ----------
    rests : {"auto", "never", "joins"}
        ``"auto"`` (default) adds a rest in the middle of each failing section (and where its
        replay strayed, of the sections before it on its curve; where a section that failed to
        trace lies within one that failed to trace the round before, at its middle by count of
        pieces too), and tries again, at most
        ``max_rounds`` times, and no more once two rounds in a row have verified no more of the
        figure than before them (the result's ``note`` says so; a round that leaves a section of
        more than :data:`~skatetrace.tracing.options.LONG_SECTION` pieces failed is not counted, since
        splitting is what traces such a section). The sections are traced with
        :attr:`~skatetrace.tracing.options.TraceOptions.split_on_failure`, and where the last round
        leaves a section of several pieces failed, it is searched in full once more, and where
        sections still fail, rested at every smooth join (:func:`_rested_throughout`);
        ``"never"`` traces the figure as given; ``"joins"`` rests at every smooth join.
    rel_tol : float
        Verification tolerance as a fraction of the figure's size (:func:`~skatetrace.verification.verify.verify`).
    limits : HumanLimits, optional
        What a skater can do, in the figure's units, for the feasibility verdict. Default:
        :meth:`HumanLimits.for_model` (model units at the scale of the paper's figure); give
        :meth:`HumanLimits.for_skater` for a figure in metres.
    progress : callable, optional
        Passed to :func:`~skatetrace.tracing.sections.trace_figure`.

    Returns
    -------
    VerifiedTrace
        Never raises for a failed trace or verification: see its ``success`` and ``message``,
        and its ``feasibility``. The sections' peak metrics (``max_abs_a``, ``peak_abs_adot``, ...)
        are those of the exported rows where these reach further than the tracer's own grid.
    """
    if rests not in REST_POLICIES:
        raise ValueError(f"rests must be one of {', '.join(REST_POLICIES)}, got {rests!r}")
    check_rel_tol(rel_tol)  # before the tracing, not after it
    if not (isinstance(max_rounds, int) and max_rounds >= 0):
        raise ValueError(f"max_rounds must be a whole number >= 0, got {max_rounds!r}")
    added: list[tuple[int, int]] = _all_smooth_joins(figure) if rests == "joins" else []
    current = add_rests(figure, added)
    cache: dict[tuple, Any] = {}  # sections solved in one round are reused in the next
    # a section that fails is split here, so the tracer gives up a long one sooner
    splitting = replace(options, split_on_failure=True) if rests == "auto" and options.reach is None else options
    rounds = 0
    verified: list[float] = []  # per round, the length of the figure traced and verified
    untraced: list[tuple[int, int, int]] = []  # the sections split last round that were not traced

    def last_resort(result: VerifiedTrace) -> VerifiedTrace:
        """Where the rounds have run out: sections left failing searched in full, then cut at every join."""
        result = _searched_in_full(result, params, rel_tol, cache, progress)
        if result.success:
            return result
        return _rested_throughout(result, figure, params, splitting, rel_tol, cache, progress)

    while True:
        rounds += 1
        if options.reach is None:
            trace = trace_figure(current, params, splitting, progress=progress, cache=cache)
        else:
            trace = plan_figure(current, params, options, progress=progress)
        schedule, states, report = _sampled_and_verified(trace, rel_tol)
        result = VerifiedTrace(figure=current, trace=trace, schedule=schedule, states=states, report=report,
                               rests=tuple(added), rounds=rounds)
        # a planned figure is planned once: a rest changes the program, and the plan says why it failed
        if result.success or rests != "auto" or options.reach is not None:
            return _finish(_searched_in_full(result, params, rel_tol, cache, progress), limits)
        if rounds > max_rounds:
            return _finish(last_resort(result), limits)
        passed = _passed(result)
        # A section of more pieces than LONG_SECTION that failed was given up soon, and is split
        # (splitting is what traces a long wiggle: one of 80 arcs failed as 1, 2 and 4 sections,
        # and verified as 8): a round that leaves one is not counted against the rests.
        long_failed = any(not ok and len(sec.section.pieces) > LONG_SECTION for sec, ok in zip(trace.sections, passed))
        if not (splitting.split_on_failure and long_failed):
            verified.append(_verified_length(result))
        if len(verified) > _BARREN_ROUNDS and verified[-1] <= max(verified[:-_BARREN_ROUNDS]):
            # splitting has stopped helping: each round doubles the sections to trace (a zigzag
            # read as one smooth curve took 10, 16, then 42 s a round, none of its pieces traced)
            last = last_resort(result)
            return _finish(replace(last, note=(
                f"stopped adding rests in the middle of failing sections after {rounds} rounds: the last "
                f"{_BARREN_ROUNDS} traced and verified no more of the figure than the round before them"
                + (f"; {last.note}" if last.note else ""))), limits)
        split = _to_split(trace.sections, passed)
        new = [(sec.curve_index, piece) for sec in split
               for piece in _split_joins(sec.section, not sec.success and _within(sec, untraced))]
        untraced = [_span(sec) for sec in split if not sec.success]
        if not new:
            return _finish(result, limits)
        added += new
        current = add_rests(figure, added)


#: A plan sampled like a traced figure is kept where its replay passes within this share of every
#: limit (:func:`_sampled_and_verified`); so is one whose sections that did not are sampled
#: :data:`_MIDDLE_REFINEMENT` times more finely.
_COARSE_MARGIN = 0.5
_MIDDLE_REFINEMENT = 30.0


def _sampled_and_verified(trace, rel_tol: float):
    """The controls of ``trace`` sampled for ``controls.csv``, and their replay's report.

    A plan's sections are first sampled like traced ones (:func:`schedule_from_trace` with
    ``fine=False``): a tenth of the rows. Where that replay passes within :data:`_COARSE_MARGIN` of
    its tolerance and of every cusp-speed limit, it is kept. Else the sections that keep it from
    that (:func:`~skatetrace.verification.verify.verify_within`) are sampled
    :data:`_MIDDLE_REFINEMENT` times more finely, the others' rows kept, and the whole kept on the
    same condition; else every section a thousand times (``fine=True``), as every plan was before,
    and verified again. Measured on the school
    figures and corpus drawings planned by default (2026-11-27): tabler-alarm-v1 369,000 rows
    against 25,700, the paragraph double three 621,000 against 64,000, every one verified either
    way, its deviation and cusp speeds of the same order (the replay of a plan is ill-conditioned
    near its rests, so they move both ways with the rows). Of the 17 school figures for a 1.7 m
    skater, one is not kept coarse on the plans of 2026-11-28: the paragraph double three (its first
    section's end speed 0.77 of its limit, three more sections failing the open loop): those four
    sampled thirty times more finely, 0.18, with 130,000 rows (244,000 with all ten, 63,000 coarse).
    Where the open loop already says no, the coarse replay's conditioning and closed loop are not
    run (0.1 s against 0.5 s there).
    """
    if any(sec.glide.get("planned") for sec in trace.sections):
        schedule, states = schedule_from_trace(trace, fine=False)
        report, beyond = verify_within(trace, schedule, _COARSE_MARGIN, rel_tol=rel_tol)
        if report is None:
            # the sections that came close to a limit sampled more finely, the others' rows kept
            schedule, states = resampled(trace, schedule, states, beyond, fine=_MIDDLE_REFINEMENT)
            report, _ = verify_within(trace, schedule, _COARSE_MARGIN, rel_tol=rel_tol)
        if report is not None:
            return schedule, states, report
    schedule, states = schedule_from_trace(trace)
    return schedule, states, verify(trace, schedule, rel_tol=rel_tol)


#: The largest figure :func:`trace_within_default_reach` plans: a school figure's size. At most as
#: many unknowns in all its curves' programs as one program may have
#: (:data:`~skatetrace.planning.collocation.MAX_UNKNOWNS`), and at most this many pieces. The
#: school figures have 1,666 to 7,720 unknowns and 2 to 28 pieces, and are planned, traced and
#: verified in 1.5 to 8.9 s. A drawing's IPOPT iterations grow with its pieces as well as its
#: unknowns: lucide-signature (45 pieces, 6,015 unknowns) took 19.5 s planned against 7.8 s traced
#: with the launch-glide-stop manoeuvres, heroicons-star-solid-20 (49, 6,537) 11.2 s against 1.4 s,
#: and the corpus drawings above 9,200 unknowns up to 145 s, 21 s at the median, against 3 s
#: (``bench/CORPUS.md``, 2026-11-26, when the same meshes counted 1.31 times the unknowns and
#: this was 12,000: the collocation's end states have since been merged with its nodes).
DEFAULT_PLAN_UNKNOWNS = 9_200
DEFAULT_PLAN_PIECES = 32
#: The most IPOPT work (iterations times unknowns, summed over the programs:
#: :attr:`TraceOptions.plan_budget`) :func:`trace_within_default_reach` spends on a plan. The
#: school figures for a 1.7 m skater spend 69,000 to 527,000 (the paragraph double three), 0.5 to
#: 3.0 s of IPOPT on one core (2026-11-28). Of 65 icons of nine icon sets, 13 under the limits
#: above spent 1.06 to 4.5 million, 8.7 to 33 s of IPOPT, where their launch-glide-stop trace
#: takes 1 to 3 s, and none of their plans was humanly feasible (2026-11-27, in the counts before
#: the collocation's end states were merged with its nodes, 1.31 times today's for the same
#: iterations, when this was 1,000,000; IPOPT's time grows as the unknowns^1.16 an iteration, so
#: the product of the two is a fair measure).
DEFAULT_PLAN_BUDGET = 765_000


@dataclass(frozen=True, slots=True, kw_only=True)
class DefaultReachTrace:
    """What :func:`trace_within_default_reach` made: the result kept and the options it was made with.

    ``fell_back`` says why the launch-glide-stop trace was kept instead of a plan: ``"too large"``
    (the figure is larger than the default reach plans: it was not planned), ``"over budget"``
    (the planning spent its budget, :data:`DEFAULT_PLAN_BUDGET`, before the plan was made),
    ``"unplanned"`` (a section has no plan) or ``"unverified"`` (the plan's replay failed the
    verification), and ``reason`` says more; both are empty where the plan (or, failing
    everything, the whole plan) is kept. ``unknowns`` is the size of the figure's programs.
    """

    result: VerifiedTrace
    options: TraceOptions
    unknowns: int
    fell_back: str = ""
    reason: str = ""


def _plan_size(figure: Figure, params: SleighParams | None, options: TraceOptions) -> tuple[int, int]:
    """The unknowns of ``figure``'s programs within ``options.reach`` and its number of pieces."""
    if options.reach is None:
        raise ValueError("planning needs options.reach (a reach to plan within), got None")
    return figure_unknowns(figure, params, options), sum(len(curve.pieces) for curve in figure.curves)


def _beyond(size: int, pieces: int, max_unknowns: int | None, max_pieces: int | None) -> str:
    """Why a figure of ``size`` unknowns and ``pieces`` pieces is larger than the bounds, or ``""``."""
    for name, bound in (("max_unknowns", max_unknowns), ("max_pieces", max_pieces)):
        if bound is not None and (isinstance(bound, bool) or not isinstance(bound, int) or bound < 0):
            raise ValueError(f"{name} must be a whole number >= 0 or None, got {bound!r}")
    beyond = ([f"{size:,} unknowns in its programs, more than {max_unknowns:,}"]
              if max_unknowns is not None and size > max_unknowns else []) \
        + ([f"{pieces:,} pieces, more than {max_pieces:,}"] if max_pieces is not None and pieces > max_pieces else [])
    return f"{' and '.join(beyond)}: larger than a school figure" if beyond else ""


def too_large_to_plan(figure: Figure, params: SleighParams | None, options: TraceOptions, *,
                      max_unknowns: int | None = DEFAULT_PLAN_UNKNOWNS,
                      max_pieces: int | None = DEFAULT_PLAN_PIECES) -> str:
    """Why :func:`trace_within_default_reach` would not plan ``figure`` within ``options.reach``
    (larger than a school figure, :data:`DEFAULT_PLAN_UNKNOWNS`), or ``""`` where it would.

    Raises
    ------
    ValueError
        If a bound is not a whole number >= 0 (or None: no bound), or ``options.reach`` is None.
    """
    return _beyond(*_plan_size(figure, params, options), max_unknowns, max_pieces)


def trace_within_default_reach(figure: Figure, params: SleighParams | None, options: TraceOptions, *,
                               rests: str = "auto", rel_tol: float = 1e-6, limits: HumanLimits | None = None,
                               progress=None, max_unknowns: int | None = DEFAULT_PLAN_UNKNOWNS,
                               max_pieces: int | None = DEFAULT_PLAN_PIECES,
                               max_work: int | None = DEFAULT_PLAN_BUDGET) -> DefaultReachTrace:
    """A reach the user did not ask for: the plan within ``options.reach`` where it traces and verifies
    the figure, else the launch-glide-stop manoeuvres (``reach=None``) where they do.

    This is what ``skatetrace trace`` does for a figure in metres without ``--reach``: the user asked
    for a trace, not a plan. The launch-glide-stop trace is kept when

    - the figure's programs have more than ``max_unknowns`` unknowns in all
      (:func:`~skatetrace.planning.planner.figure_unknowns`), or the figure more than
      ``max_pieces`` pieces: such a figure is not planned, which would take tens of seconds to
      minutes, and the launch-glide-stop trace is kept whatever its
      outcome (a drawing of 150 pieces whose trace failed a section failed its plan too, after
      175 s);
    - the planning spends more than ``max_work`` (:attr:`TraceOptions.plan_budget`, unless
      ``options`` has one): the launch-glide-stop trace is kept whatever its outcome, as above;
    - a section has no plan, and it traces every section. Planned all or nothing
      (``options.all_or_nothing``), no curve is planned further once a section has no plan; where
      the launch-glide-stop trace fails too, the whole plan (every curve planned as far as it goes,
      ``all_or_nothing=False``) is made and kept with its failures;
    - the plan traces every section but its replay fails the verification, and it passes. A plan
      is exact to the finish's residuals (1e-10 at the shooting segments' joins); where a section
      moves the mass behind the blade for long, the open loop amplifies them beyond the tolerance
      (measured: a 6 m line, 1e-10 grown to 1e-6 rad of heading).

    The launch-glide-stop trace of a figure that is planned is made beforehand, beside the plan, in a
    child at the lowest priority (:class:`~skatetrace.processes.Background` with ``idle=True``): it
    runs on what the planner leaves idle (a curve's linked program, one program on one core, leaves
    the other core free for seconds) and costs a plan that is kept next to nothing. Where the plan
    is given up and the child is done, its trace is taken. Where it is not done, it is waited for
    while it runs on at least half a core (:meth:`~skatetrace.processes.Background.awaited`): with
    the planning over it has a core to itself and a head start (phosphor's device-rotate-light: 3.0 s
    waited against 4.4 s made afresh); where other work on the machine starves it, it is ended and
    the trace made here. The answer is the same either way.

    Parameters
    ----------
    options : TraceOptions
        With ``reach`` set; the rest as for :func:`trace_and_verify`.
    max_unknowns, max_pieces : int or None
        The largest figure planned (None: any).
    max_work : int or None
        The planning's budget where ``options.plan_budget`` is None (None: no bound).

    Returns
    -------
    DefaultReachTrace
        ``fell_back`` and ``reason`` say why the launch-glide-stop trace was kept, if it was.
    """
    size, pieces = _plan_size(figure, params, options)
    beyond = _beyond(size, pieces, max_unknowns, max_pieces)

    def run(opts: TraceOptions, told=progress) -> VerifiedTrace:
        return trace_and_verify(figure, params, opts, rests=rests, rel_tol=rel_tol, limits=limits, progress=told)

    unbounded = replace(options, reach=None, all_or_nothing=False)
    if beyond:
        return DefaultReachTrace(result=run(unbounded), options=unbounded, unknowns=size, fell_back="too large",
                                 reason=beyond)
    if options.plan_budget is None:
        options = replace(options, plan_budget=max_work)

    def quietly() -> VerifiedTrace:
        # made in a child on what the planner leaves idle: it tells nobody of its progress
        with reporting(lambda *_: None), warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return run(unbounded, None)

    with Background(quietly, options.workers, idle=True) as early:

        def fallback() -> VerifiedTrace:
            """The launch-glide-stop trace: the child's, waited for while it runs at speed, else made here
            (the same answer)."""
            if early.ready():
                return early.result()
            waited = early.awaited()
            return waited[0] if waited is not None else run(unbounded)

        done = run(options)
        if done.success:
            return DefaultReachTrace(result=done, options=options, unknowns=size)
        spent = next((s.message for s in done.trace.sections if s.status is TraceStatus.OVER_BUDGET), None)
        if spent is not None:
            return DefaultReachTrace(result=fallback(), options=unbounded, unknowns=size, fell_back="over budget",
                                     reason=spent)
        bad = [s for s in done.trace.sections if not s.success]
        # a reason, not "skipped" (all or nothing)
        failed = next((s for s in bad if s.status is not TraceStatus.NOT_PLANNED), bad[0]).message if bad else None
        again = fallback()
    if failed is None:  # every section planned, the replay failed
        if again.success:
            return DefaultReachTrace(result=again, options=unbounded, unknowns=size, fell_back="unverified",
                                     reason=done.report.message)
        return DefaultReachTrace(result=done, options=options, unknowns=size)
    if all(s.success for s in again.trace.sections):
        return DefaultReachTrace(result=again, options=unbounded, unknowns=size, fell_back="unplanned", reason=failed)
    if not options.all_or_nothing:
        return DefaultReachTrace(result=done, options=options, unknowns=size)
    whole = replace(options, all_or_nothing=False)
    return DefaultReachTrace(result=run(whole), options=whole, unknowns=size)


_PEAKS = ("max_abs_a", "max_abs_b", "peak_abs_adot", "peak_abs_bdot", "peak_mass_kinetic_energy")


def _finish(result: VerifiedTrace, limits: HumanLimits | None) -> VerifiedTrace:
    """Refresh the sections' peaks from the exported rows, and add the feasibility verdict.

    The tracer's metrics come from samples (a planned section's from a uniform grid, a traced
    one's from its integration steps), which can miss a narrow spike of the rates (where the mass
    passes near the singular point); the exported rows resolve it.
    """
    trace = result.trace
    peaks = exported_peaks(result.schedule, result.states, trace.params, len(trace.sections))
    sections = tuple(replace(sec, metrics={**sec.metrics, **{k: max(sec.metrics.get(k, 0.0), p[k]) for k in _PEAKS}})
                     if p else sec for sec, p in zip(trace.sections, peaks))
    trace = replace(trace, sections=sections)
    if limits is None:
        limits = HumanLimits.for_model(params=trace.params)
    feasibility = assess_feasibility(trace, result.schedule, result.states, limits)
    return replace(result, trace=trace, feasibility=feasibility)


@dataclass(frozen=True, slots=True, kw_only=True)
class ReachPoint:
    """One reach of a sweep (:func:`sweep_reach`): what planning within it gave, measured on the exported rows.

    ``reach`` is None for the launch-glide-stop manoeuvres (the reference). ``success`` is the
    first verdict (traced and verified), ``feasible`` the second; ``distance`` is the mass's
    largest distance from the blade, ``peak_force`` the largest force on it, ``effort`` the
    integral of the squared force, ``duration`` the figure's, ``cusp_impulse`` and
    ``cusp_mass_speed`` the largest impulse on the mass at a cusp and its speed relative to the
    stopped blade there; NaN where nothing was traced.
    """

    reach: float | None
    success: bool
    feasible: bool
    message: str
    distance: float
    peak_force: float
    effort: float
    duration: float
    cusp_impulse: float
    cusp_mass_speed: float
    seconds: float


@dataclass(frozen=True, slots=True, kw_only=True)
class ReachSweep:
    """The trade-off of a figure: effort, force and duration against the reach (:func:`sweep_reach`)."""

    figure: str
    objective: str
    points: tuple[ReachPoint, ...]
    reference: ReachPoint

    @property
    def success(self) -> bool:
        """True when at least one reach was planned, traced exactly and verified."""
        return any(p.success for p in self.points)

    @property
    def smallest_reach(self) -> float | None:
        """The smallest reach swept that was planned and verified (None if none was)."""
        ok = [p.reach for p in self.points if p.success]
        return min(ok) if ok else None

    def to_dict(self) -> dict[str, Any]:
        """The sweep as plain data (schema ``skatetrace.tradeoff/1``)."""
        from dataclasses import asdict

        return {"schema": "skatetrace.tradeoff/1", "figure": self.figure, "objective": self.objective,
                "smallest_reach": self.smallest_reach, "reference": asdict(self.reference),
                "points": [asdict(p) for p in self.points]}


def sweep_reach(figure: Figure, reaches: Iterable[float], params: SleighParams | None = None,
                options: TraceOptions = TraceOptions(), *, rel_tol: float = 1e-6, limits: HumanLimits | None = None,
                progress=None) -> ReachSweep:
    """Plan ``figure`` within each of ``reaches`` and measure what each costs, beside today's manoeuvres.

    Parameters
    ----------
    reaches : iterable of float
        Reaches to plan within (the figure's units), each positive; swept in increasing order.
    options : TraceOptions
        Everything else (speed, objective, bounds); its ``reach`` is replaced by each of ``reaches``.
    progress : callable, optional
        Called as ``progress(done, total)`` after each reach (the reference counts as one).

    Returns
    -------
    ReachSweep
        Never raises for a reach that cannot be planned: its point says so (``success`` False).
    """
    values = sorted(float(r) for r in reaches)
    if not values or not all(np.isfinite(r) and r > 0 for r in values):
        raise ValueError(f"reaches must be positive finite lengths, at least one; got {values!r}")
    import time

    def point(reach: float | None) -> ReachPoint:
        t0 = time.perf_counter()
        done = trace_and_verify(figure, params, replace(options, reach=reach), rests="never" if reach else "auto",
                                rel_tol=rel_tol, limits=limits)
        traced = done.schedule.t.size > 0 and done.feasibility is not None
        info = done.feasibility.info if traced else {}
        checks = {c.name: c.value for c in done.feasibility.checks} if traced else {}
        nan = float("nan")
        return ReachPoint(
            reach=reach, success=done.success, feasible=bool(done.feasibility and done.feasibility.feasible),
            message=done.message, distance=float(checks.get("reach", nan)),
            peak_force=float(info.get("peak_force_on_mass", nan)), effort=float(info.get("effort", nan)),
            duration=float(done.schedule.t[-1] - done.schedule.t[0]) if traced else nan,
            cusp_impulse=float(info.get("max_cusp_impulse", nan)),
            cusp_mass_speed=float(info.get("max_cusp_mass_speed", nan)), seconds=time.perf_counter() - t0)

    total = len(values) + 1
    reference = point(None)
    if progress is not None:
        progress(1, total)
    points = []
    for k, reach in enumerate(values):
        points.append(point(reach))
        if progress is not None:
            progress(k + 2, total)
    return ReachSweep(figure=figure.name, objective=options.objective, points=tuple(points), reference=reference)
