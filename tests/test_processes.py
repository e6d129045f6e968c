"""Work shared out between this process and forked children (skatetrace.processes): same answers, nothing lost."""

import multiprocessing
import os
import time

import pytest

from skatetrace import processes


def test_map_forked_is_the_list_comprehension_in_order(forking):
    offset = 1000  # a closure: nothing is pickled on the way in
    parent = os.getpid()
    out = processes.map_forked(lambda x: (x + offset, os.getpid() == parent), list(range(7)), workers=3)
    assert [v for v, _ in out] == [x + 1000 for x in range(7)]
    # item i ran in process i % 3: this one for 0, 3, 6, children for the rest
    assert [here for _, here in out] == [i % 3 == 0 for i in range(7)]


def test_a_share_whose_child_dies_or_fails_is_run_here(forking):
    parent = os.getpid()

    def dies(x):
        if os.getpid() != parent and x == 3:
            os._exit(7)  # a child killed mid-share: its answers never come
        return 2 * x

    assert processes.map_forked(dies, list(range(6)), workers=2) == [0, 2, 4, 6, 8, 10]

    def fails(x):
        if os.getpid() != parent:
            raise RuntimeError("only in the child")
        return -x

    assert processes.map_forked(fails, list(range(4)), workers=2) == [0, -1, -2, -3]


def test_an_error_is_raised_here_as_without_children(forking):
    def bad(x):
        if x == 1:
            raise ValueError("item 1 is bad")
        return x

    with pytest.raises(ValueError, match="item 1 is bad"):
        processes.map_forked(bad, [0, 1, 2], workers=2)


def test_one_worker_or_no_fork_runs_everything_here(monkeypatch):
    parent = os.getpid()
    assert processes.map_forked(lambda x: os.getpid() == parent, [1, 2, 3], workers=1) == [True] * 3
    monkeypatch.setattr(processes, "can_fork", lambda: False)
    assert processes.map_forked(lambda x: os.getpid() == parent, [1, 2, 3], workers=2) == [True] * 3


