"""support.forkserver: scripts run in forked copies of an interpreter that ran a preload once."""
from __future__ import annotations

import signal
import subprocess

import pytest

from support.forkserver import ForkServer

#: a preload that makes state the scripts then see, and counts the forks made through os.fork (as
#: tests/balancer/scene/test_plotter.py's prelude does): the server's own forks must not count
PRELUDE = """
import os, sys
seen, forks = [], [0]
os.fork = lambda fork=os.fork: forks.__setitem__(0, forks[0] + 1) or fork()
print("the preload's own output")
"""


@pytest.fixture(scope="module")
def server():
    running = ForkServer(PRELUDE)
    yield running
    running.close()


def test_each_script_starts_from_the_preload_and_leaves_nothing_for_the_next(server, tmp_path):
    first = server.run("seen.append(sys.argv[1:]); import os; print(seen, forks[0], os.getcwd())", ["a", 1],
                       cwd=tmp_path)
    assert first.returncode == 0 and first.stdout == f"[['a', '1']] 0 {tmp_path.resolve()}\n"  # no server fork counted
    second = server.run("print(seen, forks[0])")
    assert second.stdout == "[] 0\n" and second.stderr == ""


def test_exit_codes_signals_and_tracebacks_come_back_as_from_a_subprocess(server):
    assert server.run("import sys; sys.exit(3)").returncode == 3
    said = server.run("import sys; sys.exit('no way')")
    assert (said.returncode, said.stderr) == (1, "no way\n")
    crashed = server.run("import os, signal; os.kill(os.getpid(), signal.SIGSEGV)")
    assert crashed.returncode == -signal.SIGSEGV
    failed = server.run("print('before'); raise ValueError('boom')")
    assert failed.returncode == 1 and failed.stdout == "before\n" and "ValueError: boom" in failed.stderr
    assert server.run("print('still serving')").stdout == "still serving\n"


def test_a_script_past_its_timeout_is_killed_and_the_server_serves_on(server):
    with pytest.raises(subprocess.TimeoutExpired):
        server.run("import time; time.sleep(60)", timeout=0.3)
    assert server.run("print(forks[0])").stdout == "0\n"
