"""Identification: accuracy on exact data, efficiency under noise, honesty when ill-posed."""
import warnings

import numpy as np
import pytest

import modal
from modal import QualityWarning, ResolutionWarning, identify
from modal.sdof.checks import find_missing_mode
from modal.identify import BANDWISE_METHODS
from modal.model import cramer_rao_sdof
from modal.nls import fit_modes
from modal.peaks import estimate_noise_std
from modal.synthetic import add_noise, matrix_frf, modal_frf, modal_parameters_of_matrices, sdof_frf

KINDS = ["receptance", "mobility", "accelerance"]
DAMPINGS = [0.001, 0.01, 0.05, 0.2]


def sdof_case(kind, zeta, lines_per_band, m=2.0, k=1e5, offset=0.37):
    """SDOF driving point with `lines_per_band` lines per half-power bandwidth 2ζfn."""
    wn = np.sqrt(k / m)
    fn = wn / (2 * np.pi)
    df = 2 * zeta * fn / lines_per_band
    n = int(np.ceil(8 * zeta * fn / df))
    f = fn + (np.arange(-n, n + 1) + offset) * df
    f = f[(f > 0.05 * fn)]
    return sdof_frf(f, m, k, 2 * zeta * m * wn, kind=kind), fn, m, k, 2 * zeta * m * wn


@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("zeta", DAMPINGS)
def test_exact_sdof_all_methods(kind, zeta):
    frf, fn, m, k, c = sdof_case(kind, zeta, lines_per_band=3)
    nls = identify(frf, "nls")[0]
    # exact data, exact model: only rounding and the LM stopping rule (1e-13) remain
    assert abs(nls.natural_frequency_hz / fn - 1) < 1e-9
    assert abs(nls.damping_ratio / zeta - 1) < 1e-9
    for value, truth in ((nls.stiffness_n_per_m, k), (nls.damping_n_s_per_m, c), (nls.mass_kg, m)):
        assert abs(value / truth - 1) < 1e-6
    assert nls.flags == ("driving_point_assumed",)
    circle = identify(frf, "circle")[0]
    # the mobility circle is exact for viscous damping and the angle fit recovers the pole:
    # only rounding remains, eps amplified by the band's conditioning ~1/ζ (2e-13 at ζ = 1e-3;
    # observed <= 5.5e-14 relative, 0 on ωn); 10 eps/ζ leaves a factor 4 for other platforms' BLAS
    rounding = 10 * np.finfo(float).eps / zeta
    assert abs(circle.natural_frequency_hz / fn - 1) < rounding
    assert abs(circle.damping_ratio / zeta - 1) < rounding
    frf5, *_ = sdof_case(kind, zeta, lines_per_band=5)
    hp = identify(frf5, "halfpower")[0]
    # dB interpolation + refined peak + exact inversion: ~L^-3 error, 5e-3 at L = 5 (numerics.md §1)
    assert abs(hp.damping_ratio / zeta - 1) < 5e-3
    assert hp.flags == ("driving_point_assumed",)


THREE_FN = np.array([50.0, 120.0, 300.0])
THREE_ZETA = np.array([0.01, 0.02, 0.03])
THREE_A = np.array([1.0, 0.5 + 0.05j, 2.0])  # slightly complex, below the 10° complex_mode flag


@pytest.mark.parametrize("kind", KINDS)
def test_three_separated_modes(kind):
    f = np.linspace(10, 400, 4001)
    frf = modal_frf(f, THREE_FN, THREE_ZETA, THREE_A, kind=kind)
    nls = identify(frf, "nls")
    assert len(nls) == 3
    for r, mode in enumerate(nls):
        assert abs(mode.natural_frequency_hz / THREE_FN[r] - 1) < 1e-9
        assert abs(mode.damping_ratio / THREE_ZETA[r] - 1) < 1e-9
        assert abs(mode.modal_constant / THREE_A[r] - 1) < 1e-8
    # exact data: the circle's own bias (the neighbours bend the circle) is far above its
    # noise-driven error, so the refinement check flags it and folds it into the errors
    with pytest.warns(QualityWarning, match="method_bias"):
        circle = identify(frf, "circle")
    for r, mode in enumerate(circle):
        # neighbours bend the circle slightly: 1e-4 on ωn and 1e-2 on ζ (issue 2)
        assert abs(mode.natural_frequency_hz / THREE_FN[r] - 1) < 1e-4
        assert abs(mode.damping_ratio / THREE_ZETA[r] - 1) < 1e-2
        assert "method_bias" in mode.flags
        # the flag comes from ζ. Exact data: the widened error is hypot(noise part, bias) and the
        # noise part of exact data is rounding, so it must be the actual error itself, from above
        # and within 1 % (a noise part <= 0.14 of the bias; observed 1.0002-1.0046). "Covers the
        # error" alone held by construction (the refinement is the truth to 1e-9); this also
        # fails for an error that is inflated or not widened.
        # The lower end allows the refinement's own distance from the truth (<= 1e-9 relative, asserted for
        # nls above), which the fold cannot know: 1e-9 x 0.03 against errors >= 1e-5, so 1 - 1e-6
        assert 1.0 - 1e-6 <= mode.std.damping_ratio / abs(mode.damping_ratio - THREE_ZETA[r]) <= 1.01


def test_matrix_system_multichannel_driving_and_transfer():
    M = np.diag([2.0, 1.0, 1.5])
    K = np.array([[4e4, -2e4, 0], [-2e4, 5e4, -3e4], [0, -3e4, 3e4]])
    C = 2.0 * M + 2e-5 * K  # proportional: real modes, real modal constants
    wn, zeta = modal_parameters_of_matrices(M, C, K)
    f = np.linspace(1, 1.6 * wn.max() / (2 * np.pi), 3000)
    frf = matrix_frf(f, M, C, K, reference_dof=0)
    result = identify(frf)
    assert len(result) == 3 and result.n_channels == 3
    for r, mode in enumerate(result):
        assert abs(mode.omega_n_rad_s / wn[r] - 1) < 1e-9
        assert abs(mode.damping_ratio / zeta[r] - 1) < 1e-8
        assert mode.modal_constant.shape == (3,)
        assert mode.driving_point.tolist() == [True, False, False]
        assert np.isfinite(mode.mass_kg[0]) and np.all(np.isnan(mode.mass_kg[1:]))
        assert "not_driving_point" in mode.flags
        # driving point: A_r = φ_0r² > 0, so the modal mass is 1/A_r
        assert abs(mode.stiffness_n_per_m[0] - mode.mass_kg[0] * mode.omega_n_rad_s**2) < 1e-9 * mode.stiffness_n_per_m[0]


