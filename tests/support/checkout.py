"""What a test run leaves in the checkout: a snapshot before and after, compared.

``git status --porcelain --ignored`` lists new and changed files, tracked, untracked and
ignored; an ignored or untracked folder is listed once, as a folder, so the files inside
each such folder are listed too, or a second ``out/inline.h5`` written into an ``out/``
that was already there would go unseen. Ignored files (where runs write their outputs)
carry their size and modification time, so that one rewritten is seen too; tracked and
untracked files carry only their status, so that a person editing the sources while the
suite runs is not blamed on the tests (a test that changes a clean tracked file, or makes
a new one, is still seen). Virtual environments and the caches of Python and the test
tools are left out: running the suite makes them, and they belong to no one's work.

:class:`CheckoutGuard` is the pytest plugin that takes the snapshots at the start and the
end of a session and fails the session, naming the files, when a run left any.
"""
from __future__ import annotations

import os
import subprocess
from pathlib import Path

import pytest

__all__ = ["snapshot", "left_behind", "CheckoutGuard", "IGNORED_NAMES"]

#: folders (at any depth) whose contents a run may create or change
IGNORED_NAMES = frozenset({".venv", "venv", "__pycache__", ".pytest_cache", ".hypothesis", ".mypy_cache",
                           ".ruff_cache", ".tox", ".nox"})


def _skipped(relative: str) -> bool:
    parts = Path(relative).parts
    return any(part in IGNORED_NAMES or part.endswith(".egg-info") for part in parts)


def snapshot(root: str | os.PathLike) -> set[str] | None:
    """Entries describing the checkout's state beyond its commit; None where git cannot tell (no git, no checkout)."""
    root = Path(root)
    try:
        # no optional locks: the snapshot must not get in the way of git commands run meanwhile
        done = subprocess.run(["git", "--no-optional-locks", "status", "--porcelain", "--ignored", "-z"], cwd=root,
                              capture_output=True, timeout=120)
    except (OSError, subprocess.TimeoutExpired):
        return None
    if done.returncode != 0:
        return None
    entries: set[str] = set()
    for record in done.stdout.decode("utf-8", "surrogateescape").split("\0"):
        if len(record) < 4:
            continue
        status, path = record[:2], record[3:]
        if _skipped(path):
            continue
        full = root / path
        if status in ("??", "!!") and full.is_dir():  # a folder listed as one entry: its files, one by one
            for folder, dirs, files in os.walk(full):
                dirs[:] = [d for d in dirs if d not in IGNORED_NAMES and not d.endswith(".egg-info")]
                for name in files:
                    entries.add(_describe(root, Path(folder) / name, status) if status == "!!" else
                                f"{status} {(Path(folder) / name).relative_to(root).as_posix()}")
        elif status == "!!" and full.is_file():
            entries.add(_describe(root, full, status))
        else:
            entries.add(f"{status} {path}")
    return entries


def _describe(root: Path, path: Path, status: str) -> str:
    try:
        stat = path.stat()
        return f"{status} {path.relative_to(root).as_posix()} ({stat.st_size} bytes, mtime {stat.st_mtime_ns})"
    except OSError:
        return f"{status} {path.relative_to(root).as_posix()}"


def left_behind(before: set[str] | None, after: set[str] | None) -> list[str]:
    """The entries of ``after`` not in ``before`` (what a run wrote), sorted; empty where either is unknown."""
    if before is None or after is None:
        return []
    return sorted(after - before)


class CheckoutGuard:
    """A pytest plugin: the session fails when its tests left new or changed files in the checkout at ``root``.

    Register it once (``config.pluginmanager.register(CheckoutGuard(root))``). Outside a git checkout it
    checks nothing; a run that only collects is not checked.
    """

    def __init__(self, root: str | os.PathLike):
        self.root = Path(root)
        self.before: set[str] | None = None

    def pytest_sessionstart(self, session) -> None:
        self.before = snapshot(self.root)

    @pytest.hookimpl(tryfirst=True)  # before the terminal summary, which then shows the failed status
    def pytest_sessionfinish(self, session, exitstatus) -> None:
        if self.before is None or session.config.option.collectonly:
            return
        left = left_behind(self.before, snapshot(self.root))
        if not left:
            return
        lines = [f"the test run left {len(left)} new or changed file(s) in the checkout {self.root} (every test "
                 "writes under a temporary folder: tmp_path; pass out=, plots_dir= or cwd= pointing there):"]
        lines += [f"  {entry}" for entry in left[:50]]
        reporter = session.config.pluginmanager.get_plugin("terminalreporter")
        if reporter is not None:
            reporter.ensure_newline()
            for line in lines:
                reporter.write_line(line, red=True, bold=line is lines[0])
        session.exitstatus = pytest.ExitCode.TESTS_FAILED
