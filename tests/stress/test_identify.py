"""Stress: identification over random modal parameters (hypothesis property tests).

The cases span damping 1e-5 … 0.5, natural frequencies 0.1 Hz … 100 kHz,
k 1 … 1e10 N/m and m 1e-4 … 1e4 kg (driving point, A = 1/m), noise 0 … 20 % of
max |H|, 0.05 … 1000 lines per half-power band of the narrowest mode, 1 … 8
modes whose neighbours overlap (2ζωn / Δω) by up to 3, on uniform and jittered
(non-uniform) frequency axes, in all three FRF kinds.

Invariants checked:

* ``natural_frequency_hz`` and ``damping_ratio`` of every reported mode are
  finite; k, c and m are finite unless the mode says why (``not_driving_point``
  or ``non_positive_constant``).
* Every estimate (fn, ζ, m, k) lies within ``K_SIGMA`` of its own standard
  errors of the truth, or the mode carries a flag.  The rounding floor ``RTOL_EXACT`` is added for
  noise-free data, where the reported standard errors shrink to ~1e-16 relative
  (they scale with the noise estimate) while the fit still stops at the LM rule.
* Results do not depend on units: H × 1e±6 and f × 1e±3 give the same damping,
  f scaled by the factor, and m, k scaled as the modal constant dictates.
* The three FRF kinds give the same modes (within their combined standard errors).

The stress variants (``-m stress``) draw hundreds of cases; the default run keeps a
few derandomised examples of each so the invariants are exercised on every run.

Accuracy is asserted for modes separated by an overlap up to ``OVERLAP_ASSERTED``
(docs/stress.md, finding 12), including when peak detection misses a mode: each
reported mode is then compared with the nearest true one, and a hidden neighbour
that biases it has to raise ``missing_mode``.
"""
from __future__ import annotations

import functools
import math
import os
import warnings
from dataclasses import dataclass

import numpy as np
import pytest
from hypothesis import HealthCheck, event, given, note, seed, settings
from hypothesis import strategies as st

import modal
from modal import FRF, add_noise, identify, modal_frf
from modal.frf import KIND_POWER

#: accept an estimate within this many of its own standard errors of the truth
#: (a 5-sigma Gaussian excursion has probability 6e-7 per estimate)
K_SIGMA = 5.0
#: relative floor for noise-free data: the LM refinement stops at a relative step of
#: 1e-13 and exact-data tests in test_identify reproduce the truth to 1e-9
RTOL_EXACT = 1e-9
#: accuracy is asserted for modes this well separated (overlap 2ζωn/Δω); identify flags
#: close_modes above 1.5, where the NLS errors turn optimistic (finding 12 in docs/stress.md)
OVERLAP_ASSERTED = 1.2
#: when peak detection misses a mode, accuracy is asserted up to this overlap. Closer, modes
#: merged into one peak can look like one broader mode within the noise: 1, 1.2 and 1.44 Hz at
#: ζ = 0.1 (A 1:10:1), 6 % noise, 10 lines per band give chi2 1.0-1.5 while ζ is 6-9 of its
#: errors off (STRESS_SEED=7 with this limit at 1.2; docs/stress.md, finding 17)
HIDDEN_OVERLAP_ASSERTED = 0.3
#: cap on the number of lines so that one case takes well under a second or two
N_MAX = 3000
N_MIN = 16
INFO_FLAGS: set[str] = set()
KINDS = ("receptance", "mobility", "accelerance")
STRESS_SEED = int(os.environ.get("STRESS_SEED", "8"))

STRESS = settings(max_examples=int(os.environ.get("STRESS_EXAMPLES", "500")), deadline=None, database=None,
                  suppress_health_check=list(HealthCheck), print_blob=True)
FAST = settings(max_examples=12, deadline=None, database=None, derandomize=True,
                suppress_health_check=list(HealthCheck))


