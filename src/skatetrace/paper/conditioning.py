"""How much of each reproduced number survives tiny perturbations: only stable digits are printed.

Several of the paper's rows pass through ``a = 0``, where eq. (b_diff_eq) is singular
(:mod:`~skatetrace.paper.singular`): what an accurate integration reports after such a crossing
depends on its step sizes and on round-off, and differs between CPUs. So every evaluation in the
report is repeated under perturbations that any honest result must survive,

- the solver tolerances (reduced model ``rtol`` 1e-10 to 1e-13, full dynamics ten times tighter,
  at least 1e-13; for the exact engine its own ``rtol``), and
- the initial state multiplied component-wise by ``1 +- 1e-12`` (random signs, a few seeds; a zero
  component becomes ``+-1e-12``),

and each yardstick is reported by its spread over the runs (:class:`Spread`): as many significant
digits as the spread leaves stable (:func:`stable_digits`), a bound ``<= 1e-N`` for residuals at
round-off level, and ``ill-conditioned (spread lo to hi)`` where the runs disagree by more than
10 % (or a yes/no verdict differs between runs).
"""

from __future__ import annotations

import dataclasses
import math
import time
from dataclasses import dataclass, field
from typing import Sequence

import numpy as np

from ..dynamics.model import SleighParams
from ..tracing.sections import TraceOptions
from .evaluate import ArcEvaluation, evaluate_exact_arc, evaluate_paper_arc
from .procedure import paper_cost
from .reduced import TIGHT_SOLVER, ReducedOptions
from .tables import PaperRow

__all__ = ["Perturbation", "Spread", "Conditioning", "perturbations", "stable_digits", "format_stable",
           "spread_of", "condition_paper_arc", "condition_exact_arc", "condition_cost", "ILL_CONDITIONED"]

#: Relative spread above which a number is reported as ill-conditioned.
ILL_CONDITIONED = 0.1
#: Residuals (distances, end speeds, the exact engine's errors) at or below this are reported as bounds.
RESIDUAL_FLOOR = 1e-8


@dataclass(frozen=True, slots=True)
class Perturbation:
    """One perturbed re-run: a solver ``rtol`` (None: the nominal one) and/or a seed for the initial state."""

    label: str
    rtol: float | None = None
    seed: int | None = None
    eps: float = 1e-12

    def initial(self, initial: Sequence[float]) -> tuple[float, ...]:
        """``initial`` with each component times ``1 +- eps`` (zeros become ``+-eps``); unchanged without a seed."""
        x = np.asarray(initial, dtype=float)
        if self.seed is None:
            return tuple(float(v) for v in x)
        signs = np.random.default_rng(self.seed).choice([-1.0, 1.0], size=x.size)
        out = np.where(x != 0.0, x * (1.0 + self.eps * signs), self.eps * signs)
        return tuple(float(v) for v in out)


def perturbations(rtols: Sequence[float] = (1e-10, 1e-11, 1e-12, 1e-13), seeds: Sequence[int] = (1, 2, 3),
                  eps: float = 1e-12) -> tuple[Perturbation, ...]:
    """The default set: one run per tolerance, one per seed (at the nominal tolerance)."""
    for rt in rtols:
        if not (rt > 0 and math.isfinite(rt)):
            raise ValueError(f"tolerances must be positive numbers, got {rt!r}")
    if not (eps > 0 and math.isfinite(eps)):
        raise ValueError(f"eps must be a positive number, got {eps!r}")
    return (tuple(Perturbation(f"rtol {rt:g}", rtol=float(rt)) for rt in rtols)
            + tuple(Perturbation(f"initial state x (1 +- {eps:g}), seed {s}", seed=int(s), eps=eps) for s in seeds))


def stable_digits(lo: float, hi: float, max_digits: int = 4) -> int:
    """Significant digits that ``lo`` and ``hi`` share: ``floor(-log10(|hi - lo| / max(|lo|, |hi|)))``.

    Clamped to ``[0, max_digits]``; 0 when the two differ in sign or by 100 % or more, or are not
    finite; ``max_digits`` when they are equal.

    Examples
    --------
    >>> stable_digits(0.0855, 0.0856), stable_digits(1.0, 1.0), stable_digits(2.9e-6, 4.9e-5)
    (2, 4, 0)
    >>> stable_digits(-1.0, 1.0), stable_digits(0.14299, 0.14301)  # both print as 0.143
    (0, 3)
    """
    lo, hi = float(lo), float(hi)
    if not (math.isfinite(lo) and math.isfinite(hi)):
        return 0
    if lo == hi:
        return max_digits
    if lo * hi < 0:
        return 0
    rel = abs(hi - lo) / max(abs(lo), abs(hi))
    if rel >= 1.0:
        return 0
    return max(0, min(max_digits, math.floor(-math.log10(rel))))


def _g(x: float, digits: int) -> str:
    """``x`` to ``digits`` significant digits, trailing zeros kept (they are stable digits too)."""
    if x == 0.0:
        return "0"
    mant, e, exp = f"{x:#.{digits}g}".partition("e")
    return mant.rstrip(".") + e + exp


