"""The planning problem of one curve as a nonlinear program: direct collocation, solved by IPOPT through CasADi.

Each section (rest to rest) is a chain of phases, one per piece, each of free duration, on a
mesh of Radau collocation intervals (degree 3) graded towards the rests, where the mass moves
fastest. The state is ``x = (p1, p2, a, b, s, u)`` of :mod:`skatetrace.planning.symbolic`; the
control ``w = du/dt`` is constant on each interval, so ``u`` is piecewise linear in time: exactly
the form the exact finish (:mod:`skatetrace.planning.finish`) integrates. The curvature condition
holds by construction (the rates follow from ``u``), so the blade follows every piece for every
``u``; what the program shapes is the motion of the mass.

Constraints: rest (``xi2 = 0``) and the arc length at the ends of every section; the blade moving
forwards (``0 <= xi2 <= top_speed``) inside; the mass within ``reach`` of the contact point and
clear of the singular point; the mass's position on the ice continuous from one section to the
next (``(a, b)`` turned by the cusp's pivot or reversal) and, where asked, its velocity too;
optional bounds on the mass's acceleration on the ice and its speed relative to the blade.
Objective: least effort, ``int |m A|^2 dt`` with ``A`` the mass's acceleration on the ice, at a
given duration per section; or least time.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import casadi as ca
import numpy as np

from .symbolic import sleigh_functions

__all__ = ["PieceSpec", "SectionSpec", "ProgramOptions", "ProgramSolution", "solve_program"]

_DEGREE = 3
#: IPOPT's ends that may still leave a feasible point, and the largest constraint violation of one.
_STALLED = ("Error_In_Step_Computation", "Maximum_Iterations_Exceeded", "Restoration_Failed",
            "Search_Direction_Becomes_Too_Small", "Solved_To_Acceptable_Level")
_FEASIBLE = 1e-8


def _radau() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Collocation points (with 0), derivative matrix ``C`` and quadrature weights ``B``."""
    tau = np.append(0.0, ca.collocation_points(_DEGREE, "radau"))
    C = np.zeros((_DEGREE + 1, _DEGREE + 1))
    B = np.zeros(_DEGREE + 1)
    for j in range(_DEGREE + 1):
        p = np.poly1d([1.0])
        for r in range(_DEGREE + 1):
            if r != j:
                p *= np.poly1d([1.0, -tau[r]]) / (tau[j] - tau[r])
        dp = np.polyder(p)
        C[j] = [dp(t) for t in tau]
        B[j] = np.polyint(p)(1.0)
    return tau, C, B


@dataclass(frozen=True, slots=True)
class PieceSpec:
    """One piece of a section: curvature coefficients ``(c0, c1, c2, c3)`` in the distance travelled, and its length."""

    coefficients: tuple[float, float, float, float]
    length: float


@dataclass(frozen=True, slots=True)
class SectionSpec:
    """A section in its travel frame, and how it meets the one before.

    ``turn`` is the angle from the previous section's travel frame at its end to this section's at
    its start (minus the pivot, and ``pi`` for a reversal): a mass fixed on the ice has
    ``(a, b)_start = R(turn) (a, b)_previous end``. ``duration`` is the section's duration for
    the least-effort objective (normalised time, top speed 1).
    """

    pieces: tuple[PieceSpec, ...]
    turn: float = 0.0
    duration: float = math.nan

    @property
    def length(self) -> float:
        return float(sum(p.length for p in self.pieces))


@dataclass(frozen=True, slots=True, kw_only=True)
class ProgramOptions:
    """What the program asks for, in normalised units (masses with ``M + m = 1``, top speed 1).

    Besides the constraints of the module docstring: ``start_position`` and ``start_rates`` pin
    the first section's start (the mass's ``(a, b)`` and its rates); ``closing_turn`` links the
    last section back to the first; the mesh has at least ``intervals`` per section and one per
    ``interval_duration`` of it; ``min_speed`` is the floor of the blade's speed away from the
    rests; ``tol``, ``max_iter``, ``print_level``, ``barrier`` (IPOPT's ``mu_strategy``) and
    ``mu_init`` go to IPOPT (``max_iter`` 500: the linked programs that converged took at most 361
    iterations, the single sections about 200, and a program that runs to 1000 costs minutes).
    """

    M: float
    m: float
    I: float
    reach: float
    objective: str = "effort"
    max_accel: float | None = None
    max_rate: float | None = None
    singular_clearance: float = 0.0
    continuous_velocity: bool = True
    impulse_time: float = 0.1
    closing_turn: float | None = None
    start_position: tuple[float, float] | None = None
    start_rates: tuple[float, float] | None = None
    intervals: int = 36
    interval_duration: float = 0.3
    top_speed: float = 1.0
    min_speed: float = 0.02
    tol: float = 1e-8
    barrier: str = "adaptive"
    mu_init: float = 0.1
    max_iter: int = 500
    print_level: int = 0


