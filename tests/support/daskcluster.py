"""A real Dask cluster for tests: ``dask scheduler`` and ``dask worker`` processes from the installed
``dask`` command on 127.0.0.1 (free ports; stopped at the end of the session)."""
from __future__ import annotations

import os
import socket
import subprocess
import sys
from pathlib import Path

DASK = Path(sys.executable).with_name("dask")

#: Dask settings of the test cluster's processes (environment variables, a user's own setting kept): its
#: diagnostics for a dashboard nobody opens, the profiler sampling every worker's threads every 10 ms, the
#: event-loop health check every 20 ms, the system monitor every 0.5 s, made an idle scheduler with two
#: nanny workers burn 5.8 CPU-s a minute (1.6 without them), taken from the tests running beside it; the
#: tests of dashboards and of ``modal batch``'s own cluster as configured by default
#: (tests/modal/batch/test_cluster.py) start theirs without these
QUIET = {"DASK_DISTRIBUTED__WORKER__PROFILE__ENABLED": "False",
         "DASK_DISTRIBUTED__ADMIN__TICK__INTERVAL": "1s",
         "DASK_DISTRIBUTED__ADMIN__SYSTEM_MONITOR__INTERVAL": "5s"}


def quiet_environment(environ=os.environ) -> dict[str, str]:
    """``environ`` with :data:`QUIET`'s settings where it has none of its own."""
    return {**QUIET, **environ}


def free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


def start_worker(address: str, name: str, folder: Path, nanny: bool = False) -> subprocess.Popen:
    """One worker, without a nanny by default (so that killing it loses it for good); with ``nanny``
    as ``dask worker`` runs by default: the worker is then a daemonic child process of its nanny."""
    return subprocess.Popen([str(DASK), "worker", address, "--name", name, "--nthreads", "1",
                             "--nanny" if nanny else "--no-nanny", "--no-dashboard", "--host", "127.0.0.1",
                             "--local-directory", str(folder)],
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, cwd=folder, env=quiet_environment())


def wait_for_workers(address: str, n: int, timeout: float = 60.0) -> None:
    from distributed import Client

    with Client(address, timeout="30s", set_as_default=False) as client:
        client.wait_for_workers(n, timeout=timeout)


def stop(procs) -> None:
    for proc in procs:
        if proc.poll() is None:
            proc.terminate()
    for proc in procs:
        try:
            proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()


def cluster(tmp_path_factory):
    """``dask scheduler`` and two ``dask worker`` processes on 127.0.0.1, each with its nanny as in a
    deployment (the worker processes are daemonic); yields (address, folder, processes)."""
    assert DASK.is_file(), f"{DASK}: the dask command is not installed (dask[distributed] is a dependency)"
    folder = tmp_path_factory.mktemp("dask")  # the processes' working and local directory
    port = free_port()
    address = f"tcp://127.0.0.1:{port}"
    procs = [subprocess.Popen([str(DASK), "scheduler", "--host", "127.0.0.1", "--port", str(port), "--no-dashboard"],
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, cwd=folder, env=quiet_environment())]
    try:
        procs += [start_worker(address, f"w{i}", folder, nanny=True) for i in range(2)]
        wait_for_workers(address, 2)
        yield address, folder, procs
    finally:
        # the workers first, while their scheduler still answers: a nanny whose scheduler is going
        # too waits out its timeouts (8 s against 1 s)
        stop(procs[1:])
        stop(procs[:1])


class SessionCluster:
    """The run's cluster (:func:`cluster`), started when a test first asks for it and stopped by :meth:`stop`
    as soon as no test left on this process needs it (conftest.py), not at the end of the session: an idle
    scheduler with two nanny workers burns about 0.1 CPU-s every second (6.3 CPU-s a minute measured),
    taken from the tests still running. Asked for again after a stop, it starts again."""

    def __init__(self, tmp_path_factory):
        self._factory = tmp_path_factory
        self._run = None
        self._value = None
        #: how often the cluster was started (for the tests of this class)
        self.starts = 0

    @property
    def running(self) -> bool:
        return self._value is not None

    def get(self):
        """(address, folder, processes) of the running cluster, started if it is not."""
        if self._value is None:
            self._run = cluster(self._factory)
            self._value = next(self._run)
            self.starts += 1
        return self._value

    def stop(self) -> None:
        """Stop the processes (workers first, as :func:`cluster` does); nothing if it is not running."""
        run, self._run, self._value = self._run, None, None
        if run is not None:
            run.close()


def last_user(nodeids, needs) -> str | None:
    """Of tests run in the order ``nodeids``, the last that ``needs`` the cluster (a predicate on a node id)."""
    last = None
    for nodeid in nodeids:
        if needs(nodeid):
            last = nodeid
    return last


def done_with_cluster(nodeid: str, next_nodeid: str | None, last: str | None, file_groups: bool,
                      in_group) -> bool:
    """Whether no test left on this process needs the cluster after test ``nodeid``.

    ``next_nodeid`` is the test this process runs next (None: none), ``last`` the last test of the run's
    order that asks for the cluster (:func:`last_user`): in a run in one process the tests after it do
    without. Under ``-n N``'s file groups (``file_groups``, :mod:`support.workergroups`) a worker gets every
    file naming the cluster in one piece, the others' tests never in between: the group is over when the next
    test's file is outside it (``in_group``, a predicate on a file's path relative to the root).
    """
    if next_nodeid is None or nodeid == last:
        return True
    return file_groups and not in_group(next_nodeid.split("::", 1)[0])
