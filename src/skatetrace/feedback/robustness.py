"""Robustness of a traced figure: many perturbed sleighs replayed in open and closed loop, and how far they stray.

A :class:`Perturbation` says how the sleighs actually skated differ from the model and what the
controller sees: each of ``M, m, I`` off by up to ``param_error`` (a fraction), the start of every
curve displaced by ``position_error`` in a random direction and its heading off by
``angle_error`` either way, the state seen ``delay`` late and its position with noise.
:func:`perturbed_plant` draws the trials, reproducibly from the seed. :func:`robustness` replays
the same trials in open loop (the schedule's own rates) and in closed loop (a tracking law per
section, :func:`lqr_laws` by default) and measures, per trial,

- the largest distance of the blade from its section's pieces (``inf`` where the replay turned
  non-finite: the trial diverged),
- the largest speed of the blade at a rest, the cusp speed (zero in the exact trace).

Each section is measured and its samples let go (:func:`~skatetrace.feedback.closed_loop.loop_sections`),
and the trials run in batches of at most :data:`MAX_SAMPLES` samples a section: memory stays bounded for
any figure and any number of trials. The first :data:`PATH_TRIALS` trials' blade paths are kept, thinned.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, replace
from enum import Enum
from typing import Any

import numpy as np

from ..dynamics.model import SleighParams
from ..figures.figure import Section
from ..figures.geometry import distance_to_segment
from .closed_loop import Plant, loop_sections, section_steps
from .lqr import ROBUST_RATE_WEIGHT, TrackingLaw, design, robust_gains

__all__ = ["SCHEMA", "Perturbation", "default_perturbation", "perturbed_plant", "LoopOutcome", "RobustnessStatus",
           "RobustnessReport", "lqr_laws", "quantiles", "robustness"]

SCHEMA = "skatetrace.robustness/1"
#: Most trials a study may ask for.
MAX_TRIALS = 10_000
#: Most Runge-Kutta steps a section may take (``steps``, or its duration over the delay).
MAX_STEPS = 1_000_000
#: Samples of one section times trials integrated at once (about 140 bytes each, with what the controller saw):
#: larger studies run in batches.
MAX_SAMPLES = 2_000_000
#: Trials whose blade paths are kept for drawing, and at most how many points of each section.
PATH_TRIALS = 32
PATH_POINTS = 400
_QUANTILES = (("p50", 50.0), ("p95", 95.0), ("max", 100.0))
_AMOUNTS = {"param_error": "fraction of M, m and I", "position_error": "start displacement, figure units",
            "angle_error": "start heading error, radians", "delay": "age of the state the controller sees",
            "noise": "standard deviation of the measured position, figure units"}


@dataclass(frozen=True, slots=True, kw_only=True)
class Perturbation:
    """How the trials differ from the model, and how many there are.

    Parameters
    ----------
    param_error : float
        Each of ``M, m, I`` is multiplied by its own ``1 + U(-param_error, param_error)``; below 1.
    position_error : float
        The start of every curve is displaced by exactly this distance (figure units), in a
        uniformly random direction.
    angle_error : float
        The start heading of every curve is off by this angle (radians), either way at random.
    delay : float
        Age of the state the controller acts on (the figure's time unit).
    noise : float
        Standard deviation of the error of the position the controller sees (figure units), drawn
        anew at every step.
    trials : int
        Number of perturbed sleighs, 1 to :data:`MAX_TRIALS`.
    seed : int
        Seed of the draws (a whole number >= 0): the same seed draws the same trials.

    Examples
    --------
    >>> Perturbation(param_error=0.01).trials
    32
    >>> Perturbation(param_error=1.5)
    Traceback (most recent call last):
    ...
    ValueError: `param_error` (fraction of M, m and I) must be below 1 (100 %), got 1.5; e.g. 0.05 for +-5 %
    """

    param_error: float = 0.05
    position_error: float = 0.0
    angle_error: float = 0.0
    delay: float = 0.0
    noise: float = 0.0
    trials: int = 32
    seed: int = 0

    def __post_init__(self) -> None:
        for name, label in _AMOUNTS.items():
            value = getattr(self, name)
            if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, float, np.integer, np.floating)):
                raise TypeError(f"`{name}` ({label}) must be a number, got {value!r}")
            if not (math.isfinite(value) and value >= 0):
                raise ValueError(f"`{name}` ({label}) must be a finite number >= 0, got {value!r}")
            object.__setattr__(self, name, float(value))
        if not self.param_error < 1:
            raise ValueError(f"`param_error` ({_AMOUNTS['param_error']}) must be below 1 (100 %), got "
                             f"{self.param_error!r}; e.g. 0.05 for +-5 %")
        for name, low, high in (("trials", 1, MAX_TRIALS), ("seed", 0, None)):
            value = getattr(self, name)
            whole = isinstance(value, (int, np.integer)) and not isinstance(value, (bool, np.bool_))
            if not (whole and value >= low and (high is None or value <= high)):
                span = f"from {low} to {high}" if high is not None else f">= {low}"
                raise ValueError(f"`{name}` must be a whole number {span}, got {value!r}")
            object.__setattr__(self, name, int(value))

    def to_dict(self) -> dict[str, float | int]:
        """Every field (``angle_error`` in radians)."""
        return {k: getattr(self, k) for k in (*_AMOUNTS, "trials", "seed")}


def default_perturbation(size: float, unit: str = "model", **changes) -> Perturbation:
    """The scenario of issue 16 for a figure of ``size`` in ``unit``, with ``changes`` to any field.

    ``param_error`` 5 %, ``angle_error`` 0.5 degrees, 32 trials, seed 0; for a figure in metres
    (``unit="m"``) ``position_error`` 1 mm and ``delay`` 10 ms, in model units ``position_error``
    1e-4 of the figure's size (1 mm on a figure 10 m across) and ``delay`` 0.01 time units.
    """
    metres = unit == "m"
    base = dict(param_error=0.05, position_error=1e-3 if metres else 1e-4 * size, angle_error=math.radians(0.5),
                delay=0.01, noise=0.0, trials=32, seed=0)
    return Perturbation(**{**base, **changes})


def perturbed_plant(params: SleighParams, perturbation: Perturbation) -> Plant:
    """The trials of ``perturbation`` about the model ``params``, drawn from its seed.

    The draws are the same for every size of error (the errors scale one set of random numbers),
    so that studies with larger errors perturb the same sleighs further, and the first trials are
    the same for any number of trials (five numbers a trial, drawn trial by trial).
    """
    p = perturbation
    u = np.random.default_rng(p.seed).random((p.trials, 5)).T
    scale = 1.0 + p.param_error * (2.0 * u[:3] - 1.0)
    direction = 2.0 * math.pi * u[3]
    sign = np.where(u[4] < 0.5, -1.0, 1.0)
    return Plant(M=params.M * scale[0], m=params.m * scale[1], I=params.I * scale[2],
                 dx=p.position_error * np.cos(direction), dy=p.position_error * np.sin(direction),
                 dtheta=p.angle_error * sign, delay=p.delay, noise=p.noise)


def quantiles(values) -> dict[str, float]:
    """``{"p50", "p95", "max"}`` of ``values``, linear between order statistics (numpy's default).

    A NaN counts as an infinity, and a statistic that reaches an infinite value is one: with 2 of
    32 trials diverged, ``p95`` and ``max`` are ``inf``. No values: NaN.

    Examples
    --------
    >>> quantiles([1.0, 2.0, 3.0, float("inf")])
    {'p50': 2.5, 'p95': inf, 'max': inf}
    """
    v = np.sort(np.where(np.isnan(values), np.inf, np.asarray(values, dtype=float)))
    out = {key: math.nan for key, _ in _QUANTILES}
    for key, q in _QUANTILES if v.size else ():  # no values: NaN
        pos = q / 100.0 * (v.size - 1)
        lo, frac = int(pos), pos - int(pos)
        hi = min(lo + 1, v.size - 1)
        out[key] = float(v[lo]) if frac == 0.0 or v[hi] == v[lo] else float(v[lo] + frac * (v[hi] - v[lo]))
    return out


def _null(stats: dict[str, float]) -> dict[str, float | None]:
    return {k: (v if math.isfinite(v) else None) for k, v in stats.items()}


@dataclass(frozen=True, slots=True, kw_only=True)
class LoopOutcome:
    """One family of replays (open or closed loop), per trial.

    Attributes
    ----------
    deviation : ndarray, shape (n,)
        Largest distance of the blade from its section's pieces (figure units); ``inf``: diverged.
    cusp_speed : ndarray, shape (n,)
        Largest speed of the blade at a rest (figure units per time unit); ``inf``: diverged.
    paths : tuple
        Per section, ``None`` (not traced) or the blade's positions ``(2, k, m)`` at ``k`` instants
        of the first ``m`` trials (at most :data:`PATH_TRIALS`), for drawing; NaN where not finite.
    seconds : float
        Wall time of the replays.
    mass_reach : ndarray, shape (n,)
        Largest distance of the moving mass from the blade's contact point, ``sqrt(a^2 + b^2)``
        (figure units): what a skater would have to reach for this loop; ``inf``: diverged.
    """

    deviation: np.ndarray
    cusp_speed: np.ndarray
    paths: tuple
    seconds: float
    mass_reach: np.ndarray | None = None

    @property
    def trials(self) -> int:
        return int(self.deviation.size)

    @property
    def diverged(self) -> int:
        """How many trials' replays turned non-finite."""
        return int(np.sum(~np.isfinite(self.deviation)))

    def to_dict(self) -> dict[str, Any]:
        """``trials``, ``diverged``, ``max_deviation``, ``cusp_speed`` and ``mass_reach``
        (``{"p50", "p95", "max"}``, non-finite as ``None``), ``seconds``."""
        reach = self.mass_reach if self.mass_reach is not None else np.full(self.trials, np.nan)
        return {"trials": self.trials, "diverged": self.diverged, "max_deviation": _null(quantiles(self.deviation)),
                "cusp_speed": _null(quantiles(self.cusp_speed)), "mass_reach": _null(quantiles(reach)),
                "seconds": self.seconds}


class RobustnessStatus(Enum):
    """Outcome of a robustness study; the value is the message."""

    COMPLETE = "open and closed loop replayed"
    LAW_FAILED = "the tracking law could not be designed for every section: those ran open loop in the closed loop"
    NOTHING_TRACED = "no section was traced: nothing to replay"


@dataclass(frozen=True, slots=True, kw_only=True)
class RobustnessReport:
    """A robustness study: the perturbation, the law, and the open and closed loop's outcomes.

    ``success`` is True when both families were replayed with a law for every traced section,
    whatever the numbers; a law that could not be designed is listed in ``failed_laws`` (section,
    message), and the closed loop runs that section on the schedule alone.
    """

    success: bool
    status: RobustnessStatus
    message: str
    figure_size: float
    perturbation: Perturbation
    open_loop: LoopOutcome
    closed_loop: LoopOutcome
    law: dict
    steps: int
    sections: int
    replayed: int
    failed_laws: tuple[tuple[int, str], ...] = ()

    def to_dict(self) -> dict[str, Any]:
        """JSON-safe data (schema :data:`SCHEMA`); non-finite statistics are ``None``."""
        return {"schema": SCHEMA, "success": self.success, "status": self.status.name, "message": self.message,
                "figure_size": self.figure_size, "perturbation": self.perturbation.to_dict(), "law": self.law,
                "steps": self.steps, "sections": self.sections, "replayed": self.replayed,
                "failed_laws": [{"section": si, "message": msg} for si, msg in self.failed_laws],
                "open_loop": self.open_loop.to_dict(), "closed_loop": self.closed_loop.to_dict()}


def lqr_laws(refs, params: SleighParams, size: float, rate_weight: float = ROBUST_RATE_WEIGHT
             ) -> tuple[list[TrackingLaw | None], dict[str, Any]]:
    """The default law: :func:`~skatetrace.feedback.lqr.design` with
    :func:`~skatetrace.feedback.lqr.robust_gains` for each traced section, its gains
    :meth:`~skatetrace.feedback.lqr.TrackingLaw.thinned` (the law tested is the law exported).

    Returns the laws (``None`` where ``refs`` has none) and their description for the report.
    """
    gains = robust_gains(size, rate_weight)
    laws = [None if ref is None else design(ref, params, gains).thinned() for ref in refs]
    return laws, {"name": "lqr", "about": "time-varying LQR about each section's trace", "gains": gains.to_dict()}


class _Tally:
    """Per-trial maxima over the sections measured so far, and the paths kept for drawing."""

    def __init__(self, n: int, sections: int):
        self.deviation = np.zeros(n)
        self.cusp_speed = np.zeros(n)
        self.mass_reach = np.zeros(n)
        self.paths: list[list[np.ndarray]] = [[] for _ in range(sections)]

    def add(self, si: int, section: Section, samples: dict, rows: slice) -> None:
        state = samples["state"]  # (7, k, trials of the batch)
        finite = np.all(np.isfinite(state), axis=(0, 1))
        xy = np.where(finite, state[3:5], 0.0)
        with np.errstate(all="ignore"):
            d = None
            for p in section.pieces:
                dp = distance_to_segment(xy.reshape(2, -1), p.start, p.segment)
                d = dp if d is None else np.minimum(d, dp)
            dev = np.where(finite, np.max(d.reshape(xy.shape[1:]), axis=0), np.inf)
            cusp = np.max(samples["cusp_speed"], axis=1)
            reach = np.where(finite, np.max(np.hypot(*np.where(finite, state[5:7], 0.0)), axis=0), np.inf)
        cusp = np.where(finite & np.isfinite(cusp), cusp, np.inf)
        self.mass_reach[rows] = np.maximum(self.mass_reach[rows], reach)
        self.deviation[rows] = np.maximum(self.deviation[rows], dev)
        self.cusp_speed[rows] = np.maximum(self.cusp_speed[rows], cusp)
        keep = max(0, min(rows.stop, PATH_TRIALS) - rows.start)
        if keep:
            idx = np.unique(np.linspace(0, state.shape[1] - 1, min(state.shape[1], PATH_POINTS)).round().astype(int))
            path = state[3:5][:, idx, :keep]
            self.paths[si].append(np.where(np.isfinite(path), path, np.nan))

    def outcome(self, seconds: float) -> LoopOutcome:
        paths = tuple(np.concatenate(p, axis=2) if p else None for p in self.paths)
        return LoopOutcome(deviation=self.deviation, cusp_speed=self.cusp_speed, paths=paths, seconds=seconds,
                           mass_reach=self.mass_reach)


def _replay(refs, sections, plant: Plant, laws, steps: int, batch: int, seed: int, tick) -> LoopOutcome:
    t0 = time.perf_counter()
    n = plant.trials
    tally = _Tally(n, len(sections))
    for b0 in range(0, n, batch):
        rows = slice(b0, min(n, b0 + batch))
        part = replace(plant, **{k: getattr(plant, k)[rows] for k in ("M", "m", "I", "dx", "dy", "dtheta")})
        run = loop_sections(refs, part, laws, steps=steps, seed=np.random.SeedSequence([seed, b0]))
        for si, section in enumerate(sections):
            with np.errstate(all="ignore"):  # a diverging trial overflows: that is what is measured
                samples = next(run)  # measured, then let go before the next section is integrated
            if samples is not None:
                tally.add(si, section, samples, rows)
                tick()
            del samples
    return tally.outcome(time.perf_counter() - t0)


def _check(refs, sections, laws, size, steps, delay) -> None:
    if not (len(refs) == len(sections) == len(laws)):
        raise ValueError(f"refs, sections and laws must have one entry per section, got {len(refs)}, "
                         f"{len(sections)} and {len(laws)}")
    missing = [si for si, (ref, law) in enumerate(zip(refs, laws)) if ref is not None and law is None]
    if missing:
        raise ValueError(f"every traced section needs a law; sections {missing} have none")
    if isinstance(size, bool) or not (isinstance(size, (int, float, np.integer, np.floating)) and 0 < size < math.inf):
        raise ValueError(f"`size` (the figure's size) must be a positive finite number, got {size!r}")
    if isinstance(steps, bool) or not (isinstance(steps, (int, np.integer)) and 1 <= steps <= MAX_STEPS):
        raise ValueError(f"`steps` must be a whole number from 1 to {MAX_STEPS}, got {steps!r}")
    for si, need in ((si, section_steps(r.duration, steps, delay)) for si, r in enumerate(refs) if r is not None):
        if need > MAX_STEPS:
            raise ValueError(f"a delay of {delay:g} needs {need:.3g} steps over section {si} (at most {MAX_STEPS}, "
                             "one step per delay): give a longer delay, or none")


def robustness(refs, sections, params: SleighParams, laws, perturbation: Perturbation = Perturbation(), *,
               size: float, steps: int = 4000, law: dict[str, Any] | None = None, progress=None) -> RobustnessReport:
    """Replay a traced figure on perturbed sleighs in open and closed loop, and measure how far each strays.

    Parameters
    ----------
    refs : sequence of Reference or None
        The sections' references in skating order (``None``: not traced).
    sections : sequence of Section
        The figure's sections (their pieces on the ice), one per reference: the deviation is
        measured from each section's own pieces.
    params : SleighParams
        The model: the controller's, about which the trials are perturbed.
    laws : sequence
        One per section (``None`` where there is no reference), each with ``rates(t, z, measured_at)``
        as :class:`~skatetrace.feedback.lqr.TrackingLaw` has; a law whose ``success`` is False is
        reported in ``failed_laws``. See :func:`lqr_laws`.
    perturbation : Perturbation
    size : float
        The figure's size: the scale the report's reader compares deviations with.
    steps : int
        Runge-Kutta steps per section (more where the delay asks for them).
    law : dict, optional
        The law's description for the report (default: the name of the laws' type).
    progress : callable, optional
        Called as ``progress(done, total)`` after each section of each batch of trials, both loops.

    Returns
    -------
    RobustnessReport
        Never raises for a replay that diverges (that trial's deviation is ``inf``) or a law that
        failed (``success=False``).

    Raises
    ------
    ValueError
        Arguments that do not fit together, ``steps`` out of range, or a delay so short that a
        section would need more than :data:`MAX_STEPS` steps.
    """
    refs, sections, laws = list(refs), list(sections), list(laws)
    _check(refs, sections, laws, size, steps, perturbation.delay)
    if law is None:
        law = {"name": next((type(x).__name__ for x in laws if x is not None), "none")}
    failed = tuple((si, str(getattr(x, "message", "failed"))) for si, x in enumerate(laws)
                   if x is not None and getattr(x, "success", True) is False)
    replayed = sum(r is not None for r in refs)
    common = dict(figure_size=float(size), perturbation=perturbation, law=law, steps=steps, sections=len(refs),
                  replayed=replayed, failed_laws=failed)
    if replayed == 0:
        empty = LoopOutcome(deviation=np.zeros(0), cusp_speed=np.zeros(0), paths=(None,) * len(refs), seconds=0.0)
        nothing = RobustnessStatus.NOTHING_TRACED
        return RobustnessReport(success=False, status=nothing, message=nothing.value, open_loop=empty,
                                closed_loop=empty, **common)
    plant = perturbed_plant(params, perturbation)
    longest = max(section_steps(r.duration, steps, perturbation.delay) for r in refs if r is not None) + 1
    batch = max(1, MAX_SAMPLES // longest)
    total, done = 2 * replayed * -(-perturbation.trials // batch), iter(range(1, 1 << 62))
    tick = (lambda: progress(next(done), total)) if progress is not None else (lambda: None)
    open_loop = _replay(refs, sections, plant, None, steps, batch, perturbation.seed, tick)
    closed_loop = _replay(refs, sections, plant, laws, steps, batch, perturbation.seed, tick)
    status = RobustnessStatus.LAW_FAILED if failed else RobustnessStatus.COMPLETE
    message = ("; ".join(f"section {si}: {msg}" for si, msg in failed) + " (those sections ran open loop)" if failed
               else f"open and closed loop replayed on {perturbation.trials} perturbed sleighs")
    return RobustnessReport(success=not failed, status=status, message=message, open_loop=open_loop,
                            closed_loop=closed_loop, **common)
