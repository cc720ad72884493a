"""The FRF container and the synthetic generators."""
import numpy as np
import pytest

from modal import FRF, FRFValidationError, ModalWarning, ParameterError
from modal.synthetic import add_noise, matrix_frf, modal_frf, modal_parameters_of_matrices, sdof_frf


def test_single_and_multi_channel_shapes():
    f = np.linspace(1, 10, 5)
    single = FRF(f, np.ones(5))
    multi = FRF(f, np.ones((3, 5)), response_points=["1", "2", "3"], reference_points="1")
    assert single.n_channels == 1 and single.response.shape == (5,) and single.channels.shape == (1, 5)
    assert multi.n_channels == 3 and multi.channels.shape == (3, 5)
    assert multi.is_driving_point().tolist() == [True, False, False]
    # a single channel without point ids: nothing says it is a driving point, and nothing assumes it
    assert single.is_driving_point().tolist() == [False] and not single.driving_point_known
    assert multi.driving_point_known


def test_arrays_are_read_only():
    frf = FRF([1.0, 2.0], [1j, 2j])
    with pytest.raises(ValueError):
        frf.response[0] = 0


def test_unsorted_frequencies_are_sorted_with_a_warning():
    with pytest.warns(ModalWarning, match="sorted"):
        frf = FRF([3.0, 1.0, 2.0], [30, 10, 20])
    assert frf.frequency_hz.tolist() == [1.0, 2.0, 3.0]
    assert frf.response.real.tolist() == [10, 20, 30]


@pytest.mark.parametrize(
    "freq, resp, match",
    [
        ([1.0, 1.0, 2.0], [1, 2, 3], "duplicate"),
        ([1.0, np.nan, 2.0], [1, 2, 3], "non-finite value"),
        ([1.0, np.inf, 2.0], [1, 2, 3], "non-finite value"),
        ([1.0, 2.0, 3.0], [1, np.nan, 3], "channel 0, line 1"),
        ([1.0, 2.0, 3.0], [1, 2], r"expected \(3,\)"),
        ([[1.0, 2.0]], [1, 2], "1-D"),
        ([1.0], [1], "at least 2"),
        ([-1.0, 2.0], [1, 2], "negative"),
        (["a", "b"], [1, 2], "not numeric"),
    ],
)
def test_bad_input_is_rejected_clearly(freq, resp, match):
    with pytest.raises(FRFValidationError, match=match):
        FRF(freq, resp, source="test.csv")


def test_error_names_the_source():
    with pytest.raises(FRFValidationError, match=r"^beam\.csv: field 'frequency_hz'"):
        FRF([1.0, 1.0], [1, 2], source="beam.csv")


def test_unknown_kind_and_wrong_point_count():
    with pytest.raises(FRFValidationError, match="kind"):
        FRF([1.0, 2.0], [1, 2], kind="compliance")
    with pytest.raises(FRFValidationError, match="one per channel"):
        FRF([1.0, 2.0], np.ones((2, 2)), response_points=["1"])


@pytest.mark.parametrize("start", ["receptance", "mobility", "accelerance"])
def test_kind_conversions_are_exact_round_trips(start):
    f = np.linspace(1, 100, 50)
    frf = modal_frf(f, [40.0], [0.02], [1.0], kind=start)
    for other in ("receptance", "mobility", "accelerance"):
        back = frf.as_kind(other).as_kind(start)
        # two multiplications by (iω)^±p: a few ulps
        np.testing.assert_allclose(back.response, frf.response, rtol=1e-14)
    np.testing.assert_allclose(frf.as_kind("accelerance").response,
                               modal_frf(f, [40.0], [0.02], [1.0], kind="accelerance").response, rtol=1e-13)


def test_conversion_at_zero_hz_to_lower_kind_is_refused():
    frf = FRF([0.0, 1.0], [0, 1], kind="accelerance")
    with pytest.raises(FRFValidationError, match="0 Hz"):
        frf.as_kind("receptance")


def test_sdof_matches_modal_form():
    f = np.linspace(1, 50, 200)
    m, k, c = 2.0, 1e4, 3.0
    wn = np.sqrt(k / m)
    direct = sdof_frf(f, m, k, c, kind="mobility")
    modal = modal_frf(f, [wn / 2 / np.pi], [c / (2 * m * wn)], [1 / m], kind="mobility")
    np.testing.assert_allclose(direct.response, modal.response, rtol=1e-12)


def test_matrix_frf_matches_modal_superposition():
    # 2-DOF chain with proportional damping C = a M + b K: real modes, exact modal sum
    M = np.diag([1.0, 2.0])
    K = np.array([[3e4, -1e4], [-1e4, 1e4]])
    C = 0.5 * M + 1e-4 * K
    f = np.linspace(1, 40, 300)
    frf = matrix_frf(f, M, C, K, reference_dof=0)
    lam, vec = np.linalg.eig(np.linalg.solve(M, K))
    order = np.argsort(lam)
    lam, vec = lam[order], vec[:, order]
    vec = vec / np.sqrt(np.einsum("ir,ij,jr->r", vec, M, vec))  # mass-normalised
    wn = np.sqrt(lam)
    zeta = (0.5 / wn + 1e-4 * wn) / 2
    A = vec * vec[0][None, :]  # A_r = φ_jr φ_0r
    expected = modal_frf(f, wn / 2 / np.pi, zeta, A)
    np.testing.assert_allclose(frf.channels, expected.channels, rtol=1e-9, atol=1e-15)
    wn2, zeta2 = modal_parameters_of_matrices(M, C, K)
    np.testing.assert_allclose(wn2, wn, rtol=1e-12)
    np.testing.assert_allclose(zeta2, zeta, rtol=1e-10)


