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


@pytest.mark.parametrize("numerator, denominator, factor", [("g", "N", G), ("g", "NONE", G), ("m/s^2", "", 1.0),
                                                             ("mm/s^2", "N", 1e-3)])
def test_uff_unit_labels_are_converted(tmp_path, numerator, denominator, factor):
    # UFF 58 keeps the numerator's and the denominator's unit labels apart; a force denominator (data type 13)
    # without a label is in N, UFF's default unit system
    import os

    import pyuff

    si = modal_frf(FREQUENCY, [40.0], [0.02], [1.0], kind="accelerance").response
    path = tmp_path / "labels.uff"
    open(path, "wb").close()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # pyuff leaves its file handles to the garbage collector
        pyuff.UFF(os.fspath(path)).write_sets({
            "type": 58, "binary": 1, "id1": "frf", "id2": "NONE", "id3": "NONE", "id4": "NONE", "id5": "NONE",
            "func_type": 4, "func_id": 1, "ver_num": 0, "load_case_id": 0, "rsp_ent_name": "NONE", "rsp_node": 1,
            "rsp_dir": 3, "ref_ent_name": "NONE", "ref_node": 1, "ref_dir": 3, "abscissa_spacing": 1,
            "abscissa_min": FREQUENCY[0], "abscissa_inc": FREQUENCY[1] - FREQUENCY[0], "z_axis_value": 0.0,
            "abscissa_spec_data_type": 18, "abscissa_axis_lab": "Frequency", "abscissa_axis_units_lab": "Hz",
            "ordinate_spec_data_type": 12, "ordinate_axis_lab": "NONE", "ordinate_axis_units_lab": numerator,
            "orddenom_spec_data_type": 13, "orddenom_axis_lab": "NONE", "orddenom_axis_units_lab": denominator,
            "z_axis_spec_data_type": 0, "x": FREQUENCY, "data": si / factor}, mode="add", force_double=True)
    frf = read_frf(path)
    assert frf.units == "m/s^2/N"
    np.testing.assert_allclose(frf.response, si, rtol=1e-12)


def test_the_table_does_not_call_constants_in_an_unknown_unit_1_per_kg():
    # the modal constants of an FRF in V/V are in V/V (an accelerance; (V/V)/s for a mobility), not 1/kg: the table's header says so
    si = modal_frf(FREQUENCY, [40.0], [0.02], [[1.0]], kind="accelerance", response_points=["1+Z"],
                   reference_points=["1+Z"])
    volts = modal.FRF(si.frequency_hz, si.response * 0.01, kind="accelerance", units="V/V",
                      response_points=["1+Z"], reference_points=["1+Z"])
    from modal.report.tables import format_table

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        table = format_table(modal.identify(volts, "nls"))
        assert "A [1/kg]" in format_table(modal.identify(si, "nls"))
    assert "A [V/V-based]" in table and "1/kg" not in table


@pytest.mark.parametrize("kind, constant, upper", [("accelerance", "V/V", "(V/V) s^2"),
                                                   ("mobility", "(V/V)/s", "(V/V) s"),
                                                   ("receptance", "(V/V)/s^2", "V/V")])
def test_the_archive_and_the_json_carry_the_constants_true_unit(tmp_path, kind, constant, upper):
    # A = H_receptance (ωn² − ω² + 2iζωnω) is the FRF's unit times s^(p − 2) (1/kg for an accelerance in m/s²/N):
    # an FRF in V/V gives constants in V/V (accelerance), (V/V)/s (mobility), (V/V)/s² (receptance). The archive
    # wrote "1/kg" on them (and on their errors), and the line noise in the kind's SI unit
    import json

    import h5py

    import modal.cli
    from modal.archive import read_archive, write_archive
    from support.cli import run_main

    si = modal_frf(FREQUENCY, [40.0, 120.0], [0.02, 0.01], [1.0, 0.5], kind=kind, response_points=["1+Z"],
                   reference_points=["1+Z"])
    volts = modal.FRF(si.frequency_hz, si.response * 0.01, kind=kind, units="V/V", response_points=["1+Z"],
                      reference_points=["1+Z"])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        result = modal.identify(volts, "nls")
        reference = modal.identify(si, "nls")
    write_archive(tmp_path / "volts.h5", {"identify_nls": result, "si": reference})
    with h5py.File(tmp_path / "volts.h5", "r") as f:
        assert f["identify_nls/modes/0/modal_constant"].attrs["units"] == constant
        assert f["identify_nls/modes/1/std/modal_constant"].attrs["units"] == constant
        assert f["identify_nls/noise_std"].attrs["units"] == "V/V"
        assert f["identify_nls/modes/0/natural_frequency_hz"].attrs["units"] == "Hz"  # the rest as before
        assert f["si/modes/0/modal_constant"].attrs["units"] == "1/kg"  # an SI FRF's constants are in 1/kg
        assert f["si/noise_std"].attrs["units"] == modal.frf.DEFAULT_UNITS[kind]
    assert read_archive(tmp_path / "volts.h5")["identify_nls"].settings["frf_units"] == "V/V"
    # the residual terms (where a method fits them): the upper one a receptance, the lower one as the constants
    assert result.archive_units()["residuals"] == (f"{upper} (column 0: upper residual), {constant} "
                                                   "(column 1: lower residual)")
    # modal fit --json says the constants' unit beside them
    for frf, expected in ((volts, constant), (si, "1/kg")):
        path = tmp_path / f"{expected.replace('/', '_')}.csv"
        write_frf(frf, path)
        done = run_main(modal.cli.main, ["fit", path, "--method", "nls", "--json"])
        assert done.returncode == 0, done.stderr
        assert json.loads(done.stdout)["modal_constant_units"] == expected
