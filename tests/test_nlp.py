"""The sparse program of the planner: its assembled derivatives are CasADi's own, and a failed solve is data."""

import casadi as ca
import numpy as np
import pytest

import scipy.sparse as sps

from skatetrace.planning.nlp import GiveUp, SparseProgram, _dm


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
    f, g = prog.expanded()
    sigma, lam = ca.SX.sym("sigma"), ca.SX.sym("lam", g.numel())
    auto = ca.Function("auto", [prog.x, sigma, lam], [ca.triu(ca.hessian(sigma * f + ca.dot(lam, g), prog.x)[0])])
    mine = prog._functions()[1]["hess_lag"]
    rng = np.random.default_rng(1)
    for _ in range(3):
        x, s, lg = rng.normal(size=prog.n), rng.normal(), rng.normal(size=g.numel())
        want = np.array(auto(x, s, lg))
        got = np.array(mine(x, [], s, lg))
        np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-12 * np.abs(want).max())


def test_a_scipy_matrix_becomes_the_dm_casadi_makes_of_it():
    # duplicates (summed), rows out of order within a column, an explicit zero and empty columns
    rows, cols = np.array([3, 0, 3, 1, 0, 2]), np.array([0, 0, 0, 2, 2, 5])
    data = np.array([1.5, -2.0, 0.25, 0.0, 7.0, 1e-300])
    a = sps.csc_matrix((data, (rows, cols)), shape=(4, 7))
    a.indices[:2] = a.indices[1::-1].copy()  # unsorted, as a matrix built by hand may be
    a.data[:2] = a.data[1::-1].copy()
    a.has_sorted_indices = False
    want = ca.DM(sps.csc_matrix(a.toarray()))
    got = _dm(a)
    assert got.sparsity().get_triplet() == ca.DM(a.tocoo().tocsc()).sparsity().get_triplet()
    np.testing.assert_array_equal(np.array(got), np.array(want))
    assert got.nnz() == 5  # (3, 0) summed, the explicit zero kept as CasADi keeps it
    big = sps.random(300, 2000, density=1e-2, format="csc", random_state=3)
    assert ca.norm_inf(_dm(big) - ca.DM(big)) == 0 and _dm(big).sparsity() == ca.DM(big).sparsity()


def test_the_program_evaluates_its_blocks_and_rows_in_order():
    # the oracle IPOPT evaluates, against the blocks evaluated one by one in numpy
    N = 5
    prog = _program(N)
    f, g = prog.expanded()
    x = np.random.default_rng(4).normal(size=prog.n)
    fx, gx = (np.array(v).ravel() for v in ca.Function("o", [prog.x], [f, g])(x))
    p = np.random.default_rng(0).random((2, N))  # the parameters _program drew
    s = np.linspace(0.1, 0.5, N)
    z0, z1, z2 = x[0:2 * N:2], x[1:2 * N:2], s * x[2 * N]
    rows = np.concatenate([np.ravel([z0 ** 2 * z1 - p[0], np.sin(z2) * z0], order="F"), z1 ** 3 * 1.5,
                           [x[-3] ** 2 * x[0] + x[-1] ** 3, x[1] - x[2]]])
    np.testing.assert_allclose(gx, rows, rtol=1e-14, atol=1e-14)
    np.testing.assert_allclose(fx, np.sum(z0 ** 4 + z1 * z2 * 2.0) + x[-2] ** 2 * x[3], rtol=1e-14)


