"""A sparse nonlinear program whose Hessian is assembled from the small Hessians of its repeated blocks.

A collocation program repeats one small function (a collocation interval) hundreds of times.
CasADi derives the Hessian of the Lagrangian of the whole expanded program symbolically, and
that derivation, repeated for every program the planner solves, cost more than IPOPT's
iterations (1.2 s of 2 s for one section, 4 s of 8 s for a curve of four). Here the Hessian of
one block is derived once, evaluated for every interval by a CasADi map, and scattered into the
program's Hessian by a constant sparse matrix; only the few other terms (boundary conditions,
links between sections) are differentiated as a whole. IPOPT receives it as ``hess_lag``.

Unknowns are one vector :attr:`SparseProgram.x`; a block's local unknowns are entries of it,
each times a constant (a collocation interval's length is a piece's duration times a fraction).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import casadi as ca
import numpy as np
import scipy.sparse as sps

__all__ = ["SparseProgram", "ProgramResult"]


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
class _Blocks:
    """One mapped block: the Hessian of its local Lagrangian and where its unknowns and rows sit."""

    hessian: ca.Function
    pattern: tuple  # (rows, columns) of the local Hessian's nonzeros, in the order of its output
    index: np.ndarray  # (nz, N) entries of x
    scale: np.ndarray  # (nz, N)
    params: tuple
    rows: tuple  # per constrained output: (rows_out, N) constraint rows, or None for the cost output


class SparseProgram:
    """Unknowns, constraints and objective of one program, with IPOPT and an assembled Hessian.

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
        self._g: list = []
        self._lbg: list[np.ndarray] = []
        self._ubg: list[np.ndarray] = []
        self._ng = 0
        self._f_blocks = 0
        self._f_rest = 0
        self._g_rest: list = []
        self._rest_rows: list[np.ndarray] = []
        self._blocks: list[_Blocks] = []

    def view(self, start: int, rows: int, cols: int = 1) -> ca.SX:
        """The unknowns ``x[start:start + rows * cols]`` as a ``rows x cols`` matrix (column-major)."""
        return ca.reshape(self.x[start:start + rows * cols], rows, cols)

    def _add_rows(self, expr, lb, ub) -> np.ndarray:
        expr = ca.vec(expr)
        k = expr.numel()
        self._g.append(expr)
        self._lbg.append(np.broadcast_to(np.asarray(lb, dtype=float), (k,)).copy())
        self._ubg.append(np.broadcast_to(np.asarray(ub, dtype=float), (k,)).copy())
        rows = np.arange(self._ng, self._ng + k)
        self._ng += k
        return rows

    def constrain(self, expr, lb=0.0, ub=None) -> None:
        """``lb <= expr <= ub`` (``ub`` defaults to ``lb``: an equality), ``expr`` any expression of :attr:`x`."""
        ub = lb if ub is None else ub
        rows = self._add_rows(expr, lb, ub)
        self._g_rest.append(ca.vec(expr))
        self._rest_rows.append(rows)

    def linear(self, expr, lb=0.0, ub=None) -> None:
        """A constraint known to be linear in :attr:`x` (it adds nothing to the Hessian)."""
        self._add_rows(expr, lb, ub if ub is not None else lb)

    def minimize(self, expr) -> None:
        """Add ``expr`` (an expression of :attr:`x`) to the objective."""
        self._f_rest = self._f_rest + expr

    def mapped(self, fn: ca.Function, index: np.ndarray, scale: np.ndarray, params: tuple, kinds: tuple) -> list:
        """``fn`` over ``N`` blocks: its first input the local unknowns, the rest ``params``.

        ``index`` and ``scale`` (``nz x N``) say that local unknown ``i`` of block ``k`` is
        ``scale[i, k] * x[index[i, k]]``; ``params`` are constants with one column, or ``N``.
        ``kinds`` gives per output of ``fn``: ``"cost"`` (summed into the objective) or
        ``(lb, ub)`` (bounds of every row, scalars or arrays of the output's ``rows x N``).
        Returns the outputs over all blocks.
        """
        index = np.asarray(index, dtype=np.int64)
        scale = np.asarray(scale, dtype=float)
        nz, N = index.shape
        z = ca.reshape(self.x[index.ravel(order="F").tolist()], nz, N) * ca.DM(scale)
        outs = fn.map(N)(z, *params)
        outs = outs if isinstance(outs, (list, tuple)) else [outs]
        rows = []
        for out, kind in zip(outs, kinds):
            if kind == "cost":
                self._f_blocks = self._f_blocks + ca.sum2(ca.sum1(out))
                rows.append(None)
            else:
                lb, ub = kind
                r = self._add_rows(out, np.asarray(lb, dtype=float).ravel(order="F") if np.ndim(lb) else lb,
                                   np.asarray(ub, dtype=float).ravel(order="F") if np.ndim(ub) else ub)
                rows.append(r.reshape(out.shape, order="F"))
        self._blocks.append(_Blocks(*_local_hessian(fn, kinds), index, scale, tuple(params), tuple(rows)))
        return list(outs)

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
        nz, N = blk.index.shape
        z = ca.reshape(xm[blk.index.ravel(order="F").tolist()], nz, N) * ca.DM(blk.scale)
        lams = [ca.reshape(lam_g[r.ravel(order="F").tolist()], r.shape[0], N) for r in blk.rows if r is not None]
        local = blk.hessian.map(N)(z, *blk.params, lam_f, *lams)  # (nnz_local, N)
        li, lj = blk.pattern
        # local entry (i, j) of block k lands at (index[i, k], index[j, k]), scaled; upper triangle only
        r, c = blk.index[li, :], blk.index[lj, :]
        keep = r <= c
        src = (np.arange(li.size)[:, None] + li.size * np.arange(N)[None, :])[keep]
        key = c[keep] * self.n + r[keep]  # column-major position, CasADi's order of nonzeros
        keys = np.unique(key)
        weights = (blk.scale[li, :] * blk.scale[lj, :])[keep]
        scatter = sps.csc_matrix((weights, (np.searchsorted(keys, key), src)), shape=(keys.size, li.size * N))
        values = ca.mtimes(ca.DM(scatter), ca.vec(local))
        sparsity = ca.Sparsity.triplet(self.n, self.n, (keys % self.n).tolist(), (keys // self.n).tolist())
        return ca.MX(sparsity, values)

    def solve(self, options: dict) -> ProgramResult:
        """Solve with IPOPT (``options`` are nlpsol options, e.g. ``ipopt.tol``). Never raises for a failed solve."""
        g = ca.vertcat(*self._g) if self._g else ca.SX(0, 1)
        nlp = {"x": self.x, "f": self._f_blocks + self._f_rest, "g": g}
        opts = dict(options)
        opts.setdefault("error_on_fail", False)
        opts["hess_lag"] = self._hessian()
        solver = ca.nlpsol("plan", "ipopt", nlp, opts)
        lbg = np.concatenate(self._lbg) if self._lbg else np.zeros(0)
        ubg = np.concatenate(self._ubg) if self._ubg else np.zeros(0)
        sol = solver(x0=self.x0, lbx=self.lbx, ubx=self.ubx, lbg=lbg, ubg=ubg)
        stats = solver.stats()
        return ProgramResult(success=bool(stats.get("success", False)), status=str(stats.get("return_status", "unknown")),
                             x=np.asarray(sol["x"]).ravel(), objective=float(sol["f"]),
                             iterations=int(stats.get("iter_count", 0)), stats=stats)


def _local_hessian(fn: ca.Function, kinds: tuple) -> tuple[ca.Function, tuple[np.ndarray, np.ndarray]]:
    """The Hessian of one block's Lagrangian in its local unknowns (the column of its nonzeros), and their pattern."""
    z = ca.SX.sym("z", fn.size1_in(0))
    params = [ca.SX.sym(f"p{i}", fn.sparsity_in(i + 1)) for i in range(fn.n_in() - 1)]
    outs = fn(z, *params)
    outs = outs if isinstance(outs, (list, tuple)) else [outs]
    sigma = ca.SX.sym("sigma")
    lams, lag = [], 0
    for out, kind in zip(outs, kinds):
        if kind == "cost":
            lag = lag + sigma * ca.sum1(ca.vec(out))
        else:
            lam = ca.SX.sym("lam", out.numel())
            lams.append(lam)
            lag = lag + ca.dot(lam, ca.vec(out))
    H = ca.hessian(lag, z)[0]
    li, lj = H.sparsity().get_triplet()
    fh = ca.Function("block_hessian", [z, *params, sigma, *lams], [ca.vertcat(*H.nonzeros()) if H.nnz() else ca.SX(0, 1)])
    return fh, (np.asarray(li, dtype=np.int64), np.asarray(lj, dtype=np.int64))


def _is_zero(expr) -> bool:
    return isinstance(expr, (int, float)) and expr == 0 or (hasattr(expr, "is_zero") and expr.is_zero())