def test_noise_efficiency_against_cramer_rao():
    """ζ = 0.01, σ = 1 % of max|H|, 10 lines per band, 200 seeded trials (issue 2)."""
    fn, zeta = 100.0, 0.01
    bw = 2 * zeta * fn
    df = bw / 10
    f = np.arange(fn - 3 * bw, fn + 3 * bw + df / 2, df)
    clean = modal_frf(f, [fn], [zeta], [1.0])
    sigma = 0.01 * np.abs(clean.response).max()
    errors, stds = [], []
    for seed in range(200):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", QualityWarning)
            mode = identify(add_noise(clean, 0.01, seed=seed), bands_hz=[(f[0], f[-1])])[0]
        errors.append([mode.natural_frequency_hz - fn, mode.damping_ratio - zeta])
        stds.append([mode.std.natural_frequency_hz, mode.std.damping_ratio])
    errors, stds = np.array(errors), np.array(stds)
    # bound of the model the estimator fits: (ωn, ζ, A) and the band's complex offset
    crlb = cramer_rao_sdof(2 * np.pi * f, 2 * np.pi * fn, zeta, 1.0, 0, sigma, offset=True)
    crlb_hz = np.array([crlb[0] / (2 * np.pi), crlb[1]])
    ratio = np.median(np.abs(errors), axis=0) / (0.6745 * crlb_hz)
    assert np.all(ratio <= 1.2), ratio
    # reported standard errors against the observed scatter: 25 % (the scatter of a
    # 200-sample standard deviation alone is ±5 %)
    scatter = errors.std(axis=0)
    assert np.all(np.abs(np.median(stds, axis=0) / scatter - 1) < 0.25)


def test_resolution_limited_damping_is_flagged_not_hidden():
    # ζ = 1e-4 at 100 Hz: half-power width 0.02 Hz on 0.5 Hz lines (0.04 lines per band)
    f = np.arange(50.0, 150.0, 0.5) + 0.13
    frf = modal_frf(f, [100.0], [1e-4], [1.0])
    for method in ("halfpower", "circle"):
        with pytest.warns(ResolutionWarning, match="resolution_limited"):
            mode = identify(frf, method)[0]
        assert "resolution_limited" in mode.flags
        assert np.isfinite(mode.natural_frequency_hz) and np.isfinite(mode.damping_ratio)
        assert not mode.ok
    nls = identify(frf, "nls")[0]  # exact data: the off-resonance lines carry the pole
    assert abs(nls.damping_ratio / 1e-4 - 1) < 1e-6
    assert nls.lines_per_bandwidth < 0.1


def test_close_modes_are_flagged():
    # two modes 1 Hz apart with 2 Hz half-power widths: one peak, SDOF model cannot fit
    f = np.linspace(80, 120, 801)
    frf = add_noise(modal_frf(f, [100.0, 101.0], [0.01, 0.01], [1.0, 1.0]), 0.002, seed=1)
    with pytest.warns(QualityWarning, match="model_inadequate"):
        result = identify(frf)
    assert len(result) == 1
    assert "model_inadequate" in result[0].flags and result[0].chi2 > 3


def test_peak_outside_band_is_flagged():
    f = np.linspace(50, 150, 1001)
    frf = modal_frf(f, [100.0], [0.01], [1.0])
    for method in ("halfpower", "circle"):
        with pytest.warns(modal.ModalWarning, match="band_edge_peak"):
            mode = identify(frf, method, bands_hz=[(80.0, 97.0)])[0]
        assert "band_edge_peak" in mode.flags
        assert np.isfinite(mode.damping_ratio)


def test_results_do_not_depend_on_units():
    frf, fn, m, k, c = sdof_case("mobility", 0.02, 6)
    base = identify(add_noise(frf, 0.005, seed=4))[0]
    scaled_frf = modal.FRF(frf.frequency_hz * 1e3, add_noise(frf, 0.005, seed=4).response * 1e6, kind="mobility")
    scaled = identify(scaled_frf)[0]
    assert abs(scaled.damping_ratio / base.damping_ratio - 1) < 1e-8
    assert abs(scaled.natural_frequency_hz / (1e3 * base.natural_frequency_hz) - 1) < 1e-10
    # mobility Y = iωA/D: scaling Y by 1e6 and ω by 1e3 scales A by 1e9, so m by 1e-9
    assert abs(scaled.mass_kg / (base.mass_kg * 1e-9) - 1) < 1e-8


def test_three_kinds_give_the_same_modes():
    f = np.linspace(10, 400, 2001)
    found = [identify(modal_frf(f, THREE_FN, THREE_ZETA, THREE_A, kind=kind)) for kind in KINDS]
    for modes in zip(*found):
        fns = [m.natural_frequency_hz for m in modes]
        assert np.ptp(fns) < 1e-9 * fns[0]


def test_rows_are_json_ready():
    import json

    result = identify(modal_frf(np.linspace(10, 400, 2001), THREE_FN, THREE_ZETA, THREE_A))
    rows = result.rows()
    assert len(rows) == 3
    text = json.dumps([{k: (str(v) if isinstance(v, complex) else v) for k, v in row.items()} for row in rows])
    # the keys of each mode at the top level of its object (the nested "std" repeats the
    # quantity names, so a search of the text would pass with them missing from the mode)
    quantities = ("natural_frequency_hz", "damping_ratio", "stiffness_n_per_m", "damping_n_s_per_m", "mass_kg")
    for row, truth in zip(json.loads(text), THREE_FN):
        assert set(quantities + ("std", "flags", "channel", "method")) <= set(row)
        assert set(quantities) <= set(row["std"])
        assert row["natural_frequency_hz"] == pytest.approx(truth, rel=1e-9)
        assert all(isinstance(row[q], float) and isinstance(row["std"][q], float) for q in quantities)