@dataclass(frozen=True)
class Case:
    """One synthetic test case and its truth."""

    frequency_hz: np.ndarray
    fn: np.ndarray
    zeta: np.ndarray
    modal_constant: np.ndarray
    kind: str
    noise: float
    noise_seed: int
    lines_per_band: float
    uniform: bool
    explicit_bands: bool

    @property
    def overlap(self) -> float:
        """Largest modal overlap 2·ζ·fn / Δf between neighbours (0 for one mode)."""
        if self.fn.size < 2:
            return 0.0
        width = 2 * np.maximum(self.zeta[1:] * self.fn[1:], self.zeta[:-1] * self.fn[:-1])
        return float(np.max(width / np.diff(self.fn)))

    @property
    def mass(self) -> np.ndarray:
        return 1.0 / self.modal_constant.real

    @property
    def stiffness(self) -> np.ndarray:
        return self.mass * (2 * np.pi * self.fn) ** 2

    def frf(self, kind: str | None = None) -> FRF:
        # a driving point, said by its point ids (k, c, m are given only where the driving point is known)
        clean = modal_frf(self.frequency_hz, self.fn, self.zeta, self.modal_constant, kind=kind or self.kind,
                          response_points=["1"], reference_points=["1"])
        return add_noise(clean, self.noise, seed=self.noise_seed) if self.noise > 0 else clean

    def bands(self) -> list[tuple[float, float]]:
        """±3 half-power widths per mode, clipped halfway to the neighbours."""
        out = []
        for r, (f, z) in enumerate(zip(self.fn, self.zeta)):
            lo, hi = f - 6 * z * f, f + 6 * z * f
            if r > 0:
                lo = max(lo, 0.5 * (self.fn[r - 1] + f))
            if r < self.fn.size - 1:
                hi = min(hi, 0.5 * (self.fn[r + 1] + f))
            out.append((max(lo, self.frequency_hz[0]), min(hi, self.frequency_hz[-1])))
        return out


@st.composite
def cases(draw, max_modes: int = 8, noise_max: float = 0.2, explicit: bool | None = None) -> Case:
    """Random modal parameters, axis and noise (see the module docstring for the ranges)."""
    n = draw(st.integers(1, max_modes))
    f1 = 10 ** draw(st.floats(-1.0, 5.0))
    zeta0 = 10 ** draw(st.floats(-5.0, math.log10(0.5)))
    spread = np.array(draw(st.lists(st.floats(-0.3, 0.3), min_size=n, max_size=n)))
    zeta = np.clip(zeta0 * 10**spread, 1e-5, 0.5)
    overlap = 10 ** np.array(draw(st.lists(st.floats(-2.0, math.log10(3.0)), min_size=n - 1, max_size=n - 1)))
    fn = [f1]
    for r in range(n - 1):
        fn.append(fn[-1] * (1 + 2 * max(zeta[r], zeta[r + 1]) / overlap[r]))
    fn = np.array(fn)
    if fn[-1] > 1e5:
        fn *= 1e5 / fn[-1]
    fn = np.maximum(fn, 0.1)
    fn = np.maximum.accumulate(fn * (1 + 1e-9 * np.arange(n)))  # distinct when the clip merged some
    # mass of the first mode: m in [1e-4, 1e4] kg with k = m ωn² in [1, 1e10] N/m
    wn = 2 * np.pi * fn[0]
    lo, hi = max(1e-4, 1 / wn**2), min(1e4, 1e10 / wn**2)
    m = 10 ** (math.log10(lo) + draw(st.floats(0.0, 1.0)) * math.log10(hi / lo))
    ratios = 10 ** np.array(draw(st.lists(st.floats(-1.0, 1.0), min_size=n - 1, max_size=n - 1)))
    const = np.r_[1.0, ratios] / m
    noise = draw(st.one_of(st.just(0.0), st.floats(0.0, noise_max)))
    lines = 10 ** draw(st.floats(math.log10(0.05), 3.0))
    uniform = draw(st.booleans())
    bw = 2 * zeta * fn
    f_lo, f_hi = max(fn[0] - 5 * bw[0], 0.05 * fn[0]), fn[-1] + 5 * bw[-1]
    df = bw.min() / lines
    df = min(max(df, (f_hi - f_lo) / N_MAX), (f_hi - f_lo) / N_MIN)
    offset = draw(st.floats(0.0, 0.999))
    if uniform:
        f = f_lo + (np.arange(int((f_hi - f_lo) / df)) + offset) * df
    else:
        jitter = np.random.default_rng(draw(st.integers(0, 2**32 - 1))).uniform(0.5, 1.5, int((f_hi - f_lo) / df))
        f = f_lo + offset * df + np.concatenate([[0.0], np.cumsum(jitter[:-1] * df)])
    kind = draw(st.sampled_from(KINDS))
    use_bands = draw(st.booleans()) if explicit is None else explicit
    return Case(f, fn, zeta, const, kind, noise, draw(st.integers(0, 2**31)), float(bw.min() / df), uniform, use_bands)


