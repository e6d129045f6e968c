"""The exact trace as a reference for feedback: per section, the state and the mass rates over time.

A :class:`Reference` holds one section's sampled exact motion: the rows of ``controls.csv``
(``t, a, b, adot, bdot`` and the solver's ``p1, p2, theta, x, y`` there). Between rows the state is
the cubic Hermite interpolant whose slopes are the model's own derivatives at the rows, and the mass
position the interpolant the replay uses, so that ``adot, bdot`` are its derivatives.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..dynamics.controls import ControlSchedule
from ..dynamics.model import SleighParams
from ..dynamics.model import rhs as model_rhs
from ..figures.figure import Join, Section

__all__ = ["Reference", "references", "rhs", "section_reference", "variable_scales"]

_STATE = ("p1", "p2", "theta", "x", "y", "a", "b")


def rhs(params, z, ad, bd):
    """``dz/dt`` of ``z = (p1, p2, theta, x, y, a, b)`` (rows) under mass rates ``ad, bd``.

    The sleigh's five rows are :func:`skatetrace.dynamics.model.rhs`; ``params`` is anything with
    ``M, m, I`` (a :class:`SleighParams`, or arrays of one value per trial).
    """
    return np.vstack([model_rhs(params, z[:5], z[5], z[6], ad, bd),
                      np.broadcast_to(ad, z.shape[1:]), np.broadcast_to(bd, z.shape[1:])])


@dataclass(frozen=True, slots=True, eq=False)
class Reference:
    """One section of an exact trace.

    ``grid`` are times from the section's start (non-decreasing; a repeated time is a jump of the
    rates); ``z`` the states ``(p1, p2, theta, x, y, a, b)`` there, shape ``(7, k)``, ``zdot`` their
    derivatives, ``u`` the rates ``(adot, bdot)``; ``piece`` the figure's piece of each row;
    ``join`` the join before the section (its pivot is applied at the rest that starts it),
    ``None`` at a curve's start.
    """

    grid: np.ndarray
    z: np.ndarray
    zdot: np.ndarray
    piece: np.ndarray
    join: Join | None
    curve_start: bool

    @property
    def duration(self) -> float:
        return float(self.grid[-1])

    def spans(self) -> list[tuple[float, float]]:
        """The smooth stretches ``(t0, t1)`` between the jumps of the rates (the repeated times)."""
        g = self.grid
        cuts = np.concatenate([[g[0]], g[1:][np.diff(g) == 0.0], [g[-1]]])
        return [(float(c0), float(c1)) for c0, c1 in zip(cuts[:-1], cuts[1:]) if c1 > c0]

    def state_at(self, tau) -> tuple[np.ndarray, np.ndarray]:
        """States ``(7, n)`` and rates ``(2, n)`` at section times ``tau`` (clamped to the section;
        from the right at a jump)."""
        t = self.grid
        tau = np.clip(np.atleast_1d(np.asarray(tau, dtype=float)), t[0], t[-1])
        k = np.clip(np.searchsorted(t, tau, side="right") - 1, 0, t.size - 2)
        h = t[k + 1] - t[k]
        ok = h > 0
        hs = np.where(ok, h, 1.0)
        u = np.where(ok, (tau - t[k]) / hs, 0.0)
        y0, y1 = self.z[:, k], self.z[:, k + 1]
        d0, d1 = self.zdot[:, k] * hs, self.zdot[:, k + 1] * hs
        val = (2 * u**3 - 3 * u**2 + 1) * y0 + (u**3 - 2 * u**2 + u) * d0 + (-2 * u**3 + 3 * u**2) * y1 \
            + (u**3 - u**2) * d1
        der = ((6 * u**2 - 6 * u) * y0 + (3 * u**2 - 4 * u + 1) * d0 + (-6 * u**2 + 6 * u) * y1
               + (3 * u**2 - 2 * u) * d1) / hs
        val = np.where(ok, val, y0)
        rates = np.where(ok, der[5:7], self.zdot[5:7, k])
        return val, rates


def references(sections: list[Section], schedule: ControlSchedule, states: dict[str, np.ndarray],
               start_times, params: SleighParams) -> list[Reference | None]:
    """One :class:`Reference` per section from a sampled schedule and its solver states.

    ``states`` holds ``x, y, theta, p1, p2`` at the schedule's rows (as
    :func:`~skatetrace.verification.verify.schedule_from_trace` returns them, or as read from
    ``controls.csv``). A section without rows (not traced) gets ``None``.
    """
    out: list[Reference | None] = []
    for si, (section, t0) in enumerate(zip(sections, start_times)):
        rows = np.flatnonzero(schedule.section == si)
        if rows.size < 2:
            out.append(None)
            continue
        z = np.vstack([states["p1"][rows], states["p2"][rows], states["theta"][rows], states["x"][rows],
                       states["y"][rows], schedule.a[rows], schedule.b[rows]])
        zdot = rhs(params, z, schedule.adot[rows], schedule.bdot[rows])
        first = section.pieces[0]
        out.append(Reference(grid=schedule.t[rows] - float(t0), z=z, zdot=zdot, piece=schedule.piece[rows],
                             join=first.join_before, curve_start=first.join_before is None))
    return out


def variable_scales(z: np.ndarray) -> np.ndarray:
    """The largest ``|value|`` of each of the seven variables ``z`` (7, k), or of its kind where it stays at zero.

    A variable within 1e-9 of zero all along, relative to its kind (the heading along a line drawn
    level, ``x`` along one drawn upright), takes the scale of its kind: the larger of ``p1, p2``, of
    ``x, y``, of ``a, b``, and a radian for the heading. Held to its own, its absolute tolerance was a
    denormal number (1e-314) that no step of DOP853 could meet, the initial step came out zero
    (:func:`~skatetrace.feedback.closed_loop.replay_law`), and :func:`section_reference` measured its
    interpolation error against 1e-300, never met: its rows grew to ``max_points``.
    """
    big = np.max(np.abs(z), axis=1)
    pair = np.maximum(big[[1, 0, 2, 4, 3, 6, 5]], big)
    kind = np.array([pair[0], pair[1], 1.0, pair[3], pair[4], pair[5], pair[6]])
    return np.maximum(np.where(big < 1e-9 * kind, kind, big), 1e-300)


def section_reference(sec, params: SleighParams, *, points: int = 20_000, tol: float = 1e-9,
                      max_points: int = 1_280_000) -> Reference:
    """A :class:`Reference` sampled from a traced section itself (the exact motion at any time).

    ``points`` times spread evenly over the section, and both sides of every breakpoint (where the
    rates jump), four times as many until the interpolated state is within ``tol`` of the exact
    motion (relative to each variable's largest value) at the middle of every interval, or
    ``max_points`` is reached. Far finer than the rows of ``controls.csv``: a tracking law about a
    coarser reference corrects its interpolation error (measured: 1.8e-6 of the rates on a section
    of eight pieces at 20,000 points, 2.6e-8 at 80,000).
    """
    bps = sec.breakpoints()
    T = float(bps[-1])
    inner = bps[1:-1]
    while True:
        t = np.union1d(np.linspace(0.0, T, points), bps)
        right = sec.evaluate(t)
        if inner.size:
            left = sec.evaluate(inner, side="left")
            idx = np.searchsorted(t, inner)
            t = np.insert(t, idx, inner)
            right = {k: np.insert(right[k], idx, left[k]) for k in right}
        z = np.vstack([right[k] for k in _STATE])
        zdot = rhs(params, z, right["adot"], right["bdot"])
        pieces = np.array([p.index for p in sec.section.pieces])[right["segment"]]
        first = sec.section.pieces[0]
        ref = Reference(grid=t, z=z, zdot=zdot, piece=pieces, join=first.join_before,
                        curve_start=first.join_before is None)
        if points >= max_points:
            return ref
        h = np.diff(t)
        mid = (t[:-1] + 0.5 * h)[h > 0]
        exact = sec.evaluate(mid)
        got, _ = ref.state_at(mid)
        scale = variable_scales(z)
        err = max(float(np.max(np.abs(got[i] - exact[k]))) / scale[i] for i, k in enumerate(_STATE))
        if err <= tol:
            return ref
        points *= 4
