"""Independent programs solved side by side: the same answers as one after another, and never lost."""

import os
import threading
from concurrent.futures.process import BrokenProcessPool

import numpy as np
import pytest

import skatetrace as st
from skatetrace.figures.figure import figure_from_dict
from skatetrace import processes
from skatetrace.planning import pool
from skatetrace.planning.planner import _cusp_pins, _program_options, _warm_options, curve_specs

#: Two arcs joined by a pivot: two distinct sections, so two warm-start programs to share out.
PIVOT = {"schema": "skatetrace.figure/1", "name": "two arcs", "params": {"M": 2, "m": 1, "I": 3},
         "curves": [{"pieces": [{"type": "arc", "radius": 1.2, "sweep_deg": 150},
                                {"type": "arc", "radius": 1.5, "sweep_deg": -120}],
                     "joins": [{"type": "cusp", "pivot_deg": -40}]}]}


@pytest.fixture(scope="module")
def jobs():
    fig = figure_from_dict(PIVOT)
    popts = _program_options(fig.params, st.TraceOptions(reach=1.0))
    specs, _sections = curve_specs(fig.curves[0])
    return [([spec], _warm_options(popts, start, end), None, None)
            for spec, (start, end) in zip(specs, _cusp_pins(specs, popts.reach))]


@pytest.fixture(scope="module")
def serial(jobs):
    return pool.solve_programs(jobs, workers=1)


def _same(a, b):
    assert a.success == b.success and a.iterations == b.iterations
    for xa, xb in zip(a.states, b.states):
        np.testing.assert_allclose(xa, xb, rtol=1e-9, atol=1e-12)


def test_programs_solved_in_worker_processes_are_the_ones_solved_here(jobs, serial, pools_made):
    side_by_side = pool.solve_programs(jobs, workers=2)
    assert pools_made == [2]  # the pool was used, one process per program
    assert all(s.success for s in serial)
    for a, b in zip(serial, side_by_side):
        _same(a, b)


class _BrokenPool:
    """A pool whose workers all die: every answer is lost with them."""

    def __init__(self, *args, **kwargs):
        pass

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        return False

    def submit(self, fn, *args):
        class Dead:
            def result(self):
                raise BrokenProcessPool("a worker died")
        return Dead()


def test_a_pool_that_breaks_loses_nothing(jobs, serial, monkeypatch):
    monkeypatch.setattr(processes, "ProcessPoolExecutor", _BrokenPool)
    monkeypatch.setattr(processes, "can_fork", lambda: True)
    again = pool.solve_programs(jobs, workers=2)
    assert len(again) == len(jobs)
    for a, b in zip(serial, again):
        _same(a, b)


def test_no_fork_while_other_threads_run(jobs, serial, monkeypatch):
    # a fork copies only the calling thread: another thread's locks would stay held in the child
    def refuse(*args, **kwargs):
        raise AssertionError("forked while another thread ran")

    monkeypatch.setattr(processes, "ProcessPoolExecutor", refuse)
    stop = threading.Event()
    other = threading.Thread(target=stop.wait)
    other.start()
    try:
        again = pool.solve_programs(jobs, workers=2)
    finally:
        stop.set()
        other.join()
    for a, b in zip(serial, again):
        _same(a, b)


def test_a_plan_does_not_depend_on_the_workers():
    fig = figure_from_dict(PIVOT)
    one = st.plan_figure(fig, options=st.TraceOptions(reach=1.0, workers=1))
    two = st.plan_figure(fig, options=st.TraceOptions(reach=1.0, workers=2))
    assert one.success and two.success
    for a, b in zip(one.sections, two.sections):
        assert a.residuals == pytest.approx(b.residuals, rel=1e-6, abs=1e-13)
        t = np.linspace(0.0, a.duration, 101)
        va, vb = a.evaluate(t, geometry=False), b.evaluate(t, geometry=False)
        for key in ("a", "b", "xi2"):
            np.testing.assert_allclose(va[key], vb[key], rtol=1e-9, atol=1e-12)


@pytest.mark.parametrize("bad", [0, -1, 1025, 2.0, True, "2"])
def test_workers_must_be_a_whole_number_of_processes(bad):
    with pytest.raises(ValueError, match="workers"):
        st.TraceOptions(workers=bad)



