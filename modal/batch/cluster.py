"""The Dask client of a batch: a given client, a scheduler address, or an embedded local cluster."""
from __future__ import annotations

import logging
import os
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

from ..errors import ModalError

__all__ = ["open_client", "default_workers"]


def default_workers() -> int:
    """Workers of the embedded cluster by default: the cores this process may use."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover - not on Linux
        return max(1, os.cpu_count() or 1)


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


@contextmanager
def open_client(client: Any = None, workers: int | None = None) -> Iterator[Any]:
    """Yield a ``distributed.Client``.

    Parameters
    ----------
    client : distributed.Client or str, optional
        A client (used as it is, left open) or a scheduler address (``tcp://HOST:PORT``,
        connected and closed). Default: a local cluster of worker processes, closed after.
    workers : int, optional
        Worker processes of the local cluster (one thread each); default :func:`default_workers`.

    Raises
    ------
    ModalError
        The scheduler cannot be reached.
    """
    from distributed import Client, LocalCluster

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
    n = workers or default_workers()
    with LocalCluster(n_workers=n, threads_per_worker=1, processes=True, dashboard_address=None,
                      silence_logs=logging.ERROR) as cluster, Client(cluster, set_as_default=False) as local:
        yield local