def test_plots_drawn_in_children_are_written_and_recorded_here(forking, tmp_path):
    """The PNGs come back as bytes and are written by this process, so the output folder's record
    of what the run wrote (its manifest) holds every plot."""
    import skatetrace as st
    from skatetrace.outputs.files import record_writes
    from skatetrace.outputs.plotting import save_all

    done = st.trace_and_verify(st.pattern("line"))
    seen = []
    with record_writes(seen.append):
        written = save_all(done.trace, done.report, tmp_path)
    assert [p.name for p in seen] == [p.name for p in written] == ["figure.png", "controls.png", "speed.png",
                                                                  "mass_path.png", "energies.png"]
    assert all(p.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" for p in written)


def test_a_child_runs_its_own_side_by_side_work_itself():
    # the verification samples its sections with map_forked, and may itself run in a child (a
    # plot, a share of other work): a daemonic child may not fork, so it runs the work itself
    # instead of failing and leaving its share to be run again here
    if not processes.can_fork():
        pytest.skip("this test process may not fork")
    parent = os.getpid()

    def outer(x):
        return os.getpid(), processes.map_forked(lambda y: os.getpid(), [0, 1], workers=2)

    (here, inner_here), (child, inner_child) = processes.map_forked(outer, [0, 1], workers=2)
    assert here == parent and child != parent  # item 1 ran in the child, not again here
    assert inner_child == [child, child]
    assert inner_here[0] == parent and inner_here[1] not in (parent, child)


def test_evaluated_ahead_yields_every_item_in_order_and_skips_the_unwanted(forking):
    parent = os.getpid()
    calls = []

    def fn(x):
        calls.append(x)  # in this process only: a child's list is its own
        return 10 * x, os.getpid() == parent

    out = list(processes.evaluated_ahead(fn, range(12), lambda x: x % 3 != 0, alone_for=0.0, batch=2, workers=2))
    assert [item for item, _ in out] == list(range(12))
    assert [r and r[0] for _, r in out] == [None if x % 3 == 0 else 10 * x for x in range(12)]
    assert 0 not in calls and 3 not in calls  # fn never sees an unwanted item
    # the first item alone here, then batches of two per process: some answers came from a child
    assert out[1][1][1] and not all(r[1] for _, r in out if r)


def test_evaluated_ahead_asks_wanted_when_it_makes_a_batch(forking):
    # a search that has its answer turns the later items away: a batch made after that skips them
    found = []

    def wanted(x):
        return not found

    seen = []
    for item, result in processes.evaluated_ahead(lambda x: x, range(20), wanted, alone_for=0.0, batch=2,
                                                  workers=2):
        seen.append((item, result))
        if item == 5:
            found.append(item)
    # item 0 alone, then batches of 2 x 2 workers: 1..4, 5..8 (made before 5 was seen), 9..12, ...
    assert [r for _, r in seen[:9]] == list(range(9))
    assert all(r is None for i, r in seen if i >= 9)


def test_evaluated_ahead_sizes_its_rounds_by_the_time_an_item_takes(forking, monkeypatch):
    # items of 40 ms or more in rounds meant to take 0.1 s: two items a process at most, not the
    # eight a batch allows (a round is made with what the search knew when it was made, so a long
    # one evaluates items the search would have turned away by then)
    import time

    made, real = [], processes.map_forked

    def forked(fn, items, workers=None):
        made.append(len(items))
        return real(fn, items, workers)

    monkeypatch.setattr(processes, "map_forked", forked)

    def slow(x):
        time.sleep(0.04)
        return x

    out = list(processes.evaluated_ahead(slow, range(13), lambda x: True, alone_for=0.0, batch=8, round_for=0.1,
                                         workers=2))
    assert [r for _, r in out] == list(range(13))
    assert made and all(1 <= n <= 4 for n in made) and sum(made) == 12  # item 0 alone, then rounds of 2 to 4


def test_evaluated_ahead_alone_or_in_a_child_runs_everything_here(forking):
    parent = os.getpid()
    out = list(processes.evaluated_ahead(lambda x: os.getpid(), range(6), lambda x: True, alone_for=60.0))
    assert all(pid == parent for _, pid in out)  # all within the time alone

    def in_child(_):
        here = os.getpid()
        pids = [pid for _, pid in processes.evaluated_ahead(lambda x: os.getpid(), range(6), lambda x: True,
                                                            alone_for=0.0, batch=1, workers=2)]
        return here, pids

    (_, _), (child, pids) = processes.map_forked(in_child, [0, 1], workers=2)
    assert pids == [child] * 6  # a worker forks nothing more: its siblings already fill the cores


def test_background_answers_from_a_child_while_this_process_goes_on(forking):
    import time

    parent = os.getpid()
    with processes.Background(lambda: (os.getpid(), [1.5] * 3), 2) as job:
        started = time.perf_counter()  # the child computes while this process does something else
        here = sum(range(1000))
        assert time.perf_counter() - started < 1.0 and here == 499500
        pid, value = job.result()
    assert pid != parent and value == [1.5] * 3


@pytest.mark.parametrize("how", ["dies", "fails"])
def test_background_whose_child_dies_or_fails_is_computed_here(forking, how):
    parent = os.getpid()

    def work():
        if os.getpid() != parent:
            if how == "dies":
                os._exit(3)
            raise RuntimeError("only in the child")
        return "here"

    with processes.Background(work, 2) as job:
        assert job.result() == "here"

    def always_fails():
        raise ValueError("a bad input")

    with processes.Background(always_fails, 2) as job, pytest.raises(ValueError, match="a bad input"):
        job.result()  # raised here, as without a child


@pytest.mark.parametrize("why", ["no fork", "one worker"])
def test_background_without_fork_computes_on_demand_here(monkeypatch, why):
    monkeypatch.setattr(processes, "can_fork", lambda: why != "no fork")
    calls = []
    with processes.Background(lambda: calls.append(os.getpid()) or "done", 1 if why == "one worker" else None) as job:
        assert calls == []  # nothing is computed until asked for
        assert job.result() == "done"
    assert calls == [os.getpid()]


def test_leaving_the_block_ends_a_child_still_at_work(forking):
    import time

    with pytest.raises(KeyboardInterrupt):
        with processes.Background(lambda: time.sleep(60), 2) as job:
            child = job._child._process
            raise KeyboardInterrupt
    assert not child.is_alive() and child.exitcode is not None


def test_an_idle_background_child_runs_at_the_lowest_priority_and_says_when_it_is_done(forking):
    import time

    here = os.nice(0)
    with processes.Background(lambda: os.nice(0), 2, idle=True) as job:
        deadline = time.monotonic() + 60
        while not job.ready() and time.monotonic() < deadline:
            time.sleep(0.01)
        assert job.ready()
        assert job.result() == min(19, here + processes.IDLE_NICENESS)
    with processes.Background(lambda: os.nice(0), 2) as job:  # not idle: this process's own
        assert job.result() == here


def test_a_background_child_not_yet_done_is_not_ready_and_can_be_cancelled(forking, monkeypatch):
    import time

    with processes.Background(lambda: time.sleep(60), 2, idle=True) as job:
        assert not job.ready()
        child = job._child._process
        job.cancel()  # ended at once, not waited for
        assert not child.is_alive() and child.exitcode is not None and not job.ready()
    # without a child there is nothing to wait for, and nothing ready: the caller computes here
    monkeypatch.setattr(processes, "can_fork", lambda: False)
    with processes.Background(lambda: "here", 2, idle=True) as job:
        assert not job.ready() and job.result() == "here"


def _busy_then_pid(seconds):
    import time

    end = time.process_time() + seconds
    while time.process_time() < end:
        pass
    return os.getpid()


def test_an_idle_child_is_waited_for_while_it_runs_and_ended_where_it_is_starved(forking, monkeypatch):
    import time

    parent = os.getpid()
    # at work (this process waits): waited for, its answer taken. Not idle, and asked for a
    # twentieth of a core, so that other work on a busy test machine cannot starve it
    with processes.Background(lambda: _busy_then_pid(0.6), 2) as job:
        assert not job.ready()
        waited = job.awaited(share=0.05)
        assert waited is not None and waited[0] != parent and not job.ready()
    # a child that gets no processor time (here: asleep, as one starved by other work would be)
    # is ended after a window, not waited for
    with processes.Background(lambda: time.sleep(60), 2, idle=True) as job:
        child = job._child._process
        started = time.monotonic()
        assert job.awaited(window=0.2) is None
        assert time.monotonic() - started < 5 and not child.is_alive() and not job.ready()
    # where its processor time cannot be read (not Linux), nor is it waited for
    monkeypatch.setattr(processes._Child, "cpu_seconds", lambda self: None)
    with processes.Background(lambda: _busy_then_pid(60), 2, idle=True) as job:
        child = job._child._process
        assert job.awaited() is None and not child.is_alive()
    # without a child there is nothing to wait for
    monkeypatch.setattr(processes, "can_fork", lambda: False)
    with processes.Background(lambda: "here", 2, idle=True) as job:
        assert job.awaited() is None and job.result() == "here"


def _pid_of(x):
    return x * x, os.getpid()


@pytest.mark.parametrize("chunk", [1, 3, 20])
def test_run_jobs_in_chunks_yields_every_result_in_order(forking, chunk):
    """Jobs handed over a chunk at a time come back in order, each once, computed in the workers."""
    out = list(processes.run_jobs(_pid_of, list(range(10)), workers=2, chunk=chunk))
    assert [v for v, _ in out] == [x * x for x in range(10)]
    assert os.getpid() not in {pid for _, pid in out}
    # a chunk runs in one worker, one job after another
    for k in range(0, 10, chunk):
        assert len({pid for _, pid in out[k:k + chunk]}) == 1


_PARENT = os.getpid()  # the test process; forked workers inherit it


def _dies_in_a_worker_on_seven(x):
    if x == 7 and os.getpid() != _PARENT:
        os._exit(3)  # a worker killed in its chunk: the pool breaks, and its chunk never comes back
    return x, os.getpid()


def test_run_jobs_in_chunks_runs_here_what_a_dead_worker_did_not_send(forking):
    """The results before the broken chunk are kept; that chunk and the rest are run here."""
    out = list(processes.run_jobs(_dies_in_a_worker_on_seven, list(range(10)), workers=2, chunk=3))
    assert [v for v, _ in out] == list(range(10))
    assert out[7][1] == _PARENT  # computed here, after its worker died


def _pid_after(x):
    """The worker's pid at once for job 0; any other job sleeps for a minute (a program left running)."""
    if x:
        time.sleep(60.0)
    return os.getpid()


def test_run_jobs_closed_early_ends_its_workers_at_once(forking):
    """A caller that stops asking (a planning budget spent) leaves no worker at work on a dropped job:
    one would hold the interpreter's exit until its job ends (concurrent.futures joins them then)."""
    solved = processes.run_jobs(_pid_after, [0, 1, 2], workers=2)
    next(solved)
    time.sleep(0.2)  # the other worker is asleep in job 1
    children = {p.pid for p in multiprocessing.active_children()}
    start = time.perf_counter()
    solved.close()
    while children & {p.pid for p in multiprocessing.active_children()}:
        assert time.perf_counter() - start < 10.0, "a worker was left at its job"
        time.sleep(0.05)
