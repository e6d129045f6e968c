"""Independent verification: replay a control schedule through the full five equations.

The replay knows nothing of how the controls were found. It reads the sampled schedule
(:class:`~skatetrace.dynamics.controls.ControlSchedule`, the content of ``controls.csv``), interpolates it by
cubic Hermite splines, integrates eqs. (p1_eq)-(y_eq) with DOP853 at tight tolerances, and applies
at each cusp only what the figure prescribes: the sleigh is at rest, the blade pivots by the
join's angle, and the momenta are those of the mass's motion at rest. It then measures

- the deviation from the target figure both ways (replayed points to the figure, figure to the
  replayed path), per section and overall,
- the speed at every cusp,
- the drift of ``p1 + r p2`` on each arc and of ``p2`` on each line (both are invariants there;
  a spiral has no such invariant).

Where a section fails, the replay's conditioning is measured (its spread under a ``1e-12``
change of the controls). Where that spread is too large for the check to mean anything, the
section is verified by the closed loop instead (the model under the tracking law about the
trace, :mod:`skatetrace.feedback`), with the same tolerances and a bound on how far the law
departs from the schedule. Tolerances are never loosened.
"""

from __future__ import annotations

import contextlib
import math
from dataclasses import dataclass, field
from functools import partial
from typing import Any, Callable, Collection

import numpy as np
from scipy.spatial import cKDTree

from ..dynamics.controls import ControlSchedule, sample_intervals
from ..dynamics.model import SleighParams, momenta, velocities
from ..dynamics.replayer import replay_chunk
from ..dynamics.simulate import simulate
from ..figures.geometry import segment_points
from ..processes import map_forked
from ..progress import Channel
from ..tracing.sections import FigureTrace
from .distances import figure_to_replay, nearer_pieces

__all__ = ["schedule_from_trace", "resampled", "Replay", "VerificationReport", "replay", "reporting", "verify",
           "verify_within"]

#: Bounds on the dense samples of the replay and of the figure, so that memory stays bounded for
#: any figure size and speed (figures of ordinary size and duration stay far below them).
MAX_REPLAY_SAMPLES = 200_000
MAX_FIGURE_SAMPLES = 100_000


#: Distinct sections whose controls are sampled side by side (:func:`schedule_from_trace`), a round
#: of :data:`_SAMPLE_ROUND` at a time: at least this many, or as many manoeuvre legs between them
#: as :data:`_FORK_LEGS`; fewer are sampled here (a fork costs milliseconds). A planned section has
#: some forty legs where a launch-glide-stop section has a few: the paragraph double three's ten
#: planned sections (414 legs) were sampled in 0.31 s here and 0.22 s side by side, thirty times
#: more finely (2026-11-28).
_FORK_SECTIONS = 16
_FORK_LEGS = 64
_SAMPLE_ROUND = 128

_SAMPLED = ("a", "b", "adot", "bdot", "p1", "p2", "s", "xi1", "xi2", "segment")

_PROGRESS = Channel("verification")


def reporting(report: Callable[[str, int, int], None]) -> contextlib.AbstractContextManager[None]:
    """Within the ``with`` block, call ``report(stage, done, total)`` as a trace is verified.

    ``stage`` is ``"sampling the controls"`` (:func:`schedule_from_trace`; ``done`` of ``total``
    distinct sections), ``"replaying"`` or ``"measuring"`` (:func:`verify`; sections). A figure of
    2,000 sections takes tens of seconds. Per thread and task, like
    :func:`skatetrace.planning.pool.reporting` (:class:`skatetrace.progress.Channel`).
    """
    return _PROGRESS.listening(report)


#: The least share of a launch-glide-stop section's largest ``|a|, |b|`` (and largest rate) that
#: one of its pieces is sampled relative to (``scale_floor`` of :func:`sample_intervals`). Each
#: piece was held to its own scale: where the mass passes through the blade's contact point, a
#: piece of values 1e-4 of the others was sampled to 1e-15 and Adwaita's view-app-grid icon (nine
#: dots at 6 m / 1 mm) got 873,000 rows a dot, 322,000 of them in two pieces, and 9.1 million rows
#: in ``controls.csv`` (2.3 GB). With 1e-2, 231,000 a dot and the same deviation (1.29e-6). Over
#: the corpus and the school figures (2026-11-27) 15 of 70 figures got fewer rows (3.5 million
#: against 4.1 in all), every one verified, the deviations and cusp speeds moving both ways
#: (geometric means of their ratios 1.006 and 1.006: the replay's own spread). A floor of 1 (one
#: scale for the section) took 31% of the rows but moved the cusp speeds up to 5 times.
SCALE_FLOOR = 1e-2


#: How many times more finely than the others a planned section is sampled by default
#: (:func:`schedule_from_trace`): values to 1e-14 of their largest, rates to 1e-12.
PLANNED_REFINEMENT = 1000.0


def _refinement(fine: bool | float) -> float:
    """The factor ``fine`` asks of a planned section's tolerances (:func:`schedule_from_trace`)."""
    if isinstance(fine, (bool, np.bool_)):
        return PLANNED_REFINEMENT if fine else 1.0
    if not isinstance(fine, (int, float, np.integer, np.floating)) or not 1.0 <= fine < math.inf:
        raise ValueError(f"fine must be True, False or a number >= 1 (how many times more finely a planned "
                         f"section is sampled), got {fine!r}")
    return float(fine)


