"""Plots drawn in a forked child while the scene runs on (issue 19 goal 4).

Each case runs in a fresh interpreter: the test process may have threads alive (Dask
clients of other tests), and run_scene then rightly declines to fork.
"""
from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
DEMO = ROOT / "data" / "synthetic" / "demo_scene.toml"
pytestmark = pytest.mark.skipif(not hasattr(os, "fork"), reason="plot_jobs > 1 needs os.fork (POSIX)")

PRELUDE = f"""
import json, os, sys
sys.path.insert(0, {str(ROOT)!r})
forks = [0]
_fork = os.fork
def counting_fork():
    forks[0] += 1
    return _fork()
os.fork = counting_fork
from balancer.scene import run_scene, plots, stages
from modal.errors import SceneError
demo = {str(DEMO)!r}
"""


def _run(tmp_path: Path, body: str) -> dict:
    script = PRELUDE + body + "\nprint(json.dumps(out))\n"
    proc = subprocess.run([sys.executable, "-c", script], cwd=tmp_path, capture_output=True, text=True, timeout=300,
                          env={**os.environ, "MPLBACKEND": "Agg"})
    assert proc.returncode == 0, proc.stderr[-2000:]
    return json.loads(proc.stdout.strip().splitlines()[-1])


def test_plots_from_child_processes_are_the_same_files(tmp_path):
    out = _run(tmp_path, """
serial = run_scene(demo, out="a.h5", plots_dir="a")
before = forks[0]
forked = run_scene(demo, out="b.h5", plots_dir="b", plot_jobs=2)
out = {"serial": list(serial.plot_paths), "forked": list(forked.plot_paths), "forks": [before, forks[0]]}
""")
    assert out["forks"][0] == 0 and out["forks"][1] >= 1  # plot_jobs=2 did fork, the default did not
    names = [Path(p).name for p in out["serial"]]
    assert names == [Path(p).name for p in out["forked"]] and len(names) == 6
    for name in names:  # Agg output is deterministic: byte for byte
        assert (tmp_path / "a" / name).read_bytes() == (tmp_path / "b" / name).read_bytes(), name
    assert not list((tmp_path / "b").glob("*.tmp"))


def test_a_failing_plot_in_a_child_is_reported(tmp_path):
    # the identify plot is the one handed to a child as soon as its stage is done (no child
    # is running yet then), so the failure happens in the child and must reach the caller
    out = _run(tmp_path, """
def broken(results):
    raise ValueError("no figure today")
plots._FIGURES["identify"] = broken
try:
    run_scene(demo, out="c.h5", plots_dir="c", plot_jobs=2)
    out = {"error": None}
except RuntimeError as exc:
    out = {"error": str(exc), "forks": forks[0]}
""")
    assert out["forks"] >= 1
    assert "identify" in out["error"] and "ValueError: no figure today" in out["error"]


def test_a_failing_stage_leaves_no_plots_drawn_early(tmp_path):
    # the identify plot is drawn by a child while the later stages run; when one of them
    # fails, the run writes nothing: no archive and no plot (as without plot_jobs)
    out = _run(tmp_path, """
def broken(scene, **kwargs):
    raise SceneError("mounts: broken on purpose")
stages.STAGE_FUNCTIONS["mounts"] = broken
try:
    run_scene(demo, out="d.h5", plots_dir="d", plot_jobs=2)
    out = {"error": None}
except SceneError as exc:
    out = {"error": str(exc), "forks": forks[0]}
""")
    assert out["forks"] >= 1 and "broken on purpose" in out["error"]
    assert not (tmp_path / "d.h5").exists()
    assert not list((tmp_path / "d").glob("*"))


@pytest.mark.parametrize("jobs", [1, 2])
def test_a_failing_plot_is_reported_with_its_stage(tmp_path, monkeypatch, jobs):
    from balancer.scene import plots, run_scene

    def broken(results):
        raise ValueError("no figure today")

    # with 2 jobs the identify plot is handed to a child as soon as its stage is done (no child is running
    # yet then) when forking is usable (no other thread in the process: a Dask cluster of another test in the
    # same session makes it draw here instead); wherever it is drawn, the failure reaches the caller the same way
    monkeypatch.setitem(plots._FIGURES, "identify", broken)
    with pytest.raises(RuntimeError, match="plots of identify.*ValueError: no figure today"):
        run_scene(DEMO, out=tmp_path / "c.h5", plots_dir=tmp_path / "c", plot_jobs=jobs)



def test_every_stage_figure_declares_the_results_it_reads():
    # a plotting process is handed only runner._PLOT_INPUTS[stage] (the byte-for-byte test above shows the
    # demo's figures come out the same from that subset); a new figure must say what it reads
    from balancer.scene import plots, runner

    assert set(runner._PLOT_INPUTS) == set(plots._FIGURES)
    assert all(stage in inputs for stage, inputs in runner._PLOT_INPUTS.items())


def test_preloaded_modules_are_all_a_figure_imports(tmp_path):
    # the plotting process imports plots.PLOT_MODULES of its stages once, before it forks its helper; what
    # unpickling a stage's plot inputs and drawing them imports beyond that would be imported again by each
    # drawing process. Each stage's inputs are pickled by one run, then drawn in a fresh interpreter that
    # holds only what the parent has when it forks (the runner) and the preloaded modules.
    import pickle

    from balancer.scene import plots, run_scene, runner
    from test_scene import DRIVE

    scenes = [DEMO, ROOT / "data" / "synthetic" / "balance_scene.toml",
              {"scene": {"name": "drive"}, "drive": DRIVE, "outputs": {"plots": ["drive"]}}]
    pickled = {}
    for scene in scenes:
        run = run_scene(scene, out=tmp_path / "x.h5", plots_dir=tmp_path / "p")
        for stage in plots._FIGURES:
            if stage in run.results and stage not in pickled:
                given = {s: run.results[s] for s in runner._PLOT_INPUTS[stage] if s in run.results}
                pickled[stage] = str(tmp_path / f"{stage}.pickle")
                Path(pickled[stage]).write_bytes(pickle.dumps(given))
    assert set(pickled) == set(plots._FIGURES)  # every stage with figures is covered
    # each stage in a child of its own (forked after the runner's import), as a scene that plots only it
    out = _run(tmp_path, f"""
import pickle, balancer.scene.runner
from pathlib import Path
out = {{}}
for stage, path in {pickled!r}.items():
    read, write = os.pipe()
    if os.fork() == 0:
        plots.preload([stage])
        before = set(sys.modules)
        Path(stage).mkdir()
        plots.save_stage_plot(stage, pickle.loads(Path(path).read_bytes()), Path(stage))
        new = sorted(m for m in set(sys.modules) - before if m.split(".")[0] in ("modal", "balancer"))
        os.write(write, json.dumps(new).encode())
        os._exit(0)
    os.close(write)
    with os.fdopen(read) as report:
        out[stage] = json.loads(report.read() or '"no report"')
    os.wait()
""")
    assert out == {stage: [] for stage in pickled}
