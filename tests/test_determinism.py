"""Determinism: the same inputs and seed give bit-identical results and archives.

Identification is compared field by field with ``np.array_equal`` (NaN equal to
NaN), within one process and across processes started with different
``PYTHONHASHSEED`` values (set iteration order must not leak into results).
Archives are compared byte for byte when written with a fixed ``created``
attribute, and scene archives (which stamp the current time) byte for byte after
that one attribute's bytes are blanked in both files.
"""
from __future__ import annotations

import dataclasses
import hashlib
import os
import subprocess
import sys
import warnings
from pathlib import Path

import h5py
import numpy as np
import pytest

import modal
from modal import add_noise, identify, matrix_frf, modal_frf
from modal.archive import read_archive, write_archive

from support.paths import ROOT, SYNTHETIC


def _frfs():
    f = np.linspace(5.0, 400.0, 3001)
    single = add_noise(modal_frf(f, [50.0, 120.0, 300.0], [0.01, 0.02, 0.03], [1.0, 0.5, 2.0], kind="mobility"),
                       0.01, seed=3)
    M = np.diag([2.0, 1.0, 1.5])
    K = np.array([[4e4, -2e4, 0], [-2e4, 5e4, -3e4], [0, -3e4, 3e4]])
    multi = add_noise(matrix_frf(np.linspace(1, 80, 2500), M, 2.0 * M + 2e-5 * K, K, kind="accelerance"),
                      0.005, seed=11)
    return {"single": single, "multi": multi}


def _identify_all():
    out = {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", modal.ModalWarning)
        for name, frf in _frfs().items():
            for method in modal.METHODS:
                out[(name, method)] = identify(frf, method)
    return out


def _flatten(obj, prefix=""):
    """Every leaf of a result as (path, ndarray or scalar)."""
    if dataclasses.is_dataclass(obj):
        for f in dataclasses.fields(obj):
            yield from _flatten(getattr(obj, f.name), f"{prefix}.{f.name}")
    elif isinstance(obj, (tuple, list)):
        for i, item in enumerate(obj):
            yield from _flatten(item, f"{prefix}[{i}]")
    else:
        yield prefix, obj


def _same(a, b) -> bool:
    if isinstance(a, (str, bool, type(None))):
        return a == b
    a, b = np.asarray(a), np.asarray(b)
    if a.dtype.kind in "fc":
        return a.dtype == b.dtype and np.array_equal(a, b, equal_nan=True) and np.array_equal(
            np.signbit(a.real), np.signbit(b.real))
    return bool(np.array_equal(a, b))


def _digest(results) -> str:
    h = hashlib.sha256()
    for key in sorted(results):
        for path, leaf in _flatten(results[key], str(key)):
            h.update(path.encode())
            arr = np.asarray(leaf)
            h.update(arr.tobytes() if arr.dtype.kind in "fcib" else repr(leaf).encode())
    return h.hexdigest()


def test_identification_is_bit_identical_in_one_process():
    first, second = _identify_all(), _identify_all()
    for key in first:
        for (path, a), (_, b) in zip(_flatten(first[key], str(key)), _flatten(second[key], str(key))):
            assert _same(a, b), path


_SCRIPT = """
import sys, warnings
sys.path.insert(0, {tests!r})
import test_determinism as t
print(t._digest(t._identify_all()))
"""


@pytest.mark.slow
def test_identification_is_bit_identical_across_processes_and_hash_seeds():
    digests = set()
    for hash_seed in ("0", "12345"):
        env = {**os.environ, "PYTHONHASHSEED": hash_seed, "MPLBACKEND": "Agg"}
        out = subprocess.run([sys.executable, "-c", _SCRIPT.format(tests=str(ROOT / "tests"))], cwd=ROOT, env=env,
                             capture_output=True, text=True, timeout=300)
        assert out.returncode == 0, out.stderr
        digests.add(out.stdout.strip().splitlines()[-1])
    digests.add(_digest(_identify_all()))
    assert len(digests) == 1, digests


def test_archives_are_bit_identical_with_a_fixed_creation_time(tmp_path):
    results = _identify_all()
    items = {"frf": _frfs()["multi"], "identify": results[("multi", "nls")],
             "circle": results[("single", "circle")], "array": np.arange(5000.0)}  # > 16 kB: compressed
    a = write_archive(tmp_path / "a.h5", items, scene_text="[scene]\nname = 'x'\n", created="fixed")
    b = write_archive(tmp_path / "b.h5", items, scene_text="[scene]\nname = 'x'\n", created="fixed")
    assert a.read_bytes() == b.read_bytes()
    back = read_archive(a)
    for (path, x), (_, y) in zip(_flatten(back["identify"], "identify"), _flatten(items["identify"], "identify")):
        assert _same(x, y), path


def _strip_created(path: Path) -> bytes:
    """File bytes with the creation time blanked.

    Deleting the attribute is not enough: a variable-length string lives in the
    file's global heap, which keeps its bytes. So the timestamp's bytes (it occurs
    once) are overwritten with a same-length filler instead.
    """
    with h5py.File(path, "r") as f:
        created = f.attrs["created"]  # the one attribute allowed to differ
    created = created.encode() if isinstance(created, str) else bytes(created)
    data = path.read_bytes()
    assert data.count(created) == 1
    return data.replace(created, b"#" * len(created))


SMALL_SCENE = """
[scene]
name = "determinism"
[frf.synthetic]
natural_frequency_hz = [15.6, 120.0]
damping_ratio = [0.05, 0.02]
modal_constant = [0.5, 0.2]
kind = "accelerance"
f_max_hz = 200.0
n_lines = 2001
noise = 0.01
seed = 4
[identify]
method = "nls"
[compressor]
crank_radius_m = 0.0119
rod_length_m = 0.050
rotating_mass_kg = 0.096656
reciprocating_mass_kg = 0.148344
speed_rpm = 2950.0
[outputs]
tables = ["identify", "compressor"]
archive = true
"""


def _run_twice(scene: Path, tmp_path: Path) -> tuple[bytes, bytes]:
    import balancer

    paths = []
    for name in ("one", "two"):
        out = tmp_path / f"{name}.h5"
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", modal.ModalWarning)
            balancer.run_scene(scene, out=out, plots_dir=tmp_path / f"{name}_plots")
        paths.append(out)
    return _strip_created(paths[0]), _strip_created(paths[1])


def test_scene_archives_are_bit_identical_but_for_the_creation_time(tmp_path):
    scene = tmp_path / "small.toml"
    scene.write_text(SMALL_SCENE)
    one, two = _run_twice(scene, tmp_path)
    assert one == two


@pytest.mark.stress
def test_stress_demo_scene_archives_are_bit_identical_but_for_the_creation_time(tmp_path):
    one, two = _run_twice(SYNTHETIC / "demo_scene.toml", tmp_path)
    assert one == two
