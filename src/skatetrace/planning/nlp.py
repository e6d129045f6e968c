"""A sparse nonlinear program whose derivatives are assembled from the small derivatives of its repeated blocks.

A collocation program repeats one small function (a collocation interval) hundreds of times.
CasADi derives the derivatives of the whole expanded program symbolically, and that
derivation, repeated for every program the planner solves, cost more than IPOPT's iterations:
the Hessian of the Lagrangian 1.2 s of 2 s for one section, 4 s of 8 s for a curve of four;
once the Hessian was assembled, the constraints' Jacobian and the objective's gradient still
1.3 s of the 2 s that building the school rocker's linked program took. Here the derivatives of
one block are derived once, evaluated for every interval by a CasADi map, and placed in the
program's (by a constant sparse matrix where blocks share an unknown); only the few other terms
(boundary conditions, links between sections) are differentiated as a whole. IPOPT receives
them as ``hess_lag``, ``jac_g`` and ``grad_f``.

Unknowns are one vector :attr:`SparseProgram.x`; a block's local unknowns are entries of it,
each times a constant (a collocation interval's length is a piece's duration times a fraction).
"""

from __future__ import annotations

import collections
from dataclasses import dataclass, field

import casadi as ca
import numpy as np
import scipy.sparse as sps

from ..processes import recording_interrupts
from .blas import one_thread
from .heap import padded
from .native import native

__all__ = ["SparseProgram", "ProgramResult", "GiveUp"]


@dataclass(frozen=True, slots=True)
class GiveUp:
    """When a solve is given up as going nowhere: once IPOPT has made ``iterations`` iterations
    and the least constraint violation it has met (the largest ``lbg - g`` or ``g - ubg``) is
    still above ``violation``.

    With ``window`` > 0 a solve that has made ``iterations`` iterations also ends, as stalled,
    where its constraints were met within ``feasible`` at each of the last ``window + 1`` iterates
    while its objective fell by less than ``decrease`` of itself over them: IPOPT crawling along a
    feasible valley, its barrier at the least, with steps too short to converge before its last
    iteration. Its last iterate is kept (status ``"Stalled"``), for the caller to judge.

    Checked at every iteration (restoration phases included) by an iteration callback that only
    reads the iterate: a solve that is not ended takes the same path, to the bit.
    """

    iterations: int
    violation: float
    window: int = 0
    decrease: float = 0.0
    feasible: float = 0.0

    def __post_init__(self):
        for name, least in (("iterations", 1), ("window", 0)):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or value < least:
                raise ValueError(f"GiveUp.{name} must be a whole number >= {least}, got {value!r}")
        for name in ("violation", "decrease", "feasible"):
            if not getattr(self, name) >= 0.0:  # also refuses NaN
                raise ValueError(f"GiveUp.{name} must be >= 0, got {getattr(self, name)!r}")


class _Watch(ca.Callback):
    """IPOPT's iteration callback for a :class:`GiveUp`: counts the iterations, keeps the least
    constraint violation (until it is within the rule's), and asks IPOPT to stop once the rule says so."""

    def __init__(self, rule: GiveUp, nx: int, lbg: np.ndarray, ubg: np.ndarray):
        ca.Callback.__init__(self)
        self.rule, self.nx, self.lbg, self.ubg = rule, nx, lbg, ubg
        self.count, self.least, self.stopped, self.stalled = 0, np.inf, False, False
        self.recent: collections.deque = collections.deque(maxlen=rule.window + 1)  # (objective, violation)
        self.construct("give_up_watch", {})

    def get_n_in(self):
        return ca.nlpsol_n_out()

    def get_n_out(self):
        return 1

    def get_name_in(self, i):
        return ca.nlpsol_out(i)

    def get_name_out(self, i):
        return "stop"

    def get_sparsity_in(self, i):
        name = ca.nlpsol_out(i)
        size = {"f": 1, "x": self.nx, "lam_x": self.nx, "g": self.lbg.size, "lam_g": self.lbg.size}.get(name, 0)
        return ca.Sparsity.dense(size) if size else ca.Sparsity(0, 0)

    def eval(self, arg):
        self.count += 1
        rule = self.rule
        if self.least > rule.violation or rule.window:  # else the rule can no longer end the solve
            worst = 0.0
            if self.lbg.size:
                g = np.asarray(arg[2]).ravel()
                worst = max(float(np.max(self.lbg - g)), float(np.max(g - self.ubg)), 0.0)
            self.least = min(self.least, worst)
            self.stopped = self.count >= rule.iterations and self.least > rule.violation
            if rule.window:
                self.recent.append((float(arg[1]), worst))
                first, last = self.recent[0][0], self.recent[-1][0]
                self.stalled = (not self.stopped and self.count >= rule.iterations
                                and len(self.recent) == self.recent.maxlen
                                and max(v for _, v in self.recent) <= rule.feasible
                                and first - last < rule.decrease * abs(last))
        return [1 if self.stopped or self.stalled else 0]


