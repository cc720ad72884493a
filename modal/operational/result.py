"""The one place where operational estimates become :class:`~modal.results.ModeResult` and
:class:`~modal.results.IdentificationResult` objects (flags, warnings and all)."""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..errors import QualityWarning, warn
from ..flags import FLAG_TEXT
from ..results import IdentificationResult, ModeResult, ModeStd

__all__ = ["ModeEstimate", "KIND_OF_QUANTITY", "mode_result", "oma_result", "scaled_mode", "scaled_result",
           "merged_result", "REL_STD_LIMIT", "MPC_LIMIT",
           "OVERLAP_LIMIT", "WEAK_FRACTION"]

#: what an FRF of each measured quantity is called (the result's ``kind``)
KIND_OF_QUANTITY = {"displacement": "receptance", "velocity": "mobility", "acceleration": "accelerance"}
#: relative standard error of ζ above which a mode is flagged high_uncertainty (as for the FRF methods)
REL_STD_LIMIT = 0.1
#: MPC below which a mode's shape counts as complex
MPC_LIMIT = 0.8
#: modal overlap 2·max(ζωn)/|Δωn| above which two modes are flagged close_modes
OVERLAP_LIMIT = 1.5
#: a mode stable in fewer than this fraction of the orders has weak evidence
WEAK_FRACTION = 0.5


@dataclass(frozen=True)
class ModeEstimate:
    """One mode as an operational method found it, before its flags are raised.

    ``pole`` is the continuous-time pole (rad/s), ``shape`` the observed shape over the channels
    (largest entry 1), the standard errors NaN where the method gives none, ``n_orders`` the orders
    of the sweep that hold it stable out of ``n_orders_swept``, ``order`` the one it is reported from,
    ``flags`` those the method raised itself; ``damping_known`` False where the method measures none
    (FDD: the damping ratio is NaN).
    """

    pole: complex
    shape: np.ndarray
    std_frequency_hz: float
    std_damping_ratio: float
    std_shape: np.ndarray
    n_orders: int
    n_orders_swept: int
    order: int
    flags: frozenset = field(default_factory=frozenset)
    damping_known: bool = True
    #: the pole's first-order deviation per block of the record (rad/s), for methods that build on it
    pole_deviation: np.ndarray | None = field(default=None, repr=False, compare=False)

    @property
    def natural_frequency_hz(self) -> float:
        return float(abs(self.pole) / (2 * np.pi))

    @property
    def damping_ratio(self) -> float:
        return float(-self.pole.real / abs(self.pole)) if self.damping_known else float("nan")


def _flags(estimate: ModeEstimate, others: list[ModeEstimate], shape_mpc: float) -> set[str]:
    flags = set(estimate.flags)
    zeta, s_z = estimate.damping_ratio, estimate.std_damping_ratio
    if not np.isfinite(s_z) or (zeta > 0 and s_z / zeta > REL_STD_LIMIT):
        flags.add("high_uncertainty")
    if estimate.n_orders_swept > 1 and estimate.n_orders < WEAK_FRACTION * estimate.n_orders_swept:
        flags.add("weak_evidence")
    if np.isfinite(shape_mpc) and shape_mpc < MPC_LIMIT:
        flags.add("complex_shape")
    wn = abs(estimate.pole)
    for other in others:
        if other is estimate:
            continue
        gap = abs(abs(other.pole) - wn)
        if gap == 0 or 2 * np.nanmax([zeta * wn, other.damping_ratio * abs(other.pole), 0.0]) / gap > OVERLAP_LIMIT:
            flags.add("close_modes")
    return flags


def mode_result(estimate: ModeEstimate, flags: set[str], shape_mpc: float, band_hz, method: str) -> ModeResult:
    """A :class:`ModeResult` of an unscaled operational mode: k, c, m and the modal constant undefined (NaN)."""
    n_ch = estimate.shape.size
    nan = np.full(n_ch, np.nan)
    std = ModeStd(estimate.std_frequency_hz, estimate.std_damping_ratio, nan.copy(), nan.copy(), nan.copy(),
                  nan.copy(), mode_shape=np.asarray(estimate.std_shape, float))
    return ModeResult(
        natural_frequency_hz=estimate.natural_frequency_hz, damping_ratio=estimate.damping_ratio,
        modal_constant=np.full(n_ch, np.nan + 0j), stiffness_n_per_m=nan.copy(), damping_n_s_per_m=nan.copy(),
        mass_kg=nan.copy(), std=std, flags=tuple(sorted(flags)), method=method,
        band_hz=(float(band_hz[0]), float(band_hz[1])), driving_point=np.zeros(n_ch, bool),
        quality=estimate.n_orders / max(estimate.n_orders_swept, 1), mode_shape=np.asarray(estimate.shape, complex),
        mpc=shape_mpc)


