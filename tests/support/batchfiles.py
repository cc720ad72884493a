"""Folders of files for ``modal batch`` tests: every format ``modal fit`` reads, with the natural
frequencies each file holds, and files that crash, hang or overload a reader or a fit."""
from __future__ import annotations

import gc
import os
import warnings
from pathlib import Path

import numpy as np

from support.timedata import DigitalModes

#: the FRF files' axis: 0.6 Hz lines, the modes 2.4 and 5 Hz wide (at least 4 lines per bandwidth)
FREQ = np.linspace(20.0, 200.0, 301)
FRF_MODES_HZ = (70.0, 140.0)
#: relative noise of the FRF files: the NLS standard errors of f_n are ~1e-5 relative
NOISE = 1e-3
#: the time files' system (velocity responses, so that every file of the folder is a mobility)
FS = 1024.0
PLANT = DigitalModes(np.array([40.0, 95.0]), np.array([0.03, 0.02]), np.array([[1.0, 0.5]]), FS)


def mobility(modes_hz=FRF_MODES_HZ, seed: int = 0):
    """A noisy two-mode driving-point mobility on :data:`FREQ`."""
    from modal.synthetic import add_noise, modal_frf

    frf = modal_frf(FREQ, list(modes_hz), [0.02, 0.02], [1.0, 0.7], kind="mobility", response_points=["1+Z"],
                    reference_points=["1+Z"])
    return add_noise(frf, NOISE, seed=seed)


def _table(path: Path, header: list[str], columns, delimiter: str = ",") -> None:
    rows = [delimiter.join(header)] + [delimiter.join(repr(float(v)) for v in row) for row in np.column_stack(columns)]
    path.write_text("\n".join(rows) + "\n")


def _time_record(n: int = 2**15, seed: int = 0):
    rng = np.random.default_rng(seed)
    force = rng.standard_normal(n)
    response = PLANT.respond(force)[0]
    return force, response + 1e-3 * response.std() * rng.standard_normal(n)


def _uff_time(path: Path, force, response) -> None:
    import pyuff

    open(path, "wb").close()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # pyuff leaves its file handles to the garbage collector
        uff = pyuff.UFF(os.fspath(path))
        for k, (values, data_type, unit) in enumerate([(force, 13, "N"), (response, 11, "m/s")]):
            uff.write_sets({
                "type": 58, "binary": 1, "id1": f"channel {k + 1}", "id2": "NONE", "id3": "NONE", "id4": "NONE",
                "id5": "NONE", "func_type": 1, "func_id": k + 1, "ver_num": 0, "load_case_id": 0,
                "rsp_ent_name": "NONE", "rsp_node": k + 1, "rsp_dir": 3, "ref_ent_name": "NONE", "ref_node": 0,
                "ref_dir": 0, "abscissa_spacing": 1, "abscissa_min": 0.0, "abscissa_inc": 1.0 / FS,
                "z_axis_value": 0.0, "abscissa_spec_data_type": 17, "abscissa_axis_lab": "Time",
                "abscissa_axis_units_lab": "s", "ordinate_spec_data_type": data_type, "ordinate_axis_lab": "NONE",
                "ordinate_axis_units_lab": unit, "orddenom_spec_data_type": 0, "orddenom_axis_lab": "NONE",
                "orddenom_axis_units_lab": "NONE", "z_axis_spec_data_type": 0, "x": np.arange(values.size) / FS,
                "data": np.asarray(values, float)}, mode="add", force_double=True)
        del uff
        gc.collect()


