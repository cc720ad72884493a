"""The scene runner: does only the stages the outputs need, reuses unchanged
stages from an earlier archive, writes the archive, plots and a summary."""
from __future__ import annotations

import hashlib
import json
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

import h5py

import modal
from modal.archive import read_node, write_archive
from modal.errors import ArchiveError, SceneError

from .schema import STAGES, Reference, Scene, dependencies, load_scene, parse_scene
from .stages import STAGE_FUNCTIONS

__all__ = ["SceneRun", "run_scene", "plan", "stage_hashes"]

#: configuration sections that make up each stage's inputs (besides its dependencies' hashes)
_STAGE_CONFIG = {
    "frf": ("frf",), "identify": ("identify",), "drive": ("drive",), "rotor": ("rotor", "adb.m", "adb.n", "adb.R", "adb.D"),
    "adb_stability": ("adb.stability",), "adb_response": ("adb.response",),
    "compressor": ("compressor.crank_radius_m", "compressor.rod_length_m", "compressor.rotating_mass_kg",
                   "compressor.reciprocating_mass_kg", "compressor.speed_rpm", "compressor.harmonics",
                   "compressor.counterweight_k"),
    "mounts": ("compressor.body", "compressor.mounts"),
    "balance": ("balance",),
}


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
    """

    stages: dict[str, str]
    results: dict[str, Any]
    inputs_hash: dict[str, str]
    archive_path: str | None
    plot_paths: tuple[str, ...]
    summary: str
    timings_s: dict[str, float] = field(default_factory=dict)


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
    """SHA-256 of each stage's inputs: its configuration, its files' bytes and its dependencies' hashes."""
    hashes: dict[str, str] = {}
    for stage in STAGES:
        if stage not in stages:
            continue
        config = {key: _canonical(scene.section(key)) for key in _STAGE_CONFIG[stage]}
        if stage == "frf" and scene.section("frf.file"):
            path = scene.folder / scene.section("frf.file")
            try:
                config["file_sha256"] = hashlib.sha256(path.read_bytes()).hexdigest()
            except OSError as exc:
                raise SceneError(f"{scene.source}: key 'frf.file' = {scene.section('frf.file')!r}: cannot read {path} "
                                 f"({exc.strerror})") from None
        if stage == "balance" and scene.section("balance.readings"):
            path = scene.folder / scene.section("balance.readings")
            try:
                config["readings_sha256"] = hashlib.sha256(path.read_bytes()).hexdigest()
            except OSError as exc:
                raise SceneError(f"{scene.source}: key 'balance.readings' = {scene.section('balance.readings')!r}: "
                                 f"cannot read {path} ({exc.strerror})") from None
        payload = {"stage": stage, "config": config, "software": modal.__version__,
                   "deps": {d: hashes[d] for d in dependencies(scene, stage)}}
        hashes[stage] = hashlib.sha256(json.dumps(payload, sort_keys=True).encode()).hexdigest()
    return hashes


def _closure(scene: Scene, wanted) -> set[str]:
    need, todo = set(), list(wanted)
    while todo:
        stage = todo.pop()
        if stage not in need:
            need.add(stage)
            todo.extend(dependencies(scene, stage))
    return need


def _wanted(scene: Scene) -> list[str]:
    out = scene.section("outputs")
    wanted = set(out.get("tables", [])) | set(out.get("plots", []))
    archive = out.get("archive", False)
    if isinstance(archive, list):
        wanted |= set(archive)
    return [s for s in STAGES if s in wanted]


def plan(scene: Scene, earlier: h5py.File | None = None) -> tuple[dict[str, str], dict[str, str]]:
    """Decide each stage's status without computing anything: (statuses, hashes).

    The outputs' stages and everything upstream of them are needed; a needed
    stage whose inputs hash matches the earlier archive is reused (read back),
    any other needed stage runs, and the rest are skipped.
    """
    needed = _closure(scene, _wanted(scene))
    hashes = stage_hashes(scene, needed)
    status = {s: "skipped" for s in STAGES}
    for stage in needed:
        same = earlier is not None and stage in earlier and earlier[stage].attrs.get("inputs_hash") == hashes[stage]
        status[stage] = "reused" if same else "ran"
    return status, hashes


