"""An FRF's unit: converted to the kind's SI unit where it is known, and k, c, m withheld where it is not.

Recorders label FRFs in the units their channels were set to: ``g/N`` for an accelerometer set to g,
``mm/s/N``, ``in/lbf``. Fitted as if in SI, such an FRF gives masses and stiffnesses off by the unit's
factor (9.81 for g/N) with nothing to show for it. So the readers convert every unit this module
knows to the kind's SI unit (:data:`modal.frf.DEFAULT_UNITS`), and identification gives no k, c, m
for a unit it does not know (``V/V``, raw voltages whose sensitivities were not applied): the flag
``units_unknown`` says why. Frequencies and damping ratios do not depend on the unit.
"""
from __future__ import annotations

import re
from dataclasses import replace

import numpy as np

from .errors import FormatError, QualityWarning, warn_caller
from .frf import DEFAULT_UNITS, FRF

__all__ = ["parse_frf_unit", "frf_in_si", "si_units", "withhold_physical", "result_units"]

#: response units: (what they measure, factor to SI)
_RESPONSE_UNITS = {
    "m": ("receptance", 1.0), "mm": ("receptance", 1e-3), "um": ("receptance", 1e-6),
    "µm": ("receptance", 1e-6), "μm": ("receptance", 1e-6), "in": ("receptance", 0.0254),
    "m/s": ("mobility", 1.0), "mm/s": ("mobility", 1e-3), "in/s": ("mobility", 0.0254),
    "m/s^2": ("accelerance", 1.0), "m/s2": ("accelerance", 1.0), "m/s**2": ("accelerance", 1.0),
    "m/s²": ("accelerance", 1.0), "mm/s^2": ("accelerance", 1e-3), "mm/s2": ("accelerance", 1e-3),
    "in/s^2": ("accelerance", 0.0254), "in/s2": ("accelerance", 0.0254), "g": ("accelerance", 9.80665),
}
#: force units: factor to N
_FORCE_UNITS = {"n": 1.0, "kn": 1e3, "lbf": 4.4482216152605}
_PARENTHESES = re.compile(r"^\((.*)\)$")


def _bare(text: str) -> str:
    text = text.strip().replace(" ", "")
    match = _PARENTHESES.match(text)
    return match.group(1) if match else text


def parse_frf_unit(units: str | None) -> tuple[str, float] | None:
    """The kind and the factor to its SI unit of an FRF unit label (``"g/N"`` → accelerance, 9.80665),
    or None when the label is not one of a response unit over a force unit this module knows."""
    if not units or "/" not in units:
        return None
    response, _, force = _bare(units).rpartition("/")
    quantity = _RESPONSE_UNITS.get(_bare(response)) or _RESPONSE_UNITS.get(_bare(response).lower())
    to_newton = _FORCE_UNITS.get(_bare(force).lower())
    if quantity is None or to_newton is None:
        return None
    kind, factor = quantity
    return kind, factor / to_newton


def si_units(frf: FRF) -> bool:
    """Whether the FRF is in its kind's SI unit (no unit given counts as SI)."""
    return frf.units is None or frf.units == DEFAULT_UNITS[frf.kind]


def frf_in_si(frf: FRF) -> FRF:
    """The FRF in its kind's SI unit when its unit is known (values and ``noise_std`` scaled), else as it is.

    Raises
    ------
    FormatError
        A unit of another kind than the FRF's (``mm/N`` on an accelerance): which of the two is
        wrong cannot be told.
    """
    if si_units(frf):
        return frf
    parsed = parse_frf_unit(frf.units)
    if parsed is None:
        return frf
    kind, factor = parsed
    if kind != frf.kind:
        raise FormatError(f"{frf.source}: the unit {frf.units!r} is a {kind}'s but the FRF is declared a {frf.kind}; "
                          f"expected a unit of a {frf.kind} ({DEFAULT_UNITS[frf.kind]}) or kind={kind!r}")
    noise = None if frf.noise_std is None else np.asarray(frf.noise_std) * factor
    model = None if frf.noise_model is None else frf.noise_model.scaled(np.full(frf.n_freq, factor**2), factor)
    return replace(frf, response=np.asarray(frf.response) * factor, noise_std=noise, noise_model=model,
                   units=DEFAULT_UNITS[frf.kind])


