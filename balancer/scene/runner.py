"""The scene runner: does only the stages the outputs need, reuses unchanged
stages from an earlier archive, writes the archive, plots and a summary."""
from __future__ import annotations

import hashlib
import json
import os
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, Callable

import modal
from modal.errors import ArchiveError, ModalError, PlotError, SceneError, kept_warnings

from .plotter import Plotter, plot_error
from .registry import REGISTRY, STAGES, load, result_modules
from .rules import Reference
from .schema import Scene, load_scene, parse_scene

if TYPE_CHECKING:
    import h5py

__all__ = ["SceneRun", "run_scene", "plan", "stage_hashes"]

# h5py (and modal.archive) are imported where an archive is read or written: `python -m balancer run`
# forks its plotting process before, and what is imported by then is paid before both processes work

@dataclass(frozen=True)
class SceneRun:
    """What a run did and produced.

    Attributes
    ----------
    stages : dict
        Every stage name → ``"ran"``, ``"reused"`` (read back from the earlier
        archive, inputs unchanged) or ``"skipped"`` (not needed by the outputs).
    results : dict
        Stage name → result object, for the stages that ran or were reused.
    inputs_hash : dict
        Stage name → SHA-256 of its inputs (configuration and upstream hashes).
    archive_path : str or None
    plot_paths : tuple of str
    summary : str
        The readable summary printed by the command line.
    timings_s : dict
        Wall time of each stage that ran, s.
    warnings : dict
        Stage name → the warnings it gave (each once, in order; a reused stage's from the earlier archive), for
        the stages that gave any. They are shown as they come too, and archived with the stage.
    """

    stages: dict[str, str]
    results: dict[str, Any]
    inputs_hash: dict[str, str]
    archive_path: str | None
    plot_paths: tuple[str, ...]
    summary: str
    timings_s: dict[str, float] = field(default_factory=dict)
    warnings: dict[str, tuple[str, ...]] = field(default_factory=dict)


def _canonical(value):
    if isinstance(value, Reference):
        return value.text
    if isinstance(value, dict):
        return {k: _canonical(v) for k, v in sorted(value.items())}
    if isinstance(value, (list, tuple)):
        return [_canonical(v) for v in value]
    if isinstance(value, complex):
        return [value.real, value.imag]
    return value


def stage_hashes(scene: Scene, stages) -> dict[str, str]:
    """SHA-256 of each stage's inputs: its configuration, its files' bytes and its dependencies' hashes.

    ``stages`` are needed stages of the scene (:attr:`Scene.graph`) with all their upstream stages.
    """
    hashes: dict[str, str] = {}
    for stage in STAGES:
        if stage not in stages:
            continue
        config = {key: _canonical(scene.section(key)) for key in REGISTRY[stage].config}
        for key in REGISTRY[stage].files:
            if scene.section(key):
                config[f"{key.rpartition('.')[2]}_sha256"] = _file_sha256(scene, key)
        payload = {"stage": stage, "config": config, "software": modal.__version__,
                   "deps": {d: hashes[d] for d in scene.graph[stage]}}
        hashes[stage] = hashlib.sha256(json.dumps(payload, sort_keys=True).encode()).hexdigest()
    return hashes


def _file_sha256(scene: Scene, key: str) -> str:
    """SHA-256 of the file a key names, or of the files' own hashes in order when it names several."""
    names = scene.section(key)
    digests = []
    for name in names if isinstance(names, list) else [names]:
        path = scene.folder / name
        try:
            digests.append(hashlib.sha256(path.read_bytes()).hexdigest())
        except OSError as exc:
            raise SceneError(f"{scene.source}: key '{key}' = {names!r}: cannot read {path} "
                             f"({exc.strerror})") from None
    return digests[0] if len(digests) == 1 else hashlib.sha256(" ".join(digests).encode()).hexdigest()


def plan(scene: Scene, earlier: h5py.File | None = None) -> tuple[dict[str, str], dict[str, str]]:
    """Decide each stage's status without computing anything: (statuses, hashes).

    The outputs' stages and everything upstream of them are needed; a needed
    stage whose inputs hash matches the earlier archive is reused (read back),
    any other needed stage runs, and the rest are skipped.
    """
    needed = scene.graph
    hashes = stage_hashes(scene, needed)
    status = {s: "skipped" for s in STAGES}
    for stage in needed:
        same = earlier is not None and stage in earlier and earlier[stage].attrs.get("inputs_hash") == hashes[stage]
        status[stage] = "reused" if same else "ran"
    for stage in reversed(list(needed)):  # a stage's inputs come before it: dependents first
        if status[stage] == "ran":
            for dep in needed[stage]:
                if status[dep] == "reused" and not REGISTRY[dep].archive_whole:
                    status[dep] = "ran"  # what the archive holds of it is not all this stage computes from
    return status, hashes


