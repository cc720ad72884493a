"""support.cli.run_main: a command line's main in-process gives what its subprocess gives, and leaves no trace;
support.cli.run_module: ``python -m PROGRAM`` in-process."""
from __future__ import annotations

import subprocess
import sys
import warnings

import modal.cli
from support.cli import run_main, run_module
from support.paths import ROOT, SYNTHETIC


def test_usage_errors_and_messages_are_those_of_the_subprocess():
    # argparse's usage error (SystemExit 2) and a command's one-line error (exit 1) come back as a subprocess's
    for args in (["fit"], ["fit", str(SYNTHETIC / "no_such_file.csv")]):
        here = run_main(modal.cli.main, args)
        there = subprocess.run([sys.executable, "-m", "modal", *args], capture_output=True, text=True, cwd=ROOT,
                               timeout=120)
        assert (here.returncode, here.stdout, here.stderr) == (there.returncode, there.stdout, there.stderr)
        assert here.returncode in (1, 2) and here.stderr


def test_printed_warnings_are_captured_and_the_filters_restored():
    # main() replaces warnings.showwarning with its one-line printer; the suite's filters turn warnings into
    # errors: inside the call a warning is printed to the captured stderr, afterwards both are as before
    def main(argv):
        warnings.showwarning = lambda message, *a, **k: print(f"warning: {message}", file=sys.stderr)
        warnings.warn("a structural warning", UserWarning)
        print("done")
        return 0

    shown, filters = warnings.showwarning, list(warnings.filters)
    done = run_main(main, ["x"])
    assert (done.returncode, done.stdout, done.stderr) == (0, "done\n", "warning: a structural warning\n")
    assert warnings.showwarning is shown and warnings.filters == filters


def test_run_module_runs_the_named_programs_main():
    # `balancer run` reads a scene (a missing file: its one-line error, exit 1); `modal` has no `run` (usage, exit 2)
    scene = run_module("balancer", "run", "no_such_scene.toml")
    assert (scene.returncode, scene.stderr) == (1, "error: no_such_scene.toml: no such scene file\n")
    assert scene.args == ["python", "-m", "balancer", "run", "no_such_scene.toml"]
    usage = run_module("modal", "run", "no_such_scene.toml")
    assert usage.returncode == 2 and "python -m modal: error: argument command: invalid choice: 'run'" in usage.stderr
