"""balancer is laid out one package per study; the old import paths keep working.

The old names are the *same* module objects as the new ones (not copies), so
classes compare identical, monkeypatching through either path works and archives
written before the move (whose ``@__class__`` names the old module) still read.
"""
from __future__ import annotations

import importlib

import h5py
import pytest

from modal.archive import read_archive, write_archive

MOVED = {
    "balancer.crank": "balancer.compressor.crank",
    "balancer.crank.model": "balancer.compressor.crank.model",
    "balancer.crank.forces": "balancer.compressor.crank.forces",
    "balancer.crank.counterweight": "balancer.compressor.crank.counterweight",
    "balancer.mounts": "balancer.compressor.mounts",
    "balancer.crank_plots": "balancer.compressor.crank_plots",
    "balancer.shaft": "balancer.drive.shaft",
    "balancer.shaft.statics": "balancer.drive.shaft.statics",
    "balancer.shaft.sizing": "balancer.drive.shaft.sizing",
    "balancer.shaft.stiffness": "balancer.drive.shaft.stiffness",
    "balancer.shaft.handover": "balancer.drive.shaft.handover",
    "balancer.drive_report": "balancer.drive.report",
}


@pytest.mark.parametrize("old, new", sorted(MOVED.items()))
def test_old_import_path_is_the_new_module(old, new):
    assert importlib.import_module(old) is importlib.import_module(new)


def test_drive_names_still_importable_from_balancer_drive():
    from balancer import drive
    from balancer.drive import belt

    assert set(belt.__all__) <= set(dir(drive))
    assert drive.belt_stage is belt.belt_stage


def test_archive_naming_old_class_paths_reads_back(tmp_path):
    """An archive written before the move names e.g. ``balancer.crank.model:SliderCrank``."""
    from balancer.compressor.crank import SliderCrank

    mech = SliderCrank(crank_radius_m=0.0119, rod_length_m=0.05, rotating_mass_kg=0.1, reciprocating_mass_kg=0.15)
    path = tmp_path / "a.h5"
    write_archive(path, {"compressor": mech})
    with h5py.File(path, "r+") as f:
        assert f["compressor"].attrs["__class__"] == "balancer.compressor.crank.model:SliderCrank"
        f["compressor"].attrs["__class__"] = "balancer.crank.model:SliderCrank"
    assert read_archive(path)["compressor"] == mech