def _sample_section(sec, fine: bool | float = True) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """Sample times of one traced section and its controls and momenta there (no layout).

    Both one-sided limits are sampled at every breakpoint: an interval's last row is the limit
    from the left, the next interval's first row the limit from the right. A planned section is
    sampled more finely as ``fine`` asks (:func:`schedule_from_trace`).
    """
    def fn(tt, left):
        v = sec.evaluate(tt, geometry=False)
        if np.any(left):
            vl = sec.evaluate(tt[left], side="left", geometry=False)
            for k in v:
                v[k][left] = vl[k]
        return np.vstack([v[k] for k in _SAMPLED])

    # A planned section moves the mass fast through its rests, where the replay's momenta must
    # cancel the mass's rates: by default its rates are sampled a thousand times more finely. The
    # others' pieces are held to tolerances relative to at least SCALE_FLOOR of the section's largest values.
    planned = sec.glide.get("planned")
    factor = _refinement(fine)
    tol = dict(value_tol=1e-11 / factor, rate_tol=1e-9 / factor) if planned and factor != 1.0 else {}
    if not planned:
        tol["scale_floor"] = SCALE_FLOOR
    spans, rows = sample_intervals(fn, sec.breakpoints(), values=True, **tol)
    v = dict(zip(_SAMPLED, rows))
    v["segment"] = v["segment"].astype(int)
    return np.concatenate(spans), v


def schedule_from_trace(trace: FigureTrace, *, fine: bool | float = True,
                        sections: Collection[int] | None = None) -> tuple[ControlSchedule, dict[str, np.ndarray]]:
    """Sample every section's controls densely enough for cubic Hermite interpolation.

    Planned sections (:mod:`skatetrace.planning`) are sampled :data:`PLANNED_REFINEMENT` (a thousand)
    times more finely than the others (values to 1e-14 of their largest, rates to 1e-12): the mass
    moves fast through their rests, where the replay's momenta must cancel its rates. ``fine=False``
    samples them as the others, and a number ``fine >= 1`` that many times more finely.
    :func:`~skatetrace.pipeline.trace_and_verify` tries them coarser first. ``sections``: the
    indices of the sections to sample (all by default); the rows hold only theirs.

    Raises
    ------
    ValueError
        If ``fine`` is neither a bool nor a number >= 1.

    Returns the schedule and the matching solver states (``x, y, theta, p1, p2, xi1, xi2``) at the
    same rows, for ``controls.csv``.
    """
    _refinement(fine)  # refused before any work
    cols: dict[str, list] = {k: [] for k in ("t", "a", "b", "adot", "bdot", "section", "piece",
                                              "x", "y", "theta", "p1", "p2", "xi1", "xi2")}
    # Sections traced once and reused by trace_figure (the same shape elsewhere in the figure)
    # share their phases, hence their controls: they are sampled once and only laid out anew.
    # Many distinct sections are sampled side by side, a round at a time (the same samples).
    wanted = [sec.phases and (sections is None or si in sections) for si, sec in enumerate(trace.sections)]
    distinct: dict[tuple[int, int], Any] = {}
    for sec, want in zip(trace.sections, wanted):
        if want:
            distinct.setdefault((id(sec.phases), sec.direction), sec)
    keys, firsts = list(distinct), list(distinct.values())
    legs = sum(len(ph.maneuver.legs) for sec in firsts for ph in sec.phases if ph.maneuver is not None)
    step = _SAMPLE_ROUND if len(firsts) >= _FORK_SECTIONS or legs >= _FORK_LEGS else 1
    sampled: dict[tuple[int, int], tuple[np.ndarray, dict[str, np.ndarray]]] = {}
    for k in range(0, len(firsts), step):
        sampled.update(zip(keys[k:k + step], map_forked(partial(_sample_section, fine=fine), firsts[k:k + step])))
        _PROGRESS.report("sampling the controls", min(k + step, len(firsts)), len(firsts))
    for si, (sec, t_start) in enumerate(zip(trace.sections, trace.start_times)):
        if not wanted[si]:
            continue
        ts, v = sampled[(id(sec.phases), sec.direction)]
        x, y, theta = sec.layout(v["s"], v["segment"])
        v = dict(v, x=x, y=y, theta=theta)
        for k in ("a", "b", "adot", "bdot", "x", "y", "theta", "p1", "p2", "xi1", "xi2"):
            cols[k].append(v[k])
        cols["t"].append(t_start + ts)
        cols["section"].append(np.full(ts.size, si))
        cols["piece"].append(np.array([p.index for p in sec.section.pieces])[v["segment"]])
    arr = {k: np.concatenate(v) if v else np.empty(0) for k, v in cols.items()}
    schedule = ControlSchedule(t=arr["t"], a=arr["a"], b=arr["b"], adot=arr["adot"], bdot=arr["bdot"],
                               section=arr["section"].astype(int), piece=arr["piece"].astype(int))
    states = {k: arr[k] for k in ("x", "y", "theta", "p1", "p2", "xi1", "xi2")}
    return schedule, states