def _open_earlier(path) -> h5py.File | None:
    if path is None:
        return None
    path = Path(path)
    if not path.is_file():
        return None  # nothing to reuse yet: run everything
    import h5py

    try:
        f = h5py.File(path, "r")
    except OSError as exc:
        raise ArchiveError(f"{path}: not a readable HDF5 archive ({exc})") from None
    from modal.io.hdf5 import check_schema

    try:
        check_schema(f, str(path), error=ArchiveError)
    except ArchiveError:
        f.close()
        raise
    return f


def run_scene(scene: str | Path | dict | Scene, out: str | Path | None = None, plots_dir: str | Path | None = None,
              archive: str | Path | None = None, progress: Callable[[str], None] | None = None,
              plot_jobs: int = 1) -> SceneRun:
    """Run a scene end to end.

    Parameters
    ----------
    scene : path, dict or Scene
        A TOML file, the same content as a dict, or a validated scene.
    out : path, optional
        Archive to write, in an existing folder; default ``out/<scene name>.h5`` (``out`` is
        made) when the scene asks for an archive. The folders are checked before any work.
    plots_dir : path, optional
        Folder for the plots (made inside an existing folder); default ``<archive stem>_plots``
        beside the archive. Given for a scene whose ``[outputs]`` lists no plots, it draws the
        figures of every stage the scene runs (a warning says so when none of them draws one).
    archive : path, optional
        An earlier archive of the same scene: stages whose inputs are unchanged
        are read back from it instead of being recomputed.
    progress : callable, optional
        Called with a line of text before and after each stage that runs.
    plot_jobs : int
        Processes drawing the plots (POSIX only): with 2 or more, two forked processes draw
        them (matplotlib imported once, while this process starts on the stages), each
        stage's plots as soon as the stage is done, while the next stages run
        (``python -m balancer run`` uses 2 on a machine with several CPUs, and its plotting
        process is started before anything is imported: :mod:`.plotter`).  The files
        are the same as with 1 (default: everything in this process).
    """
    if isinstance(scene, (str, Path)):
        scene = load_scene(scene)
    elif isinstance(scene, dict):
        scene = parse_scene(scene)
    say = progress or (lambda _msg: None)
    outputs = scene.section("outputs")
    name = scene.section("scene.name") or Path(scene.source).stem or "scene"
    stored = outputs.get("archive", False)
    archive_path = None
    if stored or out is not None:
        archive_path = Path(out) if out is not None else Path("out") / f"{_slug(name)}.h5"
    plotted = list(outputs.get("plots") or [])
    if not plotted and plots_dir is not None:
        plotted = _default_plots(scene, plots_dir, say)
    folder = None
    if plotted:
        folder = Path(plots_dir) if plots_dir is not None else (
            archive_path.with_name(archive_path.stem + "_plots") if archive_path else Path("out") / f"{_slug(name)}_plots")
    # where the outputs go is checked before any work (nothing is made yet): a folder the caller names must exist
    # (the plots' own folder is made in it), the default out/ is made where it can be
    if archive_path is not None:
        _check_folder(archive_path, "archive", ArchiveError, made=out is None)
    if folder is not None:
        _check_folder(folder, "plots", PlotError, made=plots_dir is None)
    earlier = _open_earlier(archive)
    try:
        status, hashes = plan(scene, earlier)
        results: dict[str, Any] = {}
        timings: dict[str, float] = {}
        given: dict[str, tuple[str, ...]] = {}
        for stage in STAGES:
            if status[stage] == "reused":
                from modal.archive import read_node, read_warnings

                results[stage] = read_node(earlier[stage])
                said = read_warnings(earlier[stage])
                if said:
                    given[stage] = said
    finally:
        if earlier is not None:
            earlier.close()
    plotter = None
    if plotted:
        plotter = Plotter(plot_jobs, folder, plotted, result_modules(scene, plotted))
    # plot stages not yet handed to the child, in output order (a stage without figures draws nothing)
    pending = [stage for stage in plotted if REGISTRY[stage].figures]

    def hand_over() -> None:
        # plots whose stage and upstream results are all there go to the child while the parent runs on
        for stage in list(pending):
            if stage not in results or not all(status[t] != "ran" or t in results for t in scene.graph[stage]):
                continue
            # a plotting process is handed only what the figures read: it unpickles (and imports the classes of)
            # nothing more
            given = {s: results[s] for s in REGISTRY[stage].plot_inputs if s in results}
            if plotter.submit(stage, given):
                pending.remove(stage)

    plot_paths = []
    try:
        if plotter is not None and plotter.started:
            hand_over()  # reused stages' plots can start at once
        for stage in STAGES:
            if status[stage] != "ran":
                continue
            say(f"{stage}: running")
            t0 = time.perf_counter()
            kwargs = {dep: results[dep] for dep in scene.graph[stage] if dep in results}
            results[stage], said = _run_stage(stage, scene, kwargs)
            if said:
                given[stage] = said
            timings[stage] = time.perf_counter() - t0
            say(f"{stage}: done in {timings[stage]:.2f} s")
            if plotter is not None and plotter.started and pending:
                hand_over()
        if archive_path is not None:
            keep = [s for s in STAGES if s in results and (stored is True or stored is False or s in stored)]
            from modal.archive import write_archive

            archive_path.parent.mkdir(parents=True, exist_ok=True)  # checked above: exists, or is the default
            write_archive(archive_path, {s: results[s] for s in keep}, scene_text=scene.text or None,
                          inputs_hash={s: hashes[s] for s in keep},
                          warnings={s: given[s] for s in keep if s in given})
        if plotted:
            folder.mkdir(parents=True, exist_ok=True)  # checked above
            mine = {}
            if pending:  # not handed to the plotter (no fork here, or results that do not pickle)
                from .plots import save_stage_plot

            for stage in pending:
                try:
                    mine[stage] = save_stage_plot(stage, results, folder)
                except Exception as exc:  # the same report as from the child: the stage and the cause
                    raise PlotError(plot_error(stage, exc)) from exc
            theirs = plotter.collect()
            for stage in plotted:
                plot_paths += mine.get(stage, theirs.get(stage, []))
    except BaseException:
        if plotter is not None:  # a failed run leaves no plots drawn by the child
            plotter.abandon()
        raise
    from .summary import format_summary

    summary = format_summary(name, status, results, outputs.get("tables", []), timings,
                             str(archive_path) if archive_path else None, plot_paths, given)
    return SceneRun(status, results, hashes, str(archive_path) if archive_path else None, tuple(map(str, plot_paths)),
                    summary, timings, given)