@dataclass(frozen=True, slots=True, kw_only=True)
class ProgramSolution:
    """IPOPT's answer: per section the node times, states and controls, and the solver's report."""

    success: bool
    status: str
    message: str
    times: tuple[np.ndarray, ...] = ()
    states: tuple[np.ndarray, ...] = ()
    controls: tuple[np.ndarray, ...] = ()
    objective: float = math.nan
    iterations: int = 0
    meshes: tuple = ()
    stats: dict = field(default_factory=dict)


def _guess_profile(length: float, duration: float):
    """Arc length and speed of a launch-glide-stop guess: sin^2 ramps, top speed 1, ``duration``."""
    ramp = max(duration - length, 1e-3 * duration)

    def s_v(t):
        t = np.asarray(t, dtype=float)
        s = np.empty_like(t)
        v = np.empty_like(t)
        up = t < ramp
        down = t > duration - ramp
        mid = ~(up | down)
        s[up] = 0.5 * t[up] - ramp / (2 * math.pi) * np.sin(math.pi * t[up] / ramp)
        v[up] = np.sin(0.5 * math.pi * t[up] / ramp) ** 2
        s[mid] = 0.5 * ramp + (t[mid] - ramp)
        v[mid] = 1.0
        r = duration - t[down]
        s[down] = (duration - ramp) - (0.5 * r - ramp / (2 * math.pi) * np.sin(math.pi * r / ramp))
        v[down] = np.sin(0.5 * math.pi * r / ramp) ** 2
        scale = length / (duration - ramp)
        return s * scale, v * scale
    return s_v


def _mesh(spec: SectionSpec, duration: float, n: int):
    """Per piece: the guess times of its mesh nodes (graded towards both rests), at least 3 intervals each."""
    s_v = _guess_profile(spec.length, duration)
    fine = np.linspace(0.0, duration, 4001)
    s_fine = s_v(fine)[0]
    ends = np.cumsum([p.length for p in spec.pieces])
    bounds = np.concatenate([[0.0], np.interp(ends[:-1], s_fine, fine), [duration]])
    section_nodes = 0.5 * duration * (1.0 - np.cos(math.pi * np.arange(n + 1) / n))
    out = []
    for t0, t1 in zip(bounds[:-1], bounds[1:]):
        inside = section_nodes[(section_nodes > t0) & (section_nodes < t1)]
        nodes = np.concatenate([[t0], inside, [t1]])
        while nodes.size < 4:
            nodes = np.sort(np.concatenate([nodes, 0.5 * (nodes[:-1] + nodes[1:])]))
        out.append(nodes)
    return out, s_v


def _kappa(cf, s, s0):
    sigma = s - s0
    return cf[0] + sigma * (cf[1] + sigma * (cf[2] + sigma * cf[3]))


def _rot(angle, v):
    c, s = math.cos(angle), math.sin(angle)
    return ca.vertcat(c * v[0] - s * v[1], s * v[0] + c * v[1])


