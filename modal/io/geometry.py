"""Test geometries from UFF (datasets 15/2411 nodes, 82 trace lines, 164 units), CSV or TOML.

:func:`read_geometry` picks the reader by extension (``.uff``/``.unv``/``.uf`` UFF, ``.csv``,
``.toml``). Coordinates come back in metres.

UFF
    Nodes from dataset 15 (or 2411, double precision), trace lines from dataset 82 (a node 0
    lifts the pen), lengths converted with dataset 164's length factor when the file has one
    (SI = value / factor), else taken as metres. Nodes defined in a local coordinate system
    (datasets 18/2420) are refused: their transforms are not applied.

CSV (typed rows; ``#`` starts a comment; commas, semicolons or whitespace between fields)::

    units, mm            # optional: m (default), mm, cm, in or ft
    node, 1, 0, 0, 0     # node id, x, y, z
    node, 2, 500, 0, 0
    line, 1, 2, 3        # a trace line through two or more nodes
    channel, 1+Z         # optional: each channel's point id, in the data's channel order

TOML::

    length_unit = "mm"                    # optional, as above
    nodes = [[1, 0, 0, 0], [2, 500, 0, 0]]
    lines = [[1, 2]]
    channels = ["1+Z", "2+Z"]             # optional
"""
from __future__ import annotations

import os
import re
import warnings
from pathlib import Path

import numpy as np

from ..errors import FormatError, ParameterError
from ..geometry import Geometry

__all__ = ["read_geometry", "write_geometry_uff", "LENGTH_UNITS", "GEOMETRY_EXTENSIONS"]

#: metres per unit of the length units a CSV or TOML geometry may name
LENGTH_UNITS = {"m": 1.0, "mm": 1e-3, "cm": 1e-2, "in": 0.0254, "ft": 0.3048}
GEOMETRY_EXTENSIONS = {".uff": "uff", ".unv": "uff", ".uf": "uff", ".csv": "csv", ".toml": "toml"}
_EXPECTED = "a geometry file (UFF 15/2411 and 82, CSV or TOML)"


def _check(path) -> tuple[Path, str]:
    src = os.fspath(path)
    p = Path(path)
    if not p.is_file():
        raise FormatError(f"{src}: {'is a directory' if p.is_dir() else 'no such file'}; expected {_EXPECTED}")
    if p.stat().st_size == 0:
        raise FormatError(f"{src}: is empty; expected {_EXPECTED}")
    return p, src


def read_geometry(path: str | os.PathLike) -> Geometry:
    """Read a test geometry (nodes in metres, trace lines, and a channel map if the file has one).

    Parameters
    ----------
    path : path-like
        ``.uff``/``.unv``/``.uf`` (UFF datasets 15 or 2411, 82, 164), ``.csv`` or ``.toml``.

    Returns
    -------
    Geometry

    Raises
    ------
    FormatError
        The file is missing, of another format, or a field is malformed (the message names the
        file, the line or dataset and the field).
    """
    p, src = _check(path)
    kind = GEOMETRY_EXTENSIONS.get(p.suffix.lower())
    if kind is None:
        raise FormatError(f"{src}: extension {p.suffix or '(none)'!r} is not a geometry format; expected "
                          f"{', '.join(GEOMETRY_EXTENSIONS)}")
    reader = {"uff": _read_uff, "csv": _read_csv, "toml": _read_toml}[kind]
    return reader(p, src)


def _build(src, ids, xyz, lines, channels) -> Geometry:
    try:
        geometry = Geometry(np.asarray(ids, np.int64), np.asarray(xyz, float).reshape(-1, 3),
                            np.asarray(lines, np.int64).reshape(-1, 2), source=src)
        return geometry.with_channels(channels) if channels else geometry
    except ParameterError as exc:
        raise FormatError(str(exc)) from None


def _segments(polyline: list[int]) -> list[tuple[int, int]]:
    """Segments of a trace line; node 0 lifts the pen (UFF 82)."""
    out = []
    for a, b in zip(polyline[:-1], polyline[1:]):
        if a != 0 and b != 0 and a != b:
            out.append((a, b))
    return out