def run(case: Case, method: str = "nls", frf: FRF | None = None):
    """identify() with the toolkit's warnings caught; None if it refused with its own error."""
    frf = case.frf() if frf is None else frf
    bands = case.bands() if case.explicit_bands else None
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", modal.ModalWarning)
        warnings.simplefilter("error", RuntimeWarning)  # numpy trouble inside must not leak silently
        try:
            return identify(frf, method, bands_hz=bands)
        except modal.IdentificationError as exc:  # a clear refusal is an allowed outcome
            event(f"{method}: IdentificationError ({_reason(exc)})")
            return None


def _reason(exc: Exception) -> str:
    text = str(exc)
    for key in ("no resonance", "holds", "pairs"):
        if key in text:
            return key
    return text[:40]


def serious(mode) -> set[str]:
    return set(mode.flags) - INFO_FLAGS


def check_finite(result) -> None:
    """No NaN/Inf in fn and ζ; k, c, m finite unless a flag says why not."""
    for mode in result:
        assert np.isfinite(mode.natural_frequency_hz) and mode.natural_frequency_hz > 0, mode
        assert np.isfinite(mode.damping_ratio), mode
        # too_few_points: the method had no estimate of the modal constant at all (the data
        # cannot support one; the flag says so) — reported to the lead in docs/stress.md
        allowed_nan = {"not_driving_point", "non_positive_constant"} & set(mode.flags)
        for name in ("stiffness_n_per_m", "damping_n_s_per_m", "mass_kg"):
            value = np.asarray(getattr(mode, name))
            assert np.all(np.isfinite(value)) or allowed_nan, (name, value, mode.flags)


def within(estimate: float, truth: float, std: float) -> bool:
    """|estimate − truth| ≤ K_SIGMA·std + RTOL_EXACT·|truth| (NaN std never passes)."""
    return bool(abs(estimate - truth) <= K_SIGMA * std + RTOL_EXACT * abs(truth))


def check_accuracy(case: Case, result) -> None:
    """Each estimate within K_SIGMA standard errors of the truth, or flagged."""
    if case.overlap > OVERLAP_ASSERTED:
        event("overlapping modes: accuracy not asserted")
        return
    if len(result) == case.fn.size:
        event("all modes reported")
        truth = range(case.fn.size)
    elif case.overlap > HIDDEN_OVERLAP_ASSERTED:
        # modes merged into one peak: flagged where the residual shows it (missing_mode,
        # model_inadequate), but a merged peak within the noise is not told from one mode
        event("modes missing and overlapping: accuracy not asserted")
        return
    else:
        # peak detection missed a mode (or found a spurious one): each reported mode is
        # compared with the nearest true one; a hidden neighbour that biases it must show
        # in the residual check (flag missing_mode)
        event("modes missing: nearest true mode compared")
        truth = [int(np.argmin(np.abs(mode.natural_frequency_hz - case.fn) / (case.zeta * case.fn))) for mode in result]
    for r, mode in zip(truth, result):
        if serious(mode):
            event("flagged")
            continue
        s = mode.std
        checks = {
            "natural_frequency_hz": within(mode.natural_frequency_hz, case.fn[r], s.natural_frequency_hz),
            "damping_ratio": within(mode.damping_ratio, case.zeta[r], s.damping_ratio),
            "mass_kg": within(float(mode.mass_kg), case.mass[r], float(s.mass_kg)),
            "stiffness_n_per_m": within(float(mode.stiffness_n_per_m), case.stiffness[r], float(s.stiffness_n_per_m)),
        }
        bad = [name for name, ok in checks.items() if not ok]
        assert not bad, (f"mode {r} unflagged and outside {K_SIGMA} sigma in {bad}: "
                         f"fn {mode.natural_frequency_hz!r} vs {case.fn[r]!r} (std {s.natural_frequency_hz:.3g}); "
                         f"zeta {mode.damping_ratio!r} vs {case.zeta[r]!r} (std {s.damping_ratio:.3g}); "
                         f"m {mode.mass_kg!r} vs {case.mass[r]!r} (std {s.mass_kg:.3g})")


