"""balancer is laid out one package per study, with one way to import each module.

The modules that moved into ``balancer.compressor`` and ``balancer.drive`` are imported from there
only; archives written before the move (whose ``@__class__`` names the old module) still read,
through the archive layer's table of moved classes.
"""
from __future__ import annotations

import dataclasses
import importlib

import h5py
import numpy as np
import pytest
from support.import_graph import import_cycles, import_graph, package_modules
from support.paths import ROOT

from modal.archive import RENAMED_CLASSES, read_archive

HERE = ROOT / "tests" / "balancer" / "data"
OLD_PATHS = ("balancer.crank", "balancer.crank.model", "balancer.mounts", "balancer.crank_plots", "balancer.shaft",
             "balancer.shaft.handover", "balancer.drive_report", "balancer._moved")


@pytest.mark.parametrize("old", OLD_PATHS)
def test_old_import_paths_are_gone(old):
    with pytest.raises(ModuleNotFoundError):
        importlib.import_module(old)


def test_every_moved_class_has_its_present_home_in_the_archive_table():
    balancer = {old: new for old, new in RENAMED_CLASSES.items() if old.startswith("balancer.")}
    assert balancer  # the crank, mounts, shaft, belt and report classes
    for old, new in balancer.items():
        module, _, qualname = new.partition(":")
        cls = getattr(importlib.import_module(module), qualname)
        # the target is where the class is defined (what a new archive writes), not a re-export
        assert f"{cls.__module__}:{cls.__qualname__}" == new, old
        assert dataclasses.is_dataclass(cls)
        assert old.rpartition(":")[2] == qualname


def test_archive_written_before_the_move_reads_back_as_the_present_classes(tmp_path):
    archive = HERE / "archive_before_package_layout.h5"
    with h5py.File(archive, "r") as f:
        written = set()
        f.visititems(lambda _name, node: written.add(str(node.attrs.get("__class__", ""))))
    # the file names the old homes, so the table (not the modules' present names) makes it read
    assert {"balancer.crank.model:SliderCrank", "balancer.mounts:MountedBody", "balancer.drive:BeltDrive",
            "balancer.shaft.handover:RotorHandover"} <= written
    old = read_archive(archive)

    from balancer.compressor.crank import OptimalCounterweight, SliderCrank
    from balancer.compressor.mounts import MountedBody
    from balancer.drive.belt import BeltDrive
    from balancer.drive.shaft import RotorHandover
    from balancer.scene import run_scene

    assert type(old["compressor"].mechanism) is SliderCrank
    assert type(old["compressor"].optimum) is OptimalCounterweight
    assert type(old["mounts"].system) is MountedBody
    assert type(old["drive"].drive) is BeltDrive and type(old["drive"].handover) is RotorHandover
    # and it is the same study: the same scene run now has the same inputs and results
    now = run_scene(HERE / "scene_before_package_layout.toml", out=tmp_path / "now.h5")
    assert now.inputs_hash == old.inputs_hash
    _assert_close(old["compressor"], now.results["compressor"], rtol=0.0, where="compressor")
    _assert_close(old["drive"], now.results["drive"], rtol=0.0, where="drive")
    # the mounts' 6 x 6 eigenproblem has since been solved in numpy instead of scipy.linalg:
    # the same numbers to rounding (a few ulp of the largest entry, amplified by at most the
    # condition of the mass and stiffness matrices, < 1e3 here)
    _assert_close(old["mounts"], now.results["mounts"], rtol=1e-12)


def _assert_close(a, b, rtol, where="mounts"):
    """Equal results; float arrays within ``rtol`` times their largest entry (0: the same numbers)."""
    if dataclasses.is_dataclass(a):
        assert type(a) is type(b), where
        for f in dataclasses.fields(a):
            _assert_close(getattr(a, f.name), getattr(b, f.name), rtol, f"{where}.{f.name}")
    elif isinstance(a, (tuple, list)):
        assert len(a) == len(b), where
        for i, (x, y) in enumerate(zip(a, b)):
            _assert_close(x, y, rtol, f"{where}[{i}]")
    elif isinstance(a, np.ndarray) and a.dtype.kind in "fc":
        scale = np.max(np.abs(b)) if b.size else 0.0
        np.testing.assert_allclose(a, b, rtol=0, atol=rtol * scale, err_msg=where)
    else:
        assert np.array_equal(a, b), where


def test_drive_names_importable_from_balancer_drive():
    from balancer import drive
    from balancer.drive import belt

    assert set(belt.__all__) <= set(dir(drive))
    assert drive.belt_stage is belt.belt_stage


def test_no_import_cycle_inside_balancer():
    graph = import_graph(ROOT, "balancer")
    assert graph["balancer.scene.runner"]  # the graph is read (function-local imports included)
    assert import_cycles(graph) == []


def test_import_cycles_are_found_when_there_is_one():
    assert import_cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]
    assert import_cycles({"a": {"b"}, "b": set()}) == []


def test_no_balancer_module_is_over_750_lines():
    long = {name: n for name, (path, _) in package_modules(ROOT, "balancer").items()
            if (n := len(path.read_text(encoding="utf-8").splitlines())) > 750}
    assert long == {}


def test_no_project_bookkeeping_in_balancer_code_or_its_tests():
    # comments say what the code does; issue, goal and finding numbers go stale
    import re

    pattern = re.compile(r"\b(issue|goal|finding)\s*#?\d+", re.IGNORECASE)
    files = sorted((ROOT / "balancer").rglob("*.py")) + sorted((ROOT / "tests" / "balancer").rglob("*.py"))
    found = [f"{path.relative_to(ROOT)}:{number}" for path in files
             for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1) if pattern.search(line)]
    assert found == []