# ------------------------------------------------------------------ UFF
def _read_uff(p: Path, src: str) -> Geometry:
    import pyuff

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # pyuff leaves file handles to the garbage collector
            uff = pyuff.UFF(os.fspath(p))
            types = [int(t) for t in uff.get_set_types()]
    except Exception as exc:  # pyuff raises bare Exception
        raise FormatError(f"{src}: not a readable UFF file ({exc}); expected {_EXPECTED}") from None
    local = sorted({t for t in types if t in (18, 2420)})
    if local:
        raise FormatError(f"{src}: dataset {local[0]} defines local coordinate systems, which are not applied; "
                          f"expected nodes in global Cartesian coordinates")
    node_sets = [i for i, t in enumerate(types) if t in (15, 2411)]
    if not node_sets:
        raise FormatError(f"{src}: no dataset 15 or 2411 (nodes); found dataset types "
                          f"{sorted(set(types)) or 'none'}")

    def read(index: int, number: int) -> dict:
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                return uff.read_sets(index)
        except Exception as exc:
            raise FormatError(f"{src}: dataset {number} (set {index + 1}) could not be read ({exc})") from None

    factor = 1.0
    for i, t in enumerate(types):
        if t == 164:
            length = float(read(i, 164).get("length", 1.0))
            if not (np.isfinite(length) and length > 0):
                raise FormatError(f"{src}: dataset 164 field 'length' is {length}; expected a positive factor")
            factor = 1.0 / length
    ids, xyz = [], []
    for i in node_sets:
        d = read(i, types[i])
        try:
            nums = np.asarray(d["node_nums"], float)
            coords = np.column_stack([np.asarray(d[k], float) for k in "xyz"])
        except (KeyError, ValueError) as exc:
            raise FormatError(f"{src}: dataset {types[i]} (set {i + 1}) field {exc} is missing or not numeric") from None
        if np.any(nums != np.round(nums)) or np.any(nums < 1):
            raise FormatError(f"{src}: dataset {types[i]} (set {i + 1}) field 'node_nums' holds a value that is not a "
                              f"positive integer")
        ids.extend(nums.astype(np.int64).tolist())
        xyz.append(coords)
    lines: list[tuple[int, int]] = []
    for i, t in enumerate(types):
        if t == 82:
            d = read(i, 82)
            nodes = np.asarray(d.get("nodes", []), float)
            lines.extend(_segments(nodes.astype(np.int64).tolist()))
    return _build(src, ids, np.vstack(xyz) * factor, lines, None)


def write_geometry_uff(geometry: Geometry, path: str | os.PathLike) -> None:
    """Write nodes (dataset 15, metres) and trace lines (dataset 82, one per segment chain) to a UFF file.

    The file is written to a temporary file beside ``path`` and renamed.
    """
    import pyuff

    from ._atomic import atomic_path

    n = geometry.n_nodes
    zeros = np.zeros(n, int)
    with atomic_path(path) as tmp, warnings.catch_warnings():
        warnings.simplefilter("ignore")
        Path(tmp).write_bytes(b"")
        out = pyuff.UFF(os.fspath(tmp))
        out.write_sets({"type": 15, "node_nums": geometry.node_id, "def_cs": zeros, "disp_cs": zeros,
                        "color": zeros + 1, **{k: geometry.coordinates_m[:, j] for j, k in enumerate("xyz")}},
                       mode="add")
        for number, chain in enumerate(_chains(geometry.lines), start=1):
            out.write_sets({"type": 82, "trace_num": number, "n_nodes": len(chain), "color": 1,
                            "id": f"line {number}", "nodes": np.asarray(chain, int)}, mode="add")


def _chains(lines: np.ndarray) -> list[list[int]]:
    """Segments joined into polylines where one ends at the next one's start (fewer datasets 82)."""
    chains: list[list[int]] = []
    for a, b in lines.tolist():
        if chains and chains[-1][-1] == a:
            chains[-1].append(b)
        else:
            chains.append([a, b])
    return chains


# ------------------------------------------------------------------ CSV
_SPLIT = re.compile(r"\s*[,;]\s*|\s+")


def _number(src, line_no, field, token, kind=float):
    try:
        value = float(token)
    except ValueError:
        raise FormatError(f"{src}: line {line_no}: field '{field}' is {token!r}; expected a number") from None
    if not np.isfinite(value):
        raise FormatError(f"{src}: line {line_no}: field '{field}' is {token!r}; expected a finite number")
    if kind is int:
        if value != round(value) or value < 1:
            raise FormatError(f"{src}: line {line_no}: field '{field}' is {token!r}; expected a positive node number")
        return int(value)
    return value


