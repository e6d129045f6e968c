"""The tracking law: a time-varying linear-quadratic regulator about the exact trace of each section.

Why not the curvature law
-------------------------
The natural idea (command the blade's curvature ``kappa(s) + corrections`` through the curvature
condition, as the tracer holds the figure) fails in the glide. There the mass sits over the blade
(``a = 0``); ``adot`` then reaches the blade's speed but not its turning rate, and ``bdot`` reaches
neither: the turning rate changes only through the momentum (``dp1/dt = -m (a xi1 + bdot) xi2``).
Holding a corrected curvature instantly forces the speed to absorb every correction, and the loop
is unstable (measured: errors of 1e-9 grow to a 5e-3 limit cycle within a second on the circle eight).

The law
-------
Let ``z = (p1, p2, theta, x, y, a, b)`` be the sleigh's state with the mass position and
``u = (adot, bdot)`` the mass rates, ``dz/dt = f(z, u)`` the full model (eqs. p1_eq-y_eq and
``d(a, b)/dt = u``), and ``(z_r(t), u_r(t))`` the exact trace of a section. Linearised about it,
``d(dz)/dt = A(t) dz + B(t) du``. The law is

    u = u_r(t) - K(t) (z - z_r(t)),      K = R^-1 B^T P,

with ``P`` the solution of the Riccati equation ``-dP/dt = A^T P + P A - P B R^-1 B^T P + Q``
integrated backwards from ``P(T) = Q`` over the section. It minimises
``integral(dz^T Q dz + du^T R du) dt`` for the linearised error, so it uses whatever lever the
configuration offers at each instant (the speed through ``adot`` at a stop, the turning rate
through the momentum in a glide), and the closed loop's error decays wherever the linearisation
is stabilisable. Exactly on the trace (``dz = 0``) it gives the trace's own rates: it changes
nothing the tracer proved, and corrects only what departs from it.

Weights by Bryson's rule (each error or rate divided by what is acceptable): positions by the
convergence length ``L`` (default a hundredth of the figure's size), heading by ``L / size``,
momenta by the same fraction of their largest value on the section, the mass position by ``L``,
the mass position by a tenth of its largest distance from the blade (at least ``L``), and the
rates by the fastest mass rate of the section (times ``rate_weight``, default 100: see
:class:`TrackingGains`).

Limits (measured; ``docs/concepts/feedback.md`` has the details)
-----------------------------------------------------------------
- On the trace it reproduces the exact motion: the circle eight (1.7 m skater) stays within
  1.7e-9 of its size in a nominal closed-loop run (the open-loop schedule on the same integrator:
  1.7e-7), with rests at 1.7e-8 m/s. This is what verification relies on where the open-loop
  replay is ill-conditioned: there the law corrects the schedule by 1e-11 to 1e-9 of its rates.
- For a sleigh that is not the model use :func:`robust_gains` and give the law the momenta its
  model assigns to the measured motion (as :mod:`~skatetrace.feedback.closed_loop` does). Under
  +-5 % on ``M, m, I``, 1 mm / 0.5 deg and a 10 ms delay, the circle eight planned within 0.5 m
  stays within 0.166 m (p95 of 32; open loop 1.22 m), none diverging; the error is made where the
  plan glides with the mass over the contact point. The launch-glide-stop circle eight (the mass
  metres away) still diverges in 7 of 32, mid-section at full speed.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..dynamics.model import SleighParams, rhs_jacobian
from ..dynamics.simulate import Controller
from .reference import Reference

__all__ = ["ROBUST_RATE_WEIGHT", "TrackingGains", "TrackingLaw", "default_gains", "design", "robust_gains"]

#: Rate weight of :func:`robust_gains` (measured, not tuned per figure: see ``docs/concepts/feedback.md``).
ROBUST_RATE_WEIGHT = 3000.0


@dataclass(frozen=True, slots=True, kw_only=True)
class TrackingGains:
    """What the regulator treats as an acceptable error, in the figure's units (Bryson's rule).

    Parameters
    ----------
    length : float
        Acceptable position error of the blade and of the mass: errors are corrected over
        distances of this order.
    size : float
        The figure's size: an acceptable heading error is ``length / size``, an acceptable
        momentum error the same fraction of the section's largest momentum.
    rate_weight : float
        Multiplies the cost of the rates relative to Bryson's (the fastest mass rate of the section
        as acceptable). The default 100 keeps the closed loop's fastest mode near 200 /s on the
        circle eight (1.2e4 /s at 1, 1.2e3 /s at 10); faster modes need steps far below a
        millisecond and do not survive a delay of a few milliseconds.
    mass : float
        Acceptable error of the mass position as a fraction of its largest distance from the blade
        on the section (at least ``length``).
    """

    length: float
    size: float
    rate_weight: float = 100.0
    mass: float = 0.1

    def __post_init__(self) -> None:
        for name in ("length", "size", "rate_weight", "mass"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, float, np.integer, np.floating)) \
                    or not (math.isfinite(v) and v > 0):
                raise ValueError(f"tracking gain `{name}` must be a positive finite number, got {v!r}")
            object.__setattr__(self, name, float(v))

    def to_dict(self) -> dict[str, float]:
        return {"length": self.length, "size": self.size, "rate_weight": self.rate_weight, "mass": self.mass}


def default_gains(size: float) -> TrackingGains:
    """``length`` a hundredth of the figure's size: a correction stays local to the figure.

    For the model itself (verification): a stiff law, fastest mode near 200 /s. For a sleigh that
    is not the model, see :func:`robust_gains`.
    """
    return TrackingGains(length=0.01 * size, size=size)


def robust_gains(size: float, rate_weight: float = ROBUST_RATE_WEIGHT) -> TrackingGains:
    """:func:`default_gains` with the rates ``rate_weight`` times as costly: a slower law for a sleigh
    whose masses and inertia are off by percents.

    A fast law amplifies a model error: with the sleigh's mass 5 % off, the law of
    :func:`default_gains` drives the mass rates without bound within seconds, and a slower one does
    not (measured on the circle eight in ``docs/concepts/feedback.md``).
    """
    return TrackingGains(length=0.01 * size, size=size, rate_weight=rate_weight)


def _jacobians(p: SleighParams, z: np.ndarray, u: np.ndarray):
    """``A = df/dz`` (k, 7, 7) and ``B = df/du`` (k, 7, 2) at the columns of ``z`` (7, k), ``u`` (2, k):
    the model's exact derivatives (:func:`~skatetrace.dynamics.model.rhs_jacobian`), and ``d(a, b)/dt = u``."""
    k = z.shape[1]
    A, B = np.zeros((k, 7, 7)), np.zeros((k, 7, 2))
    for r0 in range(0, k, _BLOCK // 8):  # blocks small enough for the transposing copy to stay in cache
        rows = slice(r0, r0 + _BLOCK // 8)
        J = np.moveaxis(rhs_jacobian(p, z[:5, rows], z[5, rows], z[6, rows], u[0, rows], u[1, rows]), -1, 0)
        A[rows, :5] = J[:, :, :7]
        B[rows, :5] = J[:, :, 7:]
    B[:, 5, 0] = B[:, 6, 1] = 1.0
    return A, B


@dataclass(frozen=True, slots=True, eq=False)
class TrackingLaw:
    """The regulator of one section: gains ``K`` (k, 2, 7) at the reference's times ``t`` (k,).

    ``success`` is False (and ``message`` says why) where the Riccati equation could not be
    solved; ``K`` is then zero, the open loop: check ``success`` before relying on the law.
    ``params`` is the model the law was designed for: a replay of a different sleigh
    (:class:`~skatetrace.feedback.closed_loop.Plant`) shows the law the momenta this model gives to
    the motion it measures.
    """

    reference: Reference
    t: np.ndarray
    K: np.ndarray
    success: bool = True
    message: str = "gains designed"
    params: SleighParams | None = None

    def rates(self, tau, z: np.ndarray, measured_at=None) -> tuple[np.ndarray, np.ndarray]:
        """Mass rates at section time ``tau`` for states ``z`` (7, n) measured at ``measured_at``
        (default ``tau``): the schedule's rates at ``tau`` minus the gain times the measured error."""
        ref = self.reference
        n = z.shape[1]
        zr, ur = _reference_at(ref, tau, n)
        tm = tau
        if measured_at is not None and np.any(np.asarray(measured_at) != np.asarray(tau)):
            tm = measured_at
            zr, _ = _reference_at(ref, tm, n)
        dz = z - zr
        dz[2] = (dz[2] + np.pi) % (2 * np.pi) - np.pi
        du = np.einsum("nij,jn->in", self.gain(tm, n), dz)
        return ur[0] - du[0], ur[1] - du[1]

    def controller(self, start: float = 0.0) -> Controller:
        """This law as state feedback for :func:`skatetrace.simulate`, the section starting at ``start``.

        The schedule's rates jump at the section's breakpoints (the repeated times of
        ``reference.grid``); integrate between them for full accuracy, as
        :func:`~skatetrace.feedback.closed_loop.replay_law` does.
        """
        def rates(t, z):
            ad, bd = self.rates(t - start, np.asarray(z, dtype=float)[:, None])
            return float(ad[0]), float(bd[0])

        return Controller(rates)

    def thinned(self, rel_tol: float = 1e-3, start: int = 256) -> "TrackingLaw":
        """The same law with ``K`` kept at fewer times: linear interpolation between them stays within
        ``rel_tol`` of the largest gain at every dropped time (the rows of a fine reference run to
        millions; their gains to hundreds of megabytes of ``feedback.json``).

        Starts from ``start`` times spread evenly (and both sides of every jump of the rates), and
        adds the middle time of every interval that misses the bound until none does.
        """
        t, K = self.t, self.K.reshape(self.t.size, -1)
        n = t.size
        if n <= start:
            return self
        scale = max(float(np.max(np.abs(K))), 1e-300) * rel_tol
        jumps = np.flatnonzero(np.diff(t) == 0.0)
        keep = np.zeros(n, dtype=bool)
        keep[np.linspace(0, n - 1, start).astype(int)] = True
        keep[jumps], keep[jumps + 1] = True, True
        while True:
            idx = np.flatnonzero(keep)
            # the interpolant of each dropped row from the kept rows around it (index space: exact at jumps)
            seg = np.clip(np.searchsorted(idx, np.arange(n), side="right") - 1, 0, idx.size - 2)
            lo, hi = idx[seg], idx[seg + 1]
            h = t[hi] - t[lo]
            w = np.where(h > 0, (t - t[lo]) / np.where(h > 0, h, 1.0), 0.0)
            err = np.max(np.abs((1 - w)[:, None] * K[lo] + w[:, None] * K[hi] - K), axis=1)
            bad = np.unique(seg[(err > scale) & ~keep])
            if bad.size == 0:
                break
            keep[(idx[bad] + idx[bad + 1]) // 2] = True
        return TrackingLaw(reference=self.reference, t=t[keep], K=self.K[keep], success=self.success,
                           message=self.message, params=self.params)

    def gain(self, tau, n: int = 1) -> np.ndarray:
        """``K`` at section times ``tau`` (linear between the rows), shape ``(n, 2, 7)``."""
        t = self.t
        tau = np.asarray(tau, dtype=float)
        if tau.ndim == 0 and n > 1:  # one time for every trial: interpolate once
            return np.broadcast_to(self.gain(tau, 1), (n, 2, 7))
        tq = np.clip(np.broadcast_to(tau, (n,)), t[0], t[-1])
        j = np.clip(np.searchsorted(t, tq, side="right") - 1, 0, t.size - 2)
        h = t[j + 1] - t[j]
        w = np.where(h > 0, (tq - t[j]) / np.where(h > 0, h, 1.0), 0.0)
        return (1 - w)[:, None, None] * self.K[j] + w[:, None, None] * self.K[j + 1]


def _reference_at(ref: Reference, tau, n: int):
    """The reference's state ``(7, n)`` and rates ``(2, n)`` at ``tau`` (or ``(7, 1)`` and ``(2, 1)``,
    to broadcast, where ``tau`` is one time for every trial: evaluated once)."""
    tau = np.asarray(tau, dtype=float)
    return ref.state_at(tau if tau.ndim == 0 else np.broadcast_to(tau, (n,)))


#: Rows of the gains computed at once from the Riccati solution (bounds the temporaries).
_BLOCK = 65_536


def design(ref: Reference, params: SleighParams, gains: TrackingGains, *, max_nfev: int = 200_000) -> TrackingLaw:
    """Solve the section's Riccati equation backwards over the reference's rows.

    Never raises for a numerical failure: a Riccati solution that overflows (a reference at the
    limits of floating point, say a figure a micrometre across) or needs more than ``max_nfev``
    evaluations is returned as a law with ``success=False``.
    """
    from .riccati import solve_backwards

    t = ref.grid
    z, u = ref.state_at(t)
    A, B = _jacobians(params, z, u)
    L = gains.length
    frac = L / gains.size
    pscale = frac * max(float(np.max(np.abs(z[:2]))), 1e-300)
    ascale = max(gains.mass * float(np.max(np.hypot(z[5], z[6]))), L)
    q = np.array([1 / pscale**2, 1 / pscale**2, 1 / frac**2, 1 / L**2, 1 / L**2, 1 / ascale**2, 1 / ascale**2])
    uscale = max(float(np.max(np.abs(u))), 1e-300)
    Rinv = np.full(2, uscale**2 / gains.rate_weight)
    # scaled coordinates (dz = S y with S = diag(1/sqrt(q))) keep the Riccati equation well balanced
    s = 1 / np.sqrt(q)
    # in place: a section's rows run to a million, and each (k, 7, 7) array to half a gigabyte
    As, Bs = A, B
    As *= (1 / s)[None, :, None]
    As *= s[None, None, :]
    Bs *= (1 / s)[None, :, None]

    times = np.unique(t)  # a repeated row (a jump of the rates) has one P
    failed = TrackingLaw(reference=ref, t=t, K=np.zeros((t.size, 2, 7)), success=False,
                         message="the Riccati equation could not be solved over the section", params=params)
    if not (np.all(np.isfinite(As)) and np.all(np.isfinite(Bs)) and np.all(np.isfinite(Rinv))):
        return failed
    # compiled (skatetrace.feedback.riccati): DOP853's interpolant at the rows, step by step
    P = solve_backwards(t, As, Bs, Rinv, times, rtol=1e-6, atol=1e-9, max_nfev=max_nfev)
    if P is None:
        return failed
    # K (in the original coordinates) = R^-1 B^T P_original, with P_original = S^-1 P_scaled S^-1,
    # by blocks of rows (a repeated row reads its time's)
    column = np.searchsorted(times, t)
    K = np.empty((t.size, 2, 7))
    for r0 in range(0, t.size, _BLOCK):
        rows = slice(r0, r0 + _BLOCK)
        Ps = P[:, column[rows]].T.reshape(-1, 7, 7)
        Ps = 0.5 * (Ps + np.transpose(Ps, (0, 2, 1)))
        K[rows] = np.matmul(np.transpose(Bs[rows], (0, 2, 1)), Ps)
    K *= Rinv[None, :, None]
    K *= (1 / s)[None, None, :]
    if not np.all(np.isfinite(K)):
        return failed
    return TrackingLaw(reference=ref, t=t, K=K, params=params)
