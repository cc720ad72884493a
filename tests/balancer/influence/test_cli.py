"""The `influence` command (balancer.influence.cli): once in a subprocess as users run it, otherwise in-process."""
from __future__ import annotations

import json
import os
import subprocess
import sys

import numpy as np
import pytest

import balancer.cli
from support.cli import run_main
from support.paths import ROOT
from support.balancing import READINGS


def run_process(*args, cwd=ROOT):
    """``python -m balancer ARGS`` in a subprocess, as a user runs it."""
    env = dict(os.environ, PYTHONPATH=str(ROOT), MPLBACKEND="Agg")
    return subprocess.run([sys.executable, "-m", "balancer", *args], capture_output=True, text=True, cwd=cwd, env=env,
                          timeout=120)


def run_cli(*args, cwd=ROOT):
    """``python -m balancer ARGS`` in this process (``balancer.cli.main``, which the subprocess runs too)."""
    return run_main(balancer.cli.main, args, cwd=cwd, program="balancer")


def test_influence_command_line(tmp_path):
    out = run_process("influence", str(READINGS), "--method", "minmax", "--grade", "2.5", "--rotor-mass", "100",
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


def test_readings_echo_as_given_and_every_output_writes_micrometres(tmp_path):
    """A reading given as 3.8 um comes back as 3.8, not 3.7999999999999994 (carried through SI and back), and the unit
    is µm in the JSON, the table and the scene's summary alike."""
    import tomllib

    given = tomllib.loads(READINGS.read_text())
    doc = json.loads(run_cli("influence", str(READINGS), "--json").stdout)
    assert [r["initial_amplitude"] for r in doc["readings"]] == given["initial"]["amplitude"]
    assert [r["initial_phase_deg"] for r in doc["readings"]] == given["initial"]["phase_deg"]
    assert doc["reading_units"] == "µm"
    text = run_cli("influence", str(READINGS)).stdout
    assert " µm" in text and " um" not in text
    from balancer import run_scene
    from support.balancing import inline_scene

    summary = run_scene(inline_scene(tmp_path), out=tmp_path / "b.h5", plots_dir=tmp_path / "plots").summary
    assert "µm predicted" in summary and " um" not in summary


def test_the_split_is_rounded_to_the_weight_resolution(tmp_path):
    """--weight-resolution (or weight_resolution in the file, in its mass units): every mass on a hole is a multiple
    of the step, written as such, and the rounded split still makes the correction to within a step per hole."""
    step = 0.5
    raw = json.loads(run_cli("influence", str(READINGS), "--holes", "12", "--json").stdout)
    assert any(h["mass"] < step / 2 for row in raw["split"] for h in row)  # a sliver of a gram without rounding
    doc = json.loads(run_cli("influence", str(READINGS), "--holes", "12", "--weight-resolution", str(step),
                             "--json").stdout)
    assert doc["weight_resolution"] == step
    for row, correction in zip(doc["split"], doc["correction"]):
        masses = np.array([h["mass"] for h in row])
        assert np.all(masses > 0) and np.all(masses / step == np.round(masses / step)), masses
        made = sum(h["mass"] * np.exp(1j * np.deg2rad(h["hole_deg"])) for h in row)
        wanted = correction["mass"] * np.exp(1j * np.deg2rad(correction["angle_deg"]))
        assert abs(made - wanted) <= step / 2 * 2  # each of at most two holes off by half a step at most
    text = run_cli("influence", str(READINGS), "--holes", "12", "--weight-resolution", str(step)).stdout
    assert "(to 0.5 g)" in text
    (tmp_path / "job.toml").write_text("weight_resolution = 0.5\nholes = 12\n" + READINGS.read_text())
    assert json.loads(run_cli("influence", str(tmp_path / "job.toml"), "--json").stdout)["split"] == doc["split"]
    bad = run_cli("influence", str(READINGS), "--holes", "12", "--weight-resolution", "0")
    assert bad.returncode == 1 and "--weight-resolution = 0.0: expected the step of the weights at hand, a mass > 0 in g" \
        in bad.stderr
    (tmp_path / "bad.toml").write_text("weight_resolution = -1\n" + READINGS.read_text())
    bad = run_cli("influence", str(tmp_path / "bad.toml"), "--holes", "12")
    assert bad.returncode == 1 and "bad.toml: weight_resolution = -1: expected" in bad.stderr
