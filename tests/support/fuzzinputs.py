"""The readers' fuzzing inputs (tests/fuzz/test_readers.py): small valid seed files written by the toolkit's own
writers, and their mutations, each input reproducible from its format and index."""
from __future__ import annotations

import random
import re
import tempfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np

import modal
from modal.io import write_frf

from support.paths import SYNTHETIC

# --------------------------------------------------------------------------- seeds
def _seed_frf(n_channels: int, kind: str, n_lines: int = 48):
    f = 4.0 * np.arange(n_lines)  # an even axis that UFF 58 ASCII keeps exactly
    rng = np.random.default_rng(n_channels)
    const = rng.standard_normal((n_channels, 2)) + 0.1j * rng.standard_normal((n_channels, 2))
    return modal.modal_frf(f, [40.0, 130.0], [0.02, 0.03], const if n_channels > 1 else const[0], kind=kind,
                           response_points=[f"{i + 1}+Z" for i in range(n_channels)],
                           reference_points=["1+Z"] * n_channels)


@dataclass
class Seed:
    """A valid seed file's bytes, its name and the reader hints it needs."""

    name: str
    data: bytes
    hints: dict = field(default_factory=dict)


#: writers stamp the time (UFF 58 date field, MAT header, HDF5 @created): the same-length
#: stamp with every digit set to 1 keeps the seeds, hence every mutated input, reproducible
TIMESTAMPS = re.compile(rb"\d{2}-[A-Z][a-z]{2}-\d{2} \d{2}:\d{2}:\d{2}"
                        rb"|[A-Z][a-z]{2} [A-Z][a-z]{2} [ \d]\d \d{2}:\d{2}:\d{2} \d{4}"
                        rb"|\d{4}-\d{2}-\d{2}T\d{2}:\d{2}:\d{2}")


def _write(frf, suffix: str, fmt: str) -> bytes:
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / f"seed{suffix}"
        write_frf(frf, path, format=fmt)
        data = path.read_bytes()
    return TIMESTAMPS.sub(lambda m: re.sub(rb"\d", b"1", m.group()), data)


def make_seeds() -> dict[str, list[Seed]]:
    """Valid seed files per format (every one reads back as an FRF/Scene)."""
    one, three = _seed_frf(1, "accelerance"), _seed_frf(3, "mobility")
    seeds: dict[str, list[Seed]] = {}
    seeds["uff58"] = [Seed("uff58-1ch.uff", _write(one, ".uff", "uff58")),
                      Seed("uff58-3ch.uff", _write(three, ".uff", "uff58"))]
    seeds["uff58b"] = [Seed("uff58b-1ch.uff", _write(one, ".uff", "uff58b")),
                       Seed("uff58b-3ch.uff", _write(three, ".uff", "uff58b"))]
    demo = (SYNTHETIC / "demo_frf.csv").read_text().splitlines()
    demo_head = "\n".join(demo[:80]) + "\n"
    f = np.linspace(1.0, 100.0, 40)
    h = one.response[:40]
    plain = "frequency_hz,re,im\n" + "".join(f"{a:.10g},{b.real:.10g},{b.imag:.10g}\n" for a, b in zip(f, h))
    magdeg = "f;mag;phase_deg\n" + "".join(
        f"{a:.6f};{abs(b):.8e};{np.degrees(np.angle(b)):.6f}\n".replace(".", ",") for a, b in zip(f, h))
    complex_column = "".join(f"{complex(b)}\n" for b in h)
    seeds["csv"] = [
        Seed("csv-writer-3ch.csv", _write(three, ".csv", "csv")),
        Seed("csv-demo-head.csv", demo_head.encode()),
        Seed("csv-plain.csv", plain.encode(), {"kind": "accelerance"}),
        Seed("csv-magdeg-comma.csv", magdeg.encode(), {"kind": "mobility", "delimiter": ";", "decimal": ","}),
        Seed("csv-complex-column.txt", complex_column.encode(),
             {"kind": "accelerance", "frequency_step": 0.5, "frequency_start": 0.0}),
    ]
    seeds["mat"] = [Seed("mat5-1ch.mat", _write(one, ".mat", "mat")), Seed("mat5-3ch.mat", _write(three, ".mat", "mat"))]
    seeds["mat73"] = [Seed("mat73-1ch.mat", _write(one, ".mat", "mat73")),
                      Seed("mat73-3ch.mat", _write(three, ".mat", "mat73"))]
    seeds["hdf5"] = [Seed("hdf5-1ch.h5", _write(one, ".h5", "hdf5")), Seed("hdf5-3ch.h5", _write(three, ".h5", "hdf5"))]
    scene_text = (SYNTHETIC / "demo_scene.toml").read_text()
    seeds["scene"] = [Seed("demo_scene.toml", scene_text.encode())]
    return seeds


# --------------------------------------------------------------------------- mutations
NUMBER = re.compile(rb"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?")
MANGLED = [b"nan", b"NaN", b"inf", b"-inf", b"1e309", b"-1e309", b"1e-320", b"0", b"-0", b"-1", b"-7",
           b"99999999999999999999999", b"4294967296", b"2147483648", b"", b" ", b"1.2.3", b"0x1F", b"1e", b"--1",
           b"1,5", b"\xff\xfe", b"\x00", b"9" * 400, b"3.5", b"1e5", b"-1e-5"]
