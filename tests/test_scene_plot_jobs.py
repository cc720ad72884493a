"""Plots drawn in a forked child while the scene runs on (issue 19 goal 4): same files."""
from __future__ import annotations

import os
from pathlib import Path

import pytest

from balancer.scene import run_scene

DEMO = Path(__file__).resolve().parent.parent / "data" / "synthetic" / "demo_scene.toml"
pytestmark = pytest.mark.skipif(not hasattr(os, "fork"), reason="plot_jobs > 1 needs os.fork (POSIX)")


def test_plots_from_child_processes_are_the_same_files(tmp_path):
    serial = run_scene(DEMO, out=tmp_path / "a.h5", plots_dir=tmp_path / "a")
    forked = run_scene(DEMO, out=tmp_path / "b.h5", plots_dir=tmp_path / "b", plot_jobs=2)
    names = [Path(p).name for p in serial.plot_paths]
    assert names == [Path(p).name for p in forked.plot_paths] and len(names) == 6
    for name in names:  # Agg output is deterministic: byte for byte
        assert (tmp_path / "a" / name).read_bytes() == (tmp_path / "b" / name).read_bytes(), name
    assert not list((tmp_path / "b").glob("*.tmp"))
    assert forked.summary.replace("b.h5", "a.h5").replace(str(tmp_path / "b"), str(tmp_path / "a")).splitlines()[-3:] \
        == serial.summary.splitlines()[-3:]


@pytest.mark.parametrize("jobs", [1, 2])
def test_a_failing_plot_is_reported_with_its_stage(tmp_path, monkeypatch, jobs):
    from balancer.scene import plots

    def broken(results):
        raise ValueError("no figure today")

    # with 2 jobs the identify plot is handed to a child as soon as its stage is done (no child is running
    # yet then) when forking is usable (no other thread in the process: a Dask cluster of another test in the
    # same session makes it draw here instead); wherever it is drawn, the failure reaches the caller the same way
    monkeypatch.setitem(plots._FIGURES, "identify", broken)
    with pytest.raises(RuntimeError, match="plots of identify.*ValueError: no figure today"):
        run_scene(DEMO, out=tmp_path / "c.h5", plots_dir=tmp_path / "c", plot_jobs=jobs)
