"""Peak detection and the noise estimate."""
import numpy as np
from scipy.signal import find_peaks

from modal.peaks import _peaks_with_prominence, estimate_noise_std
from modal.synthetic import add_noise, modal_frf


def test_prominence_peaks_match_scipy():
    # our O(n) version replaces scipy.signal (1–2 s to import); it must pick the same peaks
    rng = np.random.default_rng(0)
    for _ in range(100):
        y = np.cumsum(rng.standard_normal(400))
        np.testing.assert_array_equal(_peaks_with_prominence(y, 3.0), find_peaks(y, prominence=3.0)[0])


def test_noise_estimate_matches_the_added_noise():
    f = np.linspace(1, 400, 4001)
    frf = add_noise(modal_frf(f, [50.0, 120.0], [0.02, 0.02], [1.0, 1.0]), 0.01, seed=2)
    sigma = 0.01 * np.abs(modal_frf(f, [50.0, 120.0], [0.02, 0.02], [1.0, 1.0]).response).max()
    # median of ~4000 exponential samples: relative error ~ 1.2/sqrt(4000) ≈ 2 %; resonances bias it slightly up
    assert abs(estimate_noise_std(frf)[0] / sigma - 1) < 0.1


def test_noise_estimate_ignores_a_trend_on_a_jittered_axis():
    # a line through its neighbours cancels any straight trend whatever the spacing; the plain
    # second difference kept slope × (change of spacing) and called it noise
    from modal import FRF

    rng = np.random.default_rng(3)
    f = 10 + np.cumsum(rng.uniform(0.5, 1.5, 2000))
    trend = (2 + 3j) * f
    assert estimate_noise_std(FRF(f, trend))[0] < 1e-12 * np.abs(trend).max()
    # white noise on that axis: the estimate is σ to the median's 1.2/sqrt(n) ≈ 3 % (4 of them)
    sigma = 0.1
    noise = sigma / np.sqrt(2) * (rng.standard_normal(f.size) + 1j * rng.standard_normal(f.size))
    assert abs(estimate_noise_std(FRF(f, trend + noise))[0] / sigma - 1) < 4 * 1.2 / np.sqrt(f.size)


def test_evenly_spaced_lines_take_the_same_misfit_as_any_axis():
    # an evenly spaced axis (np.linspace, whose spacings differ by rounding) is computed with weights ½ by
    # scalars: the misfit power equals the general weighted formula to rounding (the weights differ
    # from ½ by ~1e-13, the misfit by that times the neighbours' difference: 1e-11 of the mean power
    # bounds it with room), and a straight trend still cancels to rounding
    from modal.peaks import UNIFORM_WEIGHT_TOL, _misfit_power

    rng = np.random.default_rng(5)
    f = np.linspace(3.0, 403.0, 2001)
    step = np.diff(f)
    w_left = step[1:] / (step[:-1] + step[1:])
    assert 0 < np.max(np.abs(w_left - 0.5)) <= UNIFORM_WEIGHT_TOL
    values = rng.standard_normal((4, f.size)) + 1j * rng.standard_normal((4, f.size))
    misfit = values[:, 1:-1] - (w_left * values[:, :-2] + (1 - w_left) * values[:, 2:])
    general = np.abs(misfit) ** 2 / (1 + w_left**2 + (1 - w_left) ** 2)
    atol = 1e-11 * general.mean()
    np.testing.assert_allclose(_misfit_power(f, values), general, rtol=0, atol=atol)
    trend = (2 + 3j) * f
    assert _misfit_power(f, trend[None, :]).max() < (1e-12 * np.abs(trend).max()) ** 2


def test_channel_sample_takes_every_channel_up_to_its_size_and_a_fixed_unaliased_draw_beyond():
    from modal.peaks import SAMPLE_CHANNELS, channel_sample

    assert channel_sample(SAMPLE_CHANNELS) == slice(None)
    n = 3 * 400  # channels ordered point by point, three directions each (x, y, z, x, y, z, ...)
    rows = channel_sample(n)
    assert rows.size == SAMPLE_CHANNELS and np.all(np.diff(rows) > 0) and 0 <= rows[0] and rows[-1] < n
    np.testing.assert_array_equal(rows, channel_sample(n))  # the same channels on every call
    # every direction drawn about a third of the time: binomial(128, 1/3) is 42.7 ± 5.3; 4 SD either side
    # (a stride that is a multiple of 3 would draw one direction only)
    counts = np.bincount(rows % 3, minlength=3)
    expected, sd = SAMPLE_CHANNELS / 3, np.sqrt(SAMPLE_CHANNELS * (1 / 3) * (2 / 3))
    assert np.all(np.abs(counts - expected) <= 4 * sd), counts


def _many_channel_frf(n_channels=1000):
    rng = np.random.default_rng(1)
    const = rng.standard_normal((n_channels, 3)) + 0.05j * rng.standard_normal((n_channels, 3))
    f = np.linspace(0, 400, 2001)
    return add_noise(modal_frf(f, [50.0, 120.0, 300.0], [0.01, 0.02, 0.03], const, kind="accelerance"), 0.01, seed=2)


