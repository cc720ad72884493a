"""How ``pytest -n N`` shares the default run's tests between its xdist workers: whole files, and every file
that uses a shared session fixture on one worker.

Under xdist's ``load`` the tests of one file alternate between the workers, so both workers computed the
file's module fixtures and cached trials (the calibration cells' 200 noise seeds per case, the first-use
archives), and each worker started the session fixtures its share used (a Dask scheduler with two workers
costs 8-12 CPU-s to start). Here the unit handed to a worker is a file, or the group of every file naming
one of :data:`SHARED_SESSION_FIXTURES`, so each of those computations runs once. ``--dist loadgroup`` would
do the second with marks, but xdist 3.8 writes its group into ``item._nodeid``, which pytest 9 no longer
reads: the groups are worked out here, on the controller, from the test files' paths and text.
"""
from __future__ import annotations

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


class FileGroupScheduling(LoadScopeScheduling):
    """xdist's scope scheduling with a file, or a group of files (:func:`file_group`), as the scope.

    The scopes go out largest first (xdist's ``--loadscope-reorder``, by number of tests), so the run ends
    on small files and neither worker waits long for the other.
    """

    def __init__(self, config, log=None):
        super().__init__(config, log)
        self._root = Path(config.rootpath)
        self._groups: dict[str, str] = {}

    def _split_scope(self, nodeid: str) -> str:
        path = nodeid.split("::", 1)[0]
        if path not in self._groups:
            self._groups[path] = file_group(path, self._root)
        return self._groups[path]
