"""The check that a test run leaves the checkout clean (support.checkout, registered by tests/conftest.py) sees what
a run writes, and fails the run that left something."""
import os
import subprocess
import sys
from pathlib import Path

import pytest

from support.checkout import left_behind, snapshot


def _git(folder, *args):
    subprocess.run(["git", *args], cwd=folder, check=True, capture_output=True)


@pytest.fixture
def checkout(tmp_path):
    """A git checkout with a commit, an ignored out/ folder already there and a virtual environment."""
    _git(tmp_path, "init", "-q")
    (tmp_path / ".gitignore").write_text("out/\n.venv/\n__pycache__/\n")
    (tmp_path / "module.py").write_text("x = 1\n")
    (tmp_path / "edited.py").write_text("y = 1\n")
    _git(tmp_path, "add", ".")
    _git(tmp_path, "-c", "user.name=t", "-c", "user.email=t@t", "commit", "-qm", "start")
    (tmp_path / "out").mkdir()
    (tmp_path / "out" / "demo.h5").write_bytes(b"an earlier run's archive")
    (tmp_path / ".venv" / "lib").mkdir(parents=True)
    (tmp_path / "edited.py").write_text("y = 2\n")  # work in progress before the run
    (tmp_path / "draft.py").write_text("z = 1\n")
    return tmp_path


def test_files_a_run_writes_into_the_checkout_are_found(checkout):
    before = snapshot(checkout)
    assert before is not None and left_behind(before, snapshot(checkout)) == []
    # what a run may make: caches and the virtual environment's files
    (checkout / "__pycache__").mkdir()
    (checkout / "__pycache__" / "module.cpython-311.pyc").write_bytes(b"cache")
    (checkout / ".venv" / "lib" / "site.py").write_text("")
    # a person editing sources already changed or new while the suite runs is not blamed on the tests
    (checkout / "edited.py").write_text("y = 3\n")
    (checkout / "draft.py").write_text("z = 2\n")
    assert left_behind(before, snapshot(checkout)) == []
    # what it may not: a file in an ignored folder that was there, one rewritten there, a new folder, a changed
    # clean tracked file
    os.utime(checkout / "out" / "demo.h5", ns=(0, 0))
    (checkout / "out" / "inline.h5").write_bytes(b"archive")
    (checkout / "out" / "inline_plots").mkdir()
    (checkout / "out" / "inline_plots" / "balance_polar.png").write_bytes(b"png")
    (checkout / "scratch").mkdir()
    (checkout / "scratch" / "note.txt").write_text("left")
    (checkout / "module.py").write_text("x = 2\n")
    left = left_behind(before, snapshot(checkout))
    paths = {entry[3:].split(" (")[0] for entry in left}
    assert paths == {"out/demo.h5", "out/inline.h5", "out/inline_plots/balance_polar.png", "scratch/note.txt",
                     "module.py"}, left


def test_outside_a_checkout_nothing_is_claimed(tmp_path):
    assert snapshot(tmp_path) is None and left_behind(None, set()) == []


def test_a_run_that_leaves_a_file_fails_and_names_it(checkout):
    """The plugin as the suite uses it, in a pytest run of its own on the small checkout: a clean run passes, a run
    whose test writes into the checkout fails (exit 1 though every test passed) and names the file."""
    tests = Path(__file__).resolve().parent
    (checkout / "conftest.py").write_text(
        "from pathlib import Path\nfrom support.checkout import CheckoutGuard\n\n\n"
        "def pytest_configure(config):\n    config.pluginmanager.register(CheckoutGuard(Path(__file__).parent))\n")
    (checkout / "test_clean.py").write_text("def test_writes_under_tmp(tmp_path):\n"
                                            "    (tmp_path / 'a.h5').write_bytes(b'x')\n")
    (checkout / "test_messy.py").write_text("from pathlib import Path\n\n\ndef test_writes_into_the_checkout():\n"
                                            "    (Path(__file__).parent / 'out' / 'left.h5').write_bytes(b'x')\n")
    env = {**os.environ, "PYTHONPATH": str(tests)}

    def pytest_run(test):
        return subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", test], cwd=checkout,
                              capture_output=True, text=True, env=env, timeout=120)

    clean = pytest_run("test_clean.py")
    assert clean.returncode == 0, clean.stdout + clean.stderr
    messy = pytest_run("test_messy.py")
    assert messy.returncode == 1 and "1 passed" in messy.stdout, messy.stdout + messy.stderr
    assert "left 1 new or changed file(s) in the checkout" in messy.stdout and "out/left.h5" in messy.stdout