def test_bad_arguments():
    frf = modal_frf(np.linspace(10, 400, 2001), THREE_FN, THREE_ZETA, THREE_A)
    with pytest.raises(modal.IdentificationError, match="method"):
        identify(frf, "lscf")
    with pytest.raises(modal.IdentificationError, match="holds 0 lines"):
        identify(frf, bands_hz=[(1000.0, 2000.0)])
    with pytest.raises(modal.IdentificationError, match="pairs"):
        identify(frf, bands_hz=[100.0])
    with pytest.raises(modal.IdentificationError, match="no resonance"):
        identify(modal.FRF(np.linspace(1, 10, 50), np.ones(50)))


@pytest.mark.parametrize("method", ["circle", "halfpower"])
def test_many_channels_every_modal_constant(method):
    # 40 channels (> POLE_CHANNELS): the pole from the strongest, the others solved linearly
    rng = np.random.default_rng(7)
    A = rng.uniform(0.2, 2.0, (40, 3))
    frf = modal_frf(np.linspace(10, 400, 4001), THREE_FN, THREE_ZETA, A, kind="mobility")
    with pytest.warns(QualityWarning, match="method_bias"):  # exact data: bias ≫ noise error
        result = identify(frf, method)
    # the same with 0.1 % noise, where the refinement is no longer the truth and "the errors
    # cover the truth" can fail (on exact data it held by construction)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", QualityWarning)
        noisy = identify(add_noise(frf, 1e-3, seed=0), method)
    for r, mode in enumerate(noisy):
        if "method_bias" in mode.flags:
            z = np.abs(mode.modal_constant - A[:, r]) / mode.std.modal_constant
            # every channel, including the 8 outside the refinement's channels: within 3 errors
            # (P(|z| > 3) = 0.27 % for a calibrated error; observed max 1.7)
            assert np.all(z <= 3), z.max()
            # the neighbours' bias dominates the 0.1 % noise, so an honest error is about the
            # error itself (|z| ~ 1): a median below 0.55 means errors >= 1.8x too wide
            # (observed 0.92-0.96 circle, 0.71 = 1/sqrt(2) half-power, see notes/wt21b.md)
            assert np.median(z) >= 0.55, np.median(z)
    for r, mode in enumerate(result):
        assert mode.modal_constant.shape == (40,) and np.all(np.isfinite(mode.modal_constant))
        # a resonance-fitted |A| scales with the damping estimate (|A| = 2ζωn·|peak| for an SDOF),
        # so its error is bounded by the method's own ζ error, plus ~1e-2 from the neighbours
        zeta_error = abs(mode.damping_ratio / THREE_ZETA[r] - 1)
        np.testing.assert_allclose(np.abs(mode.modal_constant), A[:, r], rtol=2 * zeta_error + 2e-2)


def _method_check_case(lines_per_band, fn=100.0, zeta=0.01, half_widths=5):
    bw = 2 * zeta * fn
    df = bw / lines_per_band
    f = np.arange(fn - half_widths * bw, fn + half_widths * bw + df / 2, df)
    return modal_frf(f, [fn], [zeta], [1.0]), fn, zeta


def test_half_power_noise_bias_is_gone_and_errors_hold():
    # 300 lines per half-power band, 5 % noise: choosing the peak-fit and crossing-fit lines by
    # the noisy lines themselves lifted the -3 dB level and ζ came out low by ~20 of the method's
    # errors (docs/stress.md finding 9). The lines are now chosen on the model of the previous
    # pass (issue 21): the estimate is unbiased and its propagated errors hold. A calibrated
    # error fails |z| <= 3 with probability 0.27 % per quantity and seed, 2.7 % over these 10.
    clean, fn, zeta = _method_check_case(300)
    for seed in range(5):
        mode = identify(add_noise(clean, 0.05, seed=seed), "halfpower", bands_hz=[(clean.frequency_hz[0], clean.frequency_hz[-1])])[0]
        assert "method_bias" not in mode.flags
        assert abs(mode.damping_ratio - zeta) <= 3 * mode.std.damping_ratio
        assert abs(mode.natural_frequency_hz - fn) <= 3 * mode.std.natural_frequency_hz


@pytest.mark.parametrize("method", ["circle", "halfpower"])
def test_single_mode_methods_next_to_another_mode(method):
    # exact data, modes at 100 and 150 Hz: the neighbour biases the single-mode methods
    # (circle ζ -0.35 %, m +0.7 %: 17 and 22 of their errors before the check, finding 10)
    frf = modal_frf(np.linspace(50, 400, 3501), [100.0, 150.0], [0.02, 0.02], [1.0, 1.0])
    with pytest.warns(QualityWarning, match="method_bias"):
        result = identify(frf, method)
    assert len(result) == 2
    w1, w2 = 100.0**2, 150.0**2
    for mode, fn in zip(result, (100.0, 150.0)):
        assert "method_bias" in mode.flags
        # exact data: the widened error is hypot(noise part, bias) with a noise part of rounding,
        # so it must be the actual error from above and within 5 % (noise part <= 0.32 of the
        # bias; observed 1.0000-1.042). Only "covers" held by construction (refinement = truth).
        for value, truth, std in ((mode.damping_ratio, 0.02, mode.std.damping_ratio),
                                  (mode.natural_frequency_hz, fn, mode.std.natural_frequency_hz)):
            # (lower end: the refinement's own 1e-9 relative distance from the truth, as in
            # test_three_separated_modes)
            assert 1.0 - 1e-6 <= std / abs(value - truth) <= 1.05, (value, truth, std)
        # mass against the truth: the neighbour adds to the resonance at most
        # |H_other / H_own| = 2ζ ω_r² / |ω_1² − ω_2²| (3.2 % at 100 Hz, 7.2 % at 150 Hz)
        # to the constant the mass comes from (observed: circle 0.7 %)
        assert abs(mode.mass_kg - 1.0) <= 2 * 0.02 * fn**2 / (w2 - w1)


@pytest.mark.parametrize("method", ["circle", "halfpower"])
def test_method_check_is_quiet_on_sound_estimates(method):
    # one well-resolved mode, 1 % noise, 10 lines per band: the method is unbiased, the
    # difference to the refinement is noise with variance below the method's own; 3 sigma
    # is exceeded with probability < 0.6 % per estimate (ωn and ζ), so ≥ 3 flags in 50
    # seeded trials has probability 0.3 %
    clean, fn, zeta = _method_check_case(10, half_widths=3)
    band = [(clean.frequency_hz[0], clean.frequency_hz[-1])]
    flagged = 0
    for seed in range(50):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", QualityWarning)
            mode = identify(add_noise(clean, 0.01, seed=seed), method, bands_hz=band)[0]
        flagged += "method_bias" in mode.flags
    assert flagged <= 2