def withhold_physical(result, frf: FRF):
    """The result with k, c, m (and their errors) NaN and flag ``units_unknown`` on every mode with a driving
    point, when the FRF's unit is neither SI nor convertible; the result itself otherwise.

    The modal constants keep the file's unit then (times s² for accelerance, s for mobility, not 1/kg):
    ``settings["modal_constant_units"]`` says so, for tables."""
    if si_units(frf) or parse_frf_unit(frf.units) is not None:
        return result
    given = frf.units and "not given" not in frf.units
    settings = {**result.settings, "modal_constant_units": f"{frf.units}-based" if given else "unknown",
                "frf_units": frf.units if given else "unknown"}
    modes = []
    for mode in result.modes:
        if not np.any(mode.driving_point):
            modes.append(mode)
            continue
        nan = np.nan if np.ndim(mode.mass_kg) == 0 else np.full(np.shape(mode.mass_kg), np.nan)
        std = replace(mode.std, stiffness_n_per_m=nan, damping_n_s_per_m=nan, mass_kg=nan)
        modes.append(replace(mode, stiffness_n_per_m=nan, damping_n_s_per_m=nan, mass_kg=nan, std=std,
                             kcm_correlation=None, flags=tuple(sorted(set(mode.flags) | {"units_unknown"}))))
    if any("units_unknown" in mode.flags for mode in modes):
        warn_caller(f"{frf.source}: the FRF's unit {frf.units!r} is not one the toolkit converts to SI: k, c, m are "
                    "not given (flag units_unknown)", QualityWarning)
    return replace(result, modes=tuple(modes), settings=settings)


#: the receptance modal constant A = H_receptance (ωn² − ω² + 2iζωnω) is the FRF's unit times s^(p − 2) for an FRF
#: of power p (accelerance 2, mobility 1, receptance 0: 1/kg in SI); the upper residual is a receptance, s^p
_CONSTANT_POWER = {"accelerance": "", "mobility": "/s", "receptance": "/s^2"}
_RECEPTANCE_POWER = {"accelerance": " s^2", "mobility": " s", "receptance": ""}


def result_units(kind: str, settings: dict) -> dict[str, str]:
    """The units of an identification result's modal constants, line noise and residuals: 1/kg, the kind's SI
    unit and m/N, 1/kg in SI; derived from the FRF's own unit where it was not converted
    (``settings["frf_units"]``, set by :func:`withhold_physical`): an accelerance in V/V gives constants in
    V/V, a mobility in V/V constants in (V/V)/s; ``unknown`` where the FRF carried no unit.

    Returns
    -------
    dict
        ``modal_constant``, ``noise_std``, ``upper_residual``, ``lower_residual``.
    """
    unit = settings.get("frf_units")
    if not unit and "modal_constant_units" in settings:  # results written before the FRF's unit was kept
        unit = "unknown"
    if not unit:
        return {"modal_constant": "1/kg", "noise_std": DEFAULT_UNITS[kind], "upper_residual": "m/N",
                "lower_residual": "1/kg"}
    if unit == "unknown":
        return dict.fromkeys(("modal_constant", "noise_std", "upper_residual", "lower_residual"), "unknown")
    base = f"({unit})" if "/" in unit or " " in unit else unit
    constant = unit if kind == "accelerance" else f"{base}{_CONSTANT_POWER[kind]}"
    upper = unit if kind == "receptance" else f"{base}{_RECEPTANCE_POWER[kind]}"
    return {"modal_constant": constant, "noise_std": unit, "upper_residual": upper, "lower_residual": constant}