def describe(case: Case) -> None:
    note(f"kind={case.kind} modes={case.fn.size} fn={case.fn.tolist()} zeta={case.zeta.tolist()} "
         f"A={case.modal_constant.real.tolist()} noise={case.noise:.4g} L={case.lines_per_band:.4g} "
         f"lines={case.frequency_hz.size} uniform={case.uniform} bands={case.explicit_bands}")
    note(f"frequency_hz = {case.frequency_hz.tolist()!r}; noise seed {case.noise_seed}")


# --------------------------------------------------------------------------- finite + accurate
def check_nls(case: Case) -> None:
    describe(case)
    result = run(case, "nls")
    if result is not None:
        check_finite(result)
        check_accuracy(case, result)


def check_circle(case: Case) -> None:
    describe(case)
    result = run(case, "circle")
    if result is not None:
        check_finite(result)
        # a neighbour bends the circle: that bias is caught by the refinement check
        # (flag method_bias, errors widened), so accuracy is asserted with several modes too
        check_accuracy(case, result)


def check_halfpower(case: Case) -> None:
    describe(case)
    result = run(case, "halfpower")
    if result is not None:
        check_finite(result)
        # interpolation between lines, the noisy maximum raising the -3 dB level and the
        # neighbours bias half-power beyond its noise-driven errors; the refinement check
        # flags that (method_bias) and folds it into the errors
        check_accuracy(case, result)


@pytest.mark.stress
@pytest.mark.stress_quick
@seed(STRESS_SEED)
@STRESS
@given(cases())
def test_stress_nls_finite_and_within_sigma_or_flagged(case):
    check_nls(case)


@FAST
@given(cases(max_modes=3))
def test_nls_finite_and_within_sigma_or_flagged(case):
    check_nls(case)


@pytest.mark.stress
@pytest.mark.stress_quick
@seed(STRESS_SEED + 1)
@STRESS
@given(cases())
def test_stress_circle_finite_and_within_sigma_or_flagged(case):
    check_circle(case)


@FAST
@given(cases(max_modes=2))
def test_circle_finite_and_within_sigma_or_flagged(case):
    check_circle(case)


@pytest.mark.stress
@pytest.mark.stress_quick
@seed(STRESS_SEED + 2)
@STRESS
@given(cases())
def test_stress_halfpower_finite_and_within_sigma_or_flagged(case):
    check_halfpower(case)


@FAST
@given(cases(max_modes=1))
def test_halfpower_finite_and_within_sigma_or_flagged(case):
    check_halfpower(case)


# --------------------------------------------------------------------------- units
#: scale-equivariance is exact in real arithmetic; decimal factors are not powers of
#: two, so each line is rounded (1e-16) and the LM iterations take a different path to
#: the same minimum, stopping at a relative step of 1e-13 — 1e-7 leaves a wide margin
#: yet is far below any physical difference
RTOL_UNITS = 1e-7


