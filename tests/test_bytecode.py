"""The run's bytecode cache (support.bytecode) where the environment forbids writing one."""
from __future__ import annotations

import subprocess
import sys

from support.bytecode import cache_outside_the_checkout
from support.paths import ROOT


def test_forbidden_bytecode_is_cached_in_a_temporary_folder_instead(tmp_path):
    environ = {"PYTHONDONTWRITEBYTECODE": "1", "PATH": "/bin"}
    prefix = cache_outside_the_checkout(environ, str(tmp_path))
    assert prefix is not None and prefix.startswith(str(tmp_path))
    assert environ == {"PATH": "/bin", "PYTHONPYCACHEPREFIX": prefix}


def test_an_environment_that_allows_bytecode_or_names_its_cache_is_kept(tmp_path):
    for environ in ({"PATH": "/bin"}, {"PYTHONDONTWRITEBYTECODE": "", "PATH": "/bin"},
                    {"PYTHONDONTWRITEBYTECODE": "1", "PYTHONPYCACHEPREFIX": "/elsewhere"}):
        before = dict(environ)
        assert cache_outside_the_checkout(environ, str(tmp_path)) is None
        assert environ == before


def test_the_runs_subprocesses_cache_bytecode_and_never_in_the_checkout():
    # what a CLI subprocess of this run inherits: bytecode written (else every one compiles the
    # sources again), and where PYTHONDONTWRITEBYTECODE kept it out of the sources, still out of them
    code = "import sys; print(int(sys.flags.dont_write_bytecode)); print(sys.pycache_prefix or '')"
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60, check=True)
    flag, prefix = done.stdout.splitlines()
    assert flag == "0"
    if prefix:
        assert not prefix.startswith(str(ROOT))
