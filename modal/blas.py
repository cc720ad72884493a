"""One BLAS thread for computations made of many small matrix products.

Operational analysis does thousands of small products (one per frequency line and block for the
correlations, per block and order for the error bars). An OpenBLAS that uses a thread per core for each of
them spends more time waking its threads and waiting for them than computing: ``modal.oma`` on 10⁶ samples ×
64 channels took 0.74 s with one thread and 1.09 s (1.86 s of CPU) with two on an idle 2-core machine, and
8-12 s when other processes held the cores (benchmarks/REPORT.md, operational analysis, run 9).
:func:`one_blas_thread` limits whichever BLAS numpy and scipy loaded (threadpoolctl finds them) for the call
only, and gives the caller's setting back after it. :func:`modal.identify` runs with it too: its fits (band
by band, or the global method's) are small products as well; on 48 channels × 4000 lines a BLAS thread per
core cost 3-6 times the CPU and wall time of one thread on a loaded 2-core machine.
"""
from __future__ import annotations

import sys
from contextlib import contextmanager
from typing import Iterator

__all__ = ["one_blas_thread"]

_controller = None
_controller_has_scipy = False


@contextmanager
def one_blas_thread() -> Iterator[None]:
    """Run the block (or, as a decorator, the function) with one BLAS thread.

    The BLAS libraries limited are those loaded by the call: numpy's, and scipy's once ``scipy.linalg`` is
    (identification does without it: importing it only to limit its BLAS cost 0.2 CPU-s per process).
    """
    global _controller, _controller_has_scipy
    has_scipy = "scipy.linalg" in sys.modules
    if _controller is None or (has_scipy and not _controller_has_scipy):
        from threadpoolctl import ThreadpoolController

        _controller = ThreadpoolController()  # the BLAS libraries loaded by now
        _controller_has_scipy = has_scipy
    # the libraries' own setters, not threadpoolctl's limit(): that reads every library's whole info on each
    # entry (0.17 ms, against 2 µs for a setter; identification enters once per call); and a library already
    # at one thread (OPENBLAS_NUM_THREADS=1) is left as it is
    blas = [lib for lib in _controller.lib_controllers if lib.user_api == "blas"]
    before = [lib.get_num_threads() for lib in blas]
    for lib, threads in zip(blas, before):
        if threads != 1:
            lib.set_num_threads(1)
    try:
        yield
    finally:
        for lib, threads in zip(blas, before):
            if threads is not None and threads != 1:
                lib.set_num_threads(threads)
