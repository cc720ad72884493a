"""The scene command line (python -m balancer run): JSON output and exit codes."""
import json

import subprocess
import sys
import textwrap

from balancer.scene import STAGES

from support.cli import run_module


def test_cli_json_and_exit_codes(tmp_path):
    path = tmp_path / "s.toml"
    path.write_text(textwrap.dedent("""
        [compressor]
        crank_radius_m = 0.035
        rod_length_m = 0.140
        rotating_mass_kg = 0.55
        reciprocating_mass_kg = 1.13
        speed_rpm = 1000.0
        [outputs]
        tables = ["compressor"]
        """))
    cmd = [sys.executable, "-m", "balancer", "run", str(path), "--json", "--out", str(tmp_path / "o.h5")]
    out = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    # stdout is a pipe (block-buffered) and `run` leaves by os._exit after flushing: the whole document arrives
    doc = json.loads(out.stdout)
    assert doc["stages"] == {s: ("ran" if s == "compressor" else "skipped") for s in STAGES}
    assert doc["warnings"] == {}  # the stages' warnings, by stage: this compressor gives none
    # seed 004: 285.5 N at the optimum (crank_drive.md)
    assert abs(doc["results"]["compressor"]["max_force_n"] - 285.5) < 0.05
    path.write_text("[outputs]\ntables = ['compressor']\n")
    bad = run_module(*cmd[2:])  # the same main, in this process
    assert bad.returncode == 1 and bad.stderr.count("\n") == 1 and "s.toml" in bad.stderr
    usage = run_module("balancer", "run")
    assert usage.returncode == 2


def test_run_help_says_what_a_run_does():
    from balancer.cli import build_parser

    run = build_parser()._subparsers._group_actions[0].choices["run"]
    assert run.description and "scene" in run.description and "archive" in run.description
    assert "Run a scene" in run.format_help()