def _open_earlier(path) -> h5py.File | None:
    if path is None:
        return None
    path = Path(path)
    if not path.is_file():
        return None  # nothing to reuse yet: run everything
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


#: rough CPU cost (s) of each stage's figures and of importing matplotlib's figure machinery: used only to decide
#: which figures the parent takes over from the plotting child at the end (the output does not depend on it)
_PLOT_COST_S = {"identify": 0.15, "adb_response": 0.14, "compressor": 0.1, "adb_stability": 0.04, "mounts": 0.04}
_PLOT_IMPORT_COST_S = 0.14


class _Plotter:
    """A forked child that draws the stage plots while the parent runs the stages (``plot_jobs > 1``).

    Started before the first stage, the child imports the plotting modules (matplotlib) while the
    parent computes; each plot stage's results (with those of the stages it depends on) are sent to
    it, pickled through a pipe, as soon as they are complete, and it draws them in that order (atomic
    writes, as :func:`~balancer.scene.plots.save_stage_plot`).  At the end the parent takes over
    figures the child has not started when that finishes sooner (:meth:`share`), so no figure is
    drawn twice on purpose and both CPUs draw.  ``started`` is False (everything drawn in the parent)
    where ``os.fork`` is missing or more than one thread is alive (forking a threaded process is unsafe).
    """

    def __init__(self, jobs: int, folder: Path):
        import os
        import threading

        self.folder = folder
        self.pid: int | None = None
        self.sent: list[str] = []
        self._drawn: list[Path] = []
        self._status_text = b""
        self._started_order: list[str] = []
        if max(1, int(jobs)) > 1 and hasattr(os, "fork") and threading.active_count() == 1:
            self._fork()

    @property
    def started(self) -> bool:
        return self.pid is not None

    def _fork(self) -> None:
        import os
        import sys

        self.folder.mkdir(parents=True, exist_ok=True)
        sys.stdout.flush()
        sys.stderr.flush()
        jobs_read, self._jobs = os.pipe()
        self._status, status_write = os.pipe()
        self._report, report_write = os.pipe()
        pid = os.fork()
        if pid == 0:  # child: draw, report, leave without running the parent's exit handlers
            code = 0
            try:
                for fd in (self._jobs, self._status, self._report):
                    os.close(fd)
                report = self._serve(jobs_read, status_write)
                code = 1 if "error" in report else 0
            except BaseException as exc:  # noqa: BLE001 - reported to the parent, which raises it
                report, code = {"error": f"{type(exc).__name__}: {exc}"}, 1
            try:
                data = json.dumps(report).encode()
                while data:
                    data = data[os.write(report_write, data):]
            finally:
                os._exit(code)
        for fd in (jobs_read, status_write, report_write):
            os.close(fd)
        self.pid = pid

    # ---- child side
    def _serve(self, jobs_read: int, status_write: int) -> dict:
        import os
        import pickle
        import queue
        import threading

        messages: queue.Queue = queue.Queue()

        def reader() -> None:  # drains the pipe so that the parent never waits on a full pipe
            with os.fdopen(jobs_read, "rb") as pipe:
                while True:
                    head = pipe.read(8)
                    if len(head) < 8:
                        messages.put(("end",))
                        return
                    messages.put(pipe.read(int.from_bytes(head, "little")))

        threading.Thread(target=reader, daemon=True).start()
        from .plots import save_stage_plot  # matplotlib, imported while the parent computes

        todo: list[str] = []
        given: dict[str, dict] = {}
        skip: set[str] = set()
        drawn: dict[str, list[str]] = {}
        error = None
        ended = False
        while True:
            block = not todo and not ended
            while True:
                try:
                    message = messages.get(block=block)
                except queue.Empty:
                    break
                block = False
                if not isinstance(message, tuple):
                    message = pickle.loads(message)
                if message[0] == "draw":
                    todo.append(message[1])
                    given[message[1]] = message[2]
                elif message[0] == "skip":
                    skip.update(message[1])
                else:
                    ended = True
            todo = [stage for stage in todo if stage not in skip]
            if todo and error is None:
                stage = todo.pop(0)
                os.write(status_write, stage.encode() + b"\n")
                try:
                    drawn[stage] = [str(p) for p in save_stage_plot(stage, given.pop(stage), self.folder)]
                except Exception as exc:  # the same report as from the parent: the stage and the cause
                    error = f"plots of {stage}: {type(exc).__name__}: {exc}"
                continue
            todo = []
            if ended:
                return {"drawn": drawn} if error is None else {"drawn": drawn, "error": error}

    # ---- parent side
    def _send(self, message: tuple) -> bool:
        import os
        import pickle

        try:
            data = pickle.dumps(message, protocol=pickle.HIGHEST_PROTOCOL)
        except Exception:  # noqa: BLE001 - a result that does not pickle is drawn by the parent
            return False
        data = len(data).to_bytes(8, "little") + data
        try:
            while data:
                data = data[os.write(self._jobs, data):]
        except BrokenPipeError:  # the child has ended (its report says why)
            return False
        return True

    def submit(self, stage: str, results: dict) -> bool:
        """Send a stage's plot to the child; False if it stays with the parent."""
        if not self.started or not self._send(("draw", stage, results)):
            return False
        self.sent.append(stage)
        return True

    def _started_stages(self) -> set[str]:
        import os
        import select

        text = b""
        while select.select([self._status], [], [], 0)[0]:
            chunk = os.read(self._status, 65536)
            if not chunk:
                break
            text += chunk
        self._status_text += text
        self._started_order = [line.decode() for line in self._status_text.split(b"\n") if line]
        return set(self._started_order)

    def share(self) -> list[str]:
        """Take back, from the end of the child's queue, the figures the parent draws sooner (matplotlib
        to import, if not yet, plus their drawing, against what the child has left); tell the child."""
        import sys

        if not self.started:
            return []
        started = self._started_stages()
        waiting = [stage for stage in self.sent if stage not in started]
        cost = {stage: _PLOT_COST_S.get(stage, 0.1) for stage in waiting}
        parent = 0.0 if "balancer.scene.plots" in sys.modules else _PLOT_IMPORT_COST_S
        # what the child has left: about half of the figure it drew last (it may be done with it) and the waiting ones
        last = self._started_order[-1] if self._started_order else ""
        child = 0.5 * _PLOT_COST_S.get(last, 0.1) * bool(last) + sum(cost.values())
        taken: list[str] = []
        for stage in reversed(waiting):
            if parent + cost[stage] >= child - cost[stage]:
                break
            parent += cost[stage]
            child -= cost[stage]
            taken.insert(0, stage)
        self._send(("skip", taken))
        return taken

    def collect(self) -> dict[str, list[Path]]:
        """Tell the child there is nothing more, wait for it; the paths of each stage it drew (raises
        RuntimeError if a figure failed there)."""
        import os

        if not self.started:
            return {}
        self._send(("end",))
        os.close(self._jobs)
        chunks = []
        while True:
            chunk = os.read(self._report, 65536)
            if not chunk:
                break
            chunks.append(chunk)
        for fd in (self._report, self._status):
            os.close(fd)
        os.waitpid(self.pid, 0)
        self.pid = None
        report = json.loads(b"".join(chunks) or b'{"error": "plot process ended without a report"}')
        done = {stage: [Path(p) for p in paths] for stage, paths in report.get("drawn", {}).items()}
        for paths in done.values():
            self._drawn.extend(paths)
        if "error" in report:
            raise RuntimeError(report["error"])
        return done

    def abandon(self) -> None:
        """Wait for the child and remove the plots it drew (the run failed)."""
        if self.started:
            self._send(("skip", list(self.sent)))
            try:
                self.collect()
            except RuntimeError:
                pass
        for path in self._drawn:
            path.unlink(missing_ok=True)


