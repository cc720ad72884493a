"""Fuzzing every reader: mutated valid files give an FRF/Scene or the toolkit's own error.

Seeds are small valid files written by the toolkit's own writers (UFF 58 ASCII
and 58b binary, CSV in several layouts, MAT v5 and v7.3, HDF5) and the demo
scene TOML.  Each input is one seed mutated by a seeded RNG (``Random(f"{fmt}:{i}")``,
so every input is reproducible from its format and index): bit flips,
truncation, byte insertion and deletion, line duplication and deletion, number
mangling (NaN, Inf, huge, tiny, negative, malformed), and for the HDF5-based
formats structural edits made with h5py (deleted or retyped datasets and
attributes).

Allowed outcomes: a valid :class:`modal.FRF` (or :class:`balancer.scene.Scene`),
or a :class:`modal.errors.ModalError` subclass (FormatError,
FRFValidationError, SceneError, ...).  ModalWarning warnings are allowed.
Anything else — another exception, a hang beyond ``TIME_LIMIT_S`` — is a
finding; the test lists each distinct one with the format and index that
reproduce it (``python tests/fuzz/test_readers.py FORMAT INDEX OUT`` writes
that input to OUT).

The default run tries ``FAST_COUNT`` inputs per format; ``-m stress`` tries
``STRESS_COUNT`` (10,000) per format.
"""
from __future__ import annotations

import math
import os
import re
import select
import shutil
import signal
import sys
import tempfile
import time
import traceback
import warnings
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # tests/: support and conftest
os.environ.setdefault("MPLBACKEND", "Agg")

import modal  # noqa: E402
from modal.errors import ModalError, ModalWarning  # noqa: E402

from support.fuzzinputs import Seed, make_seeds, mutated_input  # noqa: E402
from support.paths import ROOT, SYNTHETIC  # noqa: E402

FAST_COUNT = int(os.environ.get("FUZZ_FAST_COUNT", "60"))
STRESS_COUNT = int(os.environ.get("FUZZ_STRESS_COUNT", "10000"))
#: a reader that takes longer than this on a file of a few kB is hanging (normal reads
#: take about 20 ms); the forked reader is killed and the input recorded as a finding
TIME_LIMIT_S = 5
#: read_frf gives up on an HDF5 file after ``modal.io.hdf5.READ_TIMEOUT_S`` (20 s) with a
#: FormatError (libhdf5 loops forever on about 1 damaged file in 160, finding 8); here it
#: gives up after 1 s, 20 times a read's time under heavy load (45 ms at load 18), so that
#: such inputs end in that FormatError before the watchdog and each costs 1 s instead of 20
HDF5_READ_TIMEOUT_S = 1.0
FORMATS = ("uff58", "uff58b", "csv", "mat", "mat73", "hdf5", "scene")


# --------------------------------------------------------------------------- harness
class Hang(Exception):
    """A reader ran past TIME_LIMIT_S."""


def _alarm(signum, frame):  # pragma: no cover - only on a hang
    raise Hang(f"no result after {TIME_LIMIT_S} s")


def read_any(fmt: str, path: Path, hints: dict):
    if fmt == "scene":
        from balancer.scene import load_scene

        return load_scene(path)
    return modal.read_frf(path, **hints)


def _signature(exc: BaseException) -> str:
    frames = traceback.extract_tb(exc.__traceback__)
    ours = [fr for fr in frames if "/modal/" in fr.filename or "/balancer/" in fr.filename]
    where = ours[-1] if ours else (frames[-1] if frames else None)
    place = f"{Path(where.filename).name}:{where.lineno} {where.name}" if where else "?"
    return f"{type(exc).__name__} at {place}"


def _clean(text: str) -> str:
    return " ".join(str(text).split())[:200]


