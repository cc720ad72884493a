"""The forked reader of MAT v5 and HDF5 files ends even when its parent is killed."""
import os
import signal
import subprocess
import sys
import time

import pytest

_SCRIPT = """
import os, sys
from modal.io._isolate import call_isolated

def hang(path):
    with open(path, "w") as f:
        f.write(str(os.getpid()))
    while True:  # a reader stuck for ever (libhdf5 looping on a damaged file)
        pass

call_isolated(hang, (sys.argv[1],), "x.h5", "HDF5 file", timeout_s=1.0)
"""


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    # a zombie (ended, not yet reaped by init) counts as ended
    try:
        with open(f"/proc/{pid}/stat") as f:
            return f.read().split(")")[-1].split()[0] != "Z"
    except OSError:
        return True


@pytest.mark.skipif(not hasattr(signal, "alarm") or sys.platform != "linux", reason="POSIX fork and /proc")
def test_orphaned_reader_ends_itself(tmp_path):
    # the stress fuzzer killed its reader after 5 s; the reader's own forked child, hung in
    # libhdf5, then lived on as an orphan spinning at full CPU (dozens of them). The child
    # now ends by SIGALRM 2 s after its parent's deadline, whatever happened to the parent.
    pid_file = tmp_path / "pid"
    proc = subprocess.Popen([sys.executable, "-c", _SCRIPT, str(pid_file)])
    deadline = time.monotonic() + 30
    while not (pid_file.exists() and pid_file.read_text()) and time.monotonic() < deadline:
        time.sleep(0.01)
    child = int(pid_file.read_text())
    proc.kill()  # the parent dies before its own 1 s deadline could end the child
    proc.wait()
    ends = time.monotonic() + 10  # alarm at ceil(1) + 2 = 3 s after the child started
    while _alive(child) and time.monotonic() < ends:
        time.sleep(0.05)
    alive = _alive(child)
    if alive:
        os.kill(child, signal.SIGKILL)
    assert not alive


@pytest.mark.skipif(sys.platform != "linux", reason="POSIX fork")
def test_readers_work_in_a_daemonic_process(tmp_path):
    """multiprocessing refuses children to daemonic processes (a Pool's workers, the worker processes
    of Dask's nannies): the reader's child is forked with os.fork itself, so MAT and HDF5 files read there."""
    import multiprocessing

    import numpy as np

    from modal import read_frf, write_frf
    from modal.synthetic import modal_frf

    frf = modal_frf(np.linspace(10.0, 100.0, 91), [40.0], [0.02], [1.0], kind="mobility")
    paths = [str(tmp_path / "a.mat"), str(tmp_path / "a.h5")]
    for path in paths:
        write_frf(frf, path)
    with multiprocessing.get_context("fork").Pool(1) as pool:  # its worker is daemonic
        back = pool.map(read_frf, paths)
    for item in back:
        np.testing.assert_array_equal(item.response, frf.response)


def _allocate_too_much(n_bytes):
    raise MemoryError(f"Unable to allocate {n_bytes} bytes")


@pytest.mark.skipif(not hasattr(os, "fork"), reason="POSIX fork")
def test_a_reader_out_of_memory_is_a_memory_error_not_a_damaged_file():
    # running out of memory says nothing about the file: the batch's fitting process reports it as
    # "out of memory" (to be retried with more), never as a damaged file (kept as the file's verdict)
    from modal.errors import FormatError
    from modal.io._isolate import call_isolated

    with pytest.raises(MemoryError, match="Unable to allocate 80000000 bytes") as caught:
        call_isolated(_allocate_too_much, (80_000_000,), "x.h5", "HDF5 file")
    assert not isinstance(caught.value, FormatError)
