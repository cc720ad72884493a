"""A declared kind the data contradict (modal.kind_check): warned, naming the kind the data look like."""
import warnings

import numpy as np
import pytest

import modal
from modal.kind_check import kind_contradiction
from modal.synthetic import add_noise, modal_frf
from support.paths import REAL, SYNTHETIC

#: four separated modes of equal modal mass, 0.01 % noise: every mode stands well above the noise in every kind
FREQ = np.linspace(0.0, 1000.0, 4001)
FN, ZETA = [80.0, 210.0, 400.0, 650.0], [0.01, 0.015, 0.01, 0.02]


def _driving_point(true_kind, declared, sign=1.0):
    data = add_noise(modal_frf(FREQ, FN, ZETA, [1.0] * 4, kind=true_kind), 1e-4, seed=1)
    return modal.FRF(FREQ, sign * data.response, kind=declared, response_points=["1"], reference_points=["1"])


def _kind_warnings(frf, **options):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = modal.identify(frf, "nls", **options)
    return result, [str(w.message) for w in caught if "look like" in str(w.message)]


def _shipped():
    files = [(path, dict(frequency_step=1.0, kind="accelerance")) for path in sorted(REAL.glob("pyuff_meas_point_*.txt"))]
    return files + [(SYNTHETIC / "demo_frf.csv", {}), (SYNTHETIC / "plate_frf.uff", {})]


@pytest.mark.parametrize("path, hints", _shipped(), ids=lambda v: getattr(v, "name", ""))
def test_no_false_alarm_on_the_shipped_files_and_a_warning_when_read_as_receptance(path, hints):
    frf = modal.read_frf(path, **hints)
    assert frf.kind == "accelerance"
    result, found = _kind_warnings(frf)
    assert found == [] and len(result) >= 3
    # the same numbers declared a receptance: the masses come out omega_r**2 times too small, and the level
    # between the modes (receptance-unit slopes -2.2 to -1.1 as accelerance) does not fall as a receptance's
    wrong = modal.FRF(frf.frequency_hz, frf.response, kind="receptance")
    _, found = _kind_warnings(wrong)
    assert len(found) == 1 and "the data look like accelerance, not receptance as declared" in found[0]
    assert "--kind accelerance" in found[0]


def test_the_demo_driving_point_read_as_receptance_gives_power_back():
    frf = modal.read_frf(SYNTHETIC / "demo_frf.csv")
    wrong = modal.FRF(frf.frequency_hz, frf.response, kind="receptance", response_points=frf.response_points,
                      reference_points=frf.reference_points)
    _, found = _kind_warnings(wrong)
    assert len(found) == 1 and "look like accelerance" in found[0]
    assert "would give power back on 100 %" in found[0] and "absorbs power on 100 %" in found[0]


@pytest.mark.parametrize("true_kind, declared", [("accelerance", "receptance"), ("accelerance", "mobility"),
                                                 ("mobility", "receptance"), ("receptance", "accelerance")])
def test_a_driving_point_of_another_kind_is_named(true_kind, declared):
    result, found = _kind_warnings(_driving_point(true_kind, declared))
    assert len(result) == 4
    assert len(found) == 1 and f"the data look like {true_kind}, not {declared} as declared" in found[0]


@pytest.mark.parametrize("kind", ["receptance", "mobility", "accelerance"])
def test_no_warning_for_the_declared_kind_nor_for_a_reversed_sign(kind):
    for sign in (1.0, -1.0):
        result, found = _kind_warnings(_driving_point(kind, kind, sign))
        assert len(result) == 4 and found == []
    # a reversed sign is a sign, not a kind: the constants say so (non_positive_constant)
    assert all("non_positive_constant" in mode.flags for mode in result)


def test_too_few_modes_to_judge_give_no_verdict():
    frf = modal_frf(FREQ, FN[:2], ZETA[:2], [1.0, 1.0], kind="accelerance")
    wrong = modal.FRF(frf.frequency_hz, frf.response, kind="receptance")
    modes, found = _kind_warnings(wrong)  # without a driving point only the skeleton could tell
    assert len(modes) == 2 and found == []
    assert kind_contradiction(wrong, modes) is None