def test_the_default_never_fills_a_many_core_machine(jobs, serial, monkeypatch):
    made = []

    class Spy(_BrokenPool):
        def __init__(self, *args, max_workers, **kwargs):
            made.append(max_workers)

    monkeypatch.setattr(processes, "available_workers", lambda: 64)
    monkeypatch.setattr(processes, "ProcessPoolExecutor", Spy)
    monkeypatch.setattr(processes, "can_fork", lambda: True)
    many = [jobs[i % len(jobs)] for i in range(pool.DEFAULT_MAX_WORKERS + 1)]
    again = pool.solve_programs(many)  # the spy's pool loses every answer: solved here instead
    assert made == [pool.DEFAULT_MAX_WORKERS]
    for a, b in zip(again[:2], serial):
        _same(a, b)


def _work(sol):
    return sol.iterations * sol.unknowns


def test_a_budget_counts_iterations_times_unknowns_and_stops_at_the_program_that_spends_it(jobs, serial, pools_made):
    first, second = (_work(s) for s in serial)
    assert first > 0 and second > 0 and all(s.unknowns > 0 for s in serial)
    with pool.spending(first + second) as budget:  # enough: both solved, as without a budget
        again = pool.solve_programs(jobs, workers=1)
    assert (budget.spent, budget.programs) == (first + second, 2)
    for a, b in zip(serial, again):
        _same(a, b)
    # one unit short: the second program stops where it alone would spend what is left (at most one
    # iteration more), and the batch raises; the same on one worker or two
    for workers in (1, 2):
        with pool.spending(first + second - 1) as budget, pytest.raises(pool.BudgetSpent, match="planning budget"):
            pool.solve_programs(jobs, workers=workers)
        assert budget.programs == 2 and first + second - 1 < budget.spent <= first + second
    assert pools_made == [2]
    # spent already: a later batch solves nothing
    with pool.spending(first - 1) as budget:
        with pytest.raises(pool.BudgetSpent):
            pool.solve_programs(jobs[:1], workers=1)
        with pytest.raises(pool.BudgetSpent, match="before this batch"):
            pool.solve_programs(jobs[1:], workers=1)
        assert budget.programs == 1
    # outside a block nothing is counted, and an inner block replaces an outer one until it ends
    with pool.spending(10**12) as outer:
        with pool.spending(None) as inner:
            pool.solve_programs(jobs[:1], workers=1)
        assert inner is None and outer.spent == 0
        pool.solve_programs(jobs[:1], workers=1)
        assert outer.spent == first


def test_a_batch_given_a_share_of_a_budget_leaves_the_rest_for_what_follows(jobs, serial):
    # the linked programs' batch (the planner's share 0.75): each program stops after its part of
    # the share, with the status of one out of iterations, and no BudgetSpent is raised
    first, second = (_work(s) for s in serial)
    limit = 2 * (first + second)
    with pool.spending(limit) as budget:
        capped = pool.solve_programs(jobs, workers=1, share=0.4 * min(first, second) / limit)
        assert budget.spent <= 0.4 * min(first, second) + sum(s.unknowns for s in serial)
        for sol, full in zip(capped, serial):
            assert not sol.success and sol.status == "Maximum_Iterations_Exceeded"
            assert 0 < sol.iterations < full.iterations
        # the rest is there for the next batch, which is given all of it (the default share 1)
        again = pool.solve_programs(jobs, workers=1)
    for a, b in zip(serial, again):
        _same(a, b)
    # outside a spending block the share counts for nothing
    for a, b in zip(serial, pool.solve_programs(jobs, workers=1, share=0.01)):
        _same(a, b)
    for bad in (0.0, -0.5, 1.5, float("nan")):
        with pytest.raises(ValueError, match="share of the planning budget"):
            pool.solve_programs(jobs, workers=1, share=bad)


def test_a_program_given_what_is_left_of_a_budget_stops_one_iteration_past_it(jobs, serial):
    spec, opts, _guess, _meshes = jobs[0]
    full = serial[0]
    n = full.unknowns
    capped = pool.solve_program(spec, opts, max_work=5 * n)
    assert not capped.success and capped.status == "Maximum_Iterations_Exceeded" and capped.iterations == 6
    assert _work(capped) > 5 * n
    # a program that needs less than it is given is the same as without
    _same(pool.solve_program(spec, opts, max_work=_work(full)), full)


@pytest.mark.parametrize("bad", [-1, 1.5, True, "1000"])
def test_a_budget_must_be_a_whole_number_of_units(bad):
    with pytest.raises(ValueError, match="planning budget must be a whole number"):
        with pool.spending(bad):
            pass
    with pytest.raises(ValueError, match="plan_budget must be a whole number"):
        st.TraceOptions(reach=1.0, plan_budget=bad)