def _unit(src, where, name) -> float:
    factor = LENGTH_UNITS.get(str(name).strip().lower())
    if factor is None:
        raise FormatError(f"{src}: {where}: length unit {name!r}; expected one of {', '.join(LENGTH_UNITS)}")
    return factor


def _read_csv(p: Path, src: str) -> Geometry:
    try:
        text = p.read_text(encoding="utf-8-sig")
    except UnicodeDecodeError:
        raise FormatError(f"{src}: not UTF-8 text; expected a geometry CSV (rows node/line/channel/units)") from None
    factor, ids, xyz, lines, channels = 1.0, [], [], [], []
    for line_no, raw in enumerate(text.splitlines(), start=1):
        body = raw.split("#", 1)[0].strip()
        if not body:
            continue
        fields = [f for f in _SPLIT.split(body) if f]
        kind = fields[0].lower()
        if kind == "units":
            if len(fields) != 2:
                raise FormatError(f"{src}: line {line_no}: 'units' row has {len(fields) - 1} fields; expected 1")
            factor = _unit(src, f"line {line_no}", fields[1])
        elif kind == "node":
            if len(fields) != 5:
                raise FormatError(f"{src}: line {line_no}: 'node' row has {len(fields) - 1} fields; expected 4 "
                                  f"(id, x, y, z)")
            ids.append(_number(src, line_no, "id", fields[1], int))
            xyz.append([_number(src, line_no, axis, tok) for axis, tok in zip("xyz", fields[2:])])
        elif kind == "line":
            nodes = [_number(src, line_no, f"node {k}", tok, int) for k, tok in enumerate(fields[1:], start=1)]
            if len(nodes) < 2:
                raise FormatError(f"{src}: line {line_no}: 'line' row has {len(nodes)} node(s); expected 2 or more")
            lines.extend(_segments(nodes))
        elif kind == "channel":
            if len(fields) != 2:
                raise FormatError(f"{src}: line {line_no}: 'channel' row has {len(fields) - 1} fields; expected 1 "
                                  f"(a point id such as 3+Z)")
            channels.append(fields[1])
        else:
            raise FormatError(f"{src}: line {line_no}: row type {fields[0]!r}; expected node, line, channel or units")
    if not ids:
        raise FormatError(f"{src}: no 'node' rows; expected rows 'node, id, x, y, z'")
    return _build(src, ids, np.array(xyz) * factor, lines, channels)


# ------------------------------------------------------------------ TOML
def _read_toml(p: Path, src: str) -> Geometry:
    import tomllib

    try:
        doc = tomllib.loads(p.read_text(encoding="utf-8"))
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise FormatError(f"{src}: not valid TOML ({exc})") from None
    unknown = sorted(set(doc) - {"length_unit", "nodes", "lines", "channels"})
    if unknown:
        raise FormatError(f"{src}: unknown key {unknown[0]!r}; expected length_unit, nodes, lines, channels")
    factor = _unit(src, "field 'length_unit'", doc.get("length_unit", "m"))
    nodes = doc.get("nodes")
    if not isinstance(nodes, list) or not nodes:
        raise FormatError(f"{src}: field 'nodes' is missing or empty; expected [[id, x, y, z], ...]")
    ids, xyz = [], []
    for k, row in enumerate(nodes):
        where = f"field 'nodes' row {k}"
        if not isinstance(row, list) or len(row) != 4 or not all(isinstance(v, (int, float)) for v in row):
            raise FormatError(f"{src}: {where} is {row!r}; expected [id, x, y, z] numbers")
        if not isinstance(row[0], int) or row[0] < 1:
            raise FormatError(f"{src}: {where} id is {row[0]!r}; expected a positive integer")
        if not all(np.isfinite(row[1:])):
            raise FormatError(f"{src}: {where} has a coordinate that is not finite")
        ids.append(row[0])
        xyz.append(row[1:])
    lines = []
    for k, row in enumerate(doc.get("lines", [])):
        if not isinstance(row, list) or len(row) < 2 or not all(isinstance(v, int) and v > 0 for v in row):
            raise FormatError(f"{src}: field 'lines' row {k} is {row!r}; expected two or more node numbers")
        lines.extend(_segments(row))
    channels = doc.get("channels", [])
    if not isinstance(channels, list) or not all(isinstance(c, str) for c in channels):
        raise FormatError(f"{src}: field 'channels' must be a list of point ids such as \"3+Z\"")
    return _build(src, ids, np.array(xyz, float) * factor, lines, channels)