def test_circle_errors_match_scatter():
    # 30 lines per band, 1 % noise, 100 seeds: the circle is efficient on the lines it uses,
    # and its errors (floored at the Cramér–Rao bound of those lines; one channel, no median
    # penalty) match the observed scatter to 25 % (a 100-sample SD alone scatters ±7 %).
    # The mass too: the circle's own constant (its diameter) had errors 1.5x optimistic
    # (median error / scatter 0.65; found by the stress run, finding 24); its variance along
    # the difference from the refinement is now at least that difference squared
    clean, fn, zeta = _method_check_case(30, half_widths=3)
    band = [(clean.frequency_hz[0], clean.frequency_hz[-1])]
    values, stds, masses, mass_stds = [], [], [], []
    for seed in range(100):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", QualityWarning)  # damping_pair_spread at times
            mode = identify(add_noise(clean, 0.01, seed=seed), "circle", bands_hz=band)[0]
        values.append(mode.damping_ratio)
        stds.append(mode.std.damping_ratio)
        masses.append(float(mode.mass_kg))
        mass_stds.append(float(mode.std.mass_kg))
    assert abs(np.median(stds) / np.std(values) - 1) < 0.25
    assert abs(np.median(mass_stds) / np.std(masses) - 1) < 0.25


def test_hidden_neighbour_is_flagged_missing_mode():
    # docs/stress.md finding 11: a weak mode at 115 Hz on the shoulder of the 154 Hz one
    # escapes peak detection at 4.4 % noise; NLS then bends the 154 Hz mode towards it
    # (~12 of its errors off) while chi2 ≈ 2-3.3 stays near the limit. The residual check
    # adds one mode, finds the reduction significant (F-test at 1e-6) and flags it.
    f = np.linspace(50, 250, 3001)
    clean = modal_frf(f, [115, 154], [0.053, 0.057], [0.0008, 0.0036], kind="accelerance")
    for seed in range(4):
        with pytest.warns(QualityWarning, match=r"missing_mode.*near 11[45]\.\d+ Hz"):
            result = identify(add_noise(clean, 0.044, seed=seed))
        assert len(result) == 1 and "missing_mode" in result[0].flags
    # with both bands given, both modes are fitted and the check stays quiet
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        both = identify(add_noise(clean, 0.044, seed=0), bands_hz=[(95, 134.5), (134.5, 200)])
    assert [round(m.natural_frequency_hz) for m in both] == [115, 154]


@pytest.mark.parametrize("method", BANDWISE_METHODS)
def test_missing_mode_check_is_quiet_without_a_hidden_mode(method):
    # one mode, 1 % noise (false alarm < 1e-6 per test); and a strong mode just outside the
    # band, whose slope the band offset cannot absorb (structure that is not a mode here)
    clean, fn, zeta = _method_check_case(10, half_widths=3)
    band = [(clean.frequency_hz[0], clean.frequency_hz[-1])]
    for seed in range(20):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", QualityWarning)
            mode = identify(add_noise(clean, 0.01, seed=seed), method, bands_hz=band)[0]
        assert "missing_mode" not in mode.flags
    f = np.arange(90.0, 110.0, 0.1)
    near = modal_frf(f, [100.0, 130.0], [0.01, 0.02], [1.0, 2.0])
    for noise in (0.0, 0.001, 0.01):
        frf = add_noise(near, noise, seed=1) if noise else near
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", QualityWarning)
            mode = identify(frf, method, bands_hz=[(90.0, 110.0)])[0]
        assert "missing_mode" not in mode.flags


@pytest.mark.parametrize("method", BANDWISE_METHODS)
def test_band_edges_do_not_depend_on_the_frequency_unit(method):
    # docs/stress.md finding 13: a band edge exactly on a line (halfway between two peaks on
    # the 0.002 Hz grid) let rounding of the kHz axis drop the line at 1.000 Hz, and NLS ζ
    # moved 2.3 %. Edges now lie halfway between lines.
    fn = 1.0 * 1.002000001 ** np.arange(7)
    f = np.round(np.arange(0.99, 1.0201, 0.002), 6)
    frf = modal_frf(f, fn, np.full(7, 1e-3), np.r_[np.full(6, 39.4784176), 394.784176])
    results = []
    for scale in (1.0, 1e-3, 1e3):
        scaled = modal.FRF(f * scale, frf.response * scale, kind=frf.kind)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", modal.ModalWarning)  # unresolved: flagged
            results.append(identify(scaled, method))
    for modes in zip(*results):
        assert len({m.n_lines for m in modes}) == 1
        # the same lines, so only rounding and the LM stopping rule (1e-13) separate them
        np.testing.assert_allclose([m.damping_ratio for m in modes], modes[0].damping_ratio, rtol=1e-7)


def _overlapping_case(ratio):
    # modes at 1, r, r² Hz with ζ = 0.1 (overlap 0.2/(r−1)) and a mode at 10.55 Hz whose
    # receptance peak is 0.4 σ: below the noise (docs/stress.md finding 12)
    fn = np.array([1.0, ratio, ratio**2, 10.55])
    zeta = np.full(4, 0.1)
    f = np.linspace(0.05, 16, 800)
    bands = []
    for r, (fr, z) in enumerate(zip(fn, zeta)):
        lo, hi = fr - 6 * z * fr, fr + 6 * z * fr
        lo = max(lo, 0.5 * (fn[r - 1] + fr)) if r > 0 else lo
        hi = min(hi, 0.5 * (fn[r + 1] + fr)) if r < 3 else hi
        bands.append((max(lo, f[0]), min(hi, f[-1])))
    return modal_frf(f, fn, zeta, np.full(4, 39.4784176)), fn, zeta, bands