def _read_one(fmt: str, index: int, seed: Seed, path: Path, out) -> None:
    """Read one input and log its outcome (``W`` lines for foreign warnings, then ``R``)."""
    from balancer.scene import Scene

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        signal.alarm(TIME_LIMIT_S)
        try:
            result = read_any(fmt, path, seed.hints)
            expected = Scene if fmt == "scene" else modal.FRF
            if not isinstance(result, expected):
                outcome = f"finding\treturned {type(result).__name__}\t{_clean(repr(result))}"
            elif fmt != "scene" and not (np.all(np.isfinite(result.frequency_hz))
                                         and np.all(np.diff(result.frequency_hz) > 0)
                                         and np.all(np.isfinite(result.response))):
                outcome = "finding\tinvalid FRF returned\t"
            else:
                outcome = "valid\t\t"
        except ModalError as exc:
            outcome = f"{type(exc).__name__}\t\t"
        except Exception as exc:  # noqa: BLE001 - the finding we are looking for
            outcome = f"finding\t{_signature(exc)}\t{_clean(exc)}"
        finally:
            signal.alarm(0)
    for w in caught:
        if not issubclass(w.category, ModalWarning):
            out.write(f"W\t{index}\t{w.category.__name__}: {_clean(w.message)[:80]}\n")
    out.write(f"R\t{index}\t{outcome}\n")
    out.flush()


def _reader(fmt: str, seeds: dict[str, list[Seed]], start: int, count: int, folder: Path, out) -> None:
    """Read inputs ``start..count-1`` one after another, ``S i`` written before input ``i`` is read."""
    for index in range(start, count):
        seed, how, data = mutated_input(seeds, fmt, index)
        path = folder / seed.name  # scene: relative file references resolve in the folder
        path.write_bytes(data)
        out.write(f"S\t{index}\t{how}\n")
        out.flush()
        _read_one(fmt, index, seed, path, out)


def _watch(pid: int, fd: int, out, count: int) -> int:
    """Copy a forked reader's log lines from ``fd`` to ``out`` until it ends; the next index to read.

    A reader that gives no result ``TIME_LIMIT_S`` (plus 1 s) after starting an input is
    hanging (inside compiled code SIGALRM cannot end it): it is killed and the input recorded.
    A reader that dies records a finding for the input it was reading.
    """
    pending: int | None = None  # the index started and not finished
    last = -1
    deadline = math.inf
    buffer = b""
    while True:
        ready, _, _ = select.select([fd], [], [], max(0.0, min(deadline - time.monotonic(), 1.0)))
        if not ready:
            if time.monotonic() <= deadline:
                continue
            os.killpg(pid, signal.SIGKILL)  # with the reader's own forked child, stuck in libhdf5
            os.waitpid(pid, 0)
            os.close(fd)
            out.write(f"R\t{pending}\tfinding\thang: no result after {TIME_LIMIT_S} s (killed)\t\n")
            out.flush()
            return pending + 1
        chunk = os.read(fd, 65536)
        if not chunk:
            break
        buffer += chunk
        *lines, buffer = buffer.split(b"\n")
        for line in lines:
            text = line.decode("utf-8")
            out.write(text + "\n")
            kind, index = text.split("\t", 2)[:2]
            if kind == "S":
                pending, deadline = int(index), time.monotonic() + TIME_LIMIT_S + 1.0
            elif kind == "R":
                pending, last, deadline = None, int(index), math.inf
        out.flush()
    os.close(fd)
    _, status = os.waitpid(pid, 0)
    if pending is not None:
        code = os.waitstatus_to_exitcode(status)
        reason = f"signal {-code}" if code < 0 else f"exit {code}"
        out.write(f"R\t{pending}\tfinding\tprocess died ({reason}) reading the input\t\n")
        out.flush()
        return pending + 1
    if last + 1 < count:
        raise RuntimeError(f"fuzz reader for input {last + 1} ended without reading it (status {status})")
    return count