def test_noise_is_seeded_and_scaled():
    f = np.linspace(1, 10, 20000)
    clean = FRF(f, np.ones(f.size) * 2.0)
    a, b = add_noise(clean, 0.1, seed=3), add_noise(clean, 0.1, seed=3)
    assert np.array_equal(a.response, b.response)
    noise = a.response - clean.response
    # E|n|² = (0.1 · max|H|)² = 0.04; the sample of 20000 has a relative error ~ 1/√20000
    assert abs(np.mean(np.abs(noise) ** 2) / 0.04 - 1) < 5 / np.sqrt(20000)


def test_bad_synthetic_parameters():
    with pytest.raises(ParameterError, match="natural_frequency_hz"):
        modal_frf([1, 2], [-1.0], [0.1], [1.0])
    with pytest.raises(ParameterError, match="damping_ratio"):
        modal_frf([1, 2], [1.0], [-0.1], [1.0])
    with pytest.raises(ParameterError, match="positive definite"):
        matrix_frf([1, 2], -np.eye(2), np.zeros((2, 2)), np.eye(2))


# ---- what identification needs, carried as fields: the noise per line and the window's time constant

def test_noise_and_window_fields_are_checked_and_name_the_field():
    f = np.linspace(1, 10, 5)
    with pytest.raises(FRFValidationError, match="field 'noise_std'"):
        FRF(f, np.ones(5), noise_std=np.ones(4), source="a.h5")  # not shaped like the response
    with pytest.raises(FRFValidationError, match="a.h5: field 'noise_std'"):
        FRF(f, np.ones(5), noise_std=-np.ones(5), source="a.h5")
    for decay in (0.0, -1.0, float("nan"), "long"):
        with pytest.raises(FRFValidationError, match="field 'exponential_decay_s'"):
            FRF(f, np.ones(5), exponential_decay_s=decay)
    plain = FRF(f, np.ones(5))
    assert plain.noise_std is None and plain.exponential_decay_s is None


def test_noise_per_line_follows_sorting_cropping_channels_and_kind():
    f = np.array([3.0, 1.0, 2.0, 4.0])
    noise = np.array([[0.3, 0.1, 0.2, 0.4], [3.0, 1.0, 2.0, 4.0]])
    with pytest.warns(ModalWarning, match="sorted"):
        frf = FRF(f, np.ones((2, 4)), kind="receptance", noise_std=noise, exponential_decay_s=0.5)
    assert frf.noise_std.tolist() == [[0.1, 0.2, 0.3, 0.4], [1.0, 2.0, 3.0, 4.0]]  # moved with its lines
    assert frf.cropped(2.0, 3.0).noise_std.tolist() == [[0.2, 0.3], [2.0, 3.0]]
    one = frf.channel(1)
    assert one.noise_std.tolist() == [1.0, 2.0, 3.0, 4.0] and one.exponential_decay_s == 0.5
    # a receptance's error times |iω|² is the accelerance's error, line by line (exact but for one rounding)
    converted = frf.as_kind("accelerance")
    omega = 2 * np.pi * frf.frequency_hz
    assert np.allclose(converted.noise_std, frf.noise_std * omega**2, rtol=1e-15, atol=0)


def test_identify_takes_the_noise_and_the_window_from_the_fields():
    from modal import identify

    # a mode seen through an exponential window exp(-t/τ): its pole moved left by 1/τ (exact)
    fn, zeta, tau = 50.0, 0.01, 0.5
    wn = 2 * np.pi * fn
    sigma = zeta * wn + 1 / tau
    wd = wn * np.sqrt(1 - zeta**2)
    wn_m = np.hypot(wd, sigma)
    f = np.linspace(40.0, 60.0, 801)
    seen = modal_frf(f, [wn_m / (2 * np.pi)], [sigma / wn_m], [1.0])
    level = 1e-3 * np.abs(seen.response).max()
    frf = FRF(f, add_noise(seen, 1e-3, seed=1).response, noise_std=np.full(f.size, level), exponential_decay_s=tau)
    result = identify(frf, "nls", bands_hz=[(44.0, 56.0)])
    mode = result[0]
    # the window's damping (σ/ωn of the seen pole, less ζ: 0.0064) taken back out, to the noise's errors
    # (0.1 % noise: std of ζ ~1e-5; without the window's τ the fit would report 0.0164)
    assert abs(mode.damping_ratio - zeta) < 5 * mode.std.damping_ratio
    assert abs(mode.window_damping_ratio - (sigma / wn_m - zeta)) < 5 * mode.std.damping_ratio
    # the noise the fit used is the FRF's own per line (its RMS over the band), not one estimated from the data
    assert result.noise_std == pytest.approx([level], rel=1e-12)