def resampled(trace: FigureTrace, schedule: ControlSchedule, states: dict[str, np.ndarray], sections: Collection[int],
              *, fine: bool | float) -> tuple[ControlSchedule, dict[str, np.ndarray]]:
    """``schedule`` and its ``states`` (:func:`schedule_from_trace`) with the rows of ``sections`` sampled again as
    ``fine`` asks; every other section's rows as they were."""
    part, part_states = schedule_from_trace(trace, fine=fine, sections=sections)
    kept = ~np.isin(schedule.section, np.fromiter(sections, dtype=int))
    # each section's rows are consecutive, in time order, from one of the two: a stable sort by section
    order = np.argsort(np.concatenate([schedule.section[kept], part.section]), kind="stable")

    def merged(base: np.ndarray, new: np.ndarray) -> np.ndarray:
        return np.concatenate([base[kept], new])[order]

    fields = {k: merged(getattr(schedule, k), getattr(part, k)) for k in ("t", "a", "b", "adot", "bdot", "section",
                                                                           "piece")}
    return ControlSchedule(**fields), {k: merged(v, part_states[k]) for k, v in states.items()}


@dataclass(frozen=True, slots=True, kw_only=True)
class Replay:
    """Dense samples of the replayed full dynamics: arrays of shape ``(n,)``, ``section`` labels."""

    t: np.ndarray
    state: np.ndarray  # (5, n): p1, p2, theta, x, y
    controls: np.ndarray  # (4, n): a, b, adot, bdot
    section: np.ndarray
    piece: np.ndarray

    def velocities(self, params: SleighParams):
        return velocities(params, self.state[0], self.state[1], *self.controls)

    def take(self, idx) -> "Replay":
        """The rows ``idx`` (in that order) as a replay of their own."""
        return Replay(t=self.t[idx], state=self.state[:, idx], controls=self.controls[:, idx],
                      section=self.section[idx], piece=self.piece[idx])


def replay(trace: FigureTrace, schedule: ControlSchedule, *, rtol: float = 1e-13, atol: float = 1e-14,
           points_per_unit: float = 400.0, engine: str = "compiled") -> Replay:
    """Integrate the full dynamics under ``schedule``, applying the figure's cusps.

    Parameters
    ----------
    rtol, atol : float
        DOP853's tolerances.
    points_per_unit : float
        Density of the returned samples per unit of time (at least 50 per chunk).
    engine : {"compiled", "scipy"}
        ``"compiled"`` (default) integrates with :func:`skatetrace.dynamics.replayer.replay_chunk`;
        ``"scipy"`` with :func:`skatetrace.dynamics.simulate.simulate` (``solve_ivp``), about a hundred
        times slower, as a cross-check of the first.
    """
    if engine not in ("compiled", "scipy"):
        raise ValueError(f"engine must be 'compiled' or 'scipy', got {engine!r}")
    params = trace.params
    ts, states, ctrls, secs, pieces = [], [], [], [], []
    y = None
    prev_section = None
    # Memory is bounded whatever the time scale (a slow --speed or a long figure): beyond
    # MAX_REPLAY_SAMPLES in all the density drops below points_per_unit.
    span = float(schedule.t[-1] - schedule.t[0]) if schedule.t.size else 0.0
    if span * points_per_unit > MAX_REPLAY_SAMPLES:
        points_per_unit = MAX_REPLAY_SAMPLES / span
    for i0, i1 in schedule.chunks():
        si = int(schedule.section[i0])
        sec = trace.sections[si]
        t0, t1 = float(schedule.t[i0]), float(schedule.t[i1 - 1])
        a, b, ad, bd = schedule.a[i0], schedule.b[i0], schedule.adot[i0], schedule.bdot[i0]
        if si != prev_section:
            _PROGRESS.report("replaying", si, len(trace.sections))
            first = sec.section.pieces[0]
            # Start from the figure's own layout at a curve's start or after a section that could
            # not be traced (its motion is missing); otherwise carry on from the replay itself.
            if y is None or first.join_before is None or prev_section != si - 1:
                theta = first.start.heading + (math.pi if first.direction < 0 else 0.0)
                x0, y0 = first.start.x, first.start.y
            else:
                theta = y[2] + first.join_before.pivot
                x0, y0 = y[3], y[4]
            p1, p2 = momenta(params, 0.0, 0.0, a, b, ad, bd)
            y = np.array([p1, p2, theta, x0, y0])
            prev_section = si

        n = max(50, int(math.ceil((t1 - t0) * points_per_unit)))
        tt = np.linspace(t0, t1, n)
        # NaN where a failed integration did not reach: verify reports it
        if engine == "compiled":
            run = replay_chunk(params, y, schedule, i0, i1, tt, rtol=rtol, atol=atol)
            ys, y_end, cs = run.states, run.y_end, run.controls
        else:
            traj = simulate(params, y, schedule.scalar_interpolant(i0, i1), (t0, t1), rtol=rtol, atol=atol)
            ys, y_end, cs = traj(tt), traj.state[:, -1], np.vstack(schedule.interpolant(i0, i1)(tt))
        ts.append(tt)
        states.append(ys)
        ctrls.append(cs)
        secs.append(np.full(n, si))
        idx = np.clip(np.searchsorted(schedule.t[i0:i1], tt, side="right") - 1, 0, i1 - i0 - 1)
        pieces.append(schedule.piece[i0:i1][idx])
        y = y_end
    _PROGRESS.report("replaying", len(trace.sections), len(trace.sections))
    if not ts:
        # No section was traced (every one failed): nothing to replay, which verify reports.
        return Replay(t=np.empty(0), state=np.empty((5, 0)), controls=np.empty((4, 0)),
                      section=np.empty(0, dtype=int), piece=np.empty(0, dtype=int))
    return Replay(t=np.concatenate(ts), state=np.hstack(states), controls=np.hstack(ctrls),
                  section=np.concatenate(secs), piece=np.concatenate(pieces))


