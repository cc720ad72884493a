"""The argument checks of modal (modal.validate): the checked value back, or a one-line error naming it."""
import numpy as np
import pytest

from modal import FRFValidationError, IdentificationError, ParameterError, identify
from modal.synthetic import modal_frf
from modal.validate import finite_samples, non_negative, one_of, per_channel, per_line, positive, positive_number


def test_checked_values_come_back_as_numbers():
    assert positive("mass_kg", 2).tolist() == [2.0]
    assert non_negative("level", [0.0, 1.5]).tolist() == [0.0, 1.5]
    assert positive_number("sample_rate_hz", "1024", "rate in Hz") == 1024.0
    assert one_of("window", "hann", ("rect", "hann")) == "hann"
    assert per_channel("noise_std", 0.5, 3).tolist() == [0.5, 0.5, 0.5]
    assert per_channel("noise_std", [0.5, 0.0], 2).tolist() == [0.5, 0.0]
    assert per_line("coherence", [[0.5, 1.0]], (1, 2)).tolist() == [[0.5, 1.0]]


@pytest.mark.parametrize("check, args, message", [
    (positive, ("mass_kg", [1.0, 0.0]), r"^'mass_kg' must be finite and > 0, got \[1.0, 0.0\]$"),
    (positive, ("mass_kg", np.inf), r"^'mass_kg' must be finite and > 0, got inf$"),
    (non_negative, ("level", -1e-3), r"^'level' must be finite and >= 0, got -0.001$"),
    (non_negative, ("level", np.nan), r"^'level' must be finite and >= 0, got nan$"),
    (positive_number, ("sample_rate_hz", 0, "rate in Hz"), r"^field 'sample_rate_hz' is 0; expected a positive rate in Hz$"),
    (positive_number, ("exponential_decay_s", "long", "time in s"), r"^field 'exponential_decay_s' is 'long'; expected"),
    (per_channel, ("noise_std", [1.0, 2.0], 3), r"^'noise_std' has 2 values; expected one, or one per channel \(3\)$"),
    (per_line, ("coherence", [0.5, 1.0], (1, 2)), r"^field 'coherence' must be finite, >= 0 and shaped like 'response' \(1, 2\)$"),
    (per_line, ("coherence", [[0.5, -1.0]], (1, 2)), r"^field 'coherence' must be finite, >= 0"),
    (one_of, ("window", "hamming", ("rect", "hann")), r"^field 'window' is 'hamming'; expected one of rect, hann$"),
])
def test_bad_values_give_one_line_naming_the_argument(check, args, message):
    with pytest.raises(ParameterError, match=message):
        check(*args)


def test_the_caller_chooses_the_error_and_the_file():
    with pytest.raises(FRFValidationError, match=r"^a\.h5: field 'exponential_decay_s' is -1"):
        positive_number("exponential_decay_s", -1, "time in s", FRFValidationError, "a.h5")
    with pytest.raises(IdentificationError, match="'noise_std'"):
        non_negative("noise_std", -1.0, IdentificationError)


def test_non_finite_samples_are_found_block_by_block():
    signal = np.zeros((2, 50))
    finite_samples(signal, "response", "rec.csv", block=16)
    signal[1, 37] = np.nan  # in the third block of 16
    with pytest.raises(ParameterError, match=r"^rec\.csv: field 'response' has a non-finite sample at channel 2, sample 37"):
        finite_samples(signal, "response", "rec.csv", block=16)


@pytest.mark.parametrize("method", ["nls", "global"])
def test_identify_checks_a_given_noise_for_every_method(method):
    frf = modal_frf(np.linspace(10.0, 100.0, 400), [30.0, 60.0], [0.02, 0.02], [1.0, 1.0])
    with pytest.raises(IdentificationError, match="'noise_std' must be finite and >= 0"):
        identify(frf, method, noise_std=np.nan)
    with pytest.raises(IdentificationError, match="field 'method' is 'lsq'"):
        identify(frf, "lsq")
