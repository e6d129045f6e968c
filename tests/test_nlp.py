"""The sparse program of the planner: its assembled Hessian is CasADi's own, and a failed solve is data."""

import casadi as ca
import numpy as np

from skatetrace.planning.nlp import SparseProgram


def _program(N: int = 5) -> SparseProgram:
    # blocks that share an unknown (scaled differently in each, like a piece's duration in its
    # intervals), a broadcast parameter and a mapped one, a cost, equalities and bounded rows;
    # and terms outside the blocks
    rng = np.random.default_rng(0)
    prog = SparseProgram(2 * N + 1 + 3)
    z, p, q = ca.SX.sym("z", 3), ca.SX.sym("p", 2), ca.SX.sym("q", 2)
    fn = ca.Function("f", [z, p, q], [ca.vertcat(z[0] ** 2 * z[1] - p[0], ca.sin(z[2]) * z[0]),
                                      z[0] ** 4 + z[1] * z[2] * q[1], z[1] ** 3 * q[0]])
    index = np.vstack([np.arange(0, 2 * N, 2), np.arange(1, 2 * N, 2), np.full(N, 2 * N)])
    scale = np.vstack([np.ones(N), np.ones(N), np.linspace(0.1, 0.5, N)])
    prog.mapped(fn, index, scale, (ca.DM(rng.random((2, N))), ca.DM([1.5, 2.0])), ((0, 0), "cost", (-1, 1)))
    prog.constrain(prog.x[-3] ** 2 * prog.x[0] + prog.x[-1] ** 3, 1.0)
    prog.linear(prog.x[1] - prog.x[2])
    prog.minimize(prog.x[-2] ** 2 * prog.x[3])
    return prog


def test_the_assembled_hessian_is_the_lagrangians():
    prog = _program()
    g = ca.vertcat(*prog._g)
    f = prog._f_blocks + prog._f_rest
    sigma, lam = ca.SX.sym("sigma"), ca.SX.sym("lam", g.numel())
    auto = ca.Function("auto", [prog.x, sigma, lam], [ca.triu(ca.hessian(sigma * f + ca.dot(lam, g), prog.x)[0])])
    mine = prog._hessian()
    rng = np.random.default_rng(1)
    for _ in range(3):
        x, s, lg = rng.normal(size=prog.n), rng.normal(), rng.normal(size=g.numel())
        want = np.array(auto(x, s, lg))
        got = np.array(mine(x, [], s, lg))
        np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-12 * np.abs(want).max())


def test_a_solve_that_fails_comes_back_as_data():
    prog = SparseProgram(1)
    prog.constrain(prog.x[0] ** 2, -2.0, -1.0)  # no real x has a negative square
    prog.minimize(prog.x[0] ** 2)
    res = prog.solve({"print_time": False, "ipopt.print_level": 0, "ipopt.sb": "yes", "ipopt.max_iter": 50})
    assert not res.success
    assert res.status in ("Infeasible_Problem_Detected", "Maximum_Iterations_Exceeded", "Restoration_Failed")


def test_a_solve_finds_the_minimum():
    prog = _program()
    prog.x0[:] = 0.5
    res = prog.solve({"print_time": False, "ipopt.print_level": 0, "ipopt.sb": "yes"})
    assert res.success, res.status
    assert res.x.shape == (prog.n,) and np.isfinite(res.objective)
