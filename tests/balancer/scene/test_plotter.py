"""Plots drawn by forked plotting processes while the scene runs on (balancer.scene.plotter).

Each forking case runs in a fresh interpreter's process (a child of one forked per case, the fixture
``fresh``): the test process may have threads alive (Dask clients of other tests), and run_scene then
rightly declines to fork. The serial drawing they are compared with is one run of the demo scene in the
test process (serial_demo).
"""
from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from support.paths import ROOT  # noqa: E402
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
from balancer.scene import run_scene
from modal.errors import SceneError
demo = {str(DEMO)!r}
"""


@pytest.fixture(scope="module")
def fresh():
    """A fresh interpreter that has run :data:`PRELUDE` and forks a copy of itself for each case
    (support.forkserver): each case's process is the one ``python -c PRELUDE + case`` would be, without
    paying the interpreter's start and the prelude's imports again."""
    from support.forkserver import ForkServer

    server = ForkServer(PRELUDE, env={**os.environ, "MPLBACKEND": "Agg"})
    yield server
    server.close()


def _run(fresh, tmp_path: Path, body: str) -> dict:
    proc = fresh.run(body + "\nprint(json.dumps(out))\n", cwd=tmp_path, timeout=300)
    assert proc.returncode == 0, proc.stderr[-2000:]
    return json.loads(proc.stdout.strip().splitlines()[-1])


@pytest.fixture(scope="module")
def serial_demo(tmp_path_factory):
    """The demo scene run once here with the default ``plot_jobs`` (every figure drawn in this process): the
    files the forked, command-line and per-stage drawings are compared with, byte for byte. Returns the run
    and its plots folder, and the forks the run asked for: with forking allowed (``_can_fork`` true, as in a
    process without threads), each one recorded and refused."""
    from balancer.scene import plotter, run_scene

    folder = tmp_path_factory.mktemp("serial_demo")
    forks = []

    def refused_fork():
        forks.append(1)
        raise OSError("the default run must not fork")

    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(plotter, "_can_fork", lambda: True)
        patch.setattr(os, "fork", refused_fork)
        run = run_scene(DEMO, out=folder / "a.h5", plots_dir=folder / "a")
    return run, folder / "a", len(forks)


def test_plots_from_child_processes_are_the_same_files_and_the_parent_never_draws(fresh, tmp_path, serial_demo):
    # the forked run in a fresh interpreter: the parent computes while its plotting process imports
    # matplotlib's figure machinery (about 0.6 s), so the parent itself must not import it, or the two costs
    # add up instead of overlapping; the serial run (serial_demo) draws in its own process
    out = _run(fresh, tmp_path, """
forked = run_scene(demo, out="b.h5", plots_dir="b", plot_jobs=2)
out = {"forked": list(forked.plot_paths), "forks": forks[0], "parent_drew": "matplotlib.figure" in sys.modules}
""")
    serial, serial_folder, serial_forks = serial_demo
    assert out["forks"] >= 1 and serial_forks == 0  # plot_jobs=2 did fork, the default did not
    assert out["parent_drew"] is False
    names = [Path(p).name for p in serial.plot_paths]
    assert names == [Path(p).name for p in out["forked"]] and len(names) == 6
    for name in names:  # Agg output is deterministic: byte for byte
        assert (serial_folder / name).read_bytes() == (tmp_path / "b" / name).read_bytes(), name
    assert not list((tmp_path / "b").glob("*.tmp"))


def test_a_failing_plot_in_a_child_is_reported(fresh, tmp_path):
    # the identify plot is the one handed to a child as soon as its stage is done (no child
    # is running yet then), so the failure happens in the child and must reach the caller
    out = _run(fresh, tmp_path, """
from balancer.scene import plots
def broken(results):
    raise ValueError("no figure today")
plots.identify_figures = broken
try:
    run_scene(demo, out="c.h5", plots_dir="c", plot_jobs=2)
    out = {"error": None}
except RuntimeError as exc:
    out = {"error": str(exc), "forks": forks[0]}
""")
    assert out["forks"] >= 1
    assert "identify" in out["error"] and "ValueError: no figure today" in out["error"]


def test_a_failing_stage_leaves_no_plots_drawn_early(fresh, tmp_path):
    # the identify plot is drawn by a child while the later stages run; when one of them
    # fails, the run writes nothing: no archive and no plot (as without plot_jobs)
    out = _run(fresh, tmp_path, """
from balancer.scene import stages
def broken(scene, **kwargs):
    raise SceneError("mounts: broken on purpose")
stages.stage_mounts = broken
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
    monkeypatch.setattr(plots, "identify_figures", broken)
    with pytest.raises(RuntimeError, match="plots of identify.*ValueError: no figure today"):
        run_scene(DEMO, out=tmp_path / "c.h5", plots_dir=tmp_path / "c", plot_jobs=jobs)