def solve_program(sections: list[SectionSpec], options: ProgramOptions, guess=None, meshes=None) -> ProgramSolution:
    """Build and solve the program of a chain of sections (one curve, or the unit of a repeated one).

    ``guess`` (optional) is a :class:`ProgramSolution` of the same sections to start from; by
    default the start is a launch-glide-stop: sin^2 speed ramps with the mass still at
    ``(0, b_g)``, ``b_g`` half the reach on the side away from the singular points.
    ``meshes`` (optional) gives per section and piece the mesh nodes (any increasing times; only
    their proportions count), e.g. a refined :attr:`ProgramSolution.meshes`; ``guess`` must then
    be given on the same nodes. Never raises for a program IPOPT cannot solve: the result says so.
    """
    o = options
    meshes_in = meshes
    fn = sleigh_functions(o.M, o.m, o.I)
    f, accel, xi2f, ratesf = fn["f"], fn["accel"], fn["xi2"], fn["rates"]
    tau, C, B = _radau()
    opti = ca.Opti()
    interval = _interval_function(fn, C, B, o)
    cost = 0
    handles = []
    prev_end = None  # (x, cf, s0) at the end of the previous section
    first_start = None
    reach2 = o.reach * o.reach
    for k, spec in enumerate(sections):
        duration = spec.duration if math.isfinite(spec.duration) else 1.25 * spec.length
        # at least ``intervals`` per section, and one per ``interval_duration`` of it: a long section
        # on a fixed count plans too coarsely for the exact finish to mend (circle eight, serpentine)
        n = max(o.intervals, math.ceil(duration / o.interval_duration))
        default_mesh, s_v = _mesh(spec, duration, n)
        meshes = default_mesh if meshes_in is None else meshes_in[k]
        kg = max(spec.pieces, key=lambda p: p.length).coefficients[0]
        b_guess = -0.5 * o.reach if kg > 0 else 0.5 * o.reach
        sec_T, sec_X, sec_W, sec_Xc = [], [], [], []
        s_start = 0.0
        x_prev_piece = None
        for j, piece in enumerate(spec.pieces):
            cf = ca.DM(list(piece.coefficients))
            nodes = meshes[j]
            frac = (nodes - nodes[0]) / (nodes[-1] - nodes[0])
            N = frac.size - 1
            T = opti.variable()
            opti.subject_to(T >= 1e-6 * duration)
            opti.set_initial(T, default_mesh[j][-1] - default_mesh[j][0])
            X = opti.variable(6, N + 1)
            Xc = opti.variable(6, _DEGREE * N)
            W = opti.variable(1, N)
            # the guess
            tg = default_mesh[j][0] + (nodes - nodes[0]) / (nodes[-1] - nodes[0]) * (
                default_mesh[j][-1] - default_mesh[j][0])
            sg, vg = s_v(tg)
            kap = np.array([float(_kappa(piece.coefficients, s, s_start)) for s in sg])
            M_, m_, I_ = o.M, o.m, o.I
            p1g = (I_ + m_ * b_guess**2) * kap * vg - m_ * b_guess * vg
            p2g = (M_ + m_) * vg - m_ * b_guess * kap * vg
            Xg = np.vstack([p1g, p2g, np.zeros_like(tg), np.full_like(tg, b_guess), sg, np.zeros_like(tg)])
            opti.set_initial(X, Xg)
            opti.set_initial(Xc, np.repeat(Xg[:, 1:], _DEGREE, axis=1))
            opti.set_initial(W, 0.0)
            if x_prev_piece is not None:
                opti.subject_to(X[:, 0] == x_prev_piece)
            hs = T * ca.DM(np.diff(frac)).T  # (1, N) interval lengths
            defect, quad, path = interval.map(N)(X[:, :N], ca.reshape(Xc, 6 * _DEGREE, N), W, hs, cf, s_start)
            opti.subject_to(ca.vec(defect) == 0)
            opti.subject_to(X[:, 1:] == Xc[:, _DEGREE - 1::_DEGREE])
            cost += ca.sum2(quad)
            opti.subject_to(opti.bounded(0.0, ca.vec(path[0:_DEGREE, :]), o.top_speed))
            # The blade keeps moving between the rests: a speed that only touches zero (the blade
            # waiting at a rest while the mass moves, seen on the counter and the bracket) comes out
            # slightly negative in the exact motion, a stall. The floor rises from the rests to
            # min_speed (2 % of the glide) over a tenth of the section, at the collocation points' guessed times.
            if o.min_speed > 0.0:
                g0, g1 = default_mesh[j][0], default_mesh[j][-1]
                tc = g0 + (frac[:-1, None] + np.diff(frac)[:, None] * tau[None, 1:]) * (g1 - g0)
                ramp = np.minimum(1.0, np.minimum(tc, duration - tc) / (0.1 * duration))
                opti.subject_to(ca.vec(path[0:_DEGREE, :]) >= ca.vec(ca.DM(o.min_speed * ramp.T)))
            opti.subject_to(ca.vec(path[_DEGREE:2 * _DEGREE, :]) <= reach2)
            row = 2 * _DEGREE
            if o.singular_clearance > 0.0:
                opti.subject_to(ca.vec(path[row:row + _DEGREE, :]) >= o.singular_clearance**2)
                row += _DEGREE
            if o.max_accel is not None:
                opti.subject_to(ca.vec(path[row:row + _DEGREE, :]) <= o.max_accel**2)
                row += _DEGREE
            if o.max_rate is not None:
                opti.subject_to(ca.vec(path[row:row + _DEGREE, :]) <= o.max_rate**2)
            if j == 0:
                opti.subject_to(X[4, 0] == 0.0)
                opti.subject_to(xi2f(X[:, 0], 0.0, cf, s_start) == 0.0)
                opti.subject_to(X[2, 0] ** 2 + X[3, 0] ** 2 <= reach2)
                start = (X[:, 0], cf, s_start)
                if k == 0 and o.start_position is not None:
                    opti.subject_to(X[2:4, 0] == ca.DM(list(o.start_position)))
                if k == 0 and o.start_rates is not None:
                    opti.subject_to(ratesf(X[:, 0], 0.0, cf, s_start) == ca.DM(list(o.start_rates)))
            x_prev_piece = X[:, N]
            s_start += piece.length
            opti.subject_to(X[4, N] == s_start)  # the join (or the section's end) where the piece ends
            sec_T.append(T)
            sec_X.append(X)
            sec_W.append(W)
            sec_Xc.append(Xc)
            last_cf = cf
        x_end = sec_X[-1][:, -1]
        s_last = s_start - spec.pieces[-1].length
        opti.subject_to(xi2f(x_end, 0.0, last_cf, s_last) == 0.0)
        if o.objective == "effort":
            opti.subject_to(sum(sec_T) == duration)
        end = (x_end, last_cf, s_last)
        if prev_end is not None:
            cost += _link(opti, prev_end, start, spec.turn, ratesf, o)
        else:
            first_start = start
        prev_end = end
        handles.append((sec_T, sec_X, sec_W, meshes, sec_Xc))
    if o.closing_turn is not None and first_start is not None:
        cost += _link(opti, prev_end, first_start, o.closing_turn, ratesf, o)
    if o.objective == "time":
        cost += sum(sum(h[0]) for h in handles)
    opti.minimize(cost)
    if guess is not None:
        _set_guess(opti, handles, guess)
    # IPOPT's barrier: adaptive updates take half the iterations of the monotone default on one
    # section; the linked program of a curve does better monotone from mu = 0.1 (245 against 361)
    opti.solver("ipopt", {"expand": True, "print_time": False, "ipopt.print_level": o.print_level, "ipopt.sb": "yes",
                          "ipopt.mu_strategy": o.barrier, "ipopt.mu_init": o.mu_init,
                          "ipopt.max_iter": o.max_iter, "ipopt.tol": o.tol})
    try:
        sol = opti.solve()
        ok = True
    except RuntimeError:
        sol = opti.debug
        ok = False
    stats = opti.stats()
    status = str(stats.get("return_status", "unknown"))
    message = status.replace("_", " ").lower()
    if not ok and status in _STALLED:
        # A feasible point where IPOPT could not prove optimality (one-foot eight: the constraints
        # met to 5e-13, the step computation failing on degenerate multipliers) is a plan: the
        # exact finish and the certified reach do not rely on its optimality.
        inf_pr = stats.get("iterations", {}).get("inf_pr", [math.inf])
        if inf_pr and inf_pr[-1] <= _FEASIBLE:
            ok = True
            message = f"feasible, optimality not proven ({message})"
    times, states, controls = [], [], []
    for sec_T, sec_X, sec_W, meshes, _xc in handles:
        t0 = 0.0
        ts, xs, ws = [], [], []
        for T, X, W, nodes in zip(sec_T, sec_X, sec_W, meshes):
            Tv = float(sol.value(T))
            frac = (nodes - nodes[0]) / (nodes[-1] - nodes[0])
            ts.append(t0 + Tv * frac if not ts else (t0 + Tv * frac)[1:])
            Xv = np.asarray(sol.value(X)).reshape(6, -1)
            xs.append(Xv if not xs else Xv[:, 1:])
            ws.append(np.atleast_1d(sol.value(W)).ravel())
            t0 += Tv
        times.append(np.concatenate(ts))
        states.append(np.hstack(xs))
        controls.append(np.concatenate(ws))
    return ProgramSolution(success=ok, status=status, message=message,
                           times=tuple(times), states=tuple(states), controls=tuple(controls),
                           meshes=tuple(tuple(h[3]) for h in handles),
                           objective=float(sol.value(cost)), iterations=int(stats.get("iter_count", 0)), stats={
                               k: stats[k] for k in ("t_wall_total",) if k in stats})


