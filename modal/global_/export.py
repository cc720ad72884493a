"""Exports of a global identification through pyuff: UFF 55 (mode shapes) and UFF 58 (synthesised FRFs).

``export_uff(result, frf, path)`` writes, atomically, one dataset 55 per mode
(complex eigenvalue analysis, analysis type 3, translations x, y, z per node, the mode's eigenvalue λ = −ζωn +
iωn√(1 − ζ²), the modal constants of the first reference's channels as the shape,
placed on each response point's node and direction) followed by one dataset 58 per
channel with the synthesised FRF (residual terms included) on the FRF's lines.
"""
from __future__ import annotations

import os
import tempfile
import warnings
from pathlib import Path

import numpy as np

from ..errors import FormatError
from ..frf import FRF
from ..io._atomic import atomic_path
from ..io.uff import parse_point, write_frf_uff
from ..results import IdentificationResult

__all__ = ["export_uff", "shape_dataset"]


def _node_direction(point: str | None, index: int) -> tuple[int, int]:
    if point is None:
        return index + 1, 3
    try:
        node, direction = parse_point(point)
    except ValueError:
        return index + 1, 3
    return node, direction if direction else 3


def shape_dataset(mode, number: int, frf: FRF) -> dict:
    """The dataset 55 of one mode: the shape of the first reference's channels on their nodes."""
    shape = np.atleast_1d(np.asarray(mode.modal_constant, complex))
    refs = frf.reference_points
    channels = np.arange(frf.n_channels) if refs is None else np.flatnonzero(np.array(refs) == refs[0])
    points = frf.response_points
    nodes: dict[int, np.ndarray] = {}
    for ch in channels:
        node, direction = _node_direction(None if points is None else points[ch], int(ch))
        if abs(direction) > 3:
            continue  # rotations: dataset 55 with 3 values per node holds translations only
        dof = np.zeros(3, complex) if node not in nodes else nodes[node]
        dof[abs(direction) - 1] = shape[ch] * np.sign(direction)
        nodes[node] = dof
    node_nums = np.array(sorted(nodes))
    values = np.array([nodes[n] for n in node_nums]).reshape(-1, 3)  # (n_nodes, 3): x, y, z
    wn, zeta = mode.omega_n_rad_s, mode.damping_ratio
    eig = complex(-zeta * wn, wn * np.sqrt(max(1 - zeta**2, 0.0)))
    return {
        "type": 55, "id1": f"global mode {number}", "id2": f"{mode.natural_frequency_hz:.6g} Hz, zeta {zeta:.4g}",
        "id3": "modalbal", "id4": "NONE", "id5": "NONE", "model_type": 1, "analysis_type": 3, "data_ch": 2,
        "spec_data_type": 8, "data_type": 5, "n_data_per_node": 3, "load_case": 1, "mode_n": number,
        "eig": eig, "modal_a": 0j, "modal_b": 0j, "node_nums": node_nums,
        **{f"r{k + 1}": values[:, k] for k in range(3)},
    }


def export_uff(result: IdentificationResult, frf: FRF, path: str | os.PathLike, geometry=None) -> None:
    """Write the mode shapes (UFF 55) and the synthesised FRFs (UFF 58) of ``result`` to ``path``, after the
    test geometry (UFF 15 nodes and 82 trace lines) when one is given.

    Parameters
    ----------
    result : IdentificationResult
        Of ``frf`` (any method; a global result adds its residual terms to the synthesis).
    frf : FRF
        The fitted FRF: its channels' point ids place the shapes and its lines carry the synthesis.
    path : path-like
        Target file, written to a temporary file beside it and renamed.
    geometry : Geometry, optional
        Written first, so that a viewer of the file draws the shapes on it (the shapes stand on the nodes of
        the channels' point ids).
    """
    import pyuff

    src = os.fspath(path)
    freq = frf.frequency_hz[frf.frequency_hz > 0]
    synth = result.synthesize(freq)
    synth = FRF(synth.frequency_hz, synth.response, kind=synth.kind, response_points=frf.response_points,
                reference_points=frf.reference_points, units=frf.units, source=src)
    with tempfile.TemporaryDirectory(prefix="modalbal-uff55-") as scratch_dir:
        scratch = Path(scratch_dir)
        part58 = scratch / "frf.uff"
        write_frf_uff(synth, part58)
        part15 = scratch / "geometry.uff"
        if geometry is not None:
            from ..io.geometry import write_geometry_uff

            write_geometry_uff(geometry, part15)
        with atomic_path(path) as tmp:
            try:
                with open(tmp, "wb") as out, warnings.catch_warnings():
                    warnings.simplefilter("ignore")  # pyuff leaves file handles to the garbage collector
                    if geometry is not None:
                        out.write(part15.read_bytes())
                    for number, mode in enumerate(result.modes, start=1):
                        one = scratch / f"mode{number}.uff"
                        one.write_bytes(b"")
                        pyuff.UFF(os.fspath(one)).write_sets(shape_dataset(mode, number, frf), mode="add")
                        out.write(one.read_bytes())
                    out.write(part58.read_bytes())
            except Exception as exc:  # pyuff raises bare Exception
                if isinstance(exc, FormatError):
                    raise
                raise FormatError(f"{src}: pyuff could not write dataset 55 ({exc})") from None
