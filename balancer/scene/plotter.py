"""The processes that draw a scene's plots while the scene runs on.

A plotting process is forked and imports the drawing modules (matplotlib) while the parent
computes; it then forks a helper, which inherits them, and both take figures from one queue
(whichever is free draws the next), so matplotlib is imported once and both CPUs draw once the
parent is done.  Each plot stage's results (those its figures read) are pickled to a temporary
file as soon as they are complete and announced by a fixed-size record on a pipe (the parent
never waits on the plotters).  Figures are written atomically, as by
:func:`balancer.scene.plots.save_stage_plot`.

``python -m balancer run`` starts its plotting process first of all (:func:`start_early`, before
the parent imports ``modal``), and the process imports only the parts of ``modal`` that drawing
needs (:func:`_drawing_modal`): both CPUs then work from the start, the parent on the
identification toolkit's imports and the stages, the plotting process on matplotlib's.
:class:`Plotter` takes that process over when the run has plots, else forks one the same way.

This module imports only the standard library: it is loaded before anything else.  The drawing
modules are imported in the plotting process, after the fork, and ``modal`` (whose package import
loads the whole identification toolkit) only where a failure is reported.
"""
from __future__ import annotations

import gc
import importlib.util
import json
import os
import pickle
import signal
import sys
import tempfile
import threading
from pathlib import Path
from typing import Callable

__all__ = ["Plotter", "start_early", "dismiss_early", "plot_error"]

#: size of one record on the plotters' pipe: written at once (atomic below PIPE_BUF) and read whole by
#: whichever drawing process is free
RECORD = 1024


def plot_error(stage: str, exc: BaseException) -> str:
    """How a failed figure is reported, wherever it was drawn: the stage and the cause."""
    return f"plots of {stage}: {type(exc).__name__}: {exc}"


def _write_record(fd: int, payload: dict) -> None:
    record = json.dumps(payload).encode()
    if len(record) > RECORD:
        raise ValueError("plot job record too long")
    os.write(fd, record.ljust(RECORD))  # one atomic write; the pipe holds 64 records


def _read_record(fd: int) -> dict | None:
    """The next record on the pipe, or None when it is closed (nothing more to draw)."""
    record = os.read(fd, RECORD)
    while record and len(record) < RECORD:  # not expected (records are written whole), but be exact
        more = os.read(fd, RECORD - len(record))
        if not more:
            break
        record += more
    return json.loads(record) if record else None


def _write_report(fd: int, report: dict) -> None:
    data = json.dumps(report).encode()
    while data:
        data = data[os.write(fd, data):]


def _read_report(fd: int) -> dict:
    chunks = []
    while True:
        chunk = os.read(fd, 65536)
        if not chunk:
            break
        chunks.append(chunk)
    os.close(fd)
    return json.loads(b"".join(chunks) or b'{"error": "plot process ended without a report"}')


def _fork_quietly() -> int:
    """``os.fork`` with the garbage collector's objects frozen around it, so that the child's collections
    do not write to (and copy) every page of the parent's objects."""
    sys.stdout.flush()
    sys.stderr.flush()
    gc.freeze()
    pid = os.fork()
    if pid != 0:
        gc.unfreeze()
    return pid


def _report_and_exit(work: Callable[[], dict], report_write: int, helpers: list[int] | None = None) -> None:
    """In a forked child: run ``work``, write its report (or the exception) to ``report_write`` and
    leave with ``os._exit`` (never the parent's exit handlers): 0 on success, 1 on an error.

    The report's pipe is closed before leaving, so the reader has it at once rather than after
    this process's memory is torn down (a few ms); the ``helpers`` it forked (pids) are reaped then.
    """
    code = 1
    try:
        report = work()
        code = 1 if "error" in report else 0
    except BaseException as exc:  # noqa: BLE001 - reported to the parent, which raises it
        report = {"error": f"{type(exc).__name__}: {exc}"}
    try:
        _write_report(report_write, report)
        os.close(report_write)
        for pid in helpers or ():
            os.waitpid(pid, 0)
    finally:
        os._exit(code)