def test_overlapping_modes_errors_match_scatter():
    # overlap 1.2, 1.6 % noise, 40 seeds. Before: the sub-noise mode's ζ was driven to ≤ 0,
    # every such LM step was rejected, λ grew until the other modes stalled at their start
    # values, and ζ₁'s z-score had SD 2.0 (max 7.6). Now a pole pushed to ζ ≤ 0 moves to a
    # tenth of its value instead. A 40-sample SD scatters ±11 %, so [0.65, 1.35] is 3 sigma.
    clean, fn, zeta, bands = _overlapping_case(1.2)
    z = []
    for seed in range(40):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", modal.ModalWarning)
            mode = identify(add_noise(clean, 0.016, seed=seed), bands_hz=bands)[0]
        assert "close_modes" not in mode.flags  # overlap 1.2 < OVERLAP_LIMIT
        z.append((mode.damping_ratio - zeta[0]) / mode.std.damping_ratio)
    assert 0.65 < np.std(z) < 1.35 and np.max(np.abs(z)) < 5


def test_heavily_overlapping_modes_are_flagged_close():
    # overlap 2.2: the errors are 2-4x optimistic there, so the modes say so
    clean, *_, bands = _overlapping_case(1.1)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = identify(add_noise(clean, 0.016, seed=0), bands_hz=bands)
    assert any("close_modes" in str(w.message) and w.category is QualityWarning for w in caught)
    assert "close_modes" in result[0].flags and "close_modes" in result[1].flags


def test_unidentifiable_mode_stays_finite():
    # stress (units property): 16 lines for modes at 1 and 1.02 Hz at 3 % noise. After the
    # ζ ≤ 0 rule a pole ran off to ωn ≈ 1e35 Hz, ζ ≈ 1e59 and overflowed; poles are now kept
    # within a factor 2 of the lines and ζ ≤ 10, and such a mode ends flagged
    f = np.array([0.9, 0.9126031361863293, 0.9211361649560577, 0.9271328164451933, 0.9328584870699487,
                  0.947415990509741, 0.9630762815617414, 0.9753432572621412, 0.9889721356768664,
                  1.0005406414951075, 1.0164483131395692, 1.0310344524341384, 1.0366072715136294,
                  1.0516539974926218, 1.05756875411778, 1.0711993937659186])
    clean = modal_frf(f, [1.0, 1.02000000102], [0.01, 0.005623413251903491],
                      [39.47841760435743, 394.78417604357435], kind="accelerance")
    frf = add_noise(clean, 0.03125, seed=126)
    middle = 0.5 * (1.0 + 1.02000000102)  # ±6ζfn clipped halfway, as the stress case
    bands = [(0.94, middle), (middle, 1.02000000102 * (1 + 6 * 0.005623413251903491))]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", modal.ModalWarning)
        warnings.simplefilter("error", RuntimeWarning)
        result = identify(frf, bands_hz=bands)
    for mode in result:
        assert 0.45 <= mode.natural_frequency_hz <= 2.2 and 0 < mode.damping_ratio <= 10
    assert any(not m.ok for m in result)


def test_two_modes_merged_into_one_peak_are_flagged_missing_mode():
    # exact data, modes at 1 and 1.2 Hz with ζ = 0.1 (overlap 1.2) on 16 lines: peak detection
    # sees one peak; the fitted mode lies between them, many errors from either. Adding a mode
    # removes the residual (F-test) and the pair overlaps by less than 1.5, so it is not a
    # split of one mode: missing_mode (found by the accuracy property on a jittered axis)
    f = np.linspace(0.05, 2.3, 16)
    with pytest.warns(QualityWarning, match=r"missing_mode.*near 1\.\d+ Hz"):
        result = identify(modal_frf(f, [1.0, 1.2], [0.1, 0.1], [39.4784176] * 2))
    assert len(result) == 1 and "missing_mode" in result[0].flags


@pytest.mark.parametrize("method", BANDWISE_METHODS)
def test_linear_solves_do_not_depend_on_the_units(method):
    # receptance at 1e7 Hz (f × 1e3): mode columns ~1e-16 beside the offset column of ones
    # fell below lstsq's rank cut-off, half-power masses came out 1e29 off and missing_mode
    # depended on the unit (units property, STRESS_SEED=7). Columns are now scaled first.
    f = np.linspace(5e3, 2e4, 600)
    frf = add_noise(modal_frf(f, [1e4, 1.3e4], [0.05, 0.05], [1e4, 1e4]), 0.01, seed=2)
    scaled = modal.FRF(f * 1e3, frf.response * 1e-6, kind=frf.kind)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", modal.ModalWarning)
        base, other = identify(frf, method), identify(scaled, method)
    for a, b in zip(base, other):
        # receptance A' = s_h s_f² A = A here: the same masses, up to rounding and LM paths
        assert abs(b.mass_kg / a.mass_kg - 1) < 1e-9
        assert a.flags == b.flags


def test_solve_linear_scales_columns():
    from modal.model import solve_linear

    x = np.linspace(1, 2, 50)
    design = np.column_stack([1e-17 / x**2, np.ones_like(x)])
    coef = np.array([3e16, 2.0])
    np.testing.assert_allclose(solve_linear(design, design @ coef), coef, rtol=1e-12)


def test_no_lines_left_for_errors_is_flagged():
    # exact data, two modes with ζ = 0.001 on 0.0052 Hz lines and bands of ±6ζfn: five lines
    # for two modes and two offsets leave no degree of freedom for a residual. The Fisher
    # product then met inf·0 (RuntimeWarning) and the errors were NaN without a flag.
    f = 0.99 + 0.0052423755 * np.arange(16)
    fn = np.array([1.0, 1.0632455542666133])
    frf = modal_frf(f, fn, [0.001, 0.001], [39.4784176] * 2)
    bands = [(fr * (1 - 0.006), fr * (1 + 0.006)) for fr in fn]
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        warnings.simplefilter("error", RuntimeWarning)
        result = identify(frf, bands_hz=bands)
    assert any(issubclass(w.category, ResolutionWarning) for w in caught)
    for mode, truth in zip(result, fn):
        assert "too_few_points" in mode.flags
        assert abs(mode.natural_frequency_hz / truth - 1) < 1e-9  # exact data: still exact


