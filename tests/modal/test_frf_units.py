"""An FRF's unit (modal.frf_units): known units read as SI, unknown ones give no k, c, m."""
from __future__ import annotations

import warnings

import numpy as np
import pytest

import modal
from modal.errors import FormatError, QualityWarning
from modal.frf_units import parse_frf_unit
from modal.io import read_frf, write_frf
from modal.synthetic import modal_frf

G = 9.80665  # m/s^2, exact by definition
LBF = 4.4482216152605  # N, exact by definition
FREQUENCY = np.arange(1.0, 200.25, 0.25)  # Hz, a step UFF 58 keeps exactly


@pytest.mark.parametrize("label, kind, factor", [
    ("g/N", "accelerance", G), ("(m/s^2)/N", "accelerance", 1.0), ("m/s2/N", "accelerance", 1.0),
    ("mm/s^2/N", "accelerance", 1e-3), ("g/lbf", "accelerance", G / LBF), ("mm/s/N", "mobility", 1e-3),
    ("in/s/lbf", "mobility", 0.0254 / LBF), ("in/lbf", "receptance", 0.0254 / LBF), ("um/kN", "receptance", 1e-9),
])
def test_unit_labels_parse_to_their_kind_and_factor(label, kind, factor):
    parsed = parse_frf_unit(label)
    assert parsed[0] == kind and parsed[1] == pytest.approx(factor, rel=1e-15)


@pytest.mark.parametrize("label", ["V/V", "m/s^2/V", "g", "dB", "m/s^2/(unit not given)", None])
def test_labels_that_are_no_known_frf_unit(label):
    assert parse_frf_unit(label) is None


@pytest.mark.parametrize("suffix", [".csv", ".uff", ".mat", ".h5"])
def test_an_frf_file_in_g_per_newton_gives_the_true_mass(tmp_path, suffix):
    # a driving-point accelerance of a 1 kg, 40 Hz mode written in g/N (the values 1/9.80665 of SI): read back in
    # SI, so m = 1/A comes out 1 kg; fitted as if it were SI it would give 9.8 kg
    si = modal_frf(FREQUENCY, [40.0, 120.0], [0.02, 0.01], [1.0, 0.5], kind="accelerance",
                   response_points=["1+Z"], reference_points=["1+Z"])
    in_g = modal.FRF(si.frequency_hz, si.response / G, kind="accelerance", units="g/N", response_points=["1+Z"],
                     reference_points=["1+Z"])
    path = tmp_path / f"g{suffix}"
    write_frf(in_g, path)
    frf = read_frf(path)
    assert frf.units == "m/s^2/N"
    np.testing.assert_allclose(frf.response, si.response, rtol=1e-6)  # ASCII UFF keeps 6+ digits
    mode = modal.identify(frf, "nls").modes[0]
    assert mode.mass_kg == pytest.approx(1.0, rel=1e-5) and "units_unknown" not in mode.flags


def test_a_unit_of_another_kind_is_refused(tmp_path):
    frf = modal.FRF(FREQUENCY, modal_frf(FREQUENCY, [40.0], [0.02], [1.0], kind="accelerance").response,
                    kind="accelerance", units="mm/N")
    path = tmp_path / "x.csv"
    write_frf(frf, path)
    with pytest.raises(FormatError, match=r"x\.csv: the unit 'mm/N' is a receptance's but the FRF is declared an? "
                                          r"accelerance; expected"):
        read_frf(path)


def test_an_frf_in_volts_gives_frequency_and_damping_but_no_k_c_m():
    # raw voltages over voltages (sensitivities not applied): the poles are the same, k, c, m would be scaled by
    # the sensitivities' ratio: withheld on the driving point, flagged, with a warning; the transfer channel is
    # untouched (it has no k, c, m anyway)
    si = modal_frf(FREQUENCY, [40.0, 120.0], [0.02, 0.01], [[1.0, 0.5], [0.3, -0.2]], kind="accelerance",
                   response_points=["1+Z", "2+Z"], reference_points=["1+Z", "1+Z"])
    volts = modal.FRF(si.frequency_hz, si.response * 0.01, kind="accelerance", units="V/V",
                      response_points=["1+Z", "2+Z"], reference_points=["1+Z", "1+Z"])
    with pytest.warns(QualityWarning, match=r"unit 'V/V' is not one the toolkit converts.*units_unknown"):
        result = modal.identify(volts, "nls")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        reference = modal.identify(si, "nls")
    for mode, true in zip(result.modes, reference.modes):
        assert "units_unknown" in mode.flags
        assert mode.natural_frequency_hz == pytest.approx(true.natural_frequency_hz, rel=1e-9)
        assert mode.damping_ratio == pytest.approx(true.damping_ratio, rel=1e-6)
        assert np.all(np.isnan(mode.mass_kg)) and np.all(np.isnan(mode.std.stiffness_n_per_m))
        assert np.isfinite(true.mass_kg[0])
        rows = {row["channel"]: row for row in result.rows() if row["mode"] == result.modes.index(mode) + 1}
        assert "units_unknown" in rows[0]["flags"] and "units_unknown" not in rows[1]["flags"]  # channels from 0
