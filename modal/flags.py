"""Quality flags, defined once: what each means (:data:`modal.results.FLAG_TEXT`), what a user
should do about it (:data:`FLAG_ACTION`), which flags belong to a channel rather than to the
mode, and which combinations would contradict each other.

``python -m modal.flags > docs/flags.md`` writes the table of the documentation.
"""
from __future__ import annotations

import numpy as np

from .frf import line_spacing
from .results import FLAG_TEXT

__all__ = ["CHI2_LIMIT", "RELATIVE_MISFIT", "lines_near_mode", "FLAG_ACTION", "INFORMATIONAL", "DRIVING_POINT_ONLY", "TRANSFER_ONLY", "channel_flags", "contradictions",
           "flags_markdown"]

#: chi-square (residual variance over the noise variance) above which a model may be flagged model_inadequate
CHI2_LIMIT = 3.0
#: ... and only when the misfit near the mode is also more than this fraction of the data there (RMS over
#: the lines within ±3 half-power widths, at least ±3 lines). Calibrated on the real beam (data/real): its
#: clean modes show 0.2-2.4 % misfit at chi-square 770-4600 (a linear viscous model on measured data:
#: calibration, leakage on under-resolved peaks; the line-to-line noise there is tiny), while modes merged
#: into one peak show 4.5 % (three modes, exact data) and 5.3 % (a pair 1 Hz apart, 0.2 % noise). On noisy
#: data chi-square alone decides: a misfit of 3 noise σ there is above this fraction already.
RELATIVE_MISFIT = 0.03


def lines_near_mode(omega: np.ndarray, omega_n: float, damping_ratio: float) -> np.ndarray:
    """The lines (mask over ``omega``, rad/s) where :data:`RELATIVE_MISFIT` is measured for a mode at
    ``omega_n`` (rad/s): within ±3 half-power widths of it, at least ±3 line spacings."""
    spacing = line_spacing(omega) if omega.size > 1 else 0.0
    return np.abs(omega - omega_n) <= max(3 * 2 * damping_ratio * omega_n, 3 * spacing)

#: What to do when a flag is raised.
FLAG_ACTION = {
    "resolution_limited": "measure with a finer line spacing (longer record) around the mode, or trust the "
                          "nls estimate, which fits the shape of the peak rather than counting lines",
    "missing_crossing": "widen the band (--band) so that it holds both half-power points, or use method nls",
    "band_edge_peak": "give a band centred on the resonance with --band FMIN FMAX",
    "too_few_points": "widen the band or measure a finer line spacing",
    "damping_pair_spread": "use method nls; the circle is distorted (noise, a neighbouring mode or nonlinearity)",
    "model_inadequate": "look at the fit plot (--plot): add the neighbouring mode with --band, check for "
                        "nonlinearity (amplitude-dependent peaks) or a bad channel",
    "high_uncertainty": "average more measurements or improve the signal-to-noise ratio near the mode",
    "did_not_converge": "give a band around the mode with --band, or try method global",
    "driving_point_assumed": "if the response was not measured at the excitation point, say so: "
                             "--driving-point CHANNEL names the driving point, k, c, m of other channels are dropped",
    "not_driving_point": "nothing to do: a transfer FRF gives frequency, damping and modal constant but no k, c, m",
    "complex_mode": "check for close modes or non-proportional damping; k, c, m use |A| and are approximate",
    "non_positive_constant": "check the sign convention of the force and response channels and the driving-point "
                             "declaration; k, c, m are not reported",
    "close_modes": "fit the close modes together (method nls with a --band per mode, or method global)",
    "missing_mode": "give --band for both modes, or lower the peak threshold (min_prominence_db)",
    "window_damping_dominates": "measure with a longer exponential window time constant tau",
    "weak_evidence": "check the stabilisation diagram (--stabilisation-plot) and the mode shape; excite the "
                     "mode better or drop it",
    "outside_band": "widen the measured band around the mode, or treat it as a residual term",
    "rigid_body": "nothing to do for flexible modes; do not use it as a structural mode",
    "complex_shape": "check for close modes or noise; k, c, m and shape comparisons are approximate",
    "method_bias": "use the nls (or global) values, which the half-power and circle estimates start from",
}

#: Flags that describe the setting, not a defect (``ModeResult.ok`` ignores them).
INFORMATIONAL = frozenset({"driving_point_assumed", "not_driving_point"})
#: Flags about a driving-point channel's constant (never on a transfer channel).
DRIVING_POINT_ONLY = frozenset({"driving_point_assumed", "complex_mode", "non_positive_constant"})
#: Flags about a transfer channel (never on a driving-point channel).
TRANSFER_ONLY = frozenset({"not_driving_point"})


def channel_flags(flags, driving_point: bool) -> list[str]:
    """The mode's flags that apply to one channel.

    A mode's flags are raised over all its channels; the per-channel report keeps those
    about the kind of channel it is (``not_driving_point`` only on transfer channels,
    ``complex_mode`` and the like only on driving points).
    """
    drop = TRANSFER_ONLY if driving_point else DRIVING_POINT_ONLY
    return [f for f in flags if f not in drop]


def contradictions(row: dict) -> list[str]:
    """What contradicts itself in one row of :meth:`IdentificationResult.rows` (empty when consistent)."""
    flags = set(row["flags"])
    found = []
    if row["driving_point"]:
        found += [f"driving_point is true with flag {f}" for f in sorted(flags & TRANSFER_ONLY)]
    else:
        found += [f"driving_point is false with flag {f}" for f in sorted(flags & DRIVING_POINT_ONLY)]
        found += [f"transfer channel reports {name}" for name in ("stiffness_n_per_m", "damping_n_s_per_m", "mass_kg")
                  if np.isfinite(row[name])]
    if {"complex_mode", "non_positive_constant"} <= flags:
        found.append("complex_mode (constant with positive real part) with non_positive_constant")
    unknown = flags - set(FLAG_TEXT)
    found += [f"flag {f} is not defined in FLAG_TEXT" for f in sorted(unknown)]
    return found


def flags_markdown() -> str:
    """The flag table of docs/flags.md (generated: ``python -m modal.flags > docs/flags.md``)."""
    lines = [
        "# Quality flags",
        "",
        "<!-- generated by `python -m modal.flags > docs/flags.md` from modal/results.py FLAG_TEXT and",
        "     modal/flags.py FLAG_ACTION; tests/test_first_use.py fails when this file differs -->",
        "",
        "Every identified mode carries a tuple of flags (`ModeResult.flags`, the `flags` column of the table and",
        "of `--json`). An empty tuple means the estimate is sound. `driving_point_assumed` and `not_driving_point`",
        "describe the setting rather than a defect (`ModeResult.ok` ignores them). In the per-channel rows",
        "(`IdentificationResult.rows()`, the table, `--json`) a channel shows only the flags that apply to it:",
        "`not_driving_point` only on transfer channels; `driving_point_assumed`, `complex_mode` and",
        "`non_positive_constant` only on driving points.",
        "",
        "| flag | meaning | what to do |",
        "|---|---|---|",
    ]
    for name, text in FLAG_TEXT.items():
        action = FLAG_ACTION.get(name, "")
        lines.append(f"| `{name}` | {text.replace('|', '/')} | {action.replace('|', '/')} |")
    return "\n".join(lines) + "\n"


if __name__ == "__main__":  # pragma: no cover
    import sys

    sys.stdout.write(flags_markdown())