def test_merged_modes_on_a_coarse_jittered_axis_are_flagged():
    # finding 17: exact data, modes at 1 and 1.2 Hz (ζ = 0.1, A 1:10) on 16 jittered lines.
    # Peak detection sees one peak and its fitted ζ is ~5 of its errors off. The raw-data noise
    # estimate is the resonance's curvature there, which hid the misfit; the check now takes
    # the residual's own neighbour misfit. Of the 60 cases below, 55 were unflagged before
    # (5 flagged); now the few unflagged ones are those where the added mode's reduction is at
    # the level of the data's roughness on the lines (docs/stress.md), so at least 90 % flagged.
    f_lo, step = 0.05, 2.35 / 16
    flagged = total = 0
    for seed in range(20):
        rng = np.random.default_rng(seed)
        f = f_lo + rng.uniform(0, 0.999) * step + np.r_[0.0, np.cumsum(rng.uniform(0.5, 1.5, 15) * step)]
        for kind in ("receptance", "mobility", "accelerance"):
            frf = modal_frf(f, [1.0, 1.2], [0.1, 0.1], [39.4784176, 394.784176], kind=kind)
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", modal.ModalWarning)
                result = identify(frf)
            if len(result) == 1:
                total += 1
                flagged += "missing_mode" in result[0].flags
    assert total >= 50 and flagged >= 0.9 * total


def test_structure_at_the_rounding_level_is_not_a_missing_mode():
    # exact one-mode data plus a mode-shaped disturbance at 1e-12 of the signal: the residual's
    # neighbour misfit is at rounding (1e-16), so without a floor the added mode was
    # "significant"; below sqrt(eps)·max|H| structure is the arithmetic of a fit, not data
    f = np.linspace(80, 120, 801)
    clean = modal_frf(f, [100.0], [0.02], [1.0])
    bump = modal_frf(f, [95.0], [0.01], [1.0])
    frf = modal.FRF(f, clean.response + 1e-12 * bump.response / np.abs(bump.response).max()
                    * np.abs(clean.response).max())
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", modal.ModalWarning)
        result = identify(frf, bands_hz=[(80, 120)])
    assert "missing_mode" not in result[0].flags


def test_three_modes_merged_into_one_peak_are_flagged():
    # stress case (overlap 1.2, 16 lines, exact data): 1, 1.2 and 1.44 Hz, ζ = 0.1, seen as
    # one peak. One added mode overlaps the fitted one by 1.7 (a split, so not missing_mode),
    # but the residual is 5σ of the noise the residual shows (the raw estimate, 6× larger
    # there, is the resonance's curvature): model_inadequate
    f = 0.05 + 0.17687500036 * np.arange(16)
    frf = modal_frf(f, [1.0, 1.2, 1.44], [0.1] * 3, [39.4784176, 394.784176, 39.4784176])
    with pytest.warns(QualityWarning, match="model_inadequate"):
        result = identify(frf)
    assert len(result) == 1 and "model_inadequate" in result[0].flags and result[0].chi2 > 3


def test_one_invalid_pole_leaves_the_refinement_check_to_the_others():
    # stress finding 25: at 16 % noise half-power gave one mode ζ < 0; the refinement check
    # then stood down for every mode of the fit, and a neighbour 46 of its errors off went
    # unflagged. The invalid pole now starts the refinement from its band.
    from modal.sdof.quality import refinement_check
    from modal.peaks import bands_from_hz, estimate_noise_std

    f = np.linspace(80, 180, 2001)
    frf = add_noise(modal_frf(f, [100.0, 150.0], [0.01, 0.01], [1.0, 1.0]), 0.01, seed=3)
    bands = bands_from_hz(frf, [(94, 106), (141, 159)])
    noise = estimate_noise_std(frf)
    two_pi = 2 * np.pi
    poles = [(two_pi * 100.3, 0.012, 1e-3, 1e-4, None, set(), 1.0),   # 0.3 % and 20 % off
             (two_pi * 150.0, -0.01, 1e-3, 1e-4, None, set(), 1.0)]   # not a pole at all
    consts = np.ones((2, 1), complex)
    check, _ = refinement_check(frf, bands, 0, poles, consts, noise, noise)
    d_wn, d_z, _, _, std_wn_ref, std_z_ref = check[0]
    assert std_wn_ref > 0 and std_z_ref > 0  # the first mode has its reference
    # the refined pole is the truth to its error (1 % noise, ~240 lines: ~1e-3 Hz, ~1e-5 in ζ),
    # so the differences are the offsets put in, to far better than these margins
    assert abs(d_wn / two_pi - 0.3) < 0.05 and abs(d_z - 0.002) < 5e-4
    assert abs(check[1][1] - (-0.02)) < 5e-3  # and the invalid one differs by its whole error


def test_half_power_crossing_stays_on_its_side_of_the_peak():
    # stress finding 27: mobility, ζ = 0.28 and 0.5, 18 % noise. The least-squares crossing
    # of the upper side (a quadratic through the lines within 1 dB of the level, which the
    # noise scatters over the whole side) fell below zero, and sqrt(ω1·ω2) warned and gave NaN.
    # A refined crossing outside its side's lines now keeps the line-interpolated one.
    f = 0.1593487327504735 + 0.21869746550094699 * np.arange(1864)
    clean = modal_frf(f, [1.0, 67.96612506431045], [0.2761579208653549, 0.5], [39.4784176, 70.2036572],
                      kind="mobility")
    frf = add_noise(clean, 0.1796875, seed=139715)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", modal.ModalWarning)
        warnings.simplefilter("error", RuntimeWarning)
        result = identify(frf, "halfpower", bands_hz=[(0.16, 2.66), (34.48, 271.86)])
    for mode, band in zip(result, [(0.16, 2.66), (34.48, 271.86)]):
        assert np.isfinite(mode.natural_frequency_hz) and np.isfinite(mode.damping_ratio)
        assert band[0] <= mode.natural_frequency_hz <= band[1]