def run_scene(scene: str | Path | dict | Scene, out: str | Path | None = None, plots_dir: str | Path | None = None,
              archive: str | Path | None = None, progress: Callable[[str], None] | None = None,
              plot_jobs: int = 1) -> SceneRun:
    """Run a scene end to end.

    Parameters
    ----------
    scene : path, dict or Scene
        A TOML file, the same content as a dict, or a validated scene.
    out : path, optional
        Archive to write; default ``out/<scene name>.h5`` when the scene asks
        for an archive.
    plots_dir : path, optional
        Folder for the plots; default ``<archive stem>_plots`` beside the archive.
    archive : path, optional
        An earlier archive of the same scene: stages whose inputs are unchanged
        are read back from it instead of being recomputed.
    progress : callable, optional
        Called with a line of text before and after each stage that runs.
    plot_jobs : int
        Processes drawing the plots (POSIX only): with 2 or more, the plots of a stage are
        drawn in a forked child as soon as the stage is done, while the next stages run
        (``python -m balancer run`` uses 2 on a machine with several CPUs).  The files are
        the same as with 1 (default: everything in this process).
    """
    if isinstance(scene, (str, Path)):
        scene = load_scene(scene)
    elif isinstance(scene, dict):
        scene = parse_scene(scene)
    say = progress or (lambda _msg: None)
    earlier = _open_earlier(archive)
    try:
        status, hashes = plan(scene, earlier)
        results: dict[str, Any] = {}
        timings: dict[str, float] = {}
        for stage in STAGES:
            if status[stage] == "reused":
                results[stage] = read_node(earlier[stage])
    finally:
        if earlier is not None:
            earlier.close()
    outputs = scene.section("outputs")
    name = scene.section("scene.name") or Path(scene.source).stem or "scene"
    stored = outputs.get("archive", False)
    archive_path = None
    if stored or out is not None:
        archive_path = Path(out) if out is not None else Path("out") / f"{_slug(name)}.h5"
    plotted = list(outputs.get("plots") or [])
    folder = None
    if plotted:
        folder = Path(plots_dir) if plots_dir is not None else (
            archive_path.with_name(archive_path.stem + "_plots") if archive_path else Path("out") / f"{_slug(name)}_plots")
    plotter = _Plotter(plot_jobs, folder) if plotted else None
    pending = list(plotted)  # plot stages not yet handed to the child, in output order

    def hand_over() -> None:
        # plots whose stage and upstream results are all there go to the child while the parent runs on
        for stage in list(pending):
            if stage not in results or not all(status[t] != "ran" or t in results for t in dependencies(scene, stage)):
                continue
            given = {s: results[s] for s in _closure(scene, [stage]) if s in results}
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
            kwargs = {dep: results[dep] for dep in dependencies(scene, stage) if dep in results}
            results[stage] = STAGE_FUNCTIONS[stage](scene, **kwargs)
            timings[stage] = time.perf_counter() - t0
            say(f"{stage}: done in {timings[stage]:.2f} s")
            if plotter is not None and plotter.started and pending:
                hand_over()
        if archive_path is not None:
            keep = [s for s in STAGES if s in results and (stored is True or stored is False or s in stored)]
            archive_path.parent.mkdir(parents=True, exist_ok=True)
            write_archive(archive_path, {s: results[s] for s in keep}, scene_text=scene.text or None,
                          inputs_hash={s: hashes[s] for s in keep})
        if plotted:
            folder.mkdir(parents=True, exist_ok=True)
            taken = plotter.share()
            mine_to_draw = [s for s in plotted if s in pending or s in taken]
            mine = {}
            if mine_to_draw:
                from .plots import save_stage_plot

            for stage in mine_to_draw:
                try:
                    mine[stage] = save_stage_plot(stage, results, folder)
                except Exception as exc:  # the same report as from the child: the stage and the cause
                    raise RuntimeError(f"plots of {stage}: {type(exc).__name__}: {exc}") from exc
            theirs = plotter.collect()
            for stage in plotted:
                plot_paths += mine.get(stage, theirs.get(stage, []))
    except BaseException:
        if plotter is not None:  # a failed run leaves no plots drawn by the child
            plotter.abandon()
        raise
    from .summary import format_summary

    summary = format_summary(name, status, results, outputs.get("tables", []), timings,
                             str(archive_path) if archive_path else None, plot_paths)
    return SceneRun(status, results, hashes, str(archive_path) if archive_path else None, tuple(map(str, plot_paths)),
                    summary, timings)


def _slug(text: str) -> str:
    return "".join(c if c.isalnum() or c in "-_" else "_" for c in text).strip("_") or "scene"