def check_units(case: Case, s_h: float, s_f: float) -> None:
    describe(case)
    note(f"H x {s_h:g}, f x {s_f:g}")
    frf = case.frf()
    scaled = FRF(frf.frequency_hz * s_f, frf.response * s_h, kind=frf.kind, response_points=frf.response_points,
                 reference_points=frf.reference_points)
    base = run(case, "nls", frf)
    scaled_case = Case(case.frequency_hz * s_f, case.fn * s_f, case.zeta, case.modal_constant, case.kind,
                       case.noise, case.noise_seed, case.lines_per_band, case.uniform, case.explicit_bands)
    other = run(scaled_case, "nls", scaled)
    assert (base is None) == (other is None), "one scale was refused and the other not"
    if base is None:
        return
    assert len(base) == len(other)
    p = KIND_POWER[case.kind]
    # H = (iω)^p A / (ωn² − ω² + 2iζωnω): A' = s_h s_f^(2−p) A, m = 1/|A|, k = m ωn²
    m_factor = 1.0 / (s_h * s_f ** (2 - p))
    k_factor = s_f**p / s_h
    # band edges lie halfway between lines (finding 13, fixed), so both scales fit the same lines
    for a, b in zip(base, other):
        assert a.n_lines == b.n_lines, (a.band_hz, b.band_hz)
    loose = any({"close_modes", "high_uncertainty", "band_edge_peak"} & set(m.flags) for m in (*base, *other))
    if loose:
        event("units: an ill-determined mode in the fit (compared to 0.25 sigma)")
    for a, b in zip(base, other):
        if {"did_not_converge", "model_inadequate"} & (set(a.flags) | set(b.flags)):
            # a model that does not fit leaves a flat valley: where LM stops then depends on
            # the rounding path (ζ was seen to move 5e-6 relative), and the flags say so
            event("units: did_not_converge/model_inadequate (stopping point may differ)")
            continue
        if "high_uncertainty" in set(a.flags) | set(b.flags):
            # the data do not pin this mode (error > 10 % of ζ, often ζ → 0 below the noise):
            # where LM stops along its valley depends on rounding, by up to several errors
            event("units: high_uncertainty mode (values not compared)")
            continue
        # a fraction of sigma: the part of the difference that rounding may carry. When the
        # joint fit holds an ill-determined mode (flat valley: close_modes, high_uncertainty,
        # a pole at a band edge), LM's stopping point there depends on the rounding path and
        # moves every pole of the fit a little: seen up to 0.09 sigma (finding 18)
        share = 0.25 if loose else 1e-3
        tol_z = RTOL_UNITS * a.damping_ratio + share * a.std.damping_ratio
        assert abs(b.damping_ratio - a.damping_ratio) <= tol_z, (a.damping_ratio, b.damping_ratio)
        tol_f = RTOL_UNITS * a.natural_frequency_hz + share * a.std.natural_frequency_hz
        assert abs(b.natural_frequency_hz / s_f - a.natural_frequency_hz) <= tol_f
        for name, factor in (("mass_kg", m_factor), ("stiffness_n_per_m", k_factor)):
            va, vb = float(getattr(a, name)), float(getattr(b, name))
            if np.isfinite(va):
                sa = float(getattr(a.std, name))
                assert abs(vb / factor - va) <= RTOL_UNITS * abs(va) + share * sa, (name, va, vb / factor)
            else:
                assert not np.isfinite(vb)
        assert serious(a) == serious(b) or (serious(a) ^ serious(b)) <= {"high_uncertainty", "model_inadequate"}, (
            a.flags, b.flags)


SCALES = st.tuples(st.sampled_from([1e-6, 1e6]), st.sampled_from([1e-3, 1e3]))


@pytest.mark.stress
@seed(STRESS_SEED + 3)
@STRESS
@given(cases(), SCALES)
def test_stress_results_do_not_depend_on_units(case, scales):
    check_units(case, *scales)


@FAST
@given(cases(max_modes=2), SCALES)
def test_results_do_not_depend_on_units(case, scales):
    check_units(case, *scales)


