"""The numbers the report's script draws, as compact JSON: FRFs with the models over them, the
stabilisation diagrams and the mode shapes on the geometry.

What is drawn is decimated, never what the tables say: at most :data:`MAX_DRAWN_CHANNELS` channels
(evenly spread over the file, plus the RMS over every channel) and at most :data:`MAX_DRAWN_LINES`
points per curve (each bucket of lines keeps its smallest and largest |H|, so no peak is lost).
Numbers are written with 5 significant digits (what a screen shows); NaN and ±Inf as ``null``.
"""
from __future__ import annotations

import numpy as np

from ..estimate.core import EstimatedFRF
from ..flags import serious_flags
from ..frf import FRF
from ..geometry import Geometry
from ..shapes import ModeShapes, mean_phase_deviation_deg, mpc, normalise

__all__ = ["MAX_DRAWN_CHANNELS", "MAX_DRAWN_LINES", "frf_payload", "stabilisation_payload", "shapes_payload",
           "to_json", "drawn_lines", "drawn_channels"]

MAX_DRAWN_CHANNELS = 32
MAX_DRAWN_LINES = 2000


class _Numbers:
    """An array written as a JSON list of 5-significant-digit numbers."""

    def __init__(self, values, digits: int = 5) -> None:
        self.values = np.asarray(values, float).reshape(-1)
        self.digits = digits

    def json(self) -> str:
        if self.values.size == 0:
            return "[]"
        text = list(map(f"%.{self.digits}g".__mod__, self.values.tolist()))  # 2-3x numpy.char.mod's speed
        for k in np.flatnonzero(~np.isfinite(self.values)):
            text[k] = "null"
        return "[" + ",".join(text) + "]"


def to_json(obj) -> str:
    """JSON text of nested dicts, lists, strings, numbers and arrays (arrays at 5 significant digits)."""
    import json

    if isinstance(obj, _Numbers):
        return obj.json()
    if isinstance(obj, np.ndarray):
        return _Numbers(obj).json()
    if isinstance(obj, dict):
        return "{" + ",".join(f"{json.dumps(str(k))}:{to_json(v)}" for k, v in obj.items()) + "}"
    if isinstance(obj, (list, tuple)):
        return "[" + ",".join(to_json(v) for v in obj) + "]"
    if isinstance(obj, (bool, np.bool_)):
        return "true" if obj else "false"
    if isinstance(obj, (int, np.integer)):
        return str(int(obj))
    if isinstance(obj, (float, np.floating)):
        return f"{float(obj):.6g}" if np.isfinite(obj) else "null"
    if obj is None:
        return "null"
    # "</" would close the script element the JSON sits in
    return json.dumps(str(obj)).replace("</", "<\\/")