@dataclass(frozen=True, slots=True, kw_only=True)
class VerificationReport:
    """Checks of a traced figure against its independent replay. ``success`` if all pass.

    ``replay`` holds the rows that decided each section: the open loop's, or the closed loop's
    where that verified an ill-conditioned section (its record's ``instrument``), so that plots of
    it show what was checked.
    """

    success: bool
    status: str
    message: str
    figure_size: float
    tolerance: float
    max_deviation: float
    max_deviation_to_figure: float
    max_deviation_from_figure: float
    max_cusp_speed: float
    cusp_speeds: list[float]
    sections: list[dict[str, Any]]
    invariant_drift: list[dict[str, Any]]
    replay: Replay | None = field(default=None, repr=False, compare=False)

    def passed_within(self, share: float) -> bool:
        """Whether every check passed with the deviation within ``share`` of the tolerance and every
        cusp speed within ``share`` of its section's limit."""
        return self.success and self.max_deviation <= share * self.tolerance and all(
            max(rec["start_speed"], rec["end_speed"]) <= share * rec["cusp_speed_limit"]
            for rec in self.sections if rec.get("traced"))

    def to_dict(self) -> dict[str, Any]:
        return {
            "success": self.success, "status": self.status, "message": self.message,
            "figure_size": self.figure_size, "tolerance": self.tolerance,
            "max_deviation": self.max_deviation,
            "max_deviation_replay_to_figure": self.max_deviation_to_figure,
            "max_deviation_figure_to_replay": self.max_deviation_from_figure,
            "max_cusp_speed": self.max_cusp_speed, "cusp_speeds": self.cusp_speeds,
            "sections": self.sections, "invariant_drift": self.invariant_drift,
        }


def _measure(trace: FigureTrace, rep: Replay, tol: float, only=None):
    """Deviation, cusp speeds and invariant drift of the replay ``rep``, section by section.

    ``only``: the sections to measure (default all). Returns ``{section: (record, drifts)}``.
    """
    params = trace.params
    xi1, xi2, _ = rep.velocities(params)
    out = {}
    # each section's rows, found once (not with a mask over the whole replay per section)
    total_length = sum(p.segment.length for sec in trace.sections for p in sec.section.pieces)
    density = min(200.0, MAX_FIGURE_SAMPLES / max(total_length, 1e-300))  # target points per unit length
    order = np.argsort(rep.section, kind="stable")
    cuts = np.searchsorted(rep.section[order], np.arange(len(trace.sections) + 1))
    for si, sec in enumerate(trace.sections):
        if only is not None and si not in only:
            continue
        if only is None:
            _PROGRESS.report("measuring", si, len(trace.sections))
        idx = order[cuts[si]:cuts[si + 1]]
        if not sec.phases or not idx.size:
            out[si] = ({"section": si, "traced": False, "passed": False, "message": sec.message}, [])
            continue
        if idx[-1] - idx[0] + 1 == idx.size:  # a section's rows are consecutive: views, not copies
            idx = slice(int(idx[0]), int(idx[-1]) + 1)
        sub = rep.take(idx)
        sxi1, sxi2 = xi1[idx], xi2[idx]
        pts = sub.state[3:5]
        finite = bool(np.all(np.isfinite(sub.state)))
        # distances to points on the pieces: an upper bound that lets nearer_pieces skip far spirals
        samples = [segment_points(p.start, p.segment, 65) for p in sec.section.pieces]
        # a replay that turned NaN or infinite is measured as infinitely far (the distance searches
        # refuse non-finite points: a planned drawing's replay crashed the verification there)
        d_to = (nearer_pieces(cKDTree(np.hstack(samples).T).query(pts.T)[0], pts, sec.section.pieces, samples)
                if finite else np.array([math.inf]))
        rows = _rows_by_piece(sub.piece)
        d_from = [np.zeros(0) if finite else np.array([math.inf])]
        for p in sec.section.pieces if finite else ():
            n = max(64, int(p.segment.length * density))
            # Each piece's points are matched with the stretch of replay labelled with that piece
            # (one sample more each side): where two pieces pass close to each other, as at the
            # waist of a figure eight, the nearest sample may otherwise belong to the other one.
            own = rows.get(p.index)
            span = (np.arange(max(int(own[0]) - 1, 0), min(int(own[-1]) + 2, sub.t.size)) if own is not None
                    else np.arange(sub.t.size))
            d_from.append(figure_to_replay(segment_points(p.start, p.segment, n), sub, span, params))
        d_from = np.concatenate(d_from)
        speeds = (abs(float(sxi2[0])), abs(float(sxi2[-1])))
        # "At rest" means below 1e-8 of the fastest motion in the section (the glide, the blade, or
        # the mass relative to the ice): the replay resolves speeds to a fraction of that scale.
        a, b, ad, bd = sub.controls
        mass_speed = np.hypot(sxi2 - sxi1 * b + ad, sxi1 * a + bd)
        speed_scale = max(trace.options.speed, float(np.max(np.abs(sxi2))), float(np.max(mass_speed)))
        cusp_limit = 1e-8 * speed_scale
        dev = max(float(d_to.max()), float(d_from.max())) if finite else math.inf
        record = {
            "section": si, "traced": True, "pieces": [p.index for p in sec.section.pieces],
            "max_deviation_replay_to_figure": float(d_to.max()),
            "max_deviation_figure_to_replay": float(d_from.max()),
            "start_speed": speeds[0], "end_speed": speeds[1], "speed_scale": speed_scale,
            "cusp_speed_limit": cusp_limit,
            "passed": bool(sec.success and dev <= tol and max(speeds) <= cusp_limit),
        }
        drifts = []
        for p in sec.section.pieces:
            if not p.segment.constant:
                continue  # a spiral: neither p1 + r p2 nor p2 is conserved
            mp = rows.get(p.index)
            if mp is None or mp.size < 2:
                continue
            k = p.segment.coefficients[0]
            if k != 0.0:
                # r = xi2 / xi1 in the body frame: the path's radius, negated where the blade runs
                # backwards (its speed xi2 is then negative while the heading turns the same way)
                inv = sub.state[0, mp] + p.direction * sub.state[1, mp] / k
                name = "p1 + r p2"
            else:
                inv = sub.state[1, mp]
                name = "p2"
            drifts.append({"piece": p.index, "invariant": name, "drift": float(np.ptp(inv)),
                           "scale": float(np.max(np.abs(inv)) + 1e-300)})
        out[si] = (record, drifts)
    if only is None:
        _PROGRESS.report("measuring", len(trace.sections), len(trace.sections))
    return out


