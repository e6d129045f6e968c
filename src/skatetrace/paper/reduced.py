"""The paper's Chaplygin sleigh "reduced to circular trajectories", integrated both ways in time.

Section "Chaplygin Sleigh Model Reduced to Circular Trajectories" keeps ``(p1, theta, x, y)`` (and
``b`` in the appendix), eliminates ``p2`` through ``p2 = (c - p1) / r`` and imposes
``xi2 = r xi1``. With two prescribed controls (the main method) the velocity formulas
(xi1_eq)-(xi2_eq) do not satisfy ``xi2 = r xi1`` by themselves, so the reduced model has to decide
which one to keep. The paper does not say; :class:`ReducedOptions` ``closure`` selects:

- ``"xi2"`` (default, the most plausible reading): the speed ``xi2`` comes from (xi2_eq) and the
  heading turns at ``xi2 / r``; the path is a circle by construction and ``xi2`` is the speed that
  the termination event watches, as the paper describes.
- ``"xi1"``: ``xi1`` from (xi1_eq) and the speed ``r xi1``.
- ``"formulas"``: both from the formulas; the path is then not a circle.

``c`` is ``p1 + r p2`` at the initial condition: that is the invariant that holds on an arc
(PHYSICS.md). The lemma's printed ``p1 + p2 / r`` is wrong, and the paper's own
``p2 = (c - p1) / r`` matches ``p1 + r p2 = c``.

``T`` is read as the integration time in each direction (``time="each"``, default): forward on
``[0, T]`` and backward on ``[0, -T]``, each ending early where the speed vanishes (a terminal
event, as in the paper's step 5). ``time="split"`` integrates ``[0, T/2]`` and ``[0, -T/2]``.

The length of the combined arc is ``r (theta(t2) - theta(t1))``, the paper's
``L = r (Psi2 - Psi1)``; :attr:`ReducedArc.path_length` is the distance actually travelled.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.integrate import BDF, DOP853, LSODA, RK23, RK45, OdeSolution, Radau
from scipy.optimize import brentq

from ..dynamics.model import SleighParams, velocities
from .controls import CircularControl, HarmonicControl, b_rate_printed

__all__ = ["ReducedOptions", "HalfArc", "ReducedArc", "integrate_reduced", "PAPER_SOLVER", "TIGHT_SOLVER"]

_CLOSURES = ("xi2", "xi1", "formulas")
_SOLVERS = {"BDF": BDF, "Radau": Radau, "LSODA": LSODA, "RK45": RK45, "RK23": RK23, "DOP853": DOP853}
_TIMES = ("each", "split")


@dataclass(frozen=True, slots=True, kw_only=True)
class ReducedOptions:
    """How the reduced model is closed and integrated.

    Attributes
    ----------
    closure : {"xi2", "xi1", "formulas"}
        Which velocity formula the reduced main-method model keeps (module docstring). The
        appendix controls satisfy ``xi2 = r xi1`` through ``bdot``, so the choice only matters there
        up to round-off.
    time : {"each", "split"}
        Reading of the tables' ``T``.
    method, rtol, atol : solve_ivp settings
        The paper used ``"BDF"`` with scipy's default tolerances (``1e-3``, ``1e-6``).
    max_nfev : int
        Budget of right-hand-side calls per direction; a half-arc that exhausts it stops there
        (status ``"budget"``), as near the singularity ``a = 0`` of (b_diff_eq).
    fine_events : int
        Interior points per step at which the speed's sign is also checked (0: only at step ends,
        as solve_ivp does and the paper's runs did). A speed that dips through zero and back within
        one step is otherwise missed.
    """

    closure: str = "xi2"
    time: str = "each"
    method: str = "BDF"
    rtol: float = 1e-3
    atol: float = 1e-6
    max_nfev: int = 200_000
    fine_events: int = 0

    def __post_init__(self) -> None:
        if self.closure not in _CLOSURES:
            raise ValueError(f"closure must be one of {_CLOSURES}, got {self.closure!r}")
        if self.time not in _TIMES:
            raise ValueError(f"time must be one of {_TIMES}, got {self.time!r}")
        if self.method not in _SOLVERS:
            raise ValueError(f"method must be one of {sorted(_SOLVERS)}, got {self.method!r}")
        if not (self.rtol > 0 and self.atol > 0 and self.max_nfev > 0 and self.fine_events >= 0):
            raise ValueError("rtol, atol and max_nfev must be positive and fine_events >= 0")


#: The paper's own solver settings: BDF at scipy's default tolerances.
PAPER_SOLVER = ReducedOptions()
#: Settings used to evaluate a parameter set accurately (the numbers in the report).
TIGHT_SOLVER = ReducedOptions(method="DOP853", rtol=1e-11, atol=1e-12, fine_events=8)


@dataclass(frozen=True, slots=True, kw_only=True)
class HalfArc:
    """One direction of integration from ``t = 0``.

    ``t`` is ordered in the direction of integration; ``state`` has rows ``p1, theta, x, y`` (and
    ``b`` for the appendix). ``status`` is ``"stopped"`` (the speed vanished: the paper's event),
    ``"time"`` (reached ``+-T`` still moving), ``"failed"`` (the integrator gave up) or
    ``"budget"``.
    """

    t: np.ndarray
    state: np.ndarray
    sol: object
    status: str
    message: str
    nfev: int

    @property
    def t_end(self) -> float:
        return float(self.t[-1])


@dataclass(frozen=True, slots=True, kw_only=True)
class ReducedArc:
    """Backward and forward halves of one arc of the reduced model, and what they measure."""

    params: SleighParams
    radius: float
    invariant: float
    control: CircularControl | HarmonicControl
    options: ReducedOptions
    forward: HalfArc
    backward: HalfArc | None

    @property
    def t1(self) -> float:
        return self.backward.t_end if self.backward is not None else 0.0

    @property
    def t2(self) -> float:
        return self.forward.t_end

    def halves(self) -> list[HalfArc]:
        return [h for h in (self.backward, self.forward) if h is not None]

    def series(self, t) -> dict[str, np.ndarray]:
        """States, controls and velocities at times ``t`` within ``[t1, t2]``.

        Keys: ``t, p1, p2, theta, x, y, a, b, adot, bdot, xi1, xi2, eta, speed`` (``speed`` is
        the rate of arc length the reduced model uses, ``xi2`` in the default closure).
        """
        t = np.atleast_1d(np.asarray(t, dtype=float))
        cols = [self._point(float(ti)) for ti in t]
        keys = cols[0].keys() if cols else ()
        return {k: np.array([c[k] for c in cols]) for k in keys}

    def sample(self, n: int = 400) -> dict[str, np.ndarray]:
        """:meth:`series` on ``n`` points from ``t1`` to ``t2`` (with ``t = 0`` included)."""
        nb = int(round(n * abs(self.t1) / max(self.t2 - self.t1, 1e-300)))
        tb = np.linspace(self.t1, 0.0, max(nb, 2)) if self.backward is not None else np.empty(0)
        tf = np.linspace(0.0, self.t2, max(n - nb, 2))
        return self.series(np.concatenate([tb[:-1], tf]))

    def _point(self, t: float) -> dict[str, float]:
        half = self.backward if (t < 0 and self.backward is not None) else self.forward
        y = half.sol(t)
        return _evaluate(self.params, self.radius, self.invariant, self.control, self.options, t, y)

    @property
    def length(self) -> float:
        """The paper's ``L_s = r (theta(t2) - theta(t1))``."""
        th2 = self.forward.state[1, -1]
        th1 = self.backward.state[1, -1] if self.backward is not None else self.forward.state[1, 0]
        return self.radius * float(th2 - th1)

    @property
    def path_length(self) -> float:
        """Distance travelled, ``integral of |speed| dt`` over ``[t1, t2]``."""
        total = 0.0
        for h in self.halves():
            tt = np.linspace(0.0, h.t_end, 2001)
            v = np.abs(self.series(tt)["speed"])
            total += abs(float(np.sum(0.5 * (v[1:] + v[:-1]) * np.diff(tt))))
        return total

    def end_speeds(self) -> tuple[float, float]:
        """Speeds at ``t1`` and ``t2``."""
        s = self.series([self.t1, self.t2])["speed"]
        return float(s[0]), float(s[1])

    @property
    def completed(self) -> bool:
        """Both halves ended where the speed vanished, as the procedure requires."""
        return all(h.status == "stopped" for h in self.halves())


def _evaluate(params, r, c, control, options, t, y) -> dict[str, float]:
    p1, theta, x, yy = y[0], y[1], y[2], y[3]
    p2 = (c - p1) / r
    a, adot = control.a(t)
    if isinstance(control, CircularControl):
        b, bdot = control.b(t)
    else:
        b = y[4]
        bdot = b_rate_printed(params, r, p1, p2, a, adot, b)
    xi1, xi2, eta = velocities(params, p1, p2, a, b, adot, bdot)
    if options.closure == "xi2":
        speed, turn = xi2, xi2 / r
    elif options.closure == "xi1":
        speed, turn = r * xi1, xi1
    else:
        speed, turn = xi2, xi1
    return {"t": t, "p1": p1, "p2": p2, "theta": theta, "x": x, "y": yy, "a": a, "b": b, "adot": adot,
            "bdot": bdot, "xi1": xi1, "xi2": xi2, "eta": eta, "speed": speed, "turn": turn}


def _half(params, r, c, control, options, y0, t_end) -> HalfArc:
    """Step ``options.method`` from 0 to ``t_end``, stopping where the speed changes sign.

    The loop is solve_ivp's (sign of the event at step ends, root by Brent's method on the dense
    output, ``xtol`` 4 eps), with two additions: an evaluation budget, and, if
    ``options.fine_events``, a sign check at interior points of each step so that a speed that
    dips through zero and back within one step is not missed.
    """
    m = params.m
    appendix = isinstance(control, HarmonicControl)

    def f(t, y):
        v = _evaluate(params, r, c, control, options, t, y)
        out = [-m * v["eta"] * v["speed"], v["turn"], v["speed"] * math.cos(y[1]), v["speed"] * math.sin(y[1])]
        if appendix:
            out.append(v["bdot"])
        return out

    def speed(t, y):
        return _evaluate(params, r, c, control, options, t, y)["speed"]

    y0 = np.asarray(y0, dtype=float)
    ts, ys, interps = [0.0], [y0], []
    status, msg, stuck = "time", f"reached t = {t_end:g} still moving", 0
    with np.errstate(all="ignore"):  # a singular control shows up as a failed half, not a warning
        solver = _SOLVERS[options.method](f, 0.0, y0, t_end, rtol=options.rtol, atol=options.atol)
        g_prev = speed(0.0, y0)
        while True:
            message = solver.step()
            if solver.status == "failed" or not np.all(np.isfinite(solver.y)):
                status, msg = "failed", f"integration failed at t = {ts[-1]:.6g}: {message or 'non-finite state'}"
                break
            if solver.t == ts[-1]:  # LSODA can return without advancing where steps collapse
                stuck += 1
                if stuck > 50:
                    status, msg = "failed", f"integration failed at t = {ts[-1]:.6g}: no progress"
                    break
                continue
            dense = solver.dense_output()
            grid = (np.linspace(ts[-1], solver.t, options.fine_events + 2) if options.fine_events
                    else np.array([ts[-1], solver.t]))
            g = [g_prev] + [speed(float(tk), dense(float(tk))) for tk in grid[1:]]
            root = None
            for k in range(1, len(grid)):
                if g[k - 1] * g[k] < 0 or (g[k] == 0.0 and g[k - 1] != 0.0):
                    ta, tb = float(grid[k - 1]), float(grid[k])
                    root = tb if g[k] == 0.0 else brentq(lambda tt: speed(tt, dense(tt)), ta, tb,
                                                         xtol=4 * np.finfo(float).eps)
                    break
            interps.append(dense)
            if root is not None:
                ts.append(root)
                ys.append(dense(root))
                status, msg = "stopped", f"speed vanished at t = {root:.6g}"
                break
            ts.append(solver.t)
            ys.append(solver.y.copy())
            g_prev = g[-1]
            if solver.status == "finished":
                break
            if solver.nfev > options.max_nfev:
                status, msg = "budget", (f"stopped at t = {solver.t:.6g} after {solver.nfev} evaluations, the "
                                         "budget (step sizes collapse near a singular control)")
                break
    sol = OdeSolution(np.array(ts), interps) if interps else None
    return HalfArc(t=np.array(ts), state=np.array(ys).T, sol=sol, status=status, message=msg, nfev=int(solver.nfev))


def integrate_reduced(params: SleighParams, radius: float, initial, control: CircularControl | HarmonicControl,
                      T: float, options: ReducedOptions = PAPER_SOLVER, *, backward: bool = True) -> ReducedArc:
    """Integrate the reduced circular model from ``initial`` forward (and backward) in time.

    Parameters
    ----------
    radius : float
        ``r`` of the arc (positive: the arc turns left when the speed is positive).
    initial : sequence
        ``(p1, p2, theta, x, y)``, plus ``b`` for :class:`HarmonicControl`.
    T : float
        The table's time; see ``options.time``.

    Returns
    -------
    ReducedArc
        Never raises for a numerical failure: each half carries a status and message.

    Examples
    --------
    >>> from skatetrace.paper.tables import paper_row
    >>> row = paper_row("main", 1)
    >>> ctrl = CircularControl(*row.published)
    >>> arc = integrate_reduced(SleighParams(), row.radius, row.initial, ctrl, row.T, TIGHT_SOLVER)
    >>> arc.completed, round(arc.length, 4), round(row.target_length, 4)  # far from L_opt
    (True, 2.0357, 4.1469)
    >>> integrate_reduced(SleighParams(), row.radius, row.initial, ctrl, row.T).backward.message  # the paper's BDF
    'reached t = -6 still moving'
    """
    if not (radius > 0 and math.isfinite(radius)):
        raise ValueError(f"radius must be a positive number, got {radius!r}")
    if not (T > 0 and math.isfinite(T)):
        raise ValueError(f"T must be a positive time, got {T!r}")
    appendix = isinstance(control, HarmonicControl)
    initial = [float(v) for v in initial]
    if len(initial) != (6 if appendix else 5):
        raise ValueError(f"initial must be (p1, p2, theta, x, y{', b' if appendix else ''}), got {initial!r}")
    p1, p2, th, x, y = initial[:5]
    c = p1 + radius * p2
    y0 = [p1, th, x, y] + ([initial[5]] if appendix else [])
    span = T if options.time == "each" else T / 2
    fwd = _half(params, radius, c, control, options, y0, span)
    bwd = _half(params, radius, c, control, options, y0, -span) if backward else None
    return ReducedArc(params=params, radius=radius, invariant=c, control=control, options=options, forward=fwd,
                      backward=bwd)
