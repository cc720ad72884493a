"""How ``pytest -n N`` shares the default run's tests between its xdist workers: whole files, and every file
that uses a shared session fixture on one worker.

Under xdist's ``load`` the tests of one file alternate between the workers, so both workers computed the
file's module fixtures and cached trials (the calibration cells' 200 noise seeds per case, the first-use
archives), and each worker started the session fixtures its share used (a Dask scheduler with two workers
costs 8-12 CPU-s to start). Here the unit handed to a worker is a file, or the group of every file naming
one of :data:`SHARED_SESSION_FIXTURES`, so each of those computations runs once. ``--dist loadgroup`` would
do the second with marks, but xdist 3.8 writes its group into ``item._nodeid``, which pytest 9 no longer
reads: the groups are worked out here, on the controller, from the test files' paths and text.

The units go out longest first (:data:`FILE_SECONDS`, measured), so that the run ends on short files and
both workers finish together. xdist's own order is by number of tests: files of a few long tests went late
(tests/modal/batch/test_cluster.py, 4 tests and a twentieth of a worker's time, started in the last tenth of
the run), and a worker that draws such a file last runs it while the other has nothing left.
"""
from __future__ import annotations

import json
from collections import OrderedDict
from pathlib import Path

from xdist.scheduler import LoadScopeScheduling

#: session fixtures that start processes: the files that name one run on one worker (group name)
SHARED_SESSION_FIXTURES = {"dask_cluster": "dask_cluster"}


def file_group(path: str, root: Path) -> str:
    """The worker group of a test file given by its path relative to ``root``: the first shared session
    fixture its text names (:data:`SHARED_SESSION_FIXTURES`), else the file itself."""
    try:
        text = (root / path).read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError):
        return path
    for fixture, group in SHARED_SESSION_FIXTURES.items():
        if fixture in text:
            return group
    return path


#: seconds each test file took, from ``file_seconds.json`` beside this module: the wall time of its tests (setup,
#: call and teardown) in one ``pytest -n 2`` run, on a shared machine (about 3x an idle run's times; only their
#: order is used). Refresh it from ``pytest -n 2 --durations=0 -vv`` with :func:`file_seconds_from_durations`.
FILE_SECONDS: dict[str, float] = json.loads(Path(__file__).with_name("file_seconds.json").read_text("utf-8"))
#: the estimate of a file missing from :data:`FILE_SECONDS`, seconds per test (the median file's, same run)
SECONDS_PER_TEST = 0.5


def unit_seconds(nodeids, file_seconds: dict[str, float] = FILE_SECONDS) -> float:
    """Estimated time of a unit of work, s: each of its files' measured time (``file_seconds``), or for a file
    not measured its number of tests (of ``nodeids``, the unit's node ids) times :data:`SECONDS_PER_TEST`."""
    counts: dict[str, int] = {}
    for nodeid in nodeids:
        path = nodeid.split("::", 1)[0]
        counts[path] = counts.get(path, 0) + 1
    return sum(file_seconds.get(path, n * SECONDS_PER_TEST) for path, n in counts.items())


def longest_first(workqueue, file_seconds: dict[str, float] = FILE_SECONDS) -> OrderedDict:
    """xdist's queue of units (scope -> {node id: done}) reordered by :func:`unit_seconds`, longest first
    (units of equal estimate keep their order)."""
    return OrderedDict(sorted(workqueue.items(), key=lambda item: -unit_seconds(item[1], file_seconds)))


def file_seconds_from_durations(text: str) -> dict[str, float]:
    """Seconds per test file from the report of ``pytest --durations=0 -vv`` (lines ``1.23s call path::test``),
    to 0.1 s: the content of ``file_seconds.json``."""
    seconds: dict[str, float] = {}
    for line in text.splitlines():
        parts = line.split()
        if len(parts) == 3 and parts[0].endswith("s") and parts[1] in ("setup", "call", "teardown"):
            try:
                value = float(parts[0][:-1])
            except ValueError:
                continue
            path = parts[2].split("::", 1)[0]
            seconds[path] = seconds.get(path, 0.0) + value
    return {path: round(value, 1) for path, value in sorted(seconds.items())}


class FileGroupScheduling(LoadScopeScheduling):
    """xdist's scope scheduling with a file, or a group of files (:func:`file_group`), as the scope.

    The scopes go out longest first (:func:`unit_seconds`), so the run ends on short files and neither
    worker waits long for the other.
    """

    def __init__(self, config, log=None):
        super().__init__(config, log)
        self._root = Path(config.rootpath)
        self._groups: dict[str, str] = {}
        self._ordered = False

    def _split_scope(self, nodeid: str) -> str:
        path = nodeid.split("::", 1)[0]
        if path not in self._groups:
            self._groups[path] = file_group(path, self._root)
        return self._groups[path]

    def _assign_work_unit(self, node) -> None:
        if not self._ordered:  # the first assignment: the queue is complete, in xdist's order
            self.workqueue = longest_first(self.workqueue)
            self._ordered = True
        super()._assign_work_unit(node)
