"""The embedded cluster of ``modal batch``: no web server unless ``--dashboard`` (no listener, no
"Port 8787 is already in use"), and a clean exit (no heartbeat traceback from Dask on stderr)."""
from __future__ import annotations

import http.client
import socket
import subprocess
import sys
import textwrap
import time
import urllib.request
from pathlib import Path

import psutil
import pytest

from modal.io import write_frf

from support.batchfiles import mobility
from support.daskcluster import free_port

DASHBOARD_PORT = 8787


def write_inputs(folder: Path, n: int = 1) -> Path:
    """``n`` FRF files in ``folder``. One is enough for the tests here, whose subject is the cluster (its ports,
    its dashboard, its close): a worker fits it in its fitting process and keeps that open until the cluster
    closes, the other worker idles; each file more on the other worker would only start a second such process."""
    folder.mkdir()
    for k in range(n):
        write_frf(mobility(seed=k), folder / f"f{k}.uff")
    return folder


def listening_ports(pid: int) -> set[int]:
    """TCP ports the process and its descendants listen on."""
    try:
        root = psutil.Process(pid)
        procs = [root, *root.children(recursive=True)]
    except psutil.NoSuchProcess:
        return set()
    ports = set()
    for proc in procs:
        try:
            ports |= {c.laddr.port for c in proc.net_connections(kind="tcp") if c.status == psutil.CONN_LISTEN}
        except (psutil.NoSuchProcess, psutil.AccessDenied):
            continue
    return ports


def speaks_first(port: int, wait_s: float = 5.0) -> bool | None:
    """True when the listener on 127.0.0.1:port speaks first (a Dask comm sends its handshake as it
    accepts), False when it accepts and says nothing (an HTTP server waits for a request), None when
    it is gone. Nothing is ever sent to it: an HTTP request read by a Dask comm makes it log a traceback."""
    try:
        with socket.create_connection(("127.0.0.1", port), timeout=wait_s) as sock:
            try:
                return bool(sock.recv(1))
            except TimeoutError:
                return False
    except OSError:  # refused: the process has closed it
        return None


def speaks_http(port: int) -> bool:
    """Whether an HTTP server answers on 127.0.0.1:port (Dask's answers /health with "ok")."""
    try:
        with urllib.request.urlopen(f"http://127.0.0.1:{port}/health", timeout=5) as response:
            return response.status == 200
    except (OSError, http.client.HTTPException):  # refused, reset, or an answer that is not HTTP
        return False


def watch(args: list[str], dashboard: int | None = None,
          command: tuple[str, ...] = ("-m", "modal", "batch")) -> tuple[subprocess.CompletedProcess, set[int], set[int]]:
    """Run ``modal batch ARGS`` (``python COMMAND ARGS``); the ports its processes listened on while it ran,
    and those of them that were not Dask's (silent on accepting), the ``dashboard`` port if it answered HTTP."""
    proc = subprocess.Popen([sys.executable, *command, *args], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    seen, other = set(), set()
    try:
        while proc.poll() is None:
            for port in listening_ports(proc.pid) - seen:
                seen.add(port)
                if port == dashboard:
                    if speaks_http(port):
                        other.add(port)
                elif speaks_first(port) is False:
                    other.add(port)
            time.sleep(0.1)
        out, err = proc.communicate(timeout=300)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
    return subprocess.CompletedProcess(proc.args, proc.returncode, out, err), seen, other


@pytest.fixture(scope="module")
def default_run(tmp_path_factory):
    """One ``modal batch`` with its embedded cluster (two workers) and no --dashboard, watched, the
    dashboard's port taken, the scheduler answering heartbeats late (:data:`_SLOW_HEARTBEATS`): the run
    both tests of a default run read (each run starts a scheduler and two nanny workers, ~4.5 CPU-s)."""
    tmp_path = tmp_path_factory.mktemp("default_run")
    folder = write_inputs(tmp_path / "in")
    with socket.socket() as holder:
        try:  # the dashboard's port taken (by this test, or by whatever else holds it)
            holder.bind(("127.0.0.1", DASHBOARD_PORT))
            holder.listen()
        except OSError:
            pass
        return watch([str(folder), "--out", str(tmp_path / "r.h5"), "--workers", "2"],
                     command=("-c", textwrap.dedent(_SLOW_HEARTBEATS)))


def test_no_web_server_unless_asked_and_no_word_of_a_taken_port(default_run):
    done, seen, other = default_run
    assert done.returncode == 0, done.stderr
    assert len(seen) >= 3  # the watch saw the cluster: a scheduler and two workers listen (Dask's protocol)
    assert other == set() and DASHBOARD_PORT not in seen  # nothing but Dask's comms
    assert "already in use" not in done.stderr and "Traceback" not in done.stderr


def test_dashboard_when_asked(tmp_path):
    folder = write_inputs(tmp_path / "in")
    port = free_port()
    done, seen, other = watch([str(folder), "--out", str(tmp_path / "r.h5"), "--workers", "2",
                               "--dashboard", f"127.0.0.1:{port}"], dashboard=port)
    assert done.returncode == 0, done.stderr
    assert other == {port}  # the scheduler's dashboard answered; every other port was Dask's
    assert f"dashboard: http://127.0.0.1:{port}/status" in done.stderr


_SLOW_HEARTBEATS = """
import asyncio, sys
import distributed

# the scheduler answers heartbeats after 1 s (the workers send one every 0.5 s): whenever the
# cluster closes, a worker's heartbeat is in flight, as happens by chance on a loaded machine
original_init = distributed.Scheduler.__init__

def init(self, *args, **kwargs):
    original_init(self, *args, **kwargs)
    answer = self.handlers["heartbeat_worker"]

    async def slow(*a, **k):
        await asyncio.sleep(1.0)
        return answer(*a, **k)

    self.handlers["heartbeat_worker"] = slow

distributed.Scheduler.__init__ = init
from modal.cli import main
sys.exit(main(["batch", *sys.argv[1:]]))
"""


def test_the_embedded_cluster_closes_without_a_traceback(default_run):
    done = default_run[0]
    assert done.returncode == 0, done.stderr
    assert "Traceback" not in done.stderr and "ERROR" not in done.stderr, done.stderr
    assert done.stderr == ""


def test_the_embedded_cluster_leaves_the_callers_environment_as_it_was(tmp_path):
    """Dask's nannies set their workers' variables (OMP_NUM_THREADS=1, PYTHONHASHSEED, ...) in their
    own process's environment: here the caller's, whose later subprocesses then ran with one BLAS
    thread and another hash seed (tests/test_determinism.py's digests differed after such a run).
    In the workers themselves OMP_NUM_THREADS=1 holds: each worker's computations (modal.oma's shares,
    modal/parallel.py) use one thread, the cluster already running one file per worker."""
    import os

    from modal.batch import fit_files
    from modal.batch.cluster import open_client
    from modal.parallel import usable_cores

    before = dict(os.environ)
    with open_client(workers=1) as client:
        assert client.submit(usable_cores, pure=False).result() == 1
        result = fit_files(write_inputs(tmp_path / "in"), client=client)
    assert result.fitted == 1
    assert dict(os.environ) == before
