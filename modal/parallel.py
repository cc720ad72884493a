"""Long array work split over the machine's cores: a contiguous share of the items per thread, or the items
taken in turn by threads as they come free.

Operational analysis of a long record spends most of its time in loops whose iterations are independent
(the record's blocks, its channels) and whose work happens in numpy, scipy.fft and BLAS calls that release
Python's global lock. :func:`split_over_threads` hands each of ``workers`` threads one contiguous share of the
iterations: each share is computed exactly as it would be in one loop, so the results do not depend on the
number of threads, bit for bit.

Unlike a BLAS that wakes a thread per core for every small product, a share is one long task: when other
processes hold the cores, the threads wait in the operating system's queue and cost no more than one
thread would.
"""
from __future__ import annotations

import operator
import os
from concurrent.futures import ThreadPoolExecutor
from typing import Callable, Iterable, TypeVar

from .errors import ParameterError

__all__ = ["usable_cores", "thread_count", "shares", "split_over_threads", "map_over_threads", "run_beside"]

T = TypeVar("T")
S = TypeVar("S")
Item = TypeVar("Item")


def usable_cores() -> int:
    """The threads a computation may use by default: the cores this process may run on (its CPU affinity where
    the system tells it), at most ``OMP_NUM_THREADS`` where that is set to a positive integer.

    ``OMP_NUM_THREADS`` is the usual way to tell a process how many threads to use per computation; a Dask
    worker's nanny sets it to 1 (the cluster runs one computation per worker thread already), and so may a
    user who runs several analyses side by side.
    """
    try:
        cores = max(len(os.sched_getaffinity(0)), 1)
    except (AttributeError, OSError):  # (not every system has an affinity mask)
        cores = max(os.cpu_count() or 1, 1)
    limit = os.environ.get("OMP_NUM_THREADS", "").strip()
    if limit.isdigit() and int(limit) > 0:
        cores = min(cores, int(limit))
    return cores


def thread_count(workers) -> int:
    """The threads to use: ``workers``, or :func:`usable_cores` when None.

    Raises
    ------
    ParameterError
        ``workers`` is not a positive integer.
    """
    if workers is None:
        return usable_cores()
    try:
        count = operator.index(workers)
    except TypeError:
        count = 0
    if isinstance(workers, bool) or count < 1:
        raise ParameterError(f"'workers' is {workers!r}; expected a positive integer number of threads or None")
    return count


def shares(n_items: int, workers: int) -> list[tuple[int, int]]:
    """``(start, stop)`` of at most ``workers`` contiguous, non-empty shares of ``range(n_items)``, as even as
    whole items allow, in order."""
    count = max(min(int(workers), int(n_items)), 1)
    edges = [round(k * n_items / count) for k in range(count + 1)]
    return [(a, b) for a, b in zip(edges[:-1], edges[1:]) if b > a]


def split_over_threads(work: Callable[[int, int], T], n_items: int, workers) -> list[T]:
    """``[work(start, stop) for each share]`` of ``range(n_items)`` (:func:`shares`), the shares on their own
    threads when there are several.

    ``work`` must touch only its own share of any shared output. An exception raised in a share is raised
    here, the earliest share's first (as one loop would raise the first).
    """
    parts = shares(n_items, thread_count(workers))
    if len(parts) <= 1:
        return [work(a, b) for a, b in parts]
    with ThreadPoolExecutor(max_workers=len(parts)) as pool:
        futures = [pool.submit(work, a, b) for a, b in parts]
        return [future.result() for future in futures]


def map_over_threads(function: Callable[[Item], T], items: Iterable[Item], workers) -> list[T]:
    """``[function(item) for item in items]``, the items taken in order by ``workers`` threads as they come free
    (for items of unequal cost, such as eigenproblems of growing order).

    Each result is computed as one loop would compute it; an exception is raised for the earliest item that
    raised one.
    """
    items = list(items)
    count = min(thread_count(workers), len(items))
    if count <= 1:
        return [function(item) for item in items]
    with ThreadPoolExecutor(max_workers=count) as pool:
        return list(pool.map(function, items))


def run_beside(main: Callable[[], T], side: Callable[[], S], workers) -> tuple[T, S]:
    """``(main(), side())``, ``side`` on a thread of its own while ``main`` runs on this one when there are several
    ``workers`` (two short steps of one thread each, side by side), else one after the other.

    An exception raised in ``main`` is raised here (once ``side`` is done), else one raised in ``side``.
    """
    if thread_count(workers) <= 1:
        return main(), side()
    with ThreadPoolExecutor(max_workers=1) as pool:
        future = pool.submit(side)
        first = main()
        return first, future.result()
