"""Measure a paper-style arc, and the exact engine's arc, with the same yardsticks.

:func:`evaluate_paper_arc` takes control parameters for a :class:`~skatetrace.paper.tables.PaperRow`,
integrates the reduced model accurately, then re-simulates the **full** five equations from the
table's initial condition under the same mass motion (``a, b, adot, bdot`` as functions of time:
the formulas for the main method; for the appendix ``a`` from the formula and ``b, bdot`` from the
reduced solution). :func:`evaluate_exact_arc` traces the same circle with the exact engine and
verifies it. Both return an :class:`ArcEvaluation` so the report can put them side by side.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from ..dynamics.model import SleighParams, mass_energy, singular_point, skate_energy, velocities
from ..dynamics.simulate import simulate
from ..figures.figure import Curve, Figure
from ..figures.geometry import Pose, Segment
from ..tracing.sections import TraceOptions, trace_figure
from ..verification.deviation import deviation_cost, segments_target
from ..verification.verify import schedule_from_trace, verify
from .controls import CircularControl, b_rate_printed, control_from_params
from .procedure import _cost_of
from .reduced import TIGHT_SOLVER, ReducedArc, ReducedOptions, integrate_reduced
from .tables import PaperRow

__all__ = ["ArcEvaluation", "evaluate_paper_arc", "evaluate_exact_arc", "singular_distances", "full_replay"]


@dataclass(frozen=True, slots=True, kw_only=True)
class ArcEvaluation:
    """The yardsticks of one arc, whichever method produced it.

    Attributes
    ----------
    label : str
        ``"published"``, ``"re-run"`` or ``"exact"``.
    values : tuple
        Control parameters (empty for the exact engine).
    cost : float
        The row's own cost (length or end point) evaluated accurately; for the exact engine the
        same cost from its arc.
    length_error : float
        Signed ``L_s - L_d`` (length rows) or end-point miss (point rows) of the accurate
        reduced solution.
    end_speeds : tuple
        Speeds at the two ends, model used to produce the arc (reduced or exact).
    completed : bool
        Both ends stopped where the speed vanished.
    full_deviation : float
        Full dynamics: largest distance from the target circle ``| |xy - c| - r |``.
    full_end_speeds : tuple
        Full dynamics: ``xi2`` at the two ends.
    full_success : bool
        The full-dynamics integration reached both ends (a singular control can stop it; the
        other full-dynamics numbers then cover what was integrated).
    full_length : float
        Full dynamics: distance travelled.
    deviation_cost : float
        The paper's C (p = 2) of the full-dynamics path against the target arc.
    regularity_margin : float or None
        ``a1^2 - (a2^2 + a3^2)``; regular if positive (None for the exact engine).
    min_abs_a, min_dist_b_singular, min_dist_singular_point : float
        Along the arc: ``min |a|`` (0 where ``a`` changes sign or an end stops at ``a = 0``) and ``min |b - (M + m) r / m|`` (the singular set of
        (b_diff_eq)), and the distance to ``(0, -I / (M r))``, the only point where the exact
        engine's formulation is singular.
    peak_mass_energy, peak_skate_energy : float
    seconds : float
        Wall time of producing the arc (procedure or exact engine), if known.
    ok : bool
        The model's arc stopped at both ends, and the full dynamics reached both ends, stayed on
        the circle within ``1e-6`` and stopped there within ``1e-6``: the arc really is what it
        claims.
    notes : tuple of str
    series : dict
        Sampled reduced (or exact) solution for plots; ``full`` holds the full-dynamics samples.
    """

    label: str
    values: tuple
    cost: float
    length_error: float
    end_speeds: tuple
    completed: bool
    full_deviation: float
    full_end_speeds: tuple
    full_length: float
    deviation_cost: float
    regularity_margin: float | None
    min_abs_a: float
    min_dist_b_singular: float
    min_dist_singular_point: float
    peak_mass_energy: float
    peak_skate_energy: float
    full_success: bool = True
    seconds: float = math.nan
    notes: tuple = ()
    series: dict = field(default_factory=dict, repr=False, compare=False)
    full: dict = field(default_factory=dict, repr=False, compare=False)

    @property
    def ok(self) -> bool:
        speeds = [abs(v) for v in self.full_end_speeds]
        return bool(self.completed and self.full_success and self.full_deviation <= 1e-6 and speeds
                    and max(speeds) <= 1e-6)

    def to_dict(self) -> dict:
        keys = ("label", "values", "cost", "length_error", "end_speeds", "completed", "full_deviation",
                "full_end_speeds", "full_length", "deviation_cost", "regularity_margin", "min_abs_a",
                "min_dist_b_singular", "min_dist_singular_point", "peak_mass_energy", "peak_skate_energy",
                "full_success", "seconds", "notes")
        out = {k: getattr(self, k) for k in keys}
        out["ok"] = self.ok
        return out


def singular_distances(params: SleighParams, radius: float, a, b) -> tuple[float, float, float]:
    """``min |a|``, ``min |b - (M + m) r / m|`` and the least distance to ``(0, -I / (M r))``."""
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    b_sing = (params.M + params.m) * radius / params.m
    sx, sy = singular_point(params, 1.0 / radius)
    return (float(np.min(np.abs(a))), float(np.min(np.abs(b - b_sing))),
            float(np.min(np.hypot(a - sx, b - sy))))


def _controls_fn(arc: ReducedArc):
    """``t -> (a, b, adot, bdot)`` of the reduced solution, for the full simulation."""
    ctrl, params, r, c = arc.control, arc.params, arc.radius, arc.invariant

    if isinstance(ctrl, CircularControl):
        def fn(t):
            a, ad = ctrl.a(t)
            b, bd = ctrl.b(t)
            return a, b, ad, bd
        return fn

    def fn(t):
        half = arc.backward if (t < 0 and arc.backward is not None) else arc.forward
        y = half.sol(t)
        p1, b = float(y[0]), float(y[4])
        a, ad = ctrl.a(t)
        return a, b, ad, b_rate_printed(params, r, p1, (c - p1) / r, a, ad, b)
    return fn


def full_replay(arc: ReducedArc, initial, n: int = 3000, max_nfev: int = 400_000, *, rtol: float = 1e-12,
                atol: float = 1e-13) -> dict:
    """Simulate the full dynamics under ``arc``'s mass motion from ``initial`` over ``[t1, t2]``.

    Returns samples ``t, p1, p2, theta, x, y, a, b, adot, bdot, xi1, xi2`` (ordered in time), and
    ``success``/``message`` of the two integrations (DOP853 at ``rtol``, ``atol``).
    """
    params = arc.params
    fn = _controls_fn(arc)
    y0 = np.asarray(initial[:5], dtype=float)
    parts, ok, msgs = [], True, []
    for t_end in (arc.t1, arc.t2):
        if t_end == 0.0:
            continue
        with np.errstate(all="ignore"):
            tr = simulate(params, y0, fn, (0.0, t_end), rtol=rtol, atol=atol, max_nfev=max_nfev)
        ok &= tr.success
        msgs.append(tr.message)
        if tr.success:
            tt = np.linspace(0.0, t_end, n)
        else:
            tt = tr.t  # what was integrated before the failure
        st = tr(tt) if tr.success else tr.state
        parts.append((tt, st))
    if len(parts) == 2:
        (tb, sb), (tf, sf) = parts
        t = np.concatenate([tb[::-1], tf[1:]])
        st = np.hstack([sb[:, ::-1], sf[:, 1:]])
    else:
        t, st = parts[0]
    ctrl = np.array([fn(float(ti)) for ti in t]).T if t.size else np.empty((4, 0))
    with np.errstate(all="ignore"):
        xi1, xi2, _ = velocities(params, st[0], st[1], *ctrl)
    return {"t": t, "p1": st[0], "p2": st[1], "theta": st[2], "x": st[3], "y": st[4], "a": ctrl[0], "b": ctrl[1],
            "adot": ctrl[2], "bdot": ctrl[3], "xi1": xi1, "xi2": xi2, "success": bool(ok), "message": "; ".join(msgs)}


def _target(row: PaperRow, start: Pose):
    return segments_target(start, [Segment(1.0 / row.radius, row.exact_length)])


def _circle_distance(row: PaperRow, x, y) -> float:
    cx, cy = row.centre
    d = np.abs(np.hypot(np.asarray(x) - cx, np.asarray(y) - cy) - row.radius)
    return float(np.max(d)) if d.size and np.all(np.isfinite(d)) else math.inf


def evaluate_paper_arc(row: PaperRow, values, label: str, *, params: SleighParams = SleighParams(),
                       options: ReducedOptions = TIGHT_SOLVER, seconds: float = math.nan,
                       full_rtol: float = 1e-12) -> ArcEvaluation:
    """All yardsticks for the paper's method with control parameters ``values`` on ``row``.

    ``options`` integrate the reduced model, ``full_rtol`` (``atol = full_rtol / 10``) the full
    dynamics; :mod:`~skatetrace.paper.conditioning` varies both to see which yardsticks are stable.
    """
    control = control_from_params(row.method, values)
    arc = integrate_reduced(params, row.radius, row.initial, control, row.T, options)
    cost = _cost_of(row, arc, 2.0)  # the point cost reads the forward half only
    if row.method == "point":
        miss = math.hypot(arc.forward.state[2, -1] - row.target_point[0], arc.forward.state[3, -1] - row.target_point[1])
    else:
        miss = arc.length - row.target_length
    s = arc.sample(1200)
    full = full_replay(arc, row.initial, rtol=full_rtol, atol=full_rtol / 10)
    notes = [f"{name} half: {h.message}" for name, h in (("backward", arc.backward), ("forward", arc.forward))
             if h is not None and h.status != "stopped"]
    if not full["success"]:
        notes.append(f"full dynamics: {full['message']}")
    # The point rows score the forward half (from the initial condition) against the arc to the target.
    if row.method == "point":
        fwd = full["t"] >= 0
        path = np.vstack([full["x"][fwd], full["y"][fwd]])
        X, L = _target(row, Pose(*row.initial[3:5], row.initial[2]))
    else:
        path = np.vstack([full["x"], full["y"]])
        X, L = _target(row, Pose(float(s["x"][0]), float(s["y"][0]), float(s["theta"][0])))
    C = deviation_cost(path, X, L).value if np.all(np.isfinite(path)) and path.shape[1] > 1 else math.inf
    fs = (float(full["xi2"][0]), float(full["xi2"][-1])) if full["t"].size else (math.nan, math.nan)
    sd = singular_distances(params, row.radius, s["a"], s["b"])
    if _reaches_a_zero(s["a"]):
        sd = (0.0,) + sd[1:]
    ke_m = mass_energy(params, s["xi1"], s["xi2"], s["a"], s["b"], s["adot"], s["bdot"])
    ke_s = skate_energy(params, s["xi1"], s["xi2"])
    full_len = float(np.sum(np.hypot(np.diff(full["x"]), np.diff(full["y"])))) if full["t"].size > 1 else 0.0
    return ArcEvaluation(
        label=label, values=tuple(float(v) for v in values), cost=cost, length_error=float(miss),
        end_speeds=arc.end_speeds(), completed=arc.completed, full_deviation=_circle_distance(row, full["x"], full["y"]),
        full_end_speeds=fs, full_length=full_len, deviation_cost=C,
        regularity_margin=control.regularity_margin(), min_abs_a=sd[0], min_dist_b_singular=sd[1],
        min_dist_singular_point=sd[2], peak_mass_energy=_finite_max(ke_m), peak_skate_energy=_finite_max(ke_s),
        full_success=bool(full["success"]), seconds=seconds, notes=tuple(notes), series=s, full=full,
    )


def _reaches_a_zero(a, tol: float = 1e-9) -> bool:
    """``a`` changes sign along the samples, or comes within ``tol`` of 0 (an end stopped at a zero).

    Then ``min |a|`` over the arc is 0, whatever the sampled minimum happens to be: the samples'
    smallest ``|a|`` (1e-4 or 1e-15) only says how close a sample or a failed step fell to the zero.
    """
    a = np.asarray(a, dtype=float)
    a = a[np.isfinite(a)]
    return bool(a.size and (np.any(a[:-1] * a[1:] < 0) or np.min(np.abs(a)) <= tol))


def _finite_max(v) -> float:
    v = np.asarray(v, dtype=float)
    return float(np.max(v)) if v.size and np.all(np.isfinite(v)) else math.inf


def evaluate_exact_arc(row: PaperRow, *, params: SleighParams = SleighParams(),
                       options: TraceOptions = TraceOptions()) -> ArcEvaluation:
    """Trace ``row``'s arc (same radius, :attr:`PaperRow.exact_length`, rest to rest) exactly and verify it.

    The arc starts at the table's initial point and heading. The full-dynamics numbers come from
    :func:`skatetrace.verification.verify.verify` (the independent replay of the written controls).
    """
    t0 = time.perf_counter()
    start = Pose(row.initial[3], row.initial[4], row.initial[2])
    seg = Segment(1.0 / row.radius, row.exact_length)
    fig = Figure(f"paper {row.key}", (Curve((seg,), start=start, name=row.key),), params)
    trace = trace_figure(fig, params, options)
    schedule, _ = schedule_from_trace(trace)
    report = verify(trace, schedule)
    seconds = time.perf_counter() - t0
    sec = trace.sections[0]
    notes = [] if trace.success else [trace.message]
    if not report.success:
        notes.append(f"verification: {report.message}")
    if not sec.phases:
        return ArcEvaluation(label="exact", values=(), cost=math.inf, length_error=math.nan, end_speeds=(math.nan,) * 2,
                             completed=False, full_deviation=math.inf, full_end_speeds=(math.nan,) * 2,
                             full_length=math.nan, deviation_cost=math.inf, regularity_margin=None,
                             min_abs_a=math.nan, min_dist_b_singular=math.nan, min_dist_singular_point=math.nan,
                             peak_mass_energy=math.nan, peak_skate_energy=math.nan, seconds=seconds, notes=tuple(notes))
    t = np.unique(np.concatenate([np.linspace(0.0, sec.duration, 2400), sec.breakpoints()]))
    v = sec.evaluate(t)
    s = {k: v[k] for k in ("p1", "p2", "theta", "x", "y", "a", "b", "adot", "bdot", "xi1", "xi2")}
    s["t"], s["speed"] = t, v["xi2"]
    rep = report.replay
    full = {"t": rep.t, "x": rep.state[3], "y": rep.state[4], "p1": rep.state[0], "p2": rep.state[1],
            "theta": rep.state[2]}
    X, L = _target(row, start)
    C = deviation_cost(np.vstack([rep.state[3], rep.state[4]]), X, L).value
    if row.method == "point":
        end = sec.evaluate([sec.duration])
        cost = float((end["x"][0] - row.target_point[0]) ** 2 + (end["y"][0] - row.target_point[1]) ** 2) ** 2
    else:
        cost = (row.exact_length - sec.length) ** 2
    sd = singular_distances(params, row.radius, s["a"], s["b"])
    if _reaches_a_zero(s["a"]):
        sd = (0.0,) + sd[1:]
    ke_m = mass_energy(params, s["xi1"], s["xi2"], s["a"], s["b"], s["adot"], s["bdot"])
    ke_s = skate_energy(params, s["xi1"], s["xi2"])
    xi1r, xi2r, _ = report.replay.velocities(params)
    return ArcEvaluation(
        label="exact", values=(), cost=float(cost), length_error=float(sec.length - row.exact_length),
        end_speeds=(float(v["xi2"][0]), float(v["xi2"][-1])), completed=bool(sec.success),
        full_deviation=float(report.max_deviation), full_end_speeds=(float(xi2r[0]), float(xi2r[-1])),
        full_length=float(np.sum(np.hypot(np.diff(rep.state[3]), np.diff(rep.state[4])))), deviation_cost=C,
        regularity_margin=None, min_abs_a=sd[0], min_dist_b_singular=sd[1], min_dist_singular_point=sd[2],
        peak_mass_energy=float(np.max(ke_m)), peak_skate_energy=float(np.max(ke_s)),
        full_success=bool(report.replay is not None and np.all(np.isfinite(rep.state))), seconds=seconds,
        notes=tuple(notes), series=s, full=full,
    )