def _decade_bound(x: float) -> str:
    """``<= 1e-N``: the smallest power of ten at or above ``|x|``."""
    if x == 0.0:
        return "0"
    return f"≤ 1e{math.ceil(math.log10(abs(x) * (1 - 1e-12))):d}"


def format_stable(values: Sequence[float], *, residual: bool = False, max_digits: int = 3,
                  floor: float = RESIDUAL_FLOOR, limit: float = ILL_CONDITIONED) -> str:
    """The text for a yardstick measured once per run: stable digits, a bound, or "ill-conditioned".

    Parameters
    ----------
    values : sequence of float
        The yardstick in every run (the nominal run included).
    residual : bool
        An error or distance whose size is all that matters: if every run gives at most ``floor``
        it is reported as the decade bound ``<= 1e-N`` of the largest.
    limit : float
        Relative spread above which the runs are said to disagree.

    Examples
    --------
    >>> format_stable([0.08553, 0.08554, 0.08552])
    '0.0855'
    >>> format_stable([2.9e-6, 4.93e-5])
    'ill-conditioned (spread 2.9e-06 to 4.9e-05)'
    >>> format_stable([2.87e-10, 8.9e-11], residual=True)
    '≤ 1e-9'
    >>> format_stable([math.inf, math.inf])
    'inf'
    """
    v = np.asarray(values, dtype=float)
    if not v.size:
        return "—"
    lo, hi = float(np.min(v)), float(np.max(v))
    if np.any(np.isnan(v)):
        return "nan" if np.all(np.isnan(v)) else f"ill-conditioned (nan in {int(np.sum(np.isnan(v)))} of {v.size} runs)"
    if not (math.isfinite(lo) and math.isfinite(hi)):
        if lo == hi:
            return "inf" if hi > 0 else "-inf"
        return f"ill-conditioned (spread {_short(lo)} to {_short(hi)})"
    big = max(abs(lo), abs(hi))
    if residual and big <= floor:
        return _decade_bound(big)
    if lo == hi:
        return _g(lo, max_digits) if lo != 0 else "0"
    if lo * hi < 0 or (hi - lo) / big > limit:
        return f"ill-conditioned (spread {_short(lo)} to {_short(hi)})"
    d = max(1, stable_digits(lo, hi, max_digits))
    return _g(0.5 * (lo + hi), d)


def _short(x: float) -> str:
    if math.isinf(x):
        return "inf" if x > 0 else "-inf"
    return "0" if x == 0 else f"{x:.2g}"


@dataclass(frozen=True, slots=True, kw_only=True)
class Spread:
    """One yardstick over the nominal run and its perturbed re-runs.

    ``kind`` is ``"value"``, ``"residual"`` (reported as a bound when at round-off level) or
    ``"verdict"`` (yes/no: stable only if every run agrees).
    """

    name: str
    kind: str
    values: tuple

    @property
    def nominal(self):
        return self.values[0]

    @property
    def lo(self) -> float:
        return float(np.min(np.asarray(self.values, dtype=float)))

    @property
    def hi(self) -> float:
        return float(np.max(np.asarray(self.values, dtype=float)))

    @property
    def stable(self) -> bool:
        """The runs agree: same verdict, or a relative spread of at most 10 % (or all at round-off)."""
        return not self.text().startswith("ill-conditioned")

    def text(self, max_digits: int = 3) -> str:
        if self.kind == "verdict":
            yes = sum(bool(v) for v in self.values)
            if yes in (0, len(self.values)):
                return "yes" if yes else "no"
            return f"ill-conditioned (yes in {yes} of {len(self.values)} runs)"
        return format_stable(self.values, residual=self.kind == "residual", max_digits=max_digits)

    def to_dict(self) -> dict:
        d = {"kind": self.kind, "nominal": self.nominal, "text": self.text(), "stable": self.stable,
             "runs": len(self.values)}
        if self.kind != "verdict":
            d |= {"min": self.lo, "max": self.hi, "stable_digits": stable_digits(self.lo, self.hi)}
        else:
            d["yes"] = sum(bool(v) for v in self.values)
        return d


def spread_of(name: str, kind: str, values) -> Spread:
    if kind not in ("value", "residual", "verdict"):
        raise ValueError(f"kind must be 'value', 'residual' or 'verdict', got {kind!r}")
    values = tuple(bool(v) for v in values) if kind == "verdict" else tuple(float(v) for v in values)
    if not values:
        raise ValueError(f"no runs for {name!r}")
    return Spread(name=name, kind=kind, values=values)