def test_sampled_tests_over_channels_agree_with_every_channel(monkeypatch):
    # the peak test's mean and the chi-square's median over 1000 channels, from 128 of them: the same
    # peaks, and chi-square within the sample median's error. Each channel's ratio of residual variance
    # (~735 degrees of freedom: 3.7 %) to its noise estimate (a median of ~740 neighbour misfits: 1.44/sqrt(n)
    # for independent ones, x1.3 for the neighbours' overlap, 7 %) spreads by at most 0.1; the median of 128
    # draws then has error 1.25 · 0.1/sqrt(128) · sqrt(1 − 128/1000) ≈ 0.01, and 4 of them bound it
    import warnings

    import modal.peaks as peaks
    from modal import identify
    from modal.peaks import find_modes

    frf = _many_channel_frf()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sampled_bands, sampled = find_modes(frf), identify(frf, "nls")
        monkeypatch.setattr(peaks, "SAMPLE_CHANNELS", frf.n_channels)
        every_bands, every = find_modes(frf), identify(frf, "nls")
    assert sampled_bands == every_bands and len(every_bands) == 3
    for a, b in zip(sampled.modes, every.modes):
        assert a.natural_frequency_hz == b.natural_frequency_hz and a.damping_ratio == b.damping_ratio
        assert abs(a.chi2 - b.chi2) <= 4 * 1.25 * 0.1 / np.sqrt(128) * np.sqrt(1 - 128 / 1000)
        assert a.flags == b.flags


def test_rows_taken_in_blocks_and_by_index_give_each_row_its_own_estimate():
    # the whole axis' noise takes its rows in blocks that share one stencil (the neighbour weights of the
    # axis), and find_modes measures the local noise on sampled rows by index: each row's estimate must be
    # the one it gets alone, exactly (the same arithmetic on the same numbers), on a jittered axis (weighted
    # stencil) and an even one (weights ½)
    from modal.peaks import _ROWS_AT_ONCE, _misfit_power, local_noise_std, neighbour_noise_std

    rng = np.random.default_rng(11)
    n_rows = 2 * _ROWS_AT_ONCE + 7
    for f in (10 + np.cumsum(rng.uniform(0.5, 1.5, 600)), np.linspace(0.0, 300.0, 600)):
        values = rng.standard_normal((n_rows, f.size)) + 1j * rng.standard_normal((n_rows, f.size))
        values *= rng.uniform(0.1, 10.0, n_rows)[:, None]
        alone = np.array([neighbour_noise_std(f, row[None, :])[0] for row in values])
        np.testing.assert_array_equal(neighbour_noise_std(f, values), alone)
        # the even axis' factor 2/3 is applied to the medians, not to every line: the same numbers
        power = _misfit_power(f, values)
        middle = np.sort(power, axis=1)[:, power.shape[1] // 2]
        np.testing.assert_array_equal(neighbour_noise_std(f, values), np.sqrt(middle / np.log(2)))
        rows = np.sort(rng.choice(n_rows, 40, replace=False))
        lines, exclude = [100, 300, 560], [10, 20, 5]
        np.testing.assert_array_equal(local_noise_std(f, values, lines, exclude, rows=rows),
                                      local_noise_std(f, values[rows], lines, exclude))
        assert np.all(np.isfinite(local_noise_std(f, values, lines, exclude, rows=rows)))


def test_indicator_peaks_and_noise_from_one_read_are_each_ones_own():
    # identify takes the mode indicator, each channel's max |H| and the raw noise from one read of the data in
    # blocks of rows: the peaks and the noise are exactly their own functions' (elementwise work and per-row
    # medians), the indicator the RMS over channels of |H|/max to rounding (its sum runs block by block), also
    # for channels whose |H|² would leave the float range (normalised first) and fewer lines than the misfit needs
    from modal import FRF
    from modal.peaks import _INDICATOR_ROWS, _indicator_and_peak, mode_indicator

    rng = np.random.default_rng(12)
    n_ch = 2 * _INDICATOR_ROWS + 9
    f = np.linspace(10.0, 200.0, 400)
    values = rng.standard_normal((n_ch, f.size)) + 1j * rng.standard_normal((n_ch, f.size))
    values *= np.geomspace(1e-3, 1e3, n_ch)[:, None]
    for scale in (1.0, 1e-200, 1e200):
        frf = FRF(f, values * scale)
        indicator, peak, noise = _indicator_and_peak(frf, noise=True)  # no warning where |H|² leaves the range
        magnitude = np.abs(frf.channels)
        np.testing.assert_array_equal(peak, magnitude.max(axis=1))
        with np.errstate(over="ignore"):  # (identify rescales such data before it uses their noise)
            np.testing.assert_array_equal(noise, estimate_noise_std(frf))
        direct = np.sqrt(np.mean((magnitude / magnitude.max(axis=1)[:, None]) ** 2, axis=0))
        np.testing.assert_allclose(indicator, direct, rtol=1e-13, atol=0)
        np.testing.assert_array_equal(mode_indicator(frf), indicator)
    short = FRF(f[:4], values[:, :4])
    assert np.all(np.isnan(_indicator_and_peak(short, noise=True)[2]))
