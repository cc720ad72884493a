"""The Dask client of a batch: a given client, a scheduler address, or an embedded local cluster.

The embedded cluster is quiet: its scheduler and workers listen on 127.0.0.1 for Dask's own
protocol only. Dask starts an HTTP server (dashboard, metrics, health) in the scheduler on port
8787 and in every worker; here none is started unless a dashboard is asked for, so a batch opens
no web port and never reports that port 8787 is taken. It also closes cleanly: a worker's
heartbeat cut short by its own shutdown is not reported as an error. The caller's environment
variables are left as they were (Dask's nannies set their workers' in it).
"""
from __future__ import annotations

import logging
import os
import weakref
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

from distributed import Nanny, Scheduler, SpecCluster, Worker
from distributed.core import Status

from ..errors import ModalError

__all__ = ["open_client", "default_workers", "DEFAULT_DASHBOARD", "BatchScheduler", "BatchWorker"]

#: Where ``dashboard=True`` serves Dask's dashboard (Dask's usual port, this machine only).
DEFAULT_DASHBOARD = "127.0.0.1:8787"
_CLOSING = (Status.closing, Status.closing_gracefully, Status.closed, Status.failed)
_HEARTBEAT_FAILED = "Failed to communicate with scheduler during heartbeat"


def default_workers() -> int:
    """Workers of the embedded cluster by default: the cores this process may use."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover - not on Linux
        return max(1, os.cpu_count() or 1)


class BatchScheduler(Scheduler):
    """Dask's scheduler without its HTTP server unless ``http`` (the dashboard) is asked for."""

    def __init__(self, *args: Any, http: bool = False, **kwargs: Any):
        self._http = http  # read by start_http_server, which Scheduler.__init__ calls
        super().__init__(*args, **kwargs)

    def start_http_server(self, *args: Any, **kwargs: Any) -> None:
        if self._http:
            super().start_http_server(*args, **kwargs)


class _HeartbeatAtShutdown(logging.Filter):
    """Drops the heartbeat failure a worker logs when its own shutdown closes the connection of a
    heartbeat in flight (a race inside Dask: the periodic heartbeat is stopped, the one already
    sent is not); the same failure while the worker runs is kept."""

    def __init__(self, worker: Worker):
        super().__init__()
        self._worker = weakref.ref(worker)

    def filter(self, record: logging.LogRecord) -> bool:
        worker = self._worker()
        closing = worker is None or worker.status in _CLOSING
        return not (closing and str(record.msg).startswith(_HEARTBEAT_FAILED))


class BatchWorker(Worker):
    """Dask's worker without its HTTP server, quiet about a heartbeat its own shutdown cut short."""

    def __init__(self, *args: Any, **kwargs: Any):
        super().__init__(*args, **kwargs)
        logging.getLogger("distributed.worker").addFilter(_HeartbeatAtShutdown(self))

    def start_http_server(self, *args: Any, **kwargs: Any) -> None:
        return None


def _check_reachable(address: str, timeout_s: float = 5.0) -> None:
    """Fail at once, with one line, when nothing listens at a ``tcp://HOST:PORT`` address (Dask's
    client would retry until its timeout); other protocols are left to Dask."""
    import socket
    from urllib.parse import urlsplit

    parts = urlsplit(address if "://" in address else f"tcp://{address}")
    if parts.scheme != "tcp":
        return
    try:
        host, port = parts.hostname, parts.port
    except ValueError:
        host = port = None
    if not host or port is None:
        raise ModalError(f"--scheduler {address}: expected tcp://HOST:PORT")
    try:
        with socket.create_connection((host, port), timeout=timeout_s):
            pass
    except OSError as exc:
        raise ModalError(f"--scheduler {address}: cannot connect ({exc.strerror or exc}); expected a running Dask "
                         "scheduler at that address") from None


def local_cluster(workers: int, dashboard: str | None = None) -> SpecCluster:
    """The embedded cluster: ``workers`` worker processes of one thread each (with their nannies) and a
    scheduler, on 127.0.0.1; Dask's dashboard at ``dashboard`` (``HOST:PORT``) when given, else no
    HTTP server at all."""
    scheduler = {"cls": BatchScheduler,
                 "options": {"host": "127.0.0.1", "port": 0, "http": dashboard is not None,
                             "dashboard": dashboard is not None, "dashboard_address": dashboard}}
    worker = {"cls": Nanny,
              "options": {"nthreads": 1, "host": "127.0.0.1", "worker_class": BatchWorker, "dashboard": False,
                          "silence_logs": logging.ERROR}}
    return SpecCluster(scheduler=scheduler, workers={i: worker for i in range(workers)},
                       silence_logs=logging.ERROR, name="modal batch")


@contextmanager
def open_client(client: Any = None, workers: int | None = None, dashboard: str | None = None) -> Iterator[Any]:
    """Yield a ``distributed.Client``.

    Parameters
    ----------
    client : distributed.Client or str, optional
        A client (used as it is, left open) or a scheduler address (``tcp://HOST:PORT``,
        connected and closed). Default: a local cluster of worker processes, closed after.
    workers : int, optional
        Worker processes of the local cluster (one thread each); default :func:`default_workers`.
    dashboard : str, optional
        Local cluster: serve Dask's dashboard at this ``HOST:PORT`` (default: no HTTP server).

    Raises
    ------
    ModalError
        The scheduler cannot be reached.
    """
    from distributed import Client

    if client is not None and not isinstance(client, str):
        yield client
        return
    if isinstance(client, str):
        _check_reachable(client)
        try:
            connected = Client(client, timeout="10s", set_as_default=False)
        except (OSError, TimeoutError) as exc:
            raise ModalError(f"--scheduler {client}: cannot connect ({' '.join(str(exc).split())}); expected a "
                             "running Dask scheduler at that address") from None
        with connected:
            yield connected
        return
    saved = dict(os.environ)
    try:
        with local_cluster(workers or default_workers(), dashboard) as cluster:
            _restore_environment(saved)
            with Client(cluster, set_as_default=False) as local:
                yield local
    finally:
        _restore_environment(saved)  # again: a nanny that restarted its worker set them once more


def _restore_environment(saved: dict[str, str]) -> None:
    """Put back this process's environment as it was. A Dask nanny sets variables for the worker it
    spawns (OMP_NUM_THREADS=1, PYTHONHASHSEED, ...) in its own process's environment, here the caller's,
    where every subprocess the caller starts afterwards would inherit them (one BLAS thread, another
    hash seed). The workers have their copies already; a nanny sets them again before a restart."""
    for name in set(os.environ) - set(saved):
        del os.environ[name]
    for name, value in saved.items():
        if os.environ.get(name) != value:
            os.environ[name] = value