def _interval_function(fn, C, B, o) -> ca.Function:
    """One collocation interval as a flat SX function, mapped over a piece's intervals.

    Inputs ``(x_k, x_c (6 * degree), w, h, coefficients, s0)``; outputs the collocation defects,
    the interval's share of the objective and the path quantities at the collocation points (rows:
    speed ``xi2``, ``a^2 + b^2``, then as asked the squared distance from the singular point, the
    squared acceleration and the squared rates). Building the program from one mapped function
    keeps CasADi's derivative setup small: inlining every call cost seconds per solve.
    """
    f, accel, xi2f, ratesf = fn["f"], fn["accel"], fn["xi2"], fn["rates"]
    xk = ca.SX.sym("xk", 6)
    xc = ca.SX.sym("xc", 6 * _DEGREE)
    w = ca.SX.sym("w")
    h = ca.SX.sym("h")
    cf = ca.SX.sym("cf", 4)
    s0 = ca.SX.sym("s0")
    xs = [xk] + [xc[6 * r:6 * r + 6] for r in range(_DEGREE)]
    defects, quad = [], 0
    speed, reach, sing, acc, rate = [], [], [], [], []
    # The mass's acceleration from the collocation polynomial of its velocity (differentiated like
    # the states'), not from the chain rule through the dynamics: a far smaller expression for
    # IPOPT's Hessian, and the same to the mesh's accuracy (the mesh is refined against it).
    vels = [fn["velocity"](x, w, cf, s0) for x in xs]
    for r in range(1, _DEGREE + 1):
        xr = xs[r]
        xp = sum(C[q, r] * xs[q] for q in range(_DEGREE + 1))
        defects.append(h * f(xr, w, cf, s0) - xp)
        v_r, xi1_r = vels[r]
        vdot = sum(C[q, r] * vels[q][0] for q in range(_DEGREE + 1)) / h
        A = ca.vertcat(vdot[0] - xi1_r * v_r[1], vdot[1] + xi1_r * v_r[0])
        if o.objective == "effort":
            quad += B[r] * h * (o.m * o.m) * ca.sumsqr(A)
        quad += 1e-6 * B[r] * h * w**2
        speed.append(xi2f(xr, w, cf, s0))
        reach.append(xr[2] ** 2 + xr[3] ** 2)
        bs = -_kappa(cf, xr[4], s0) * o.I / o.M
        sing.append(xr[2] ** 2 + (xr[3] - bs) ** 2)
        acc.append(ca.sumsqr(A))
        rate.append(ca.sumsqr(ratesf(xr, w, cf, s0)))
    rows = speed + reach
    if o.singular_clearance > 0.0:
        rows += sing
    if o.max_accel is not None:
        rows += acc
    if o.max_rate is not None:
        rows += rate
    return ca.Function("interval", [xk, xc, w, h, cf, s0],
                       [ca.vertcat(*defects), quad, ca.vertcat(*rows)])