def test_a_budget_counts_a_program_given_up_at_the_iterations_it_was_allowed():
    # the rule that gives up a warm start going nowhere saves time, not budget: the budget decides
    # as it would have with the program run on to its cap
    from skatetrace.planning.collocation import ProgramSolution

    ran = ProgramSolution(success=False, status="Maximum_Iterations_Exceeded", message="", iterations=500,
                          unknowns=700, allowed=500)
    given_up = ProgramSolution(success=False, status="Given_Up", message="", iterations=195, unknowns=700, allowed=500)
    converged = ProgramSolution(success=True, status="Solve_Succeeded", message="", iterations=60, unknowns=700,
                                allowed=500)
    assert ran.work == given_up.work == 350_000 and converged.work == 42_000
    budget = pool.WorkBudget(380_000)  # 195 x 700 would leave room for the next; 500 x 700 does not
    budget.charge(given_up)
    assert budget.spent == 350_000
    with pytest.raises(pool.BudgetSpent):
        budget.charge(converged)


def test_programs_charged_in_order_spend_a_budget_side_by_side_as_one_after_another(jobs, serial, monkeypatch):
    # Side by side, each item's programs run from the budget as it stood at the start, and a later
    # item's may run on past the cap it would have had in order; they are charged in order, each at
    # the work it would have done: the same items kept, the budget spent at the same program, to the unit
    from threadpoolctl import threadpool_info

    monkeypatch.setattr(pool, "can_fork", lambda: True)
    monkeypatch.setattr(processes, "can_fork", lambda: True)
    first, second = (_work(s) for s in serial)

    def solved(k):
        sol = pool.solve_programs([jobs[k]], workers=1)[0]
        threads = {info["num_threads"] for info in threadpool_info() if info["user_api"] == "blas"}
        return os.getpid(), sol.iterations, threads

    for limit in (first + second, first + second // 2, first // 2):
        outcomes = []
        for workers in (1, 2):
            with pool.spending(limit) as budget:
                results, why = pool.charged_in_order(solved, [0, 1], workers)
            assert all(threads == {1} for _pid, _it, threads in results)  # numpy's BLAS on one thread
            if workers == 2 and len(results) == 2:
                assert results[1][0] != os.getpid()  # the second item ran in a child
            outcomes.append(([it for _pid, it, _t in results], why, budget.spent, budget.programs))
        assert outcomes[0] == outcomes[1]
        kept, why, spent, programs = outcomes[0]
        if limit == first + second:
            assert kept == [s.iterations for s in serial] and why is None and spent == limit
        else:
            assert spent > limit and why == (f"the planning budget of {limit:,} (IPOPT iterations x unknowns) was "
                                             f"spent after {programs} program{'s' * (programs > 1)} ({spent:,})")
            assert kept == ([serial[0].iterations] if limit > first else [])
    # without a budget nothing is counted, and every item is kept
    results, why = pool.charged_in_order(solved, [0, 1], 2)
    assert why is None and [it for _pid, it, _t in results] == [s.iterations for s in serial]


def test_a_program_that_a_share_of_the_budget_would_have_stopped_is_solved_again_in_order(jobs, serial, monkeypatch):
    # A batch with a share of the budget stops its programs without spending it (the planner's
    # linked programs): had the second item's program been stopped in order, the item would have
    # gone on from an unsolved program, so the item is solved again here, one after another
    monkeypatch.setattr(pool, "can_fork", lambda: True)
    monkeypatch.setattr(processes, "can_fork", lambda: True)
    first, second = (_work(s) for s in serial)
    n = serial[1].unknowns

    def solved(k):
        sol = pool.solve_programs([jobs[k]], workers=1, share=1.0 if k == 0 else 0.5)[0]
        return sol.status, sol.iterations

    limit = 2 * second + first - 4 * n  # alone, half of it is enough for the second; after the first, not
    assert 0.5 * limit >= second and first >= 4 * n
    outcomes = []
    for workers in (1, 2):
        with pool.spending(limit) as budget:
            outcomes.append((pool.charged_in_order(solved, [0, 1], workers), budget.spent, budget.programs))
    assert outcomes[0] == outcomes[1]
    (results, why), spent, programs = outcomes[0]
    assert why is None and programs == 2 and spent <= limit
    assert results == [(serial[0].status, serial[0].iterations), ("Maximum_Iterations_Exceeded",
                                                                  serial[1].iterations - 1)]