def write_every_format(folder: Path) -> dict[str, tuple[float, ...]]:
    """One file per format and layout ``modal fit`` reads (all mobilities: ``--kind mobility`` suits
    the layouts that do not say), with the natural frequencies (Hz) each holds, by path."""
    from scipy.io import savemat

    import h5py

    from modal.archive import write_archive
    from modal.identify import identify
    from modal.io import write_frf

    folder.mkdir(parents=True, exist_ok=True)
    truth: dict[str, tuple[float, ...]] = {}
    frf = mobility()
    for name, fmt in [("uff58.uff", "uff58"), ("uff58b.unv", "uff58b"), ("canonical.csv", "csv"),
                      ("v5.mat", "mat"), ("v73.mat", "mat73"), ("frf.h5", "hdf5")]:
        write_frf(frf, folder / name, format=fmt)
        truth[str(folder / name)] = FRF_MODES_HZ
    f, h = frf.frequency_hz, frf.response
    layouts = {
        "re_im.csv": (["Frequency (Hz)", "Re H", "Im H"], [f, h.real, h.imag], ","),
        "mag_deg.csv": (["freq", "magnitude", "phase [deg]"], [f, np.abs(h), np.degrees(np.angle(h))], ","),
        "db_deg.txt": (["f", "H dB", "H phase"], [f, 20 * np.log10(np.abs(h)), np.degrees(np.angle(h))], ";"),
    }
    for name, (header, columns, delimiter) in layouts.items():
        _table(folder / name, header, columns, delimiter)
        truth[str(folder / name)] = FRF_MODES_HZ
    archive = folder / "fit_archive.h5"  # what 'modal fit FILE --archive fit_archive.h5' writes
    write_archive(archive, {"frf": frf, "identify_nls": identify(frf, "nls")})
    truth[str(archive)] = FRF_MODES_HZ

    force, response = _time_record()
    time_s = np.arange(force.size) / FS
    _uff_time(folder / "time58b.uff", force, response)
    _table(folder / "time.csv", ["time", "force [N]", "v [m/s]"], [time_s, force, response])
    signals = np.vstack([force, response])
    savemat(folder / "time.mat", {"signals": signals, "sample_rate_hz": FS,
                                  "names": np.array(["hammer", "p1"], dtype=object),
                                  "units": np.array(["N", "m/s"], dtype=object)})
    with h5py.File(folder / "time.h5", "w") as fh:
        ds = fh.create_dataset("signals", data=signals)
        ds.attrs["names"] = ["hammer", "p1"]
        ds.attrs["units"] = ["N", "m/s"]
        fh.create_dataset("time", data=time_s)
    for name in ("time58b.uff", "time.csv", "time.mat", "time.h5"):
        truth[str(folder / name)] = tuple(PLANT.natural_frequency_hz)
    return truth


def write_crashing_mat(path: Path) -> None:
    """A MAT v5 file on which scipy.io.loadmat dies (SIGSEGV): the third ``response_points`` cell's
    dimensions element claims 10 bytes, it holds 8 (a fuzzing finding, docs/stress.md)."""
    from modal.io import write_frf
    from modal.synthetic import modal_frf

    frf = modal_frf(4.0 * np.arange(48), [40.0, 130.0], [0.02, 0.03], np.ones((3, 2)), kind="mobility",
                    response_points=["1+Z", "2+Z", "3+Z"], reference_points=["1+Z"] * 3)
    write_frf(frf, path, format="mat")
    data = bytearray(path.read_bytes())
    text = data.index(b"3+Z", data.index(b"response_points"))
    assert data[text - 24] == 8
    data[text - 24] = 10
    path.write_bytes(bytes(data))


def write_hanging_hdf5(path: Path) -> None:
    """An HDF5 file on which libhdf5 loops for ever inside an attribute read: one byte inserted at
    offset 2349 of a one-channel archive (a fuzzing finding, docs/stress.md)."""
    from modal.io import write_frf
    from modal.synthetic import modal_frf

    rng = np.random.default_rng(1)
    const = rng.standard_normal((1, 2)) + 0.1j * rng.standard_normal((1, 2))
    frf = modal_frf(4.0 * np.arange(48), [40.0, 130.0], [0.02, 0.03], const[0], kind="accelerance",
                    response_points=["1+Z"], reference_points=["1+Z"])
    write_frf(frf, path, format="hdf5")
    data = path.read_bytes()
    path.write_bytes(data[:2349] + bytes([0xa1]) + data[2349:])


def write_many_modes(path: Path, n_modes: int = 150, n_lines: int = 60_000) -> None:
    """An FRF that is slow to identify by construction: ``n_modes`` well-separated modes on a long
    axis (each found, banded and fitted in turn; 150 modes on 60 000 lines take minutes)."""
    from modal.io import write_frf
    from support.manymodes import many_modes_frf

    write_frf(many_modes_frf(n_modes, n_lines, "even", seed=3), path, format="hdf5")
