"""The `influence` command (balancer.influence.cli), run as users run it."""
from __future__ import annotations

import json
import os
import subprocess
import sys

import numpy as np
import pytest

from support.paths import ROOT
from support.balancing import READINGS


def run_cli(*args, cwd=ROOT):
    env = dict(os.environ, PYTHONPATH=str(ROOT), MPLBACKEND="Agg")
    return subprocess.run([sys.executable, "-m", "balancer", *args], capture_output=True, text=True, cwd=cwd, env=env,
                          timeout=120)


def test_influence_command_line(tmp_path):
    out = run_cli("influence", str(READINGS), "--method", "minmax", "--grade", "2.5", "--rotor-mass", "100",
                  "--speed-rpm", "3000", "--holes", "8", "--json")
    assert out.returncode == 0, out.stderr
    doc = json.loads(out.stdout)
    assert doc["method"] == "minmax" and doc["mass_units"] == "g" and len(doc["correction"]) == 2
    assert doc["iso"]["verdict"] in ("pass", "fail") and len(doc["iso"]["permissible_per_plane_kg_m"]) == 2
    assert doc["iso"]["permissible_unbalance_kg_m"] == pytest.approx(2.5e-3 * 100 / (3000 * np.pi / 30), rel=1e-12)
    assert all(len(row) <= 2 for row in doc["split"])
    ls = json.loads(run_cli("influence", str(READINGS), "--json").stdout)
    assert doc["worst_residual"] <= ls["worst_residual"] * (1 + 1e-9)
    text = run_cli("influence", str(READINGS))
    assert text.returncode == 0 and "plane 1:" in text.stdout and "condition number" in text.stdout
    (tmp_path / "bad.toml").write_text(READINGS.read_text().replace("units = \"um\"", "units = \"furlong\""))
    bad = run_cli("influence", str(tmp_path / "bad.toml"))
    assert bad.returncode == 1 and bad.stderr.count("\n") == 1 and "units" in bad.stderr and "bad.toml" in bad.stderr
    assert run_cli("influence").returncode == 2