def _rows_by_piece(piece: np.ndarray) -> dict[int, np.ndarray]:
    """The rows labelled with each piece, increasing: ``np.flatnonzero(piece == k)`` for every ``k`` at once."""
    order = np.argsort(piece, kind="stable")
    labels, starts = np.unique(piece[order], return_index=True)
    ends = np.append(starts[1:], piece.size)
    return {int(k): order[a:b] for k, a, b in zip(labels, starts, ends)}


#: The relative perturbation of the controls by which the replay's conditioning is measured (four
#: orders of magnitude above double-precision round-off), and the share of the tolerance its spread
#: may take before the open-loop replay is no longer a sharp enough instrument.
PERTURBATION = 1e-12
SPREAD_SHARE = 0.1
_OPEN_LOOP_KEYS = ("max_deviation_replay_to_figure", "max_deviation_figure_to_replay", "start_speed", "end_speed")


def _spreads(params: SleighParams, base: Replay, others: list[Replay], rows: dict[int, np.ndarray]) -> dict:
    """How far the replays ``others`` stray from ``base`` on each section's ``rows``: ``(position,
    cusp speed)``, the blade's largest distance (inf where it is not finite) and the largest change of
    the speed's size at the section's two ends."""
    out = {si: (0.0, 0.0) for si in rows}
    _, v0, _ = base.velocities(params)
    for other in others:
        _, v1, _ = other.velocities(params)
        d = np.hypot(*(other.state[3:5] - base.state[3:5]))
        for si, m in rows.items():
            far = float(np.max(d[m], initial=0.0)) if np.all(np.isfinite(d[m])) else math.inf
            ends = m[[0, -1]]
            speed = float(np.max(np.abs(np.abs(v1[ends]) - np.abs(v0[ends]))))
            out[si] = (max(out[si][0], far), max(out[si][1], speed))
    return out


def _too_spread(position: float, cusp_speed: float, tol: float, cusp_speed_limit: float) -> bool:
    """Whether an instrument's spread under ``PERTURBATION`` reaches ``SPREAD_SHARE`` of what it checks."""
    return bool(position >= SPREAD_SHARE * tol or cusp_speed >= SPREAD_SHARE * cusp_speed_limit)