# --------------------------------------------------------------------------- kinds
def check_kinds(case: Case) -> None:
    describe(case)
    found = {}
    for kind in KINDS:
        found[kind] = run(case, "nls", case.frf(kind))
    if any(r is None for r in found.values()) or len({len(r) for r in found.values()}) != 1:
        event("kinds: a kind refused or found a different number of modes (not asserted)")
        return
    if len(found["receptance"]) != case.fn.size:
        event("kinds: modes missing (not asserted)")
        return
    for modes in zip(*found.values()):
        if any(serious(m) for m in modes):
            continue
        for a in modes:
            for b in modes:
                s_f = math.hypot(a.std.natural_frequency_hz, b.std.natural_frequency_hz)
                s_z = math.hypot(a.std.damping_ratio, b.std.damping_ratio)
                # two estimates of the same truth: their difference has the combined std
                assert abs(a.natural_frequency_hz - b.natural_frequency_hz) <= (
                    K_SIGMA * s_f + RTOL_EXACT * a.natural_frequency_hz), (a, b)
                assert abs(a.damping_ratio - b.damping_ratio) <= K_SIGMA * s_z + RTOL_EXACT * a.damping_ratio, (a, b)


# bands given: automatic detection legitimately differs between kinds (the mode indicator
# weighs modes by (iω)^p); what must not differ is the estimate of the same modes


@pytest.mark.stress
@seed(STRESS_SEED + 4)
@STRESS
@given(cases(explicit=True))
def test_stress_three_kinds_give_the_same_modes(case):
    check_kinds(case)


@FAST
@given(cases(max_modes=2, explicit=True))
def test_three_kinds_give_the_same_modes(case):
    check_kinds(case)


