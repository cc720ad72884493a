"""Work shared among threads: the shares, the thread count, the order of results and errors."""
from __future__ import annotations

import threading

import pytest

from modal.errors import ParameterError
from modal.parallel import map_over_threads, run_beside, shares, split_over_threads, thread_count, usable_cores


@pytest.mark.parametrize("n_items, workers", [(50, 2), (7, 3), (2, 8), (1, 4), (64, 1)])
def test_shares_cover_the_items_once_in_order(n_items, workers):
    parts = shares(n_items, workers)
    assert len(parts) == min(n_items, workers)
    assert [i for a, b in parts for i in range(a, b)] == list(range(n_items))
    sizes = [b - a for a, b in parts]
    assert min(sizes) >= 1 and max(sizes) - min(sizes) <= 1


def test_each_share_runs_on_its_own_thread_and_results_come_in_order():
    barrier = threading.Barrier(3, timeout=10)  # fails unless the three shares run at the same time

    def work(first, stop):
        barrier.wait()
        return first, stop, threading.get_ident()

    out = split_over_threads(work, 9, 3)
    assert [(a, b) for a, b, _ in out] == [(0, 3), (3, 6), (6, 9)]
    assert len({ident for *_, ident in out}) == 3


def test_the_earliest_shares_error_is_raised():
    def work(first, stop):
        if first > 0:
            raise ValueError(f"share from {first}")
        return first

    with pytest.raises(ValueError, match="share from 3"):
        split_over_threads(work, 9, 3)


def test_one_share_runs_on_the_callers_thread():
    assert split_over_threads(lambda a, b: threading.get_ident(), 5, 1) == [threading.get_ident()]


@pytest.mark.parametrize("bad", [0, -1, True, 1.5, "2"])
def test_a_bad_thread_count_is_named(bad):
    with pytest.raises(ParameterError, match="'workers' is"):
        thread_count(bad)


def test_default_threads_follow_omp_num_threads(monkeypatch):
    monkeypatch.delenv("OMP_NUM_THREADS", raising=False)
    every_core = usable_cores()
    monkeypatch.setenv("OMP_NUM_THREADS", "1")  # as a Dask worker's nanny sets it
    assert thread_count(None) == usable_cores() == 1
    monkeypatch.setenv("OMP_NUM_THREADS", "not a number")  # ignored
    assert usable_cores() == every_core


def test_items_mapped_over_threads_come_back_in_order():
    assert map_over_threads(lambda x: x * x, range(40), 3) == [x * x for x in range(40)]
    assert map_over_threads(lambda x: x, [], 3) == []


def test_the_earliest_items_error_is_raised():
    def fails_from_seven(x):
        if x >= 7:
            raise ValueError(f"item {x}")
        return x

    with pytest.raises(ValueError, match="item 7$"):
        map_over_threads(fails_from_seven, range(20), 2)


def test_a_side_step_runs_beside_the_main_one_on_its_own_thread():
    barrier = threading.Barrier(2, timeout=10)  # fails unless the two steps run at the same time

    def step(name):
        barrier.wait()
        return name, threading.get_ident()

    (main, main_thread), (side, side_thread) = run_beside(lambda: step("main"), lambda: step("side"), 2)
    assert (main, side) == ("main", "side")
    assert main_thread == threading.get_ident() != side_thread


def test_one_worker_runs_the_side_step_after_the_main_one_here():
    done = []
    out = run_beside(lambda: done.append("main") or threading.get_ident(),
                     lambda: done.append("side") or threading.get_ident(), 1)
    assert done == ["main", "side"] and out == (threading.get_ident(), threading.get_ident())


@pytest.mark.parametrize("workers", [1, 2])
def test_the_main_steps_error_is_raised_before_the_side_steps(workers):
    def fails(name):
        raise ValueError(name)

    with pytest.raises(ValueError, match="main"):
        run_beside(lambda: fails("main"), lambda: fails("side"), workers)
    with pytest.raises(ValueError, match="side"):
        run_beside(lambda: "fine", lambda: fails("side"), workers)