def _conditioning(trace: FigureTrace, schedule: ControlSchedule, rep: Replay, sections, records, tol: float) -> dict:
    """How much the replay of each of ``sections`` moves when the controls move by ``PERTURBATION``.

    The schedule's ``a, b, adot, bdot`` are scaled by ``1 +- PERTURBATION`` and replayed again. The
    spread of the blade's position (and of the cusp speeds) between the three replays is what the
    open-loop check cannot resolve: where it reaches ``SPREAD_SHARE`` of the tolerance (or of the
    cusp-speed limit), the open loop is ill-conditioned for this check.
    """
    others = []
    for sign in (1.0, -1.0):
        f = 1.0 + sign * PERTURBATION
        other = replay(trace, ControlSchedule(t=schedule.t, a=schedule.a * f, b=schedule.b * f, adot=schedule.adot * f,
                                              bdot=schedule.bdot * f, section=schedule.section, piece=schedule.piece))
        if other.t.shape != rep.t.shape:
            return {si: {"perturbation": PERTURBATION, "ill_conditioned": False} for si in sections}
        others.append(other)
    spreads = _spreads(trace.params, rep, others, {si: np.flatnonzero(rep.section == si) for si in sections})
    size = trace.figure.size()
    out = {}
    for si in sections:
        xy, v = spreads[si]
        out[si] = {
            "perturbation": PERTURBATION, "position_spread": xy, "amplification": xy / (PERTURBATION * size),
            "cusp_speed_spread": v, "ill_conditioned": _too_spread(xy, v, tol, records[si]["cusp_speed_limit"]),
        }
    return out


#: How close (relative) a schedule's rows must be to the traced section's controls for the closed
#: loop about that section to vouch for them.
SAME_SCHEDULE = 1e-9
#: The closed loop's reference is sampled at 20,000 times per section; beyond this many turns of
#: the heading in a section it no longer resolves the motion, and the open loop's verdict stands.
MAX_CLOSED_LOOP_TURNS = 20.0


def _closed_loop_resolves(trace: FigureTrace, si: int) -> bool:
    """Whether section ``si`` is short enough in turning for the closed loop's reference."""
    turning = sum(abs(p.segment.turn) if p.segment.constant else p.segment.length * p.segment.max_abs_curvature()
                  for p in trace.sections[si].section.pieces)
    return turning <= MAX_CLOSED_LOOP_TURNS * 2 * math.pi


def _schedule_is_the_trace(trace: FigureTrace, schedule: ControlSchedule, si: int) -> bool:
    """Whether the schedule's rows of section ``si`` are the traced section's own controls.

    To ``SAME_SCHEDULE`` of each control's largest value: the rows' times are absolute, and taking
    the section's start off again rounds them, which moves a planned section's fast rates at its
    rests by about 1e-12 of their scale.
    """
    sec = trace.sections[si]
    rows = np.flatnonzero(schedule.section == si)
    if rows.size < 2:
        return False
    t = np.clip(schedule.t[rows] - trace.start_times[si], 0.0, sec.duration)
    got = np.vstack([schedule.a[rows], schedule.b[rows], schedule.adot[rows], schedule.bdot[rows]])
    close = np.zeros(rows.size, dtype=bool)
    for side in ("right", "left"):
        v = sec.evaluate(t, side=side, geometry=False)
        ref = np.vstack([v["a"], v["b"], v["adot"], v["bdot"]])
        scale = np.max(np.abs(ref), axis=1, keepdims=True) + 1e-300
        close |= np.all(np.abs(got - ref) <= SAME_SCHEDULE * scale, axis=0)
    return bool(np.all(close))


def _closed_loop(trace: FigureTrace, rep: Replay, sections) -> tuple[Replay, dict[int, float], dict[int, dict]]:
    """``rep`` with the rows of ``sections`` replaced by the closed loop's: the model under the
    tracking law about the trace (:func:`skatetrace.feedback.closed_loop.replay_law`). Also the
    law's largest correction in each, and the closed loop's own conditioning (a section whose law
    could not be designed or whose closed loop could not be integrated is left out, and keeps the
    open loop's rows and verdict).

    Each section starts at rest where the figure places it, as the replay does at a curve's start:
    where the previous section ended was checked already (within the tolerance of that point, and
    at rest), and a start error carried over would be corrected by the law and counted against
    the schedule.

    The conditioning is measured as the open loop's (:func:`_conditioning`): the gains scaled by
    ``1 +- PERTURBATION`` and the closed loop replayed again. On a long section with the mass far
    from the blade the closed loop can still amplify round-off to the cusp-speed limit (measured:
    a phosphor spiral's end speed between 0.7 and 2.3 times its limit under such changes), and
    then its verdict is no more than one run's digits.
    """
    params = trace.params
    rows = {si: np.flatnonzero(rep.section == si) for si in sections}
    # the sections' laws and replays are independent: side by side (the same numbers either way)
    done = map_forked(partial(_closed_loop_runs, trace, rep), [(si, rows[si]) for si in sections])
    runs = {si: (rows[si], out) for si, out in zip(sections, done) if out is not None}
    closed = []
    for k in range(3):
        state, controls = rep.state.copy(), rep.controls.copy()
        for m, out in runs.values():
            z, rates, _ = out[k]
            state[:, m] = z[:5]
            controls[:, m] = np.vstack([z[5:7], rates])
        closed.append(Replay(t=rep.t, state=state, controls=controls, section=rep.section, piece=rep.piece))
    corrections = {si: out[0][2] for si, (m, out) in runs.items()}
    spreads = {si: {"perturbation": PERTURBATION, "position_spread": xy, "cusp_speed_spread": v}
               for si, (xy, v) in _spreads(params, closed[0], closed[1:], {si: m for si, (m, _) in runs.items()}).items()}
    return closed[0], corrections, spreads