@dataclass(frozen=True, slots=True)
class ProgramResult:
    """IPOPT's answer: the unknowns, the objective, IPOPT's return status and statistics."""

    success: bool
    status: str
    x: np.ndarray
    objective: float
    iterations: int
    stats: dict = field(default_factory=dict)


@dataclass(frozen=True, slots=True)
class _Local:
    """The derivatives of one block function in its local unknowns, each a function of its nonzeros, and their patterns.

    ``jacobian``: of the constrained outputs stacked (pattern: rows of the stack, local unknowns);
    ``gradient``: of the summed cost outputs (pattern: local unknowns); ``hessian``: of the
    Lagrangian ``sigma * cost + lam . constrained`` (pattern: local unknowns, both ways).
    """

    jacobian: ca.Function
    jac_pattern: tuple[np.ndarray, np.ndarray]
    gradient: ca.Function
    grad_pattern: np.ndarray
    hessian: ca.Function
    pattern: tuple[np.ndarray, np.ndarray]


@dataclass(frozen=True, slots=True)
class _Blocks:
    """One mapped block: its local derivatives and where its unknowns and rows sit."""

    local: _Local
    fn: ca.Function
    index: np.ndarray  # (nz, N) entries of x
    scale: np.ndarray  # (nz, N)
    params: tuple
    rows: tuple  # per constrained output: (rows_out, N) constraint rows, or None for the cost output

    @property
    def stacked_rows(self) -> np.ndarray:
        """``(sum rows_out, N)``: the constraint row of each row of the constrained outputs stacked."""
        rows = [r for r in self.rows if r is not None]
        return np.vstack(rows) if rows else np.zeros((0, self.index.shape[1]), dtype=np.int64)