# --------------------------------------------------------------------------- the plotting process
def _draw_jobs(jobs_read: int, folder: Path, save_stage_plot: Callable) -> dict:
    """Take job records from the pipe until it is closed and draw each with ``save_stage_plot``;
    {"drawn": {stage: paths}}, with "error" naming the stage and the cause of the first failure (the later
    jobs are then only discarded)."""
    drawn: dict[str, list[str]] = {}
    error = None
    while True:
        job = _read_record(jobs_read)
        if job is None:
            return {"drawn": drawn} if error is None else {"drawn": drawn, "error": error}
        try:
            if error is None:
                with open(job["file"], "rb") as handle:
                    given = pickle.load(handle)
                drawn[job["stage"]] = [str(p) for p in save_stage_plot(job["stage"], given, folder)]
        except Exception as exc:  # the same report as from the parent: the stage and the cause
            error = plot_error(job["stage"], exc)
        finally:
            Path(job["file"]).unlink(missing_ok=True)


def _drawing_modal() -> None:
    """In a plotting process forked before ``modal`` was imported: make its submodules importable
    without running ``modal/__init__``.

    ``import modal`` loads the whole identification toolkit; drawing needs only a few of its submodules (the
    figures, the result classes it unpickles).
    The package's module is made from its spec but not executed, so each ``modal.<submodule>`` this process
    imports is loaded from the same files, and nothing else.  Only this process sees it; a name that
    ``modal/__init__`` would have provided (``modal.identify``) is missing here, by design.
    """
    sys.modules["modal"] = importlib.util.module_from_spec(importlib.util.find_spec("modal"))


def _plotting_process(jobs_read: int, helpers: list[int]) -> dict:
    """The plotting process: imports, the run's setup record (folder and plot stages), then it forks the
    helper (its pid appended to ``helpers``, to be reaped after the report) and both draw; the two reports
    merged.  Nothing to do when the pipe closes before a setup (a run without plots, or a failed one)."""
    # a short-lived process that ends with os._exit: cyclic garbage (a drawn figure) need not be
    # collected, and not collecting saves ~7 % of the drawing
    gc.disable()
    if "modal" not in sys.modules:  # forked before the parent imported it (python -m balancer run)
        _drawing_modal()
    from . import plots  # matplotlib, imported while the parent computes

    setup = _read_record(jobs_read)
    if setup is None:
        return {"drawn": {}}
    folder = Path(setup["folder"])
    plots.preload(setup["stages"], setup.get("modules", ()))  # what drawing imports: once, not in each drawer
    read, write = os.pipe()
    helper = _fork_quietly()
    if helper == 0:
        def drawer() -> dict:
            os.close(read)
            return _draw_jobs(jobs_read, folder, plots.save_stage_plot)

        _report_and_exit(drawer, write)
    os.close(write)
    helpers.append(helper)
    mine = _draw_jobs(jobs_read, folder, plots.save_stage_plot)
    theirs = _read_report(read)
    errors = [r["error"] for r in (mine, theirs) if "error" in r]
    return {"drawn": {**mine.get("drawn", {}), **theirs.get("drawn", {})},
            **({"error": "; ".join(errors)} if errors else {})}


def _spawn() -> tuple[int, int, int]:
    """Fork a plotting process; (pid, the write end of its jobs pipe, the read end of its report pipe)."""
    jobs_read, jobs_write = os.pipe()
    report_read, report_write = os.pipe()
    pid = _fork_quietly()
    if pid == 0:  # draw, report, leave without running the parent's exit handlers
        os.close(jobs_write)
        os.close(report_read)
        helpers: list[int] = []
        _report_and_exit(lambda: _plotting_process(jobs_read, helpers), report_write, helpers)
    os.close(jobs_read)
    os.close(report_write)
    return pid, jobs_write, report_read


def _can_fork() -> bool:
    """Forking is possible and safe: ``os.fork`` exists and no other thread is alive."""
    return hasattr(os, "fork") and threading.active_count() == 1


# --------------------------------------------------------------------------- started first of all
#: the plotting process :func:`start_early` forked and no run has taken over yet: (pid, jobs pipe, report pipe)
_early: tuple[int, int, int] | None = None


