"""Writing time records in the layouts :func:`modal.io.timedata.read_time` reads.

:func:`write_time` writes a :class:`~modal.io.timedata.TimeRecord` (from a
measurement or :func:`modal.synthetic.impact_record`) atomically, as

* CSV: an optional ``# full_scale: ...`` line, a header ``time [s],<name> [<unit>],...``
  and one row per sample (17 significant digits: doubles round-trip exactly);
* UFF 58b (binary, the default for ``.uff``) or 58 (ASCII): one dataset of function
  type 1 per channel, the point id from the channel's name when it is one
  (``"101+Z"``), else node k+1; record 8's data type from the quantity;
* MAT (v5/v7) and HDF5: ``signals`` (channels x samples), ``sample_rate_hz``,
  ``names``, ``quantities``, ``units`` and ``full_scale`` (NaN where unknown).
"""
from __future__ import annotations

import gc
import os
import warnings
from pathlib import Path

import numpy as np

from ..errors import FormatError, ModalWarning, warn
from ._atomic import atomic_path
from ._common import source_name
from .timedata import TimeRecord

__all__ = ["write_time", "TIME_FORMATS"]

#: formats :func:`write_time` knows
TIME_FORMATS = ("csv", "uff58b", "uff58", "mat", "hdf5")
_EXTENSIONS = {".csv": "csv", ".txt": "csv", ".uff": "uff58b", ".unv": "uff58b", ".mat": "mat", ".h5": "hdf5",
               ".hdf5": "hdf5"}
#: quantity → UFF specific data type (record 8)
_DATA_TYPE = {"force": 13, "displacement": 8, "velocity": 11, "acceleration": 12}


def write_time(record: TimeRecord, path: str | os.PathLike, format: str | None = None) -> None:
    """Write a time record, atomically (a temporary file beside the target, then a rename).

    Parameters
    ----------
    record : TimeRecord
    path : path-like
    format : {"csv", "uff58b", "uff58", "mat", "hdf5"}, optional
        Default from the extension: .csv/.txt → csv, .uff/.unv → uff58b (binary keeps the
        samples and the time step exact), .mat → mat, .h5/.hdf5 → hdf5.

    Raises
    ------
    FormatError
        Unknown format or extension.
    """
    if not isinstance(record, TimeRecord):
        raise TypeError(f"write_time() expects a TimeRecord, got {type(record).__name__}")
    target = Path(path)
    fmt = _EXTENSIONS.get(target.suffix.lower()) if format is None else str(format).lower()
    if fmt not in TIME_FORMATS:
        given = f"format={format!r}" if format is not None else f"extension {target.suffix or '(none)'!r}"
        raise FormatError(f"{source_name(path)}: {given} names no time format; expected one of "
                          f"{', '.join(TIME_FORMATS)} (extensions {', '.join(sorted(_EXTENSIONS))})")
    writer = {"csv": _write_csv, "uff58b": _write_uff, "uff58": _write_uff, "mat": _write_mat,
              "hdf5": _write_hdf5}[fmt]
    with atomic_path(target) as tmp:
        writer(record, tmp, binary=fmt == "uff58b")


def _full_scale(record: TimeRecord) -> np.ndarray:
    levels = record.full_scale or (None,) * record.n_channels
    return np.array([np.nan if v is None else float(v) for v in levels])


def _write_csv(record: TimeRecord, tmp, binary: bool = False) -> None:
    import csv

    header = ["time [s]"] + [f"{name} [{unit}]" if unit else name for name, unit in zip(record.names, record.units)]
    table = np.column_stack([np.arange(record.n_samples) / record.sample_rate_hz, record.signals.T])
    with open(tmp, "w", newline="", encoding="utf-8") as fh:
        if record.full_scale is not None:
            fh.write("# full_scale: " + ", ".join("nan" if np.isnan(v) else repr(float(v))
                                                  for v in _full_scale(record)) + "\n")
        csv.writer(fh, lineterminator="\n").writerow(header)
        np.savetxt(fh, table, delimiter=",", fmt="%.17g")


def _write_uff(record: TimeRecord, tmp, binary: bool) -> None:
    import pyuff

    from .uff import parse_point

    step = 1.0 / record.sample_rate_hz
    if not binary and abs(float("%13.5e" % step) * record.sample_rate_hz - 1) > 5e-6 \
            and record.sample_rate_hz != round(record.sample_rate_hz):
        warn(f"{source_name(tmp)}: ASCII UFF keeps the time step to 6 digits; the rate {record.sample_rate_hz!r} Hz "
             "will read back rounded (write uff58b to keep it)", ModalWarning)
    open(tmp, "wb").close()  # pyuff's "overwrite" truncates again when it switches to binary: "add" to an empty file
    x = np.arange(record.n_samples) * step
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # pyuff leaves its file handles to the garbage collector
        uff = pyuff.UFF(os.fspath(tmp))
        for k, (name, quantity, unit) in enumerate(zip(record.names, record.quantities, record.units)):
            try:
                node, direction = parse_point(name)
            except ValueError:
                node, direction = k + 1, 0
            uff.write_sets({
                "type": 58, "binary": int(binary), "id1": str(name)[:80], "id2": "NONE", "id3": "NONE",
                "id4": "NONE", "id5": "NONE", "func_type": 1, "func_id": k + 1, "ver_num": 0, "load_case_id": 0,
                "rsp_ent_name": "NONE", "rsp_node": node, "rsp_dir": direction, "ref_ent_name": "NONE",
                "ref_node": 0, "ref_dir": 0, "abscissa_spacing": 1, "abscissa_min": 0.0, "abscissa_inc": step,
                "z_axis_value": 0.0, "abscissa_spec_data_type": 17, "abscissa_axis_lab": "Time",
                "abscissa_axis_units_lab": "s", "ordinate_spec_data_type": _DATA_TYPE.get(quantity or "", 0),
                "ordinate_axis_lab": (quantity or "NONE").title(), "ordinate_axis_units_lab": unit or "NONE",
                "orddenom_spec_data_type": 0, "orddenom_axis_lab": "NONE", "orddenom_axis_units_lab": "NONE",
                "z_axis_spec_data_type": 0, "x": x, "data": np.asarray(record.signals[k], float),
            }, mode="add", force_double=True)
        del uff
        gc.collect()


def _texts(values) -> np.ndarray:
    return np.array(["" if v is None else str(v) for v in values], dtype=object)


def _write_mat(record: TimeRecord, tmp, binary: bool = False) -> None:
    from scipy.io import savemat

    with open(tmp, "wb") as fh:
        savemat(fh, {"signals": record.signals, "sample_rate_hz": float(record.sample_rate_hz),
                     "names": _texts(record.names), "quantities": _texts(record.quantities),
                     "units": _texts(record.units), "full_scale": _full_scale(record)})


def _write_hdf5(record: TimeRecord, tmp, binary: bool = False) -> None:
    import h5py

    with h5py.File(tmp, "w") as fh:
        signals = fh.create_dataset("signals", data=record.signals)
        rate = fh.create_dataset("sample_rate_hz", data=float(record.sample_rate_hz))
        rate.attrs["units"] = "Hz"
        text = h5py.string_dtype()
        for name, values in (("names", record.names), ("quantities", record.quantities), ("units", record.units)):
            fh.create_dataset(name, data=np.array(["" if v is None else str(v) for v in values], dtype=text))
        fh.create_dataset("full_scale", data=_full_scale(record))
        signals.attrs["layout"] = "channels x samples"
