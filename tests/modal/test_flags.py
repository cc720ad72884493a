"""Quality flags (modal.flags): raised where the data call for them, the rules and limits they share."""
import warnings

import numpy as np
import pytest

import modal
from modal import QualityWarning, ResolutionWarning, identify
from modal.synthetic import add_noise, modal_frf
from support.modes import overlapping_case


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


def test_peak_outside_band_is_flagged():
    f = np.linspace(50, 150, 1001)
    frf = modal_frf(f, [100.0], [0.01], [1.0])
    for method in ("halfpower", "circle"):
        with pytest.warns(modal.ModalWarning, match="band_edge_peak"):
            mode = identify(frf, method, bands_hz=[(80.0, 97.0)])[0]
        assert "band_edge_peak" in mode.flags
        assert np.isfinite(mode.damping_ratio)


def test_heavily_overlapping_modes_are_flagged_close():
    # overlap 2.2: the errors are 2-4x optimistic there, so the modes say so
    clean, *_, bands = overlapping_case(1.1)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = identify(add_noise(clean, 0.016, seed=0), bands_hz=bands)
    assert any("close_modes" in str(w.message) and w.category is QualityWarning for w in caught)
    assert "close_modes" in result[0].flags and "close_modes" in result[1].flags


# ---- the rules every method applies, and the limits the texts quote

def test_every_limit_a_text_quotes_is_the_one_the_rule_applies():
    from modal import flags

    quoted = {"high_uncertainty": f"exceeds {100 * flags.REL_STD_LIMIT:g} %",
              "close_modes": f"> {flags.OVERLAP_LIMIT:g})", "model_inadequate": f"chi-square > {flags.CHI2_LIMIT:g}",
              "method_bias": f"more than {flags.BIAS_LIMIT:g} of its standard errors",
              "complex_shape": f"MPC < {flags.MPC_LIMIT:g}", "complex_mode": f"phase > {flags.COMPLEX_PHASE_DEG:g} deg"}
    for name, text in quoted.items():
        assert text in flags.FLAG_TEXT[name], name
    assert f"more than {100 * flags.RELATIVE_MISFIT:g} % of the data" in flags.FLAG_TEXT["model_inadequate"]


def test_model_inadequate_needs_the_noise_test_and_the_misfit_test():
    from modal.flags import CHI2_LIMIT, RELATIVE_MISFIT, model_inadequate

    high, low = 2 * CHI2_LIMIT, 0.5 * CHI2_LIMIT
    assert model_inadequate(high, 2 * RELATIVE_MISFIT)
    assert not model_inadequate(high, 0.5 * RELATIVE_MISFIT)  # clean measured data: explained as well as it can be
    assert not model_inadequate(low, 2 * RELATIVE_MISFIT)
    assert model_inadequate(high, float("nan"))  # misfit not measured: the noise test alone
    assert not model_inadequate(float("nan"), 2 * RELATIVE_MISFIT)


def test_overlap_is_the_largest_with_any_other_mode():
    from modal.flags import overlap

    wn = np.array([90.0, 100.0, 103.0])
    zeta = np.array([0.09, 1e-4, 1e-4])
    # mode 1 against mode 0: 2·max(8.1, 0.01)/10 (the wider, further one); against mode 2: 2·0.0103/3
    assert overlap(wn, zeta, 1) == pytest.approx(2 * 0.09 * 90.0 / 10.0, rel=1e-12)
    assert overlap(np.array([1.0, 1.0]), np.array([0.1, 0.1]), 0) == np.inf  # one frequency: total overlap
    assert overlap(np.array([1.0, np.nan]), np.array([0.1, 0.1]), 0) == 0.0  # a mode without a pole is left out


def test_an_estimate_from_records_whose_half_power_band_holds_few_lines_is_resolution_limited():
    # random excitation, 60 s on 4096-sample segments (0.25 Hz lines): ζ 0.1 % at 40 Hz spans 0.32 lines per
    # half-power band, where the records' leakage dominates and nls's errors came out too small (z spread
    # 1.76 at 1.3 lines); ζ 1.2 % at 95 Hz spans 9 lines and is not flagged
    from modal.synthetic_time import DigitalModes, random_record

    plant = DigitalModes(np.array([40.0, 95.0]), np.array([0.001, 0.012]), np.array([0.5, 0.8]), 1024.0)
    record = random_record(plant, 60.0, response_noise=0.05, seed=3).record
    frf = modal.estimate_frf(record.signals[0], record.signals[1], 1024.0, kind="accelerance")
    with pytest.warns(ResolutionWarning, match="resolution_limited"):
        modes = identify(frf, "nls")
    light, heavy = sorted(modes, key=lambda m: m.natural_frequency_hz)
    assert "resolution_limited" in light.flags and "resolution_limited" not in heavy.flags