def oma_result(estimates: list[ModeEstimate], *, method: str, quantity: str | None, band_hz, stabilisation,
               settings: dict, harmonics_hz=(), source: str = "<array>") -> IdentificationResult:
    """The result of an operational identification: one flagged :class:`ModeResult` per estimate (in order of
    frequency), a warning per flagged mode, the stabilisation diagram and the machine tones found."""
    from .selection import mpc

    estimates = sorted(estimates, key=lambda e: abs(e.pole))
    modes = []
    for estimate in estimates:
        shape_mpc = mpc(np.asarray(estimate.shape))
        flags = _flags(estimate, estimates, shape_mpc)
        modes.append(mode_result(estimate, flags, shape_mpc, band_hz, method))
        if flags:
            reasons = "; ".join(f"{f}: {FLAG_TEXT[f]}" for f in sorted(flags))
            warn(f"{source}: {method} mode near {estimate.natural_frequency_hz:.6g} Hz is flagged ({reasons})",
                 QualityWarning)
    n_ch = estimates[0].shape.size if estimates else int(settings.get("n_channels", 0))
    kind = KIND_OF_QUANTITY.get(quantity or "acceleration", "accelerance")
    return IdentificationResult(tuple(modes), method, kind, n_ch, noise_std=np.zeros(0), residuals=None,
                                stabilisation=stabilisation, settings=settings,
                                harmonics_hz=tuple(float(f) for f in harmonics_hz))


def scaled_mode(mode: ModeResult, psi, jac_psi, inputs_sd, *, uncertain: bool) -> ModeResult:
    """``mode`` with a mass-normalised shape ψ (1/√kg, per channel) and each channel as a driving point:
    modal constant ψ² (1/kg), m = 1/ψ², k = m ωn², c = 2 ζ m ωn, their standard errors and correlation.

    ``jac_psi`` (channels × inputs) is ψ's gradient over the inputs whose standard errors are ``inputs_sd``
    (independent), the first the natural frequency (rad/s) and the last the damping ratio. ``psi`` None:
    the mode could not be scaled (flagged ``scaling_uncertain``, its k, c, m NaN).
    """
    from dataclasses import replace

    from ..results import correlation_of

    flags = set(mode.flags) | ({"scaling_uncertain"} if uncertain else set())
    if psi is None:
        return replace(mode, flags=tuple(sorted(flags)))
    psi = np.asarray(psi, float)
    wn, zeta = mode.omega_n_rad_s, mode.damping_ratio
    n_in = len(inputs_sd)
    with np.errstate(divide="ignore", invalid="ignore"):
        m = 1.0 / psi**2
        k, c = m * wn**2, 2 * zeta * m * wn
        e_w, e_z = np.eye(n_in)[0], np.eye(n_in)[-1]
        jac = np.empty((psi.size, 3, n_in))  # rows k, c, m
        jac[:, 2] = (-2.0 / psi**3)[:, None] * jac_psi
        jac[:, 0] = wn**2 * jac[:, 2] + (2 * m * wn)[:, None] * e_w[None, :]
        jac[:, 1] = (2 * zeta * wn) * jac[:, 2] + (2 * m * wn)[:, None] * e_z[None, :] \
            + (2 * zeta * m)[:, None] * e_w[None, :]
        cov = jac * np.asarray(inputs_sd, float) ** 2 @ np.swapaxes(jac, 1, 2)
        sd = np.sqrt(np.maximum(np.diagonal(cov, axis1=1, axis2=2), 0.0))
        s_psi = np.sqrt(np.sum((jac_psi * np.asarray(inputs_sd, float)) ** 2, axis=1))
    std = ModeStd(mode.std.natural_frequency_hz, mode.std.damping_ratio, 2 * np.abs(psi) * s_psi, sd[:, 0], sd[:, 1],
                  sd[:, 2], mode_shape=s_psi)
    return replace(mode, modal_constant=(psi**2).astype(complex), stiffness_n_per_m=k, damping_n_s_per_m=c, mass_kg=m,
                   std=std, flags=tuple(sorted(flags)), mode_shape=psi.astype(complex),
                   driving_point=np.ones(psi.size, bool), kcm_correlation=correlation_of(cov))


def scaled_result(before: IdentificationResult, modes: list[ModeResult], settings: dict) -> IdentificationResult:
    """``before`` with its modes replaced by the scaled ones; a warning per mode that could not be scaled."""
    from dataclasses import replace

    for mode in modes:
        if "scaling_uncertain" in mode.flags:
            warn(f"mode near {mode.natural_frequency_hz:.6g} Hz: scaling_uncertain: {FLAG_TEXT['scaling_uncertain']}",
                 QualityWarning)
    return replace(before, modes=tuple(modes), settings=settings)


def merged_result(first: IdentificationResult, merged, settings: dict, harmonics_hz) -> IdentificationResult:
    """Merged setups as one result: each entry of ``merged`` is (the first setup's mode, shape, shape's standard
    error, (frequency, its error), (damping ratio, its error), missing in a setup)."""
    from dataclasses import replace

    modes = []
    for mode, shape, shape_std, (f, sf), (z, sz), missing in merged:
        flags = set(mode.flags) | ({"missing_in_setup"} if missing else set())
        if missing:
            warn(f"mode near {f:.6g} Hz: missing_in_setup: {FLAG_TEXT['missing_in_setup']}", QualityWarning)
        n = shape.size
        nan = np.full(n, np.nan)
        std = ModeStd(sf, sz, nan.copy(), nan.copy(), nan.copy(), nan.copy(), mode_shape=shape_std)
        modes.append(replace(mode, natural_frequency_hz=f, damping_ratio=z, mode_shape=shape,
                             modal_constant=np.full(n, np.nan + 0j), stiffness_n_per_m=nan.copy(),
                             damping_n_s_per_m=nan.copy(), mass_kg=nan.copy(), std=std, flags=tuple(sorted(flags)),
                             driving_point=np.zeros(n, bool), kcm_correlation=None))
    return replace(first, modes=tuple(modes), n_channels=int(settings["n_channels"]), settings=settings,
                   harmonics_hz=tuple(harmonics_hz), stabilisation=None)