def _closed_loop_runs(trace: FigureTrace, rep: Replay, job: tuple[int, np.ndarray]) -> list | None:
    """Section ``si``'s closed loop at the replay's rows ``m`` (``job = (si, m)``), under the law and
    under its gains scaled by ``1 +- PERTURBATION``: three ``(states, rates, correction)``, or None
    where the law could not be designed or a run could not be integrated (the open loop's verdict
    stands)."""
    from ..feedback.closed_loop import replay_law
    from ..feedback.lqr import TrackingLaw, default_gains, design
    from ..feedback.reference import section_reference

    si, m = job
    params = trace.params
    ref = section_reference(trace.sections[si], params)
    law = design(ref, params, default_gains(trace.figure.size()))
    if not law.success:
        return None
    z0 = ref.state_at(0.0)[0][:, 0]
    t = np.clip(rep.t[m] - trace.start_times[si], 0.0, ref.duration)
    out = []
    for f in (1.0, 1.0 + PERTURBATION, 1.0 - PERTURBATION):
        scaled = law if f == 1.0 else TrackingLaw(reference=ref, t=law.t, K=law.K * f, params=params)
        z, rates, correction, ok = replay_law(ref, scaled, params, z0, t)
        if not ok:
            return None
        out.append((z, rates, correction))
    return out


def check_rel_tol(rel_tol) -> None:
    """Refuse a verification tolerance that is not a number in (0, 1]: ``deviation > NaN`` is False,
    so a NaN tolerance would pass every check."""
    if isinstance(rel_tol, bool) or not isinstance(rel_tol, (int, float, np.integer, np.floating)) \
            or not 0.0 < rel_tol <= 1.0:
        raise ValueError(f"rel_tol must be a number in (0, 1] (a fraction of the figure's size), got {rel_tol!r}")


def verify(trace: FigureTrace, schedule: ControlSchedule | None = None, *, rel_tol: float = 1e-6) -> VerificationReport:
    """Replay ``trace``'s controls through the full dynamics and measure everything.

    Parameters
    ----------
    rel_tol : float
        Allowed deviation from the figure as a fraction of the figure's size, in (0, 1].

    Raises
    ------
    ValueError
        If ``rel_tol`` is not a number in (0, 1] (a NaN tolerance would pass every check).
    """
    return _verified(trace, schedule, rel_tol, None)[0]


def verify_within(trace: FigureTrace, schedule: ControlSchedule, share: float, *,
                  rel_tol: float = 1e-6) -> tuple[VerificationReport | None, tuple[int, ...]]:
    """:func:`verify`'s report where it passes within ``share`` of every limit, else the sections that keep it from it.

    Returns ``(report, ())`` where ``verify`` followed by :meth:`VerificationReport.passed_within`
    passes, else ``(None, sections)``. The answer comes sooner where the open-loop replay already
    decides it: a section that passes in the open loop keeps that loop's numbers, so where one of
    them lies beyond ``share`` of its limit, or where a section that fails cannot be verified by
    the closed loop instead, neither the replay's conditioning nor the closed loop is run. The
    sections named are then those beyond the share and those that fail the open loop (undecided);
    else those whose verdict lies beyond the share or fails; every section where the trace
    failed or the replay broke down. (A plan sampled coarsely whose replay comes that close to a
    limit has those sections sampled again more finely, :func:`~skatetrace.pipeline.trace_and_verify`.)
    """
    report, beyond = _verified(trace, schedule, rel_tol, share)
    if report is not None:
        if report.passed_within(share):
            return report, ()
        beyond = _outside({si: rec for si, rec in enumerate(report.sections)}, share, report.tolerance)
    return None, beyond or tuple(range(len(trace.sections)))


def _outside(records: dict[int, dict], share: float, tol: float) -> tuple[int, ...]:
    """The traced sections of ``records`` that fail, or lie beyond ``share`` of the tolerance or a cusp-speed limit."""
    return tuple(si for si, r in records.items() if r["traced"] and (
        not r["passed"] or max(r["max_deviation_replay_to_figure"], r["max_deviation_figure_to_replay"]) > share * tol
        or max(r["start_speed"], r["end_speed"]) > share * r["cusp_speed_limit"]))


def _open_loop_beyond(trace: FigureTrace, rep: Replay, measured: dict, failing: list[int], share: float,
                      tol: float) -> tuple[int, ...]:
    """Where the open loop's ``measured`` records already keep the report from passing within ``share``: the
    sections that pass it beyond the share, with those that fail it; else (nothing decided) none."""
    if not trace.success or not np.all(np.isfinite(rep.state)):
        return tuple(range(len(trace.sections)))
    passing = {si: r for si, (r, _) in measured.items() if si not in failing}
    beyond = _outside(passing, share, tol)
    return tuple(sorted(beyond + tuple(failing))) if beyond else ()


