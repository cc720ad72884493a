"""Plain-text tables of identification results (for the command line and reports)."""
from __future__ import annotations

import numpy as np

from ..results import IdentificationResult

__all__ = ["format_table", "jsonable"]


def _pm(value: float, std: float, fmt: str) -> str:
    if not np.isfinite(value):
        return "n/a"
    if np.isfinite(std):
        return f"{value:{fmt}} ± {std:.2g}"
    return f"{value:{fmt}}"


def format_table(result: IdentificationResult, point_ids: list[str] | None = None) -> str:
    """A readable table of modes per channel (channels numbered from 1, as the command line names them).

    Columns: frequency (Hz), damping (%), modal constant (1/kg, or the file's unit when it is not one the
    toolkit converts: ``settings["modal_constant_units"]``), k (N/m),
    c (N s/m), m (kg), each with its standard error, and the flags. When no channel is known to be a
    driving point (flag ``driving_point_unknown``) a last line says why k, c, m are missing and how to
    declare the driving point.
    """
    from ..flags import FLAG_ACTION

    rows = result.rows()
    lines = [f"method: {result.method}   kind: {result.kind}   modes: {len(result)}   channels: {result.n_channels}"]
    constant = f"A [{result.settings.get('modal_constant_units', '1/kg')}]"
    header = f"{'mode':>4}  {'f_n [Hz]':>22}  {'zeta [%]':>20}  {constant:>26}  {'k [N/m]':>20}  {'c [N s/m]':>20}  {'m [kg]':>20}  flags"
    for ch in range(result.n_channels):
        label = f"channel {ch + 1}" + (f" ({point_ids[ch]})" if point_ids else "")
        lines += ["", label, header]
        for row in (r for r in rows if r["channel"] == ch):
            std = row["std"]
            A = row["modal_constant"]
            a_text = f"{A.real:.4g}{A.imag:+.3g}j" if np.isfinite(abs(A)) else "n/a"
            flags = ",".join(row["flags"]) or "-"
            lines.append(
                f"{row['mode']:>4}  {_pm(row['natural_frequency_hz'], std['natural_frequency_hz'], '.6g'):>22}  "
                f"{_pm(100 * row['damping_ratio'], 100 * std['damping_ratio'], '.4g'):>20}  {a_text:>26}  "
                f"{_pm(row['stiffness_n_per_m'], std['stiffness_n_per_m'], '.5g'):>20}  "
                f"{_pm(row['damping_n_s_per_m'], std['damping_n_s_per_m'], '.4g'):>20}  "
                f"{_pm(row['mass_kg'], std['mass_kg'], '.5g'):>20}  {flags}"
            )
    if any("driving_point_unknown" in mode.flags for mode in result.modes):
        lines += ["", "k, c, m: n/a, the driving point is unknown (no point ids say which channel was measured at "
                      "the excitation point); " + FLAG_ACTION["driving_point_unknown"]]
    return "\n".join(lines)


def jsonable(obj):
    """Nested dicts/lists ready for ``json.dump(..., allow_nan=False)``: complex numbers as
    ``{"re", "im"}``, NaN and ±Inf as None (JSON has no such numbers)."""
    if isinstance(obj, dict):
        return {k: jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [jsonable(v) for v in obj]
    if isinstance(obj, complex):
        return {"re": jsonable(obj.real), "im": jsonable(obj.imag)}
    if isinstance(obj, float) and not np.isfinite(obj):
        return None
    return obj
