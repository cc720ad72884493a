"""FRFs in MATLAB .mat files: v4/v5/v7 through SciPy, v7.3 (HDF5) through h5py.

Variables read (names are case-sensitive, as in MATLAB):

* frequency, Hz: the first of ``frequency_hz``, ``freq_hz``, ``freq``, ``frequency``, ``f``;
* response, complex: the first of ``response``, ``frf``, ``FRF``, ``H``, ``h``;
  a vector is one channel; a matrix holds one channel per column
  (``n_freq × n_channels``, as written here) or per row (``n_channels × n_freq``);
* optional ``kind`` (char), ``units`` (char), ``response_points`` and
  ``reference_points`` (cell arrays of char).

``variables={"frequency": "w", "response": "Hxy"}`` names others (also ``kind``,
``units``, ``response_points``, ``reference_points`` keys). The frequency variable
is taken to be in Hz unless ``frequency_axis=`` says otherwise ("rad/s", "cpm"...).

v7.3 files are HDF5 with a 512-byte MATLAB user block: arrays are stored
transposed (column-major), complex as a compound of ``real`` and ``imag``, char as
uint16 and cells as object references into ``#refs#``; :func:`write_frf_mat`
writes that layout with ``version="7.3"``.
"""
from __future__ import annotations

import math
import os
import warnings
from datetime import datetime, timezone
from typing import Any

import numpy as np

from ..errors import FormatError
from ..frf import FRF
from ._atomic import atomic_path
from ._common import (
    build_frf, check_file, frequency_factor, normalise_kind, resolve_kind, source_name,
)

__all__ = ["read_frf_mat", "write_frf_mat", "DEFAULT_VARIABLES"]

#: Candidate names of each variable, in the order they are looked for.
DEFAULT_VARIABLES = {
    "frequency": ("frequency_hz", "freq_hz", "freq", "frequency", "f"),
    "response": ("response", "frf", "FRF", "H", "h"),
    "kind": ("kind",),
    "units": ("units",),
    "response_points": ("response_points",),
    "reference_points": ("reference_points",),
}
_MATLAB_CLASS = {"float64": "double", "float32": "single", "bool": "logical"}
_HDF5_SIGNATURE = b"\x89HDF\r\n\x1a\n"


# ------------------------------------------------------------------ reading
def read_frf_mat(path: str | os.PathLike, **hints: Any) -> FRF:
    """Read an FRF from a MATLAB .mat file (v4, v5/v7 or v7.3).

    Parameters
    ----------
    path : path-like
    **hints
        ``variables`` (dict mapping "frequency", "response", "kind", "units",
        "response_points", "reference_points" to variable names), ``kind``,
        ``frequency_axis``, ``response_points``, ``reference_points``, ``units``.

    Raises
    ------
    FormatError
        Missing variables (the message lists the file's), a real or wrongly
        shaped response, a damaged file.
    """
    src = source_name(path)
    p = check_file(path)
    with open(p, "rb") as fh:
        head = fh.read(520)
    if head[512:520] == _HDF5_SIGNATURE or head[:8] == _HDF5_SIGNATURE:
        variables = _load_v73(p, src)
    else:
        variables = _load_v5(p, src)
    return _from_variables(variables, src, hints)


#: zlib's largest compression ratio (about 1032:1): no variable of a v7 file holds more
#: elements than this times the file's size in bytes, even when compressed
_MAX_ELEMENTS_PER_BYTE = 1032

#: MATLAB classes an FRF file may hold (whosmat names)
_V5_CLASSES = frozenset({"double", "single", "char", "cell", "logical", "int8", "uint8", "int16", "uint16",
                         "int32", "uint32", "int64", "uint64"})


