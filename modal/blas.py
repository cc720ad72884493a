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

from contextlib import contextmanager
from typing import Iterator

__all__ = ["one_blas_thread"]

_controller = None


@contextmanager
def one_blas_thread() -> Iterator[None]:
    """Run the block (or, as a decorator, the function) with one BLAS thread."""
    global _controller
    if _controller is None:
        import scipy.linalg  # noqa: F401  (scipy's own BLAS is loaded with it: found below, as numpy's is)
        from threadpoolctl import ThreadpoolController

        _controller = ThreadpoolController()  # the BLAS libraries loaded by now
    with _controller.limit(limits=1, user_api="blas"):
        yield