@dataclass(frozen=True, slots=True, kw_only=True)
class Conditioning:
    """Every yardstick of one evaluation over its perturbed re-runs (the nominal run first)."""

    spreads: dict
    labels: tuple
    seconds: float
    notes: tuple = field(default=())

    def text(self, name: str, max_digits: int = 3) -> str:
        return self.spreads[name].text(max_digits)

    @property
    def ill_conditioned(self) -> tuple[str, ...]:
        """Names of the yardsticks whose runs disagree."""
        return tuple(k for k, s in self.spreads.items() if not s.stable)

    def to_dict(self) -> dict:
        return {"runs": list(self.labels), "seconds": self.seconds, "ill_conditioned": list(self.ill_conditioned),
                "yardsticks": {k: s.to_dict() for k, s in self.spreads.items()}}


def _yardsticks(ev: ArcEvaluation, exact: bool) -> dict[str, tuple[str, float | bool]]:
    value = "residual" if exact else "value"
    return {
        "cost": (value, ev.cost),
        "length_error": (value, ev.length_error),
        "completed": ("verdict", ev.completed),
        "end_speed": ("residual", max(abs(v) for v in ev.end_speeds)),
        "full_deviation": ("residual", ev.full_deviation),
        "full_success": ("verdict", ev.full_success),
        "full_end_speed": ("residual", max(abs(v) for v in ev.full_end_speeds)),
        "full_length": ("value", ev.full_length),
        "deviation_cost": ("residual", ev.deviation_cost),
        "min_abs_a": ("residual", ev.min_abs_a),
        "peak_mass_energy": ("value", ev.peak_mass_energy),
        "ok": ("verdict", ev.ok),
    }


def _collect(evals: Sequence[ArcEvaluation], labels: Sequence[str], exact: bool, seconds: float) -> Conditioning:
    rows = [_yardsticks(ev, exact) for ev in evals]
    spreads = {k: spread_of(k, rows[0][k][0], [r[k][1] for r in rows]) for k in rows[0]}
    return Conditioning(spreads=spreads, labels=tuple(labels), seconds=seconds)


def condition_paper_arc(row: PaperRow, values, *, params: SleighParams = SleighParams(),
                        nominal: ArcEvaluation | None = None,
                        runs: Sequence[Perturbation] = perturbations(),
                        options: ReducedOptions = TIGHT_SOLVER) -> Conditioning:
    """:func:`~skatetrace.paper.evaluate.evaluate_paper_arc` of ``values`` on ``row``, nominal and perturbed.

    A perturbation's ``rtol`` replaces ``options.rtol`` (``atol = rtol / 10``) and sets the full
    dynamics' ``rtol`` to a tenth of it (at least 1e-13); its seed perturbs ``row.initial``.
    """
    t0 = time.perf_counter()
    evals = [nominal if nominal is not None else evaluate_paper_arc(row, values, "nominal", params=params,
                                                                    options=options)]
    for p in runs:
        rt = options.rtol if p.rtol is None else p.rtol
        opts = dataclasses.replace(options, rtol=rt, atol=rt / 10)
        r = dataclasses.replace(row, initial=p.initial(row.initial))
        evals.append(evaluate_paper_arc(r, values, p.label, params=params, options=opts,
                                        full_rtol=max(rt / 10, 1e-13)))
    return _collect(evals, ["nominal"] + [p.label for p in runs], False, time.perf_counter() - t0)


def condition_exact_arc(row: PaperRow, *, params: SleighParams = SleighParams(), options: TraceOptions = TraceOptions(),
                        nominal: ArcEvaluation | None = None,
                        runs: Sequence[Perturbation] = perturbations()) -> Conditioning:
    """:func:`~skatetrace.paper.evaluate.evaluate_exact_arc` on ``row``, nominal and perturbed.

    A perturbation's ``rtol`` replaces the engine's ``rtol`` (``atol = rtol / 10``); its seed
    perturbs the start (point and heading, from ``row.initial``).
    """
    t0 = time.perf_counter()
    evals = [nominal if nominal is not None else evaluate_exact_arc(row, params=params, options=options)]
    for p in runs:
        opts = options if p.rtol is None else dataclasses.replace(options, rtol=p.rtol, atol=p.rtol / 10)
        evals.append(evaluate_exact_arc(dataclasses.replace(row, initial=p.initial(row.initial)), params=params,
                                        options=opts))
    return _collect(evals, ["nominal"] + [p.label for p in runs], True, time.perf_counter() - t0)


def condition_cost(row: PaperRow, values, *, params: SleighParams = SleighParams(),
                   runs: Sequence[Perturbation] = perturbations(), options: ReducedOptions = TIGHT_SOLVER,
                   nominal: float | None = None) -> Spread:
    """The row's cost at ``values`` (reduced model only, as the rounding study measures it), perturbed."""
    def cost(r, opts):
        return paper_cost(r, values, params, opts)[0]

    vals = [nominal if nominal is not None else cost(row, options)]
    for p in runs:
        rt = options.rtol if p.rtol is None else p.rtol
        vals.append(cost(dataclasses.replace(row, initial=p.initial(row.initial)),
                         dataclasses.replace(options, rtol=rt, atol=rt / 10)))
    return spread_of("cost", "value", vals)