def test_every_stage_figure_declares_the_results_it_reads():
    # a plotting process is handed only the stage's plot_inputs (the byte-for-byte test above shows the
    # demo's figures come out the same from that subset); a stage with figures must say what they read
    from balancer.scene.registry import REGISTRY

    with_figures = [stage for stage in REGISTRY.values() if stage.figures]
    assert {"frf", "identify", "balance"} <= {stage.name for stage in with_figures}  # frf: a time record's estimate
    assert all(stage.name in stage.plot_inputs and set(stage.plot_inputs) <= set(REGISTRY) for stage in with_figures)
    assert all(not stage.plot_inputs and not stage.plot_modules for stage in REGISTRY.values() if not stage.figures)


def test_every_figure_draws_the_same_in_a_plotting_process_with_only_the_drawing_modules(tmp_path, serial_demo):
    # `python -m balancer run` forks its plotting process before modal is imported, and the process loads
    # only modal's submodules that drawing needs (balancer.scene.plotter._drawing_modal), then the plot_modules
    # of its stages once, before it forks its helper. Each stage's plot inputs are pickled by a run here,
    # then drawn in such a process, a child of its own per stage (as a scene that plots only it): the files
    # are byte for byte the ones drawn here, drawing imports no modal/balancer module beyond the preloaded
    # ones (each drawing process would import it again), and the identification toolkit never loads.
    import pickle

    from balancer.scene import parse_scene, plots, run_scene
    from balancer.scene.registry import REGISTRY, result_modules
    from balancer.scene.schema import load_scene
    from support.scenes import DRIVE

    # the hammer scene first: its frf stage is a time record's estimate, which draws (a file's FRF draws nothing)
    scenes = [ROOT / "data" / "synthetic" / "hammer_scene.toml", DEMO, ROOT / "data" / "synthetic" / "balance_scene.toml",
              {"scene": {"name": "drive"}, "drive": DRIVE, "outputs": {"plots": ["drive"]}}]
    figured = [stage for stage, entry in REGISTRY.items() if entry.figures]
    pickled, modules, serial = {}, {}, {}
    for k, scene in enumerate(scenes):
        # each scene's own plots folder: the run draws the plots its scene lists in this process (plot_jobs=1),
        # the serial drawing the child's files are compared with; a stage it does not draw is drawn here
        if scene == DEMO:
            run, drawn_in = serial_demo[:2]
        else:
            run, drawn_in = run_scene(scene, out=tmp_path / "x.h5", plots_dir=tmp_path / f"p{k}"), tmp_path / f"p{k}"
        drawn = {Path(p).name for p in run.plot_paths}
        for stage in figured:
            if stage in run.results and stage not in pickled:
                given = {s: run.results[s] for s in REGISTRY[stage].plot_inputs if s in run.results}
                # what the run's plotting process imports for it beside the stage's plot_modules (a time record's
                # estimate class, handed to the frf's and identify's figures)
                checked = load_scene(scene) if isinstance(scene, Path) else parse_scene(scene)
                modules[stage] = list(result_modules(checked, [stage]))
                pickled[stage] = str(tmp_path / f"{stage}.pickle")
                Path(pickled[stage]).write_bytes(pickle.dumps(given))
                serial[stage] = sorted(drawn_in / name for name in drawn if name.startswith(stage + "_"))
                if not serial[stage]:
                    (tmp_path / "serial").mkdir(exist_ok=True)
                    serial[stage] = plots.save_stage_plot(stage, given, tmp_path / "serial")
    assert set(pickled) == set(figured)  # every stage with figures is covered
    script = f"""
import json, os, pickle, sys
from pathlib import Path
sys.path.insert(0, {str(ROOT)!r})
from balancer.scene import plotter
plotter._drawing_modal()
import matplotlib.figure
from balancer.scene import plots
out = {{}}
for stage, path in {pickled!r}.items():
    read, write = os.pipe()
    if os.fork() == 0:
        plots.preload([stage], {modules!r}[stage])
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
out["toolkit"] = sorted(m for m in ("modal.identify", "modal.sdof.checks", "modal.nls", "scipy.special", "h5py")
                        if m in sys.modules)
print(json.dumps(out))
"""
    proc = subprocess.run([sys.executable, "-c", script], cwd=tmp_path, capture_output=True, text=True, timeout=300,
                          env={**os.environ, "MPLBACKEND": "Agg"})
    assert proc.returncode == 0, proc.stderr[-2000:]
    out = json.loads(proc.stdout.strip().splitlines()[-1])
    assert out == {**{stage: [] for stage in pickled}, "toolkit": []}
    assert all(serial[stage] for stage in pickled)  # every stage drew at least one figure
    for stage, paths in serial.items():
        assert sorted(p.name for p in (tmp_path / stage).iterdir()) == [p.name for p in paths], stage
        for path in paths:
            assert (tmp_path / stage / path.name).read_bytes() == path.read_bytes(), path.name