def _verified(trace: FigureTrace, schedule: ControlSchedule | None, rel_tol: float,
              within: float | None) -> tuple[VerificationReport | None, tuple[int, ...]]:
    """``(report, ())``: :func:`verify`; or ``(None, sections)`` as soon as the report is sure not to pass within
    ``within`` of every limit (if given), with the sections that keep it from it (see :func:`verify_within`)."""
    check_rel_tol(rel_tol)
    if schedule is None:
        schedule, _ = schedule_from_trace(trace)
    size = trace.figure.size()
    tol = rel_tol * size
    rep = replay(trace, schedule)
    measured = _measure(trace, rep, tol)
    conditioning = {}
    decided = rep  # the rows each section's verdict rests on
    failing = [si for si, (r, _) in measured.items() if r["traced"] and not r["passed"] and trace.sections[si].success]
    beyond = () if within is None else _open_loop_beyond(trace, rep, measured, failing, within, tol)
    if beyond:
        return None, beyond
    if failing and np.all(np.isfinite(rep.state)):
        conditioning = _conditioning(trace, schedule, rep, failing, {si: measured[si][0] for si in failing}, tol)
        # the closed loop follows the trace's own motion: it stands in only for the trace's own schedule
        ill = [si for si in failing if conditioning[si]["ill_conditioned"] and _closed_loop_resolves(trace, si)
               and _schedule_is_the_trace(trace, schedule, si)]
        if within is not None and len(ill) < len(failing):
            return None, tuple(failing)  # a section fails the open loop, and the closed loop cannot stand in for it
        if ill:
            closed, corrections, spreads = _closed_loop(trace, rep, ill)
            ill = list(corrections)
            if ill:
                decided = closed
            again = _measure(trace, closed, tol, only=ill)
            for si in ill:
                record, drifts = again[si]
                record["open_loop"] = {k: measured[si][0][k] for k in _OPEN_LOOP_KEYS}
                record["max_correction"] = corrections[si]
                record["instrument"] = "closed loop"
                spread = spreads[si]
                spread["ill_conditioned"] = _too_spread(spread["position_spread"], spread["cusp_speed_spread"], tol,
                                                        record["cusp_speed_limit"])
                record["closed_loop_conditioning"] = spread
                # the closed loop stands for the schedule only if the law barely departed from it,
                # and only if its own verdict is more than round-off
                record["passed"] = bool(record["passed"] and corrections[si] <= rel_tol
                                        and not spread["ill_conditioned"])
                measured[si] = (record, drifts)
    sections, drifts, cusp_speeds, bad_cusps, problems = [], [], [], [], []
    dev_to, dev_from = 0.0, 0.0
    for si in range(len(trace.sections)):
        record, d = measured[si]
        if record["traced"]:
            record.setdefault("instrument", "open loop")
        if si in conditioning:
            record["conditioning"] = conditioning[si]
        if record.get("max_correction", 0.0) > rel_tol:
            problems.append(f"section {si}: the closed loop departed from the schedule by "
                            f"{record['max_correction']:.3g} of its fastest rate (limit {rel_tol:g}), "
                            "so it does not vouch for it")
        if record.get("closed_loop_conditioning", {}).get("ill_conditioned"):
            c = record["closed_loop_conditioning"]
            problems.append(f"section {si}: neither replay can decide (the open loop is ill-conditioned, and a change "
                            f"of {PERTURBATION:g} in the closed loop's gains moves its cusp speed by "
                            f"{c['cusp_speed_spread']:.3g} (limit {record['cusp_speed_limit']:.3g}) and the blade by "
                            f"{c['position_spread']:.3g} (tolerance {tol:.3g}))")
        sections.append(record)
        drifts.extend(d)
        if not record["traced"]:
            continue
        speeds = (record["start_speed"], record["end_speed"])
        cusp_speeds.extend(speeds)
        if max(speeds) > record["cusp_speed_limit"]:
            bad_cusps.append(f"section {si}: {max(speeds):.3g} > {record['cusp_speed_limit']:.3g}")
        dev_to = max(dev_to, record["max_deviation_replay_to_figure"])
        dev_from = max(dev_from, record["max_deviation_figure_to_replay"])
    max_dev = max(dev_to, dev_from)
    if not np.all(np.isfinite(rep.state)):
        max_dev = math.inf  # the replay broke down somewhere: never let NaN pass a comparison
    max_cusp = max(cusp_speeds) if cusp_speeds else 0.0
    if not trace.success:
        problems.insert(0, trace.message)
    if max_dev > tol:
        problems.append(f"deviation {max_dev:.3g} exceeds {tol:.3g} ({rel_tol:g} x figure size {size:.4g})")
    if bad_cusps:
        problems.append("speed at a cusp above 1e-8 of the section's fastest motion (" + "; ".join(bad_cusps) + ")")
    ok = not problems
    return VerificationReport(
        success=ok, status="passed" if ok else "failed",
        message="all checks passed" if ok else "; ".join(problems),
        figure_size=size, tolerance=tol, max_deviation=max_dev, max_deviation_to_figure=dev_to,
        max_deviation_from_figure=dev_from, max_cusp_speed=max_cusp, cusp_speeds=cusp_speeds,
        sections=sections, invariant_drift=drifts, replay=decided,
    ), ()