def _link(opti, end, start, turn, ratesf, o):
    """Position (and velocity) of the mass on the ice continuous from ``end`` to ``start``; returns any penalty."""
    x_end, cf_e, s_e = end
    x_start, cf_s, s_s = start
    opti.subject_to(x_start[2:4] == _rot(turn, x_end[2:4]))
    v_end = _rot(turn, ratesf(x_end, 0.0, cf_e, s_e))
    v_start = ratesf(x_start, 0.0, cf_s, s_s)
    if o.continuous_velocity:
        opti.subject_to(v_start == v_end)
        return 0
    return (o.m * o.m) * ca.sumsqr(v_start - v_end) / o.impulse_time


def _set_guess(opti, handles, guess: ProgramSolution) -> None:
    """Start from a solution of the same program (e.g. at another reach)."""
    for (sec_T, sec_X, sec_W, meshes, sec_Xc), times, X, W in zip(handles, guess.times, guess.states,
                                                                   guess.controls):
        i = 0
        for T, Xv, Wv, nodes, Xc in zip(sec_T, sec_X, sec_W, meshes, sec_Xc):
            N = nodes.size - 1
            opti.set_initial(T, times[i + N] - times[i])
            opti.set_initial(Xv, X[:, i:i + N + 1])
            opti.set_initial(Wv, W[i:i + N])
            opti.set_initial(Xc, np.repeat(X[:, i + 1:i + N + 1], _DEGREE, axis=1))
            i += N