def child(fmt: str, start: int, count: int, folder: Path, log: Path, seeds: dict[str, list[Seed]]) -> None:
    """Read inputs ``start..count-1`` of ``fmt`` (mutations of ``seeds``), one log line per outcome.

    Runs in its own process (see :func:`fuzz`). Where ``os.fork`` exists the inputs are read
    in a forked reader process, one after another; when a reader kills its process (a
    segfault in a compiled library) or hangs, that is recorded for the input it was reading
    and a new reader, forked again from this process (seeds made, modules loaded), carries
    on with the next input. ``S i`` is written before input ``i`` is read.
    """
    if fmt == "scene":
        shutil.copy(SYNTHETIC / "demo_frf.csv", folder / "demo_frf.csv")
    import balancer.scene  # noqa: F401 - loaded once, before forking
    import modal.io.csv, modal.io.hdf5, modal.io.mat, modal.io.uff  # noqa: E401,F401
    modal.io.hdf5.READ_TIMEOUT_S = HDF5_READ_TIMEOUT_S
    signal.signal(signal.SIGALRM, _alarm)
    with open(log, "a", encoding="utf-8", buffering=1) as out:
        if not hasattr(os, "fork"):
            _reader(fmt, seeds, start, count, folder, out)
            return
        index = start
        while index < count:
            read_end, write_end = os.pipe()
            pid = os.fork()
            if pid == 0:  # the reader: read, log to the pipe, leave without cleanup
                code = 0
                os.setpgid(0, 0)  # its own group: a hang kills it with the children it forked
                os.close(read_end)
                try:
                    with os.fdopen(write_end, "w", encoding="utf-8") as pipe:
                        _reader(fmt, seeds, index, count, folder, pipe)
                except BaseException:  # noqa: BLE001 - the parent records the death
                    code = 3
                os._exit(code)
            os.close(write_end)
            index = _watch(pid, read_end, out, count)


@dataclass
class Tally:
    """Outcomes of one format's fuzz run."""

    tried: int = 0
    outcomes: Counter = field(default_factory=Counter)
    other_warnings: Counter = field(default_factory=Counter)
    findings: dict = field(default_factory=dict)  # signature -> [count, first index, mutation, message]

    def finding(self, signature: str, index: int, how: str, message: str) -> None:
        entry = self.findings.setdefault(signature, [0, index, how, message])
        entry[0] += 1
        self.outcomes["finding"] += 1


#: what a fuzzing child process starts from (:func:`fuzz`): this module, its seeds and the readers loaded once
CHILD_PRELOAD = f"""
import importlib.util, sys
from pathlib import Path
spec = importlib.util.spec_from_file_location("fuzz_readers", {__file__!r})
fuzzing = sys.modules["fuzz_readers"] = importlib.util.module_from_spec(spec)
spec.loader.exec_module(fuzzing)
seeds = fuzzing.make_seeds()
import balancer.scene, modal.io.csv, modal.io.hdf5, modal.io.mat, modal.io.uff
"""


def fuzz(fmt: str, count: int, folder: Path, server) -> Tally:
    """Read ``count`` mutated inputs of ``fmt`` in child processes; classify every outcome.

    Each child is forked by ``server`` (a :class:`support.forkserver.ForkServer` of :data:`CHILD_PRELOAD`).
    A child that dies (a signal such as SIGSEGV, or an exit without a result)
    is recorded as a finding for the input it was reading, and a new child
    carries on with the next input.
    """
    tally = Tally()
    log = folder / f"{fmt}.log"
    start = 0
    while start < count:
        proc = server.run("fuzzing.child(sys.argv[1], *map(int, sys.argv[2:4]), *map(Path, sys.argv[4:6]), seeds)",
                          [fmt, start, count, folder, log], cwd=ROOT, timeout=count * TIME_LIMIT_S + 120)
        started: dict[int, str] = {}
        done: set[int] = set()
        for line in log.read_text(encoding="utf-8").splitlines():
            parts = line.split("\t")
            if parts[0] == "S":
                started[int(parts[1])] = parts[2]
            elif parts[0] == "R":
                done.add(int(parts[1]))
        missing = sorted(set(started) - done)
        if proc.returncode == 0 and not missing:
            break
        if not missing:  # died before reading anything: a harness problem, not a finding
            raise RuntimeError(f"fuzz child for {fmt} failed: {proc.stderr[-2000:]}")
        index = missing[-1]
        reason = f"signal {-proc.returncode}" if proc.returncode < 0 else f"exit {proc.returncode}"
        last = [ln for ln in proc.stderr.splitlines() if ln.strip()][-1:] or [""]
        with open(log, "a", encoding="utf-8") as out:
            out.write(f"R\t{index}\tfinding\tprocess died ({reason}) reading the input\t{_clean(last[0])}\n")
        start = index + 1
    for line in log.read_text(encoding="utf-8").splitlines():
        parts = line.split("\t")
        if parts[0] == "S":
            started_how = parts[2]
            continue
        if parts[0] == "W":
            tally.other_warnings[parts[2]] += 1
        elif parts[0] == "R":
            tally.tried += 1
            if parts[2] == "finding":
                tally.finding(parts[3], int(parts[1]), started_how, parts[4] if len(parts) > 4 else "")
            else:
                tally.outcomes[parts[2]] += 1
    return tally


