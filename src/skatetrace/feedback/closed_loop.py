"""Replays of a figure under the tracking law or the open-loop schedule, for many perturbed sleighs at once.

Each section is integrated over its reference duration with the classical fourth-order Runge-Kutta
method at a fixed step, all trials side by side in numpy arrays. The sleigh of each trial may differ
from the controller's model (``M, m, I``) and start off the figure, and the controller may see its
state late (``delay``) and with noise on the position (``noise``). The controller measures motion,
not momenta: it sees the momenta that its own model gives to the blade's measured velocities and
the mass's motion (the same as the sleigh's own where the sleigh is the model).

- **Open loop**: the rates are the schedule's.
- **Closed loop**: the rates are the :class:`~skatetrace.feedback.lqr.TrackingLaw`'s.

At every rest, as in the verification replay, the blade pivots by the join's angle, the mass starts
the next section where the schedule starts it, and the momenta are those of the mass's motion at
rest (the idealised impulse of a cusp). The blade's speed just before that impulse is the cusp speed.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..dynamics.model import SleighParams, body_velocities, momenta
from ..dynamics.simulate import simulate
from .law_replay import SpanRun, law_arrays, replay_span
from .lqr import TrackingLaw
from .reference import Reference, rhs, variable_scales

__all__ = ["Plant", "LoopRun", "loop_sections", "run_loop", "section_steps"]


@dataclass(frozen=True, slots=True, kw_only=True)
class Plant:
    """The sleighs actually skated, one per trial (arrays of shape ``(n,)``), and what the controller sees.

    ``dx, dy, dtheta`` displace each curve's starting pose; ``delay`` is the age of the state the
    controller acts on; ``noise`` the standard deviation of the error of the position it sees
    (drawn anew at every step).
    """

    M: np.ndarray
    m: np.ndarray
    I: np.ndarray
    dx: np.ndarray
    dy: np.ndarray
    dtheta: np.ndarray
    delay: float = 0.0
    noise: float = 0.0

    @classmethod
    def nominal(cls, params: SleighParams, n: int = 1) -> "Plant":
        z = np.zeros(n)
        return cls(M=np.full(n, params.M), m=np.full(n, params.m), I=np.full(n, params.I), dx=z, dy=z, dtheta=z)

    @property
    def trials(self) -> int:
        return int(self.M.size)


@dataclass(frozen=True, slots=True, kw_only=True)
class LoopRun:
    """Samples of every trial, per section (``None`` where the section was not traced).

    Each section is a dict: ``t`` local times ``(k,)``, ``state`` ``(7, k, n)`` (``p1, p2, theta, x, y,
    a, b``), ``rates`` ``(2, k, n)``, ``xi2`` ``(k, n)`` the blade's speed, ``cusp_speed`` ``(n, 2)``
    (the blade's speed at the rests that start and end the section).
    """

    sections: tuple
    closed: bool

    def cusp_speeds(self) -> np.ndarray:
        """Blade speeds at every rest, shape ``(n, 2 * traced sections)``."""
        return np.hstack([s["cusp_speed"] for s in self.sections if s is not None])


def _start_state(ref: Reference, plant: Plant, prev_end) -> np.ndarray:
    """State of every trial at the rest that starts a section."""
    n = plant.trials
    z0, u0 = ref.state_at(0.0)
    a0, b0, ad0, bd0 = float(z0[5, 0]), float(z0[6, 0]), float(u0[0, 0]), float(u0[1, 0])
    if prev_end is None or ref.curve_start:
        x, y, th = z0[3, 0] + plant.dx, z0[4, 0] + plant.dy, z0[2, 0] + plant.dtheta
    else:
        th = prev_end[2] + (ref.join.pivot if ref.join is not None else 0.0)
        x, y = prev_end[3], prev_end[4]
    # at rest: the momenta of the mass's own motion, in each true sleigh
    p1, p2 = momenta(plant, 0.0, 0.0, a0, b0, ad0, bd0)
    return np.vstack([p1, p2, th, x, y, np.full(n, a0), np.full(n, b0)])


class _Section:
    """One section's integration for all trials: the controller, the delay line, the steps."""

    def __init__(self, ref: Reference, plant: Plant, law: TrackingLaw | None, h: float, history: np.ndarray):
        self.ref, self.plant, self.law, self.h = ref, plant, law, h
        self.hist = np.empty_like(history)  # (7, k, n) like the samples: what the controller saw at t = j h
        self.count = 0  # how many of them are recorded
        self.noise = np.zeros((2, plant.trials))
        _, u0 = ref.state_at(np.zeros(plant.trials))
        self.last = u0  # the rates last commanded, (2, n): the controller knows them

    def sense(self, z: np.ndarray) -> np.ndarray:
        """What the controller makes of the state ``z``: its momenta are the law's model's for the
        motion measured (the blade's speed and turning rate, the mass's position and the rates last
        commanded). A skater or a robot measures motion, not momenta; where the sleigh is the model
        this is ``z`` itself."""
        model = getattr(self.law, "params", None)
        if model is None:
            return z
        p, (ad, bd) = self.plant, self.last
        xi1, xi2, _ = body_velocities(p.M, p.m, p.I, z[0], z[1], z[5], z[6], ad, bd)
        seen = z.copy()
        seen[0], seen[1] = momenta(model, xi1, xi2, z[5], z[6], ad, bd)
        return seen

    def record(self, k: int, z: np.ndarray) -> None:
        """Keep what the controller sees at step ``k`` for the delay line."""
        self.hist[:, k] = self.sense(z)
        self.count = k + 1

    def measured(self, t: float, z: np.ndarray) -> np.ndarray:
        """The state the controller sees at time ``t``: ``delay`` old, with noise on the position."""
        d = self.plant.delay
        if d > 0.0 and self.count:
            tm = max(t - d, 0.0) / self.h
            j = min(int(tm), self.count - 1)
            j1 = min(j + 1, self.count - 1)
            w = min(tm - j, 1.0)
            z = (1 - w) * self.hist[:, j] + w * self.hist[:, j1]
        else:
            z = self.sense(z)
        if self.plant.noise > 0.0:
            z = z.copy()
            z[3:5] += self.noise
        return z

    def rates(self, t: float, z: np.ndarray):
        if self.law is None:
            _, u = self.ref.state_at(t)  # one time for every trial
            n = z.shape[1]
            return np.broadcast_to(u[0], (n,)), np.broadcast_to(u[1], (n,))
        # a late measurement is compared with the reference at its own time
        ad, bd = self.law.rates(t, self.measured(t, z), max(t - self.plant.delay, 0.0))
        self.last = (ad, bd)
        return ad, bd

    def derivative(self, t: float, z: np.ndarray, rates=None) -> np.ndarray:
        return rhs(self.plant, z, *(self.rates(t, z) if rates is None else rates))

    def step(self, t: float, z: np.ndarray, h: float, rates) -> np.ndarray:
        """One Runge-Kutta step from ``(t, z)``, where the rates are ``rates`` (already evaluated)."""
        k1 = self.derivative(t, z, rates)
        k2 = self.derivative(t + 0.5 * h, z + 0.5 * h * k1)
        k3 = self.derivative(t + 0.5 * h, z + 0.5 * h * k2)
        k4 = self.derivative(t + h, z + h * k3)
        return z + h / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)

    def speed(self, t: float, z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The blade's speed and the rates ``(2, n)`` at ``(t, z)``."""
        ad, bd = self.rates(t, z)
        p = self.plant
        _, xi2, _ = body_velocities(p.M, p.m, p.I, z[0], z[1], z[5], z[6], ad, bd)
        return xi2, np.vstack([ad, bd])


def section_steps(duration: float, steps: int, delay: float) -> int:
    """Runge-Kutta steps over a section of ``duration``: ``steps``, or more so that no step is longer
    than the ``delay`` (the delay line reads the recorded states)."""
    return max(steps, int(math.ceil(duration / delay)) if delay > 0.0 else 0)


def run_loop(refs: list[Reference | None], plant: Plant, laws: list[TrackingLaw | None] | None, *,
             steps: int = 4000, seed: int = 0) -> LoopRun:
    """Integrate every section of a figure for every trial.

    Parameters
    ----------
    refs : list of Reference or None
        The sections in skating order (``None``: not traced; the next one starts from the layout).
    laws : list of TrackingLaw, or None
        One per section (closed loop), or ``None`` to replay the open-loop schedule.
    steps : int
        Runge-Kutta steps per section (at most the delay apart when there is one).
    seed : int
        Seed of the measurement noise.
    """
    return LoopRun(sections=tuple(loop_sections(refs, plant, laws, steps=steps, seed=seed)), closed=laws is not None)


def loop_sections(refs: list[Reference | None], plant: Plant, laws: list[TrackingLaw | None] | None, *,
                  steps: int = 4000, seed: int = 0):
    """:func:`run_loop` one section at a time: yields each section's samples as soon as they are integrated.

    Each item is what :class:`LoopRun` holds for the section (a dict, or ``None`` where it was not
    traced). A caller that measures a section and lets its samples go before asking for the next
    holds one section's samples at a time, not the whole figure's. The arguments are
    :func:`run_loop`'s, and so are the samples, to the bit.
    """
    rng = np.random.default_rng(seed)
    n = plant.trials
    prev_end = None
    for si, ref in enumerate(refs):
        if ref is None:
            yield None
            prev_end = None
            continue
        T = ref.duration
        count = section_steps(T, steps, plant.delay)
        h = T / count
        ts, zs, rs, vs = np.empty(count + 1), np.empty((7, count + 1, n)), np.empty((2, count + 1, n)), \
            np.empty((count + 1, n))
        sec = _Section(ref, plant, None if laws is None else laws[si], h, zs)
        z = _start_state(ref, plant, prev_end)
        for k in range(count + 1):
            t = k * h
            ts[k], zs[:, k] = t, z
            sec.record(k, z)
            if plant.noise > 0.0:
                sec.noise = rng.normal(0.0, plant.noise, (2, n))
            vs[k], rs[:, k] = sec.speed(t, z)
            if k == count:
                break
            z = sec.step(t, z, h, rs[:, k])
        prev_end = z
        yield {"t": ts, "state": zs, "rates": rs, "xi2": vs, "cusp_speed": np.abs(np.vstack([vs[0], vs[-1]])).T}
        del ts, zs, rs, vs, sec  # the caller's copy is the only one left while the next section runs


def replay_law(ref: Reference, law: TrackingLaw, params: SleighParams, z0, t_out, *, rtol: float = 1e-12,
               atol: float = 1e-14, max_nfev: int = 300_000, engine: str = "compiled"):
    """One sleigh (the model itself) under the law, integrated accurately: DOP853 between the rate jumps.

    Parameters
    ----------
    z0 : array_like, shape (7,)
        State ``(p1, p2, theta, x, y, a, b)`` at the section's start.
    t_out : array_like
        Section times (non-decreasing, within the section) at which to report.
    rtol, atol : float
        DOP853's tolerances; ``atol`` is relative to each variable's largest value on the reference (its
        kind's where it stays at zero: :func:`~skatetrace.feedback.reference.variable_scales`).
    max_nfev : int
        Budget of evaluations of the law over the whole section; beyond it the replay stops and
        reports ``success=False``.
    engine : {"compiled", "scipy"}
        ``"compiled"`` (default) integrates with :func:`skatetrace.feedback.law_replay.replay_span`;
        ``"scipy"`` with :func:`skatetrace.dynamics.simulate.simulate` (``solve_ivp``) and the law's
        :meth:`~skatetrace.feedback.lqr.TrackingLaw.controller`, some two hundred times slower, as a
        cross-check of the first. The two take the same steps, up to rounding.

    Returns
    -------
    states : ndarray, shape (7, n)
    rates : ndarray, shape (2, n)
        The law's rates at ``t_out`` (from the right at a jump).
    correction : float
        The largest feedback term ``|K (z - z_ref)|`` met at ``t_out``, relative to the section's
        fastest scheduled rate: how far the law had to depart from the schedule.
    success : bool
        False if an integration failed (the states from there on are NaN: from the failure with
        the compiled engine, from the start of the span that failed with scipy's).
    """
    if engine not in ("compiled", "scipy"):
        raise ValueError(f"engine must be 'compiled' or 'scipy', got {engine!r}")
    t_out = np.asarray(t_out, dtype=float)
    end = ref.duration
    scale = variable_scales(ref.z) * atol
    if engine == "compiled":
        arrays = law_arrays(ref, law)

        def span_run(z, c0, c1, tt, budget):
            return replay_span(arrays, params, z, (c0, c1), tt, rtol=rtol, atol=scale, max_nfev=budget)
    else:
        controller = law.controller()

        def span_run(z, c0, c1, tt, budget):
            # a jump of the rates at c0: the law is read from the right there (just inside the span)
            run = simulate(params, z, controller, (c0, c1), rtol=rtol, atol=scale, max_nfev=budget)
            states = run(tt) if run.success else np.full((7, tt.size), np.nan)
            return SpanRun(success=run.success, y_end=run.state[:, -1] if run.success else None, states=states,
                           nfev=run.nfev)

    states = np.full((7, t_out.size), np.nan)
    z = np.asarray(z0, dtype=float)
    ok = True
    budget = max_nfev
    for c0, c1 in ref.spans():
        inside = (t_out >= c0) & ((t_out < c1) | (c1 == end) & (t_out <= c1))
        run = span_run(z, c0, c1, t_out[inside], budget)
        budget -= run.nfev
        states[:, inside] = run.states
        if not run.success:
            ok = False
            break
        z = run.y_end
    ur = ref.state_at(t_out)[1]
    finite = np.all(np.isfinite(states), axis=0)
    rates = np.full((2, t_out.size), np.nan)
    if np.any(finite):
        rates[:, finite] = np.vstack(law.rates(t_out[finite], states[:, finite]))
    rate_scale = max(float(np.max(np.abs(ref.zdot[5:7]))), 1e-300)
    correction = float(np.max(np.abs(rates[:, finite] - ur[:, finite]), initial=0.0)) / rate_scale
    return states, rates, correction, ok and bool(np.all(finite))