def test_the_command_line_draws_the_same_files_from_its_early_plotting_process(tmp_path, serial_demo):
    # `python -m balancer run` starts its plotting process before it imports modal; the run takes it over:
    # the same files, byte for byte, as drawn in one process
    serial, serial_folder, _ = serial_demo
    proc = subprocess.run([sys.executable, "-m", "balancer", "run", str(DEMO), "--out", str(tmp_path / "b.h5"),
                           "--plots", str(tmp_path / "b")], cwd=ROOT, capture_output=True, text=True, timeout=300,
                          env={**os.environ, "MPLBACKEND": "Agg"})
    assert proc.returncode == 0, proc.stderr[-2000:]
    names = [Path(p).name for p in serial.plot_paths]
    assert sorted(p.name for p in (tmp_path / "b").iterdir()) == sorted(names) and len(names) == 6
    for name in names:
        assert (serial_folder / name).read_bytes() == (tmp_path / "b" / name).read_bytes(), name


def test_an_early_plotting_process_reports_a_failed_figure_and_is_dismissed_when_unused(fresh, tmp_path):
    # taken over by a run: a figure that fails there reaches the caller with its stage; not taken over (no
    # plots, or the run failed first): dismiss_early ends it and no child process is left behind
    script = f"""
import json, os, sys
sys.path.insert(0, {str(ROOT)!r})
from balancer.scene import plots, run_scene
def broken(results):
    raise ValueError("no figure today")
plots.identify_figures = broken   # before the fork: the plotting process has it too
from balancer.scene import plotter
out = {{"started": plotter.start_early()}}
try:
    run_scene({str(DEMO)!r}, out="c.h5", plots_dir="c", plot_jobs=2)
except RuntimeError as exc:
    out["error"] = str(exc)
out["taken"] = plotter._early is None
out["second"] = plotter.start_early()
plotter.dismiss_early()
try:
    os.waitpid(-1, os.WNOHANG)
    out["children"] = "left"
except ChildProcessError:
    out["children"] = "none"
print(json.dumps(out))
"""
    proc = fresh.run(script, cwd=tmp_path, timeout=300)
    assert proc.returncode == 0, proc.stderr[-2000:]
    out = json.loads(proc.stdout.strip().splitlines()[-1])
    assert out["started"] and out["taken"] and out["second"]
    assert "plots of identify" in out["error"] and "ValueError: no figure today" in out["error"]
    assert out["children"] == "none"
    assert not list((tmp_path / "c").glob("*.png"))  # the figures drawn before the failure are removed


@pytest.mark.parametrize("case", ["no plots", "missing scene"])
def test_the_command_line_without_plots_or_with_a_bad_scene_ends_as_before(tmp_path, case):
    # the early plotting process is dismissed: a run without plots writes its archive and exits 0, a missing
    # scene exits 1 with its one-line error, and neither waits for the plotting process' imports
    scene = tmp_path / "scene.toml"
    if case == "no plots":
        scene.write_text(DEMO.read_text().replace('plots = ["identify", "adb_stability", "adb_response", "compressor",'
                                                  ' "mounts"]', "plots = []").replace('file = "demo_frf.csv"',
                         f'file = {str(DEMO.parent / "demo_frf.csv")!r}'))
    proc = subprocess.run([sys.executable, "-m", "balancer", "run", str(scene), "--out", str(tmp_path / "d.h5")],
                          cwd=ROOT, capture_output=True, text=True, timeout=300, env={**os.environ, "MPLBACKEND": "Agg"})
    if case == "no plots":
        assert proc.returncode == 0, proc.stderr[-2000:]
        assert (tmp_path / "d.h5").exists() and not (tmp_path / "d_plots").exists()
    else:
        assert proc.returncode == 1
        assert proc.stderr.strip().splitlines()[-1].startswith("error:") and "Traceback" not in proc.stderr


def test_a_failed_figure_ends_the_command_line_with_a_one_line_error(tmp_path, monkeypatch, capsys):
    # a figure that cannot be drawn or written (a full disk, a plots folder that went away) is the run's error:
    # exit code 1 and one line naming the stage and the cause, no traceback (modal.errors.PlotError)
    from balancer import cli
    from balancer.scene import plots
    from modal.errors import ModalError, PlotError

    def broken(results):
        raise ValueError("no figure today")

    monkeypatch.setattr(plots, "identify_figures", broken)
    code = cli.main(["run", str(DEMO), "--out", str(tmp_path / "e.h5"), "--plots", str(tmp_path / "e")])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 1
    assert err[-1] == "error: plots of identify: ValueError: no figure today"
    assert issubclass(PlotError, ModalError) and issubclass(PlotError, RuntimeError)  # callers catching either