def test_a_neighbour_moved_by_a_missing_mode_is_flagged_too():
    # stress finding 28: two modes (1 and 1.44 Hz, ζ = 0.165, A 1:5.6) at 19 % noise with both
    # bands given. The weak mode was lost below the noise (ζ → 0) and the strong one absorbed
    # it: ζ 0.233, 17 of its errors off. The missing-mode check finds the lost mode near band
    # 0; with it in the model the strong mode's pole moves by far more than its errors, so the
    # strong mode is among the moved ones (flagged missing_mode in identify)
    f = 0.05 + 0.002481875521503439 * np.arange(1521)
    fn, zeta = np.array([1.0, 1.4413468152582651]), 0.16548170999431813
    frf = add_noise(modal_frf(f, fn, [zeta] * 2, [39.4784176, 222.0034567]), 0.1875, seed=0)
    middle = 0.5 * (fn[0] + fn[1])
    bands = [(1 - 6 * zeta, middle), (middle, fn[1] * (1 + 6 * zeta))]
    keep = (f >= bands[0][0]) & (f <= bands[1][1])
    omega, response = frf.omega_rad_s[keep], frf.channels[:, keep]
    region = np.zeros(omega.size, int)
    # the model without the weak mode, as the collapsed fit had it
    fit = fit_modes(omega, response, 0, [2 * np.pi * fn[1]], [zeta], region=region)
    assert abs(fit.damping_ratio[0] - zeta) > 5 * np.sqrt(fit.mode_cov[0, 0, 1, 1])  # the bias is there
    found = find_missing_mode(omega, response, 0, region, fit.omega_n, fit.damping_ratio,
                              estimate_noise_std(frf), [(2 * np.pi * lo, 2 * np.pi * hi) for lo, hi in bands])
    assert found is not None and found.band == 0 and found.moved_bands == (0,)
    # identify itself now restarts the collapsed weak mode (finding 29), and the strong one is
    # within its errors, unflagged
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", modal.ModalWarning)
        strong = identify(frf, bands_hz=bands)[1]
    assert abs(strong.damping_ratio - zeta) < 3 * strong.std.damping_ratio
    assert not set(strong.flags) - {"driving_point_assumed"}


def test_mode_outside_every_band_on_exact_data_stays_within_its_errors():
    # stress finding 26: modes at 1, 3, 9 and 189 Hz, ζ = 0.1, exact data on a jittered axis;
    # the 189 Hz mode lies outside every band, and each band's plain offset leaves its slope
    # and curvature. The 9 Hz mode's ζ was 2.5e-7 relative off (5.5 of its errors, mass 9)
    # with no flag; the measured truncation shift is now part of its errors. 3 errors is the
    # bar: the shift estimates the bias to ~8 % (third order), so the error is ~1 of them
    fn, zeta = np.array([1.0, 3.0, 9.0, 189.0]), 0.1
    constant = np.array([1.0, 1.0, 10.0, 1.0]) * 39.478
    rng = np.random.default_rng(0)
    f = 0.05 + np.concatenate([[0.0], np.cumsum(rng.uniform(0.5, 1.5, 1888) * 0.2)])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", modal.ModalWarning)
        result = identify(modal_frf(f, fn, [zeta] * 4, constant))
    assert len(result) == 3
    for mode, true_fn, true_a in zip(result, fn, constant):
        assert not set(mode.flags) - {"driving_point_assumed"}
        assert abs(mode.natural_frequency_hz - true_fn) < 3 * mode.std.natural_frequency_hz
        assert abs(mode.damping_ratio - zeta) < 3 * mode.std.damping_ratio
        assert abs(mode.mass_kg - 1 / true_a) < 3 * mode.std.mass_kg


