"""Mass-change scaling: mass-normalised shapes and per-channel k, c, m from two operational tests."""
from __future__ import annotations

import warnings

import numpy as np
import pytest
from scipy.linalg import eigh

import modal
from modal.errors import ParameterError
from modal.synthetic import ambient_response, chain_matrices

MASSES = np.array([2.0, 1.5, 1.0, 1.2])
SPRINGS = np.array([8e3, 6e3, 5e3, 4e3])
ADDED = {0: 0.2, 1: 0.15, 2: 0.1, 3: 0.12}


@pytest.fixture(scope="module")
def records():
    M, C, K = chain_matrices(MASSES, SPRINGS, 0.01)
    dM = np.diag([ADDED[i] for i in range(4)])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        before = modal.oma(ambient_response(M, C, K, 200.0, 300_000, noise=0.1, seed=1).signals, 200.0,
                           band_hz=(1.0, 60.0))
        after = modal.oma(ambient_response(M + dM, C, K, 200.0, 300_000, noise=0.1, seed=2).signals, 200.0,
                          band_hz=(1.0, 60.0))
    return M, K, before, after


def test_shapes_are_mass_normalised_within_ten_percent(records):
    M, K, before, after = records
    scaled = modal.scale_by_mass_change(before, after, ADDED)
    w2, phi = eigh(K, M)
    assert len(scaled) == 4
    for k, mode in enumerate(scaled):
        psi = mode.mode_shape.real
        truth = phi[:, k] * np.sign(phi[:, k] @ psi)
        assert np.all(np.abs(psi / truth - 1) < 0.1)
        assert abs(psi @ M @ psi - 1) < 0.1  # ψᵀ M ψ = 1 with the chain's known masses
        # each channel a driving point: m = 1/ψ², k = m ωn², c = 2 ζ m ωn
        assert np.allclose(mode.mass_kg, 1 / psi**2)
        assert np.allclose(mode.stiffness_n_per_m, mode.mass_kg * mode.omega_n_rad_s**2)
        assert np.allclose(mode.damping_n_s_per_m, 2 * mode.damping_ratio * mode.mass_kg * mode.omega_n_rad_s)
        assert np.all(mode.driving_point) and np.all(np.isfinite(mode.std.mass_kg))
        assert mode.kcm_covariance.shape == (4, 3, 3)
        assert "scaling_uncertain" not in mode.flags


def test_too_little_mass_is_flagged(records):
    M, K, before, _ = records
    # the same record as 'after': no frequency shift at all
    with pytest.warns(modal.QualityWarning, match="scaling_uncertain"):
        scaled = modal.scale_by_mass_change(before, before, {0: 1e-6})
    assert all("scaling_uncertain" in m.flags for m in scaled)


@pytest.mark.parametrize("added, message", [({9: 0.1}, "names channel 9"), ({0: -1.0}, "expected a positive mass"),
                                            ({}, "at least one channel")])
def test_bad_masses_are_refused(records, added, message):
    _, _, before, after = records
    with pytest.raises(ParameterError, match=message):
        modal.scale_by_mass_change(before, after, added)


def test_records_in_swapped_order_are_refused(records):
    # 'after' given first: every mode rose with the "added" mass, which lowers frequencies
    _, _, before, after = records
    with pytest.raises(ParameterError, match=r"every mode rose from 'before' \(<array>\) to 'after' \(<array>\): "
                                             r"3\.\d+ -> 3\.\d+ Hz, .*are the records swapped\?"):
        modal.scale_by_mass_change(after, before, ADDED)


def test_records_of_other_channels_are_refused(records):
    import dataclasses

    _, _, before, after = records
    names = ["1+Z", "2+Z", "3+Z", "4+Z"]
    one = dataclasses.replace(before, settings={**before.settings, "channel_names": names})
    for other, how in ((names[::-1], "in another order"), (["1+Z", "2+Z", "3+Z", "5+Z"], "other channels")):
        two = dataclasses.replace(after, settings={**after.settings, "channel_names": other})
        with pytest.raises(ParameterError, match=f"'after' \\(<array>\\) holds {how} than 'before'"):
            modal.scale_by_mass_change(one, two, ADDED)


def test_a_mass_too_small_to_move_the_modes_is_flagged(records):
    # 10 g on the 2 kg end mass: the shifts (< 0.25 %) are a few of their errors, the scale factors rest on noise
    # (psi' M psi off by up to a factor 3 here); every mode flagged, none passed as mass-normalised
    M, C, K = chain_matrices(MASSES, SPRINGS, 0.01)
    _, _, before, _ = records
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        small = modal.oma(ambient_response(M + np.diag([0.01, 0, 0, 0]), C, K, 200.0, 300_000, noise=0.1,
                                           seed=3).signals, 200.0, band_hz=(1.0, 60.0))
    with pytest.warns(modal.QualityWarning, match="scaling_uncertain"):
        scaled = modal.scale_by_mass_change(before, small, {0: 0.01})
    assert len(scaled) == 4 and all("scaling_uncertain" in m.flags for m in scaled)


def test_a_mass_given_at_another_channel_than_where_it_was_added_is_flagged(records):
    # 300 g added at channel 3 and given at channel 0: the shifts fit any channel (each mode has its own scale),
    # so the scaling came out unflagged with psi' M psi of 15.0, 1.42, 0.30, 0.80 (masses 15x off); the modes'
    # shape changes tell the channel (misfit 8 of its errors given at 0, 1.0 at 3: the limit is 3)
    M, C, K = chain_matrices(MASSES, SPRINGS, 0.01)
    _, _, before, _ = records
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        after = modal.oma(ambient_response(M + np.diag([0, 0, 0, 0.3]), C, K, 200.0, 300_000, noise=0.1,
                                           seed=4).signals, 200.0, band_hz=(1.0, 60.0))
    with warnings.catch_warnings(record=True) as said:
        warnings.simplefilter("always")
        wrong = modal.scale_by_mass_change(before, after, {0: 0.3})
    assert any("shape changes disagree with masses at channel(s) 0 (misfit" in str(w.message) for w in said)
    assert len(wrong) == 4 and all("scaling_uncertain" in m.flags for m in wrong)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # where it was added: no warning, no flag
        right = modal.scale_by_mass_change(before, after, {3: 0.3})
    assert all(abs(m.mode_shape.real @ M @ m.mode_shape.real - 1) < 0.25 for m in right)