def _load_v5_here(p, src: str) -> dict[str, Any]:
    import scipy.io

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            # list the variables first: loadmat can crash the process (SIGSEGV) on a damaged
            # variable of a class we never use (e.g. a char array whose class byte says sparse)
            # and a damaged size: a 1.8 kB file whose cell claimed 268 million elements kept loadmat
            # allocating for 9 s before it failed
            size = os.path.getsize(p)
            for name, shape, cls in scipy.io.whosmat(os.fspath(p), appendmat=False):
                if cls not in _V5_CLASSES:
                    raise FormatError(f"{src}: variable {name!r} has MATLAB class {cls!r}; expected one of "
                                      f"{', '.join(sorted(_V5_CLASSES))} (numeric arrays, char, cell)")
                elements = math.prod(int(d) for d in shape)
                if elements > _MAX_ELEMENTS_PER_BYTE * size:
                    raise FormatError(f"{src}: variable {name!r} claims shape {tuple(shape)} ({elements} elements), "
                                      f"more than a {size}-byte file can hold; expected an undamaged file")
            raw = scipy.io.loadmat(os.fspath(p), squeeze_me=False, chars_as_strings=True, appendmat=False)
    except FormatError:
        raise
    except Exception as exc:  # SciPy raises ValueError, TypeError, OSError... on damaged files
        raise FormatError(f"{src}: not a readable MATLAB v4/v5/v7 file ({type(exc).__name__}: {exc}); "
                          "expected a .mat file saved by MATLAB, Octave or SciPy") from None
    return {k: _v5_value(v) for k, v in raw.items() if not k.startswith("__")}


def _load_v5(p, src: str) -> dict[str, Any]:
    """Load a v4/v5/v7 file in a forked child (SciPy's reader can crash on a damaged file)."""
    from ._isolate import call_isolated

    return call_isolated(_load_v5_here, (p, src), src, "MATLAB v4/v5/v7 file")


def _v5_value(value: Any) -> Any:
    """SciPy's loadmat value → ndarray (MATLAB shape), str, or list of str (cellstr)."""
    if isinstance(value, np.ndarray):
        if value.dtype.kind == "U":
            return "".join(value.ravel().tolist()) if value.size <= 1 else [str(s) for s in value.ravel()]
        if value.dtype.kind == "O":
            out = []
            for item in value.ravel(order="F"):
                item = _v5_value(item)
                if isinstance(item, list) and len(item) == 1:
                    item = item[0]
                out.append(item if isinstance(item, str) else item)
            return out
    return value


def _load_v73(p, src: str) -> dict[str, Any]:
    import h5py

    try:
        fh = h5py.File(p, "r")
    except OSError as exc:
        raise FormatError(f"{src}: not a readable MATLAB v7.3 (HDF5) file ({exc}); expected a .mat file") from None
    try:
        with fh:
            return {k: _v73_value(fh, fh[k]) for k in fh.keys() if not k.startswith("#")}
    except (OSError, KeyError, ValueError, TypeError, RuntimeError) as exc:
        raise FormatError(f"{src}: damaged MATLAB v7.3 content ({type(exc).__name__}: {exc}); "
                          "expected a .mat file saved by MATLAB") from None


def _attr_text(value: Any) -> str:
    return value.decode("ascii", "replace") if isinstance(value, bytes) else str(value)


def _v73_value(fh, obj) -> Any:
    """A v7.3 object → ndarray in MATLAB's shape, str (char) or list (cell)."""
    import h5py

    if isinstance(obj, h5py.Group):
        return obj  # struct or object: not used here, listed by name only
    cls = _attr_text(obj.attrs.get("MATLAB_class", b""))
    if "MATLAB_empty" in obj.attrs and int(np.asarray(obj.attrs["MATLAB_empty"]).ravel()[0]):
        return "" if cls == "char" else np.zeros((0, 0))
    data = obj[()]
    if cls == "char":
        codes = np.asarray(data).T  # back to MATLAB shape (rows, columns)
        if codes.ndim == 2 and codes.shape[0] > 1:
            return ["".join(map(chr, row)).rstrip() for row in codes]
        return "".join(map(chr, codes.ravel()))
    if cls == "cell":
        refs = np.asarray(data).T
        return [_v73_value(fh, fh[ref]) for ref in refs.ravel(order="F")]
    arr = np.asarray(data)
    if arr.dtype.names and {"real", "imag"} <= set(arr.dtype.names):
        arr = arr["real"] + 1j * arr["imag"]
    return arr.T