TOML_VALUES = [b'"x"', b"-1", b"0", b"1e400", b"nan", b"inf", b"true", b"[]", b"[1, 2]", b'["a", 1]', b"{}",
               b"{ a = 1 }", b'"identified:mode9.stiffness"', b'"drive:speed"', b'"identified:mode1.nothing"',
               b"1979-05-27", b'""', b"[[1.0, 2.0]]", b"-0.0", b"2147483648", b"99999999999999999999999"]


def _bit_flips(data: bytes, rng: random.Random) -> bytes:
    buf = bytearray(data)
    for _ in range(rng.randint(1, 8)):
        i = rng.randrange(len(buf))
        buf[i] ^= 1 << rng.randrange(8)
    return bytes(buf)


def _truncate(data: bytes, rng: random.Random) -> bytes:
    return data[: rng.randrange(len(data))]


def _insert(data: bytes, rng: random.Random) -> bytes:
    i = rng.randrange(len(data) + 1)
    junk = bytes(rng.randrange(256) for _ in range(rng.randint(1, 16)))
    if rng.random() < 0.3:
        junk = rng.choice([b"\n", b",", b";", b"\t", b"-1\n", b"#", b"=", b"[", b'"', b"\r\n", b"e"]) * rng.randint(1, 4)
    return data[:i] + junk + data[i:]


def _delete(data: bytes, rng: random.Random) -> bytes:
    i = rng.randrange(len(data))
    return data[:i] + data[i + rng.randint(1, 16):]


def _lines(data: bytes, rng: random.Random) -> bytes:
    lines = data.split(b"\n")
    i = rng.randrange(len(lines))
    action = rng.random()
    if action < 0.45:
        lines.insert(i, lines[i])  # duplicate
    elif action < 0.8:
        del lines[i]
    else:
        j = rng.randrange(len(lines))
        lines[i], lines[j] = lines[j], lines[i]
    return b"\n".join(lines)


def _numbers(data: bytes, rng: random.Random) -> bytes:
    matches = list(NUMBER.finditer(data[:200_000]))
    if not matches:
        return _insert(data, rng)
    m = rng.choice(matches)
    return data[: m.start()] + rng.choice(MANGLED) + data[m.end():]


def _toml_value(data: bytes, rng: random.Random) -> bytes:
    lines = data.split(b"\n")
    assigns = [i for i, ln in enumerate(lines) if b"=" in ln and not ln.lstrip().startswith(b"#")]
    if not assigns:
        return _lines(data, rng)
    i = rng.choice(assigns)
    key = lines[i].split(b"=", 1)[0]
    if rng.random() < 0.15:
        key = rng.choice([b"unknown_key ", b"M ", b"n ", b"file ", b"method "])
    lines[i] = key + b"= " + rng.choice(TOML_VALUES)
    return b"\n".join(lines)


def _hdf5_structure(data: bytes, rng: random.Random) -> bytes:
    """Delete or retype one dataset or attribute of an HDF5-based file (h5py)."""
    import h5py

    try:
        return _hdf5_edit(data, rng, h5py)
    except Exception:  # noqa: BLE001 - an earlier byte mutation left nothing h5py can edit
        return data


def _hdf5_edit(data: bytes, rng: random.Random, h5py) -> bytes:
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "x.h5"
        path.write_bytes(data)
        with h5py.File(path, "r+") as f:  # a v7.3 user block is kept by h5py
            nodes: list[tuple[str, str | None]] = []
            f.visititems(lambda name, obj: nodes.extend([(name, None)] + [(name, a) for a in obj.attrs]))
            nodes += [("/", a) for a in f.attrs]
            if not nodes:
                return data
            name, attr = rng.choice(nodes)
            obj = f[name]
            values = [np.array([np.nan, 1.0]), np.array([-1.0]), np.zeros((0,)), np.array([[1, 2], [3, 4]]), "text",
                      np.int64(-3), np.array([1e308, -1e308]), np.arange(7.0), b"\xff\xfe", np.array([1 + 2j, np.inf])]
            value = values[rng.randrange(len(values))]
            if attr is not None:
                if rng.random() < 0.4:
                    del obj.attrs[attr]
                else:
                    obj.attrs[attr] = value
            elif isinstance(obj, h5py.Dataset):
                parent, leaf = obj.parent, name.rsplit("/", 1)[-1]
                keep = dict(obj.attrs)
                del parent[leaf]
                if rng.random() < 0.7:
                    parent[leaf] = value
                    for k, v in keep.items():
                        parent[leaf].attrs[k] = v
            elif rng.random() < 0.5 and name != "/":
                del f[name]
        return path.read_bytes()


BYTE_MUTATIONS: dict[str, Callable[[bytes, random.Random], bytes]] = {
    "bit_flips": _bit_flips, "truncate": _truncate, "insert": _insert, "delete": _delete,
    "lines": _lines, "numbers": _numbers,
}


def mutations_for(fmt: str) -> dict[str, Callable[[bytes, random.Random], bytes]]:
    table = dict(BYTE_MUTATIONS)
    if fmt in ("hdf5", "mat73"):
        table["hdf5_structure"] = _hdf5_structure
    if fmt == "scene":
        table["toml_value"] = _toml_value
    return table


def mutated_input(seeds: dict[str, list[Seed]], fmt: str, index: int) -> tuple[Seed, str, bytes]:
    """The ``index``-th mutated input of a format: (seed, mutation names, bytes)."""
    rng = random.Random(f"{fmt}:{index}")
    seed = seeds[fmt][index % len(seeds[fmt])]
    table = mutations_for(fmt)
    names = rng.sample(sorted(table), k=rng.choice([1, 1, 1, 2, 3]))
    data = seed.data
    for name in names:
        data = table[name](data, rng) if data else data
    return seed, "+".join(names), data
