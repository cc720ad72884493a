"""A fresh interpreter that runs each script given to it in a forked copy of itself: :class:`ForkServer`.

For tests whose scripts need a process of their own (a crash must not take pytest down; a fork needs a
process without threads, which the test process may not be) but not a new interpreter's imports each time:
the server runs its ``preload`` code once, then forks a child per script and runs the script there, in the
preload's globals, as a fresh interpreter that had run the preload first would. The server itself runs no
script, so one script cannot affect another. Each run comes back as ``subprocess.run`` gives it: exit code
(minus the signal number for a child killed by a signal), stdout and stderr.
"""
from __future__ import annotations

import json
import os
import select
import signal
import subprocess
import sys
import tempfile
from collections.abc import Mapping, Sequence
from pathlib import Path

#: the server: preload (its first argument), then one JSON request per line on stdin; for each, the child's
#: pid, then its exit code once it has ended, one line each on stdout
_SERVER = r"""
import json, os, sys, traceback
fork = os.fork  # the preload may wrap os.fork for its scripts (counting their forks): not for the server's
replies = os.fdopen(os.dup(1), "w")
os.dup2(os.open(os.devnull, os.O_WRONLY), 1)  # the preload's and the server's own prints go nowhere
namespace = {"__name__": "__main__", "__builtins__": __builtins__}
exec(compile(sys.argv[1], "<preload>", "exec"), namespace)
while True:
    line = sys.stdin.readline()
    if not line:
        break
    request = json.loads(line)
    sys.stdout.flush()
    sys.stderr.flush()
    pid = fork()
    if pid == 0:
        code = 0
        try:
            replies.close()
            os.dup2(os.open(os.devnull, os.O_RDONLY), 0)
            for fd, path in ((1, request["stdout"]), (2, request["stderr"])):
                os.dup2(os.open(path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600), fd)
            os.chdir(request["cwd"])
            sys.argv = request["argv"]
            exec(compile(request["code"], "<script>", "exec"), namespace)
        except SystemExit as exc:
            code = exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 1)
            if not isinstance(exc.code, (int, type(None))):
                print(exc.code, file=sys.stderr)
        except BaseException:
            traceback.print_exc()
            code = 1
        finally:
            sys.stdout.flush()
            sys.stderr.flush()
            os._exit(code)
    print(pid, file=replies, flush=True)
    _, status = os.waitpid(pid, 0)
    print(os.waitstatus_to_exitcode(status), file=replies, flush=True)
"""


class ForkServer:
    """An interpreter that has run ``preload`` and forks a child for each :meth:`run`.

    Parameters
    ----------
    preload : str
        Python code run once in the server (imports, shared set-up); its globals are every script's.
    env : mapping, optional
        The server's environment (default: this process's), inherited by every script.
    cwd : path-like, optional
        The server's working directory.
    """

    def __init__(self, preload: str = "", env: Mapping[str, str] | None = None,
                 cwd: str | os.PathLike | None = None):
        self._proc = subprocess.Popen([sys.executable, "-c", _SERVER, preload], stdin=subprocess.PIPE,
                                      stdout=subprocess.PIPE, env=None if env is None else dict(env), cwd=cwd)
        self._buffer = b""

    def _line(self, timeout: float | None) -> str:
        """The server's next reply line; ``subprocess.TimeoutExpired`` after ``timeout`` seconds without one."""
        fd = self._proc.stdout.fileno()
        while b"\n" not in self._buffer:
            ready, _, _ = select.select([fd], [], [], timeout)
            if not ready:
                raise subprocess.TimeoutExpired(self._proc.args[:2], timeout)
            chunk = os.read(fd, 4096)
            if not chunk:
                raise RuntimeError(f"the fork server ended (exit {self._proc.wait()})")
            self._buffer += chunk
        line, self._buffer = self._buffer.split(b"\n", 1)
        return line.decode()

    def run(self, code: str, args: Sequence[object] = (), cwd: str | os.PathLike | None = None,
            timeout: float | None = None) -> subprocess.CompletedProcess:
        """Run ``code`` in a forked child, as ``python -c CODE ARGS`` would in a fresh interpreter after the preload.

        Parameters
        ----------
        code : str
            The script.
        args : sequence
            Its ``sys.argv[1:]``, each as ``str(arg)``.
        cwd : path-like, optional
            Its working directory (default: this process's).
        timeout : float, optional
            Seconds to wait, s: past them the child is killed and ``subprocess.TimeoutExpired`` raised.

        Returns
        -------
        subprocess.CompletedProcess
            ``returncode`` (``-N`` for a child killed by signal N), ``stdout`` and ``stderr`` as text.
        """
        argv = ["-c", *map(str, args)]
        with tempfile.TemporaryDirectory(prefix="modalbal-fork-") as folder:
            out, err = Path(folder) / "stdout", Path(folder) / "stderr"
            request = {"code": code, "argv": argv, "cwd": str(Path(cwd or os.getcwd()).resolve()),
                       "stdout": str(out), "stderr": str(err)}
            self._proc.stdin.write((json.dumps(request) + "\n").encode())
            self._proc.stdin.flush()
            pid = int(self._line(None))
            try:
                returncode = int(self._line(timeout))
            except subprocess.TimeoutExpired:
                os.kill(pid, signal.SIGKILL)
                self._line(None)
                raise
            return subprocess.CompletedProcess([sys.executable, *argv], returncode,
                                               out.read_text(errors="replace"), err.read_text(errors="replace"))

    def close(self) -> None:
        """End the server (it has no child left: each run waits for its own)."""
        if self._proc.poll() is None:
            self._proc.stdin.close()
            try:
                self._proc.wait(timeout=10)
            except subprocess.TimeoutExpired:
                self._proc.kill()
                self._proc.wait()
        self._proc.stdout.close()