def _lookup(variables: dict[str, Any], role: str, hints: dict[str, Any], src: str, required: bool):
    names = hints.get("variables") or {}
    if not isinstance(names, dict):
        raise FormatError(f"{src}: hint variables={names!r}; expected a dict such as "
                          "{'frequency': 'f', 'response': 'H'}")
    candidates = (names[role],) if role in names else DEFAULT_VARIABLES[role]
    for name in candidates:
        if name in variables:
            return name, variables[name]
    if not required:
        return None, None
    have = ", ".join(f"{k} {_describe(v)}" for k, v in sorted(variables.items())) or "no variables"
    wanted = " or ".join(repr(c) for c in candidates)
    raise FormatError(f"{src}: no variable {wanted} for the {role} (the file has: {have}); "
                      f"expected one, or variables={{'{role}': '<name>'}}")


def _describe(value: Any) -> str:
    if isinstance(value, np.ndarray):
        kind = "complex" if value.dtype.kind == "c" else _MATLAB_CLASS.get(value.dtype.name, value.dtype.name)
        return f"({'x'.join(map(str, value.shape))} {kind})"
    if isinstance(value, str):
        return "(char)"
    if isinstance(value, list):
        return f"(cell of {len(value)})"
    return f"({type(value).__name__})"


def _numeric(name: str, value: Any, src: str, what: str) -> np.ndarray:
    if not isinstance(value, np.ndarray) or value.dtype.kind not in "biufc":
        raise FormatError(f"{src}: variable {name!r} {_describe(value)}: not a numeric array; expected {what}")
    return value


def _from_variables(variables: dict[str, Any], src: str, hints: dict[str, Any]) -> FRF:
    fname, fval = _lookup(variables, "frequency", hints, src, required=True)
    rname, rval = _lookup(variables, "response", hints, src, required=True)
    freq = _numeric(fname, fval, src, "a real vector of frequencies in Hz")
    if freq.dtype.kind == "c" or sum(d > 1 for d in freq.shape) > 1 or freq.size < 2:
        raise FormatError(f"{src}: variable {fname!r} {_describe(freq)}: expected a real vector of at least "
                          "2 frequencies")
    freq = freq.astype(float).ravel()
    resp = _numeric(rname, rval, src, "a complex vector or matrix")
    if resp.dtype.kind != "c":
        raise FormatError(f"{src}: variable {rname!r} {_describe(resp)}: real values; expected complex FRF values "
                          "(magnitude only cannot be used; save real + 1i*imag)")
    n = freq.size
    dims = [d for d in resp.shape if d != 1]
    if len(dims) == 1 and dims[0] == n:
        resp = resp.ravel()
    elif resp.ndim == 2 and resp.shape[0] == n:
        resp = resp.T  # one channel per column (MATLAB convention)
    elif resp.ndim == 2 and resp.shape[1] == n:
        pass  # one channel per row
    else:
        raise FormatError(f"{src}: variable {rname!r} {_describe(resp)}: shape does not match {fname!r} ({n} lines); "
                          f"expected a vector of {n} or a matrix {n} x n_channels")
    resp = np.asarray(resp, dtype=complex)
    unit = hints.get("frequency_axis")
    if unit is not None:
        freq = freq * frequency_factor(unit, src, "hint frequency_axis=")
    kname, kval = _lookup(variables, "kind", hints, src, required=False)
    file_kind = None
    where = f"variable {kname or 'kind'!r}"
    if kname is not None:
        if not isinstance(kval, str):
            raise FormatError(f"{src}: {where} {_describe(kval)}: expected char, e.g. 'accelerance'")
        file_kind = normalise_kind(kval, src, where)
    kind = resolve_kind(file_kind, hints, src, where, why_unknown="the file has no 'kind' variable")
    uname, uval = _lookup(variables, "units", hints, src, required=False)
    units = uval if isinstance(uval, str) and uval else None
    n_ch = 1 if resp.ndim == 1 else resp.shape[0]
    points = []
    for role in ("response_points", "reference_points"):
        name, value = _lookup(variables, role, hints, src, required=False)
        if value is None:
            points.append(None)
            continue
        if isinstance(value, str):
            value = [value]
        if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
            raise FormatError(f"{src}: variable {name!r} {_describe(value)}: expected a cell array of char ids")
        if len(value) != n_ch:
            raise FormatError(f"{src}: variable {name!r}: {len(value)} ids; expected one per channel ({n_ch})")
        points.append(tuple(value))
    return build_frf(freq, resp, kind, src, response_points=points[0], reference_points=points[1],
                     units=units, hints=hints)