def test_the_assembled_jacobian_and_gradient_are_casadis():
    prog = _program()
    f, g = prog.expanded()
    auto = ca.Function("auto", [prog.x], [g, ca.jacobian(g, prog.x), f, ca.gradient(f, prog.x)])
    _nlp, derivatives = prog._functions()
    jac, grad = derivatives["jac_g"], derivatives["grad_f"]
    assert jac.sparsity_out(1).nnz() == ca.jacobian(g, prog.x).nnz()  # no structural zeros added, none lost
    rng = np.random.default_rng(2)
    for _ in range(3):
        x = rng.normal(size=prog.n)
        g_want, J_want, f_want, grad_want = (np.array(v) for v in auto(x))
        g_got, J_got = (np.array(v) for v in jac(x, []))
        f_got, grad_got = (np.array(v) for v in grad(x, []))
        np.testing.assert_allclose(g_got, g_want, rtol=1e-13, atol=1e-13 * np.abs(g_want).max())
        np.testing.assert_allclose(J_got, J_want, rtol=1e-13, atol=1e-13 * np.abs(J_want).max())
        np.testing.assert_allclose(f_got, f_want, rtol=1e-13)
        np.testing.assert_allclose(grad_got, grad_want, rtol=1e-13, atol=1e-13 * np.abs(grad_want).max())


def test_a_solve_that_fails_comes_back_as_data():
    prog = SparseProgram(1)
    prog.constrain(prog.x[0] ** 2, -2.0, -1.0)  # no real x has a negative square
    prog.minimize(prog.x[0] ** 2)
    res = prog.solve({"print_time": False, "ipopt.print_level": 0, "ipopt.sb": "yes", "ipopt.max_iter": 50})
    assert not res.success
    assert res.status in ("Infeasible_Problem_Detected", "Maximum_Iterations_Exceeded", "Restoration_Failed")


def test_a_solve_finds_the_minimum_that_casadis_own_derivatives_find():
    # a program with one minimum: blocks pulled towards their parameters, held on a line and
    # inside a disc, a shared unknown scaled differently in each, and a term outside the blocks
    N = 6
    prog = SparseProgram(2 * N + 2)
    z, p, q = ca.SX.sym("z", 3), ca.SX.sym("p", 2), ca.SX.sym("q")
    fn = ca.Function("f", [z, p, q], [(z[0] - p[0]) ** 2 + (z[1] - p[1]) ** 2 + z[2] ** 2, z[0] + z[1] * z[2] - q,
                                      z[0] ** 2 + z[1] ** 2])
    index = np.vstack([np.arange(0, 2 * N, 2), np.arange(1, 2 * N, 2), np.full(N, 2 * N)])
    scale = np.vstack([np.ones(N), np.ones(N), np.linspace(0.5, 1.5, N)])
    rng = np.random.default_rng(3)
    prog.mapped(fn, index, scale, (ca.DM(rng.random((2, N))), ca.DM(0.5)), ("cost", (0, 0), (-np.inf, 0.5)))
    prog.constrain(prog.x[-1] ** 2 + prog.x[0], 1.0)
    prog.minimize((prog.x[-1] - 2.0) ** 2)
    prog.x0[:] = 0.1
    options = {"print_time": False, "ipopt.print_level": 0, "ipopt.sb": "yes", "ipopt.tol": 1e-10}
    res = prog.solve(options)
    assert res.success, res.status
    f, g = prog.expanded()
    own = ca.nlpsol("own", "ipopt", {"x": prog.x, "f": f, "g": g}, options)
    sol = own(x0=prog.x0, lbg=np.concatenate(prog._lbg), ubg=np.concatenate(prog._ubg))
    assert own.stats()["success"]
    np.testing.assert_allclose(res.objective, float(sol["f"]), rtol=1e-8)
    np.testing.assert_allclose(res.x, np.array(sol["x"]).ravel(), atol=1e-6)


def _stuck() -> SparseProgram:
    # a program no x meets: IPOPT wanders (restoration phases) before it says so
    prog = SparseProgram(2)
    prog.constrain(prog.x[0] ** 2 + prog.x[1] ** 2, -2.0, -1.0)
    prog.minimize((prog.x[0] - 1.0) ** 2 + prog.x[1] ** 2)
    prog.x0[:] = 0.5
    return prog


_QUIET = {"print_time": False, "ipopt.print_level": 0, "ipopt.sb": "yes"}