def _run_stage(stage: str, scene: Scene, kwargs: dict) -> tuple[Any, tuple[str, ...]]:
    """Run one stage; its result and the toolkit's warnings it gave (:func:`modal.errors.kept_warnings`)."""
    with kept_warnings() as said:
        result = load(REGISTRY[stage].run)(scene, **kwargs)
    return result, tuple(said)


def _default_plots(scene: Scene, plots_dir, say: Callable[[str], None]) -> list[str]:
    """The plots drawn when the caller names a folder and the scene lists none: every figure of the stages it runs."""
    drawing = [stage for stage in scene.graph if REGISTRY[stage].figures]
    if drawing:
        say(f"plots: the scene's [outputs] lists none; drawing those of the stages it runs ({', '.join(drawing)}) "
            f"in {plots_dir}")
    else:
        from modal.errors import warn

        warn(f"{plots_dir}: no plot drawn: the stages this scene runs ({', '.join(scene.graph)}) draw no figure",
             stacklevel=3)
    return drawing


def _check_folder(target: Path, what: str, error: type[ModalError], made: bool) -> None:
    """``target`` (the archive, or the plots' folder) can be written: its folder exists and is writable, or, when
    ``made``, the nearest existing folder above it is (where it will be made). Raises ``error`` naming ``target``."""
    parent = target.parent
    if not parent.exists() and not made:
        raise error(f"{target}: the folder {parent} does not exist; expected an existing folder for the {what} "
                    "(create it first)")
    existing = parent
    while not existing.exists() and existing != existing.parent:
        existing = existing.parent
    if not existing.is_dir():
        raise error(f"{target}: {existing} is not a folder; expected a folder for the {what}")
    if not os.access(existing, os.W_OK | os.X_OK):
        raise error(f"{target}: the folder {existing} is not writable; expected a folder the {what} can be "
                    "written to")
    if what == "archive" and target.is_dir():
        raise error(f"{target}: is a folder; expected an archive file")
    if what == "plots" and target.exists() and not target.is_dir():
        raise error(f"{target}: is a file; expected a folder for the plots")


def _slug(text: str) -> str:
    return "".join(c if c.isalnum() or c in "-_" else "_" for c in text).strip("_") or "scene"
