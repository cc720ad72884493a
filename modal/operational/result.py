"""Operational estimates become :class:`~modal.results.ModeResult` and
:class:`~modal.results.IdentificationResult` objects through the shared assembly
(:func:`modal.assemble.assemble_modes`): the same pole rules (``high_uncertainty``, ``close_modes``),
warnings and fields as every other method. Unscaled modes go in without inputs (``driving=None``:
k, c, m NaN); mass-normalised modes as driving points at every channel, with the covariance of
(ωn, ζ, A) per channel from which k, c, m and their errors follow as for an impact test.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..assemble import ModeEstimate, assemble_modes
from ..flags import MPC_LIMIT, RULE_FLAGS, WEAK_FRACTION
from ..results import IdentificationResult, ModeResult
from ..units import TWO_PI
from .pole import PoleEstimate
from .selection import determined_mpc

__all__ = ["KIND_OF_QUANTITY", "oma_result", "scaled_result", "merged_result"]

#: what an FRF of each measured quantity is called (the result's ``kind``)
KIND_OF_QUANTITY = {"displacement": "receptance", "velocity": "mobility", "acceleration": "accelerance"}
#: the detail a mode without standard errors adds to its high_uncertainty warning
_NO_ERRORS = " (this method gives no standard errors)"


def _shape_flags(flags: set[str], shape_mpc: float, std_damping_ratio: float) -> tuple[set[str], dict[str, str]]:
    """``flags`` with those of the shape and the errors: complex_shape, and high_uncertainty where the errors
    are unknown (the shared rule raises it only from known errors)."""
    flags = set(flags)
    details = {}
    if np.isfinite(shape_mpc) and shape_mpc < MPC_LIMIT:
        flags.add("complex_shape")
    if not np.isfinite(std_damping_ratio):
        flags.add("high_uncertainty")
        details["high_uncertainty"] = _NO_ERRORS
    return flags, details


def _estimate(pole: PoleEstimate, band_hz) -> ModeEstimate:
    shape_mpc = determined_mpc(pole.shape, pole.std_shape)
    flags = set(pole.flags)
    if pole.n_orders_swept > 1 and pole.n_orders < WEAK_FRACTION * pole.n_orders_swept:
        flags.add("weak_evidence")
    flags, details = _shape_flags(flags, shape_mpc, pole.std_damping_ratio)
    return ModeEstimate(
        omega_n=abs(pole.pole), damping_ratio=pole.damping_ratio, modal_constant=None, covariance=None,
        std_omega_n=TWO_PI * pole.std_frequency_hz, std_damping_ratio=pole.std_damping_ratio,
        band_hz=(float(band_hz[0]), float(band_hz[1])), n_lines=0, lines_per_bandwidth=float("nan"), flags=flags,
        details=details, quality=pole.n_orders / max(pole.n_orders_swept, 1),
        mode_shape=np.asarray(pole.shape, complex), mpc=shape_mpc, std_mode_shape=np.asarray(pole.std_shape, float))


def oma_result(estimates: list[PoleEstimate], *, method: str, quantity: str | None, band_hz, stabilisation,
               settings: dict, harmonics_hz=(), source: str = "<array>",
               record_flags=frozenset()) -> IdentificationResult:
    """The result of an operational identification: one :class:`ModeResult` per estimate (in order of
    frequency) with k, c, m undefined, a warning per flagged mode, the stabilisation diagram and the machine
    tones found. ``record_flags``: flags of the record (e.g. ``non_stationary``) that every mode carries."""
    estimates = sorted((replace(e, flags=frozenset(e.flags) | frozenset(record_flags)) for e in estimates),
                       key=lambda e: abs(e.pole))
    modes = assemble_modes([_estimate(e, band_hz) for e in estimates], method=method, source=source, single=False,
                           driving=None)
    n_ch = estimates[0].shape.size if estimates else int(settings.get("n_channels", 0))
    kind = KIND_OF_QUANTITY.get(quantity or "acceleration", "accelerance")
    return IdentificationResult(tuple(modes), method, kind, n_ch, noise_std=np.zeros(0), residuals=None,
                                stabilisation=stabilisation, settings=settings,
                                harmonics_hz=tuple(float(f) for f in harmonics_hz))


def _again(mode: ModeResult, flags: set[str], **changes) -> ModeEstimate:
    """A mode of an operational result as an estimate to assemble again: the method's own flags (those of the
    shared rules are raised anew), ``changes`` to its fields."""
    shape = changes.pop("mode_shape", mode.mode_shape)
    std_shape = changes.pop("std_mode_shape", mode.std.mode_shape)
    omega_n = changes.pop("omega_n", mode.omega_n_rad_s)
    damping_ratio = changes.pop("damping_ratio", mode.damping_ratio)
    std_omega_n = changes.pop("std_omega_n", TWO_PI * mode.std.natural_frequency_hz)
    std_damping_ratio = changes.pop("std_damping_ratio", mode.std.damping_ratio)
    shape_mpc = determined_mpc(shape, std_shape)
    own = (set(mode.flags) - RULE_FLAGS - {"complex_shape"}) | flags
    own, details = _shape_flags(own, shape_mpc, std_damping_ratio)
    return ModeEstimate(
        omega_n=omega_n, damping_ratio=damping_ratio, std_omega_n=std_omega_n, std_damping_ratio=std_damping_ratio,
        band_hz=mode.band_hz, n_lines=mode.n_lines, lines_per_bandwidth=mode.lines_per_bandwidth, flags=own,
        details=details, chi2=mode.chi2, quality=mode.quality, mode_shape=shape, mpc=shape_mpc, std_mode_shape=std_shape,
        **{"modal_constant": None, "covariance": None, **changes})


def scaled_result(before: IdentificationResult, scaled, settings: dict) -> IdentificationResult:
    """``before`` with every channel a driving point of its mass-normalised modes.

    ``scaled`` holds, for each mode of ``before``, ``(psi, psi_std, covariance, uncertain)``: the
    mass-normalised shape ψ (1/√kg, None where the mode could not be scaled), its entries' standard errors,
    the covariance (channels, 4, 4) of (ωn, ζ, Re ψ², Im ψ²) per channel, and whether it is flagged
    ``scaling_uncertain``. The modal constant of channel j is ψ_j² (1/kg), k, c, m follow from it.
    """
    estimates = []
    for mode, (psi, psi_std, cov, uncertain) in zip(before, scaled):
        flags = {"scaling_uncertain"} if uncertain else set()
        if psi is None:
            estimates.append(_again(mode, flags, modal_constant=np.full(before.n_channels, np.nan + 0j)))
            continue
        psi = np.asarray(psi, float)
        estimates.append(_again(mode, flags, modal_constant=(psi**2).astype(complex), covariance=cov,
                                mode_shape=psi.astype(complex), std_mode_shape=np.asarray(psi_std, float)))
    modes = assemble_modes(estimates, method=before.method, source=_source(before), single=False,
                           driving=np.ones(before.n_channels, bool))
    return replace(before, modes=tuple(modes), settings=settings)


def merged_result(first: IdentificationResult, merged, settings: dict, harmonics_hz) -> IdentificationResult:
    """Merged setups as one result: each entry of ``merged`` is (the first setup's mode, shape, shape's standard
    error, (frequency Hz, its error), (damping ratio, its error), the merge's flags: ``missing_in_setup``)."""
    estimates = []
    for mode, shape, shape_std, (f, sf), (z, sz), flags in merged:
        estimates.append(_again(mode, set(flags), mode_shape=np.asarray(shape, complex),
                                std_mode_shape=np.asarray(shape_std, float), omega_n=TWO_PI * f, damping_ratio=z,
                                std_omega_n=TWO_PI * sf, std_damping_ratio=sz))
    modes = assemble_modes(estimates, method=first.method, source=_source(first), single=False, driving=None)
    return replace(first, modes=tuple(modes), n_channels=int(settings["n_channels"]), settings=settings,
                   harmonics_hz=tuple(harmonics_hz), stabilisation=None)


def _source(result: IdentificationResult) -> str:
    return str(result.settings.get("source", "<array>"))