# --------------------------------------------------------------------------- fixed findings
def test_circle_fit_fallback_stays_within_the_selected_lines():
    """Stress finding 1 (fixed in 5e4b387): the fallback indexed the band, not the lines used."""
    f = 0.47670089 + 0.10465982 * np.arange(77)
    frf = add_noise(modal_frf(f, [1.0, 1.2, 1.44, 4.32], [0.05232991, 0.1, 0.1, 0.1], [39.4784176] * 4), 0.03125,
                    seed=0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", modal.ModalWarning)
        result = identify(frf, "circle", bands_hz=[(2.88, 6.912)])
    assert np.isfinite(result[0].natural_frequency_hz) and np.isfinite(result[0].damping_ratio)


def test_channel_combination_does_not_underflow():
    """Stress finding 2 (fixed in 5e4b387): 1/max(std, 1e-300)**2 overflowed to a division by zero."""
    from modal.sdof.propagate import combine_poles

    theta = np.array([[100.0, 0.1], [100.0, 0.1]])
    # one channel's errors far below any other's: 1e-200 squares to a variance that underflows to 0
    cov = np.array([np.diag([1e-200, 1e-200]) ** 2, np.diag([1e-3, 1e-3]) ** 2])
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        value, covariance, gain = combine_poles(theta, cov, np.array([1.0, 1.0]))
    # the channel without a usable error is left out; the combination stays finite and > 0
    assert np.allclose(value, [100.0, 0.1], rtol=1e-12, atol=0)
    assert np.all(np.isfinite(covariance)) and np.all(np.diag(covariance) > 0)


# --------------------------------------------------------------------------- well-posed cases
#: a well-posed case: 1-3 modes at overlap 0.1-0.3, 0.1-3 % noise, 4-40 lines per half-power
#: band, ζ 3e-3 ... 0.05, peaks of comparable height (within 1:3). Here no flag may excuse
#: an estimate, few modes may be flagged at all, and the z-scores (estimate − truth)/std
#: across cases must have the spread of a calibrated error.
#: Cap on the share of flagged modes. A flag from a 3-sigma test (method_bias,
#: high_uncertainty) fires on noise alone in < 1 % of estimates; 5 % for NLS and half-power
#: leaves room for that (observed: NLS 0 of 74 and 0 of 409, half-power 1 of 40 and 1 of 200).
#: The circle's damping_pair_spread (damping pairs > 10 % apart, a fixed threshold, not scaled
#: to the noise) fires on noise at 3 % and few lines: with method_bias 3 of 40 and 21 of 200
#: (15 damping_pair_spread); capped at 15 %.
WELL_POSED_FLAG_RATE = {"nls": 0.05, "circle": 0.15, "halfpower": 0.1}
#: the single-mode methods are well posed on one mode only: a neighbour even at overlap 0.01
#: bends the circle and the -3 dB points beyond their noise-driven errors at 0.1 % noise, and
#: the refinement check rightly flags that (method_bias on 13 and 17 of 27 modes with 1-3)
WELL_POSED_MODES = {"nls": 3, "circle": 1, "halfpower": 1}


def z_bounds(n: int) -> tuple[float, float, float]:
    """Bounds on the spread (standard deviation) and the mean of n z-scores of a calibrated,
    unbiased error: 1 and 0, with the sample's own scatter ±1/sqrt(2n) and ±1/sqrt(n);
    3 of it (n = 40 in the default run: spread 0.66-1.34, |mean| <= 0.47; n = 200 under
    -m stress: 0.85-1.15, the issue's ±15 %, |mean| <= 0.21). Two-sided: an error 1.5x too
    wide (spread 0.67) or too narrow fails."""
    return 1 - 3 / math.sqrt(2 * n), 1 + 3 / math.sqrt(2 * n), 3 / math.sqrt(n)


def well_posed_case(rng: np.random.Generator, max_modes: int = 3) -> Case:
    """One well-posed case drawn with numpy's seeded generator (not hypothesis: its draws
    depend on the constants of whichever modules the session imported, so a derandomised
    hypothesis sample is not the same sample in every run, and a statistic over it moves)."""
    n = int(rng.integers(1, max_modes + 1))
    kind = KINDS[int(rng.integers(3))]
    f1 = 10 ** rng.uniform(0.0, 4.0)
    zeta = np.full(n, 10 ** rng.uniform(math.log10(3e-3), math.log10(0.05)))
    # neighbours at overlap 0.1-0.3: separated, and near enough that the axis stays within
    # N_MAX lines at the drawn resolution (~30 lines per band-width of spread)
    overlap = 10 ** rng.uniform(-1.0, math.log10(0.3), n - 1)
    fn = [f1]
    for r in range(n - 1):
        fn.append(fn[-1] * (1 + 2 * zeta[r] / overlap[r]))
    fn = np.array(fn)
    m = 10 ** rng.uniform(-2.0, 2.0)
    # peaks of comparable height in the drawn kind (|A| ωn^(p-2) / 2ζ), within 1:3, so that
    # every mode stands well above the noise
    ratios = 10 ** rng.uniform(-0.5, 0.5, n - 1)
    const = np.r_[1.0, ratios] * (fn / fn[0]) ** (2 - KIND_POWER[kind]) / m
    noise = 10 ** rng.uniform(-3.0, math.log10(0.03))
    lines = 10 ** rng.uniform(math.log10(4.0), math.log10(40.0))
    bw = 2 * zeta * fn
    f_lo, f_hi = fn[0] - 5 * bw[0], fn[-1] + 5 * bw[-1]
    df = bw.min() / lines
    f = f_lo + (np.arange(int((f_hi - f_lo) / df)) + rng.uniform(0.0, 0.999)) * df
    assert f.size <= N_MAX
    return Case(f, fn, zeta, const, kind, noise, int(rng.integers(2**31)), float(lines), True, True)


QUANTITIES = ("natural_frequency_hz", "damping_ratio", "mass_kg", "stiffness_n_per_m")


def _summary(case: Case) -> str:
    return (f"kind={case.kind} fn={case.fn.tolist()} zeta={case.zeta[0]:.4g} A={case.modal_constant.real.tolist()} "
            f"noise={case.noise:.4g} L={case.lines_per_band:.3g} lines={case.frequency_hz.size} "
            f"noise seed {case.noise_seed}")


def collect_well_posed(case: Case, method: str, tally: dict) -> None:
    """Every mode found and unflagged (or counted as flagged); its z-scores collected."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", modal.ModalWarning)
        warnings.simplefilter("error", RuntimeWarning)
        result = identify(case.frf(), method, bands_hz=case.bands())
    assert len(result) == case.fn.size, ("a well-posed case must be identified", _summary(case))
    check_finite(result)
    truth = {"natural_frequency_hz": case.fn, "damping_ratio": case.zeta, "mass_kg": case.mass,
             "stiffness_n_per_m": case.stiffness}
    for r, mode in enumerate(result):
        tally["modes"] += 1
        if serious(mode):
            tally["flagged"].append(sorted(serious(mode)))
        for name in QUANTITIES:
            value, std = float(getattr(mode, name)), float(getattr(mode.std, name))
            z = (value - truth[name][r]) / std
            # no flag excuses a well-posed estimate: within K_SIGMA of its own error
            assert abs(z) <= K_SIGMA, (name, value, truth[name][r], std, mode.flags, _summary(case))
            tally[name].append(z)


def check_well_posed_flags(tally: dict, method: str) -> None:
    rate = len(tally["flagged"]) / tally["modes"]
    assert rate <= WELL_POSED_FLAG_RATE[method], (rate, tally["flagged"])


def check_well_posed_spread(tally: dict, lower: bool = True) -> None:
    """Mean and spread of the z-scores; ``lower=False`` checks only that the errors are not
    too small (spread <= the upper bound), the part that holds for every method today."""
    for name in QUANTITIES:
        z = np.asarray(tally[name])
        low, high, mean = z_bounds(z.size)
        assert float(np.std(z)) <= high, (name, float(np.std(z)), high, z.size)
        if lower:
            assert abs(float(np.mean(z))) <= mean, (name, float(np.mean(z)), mean, z.size)
            assert low <= float(np.std(z)), (name, float(np.std(z)), low, z.size)


#: cases per method: 40 in the default run (under 1 s per method), STRESS_EXAMPLES (200) under -m stress
WELL_POSED_CASES = 40


@functools.lru_cache(maxsize=None)
def well_posed_tally(method: str, stress: bool) -> dict:
    """Draw the well-posed cases once per method and run (the tests below share them)."""
    tally = {"modes": 0, "flagged": [], **{name: [] for name in QUANTITIES}}
    count = int(os.environ.get("STRESS_EXAMPLES", "200")) if stress else WELL_POSED_CASES
    rng = np.random.default_rng([STRESS_SEED, 5] if stress else 21)
    for _ in range(count):
        collect_well_posed(well_posed_case(rng, WELL_POSED_MODES[method]), method, tally)
    return tally


#: Measured on main after issue 21's calibration (spread of z for fn, ζ, m; default 40 cases /
#: -m stress 200): NLS 1.02, 0.94, 1.05 / 0.99, 1.01, 1.01; circle 1.06, 1.09, 1.08 / 1.08,
#: 1.02, 1.01; half-power 0.91, 0.97, 0.96 / 0.96, 1.01, 1.01; |mean| <= 0.21. (Before it,
#: half-power's frequency spread was 0.51 / 0.59: errors 1.7-2x too large.)
METHODS = ["nls", "circle", "halfpower"]
SPREAD_METHODS = ["nls", "circle", "halfpower"]


@pytest.mark.parametrize("method", METHODS)
def test_well_posed_cases_are_found_within_their_errors_and_unflagged(method):
    # every estimate within K_SIGMA of its own error (no flag excuses it), <= 10 % flagged
    check_well_posed_flags(well_posed_tally(method, False), method)


@pytest.mark.parametrize("method", METHODS)
def test_well_posed_errors_are_not_optimistic(method):
    # errors too small (halved: spread ~1.0-1.9) fail here for every method, whatever the
    # calibration work still to come
    check_well_posed_spread(well_posed_tally(method, False), lower=False)


@pytest.mark.parametrize("method", SPREAD_METHODS)
def test_well_posed_errors_have_the_spread_of_the_errors(method):
    check_well_posed_spread(well_posed_tally(method, False))


@pytest.mark.stress
@pytest.mark.parametrize("method", METHODS)
def test_stress_well_posed_cases_are_found_within_their_errors_and_unflagged(method):
    check_well_posed_flags(well_posed_tally(method, True), method)


@pytest.mark.stress
@pytest.mark.parametrize("method", METHODS)
def test_stress_well_posed_errors_are_not_optimistic(method):
    check_well_posed_spread(well_posed_tally(method, True), lower=False)


@pytest.mark.stress
@pytest.mark.parametrize("method", SPREAD_METHODS)
def test_stress_well_posed_errors_have_the_spread_of_the_errors(method):
    check_well_posed_spread(well_posed_tally(method, True))