def test_give_up_refuses_a_rule_that_means_nothing():
    for bad in ((0, 1e-3), (2.5, 1e-3), (True, 1e-3), (10, -1.0), (10, float("nan")), (10, 1e-3, -1),
                (10, 1e-3, 2.0), (10, 1e-3, 5, -0.1), (10, 1e-3, 5, 0.01, float("nan"))):
        with pytest.raises(ValueError, match="GiveUp"):
            GiveUp(*bad)


def test_a_solve_that_goes_nowhere_is_given_up_after_its_iterations():
    free = _stuck().solve(dict(_QUIET, **{"ipopt.max_iter": 200}))
    assert not free.success and free.iterations > 8  # IPOPT alone takes longer to give up
    res = _stuck().solve(dict(_QUIET, **{"ipopt.max_iter": 200}), GiveUp(5, 0.5))
    assert not res.success and res.status == "Given_Up"
    assert res.iterations <= 5
    # the least violation met: x^2 + y^2 is never below -1, so never within 1 of its bound
    assert res.stats["least_violation"] >= 1.0 - 1e-12


def test_a_solve_the_rule_does_not_give_up_takes_the_same_path():
    options = dict(_QUIET, **{"ipopt.tol": 1e-10})
    plain = _program().solve(options)
    for rule in (GiveUp(1, 1e9), GiveUp(3, 1e3)):
        watched = _program().solve(options, rule)
        assert watched.status == plain.status and watched.iterations == plain.iterations
        np.testing.assert_array_equal(watched.x, plain.x)
    # a start that violates the constraints is given up at once where nothing is allowed
    assert _program().solve(options, GiveUp(1, 0.0)).status == "Given_Up"
    # a stall window that never fills watches the objective without ending the solve
    watched = _program().solve(options, GiveUp(1, 1e9, window=10_000, decrease=1.0, feasible=1e9))
    assert watched.status == plain.status and watched.iterations == plain.iterations
    np.testing.assert_array_equal(watched.x, plain.x)


def _valley() -> SparseProgram:
    # Rosenbrock's valley inside a disc, from its usual start: IPOPT takes some twenty iterations
    prog = SparseProgram(2)
    prog.constrain(prog.x[0] ** 2 + prog.x[1] ** 2, -np.inf, 4.0)
    prog.minimize(100.0 * (prog.x[1] - prog.x[0] ** 2) ** 2 + (1.0 - prog.x[0]) ** 2)
    prog.x0[:] = [-1.2, 1.0]
    return prog


def test_a_solve_that_stalls_ends_with_its_last_iterate():
    options = dict(_QUIET, **{"ipopt.tol": 1e-10})
    plain = _valley().solve(options)
    assert plain.success and plain.iterations > 6
    np.testing.assert_allclose(plain.x, [1.0, 1.0], atol=1e-6)
    # any iterate "within 1e9 of the constraints" and the objective "falling by less than 1e3 of
    # itself" over two iterations: the rule ends the solve at its third iteration, as stalled
    stalled = _valley().solve(options, GiveUp(3, 1e9, window=2, decrease=1e3, feasible=1e9))
    assert not stalled.success and stalled.status == "Stalled" and stalled.iterations <= 3
    assert np.all(np.isfinite(stalled.x)) and np.max(np.abs(stalled.x - 1.0)) > 1e-3  # not the minimum
    # a window wider than the iterations made cannot judge the trend yet: the same path, to the bit
    watched = _valley().solve(options, GiveUp(1, 1e9, window=plain.iterations + 5, decrease=1e3, feasible=1e9))
    assert watched.status == plain.status and watched.iterations == plain.iterations
    np.testing.assert_array_equal(watched.x, plain.x)
    # nor one whose objective fell over the window by more than ``decrease`` of itself: from 24.2 at
    # the start to the minimum's 0 (to rounding), by far more than 1e3 times what is left
    early = _valley().solve(options, GiveUp(1, 1e9, window=plain.iterations - 1, decrease=1e3, feasible=1e9))
    assert early.status == plain.status and early.iterations == plain.iterations