def report(fmt: str, tally: Tally) -> str:
    lines = [f"{fmt}: {tally.tried} inputs; outcomes {dict(tally.outcomes)}"]
    for sig, (n, first, how, message) in sorted(tally.findings.items(), key=lambda kv: -kv[1][0]):
        lines.append(f"  FINDING {sig}: {n} inputs, first index {first} ({how}): {message}")
    for text, n in tally.other_warnings.most_common(5):
        lines.append(f"  non-toolkit warning x{n}: {text}")
    return "\n".join(lines)


@pytest.fixture(scope="module")
def seeds() -> dict[str, list[Seed]]:
    made = make_seeds()
    # every seed must itself be valid, or the fuzzing says nothing
    with tempfile.TemporaryDirectory() as folder:
        for fmt, items in made.items():
            if fmt == "scene":
                shutil.copy(SYNTHETIC / "demo_frf.csv", Path(folder) / "demo_frf.csv")
            for seed in items:
                path = Path(folder) / seed.name
                path.write_bytes(seed.data)
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore", ModalWarning)
                    assert read_any(fmt, path, seed.hints) is not None
    return made


@pytest.fixture(scope="module")
def server():
    """The fuzzing children's and the crash scripts' fork server (:data:`CHILD_PRELOAD`)."""
    from support.forkserver import ForkServer

    running = ForkServer(CHILD_PRELOAD, env={**os.environ, "MPLBACKEND": "Agg"}, cwd=ROOT)
    yield running
    running.close()


def _run(fmt: str, count: int, tmp_path: Path, server) -> Tally:
    tally = fuzz(fmt, count, tmp_path, server)
    text = report(fmt, tally)
    print(text)
    assert tally.tried == count, text
    # the mutations must reach past the first check: some inputs refused with the toolkit's error
    assert sum(v for k, v in tally.outcomes.items() if k not in ("valid", "finding")) > 0, text
    return tally


#: findings reported to the lead and not yet fixed, tolerated here (format -> signature
#: prefixes) so that the fuzzing keeps running; each should be pinned by a strict xfail
KNOWN_FINDINGS: dict[str, tuple[str, ...]] = {
    # HDF5 (h5py / the HDF5 library): a damaged global heap makes an attribute read spin
    # forever (about 1 input in 160). read_frf now gives up after 20 s with a FormatError
    # (test_stress_hdf5_attribute_hang_ends_in_a_format_error), but this fuzzer's own 5 s
    # limit kills the child first, so such inputs are still tallied here as known
    # ("process died (signal 9)": killed by an outside watchdog before that limit existed)
    "hdf5": ("hang", "process died (signal 9)"),
}


def _unexpected(fmt: str, tally: Tally) -> list[str]:
    known = KNOWN_FINDINGS.get(fmt, ())
    return [sig for sig in tally.findings if not (known and sig.startswith(known))]


@pytest.mark.parametrize("fmt", FORMATS)
def test_fuzz_readers_give_frf_or_toolkit_error(fmt, seeds, server, tmp_path):
    tally = _run(fmt, FAST_COUNT, tmp_path, server)
    assert not _unexpected(fmt, tally), report(fmt, tally)


@pytest.mark.stress
@pytest.mark.stress_quick
@pytest.mark.parametrize("fmt", FORMATS)
def test_stress_fuzz_readers_give_frf_or_toolkit_error(fmt, seeds, server, tmp_path):
    tally = _run(fmt, STRESS_COUNT, tmp_path, server)
    assert not _unexpected(fmt, tally), report(fmt, tally)