def drawn_lines(magnitude: np.ndarray, limit: int = MAX_DRAWN_LINES) -> np.ndarray:
    """Indexes of the lines drawn: all up to ``limit``, else each bucket's smallest and largest value.

    Parameters
    ----------
    magnitude : ndarray, shape (n_freq,)
        What decides which lines carry the envelope (|H| of the channel drawn).
    """
    n = magnitude.size
    if n <= limit:
        return np.arange(n)
    buckets = max(limit // 2, 1)
    width = -(-n // buckets)
    padded = np.full(buckets * width, np.nan)
    padded[:n] = magnitude
    blocks = padded.reshape(buckets, width)
    finite = np.isfinite(blocks)
    low = np.argmin(np.where(finite, blocks, np.inf), axis=1)
    high = np.argmax(np.where(finite, blocks, -np.inf), axis=1)
    starts = np.arange(buckets) * width
    keep = np.concatenate([[0, n - 1], starts + low, starts + high])
    return np.unique(keep[keep < n])


def drawn_channels(n_channels: int, limit: int = MAX_DRAWN_CHANNELS) -> np.ndarray:
    """The channels offered in the channel selector: all up to ``limit``, else evenly spread."""
    if n_channels <= limit:
        return np.arange(n_channels)
    return np.unique(np.round(np.linspace(0, n_channels - 1, limit)).astype(int))


def _phase_deg(values: np.ndarray) -> np.ndarray:
    return np.degrees(np.angle(values))


def frf_payload(frf: FRF, results) -> dict:
    """Measured |H| and phase per drawn channel, each result's synthesised model, and coherence when the
    FRF was estimated from time data."""
    freq = frf.frequency_hz
    positive = freq > 0
    H = frf.channels
    models = []
    for result in results:
        synth = np.full(H.shape, np.nan + 0j)
        try:
            synth[:, positive] = result.synthesize(freq[positive]).channels
        except Exception:  # a result that cannot synthesise (no modal constants): no model curve
            continue
        models.append((result.method, synth))
    channels = drawn_channels(frf.n_channels)
    coherence = frf.coherence if isinstance(frf, EstimatedFRF) else None
    if coherence is not None:
        coherence = np.atleast_2d(np.asarray(coherence, float))
    entries = []
    if frf.n_channels > 1:
        rms = np.sqrt(np.mean(np.abs(H) ** 2, axis=0))
        idx = drawn_lines(rms)
        entries.append({"label": f"RMS over all {frf.n_channels} channels", "x": freq[idx], "mag": rms[idx],
                        "phase": None, "models": [{"method": name, "mag": np.sqrt(np.mean(np.abs(s) ** 2, axis=0))[idx],
                                                   "phase": None} for name, s in models],
                        "coherence": None if coherence is None else np.mean(coherence, axis=0)[idx]})
    for ch in channels:
        idx = drawn_lines(np.abs(H[ch]))
        label = f"channel {ch + 1}"  # counted from 1, as the command line counts
        if frf.response_points is not None:
            ref = frf.reference_points[ch] if frf.reference_points is not None else "?"
            label += f" ({frf.response_points[ch]} / {ref})"
        entries.append({"label": label, "x": freq[idx], "mag": np.abs(H[ch, idx]), "phase": _phase_deg(H[ch, idx]),
                        "models": [{"method": name, "mag": np.abs(s[ch, idx]), "phase": _phase_deg(s[ch, idx])}
                                   for name, s in models],
                        "coherence": None if coherence is None else coherence[ch, idx]})
    modes = [{"method": r.method, "f": [float(m.natural_frequency_hz) for m in r.modes]} for r in results]
    note = ""
    if frf.n_channels > channels.size:
        note = (f"{channels.size} of {frf.n_channels} channels offered (evenly spread), with the RMS over all; "
                f"the tables hold every channel")
    if frf.n_freq > MAX_DRAWN_LINES:
        note += (" " if note else "") + (f"curves drawn on at most {MAX_DRAWN_LINES} of the {frf.n_freq} lines "
                                         f"(each bucket's extremes kept)")
    return {"units": frf.units or "", "kind": frf.kind, "entries": entries, "modes": modes, "note": note}


#: stability classes of a diagram's poles, as the report's legend names them
STABILITY_CLASSES = ("new or unstable", "frequency", "frequency + vector", "frequency + damping", "all stable")


def stabilisation_payload(frf: FRF | None, result) -> dict | None:
    """Poles of every order with their stability class (:data:`STABILITY_CLASSES`), the chosen modes and
    the RMS of |H| over channels; None for a result without a diagram."""
    diagram = getattr(result, "stabilisation", None)
    if diagram is None:
        return None
    sf, sd, sv = (np.asarray(getattr(diagram, n), bool) for n in ("stable_frequency", "stable_damping",
                                                                   "stable_vector"))
    code = np.zeros(sf.size, int)
    code[sf] = 1
    code[sf & sv & ~sd] = 2
    code[sf & sd & ~sv] = 3
    code[sf & sd & sv] = 4
    out = {"method": result.method, "f": np.asarray(diagram.frequency_hz, float),
           "order": np.asarray(diagram.order, float), "cls": code.astype(float), "classes": list(STABILITY_CLASSES),
           "modes": [float(m.natural_frequency_hz) for m in result.modes],
           "flagged": [bool(serious_flags(getattr(m, "flags", ())))
                       for m in result.modes]}
    if frf is not None:
        rms = np.sqrt(np.mean(np.abs(frf.channels) ** 2, axis=0))
        idx = drawn_lines(rms)
        out["rms"] = {"x": frf.frequency_hz[idx], "y": rms[idx], "units": frf.units or ""}
    return out


def shapes_payload(shapes: ModeShapes, geometry: Geometry | None) -> dict:
    """Nodes, trace lines and each mode's normalised entries on their nodes and directions.

    The script moves node ``entry_node[j]`` by Re(φ_j e^{iθ}) along ``entry_dir[j]``; entries sharing a node
    add up, as in :func:`modal.shapes.node_displacements`.
    """
    placed = shapes.placed_on(geometry)
    values = normalise(shapes.shapes)
    lines = placed.node_index(placed.lines.ravel()) if placed.lines.size else np.zeros(0, int)
    return {
        "method": shapes.method,
        "line_geometry": geometry is None,
        "nodes": placed.coordinates_m.ravel(),
        "node_ids": [int(i) for i in placed.node_id],
        "lines": [int(i) for i in lines],
        "entry_node": [int(i) for i in placed.node_index(placed.channel_node)],
        "entry_dir": placed.channel_direction.ravel(),
        "points": list(shapes.points) if shapes.points is not None else [f"channel {c + 1}" for c in shapes.channels],
        "modes": [{"f": float(f), "zeta": float(z), "flags": list(fl), "mpc": float(p), "mpd": float(d),
                   "re": row.real, "im": row.imag}
                  for f, z, fl, p, d, row in zip(shapes.natural_frequency_hz, shapes.damping_ratio,
                                                 shapes.flags or [()] * shapes.n_modes, mpc(values),
                                                 mean_phase_deviation_deg(values), values)],
    }