def test_mode_collapsed_on_a_noise_spike_is_restarted_and_its_neighbour_unbiased():
    # stress finding 29: receptance, 1 and 1.267 Hz at ζ = 0.1, constants 39.5 and 7.0, 18.75 %
    # noise (the weak mode's peak, 0.55, is below σ ≈ 0.94), both bands given. The weak mode's
    # start sat on a noise spike and it collapsed there (ζ 2.7e-4) inside the joint fit while
    # the strong mode absorbed it: ζ 5.4 and mass 6.5 of its errors off, unflagged. Restarted
    # where the strong mode's residual peaks, the fit reaches the lower least-squares optimum
    fn, zeta, constant = np.array([1.0, 1.267]), np.array([0.1, 0.1]), np.array([39.5, 7.0])
    f = 0.05 + np.arange(2208) * 0.0011246826503806956
    bands = [(max(0.4, f[0]), 0.5 * (fn[0] + fn[1])), (0.5 * (fn[0] + fn[1]), fn[1] * 1.6)]
    frf = add_noise(modal_frf(f, fn, zeta, constant), 0.1875, seed=0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", modal.ModalWarning)
        strong, weak = identify(frf, bands_hz=bands)
    # the weak mode is back near its truth: within 3 of its own (large) errors
    assert abs(weak.natural_frequency_hz - fn[1]) < 3 * weak.std.natural_frequency_hz
    assert abs(weak.damping_ratio - zeta[1]) < 3 * weak.std.damping_ratio
    assert not set(strong.flags) - {"driving_point_assumed"}
    assert abs(strong.damping_ratio - zeta[0]) < 3 * strong.std.damping_ratio
    assert abs(strong.mass_kg - 1 / constant[0]) < 3 * strong.std.mass_kg


def test_pole_covariance_leaves_undetermined_poles_undetermined():
    # a Fisher information with one direction the data do not determine (two parameters that enter only as
    # their sum): those two get NaN variances, the determined ones the inverse of their own block, as for a
    # regular matrix, where the result is its inverse (to the rounding of the diagonal scaling, a few ulp)
    from modal.nls import _pole_covariance

    regular = np.array([[4.0, 1.0], [1.0, 3.0]])
    np.testing.assert_allclose(_pole_covariance(regular), np.linalg.inv(regular), rtol=1e-14)
    u = np.array([1.0, 1.0])
    F = np.zeros((4, 4))
    F[:2, :2] = regular
    F[2:, 2:] = 5.0 * np.outer(u, u)  # rank one: only θ2 + θ3 is determined
    cov = _pole_covariance(F)
    assert np.all(np.isnan(cov[2:, :])) and np.all(np.isnan(cov[:, 2:]))
    np.testing.assert_allclose(cov[:2, :2], np.linalg.inv(regular), rtol=1e-12)


def test_modes_the_data_do_not_determine_get_no_errors_and_a_flag():
    # stress case (test_stress_three_kinds_give_the_same_modes, STRESS_SEED 8): 8 modes at ζ ≈ 0.3 with their
    # bands given, 6.7 % noise, accelerance. Two fitted poles collapse onto one peak (5.54 Hz), so the poles'
    # Fisher information is singular to rounding (eigenvalue ratio −5e-17); its inverse had negative variances
    # (a NaN warning from deep inside, or an error of 0 after clipping). Now: no warning (pytest makes one an
    # error), and every mode without finite errors says so (high_uncertainty)
    f = 0.05 + np.arange(3000) * 0.05270584516793943
    fn = np.array([1.0, 1.6324555336661317, 2.6649110693971743, 4.350348821965546, 7.101751007795592,
                   12.857460252036226, 23.27796116073712, 38.00023650931059])
    zeta = np.array([0.31622776601683794] * 3 + [0.167132847598886, 0.31622776601683794, 0.4052316974408941,
                                                  0.31622776601683794, 0.31622776601683794])
    constants = np.array([39.47841760435743, 39.47841760435743, 209.5939507317487] + [39.47841760435743] * 4
                         + [39.47841826985506])
    bands = []
    for r, (fr, z) in enumerate(zip(fn, zeta)):
        low = max(fr - 6 * z * fr, 0.5 * (fn[r - 1] + fr)) if r > 0 else fr - 6 * z * fr
        high = min(fr + 6 * z * fr, 0.5 * (fn[r + 1] + fr)) if r < fn.size - 1 else fr + 6 * z * fr
        bands.append((max(low, f[0]), min(high, f[-1])))
    frf = add_noise(modal_frf(f, fn, zeta, constants, kind="accelerance"), 0.06657220438918549, seed=8)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", modal.ModalWarning)
        result = identify(frf, "nls", bands_hz=bands)
    undetermined = [m for m in result
                    if not all(np.isfinite(np.asarray(getattr(m.std, name), float)).all()
                               for name in ("natural_frequency_hz", "damping_ratio", "mass_kg"))]
    assert undetermined
    assert all("high_uncertainty" in m.flags for m in undetermined)
    assert all(np.isfinite(m.natural_frequency_hz) and np.isfinite(m.damping_ratio) for m in result)


def test_halfpower_constant_biased_along_its_magnitude_is_flagged():
    # docs/stress.md finding 33: exact data, four modes (1, 3, 3.6, 3.672 Hz, ζ = 0.01), bands given. The 1 Hz
    # mode's half-power mass is 4.0e-5 relative off (the neighbours' truncation), 10 of its standard errors
    # along |A|, while its covariance is long across A: tested on the total error it read 1.9 < 3 and went
    # unflagged. The Mahalanobis distance flags it, and the bias is folded into the mass error (it then
    # covers the truth within 3 of it)
    f = 0.9 + np.arange(1569) * 0.002
    fn = np.array([1.0, 3.0000000030000002, 3.6000000071999994, 3.672000011016])
    zeta = np.full(4, 0.01)
    constants = np.full(4, 39.47841760435743)
    bands = []
    for r, (fr, z) in enumerate(zip(fn, zeta)):
        low = max(fr - 6 * z * fr, 0.5 * (fn[r - 1] + fr)) if r > 0 else fr - 6 * z * fr
        high = min(fr + 6 * z * fr, 0.5 * (fn[r + 1] + fr)) if r < fn.size - 1 else fr + 6 * z * fr
        bands.append((max(low, f[0]), min(high, f[-1])))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", modal.ModalWarning)
        mode = identify(modal_frf(f, fn, zeta, constants, kind="mobility"), "halfpower", bands_hz=bands)[0]
    mass = 1 / constants[0]
    assert abs(mode.mass_kg / mass - 1) > 1e-5  # the method's bias is there ...
    assert "method_bias" in mode.flags  # ... and said
    assert abs(mode.mass_kg - mass) <= 3 * mode.std.mass_kg


def test_residual_sum_of_squares_by_difference_matches_the_residual_it_stands_for():
    # many channels: each channel's residual sum of squares is ‖y‖² − ‖Qᴴy‖² (no product with every channel)
    # where that keeps 1e-4 of ‖y‖² (nls.RSS_BY_DIFFERENCE): the two sums' rounding, ~1e-15 of ‖y‖² (a few
    # hundred lines), is then below 1e-11 of the result. Exact data (residual at rounding) take the residual
    # itself: the difference would be rounding of either sign. The residual is formed for the rows asked
    f = np.linspace(20, 400, 761)
    rng = np.random.default_rng(4)
    const = rng.standard_normal((300, 2)) + 0.1j * rng.standard_normal((300, 2))
    exact = modal_frf(f, [100.0, 250.0], [0.02, 0.02], const)
    omega, region = exact.omega_rad_s, np.zeros(f.size, int)
    for frf, direct in ((add_noise(exact, 0.01, seed=5), False), (exact, True)):
        fit = fit_modes(omega, frf.channels, 0, 2 * np.pi * np.array([100.0, 250.0]), [0.02, 0.02], region=region)
        residual = fit.residual[:]
        rss = np.sum(np.abs(residual) ** 2, axis=1)
        dof = f.size - 3 - 4 / (2 * 300)
        energy = np.sum(np.abs(frf.channels) ** 2, axis=1)
        assert np.all(rss >= 1e-4 * energy) != direct
        if direct:  # rounding: the residual's own sum, to the last bits of the summation
            np.testing.assert_allclose(fit.noise_var, rss / dof, rtol=1e-12, atol=0)
        else:
            np.testing.assert_allclose(fit.noise_var, rss / dof, rtol=1e-10, atol=0)
        # the same rows formed alone: rounding of the fitted part, ~1e-16 of the data
        np.testing.assert_allclose(fit.residual[[3, 7]], residual[[3, 7]], rtol=0,
                                   atol=1e-13 * np.abs(frf.channels).max())


@pytest.mark.parametrize("method", ["nls", "halfpower", "circle", "global"])
def test_scalar_results_are_plain_floats_whatever_the_method(method):
    # a mode's scalars are Python floats for every method (the half-power and circle poles came out as numpy
    # scalars): the archive then records them as one type, and scripts that test isinstance(x, float) or
    # serialise them see the same thing from each method
    frf = add_noise(modal_frf(np.linspace(50.0, 150.0, 201), [100.0], [0.02], [1.0]), 0.005, seed=3)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        mode = identify(frf, method).modes[0]
    scalars = {"natural_frequency_hz": mode.natural_frequency_hz, "damping_ratio": mode.damping_ratio,
               "lines_per_bandwidth": mode.lines_per_bandwidth, "chi2": mode.chi2, "quality": mode.quality,
               "window_damping_ratio": mode.window_damping_ratio, "band low": mode.band_hz[0],
               "band high": mode.band_hz[1], "std fn": mode.std.natural_frequency_hz,
               "std zeta": mode.std.damping_ratio, "stiffness": mode.stiffness_n_per_m}
    assert {name: type(value).__name__ for name, value in scalars.items()} == {name: "float" for name in scalars}