class SparseProgram:
    """Unknowns, constraints and objective of one program, with IPOPT and assembled derivatives.

    Parameters
    ----------
    n : int
        Number of unknowns. :attr:`x` is their symbol; :attr:`x0`, :attr:`lbx` and :attr:`ubx`
        (filled by the caller) are the start and the bounds.
    """

    def __init__(self, n: int):
        self.n = int(n)
        self.x = ca.SX.sym("x", self.n)
        self.x0 = np.zeros(self.n)
        self.lbx = np.full(self.n, -np.inf)
        self.ubx = np.full(self.n, np.inf)
        self._lbg: list[np.ndarray] = []
        self._ubg: list[np.ndarray] = []
        self._ng = 0
        self._f_rest = 0
        self._g_rest: list = []  # the nonlinear rows outside the blocks (for the Hessian)
        self._rest_rows: list[np.ndarray] = []
        self._g_other: list = []  # every row outside the blocks
        self._other_rows: list[np.ndarray] = []
        self._blocks: list[_Blocks] = []
        self._derived: dict = {}  # id(fn), output kinds -> _Local: one derivation per block function (kept by its blocks)

    def view(self, start: int, rows: int, cols: int = 1) -> ca.SX:
        """The unknowns ``x[start:start + rows * cols]`` as a ``rows x cols`` matrix (column-major)."""
        return ca.reshape(self.x[start:start + rows * cols], rows, cols)

    def _reserve(self, k: int, lb, ub) -> np.ndarray:
        """The next ``k`` constraint rows, with their bounds."""
        self._lbg.append(np.broadcast_to(np.asarray(lb, dtype=float), (k,)).copy())
        self._ubg.append(np.broadcast_to(np.asarray(ub, dtype=float), (k,)).copy())
        rows = np.arange(self._ng, self._ng + k)
        self._ng += k
        return rows

    def _other(self, expr, lb, ub) -> np.ndarray:
        expr = ca.vec(expr)
        rows = self._reserve(expr.numel(), lb, ub)
        self._g_other.append(expr)
        self._other_rows.append(rows)
        return rows

    def constrain(self, expr, lb=0.0, ub=None) -> None:
        """``lb <= expr <= ub`` (``ub`` defaults to ``lb``: an equality), ``expr`` any expression of :attr:`x`."""
        rows = self._other(expr, lb, lb if ub is None else ub)
        self._g_rest.append(ca.vec(expr))
        self._rest_rows.append(rows)

    def linear(self, expr, lb=0.0, ub=None) -> None:
        """A constraint known to be linear in :attr:`x` (it adds nothing to the Hessian)."""
        self._other(expr, lb, lb if ub is None else ub)

    def minimize(self, expr) -> None:
        """Add ``expr`` (an expression of :attr:`x`) to the objective."""
        self._f_rest = self._f_rest + expr

    def mapped(self, fn: ca.Function, index: np.ndarray, scale: np.ndarray, params: tuple, kinds: tuple) -> None:
        """``fn`` over ``N`` blocks: its first input the local unknowns, the rest ``params``.

        ``index`` and ``scale`` (``nz x N``) say that local unknown ``i`` of block ``k`` is
        ``scale[i, k] * x[index[i, k]]``; ``params`` are constants with one column, or ``N``.
        ``kinds`` gives per output of ``fn``: ``"cost"`` (summed into the objective) or
        ``(lb, ub)`` (bounds of every row, scalars or arrays of the output's ``rows x N``).
        The blocks are never expanded into one expression: IPOPT evaluates ``fn`` over them
        (a CasADi map), and their derivatives are derived on one block.
        """
        index = np.asarray(index, dtype=np.int64)
        scale = np.asarray(scale, dtype=float)
        N = index.shape[1]
        rows = []
        for i, kind in enumerate(kinds):
            if kind == "cost":
                rows.append(None)
                continue
            lb, ub = kind
            shape = (fn.size1_out(i) * fn.size2_out(i), N)
            r = self._reserve(shape[0] * N, np.asarray(lb, dtype=float).ravel(order="F") if np.ndim(lb) else lb,
                              np.asarray(ub, dtype=float).ravel(order="F") if np.ndim(ub) else ub)
            rows.append(r.reshape(shape, order="F"))
        shape = tuple("cost" if kind == "cost" else "rows" for kind in kinds)
        key = (id(fn), shape)
        if key not in self._derived:
            self._derived[key] = _local_derivatives(fn, shape)
        self._blocks.append(_Blocks(self._derived[key], fn, index, scale, tuple(params), tuple(rows)))

    def _oracle(self, xm):
        """The objective and the constraints (in row order) on the unknowns ``xm``: the blocks mapped, never expanded."""
        f = ca.Function("f_rest", [self.x], [self._f_rest])(xm) if not _is_zero(self._f_rest) else 0
        parts, rows = [], []
        for blk in self._blocks:
            outs = self._local_values(blk, xm, blk.fn)
            outs = outs if isinstance(outs, (list, tuple)) else [outs]
            for out, r in zip(outs, blk.rows):
                if r is None:
                    f = f + ca.sum2(ca.sum1(out))
                else:
                    parts.append(ca.vec(out))
                    rows.append(r.ravel(order="F"))
        if self._other_rows:
            parts.append(ca.Function("other", [self.x], [ca.vertcat(*self._g_other)])(xm))
            rows.append(np.concatenate(self._other_rows))
        if not parts:
            return ca.MX(f), ca.MX(0, 1)
        order = np.argsort(np.concatenate(rows), kind="stable")
        return ca.MX(f), ca.vertcat(*parts)[order.tolist()]

    def expanded(self) -> tuple[ca.SX, ca.SX]:
        """The objective and the constraints as expressions of :attr:`x`, the blocks expanded (for checks)."""
        xm = ca.MX.sym("x", self.n)
        f, g = self._oracle(xm)
        expand = ca.Function("oracle", [xm], [f, g]).expand()
        return tuple(expand(self.x))

    def _local_values(self, blk: _Blocks, xm, fn: ca.Function, *extra):
        """``fn`` (the block function or a local derivative of it) over every block of ``blk``, on the unknowns ``xm``."""
        nz, N = blk.index.shape
        z = ca.reshape(xm[blk.index.ravel(order="F").tolist()], nz, N) * ca.DM(blk.scale)
        return fn.map(N)(z, *blk.params, *extra)

    def _functions(self) -> tuple[dict, dict]:
        """The program for ``nlpsol`` (on an MX vector of unknowns) and its ``hess_lag``, ``jac_g`` and ``grad_f``.

        The objective and the constraints are built once (:meth:`_oracle`) and shared by the
        program and the functions that return them beside their derivatives.
        """
        xm = ca.MX.sym("x", self.n)
        f, g = self._oracle(xm)
        return {"x": xm, "f": f, "g": g}, {"hess_lag": self._hessian(), "jac_g": self._jacobian(xm, g),
                                           "grad_f": self._gradient(xm, f)}

    def _jacobian(self, xm, g) -> ca.Function:
        """``jac_g`` for IPOPT: the constraints ``g`` on ``xm`` and their Jacobian, the blocks' placed entry by entry."""
        values, rows, cols = [], [], []
        for blk in self._blocks:
            li, lj = blk.local.jac_pattern
            if li.size == 0:
                continue
            local = self._local_values(blk, xm, blk.local.jacobian)  # (nnz, N)
            # local entry (i, j) of block k is d row[i, k] / d x[index[j, k]], times the unknown's scale
            values.append(ca.vec(local) * ca.DM(blk.scale[lj, :].ravel(order="F")))
            rows.append(blk.stacked_rows[li, :].ravel(order="F"))
            cols.append(blk.index[lj, :].ravel(order="F"))
        if self._other_rows:
            other = ca.vertcat(*self._g_other)
            J = ca.jacobian(other, self.x)
            ri, ci = J.sparsity().get_triplet()
            if ri:
                values.append(ca.Function("other", [self.x], [ca.vertcat(*J.nonzeros())])(xm))
                rows.append(np.concatenate(self._other_rows)[np.asarray(ri, dtype=np.int64)])
                cols.append(np.asarray(ci, dtype=np.int64))
        if not values:
            return ca.Function("nlp_jac_g", [xm, ca.MX.sym("p", 0)], [g, ca.MX(self._ng, self.n)],
                               ["x", "p"], ["g", "jac_g_x"])
        r, c = np.concatenate(rows), np.concatenate(cols)
        key = c * max(self._ng, 1) + r  # column-major position, CasADi's order of nonzeros
        order = np.argsort(key, kind="stable")
        if np.any(np.diff(key[order]) == 0):
            raise ValueError("two blocks claim the same entry of the Jacobian: a row belongs to one block")
        sparsity = ca.Sparsity.triplet(self._ng, self.n, r[order].tolist(), c[order].tolist())
        J = ca.MX(sparsity, ca.vertcat(*values)[order.tolist()])
        return ca.Function("nlp_jac_g", [xm, ca.MX.sym("p", 0)], [g, J], ["x", "p"], ["g", "jac_g_x"])

    def _gradient(self, xm, f) -> ca.Function:
        """``grad_f`` for IPOPT: the objective ``f`` on ``xm`` and its gradient, the blocks' summed where they share one."""
        grad = ca.MX(self.n, 1)
        for blk in self._blocks:
            lj = blk.local.grad_pattern
            if lj.size == 0:
                continue
            N = blk.index.shape[1]
            local = self._local_values(blk, xm, blk.local.gradient)
            src = np.arange(lj.size * N)
            weights = blk.scale[lj, :].ravel(order="F")
            scatter = sps.csc_matrix((weights, (blk.index[lj, :].ravel(order="F"), src)), shape=(self.n, lj.size * N))
            grad = grad + ca.mtimes(_dm(scatter), ca.vec(local))
        if not _is_zero(self._f_rest):
            grad = grad + ca.Function("grad_rest", [self.x], [ca.gradient(self._f_rest, self.x)])(xm)
        return ca.Function("nlp_grad_f", [xm, ca.MX.sym("p", 0)], [f, ca.densify(grad)], ["x", "p"], ["f", "grad_f_x"])

    def _hessian(self) -> ca.Function:
        """``hess_lag`` for IPOPT: the upper triangle of the Lagrangian's Hessian."""
        xm = ca.MX.sym("x", self.n)
        lam_f = ca.MX.sym("lam_f")
        lam_g = ca.MX.sym("lam_g", self._ng)
        H = ca.MX(self.n, self.n)
        for blk in self._blocks:
            H = H + self._assembled(blk, xm, lam_f, lam_g)
        if self._rest_rows or not _is_zero(self._f_rest):
            lam = ca.SX.sym("lam", self._ng)
            sig = ca.SX.sym("sigma")
            rows = np.concatenate(self._rest_rows).tolist() if self._rest_rows else []
            g_rest = ca.vertcat(*self._g_rest) if self._g_rest else ca.SX(0, 1)
            lag = sig * self._f_rest + (ca.dot(lam[rows], g_rest) if rows else 0)
            Hr = ca.triu(ca.hessian(lag, self.x)[0])
            H = H + ca.Function("rest", [self.x, sig, lam], [Hr])(xm, lam_f, lam_g)
        return ca.Function("nlp_hess_l", [xm, ca.MX.sym("p", 0), lam_f, lam_g], [H],
                           ["x", "p", "lam_f", "lam_g"], ["triu_hess_gamma_x_x"])

    def _assembled(self, blk: _Blocks, xm, lam_f, lam_g):
        """One mapped block's share of the Hessian: its local Hessians scattered into the program's."""
        N = blk.index.shape[1]
        lams = [ca.reshape(lam_g[r.ravel(order="F").tolist()], r.shape[0], N) for r in blk.rows if r is not None]
        local = self._local_values(blk, xm, blk.local.hessian, lam_f, *lams)  # (nnz_local, N)
        li, lj = blk.local.pattern
        # local entry (i, j) of block k lands at (index[i, k], index[j, k]), scaled; upper triangle only
        r, c = blk.index[li, :], blk.index[lj, :]
        keep = r <= c
        src = (np.arange(li.size)[:, None] + li.size * np.arange(N)[None, :])[keep]
        key = c[keep] * self.n + r[keep]  # column-major position, CasADi's order of nonzeros
        keys = np.unique(key)
        weights = (blk.scale[li, :] * blk.scale[lj, :])[keep]
        scatter = sps.csc_matrix((weights, (np.searchsorted(keys, key), src)), shape=(keys.size, li.size * N))
        values = ca.mtimes(_dm(scatter), ca.vec(local))
        sparsity = ca.Sparsity.triplet(self.n, self.n, (keys % self.n).tolist(), (keys // self.n).tolist())
        return ca.MX(sparsity, values)

    def solve(self, options: dict, give_up: GiveUp | None = None) -> ProgramResult:
        """Solve with IPOPT (``options`` are nlpsol options, e.g. ``ipopt.tol``). Never raises for a failed solve.

        With ``give_up``, a solve that the rule gives up ends with status ``"Given_Up"`` (not a
        success), ``stats["least_violation"]`` the least constraint violation it met; one it ends as
        stalled with status ``"Stalled"`` (not a success), its last iterate kept.
        """
        nlp, derivatives = self._functions()
        opts = dict(options)
        opts.setdefault("error_on_fail", False)
        opts.update(derivatives)
        lbg = np.concatenate(self._lbg) if self._lbg else np.zeros(0)
        ubg = np.concatenate(self._ubg) if self._ubg else np.zeros(0)
        watch = None if give_up is None else _Watch(give_up, self.n, lbg, ubg)
        if watch is not None:
            opts["iteration_callback"] = watch
        solver = ca.nlpsol("plan", "ipopt", nlp, opts)
        with recording_interrupts() as caught, one_thread(), padded():  # (see planning.blas and planning.heap)
            sol = solver(x0=self.x0, lbx=self.lbx, ubx=self.ubx, lbg=lbg, ubg=ubg)
        if caught:
            # CasADi turns Ctrl-C into a failed solve ("NonIpopt_Exception_Thrown"), and a caller
            # would carry on with the next program: the user asked to stop
            raise KeyboardInterrupt
        stats = solver.stats()
        status, success = str(stats.get("return_status", "unknown")), bool(stats.get("success", False))
        if watch is not None and watch.stopped:
            status, success = "Given_Up", False
            stats = dict(stats, least_violation=watch.least)
        elif watch is not None and watch.stalled:
            status, success = "Stalled", False
        return ProgramResult(success=success, status=status, x=np.asarray(sol["x"]).ravel(), objective=float(sol["f"]),
                             iterations=int(stats.get("iter_count", 0)), stats=stats)


def _local_derivatives(fn: ca.Function, shape: tuple) -> _Local:
    """The Jacobian, gradient and Hessian of one block in its local unknowns (``shape``: "cost" or "rows" per output)."""
    z = ca.SX.sym("z", fn.size1_in(0))
    params = [ca.SX.sym(f"p{i}", fn.sparsity_in(i + 1)) for i in range(fn.n_in() - 1)]
    outs = fn(z, *params)
    outs = outs if isinstance(outs, (list, tuple)) else [outs]
    sigma = ca.SX.sym("sigma")
    lams, rows, cost = [], [], 0
    for out, kind in zip(outs, shape):
        if kind == "cost":
            cost = cost + ca.sum1(ca.vec(out))
        else:
            lams.append(ca.SX.sym("lam", out.numel()))
            rows.append(ca.vec(out))
    stacked = ca.vertcat(*rows) if rows else ca.SX(0, 1)
    J = ca.jacobian(stacked, z)
    grad = ca.gradient(cost, z) if not _is_zero(cost) else ca.SX(z.numel(), 1)
    H = ca.hessian(sigma * cost + (ca.dot(ca.vertcat(*lams), stacked) if lams else 0), z)[0]

    def nonzeros(name, expr, args):
        triplet = expr.sparsity().get_triplet()
        out = ca.vertcat(*expr.nonzeros()) if expr.nnz() else ca.SX(0, 1)
        return ca.Function(name, args, [out]), tuple(np.asarray(t, dtype=np.int64) for t in triplet)

    fj, jac_pattern = nonzeros("block_jacobian", J, [z, *params])
    fg, (grad_rows, _cols) = nonzeros("block_gradient", grad, [z, *params])
    fh, pattern = nonzeros("block_hessian", H, [z, *params, sigma, *lams])
    return _Local(native(fj), jac_pattern, native(fg), grad_rows, native(fh), pattern)


def _dm(matrix: sps.csc_matrix) -> ca.DM:
    """``ca.DM(matrix)``, made from the compressed columns at once.

    CasADi's own conversion reads the three arrays of a SciPy matrix an entry at a time: 13 ms for
    a Hessian's scatter of a few tens of thousands of entries, several times over in a program's
    derivatives. The same arrays (duplicates summed, rows sorted) make the same matrix.
    """
    matrix = sps.csc_matrix(matrix)
    matrix.sum_duplicates()
    sparsity = ca.Sparsity(matrix.shape[0], matrix.shape[1], matrix.indptr.tolist(), matrix.indices.tolist())
    return ca.DM(sparsity, np.asarray(matrix.data, dtype=float))


def _is_zero(expr) -> bool:
    return isinstance(expr, (int, float)) and expr == 0 or (hasattr(expr, "is_zero") and expr.is_zero())