_MAT_CRASH = """
import numpy as np, modal
f = 4.0 * np.arange(48)
frf = modal.modal_frf(f, [40.0, 130.0], [0.02, 0.03], [1.0, 0.5], kind="accelerance",
                      response_points=["1+Z"], reference_points=["1+Z"])
path = {path!r}
modal.write_frf(frf, path, format="mat")
data = bytearray(open(path, "rb").read())
name = data.index(b"units")
flags = data.rfind(bytes([6, 0, 0, 0, 8, 0, 0, 0]), 0, name) + 8   # array-flags subelement
assert data[flags] == 4                                               # mxCHAR_CLASS
data[flags] = 5                                                       # mxSPARSE_CLASS
open(path, "wb").write(bytes(data))
try:
    modal.read_frf(path)
    print("read")
except modal.ModalError as exc:
    print(type(exc).__name__)
"""


def test_mat_v5_char_marked_sparse_is_a_format_error(server, tmp_path):
    """Stress finding (fixed in da3e38b): scipy.io.loadmat died (SIGSEGV) on a char array whose
    class byte says sparse; run in a process of its own so that a regression cannot take pytest down."""
    proc = server.run(_MAT_CRASH.format(path=str(tmp_path / "crash.mat")), cwd=ROOT, timeout=120)
    assert proc.returncode == 0, f"exit {proc.returncode}: {proc.stderr[-500:]}"
    assert "FormatError" in proc.stdout, proc.stdout


def _main(argv: list[str]) -> None:
    """``FMT INDEX OUT``: write one mutated input to OUT for a bug report."""
    fmt_arg, index_arg, out_arg = argv[0], int(argv[1]), Path(argv[2])
    seed_used, how_used, data_used = mutated_input(make_seeds(), fmt_arg, index_arg)
    out_arg.write_bytes(data_used)
    print(f"{out_arg}: {fmt_arg} input {index_arg} = {seed_used.name} mutated by {how_used}; "
          f"read hints {seed_used.hints}")


if __name__ == "__main__":
    _main(sys.argv[1:])


def test_scene_integer_beyond_float_range_is_a_scene_error():
    """Stress finding (fixed in da3e38b): float() of a huge TOML integer raised OverflowError."""
    from balancer.scene import parse_scene
    from modal.errors import SceneError

    with pytest.raises(SceneError, match="M"):
        parse_scene({"outputs": {"tables": ["rotor"]}, "rotor": {"M": 10**400, "k": 1e4, "c": 1.0, "e": 1e-4}})


_MAT_CELL_CRASH = """
import numpy as np, modal
f = 4.0 * np.arange(48)
frf = modal.modal_frf(f, [40.0, 130.0], [0.02, 0.03], np.ones((3, 2)), kind="mobility",
                      response_points=["1+Z", "2+Z", "3+Z"], reference_points=["1+Z"] * 3)
path = {path!r}
modal.write_frf(frf, path, format="mat")
data = bytearray(open(path, "rb").read())
text = data.index(b"3+Z", data.index(b"response_points"))
assert data[text - 24] == 8
data[text - 24] = 10          # the third cell's dimensions element claims 10 bytes; it holds 8
open(path, "wb").write(bytes(data))
try:
    modal.read_frf(path)
    print("read")
except modal.ModalError as exc:
    print(type(exc).__name__)
"""


def test_mat_v5_damaged_cell_element_is_a_format_error(server, tmp_path):
    """Stress finding (fixed in 22bb339): a cell element whose dimensions length is wrong killed
    the process inside scipy.io.loadmat, past the whosmat check of da3e38b (50 of 10 000 inputs)."""
    proc = server.run(_MAT_CELL_CRASH.format(path=str(tmp_path / "cell.mat")), cwd=ROOT, timeout=120)
    assert proc.returncode == 0, f"exit {proc.returncode}: {proc.stderr[-500:]}"
    assert "FormatError" in proc.stdout, proc.stdout


_HDF5_SEED = """
import numpy as np, modal
rng = np.random.default_rng(1)
const = rng.standard_normal((1, 2)) + 0.1j * rng.standard_normal((1, 2))
frf = modal.modal_frf(4.0 * np.arange(48), [40.0, 130.0], [0.02, 0.03], const[0], kind="accelerance",
                      response_points=["1+Z"], reference_points=["1+Z"])
path = {path!r}
modal.write_frf(frf, path, format="hdf5")
data = open(path, "rb").read()
"""


