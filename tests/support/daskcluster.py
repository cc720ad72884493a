"""A real Dask cluster for tests: ``dask scheduler`` and ``dask worker`` processes from the installed
``dask`` command on 127.0.0.1 (free ports; stopped at the end of the session)."""
from __future__ import annotations

import socket
import subprocess
import sys
from pathlib import Path

DASK = Path(sys.executable).with_name("dask")


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
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, cwd=folder)


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
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, cwd=folder)]
    try:
        procs += [start_worker(address, f"w{i}", folder, nanny=True) for i in range(2)]
        wait_for_workers(address, 2)
        yield address, folder, procs
    finally:
        # the workers first, while their scheduler still answers: a nanny whose scheduler is going
        # too waits out its timeouts (8 s against 1 s)
        stop(procs[1:])
        stop(procs[:1])
