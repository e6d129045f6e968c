"""The planning problem of one curve as a nonlinear program: direct collocation, solved by IPOPT through CasADi.

Each section (rest to rest) is a chain of phases, one per piece, each of free duration, on a
mesh of Radau collocation intervals (degree 3) graded towards the rests, where the mass moves
fastest. Radau's last collocation point is the interval's end, so that point's state is the next
node's, one unknown, not a copy tied to it by a constraint: an interval has 19 unknowns (its node,
two inner points and the control), not 25, and IPOPT's linear systems are a fifth smaller, with
the same optimum (the linked programs of the rocker, the one-foot eight, the change double three
and the paragraph double three end at the same effort to five digits from the same start, in 4 to
16 % less time). The state is ``x = (p1, p2, a, b, s, u)`` of :mod:`skatetrace.planning.symbolic`;
the control ``w = du/dt`` is constant on each interval, so ``u`` is piecewise linear in time: exactly
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

from .nlp import GiveUp, SparseProgram
from ..processes import recording_interrupts
from .symbolic import sleigh_functions

__all__ = ["MAX_UNKNOWNS", "PieceSpec", "SectionSpec", "ProgramOptions", "ProgramSolution", "iterations_within",
           "program_too_large", "program_unknowns", "solve_program"]

_DEGREE = 3
#: IPOPT's ends that may still leave a feasible point, and the largest constraint violation of one.
_STALLED = ("Error_In_Step_Computation", "Maximum_Iterations_Exceeded", "Restoration_Failed",
            "Search_Direction_Becomes_Too_Small", "Solved_To_Acceptable_Level", "Stalled")
_FEASIBLE = 1e-8
#: The most unknowns a program may have: the meshes that 12,000 allowed before the end states
#: were merged with the nodes (25 unknowns an interval, not 19), so the same programs are refused.
#: The school figures' largest curve has 7,720 (the paragraph double three, solved as its unit of
#: 3,860), the corpus drawings' up to 27,000. Measured before that merge, in its counts: memory,
#: CasADi and IPOPT take about 40 kB an unknown (a single section of 24,000: 0.9 GB); time,
#: IPOPT's iterations cost more as the program grows (45 ms at 4,500 unknowns, 250 ms at 16,000,
#: 600 ms at 34,000), so a larger program takes minutes: the serpentine in exact mode (one section
#: of 313 spirals, 33,691 unknowns) ran past 15 minutes, the three turn in exact mode (a section
#: of 136 spirals, 14,677) took 398 s, and feather-settings' curve of 34,722 spent 21 s failing.
#: A section that large is traced with the launch-glide-stop manoeuvres instead (the command
#: line's default reach falls back to them); a curve that large is not linked (its chain of
#: sections is the plan).
MAX_UNKNOWNS = 9_200


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
    the first section's start (the mass's ``(a, b)`` and its rates), ``end_position`` the last
    section's end (the mass's ``(a, b)``); ``closing_turn`` links the
    last section back to the first, or with ``closing_mirror`` to the mirror image of the first
    (``b`` and its rate reversed: the unit of a curve that repeats it mirrored); the mesh has at least ``intervals`` per section and one per
    ``interval_duration`` of it; ``min_speed`` is the floor of the blade's speed away from the
    rests; ``tol``, ``max_iter``, ``print_level``, ``barrier`` (IPOPT's ``mu_strategy``) and
    ``mu_init`` go to IPOPT (``max_iter`` 500: the linked programs that converged took at most 361
    iterations, the single sections about 200, and a program that runs to 1000 costs minutes);
    ``iteration_budget``, if given, caps the iterations at that many over the number of unknowns
    (at least ``max_iter`` / 4, and never above ``max_iter``), as IPOPT's cost an iteration
    grows with the program. ``give_up`` (a :class:`~skatetrace.planning.nlp.GiveUp`, optional)
    ends a solve that is going nowhere: a program it gives up fails with status ``"Given_Up"``.
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
    closing_mirror: bool = False
    start_position: tuple[float, float] | None = None
    start_rates: tuple[float, float] | None = None
    end_position: tuple[float, float] | None = None
    intervals: int = 36
    interval_duration: float = 0.3
    top_speed: float = 1.0
    min_speed: float = 0.02
    tol: float = 1e-8
    barrier: str = "adaptive"
    mu_init: float = 0.1
    max_iter: int = 500
    iteration_budget: int | None = None
    give_up: GiveUp | None = None
    print_level: int = 0

    def iterations_for(self, n: int) -> int:
        """IPOPT's ``max_iter`` for a program of ``n`` unknowns (see ``iteration_budget``)."""
        if self.iteration_budget is None:
            return self.max_iter
        return min(self.max_iter, max(self.max_iter // 4, self.iteration_budget // max(n, 1)))


@dataclass(frozen=True, slots=True, kw_only=True)
class ProgramSolution:
    """IPOPT's answer: per section the node times, states and controls, and the solver's report.

    ``iterations`` are IPOPT's and ``unknowns`` the program's size (both 0 where no solve ran):
    their product is the work a plan's budget counts (:func:`skatetrace.planning.pool.spending`;
    see :attr:`work`). ``allowed`` is the iterations IPOPT was allowed (its ``max_iter``).
    """

    success: bool
    status: str
    message: str
    times: tuple[np.ndarray, ...] = ()
    states: tuple[np.ndarray, ...] = ()
    controls: tuple[np.ndarray, ...] = ()
    objective: float = math.nan
    iterations: int = 0
    unknowns: int = 0
    meshes: tuple = ()
    stats: dict = field(default_factory=dict)
    allowed: int = 0

    @property
    def work(self) -> int:
        """What a plan's budget counts: iterations times unknowns; a program given up as going
        nowhere (``"Given_Up"``), or stalled and not kept, at the iterations it was allowed, as if
        it had run on to them.

        So the rule that ends it (:class:`~skatetrace.planning.nlp.GiveUp`) saves time and leaves
        the budget's decisions as they were where the program would have failed at its cap; where
        it would have failed sooner (IPOPT proving it infeasible), the budget counts more. A
        stalled program that is kept counts the iterations it made: its plan goes on from there.
        """
        capped = self.status == "Given_Up" or (self.status == "Stalled" and not self.success)
        return int(self.allowed if capped else self.iterations) * int(self.unknowns)


def iterations_within(max_work: int, unknowns: int) -> int:
    """The iterations a program of ``unknowns`` may make on ``max_work`` (a plan's budget, what is left of it):
    one more than fit in it, so that a program stopped there has spent more than ``max_work``."""
    return max_work // max(unknowns, 1) + 1


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
    # A node closer to a join than a quarter of the local spacing is left out: on a symmetric
    # section the middle join and node differ by round-off, and an interval of 1e-16 made IPOPT's
    # Hessian NaN (paragraph bracket) or its steps fail (paragraph three).
    gap = 0.25 * np.gradient(section_nodes)
    out = []
    for t0, t1 in zip(bounds[:-1], bounds[1:]):
        inside = section_nodes[(section_nodes > t0 + gap) & (section_nodes < t1 - gap)]
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


@dataclass(frozen=True, slots=True)
class _PieceLayout:
    """Where a piece's unknowns sit in the program's vector: its duration, node and collocation states, controls."""

    T: int
    X: int  # 6 x (N + 1), column-major
    Xc: int  # 6 x ((degree - 1) N): the inner collocation points (the last one of an interval is its end node)
    W: int  # N
    nodes: np.ndarray  # the mesh (only its proportions count)

    @property
    def N(self) -> int:
        return self.nodes.size - 1

    @property
    def end(self) -> int:
        return self.W + self.N

    @property
    def frac(self) -> np.ndarray:
        return (self.nodes - self.nodes[0]) / (self.nodes[-1] - self.nodes[0])

    def interval_index(self) -> tuple[np.ndarray, np.ndarray]:
        """Per interval, the entries of the vector that make its unknowns ``(x_k, x_c, w, h)``, and their scales.

        ``x_c`` is the state at the degree collocation points: the inner ones, then the last,
        which is the next node.
        """
        k = np.arange(self.N)
        index = np.empty((8 + 6 * _DEGREE, self.N), dtype=np.int64)
        index[0:6] = self.X + 6 * k + np.arange(6)[:, None]
        inner = 6 * (_DEGREE - 1)
        index[6:6 + inner] = self.Xc + inner * k + np.arange(inner)[:, None]
        index[6 + inner:6 + 6 * _DEGREE] = self.X + 6 * (k + 1) + np.arange(6)[:, None]
        index[-2] = self.W + k
        index[-1] = self.T
        scale = np.ones(index.shape)
        scale[-1] = np.diff(self.frac)  # an interval lasts the piece's duration times its fraction
        return index, scale


def _layout(sections: list[SectionSpec], o: ProgramOptions, meshes) -> tuple[list, int]:
    """Per section its duration, default mesh, guess profile and pieces' layouts; and the number of unknowns."""
    out, n = [], 0
    for k, spec in enumerate(sections):
        duration = spec.duration if math.isfinite(spec.duration) else 1.25 * spec.length
        # at least ``intervals`` per section, and one per ``interval_duration`` of it: a long section
        # on a fixed count plans too coarsely for the exact finish to mend (circle eight, serpentine)
        count = max(o.intervals, math.ceil(duration / o.interval_duration))
        default_mesh, s_v = _mesh(spec, duration, count)
        lays = []
        for nodes in (default_mesh if meshes is None else meshes[k]):
            N = len(nodes) - 1
            lay = _PieceLayout(T=n, X=n + 1, Xc=n + 1 + 6 * (N + 1), W=n + 1 + 6 * (N + 1) + 6 * (_DEGREE - 1) * N,
                               nodes=np.asarray(nodes, dtype=float))
            lays.append(lay)
            n = lay.end
        out.append((duration, default_mesh, s_v, lays))
    return out, n


def _too_large(layout, n: int, o: ProgramOptions) -> str | None:
    """Why a program of ``n`` unknowns is not built (more than :data:`MAX_UNKNOWNS`), or None."""
    if n <= MAX_UNKNOWNS:
        return None
    longest = max(duration for duration, *_ in layout)
    pieces = sum(len(lays) for *_, lays in layout)
    return (f"the program would have {n:,} unknowns, more than the {MAX_UNKNOWNS:,} allowed (its longest section "
            f"lasts {longest:.3g} of the planner's time units, at one mesh interval per {o.interval_duration:g}, and "
            f"its {pieces:,} pieces have at least 3 intervals each): trace a figure this long or this finely "
            "pieced with the launch-glide-stop manoeuvres (--reach none), or in parts")


def program_unknowns(sections: list[SectionSpec], options: ProgramOptions) -> int:
    """The number of unknowns of the program of ``sections`` on its default mesh (nothing is built)."""
    return _layout(sections, options, None)[1]


def program_too_large(sections: list[SectionSpec], options: ProgramOptions) -> str | None:
    """Why :func:`solve_program` would refuse the program of ``sections`` for its size, or None."""
    layout, n = _layout(sections, options, None)
    return _too_large(layout, n, options)


def solve_program(sections: list[SectionSpec], options: ProgramOptions, guess=None, meshes=None,
                  max_work: int | None = None) -> ProgramSolution:
    """Build and solve the program of a chain of sections (one curve, or the unit of a repeated one).

    ``guess`` (optional) is a :class:`ProgramSolution` of the same sections to start from; by
    default the start is a launch-glide-stop: sin^2 speed ramps with the mass still at
    ``(0, b_g)``, ``b_g`` half the reach on the side away from the singular points.
    ``meshes`` (optional) gives per section and piece the mesh nodes (any increasing times; only
    their proportions count), e.g. a refined :attr:`ProgramSolution.meshes`; ``guess`` must then
    be given on the same nodes. ``max_work`` (optional) bounds IPOPT's iterations to one more
    than it over the program's unknowns: a program stopped there has spent more than ``max_work``
    (what is left of a plan's budget, :func:`skatetrace.planning.pool.spending`). Never raises
    for a program IPOPT cannot solve: the result says so,
    also where CasADi or IPOPT stop with an error (out of memory, say: ``status="solver_error"``).
    """
    with recording_interrupts() as caught:
        try:
            return _solve_program(sections, options, guess, meshes, max_work)
        except (RuntimeError, MemoryError) as exc:  # CasADi raises RuntimeError for its own and IPOPT's errors
            if caught:  # Ctrl-C inside CasADi (building the program, say), which made it an error: stop
                raise KeyboardInterrupt from None
            error = exc
    text = " ".join(str(error).split())
    reason = "out of memory" if "bad_alloc" in text or isinstance(error, MemoryError) else text[-200:]
    return ProgramSolution(success=False, status="solver_error", message=f"the solver stopped: {reason}")


def _solve_program(sections: list[SectionSpec], options: ProgramOptions, guess, meshes,
                   max_work: int | None = None) -> ProgramSolution:
    o = options
    layout, n = _layout(sections, o, meshes)
    refused = _too_large(layout, n, o)  # before anything symbolic is built
    if refused is not None:
        return ProgramSolution(success=False, status="too_large", message=refused)
    fn = sleigh_functions(o.M, o.m, o.I)
    xi2f, ratesf = fn["xi2"], fn["rates"]
    tau, C, B = _radau()
    interval = _interval_function(fn, C, B, o)
    prog = SparseProgram(n)
    reach2 = o.reach * o.reach
    prev_end = None  # (x, cf, s0) at the end of the previous section
    first_start = None
    durations = []
    for spec, (duration, default_mesh, s_v, lays) in zip(sections, layout):
        kg = max(spec.pieces, key=lambda p: p.length).coefficients[0]
        b_guess = -0.5 * o.reach if kg > 0 else 0.5 * o.reach
        s_start = 0.0
        x_prev_piece = None
        for j, (piece, lay) in enumerate(zip(spec.pieces, lays)):
            cf = ca.DM(list(piece.coefficients))
            N = lay.N
            X = prog.view(lay.X, 6, N + 1)
            g0, g1 = default_mesh[j][0], default_mesh[j][-1]
            prog.linear(prog.x[lay.T], 1e-6 * duration, np.inf)
            prog.x0[lay.T] = g1 - g0
            tg = g0 + lay.frac * (g1 - g0)
            sg, vg = s_v(tg)
            kap = np.array([float(_kappa(piece.coefficients, s, s_start)) for s in sg])
            p1g = (o.I + o.m * b_guess**2) * kap * vg - o.m * b_guess * vg
            p2g = (o.M + o.m) * vg - o.m * b_guess * kap * vg
            Xg = np.vstack([p1g, p2g, np.zeros_like(tg), np.full_like(tg, b_guess), sg, np.zeros_like(tg)])
            prog.x0[lay.X:lay.Xc] = Xg.ravel(order="F")
            prog.x0[lay.Xc:lay.W] = np.repeat(Xg[:, 1:], _DEGREE - 1, axis=1).ravel(order="F")
            if x_prev_piece is not None:
                prog.linear(X[:, 0] - x_prev_piece)
            index, scale = lay.interval_index()
            tc = g0 + (lay.frac[:-1, None] + np.diff(lay.frac)[:, None] * tau[None, 1:]) * (g1 - g0)
            prog.mapped(interval, index, scale, (cf, s_start), ((0.0, 0.0), "cost") + _path_bounds(o, tc.T, duration))
            if j == 0:
                prog.linear(X[4, 0])
                prog.constrain(xi2f(X[:, 0], 0.0, cf, s_start))
                prog.constrain(X[2, 0] ** 2 + X[3, 0] ** 2, -np.inf, reach2)
                start = (X[:, 0], cf, s_start)
                if prev_end is None and o.start_position is not None:
                    prog.linear(X[2:4, 0] - ca.DM(list(o.start_position)))
                if prev_end is None and o.start_rates is not None:
                    prog.constrain(ratesf(X[:, 0], 0.0, cf, s_start) - ca.DM(list(o.start_rates)))
            x_prev_piece = X[:, N]
            s_start += piece.length
            prog.linear(X[4, N] - s_start)  # the join (or the section's end) where the piece ends
            last_cf = cf
        x_end = x_prev_piece
        s_last = s_start - spec.pieces[-1].length
        prog.constrain(xi2f(x_end, 0.0, last_cf, s_last))
        Ts = sum(prog.x[lay.T] for lay in lays)
        durations.append(Ts)
        if o.objective == "effort":
            prog.linear(Ts - duration)
        end = (x_end, last_cf, s_last)
        if prev_end is not None:
            _link(prog, prev_end, start, spec.turn, ratesf, o)
        else:
            first_start = start
        prev_end = end
    if o.end_position is not None and prev_end is not None:
        prog.linear(prev_end[0][2:4] - ca.DM(list(o.end_position)))
    if o.closing_turn is not None and first_start is not None:
        _link(prog, prev_end, first_start, o.closing_turn, ratesf, o, mirror=o.closing_mirror)
    if o.objective == "time":
        prog.minimize(sum(durations))
    if guess is not None:
        _set_guess(prog, layout, guess)
    # IPOPT's barrier: adaptive updates take half the iterations of the monotone default on one
    # section; the linked program of a curve does better monotone from mu = 0.1 (245 against 361)
    # MUMPS keeps its automatic ordering: AMD factorised the change double three's linked program in
    # 33 ms an iteration against 50 ms, but changed IPOPT's path on every figure, and the plans it
    # found were worse where it mattered (the paragraph double three peaked at 187 m/s^2 against 46;
    # the circle eight's warm start took 284 iterations, both programs 240 before).
    allowed = o.iterations_for(n) if max_work is None else min(o.iterations_for(n), iterations_within(max_work, n))
    res = prog.solve({"print_time": False, "error_on_fail": False, "ipopt.print_level": o.print_level,
                      "ipopt.sb": "yes", "ipopt.mu_strategy": o.barrier, "ipopt.mu_init": o.mu_init,
                      "ipopt.max_iter": allowed, "ipopt.tol": o.tol}, o.give_up)
    ok, status = res.success, res.status
    message = status.replace("_", " ").lower()
    if status == "Given_Up":
        message = (f"given up after {res.iterations} iterations: the constraints were never met within "
                   f"{o.give_up.violation:.3g} (at best {res.stats['least_violation']:.3g})")
    elif status == "Stalled":
        message = (f"stalled after {res.iterations} iterations: the constraints met within {o.give_up.feasible:.3g} "
                   f"over the last {o.give_up.window}, the objective falling by less than "
                   f"{o.give_up.decrease:.3g} of itself")
    if not ok and status in _STALLED:
        # A feasible point where IPOPT could not prove optimality (one-foot eight: the constraints
        # met to 5e-13, the step computation failing on degenerate multipliers) is a plan: the
        # exact finish and the certified reach do not rely on its optimality.
        inf_pr = res.stats.get("iterations", {}).get("inf_pr", [math.inf])
        if inf_pr and inf_pr[-1] <= _FEASIBLE:
            ok = True
            message = f"feasible, optimality not proven ({message})"
    times, states, controls = [], [], []
    for _duration, _mesh_k, _s_v, lays in layout:
        t0 = 0.0
        ts, xs, ws = [], [], []
        for lay in lays:
            Tv = float(res.x[lay.T])
            t = t0 + Tv * lay.frac
            Xv = res.x[lay.X:lay.Xc].reshape(6, lay.N + 1, order="F")
            ts.append(t if not ts else t[1:])
            xs.append(Xv if not xs else Xv[:, 1:])
            ws.append(res.x[lay.W:lay.end].copy())
            t0 += Tv
        times.append(np.concatenate(ts))
        states.append(np.hstack(xs))
        controls.append(np.concatenate(ws))
    return ProgramSolution(success=ok, status=status, message=message,
                           times=tuple(times), states=tuple(states), controls=tuple(controls),
                           meshes=tuple(tuple(lay.nodes for lay in lays) for *_, lays in layout),
                           objective=res.objective, iterations=res.iterations, unknowns=n, allowed=allowed,
                           stats={k: res.stats[k] for k in ("t_wall_total",) if k in res.stats})


def _path_bounds(o: ProgramOptions, tc: np.ndarray, duration: float) -> tuple[tuple[np.ndarray, np.ndarray], ...]:
    """Bounds of the path rows of :func:`_interval_function` over a piece, at collocation times ``tc`` (degree x N).

    The blade keeps moving between the rests: a speed that only touches zero (the blade waiting
    at a rest while the mass moves, seen on the counter and the bracket) comes out slightly
    negative in the exact motion, a stall. The floor rises from the rests to ``min_speed`` (2 %
    of the glide) over a tenth of the section, at the collocation points' guessed times.
    """
    ramp = np.minimum(1.0, np.minimum(tc, duration - tc) / (0.1 * duration))
    out = [(np.maximum(0.0, o.min_speed * ramp), o.top_speed), (-np.inf, o.reach * o.reach)]
    for lo, hi, on in ((o.singular_clearance**2, np.inf, o.singular_clearance > 0.0),
                       (-np.inf, (o.max_accel or 0.0) ** 2, o.max_accel is not None),
                       (-np.inf, (o.max_rate or 0.0) ** 2, o.max_rate is not None)):
        if on:
            out.append((lo, hi))
    return tuple(out)


def _interval_function(fn, C, B, o) -> ca.Function:
    """One collocation interval as a flat SX function, mapped over a piece's intervals.

    Inputs ``(z, coefficients, s0)`` with ``z = (x_k, x_c (6 * degree), w, h)``; outputs the
    collocation defects, the interval's share of the objective and the path quantities at the
    collocation points (rows: speed ``xi2``, ``a^2 + b^2``, then as asked the squared distance
    from the singular point, the squared acceleration (at the interval's start too) and the
    squared rates). One function
    mapped over the mesh keeps CasADi's setup small, and its Hessian is derived once
    (:mod:`skatetrace.planning.nlp`).
    """
    xi2f, ratesf = fn["xi2"], fn["rates"]
    f = fn["f"]
    z = ca.SX.sym("z", 8 + 6 * _DEGREE)
    xk, xc, w, h = z[0:6], z[6:6 + 6 * _DEGREE], z[6 + 6 * _DEGREE], z[7 + 6 * _DEGREE]
    cf = ca.SX.sym("cf", 4)
    s0 = ca.SX.sym("s0")
    xs = [xk] + [xc[6 * r:6 * r + 6] for r in range(_DEGREE)]
    defects, quad = [], 0
    speed, reach, sing, rate = [], [], [], []
    # The mass's acceleration from the collocation polynomial of its velocity (differentiated like
    # the states'), not from the chain rule through the dynamics: a far smaller expression for
    # IPOPT's Hessian, and the same to the mesh's accuracy (the mesh is refined against it).
    vels = [fn["velocity"](x, w, cf, s0) for x in xs]

    def accel(r):
        v_r, xi1_r = vels[r]
        vdot = sum(C[q, r] * vels[q][0] for q in range(_DEGREE + 1)) / h
        return ca.vertcat(vdot[0] - xi1_r * v_r[1], vdot[1] + xi1_r * v_r[0])

    # The acceleration jumps at a node (there w changes): its limit from the right, at the
    # interval's start, is bounded too. Bounded only at the collocation points (the limit from
    # the left at the end), the exact motion of a least-time arc under max_accel 20 peaked at
    # 21.2 at a node, where the bound never looked.
    acc = [ca.sumsqr(accel(0))]
    for r in range(1, _DEGREE + 1):
        xr = xs[r]
        xp = sum(C[q, r] * xs[q] for q in range(_DEGREE + 1))
        defects.append(h * f(xr, w, cf, s0) - xp)
        A = accel(r)
        if o.objective == "effort":
            quad += B[r] * h * (o.m * o.m) * ca.sumsqr(A)
        quad += 1e-6 * B[r] * h * w**2
        speed.append(xi2f(xr, w, cf, s0))
        reach.append(xr[2] ** 2 + xr[3] ** 2)
        bs = -_kappa(cf, xr[4], s0) * o.I / o.M
        sing.append(xr[2] ** 2 + (xr[3] - bs) ** 2)
        acc.append(ca.sumsqr(A))
        rate.append(ca.sumsqr(ratesf(xr, w, cf, s0)))
    paths = [speed, reach] + [rows for rows, on in ((sing, o.singular_clearance > 0.0), (acc, o.max_accel is not None),
                                                    (rate, o.max_rate is not None)) if on]
    return ca.Function("interval", [z, cf, s0], [ca.vertcat(*defects), quad] + [ca.vertcat(*rows) for rows in paths])


def _link(prog: SparseProgram, end, start, turn, ratesf, o, mirror: bool = False) -> None:
    """Position (and velocity) of the mass on the ice continuous from ``end`` to ``start``, or its jump penalised.

    With ``mirror``, to the mirror image of ``start`` (its ``b`` and ``bdot`` reversed).
    """
    x_end, cf_e, s_e = end
    x_start, cf_s, s_s = start
    flip = ca.DM([1.0, -1.0]) if mirror else ca.DM([1.0, 1.0])
    prog.linear(flip * x_start[2:4] - _rot(turn, x_end[2:4]))
    v_end = _rot(turn, ratesf(x_end, 0.0, cf_e, s_e))
    v_start = flip * ratesf(x_start, 0.0, cf_s, s_s)
    if o.continuous_velocity:
        prog.constrain(v_start - v_end)
    else:
        prog.minimize((o.m * o.m) * ca.sumsqr(v_start - v_end) / o.impulse_time)


def _set_guess(prog: SparseProgram, layout, guess: ProgramSolution) -> None:
    """Start from a solution of the same program (e.g. at another reach), on the same mesh.

    The states at the collocation points are interpolated linearly between the nodes. (Copies
    of the next node, as before, left the school three's linked program infeasible by 7.6 at its
    start, and it took 140 iterations to find its way back, against 27. IPOPT's own states there,
    kept, took 24, but sent a single section re-solved at the default barrier parameter 116
    iterations away from where it started, against 11: at an optimum the reach is active at the
    collocation points, and the barrier pushes off it.)
    """
    tau = _radau()[0][1:]
    for (*_, lays), times, X, W in zip(layout, guess.times, guess.states, guess.controls):
        i = 0
        for lay in lays:
            N = lay.N
            prog.x0[lay.T] = times[i + N] - times[i]
            prog.x0[lay.X:lay.Xc] = X[:, i:i + N + 1].ravel(order="F")
            prog.x0[lay.W:lay.end] = W[i:i + N]
            lo, hi = X[:, i:i + N], X[:, i + 1:i + N + 1]
            at_points = (lo[:, :, None] + (hi - lo)[:, :, None] * tau[None, None, :-1]).reshape(6, (_DEGREE - 1) * N)
            prog.x0[lay.Xc:lay.W] = at_points.ravel(order="F")
            i += N