@pytest.mark.stress
@pytest.mark.stress_quick
def test_stress_hdf5_attribute_hang_ends_in_a_format_error(server, tmp_path):
    """Regression (fixed in modal/io/_isolate.py): one inserted byte made libhdf5 spin forever
    inside an attribute read; read_frf now reads HDF5 in a forked child and gives up after 20 s."""
    # the time limit is lowered from its 20 s: what is tested is that the loop ends in a FormatError
    script = _HDF5_SEED.format(path=str(tmp_path / "hang.h5")) + """
open(path, "wb").write(data[:2349] + bytes([0xa1]) + data[2349:])
import modal.io.hdf5
modal.io.hdf5.READ_TIMEOUT_S = 2.0
try:
    modal.read_frf(path)
except modal.FormatError as exc:
    print(exc)
"""
    proc = server.run(script, cwd=ROOT, timeout=60)
    assert proc.returncode == 0, proc.stderr[-500:]
    assert "hang.h5" in proc.stdout and "did not finish" in proc.stdout, proc.stdout


def test_hdf5_damaged_float_type_is_a_format_error(server, tmp_path):
    """Stress finding (fixed in 73e3971): h5py's ValueError from Dataset.dtype on a damaged float
    datatype escaped read_frf_group."""
    script = _HDF5_SEED.format(path=str(tmp_path / "type.h5")) + """
data = bytearray(data)
data[7418] |= 0x40          # a bit of the frequency_hz float datatype message
open(path, "wb").write(bytes(data))
try:
    modal.read_frf(path)
    print("read")
except modal.ModalError as exc:
    print(type(exc).__name__)
"""
    proc = server.run(script, cwd=ROOT, timeout=60)
    assert proc.returncode == 0, proc.stderr[-500:]
    assert "FormatError" in proc.stdout, proc.stdout


def _forked_reader(body) -> tuple[int, int]:
    """A forked process in its own group running ``body(pipe)``, like the fuzzer's reader: (pid, read end)."""
    read_end, write_end = os.pipe()
    pid = os.fork()
    if pid == 0:  # pragma: no cover - the child
        os.setpgid(0, 0)
        os.close(read_end)
        try:
            with os.fdopen(write_end, "w", encoding="utf-8") as pipe:
                body(pipe)
        finally:
            os._exit(0)
    os.close(write_end)
    return pid, read_end


@pytest.mark.skipif(not hasattr(os, "fork"), reason="the reader process is forked")
def test_a_reader_that_dies_or_hangs_is_recorded_and_the_run_goes_on(monkeypatch):
    import io

    def dies(pipe):
        pipe.write("S\t3\tbit_flips\n")
        pipe.flush()
        os.kill(os.getpid(), signal.SIGKILL)

    out = io.StringIO()
    pid, fd = _forked_reader(dies)
    assert _watch(pid, fd, out, 10) == 4  # the next reader starts after the input that killed this one
    assert "R\t3\tfinding\tprocess died (signal 9) reading the input" in out.getvalue()

    def hangs(pipe):
        pipe.write("S\t4\tinsert\nR\t4\tvalid\t\t\n")
        helper = os.fork()  # like read_frf's own child, stuck in compiled code
        if helper == 0:
            time.sleep(60)
            os._exit(0)
        pipe.write(f"W\t{helper}\thelper\nS\t5\tdelete\n")
        pipe.flush()
        time.sleep(60)

    monkeypatch.setitem(globals(), "TIME_LIMIT_S", 0.2)
    out = io.StringIO()
    pid, fd = _forked_reader(hangs)
    start = time.monotonic()
    assert _watch(pid, fd, out, 10) == 6
    # killed 0.2 s (+1 s) after starting input 5, not after the helper's 60 s
    assert time.monotonic() - start < 10
    assert "R\t4\tvalid" in out.getvalue() and "R\t5\tfinding\thang: no result after 0.2 s" in out.getvalue()
    helper = int(re.search(r"W\t(\d+)\thelper", out.getvalue()).group(1))
    deadline = time.monotonic() + 5  # killed with the reader's group, then reaped by init
    while time.monotonic() < deadline:
        try:
            os.kill(helper, 0)
        except ProcessLookupError:
            break
        time.sleep(0.05)
    else:
        raise AssertionError(f"the reader's child {helper} outlived the hang")