def start_early() -> bool:
    """Fork the plotting process now, before ``modal`` is imported (``python -m balancer run``); a later
    :class:`Plotter` with more than one job takes it over, and :func:`dismiss_early` ends it if none does.
    False (nothing started) where ``os.fork`` is missing, a thread is alive, or there is one CPU."""
    global _early
    if _early is not None or not _can_fork() or (os.cpu_count() or 1) < 2:
        return False
    _early = _spawn()
    return True


def dismiss_early() -> None:
    """End the early plotting process if no run took it over (it has drawn nothing: it is stopped at once)."""
    global _early
    if _early is None:
        return
    pid, jobs_write, report_read = _early
    _early = None
    os.close(jobs_write)
    os.close(report_read)
    try:
        os.kill(pid, signal.SIGKILL)
    except ProcessLookupError:  # pragma: no cover - it had already left
        pass
    os.waitpid(pid, 0)


# --------------------------------------------------------------------------- the parent's side
class Plotter:
    """The plotting processes of a run (``jobs > 1``), seen from the parent.

    Takes over the early plotting process when there is one (:func:`start_early`), else forks one
    now.  ``started`` is False (everything drawn in the parent) where ``os.fork`` is missing or more
    than one thread is alive (forking a threaded process is unsafe).

    Parameters
    ----------
    jobs : int
        Drawing processes wanted; 1 draws in the parent.
    folder : Path
        Folder of the figures.
    stages : sequence of str
        The plot stages it will be handed (the modules their figures need are imported at once).
    modules : sequence of str
        Modules of the run's result classes the figures are handed, imported at once too
        (:func:`.registry.result_modules`).
    """

    def __init__(self, jobs: int, folder: Path, stages=(), modules=()):
        global _early
        self.folder = folder
        self.stages = list(stages)
        self.pid: int | None = None
        self._payloads: list[str] = []
        self._drawn: list[Path] = []
        if max(1, int(jobs)) < 2:
            return
        self.folder.mkdir(parents=True, exist_ok=True)
        if _early is None and _can_fork():
            _early = _spawn()
        if _early is not None:
            (self.pid, self._jobs, self._report), _early = _early, None
            _write_record(self._jobs, {"folder": str(self.folder), "stages": self.stages, "modules": list(modules)})

    @property
    def started(self) -> bool:
        return self.pid is not None

    def submit(self, stage: str, results: dict) -> bool:
        """Hand a stage's plot to the plotters; False if it stays with the parent."""
        if not self.started:
            return False
        handle, payload = tempfile.mkstemp(prefix="modalbal-plot-", suffix=".pickle")
        try:
            with os.fdopen(handle, "wb") as out:
                pickle.dump(results, out, protocol=pickle.HIGHEST_PROTOCOL)
            _write_record(self._jobs, {"stage": stage, "file": payload})
        except Exception:  # noqa: BLE001 - results that do not pickle (or a plotter gone) are drawn here
            Path(payload).unlink(missing_ok=True)
            return False
        self._payloads.append(payload)
        return True

    def collect(self) -> dict[str, list[Path]]:
        """Tell the plotters there is nothing more, wait for them; the paths of each stage they drew
        (raises :class:`~modal.errors.PlotError`, a RuntimeError, if a figure failed there)."""
        if not self.started:
            return {}
        os.close(self._jobs)  # the end of the queue for both drawing processes
        report = _read_report(self._report)
        os.waitpid(self.pid, 0)
        self.pid = None
        for payload in self._payloads:  # left behind by a failure
            Path(payload).unlink(missing_ok=True)
        done = {stage: [Path(p) for p in paths] for stage, paths in report.get("drawn", {}).items()}
        for paths in done.values():
            self._drawn.extend(paths)
        if "error" in report:
            from modal.errors import PlotError  # here only: `import modal` loads the identification toolkit

            raise PlotError(report["error"])
        return done

    def abandon(self) -> None:
        """Wait for the plotters and remove the plots they drew (the run failed)."""
        if self.started:
            try:
                self.collect()
            except RuntimeError:
                pass
        for path in self._drawn:
            path.unlink(missing_ok=True)