# ------------------------------------------------------------------ writing
def write_frf_mat(frf: FRF, path: str | os.PathLike, version: str = "5") -> None:
    """Write ``frf`` as MATLAB variables, atomically.

    Variables: ``frequency_hz`` (n_freq × 1), ``response`` (n_freq × n_channels,
    complex), ``kind``, ``units`` and, when the FRF has them,
    ``response_points`` / ``reference_points`` (cell arrays).

    Parameters
    ----------
    frf : FRF
    path : path-like
    version : {"5", "7.3"}
        "5" is MATLAB's v5/v7 format (SciPy ``savemat``, uncompressed); "7.3" is
        HDF5 with the MATLAB user block (h5py).
    """
    if version not in ("5", "7.3"):
        raise FormatError(f"{source_name(path)}: MAT version {version!r}; expected '5' or '7.3'")
    variables = {
        "frequency_hz": np.asarray(frf.frequency_hz, dtype=float)[:, np.newaxis],
        "response": np.ascontiguousarray(frf.channels.T),
        "kind": frf.kind,
        "units": frf.units or "",
    }
    for role in ("response_points", "reference_points"):
        ids = getattr(frf, role)
        if ids is not None:
            variables[role] = list(ids)
    with atomic_path(path) as tmp:
        if version == "5":
            import scipy.io

            cells = {k: _cell(v) if isinstance(v, list) else v for k, v in variables.items()}
            with open(tmp, "wb") as fh:
                scipy.io.savemat(fh, cells, format="5", do_compression=False, oned_as="column")
        else:
            _write_v73(tmp, variables)


def _cell(values: list[str]) -> np.ndarray:
    cell = np.empty((len(values), 1), dtype=object)
    for i, v in enumerate(values):
        cell[i, 0] = v
    return cell


def _write_v73(tmp, variables: dict[str, Any]) -> None:
    import h5py

    with h5py.File(tmp, "w", userblock_size=512, libver="earliest") as fh:
        refs = None
        for name, value in variables.items():
            if isinstance(value, str):
                _v73_char(fh, name, value)
            elif isinstance(value, list):
                if refs is None:
                    refs = fh.create_group("#refs#")
                ref_list = []
                for i, item in enumerate(value):
                    ds = _v73_char(refs, f"{name}_{i}", item)
                    ref_list.append(ds.ref)
                arr = np.array(ref_list, dtype=h5py.ref_dtype)[np.newaxis, :]  # MATLAB n x 1, transposed
                ds = fh.create_dataset(name, data=arr)
                ds.attrs["MATLAB_class"] = np.bytes_("cell")
            else:
                arr = np.asarray(value)
                if arr.dtype.kind == "c":
                    comp = np.empty(arr.shape, dtype=[("real", "<f8"), ("imag", "<f8")])
                    comp["real"], comp["imag"] = arr.real, arr.imag
                    arr = comp
                ds = fh.create_dataset(name, data=arr.T)
                ds.attrs["MATLAB_class"] = np.bytes_("double")
    created = datetime.now(timezone.utc).strftime("%a %b %d %H:%M:%S %Y")
    text = f"MATLAB 7.3 MAT-file, Platform: GLNXA64, Created on: {created} HDF5 schema 1.00 .".encode("ascii")
    header = text.ljust(116, b" ") + b"\x00" * 8 + b"\x00\x02" + b"IM"
    with open(tmp, "r+b") as fh:
        fh.write(header)


def _v73_char(group, name: str, text: str):
    if text == "":
        ds = group.create_dataset(name, data=np.zeros(2, dtype=np.uint64))
        ds.attrs["MATLAB_empty"] = np.uint8(1)
    else:
        codes = np.array([ord(c) for c in text], dtype=np.uint16)[:, np.newaxis]  # MATLAB 1 x n, transposed
        ds = group.create_dataset(name, data=codes)
        ds.attrs["MATLAB_int_decode"] = np.int32(2)
    ds.attrs["MATLAB_class"] = np.bytes_("char")
    return ds
