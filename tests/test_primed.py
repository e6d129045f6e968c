"""Children forked before their work is known (skatetrace.processes.Primed): made ready, then given one batch."""

import os
import time

import pytest

from skatetrace import processes

#: Set by ``_prime`` in the process that runs it (a forked child inherits this module as it was).
_PRIMED = {"pid": None}
_PARENT = os.getpid()


def _prime():
    _PRIMED["pid"] = os.getpid()


def _where(shared, item):
    """``(shared + item, this pid, whether this process was primed)``: module level, so that it pickles."""
    return shared + item, os.getpid(), _PRIMED["pid"] == os.getpid()


def _dies_in_a_child(shared, item):
    if os.getpid() != _PARENT and item == 3:
        os._exit(7)  # a child killed mid-share: its answers never come
    return shared * item


def _sleeps_in_a_child(shared, item):
    if os.getpid() != _PARENT:
        time.sleep(30.0)  # uses no processor time: a child starved by other work looks the same
    return shared - item


def _fails(shared, item):
    if item == 2:
        raise ValueError("item 2 is bad")
    return item


def test_a_batch_is_computed_in_primed_children_in_order(forking):
    with processes.Primed(_prime, children=2, workers=2) as primed:
        assert primed.children == 2
        primed.submit(_where, 100, range(7))
        out = primed.results()
    assert [v for v, _pid, _primed in out] == [100 + k for k in range(7)]
    pids = [pid for _v, pid, _primed in out]
    # item k went to child k % 2, each made ready by prime() before the batch came
    assert _PARENT not in pids and len(set(pids)) == 2
    assert pids[0::2] == [pids[0]] * 4 and pids[1::2] == [pids[1]] * 3
    assert all(ready for _v, _pid, ready in out)
    assert _PRIMED["pid"] is None  # prime() ran in the children only


class _Counted:
    """Counts how often it is pickled (in this process)."""

    pickled = 0

    def __init__(self, value):
        self.value = value

    def __reduce__(self):
        _Counted.pickled += 1
        return (_Counted, (self.value,))


def _value_plus(shared, item):
    return shared.value + item


def test_the_shared_input_is_pickled_once_for_every_child(forking):
    # a figure's trace runs to tens of MB: pickled once, its bytes sent to each child
    _Counted.pickled = 0
    with processes.Primed(_prime, children=2, workers=2) as primed:
        primed.submit(_value_plus, _Counted(40), range(4))
        assert primed.results() == [40, 41, 42, 43]
    assert _Counted.pickled == 1


def test_without_children_the_batch_is_computed_by_map_forked(forking, monkeypatch):
    seen = []

    def fake_map_forked(fn, items, workers=None):
        seen.append(workers)
        return [fn(item) for item in items]

    monkeypatch.setattr(processes, "map_forked", fake_map_forked)
    with processes.Primed(_prime, children=2, workers=1) as primed:
        assert primed.children == 0
        primed.submit(_where, 1, [1, 2])
        assert [(v, pid) for v, pid, _ in primed.results()] == [(2, _PARENT), (3, _PARENT)]
    assert seen == [1]
    with processes.Primed(_prime, children=0, workers=2) as primed:
        assert primed.children == 0


def test_a_batch_that_does_not_pickle_is_computed_without_the_children(forking):
    local = 5  # a closure does not pickle: the children are ended, and map_forked computes the batch
    with processes.Primed(_prime, children=2, workers=2) as primed:
        primed.submit(lambda shared, item: (shared + item + local, _PRIMED["pid"] == os.getpid()), 10, [0, 1, 2])
        assert primed.children == 0
        out = primed.results()
    assert out == [(15, False), (16, False), (17, False)]


def test_a_share_whose_child_dies_is_computed_here(forking):
    with processes.Primed(_prime, children=2, workers=2) as primed:
        primed.submit(_dies_in_a_child, 3, range(6))
        assert primed.results() == [0, 3, 6, 9, 12, 15]


def test_a_starved_child_is_ended_and_its_share_computed_here(forking):
    with processes.Primed(_prime, children=2, workers=2) as primed:
        primed.submit(_sleeps_in_a_child, 10, range(4))
        began = time.monotonic()
        assert primed.results(share=0.5, window=0.1) == [10, 9, 8, 7]
    assert time.monotonic() - began < 20.0  # not the children's 30 s of sleep


def test_an_error_is_raised_here_as_without_children(forking):
    with processes.Primed(_prime, children=2, workers=2) as primed:
        primed.submit(_fails, None, range(4))
        with pytest.raises(ValueError, match="item 2 is bad"):
            primed.results()


def test_one_batch_only_and_none_without_a_batch(forking):
    with processes.Primed(_prime, children=2, workers=2) as primed:
        with pytest.raises(RuntimeError, match="no batch"):
            primed.results()
        primed.submit(_where, 0, [1])
        with pytest.raises(RuntimeError, match="one batch"):
            primed.submit(_where, 0, [1])
        assert primed.results()[0][0] == 1


def test_leaving_the_block_ends_children_never_given_a_batch(forking):
    with processes.Primed(_prime, children=2, workers=2) as primed:
        children = [process for process, _conn in primed._children]
        assert all(process.is_alive() for process in children)
    deadline = time.monotonic() + 10.0
    while any(process.is_alive() for process in children) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert not any(process.is_alive() for process in children)
