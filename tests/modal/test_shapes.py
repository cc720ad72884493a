"""Mode shapes from results, normalisation, MAC, MPC, MPD and animation frames."""
import warnings
from types import SimpleNamespace

import numpy as np
import pytest

import modal
from modal.errors import ParameterError
from modal.geometry import Geometry
from modal.shapes import (animation_frames, auto_mac, cross_mac, mac, mean_phase_deviation_deg, mode_shapes, mpc,
                          node_displacements, normalise)

FN = [30.0, 75.0, 140.0]
ZETA = [0.02, 0.015, 0.01]
#: mass-normalised shapes of three modes at five points (1/sqrt(kg)); point 1 is the driving point
PHI = np.array([[1.0, 0.8, 0.3, -0.2, -0.6], [0.7, -0.2, -0.9, -0.3, 0.5], [0.5, -0.8, 0.4, 0.7, -0.6]])


def _roving_accelerometer():
    const = PHI.T * PHI[:, 0][None, :]  # A_j = φ_j φ_1, (channels, modes)
    return modal.modal_frf(np.arange(1.0, 200.0, 0.25), FN, ZETA, const,
                           response_points=[f"{k}+Z" for k in range(1, 6)], reference_points=["1+Z"] * 5)


def test_shapes_of_an_identified_result_match_the_truth():
    frf = _roving_accelerometer()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", modal.ModalWarning)
        result = modal.identify(frf, "nls")
    shapes = mode_shapes(result, frf.response_points, frf.reference_points)
    assert shapes.points == tuple(f"{k}+Z" for k in range(1, 6)) and shapes.method == "nls"
    np.testing.assert_allclose(shapes.natural_frequency_hz, FN, rtol=1e-6)  # exact data: identification to rounding
    # exact data: the modal constants, hence the shapes, are recovered to the fit's rounding
    assert np.all(np.diag(mac(shapes.shapes, PHI)) > 1 - 1e-8)
    mass = normalise(shapes.shapes, "unit_modal_mass", driving_entry=0)
    np.testing.assert_allclose(mass.real, PHI * np.sign(PHI[:, :1]), atol=1e-5)
    np.testing.assert_allclose(mpc(shapes.shapes), 1.0, atol=1e-8)  # real modes


def test_roving_hammer_shapes_stand_on_the_reference_points_and_multi_reference_on_the_first():
    result = SimpleNamespace(method="global", n_channels=3, modes=(
        SimpleNamespace(natural_frequency_hz=10.0, damping_ratio=0.01, modal_constant=np.array([1, 2, 3]), flags=()),))
    hammer = mode_shapes(result, ["1"] * 3, ["1", "2", "3"])
    assert hammer.points == ("1", "2", "3") and hammer.channels.tolist() == [0, 1, 2]
    multi = mode_shapes(result, ["1+Z", "2+Z", "1+Z"], ["1+Z", "1+Z", "2+Z"])
    assert multi.channels.tolist() == [0, 1] and multi.points == ("1+Z", "2+Z")
    assert mode_shapes(result).points is None  # no ids: the channels in file order


def test_a_result_without_modal_constants_gives_its_mode_shape():
    # the form of an output-only result: a shape per mode, no modal constants
    shape = np.array([0.5, -1.0 + 0.1j])
    result = SimpleNamespace(method="oma", n_channels=2, modes=(
        SimpleNamespace(natural_frequency_hz=3.0, damping_ratio=0.02, modal_constant=None, mode_shape=shape,
                        flags=("weak_evidence",)),))
    shapes = mode_shapes(result, ["4+X", "5+X"])
    np.testing.assert_array_equal(shapes.shapes[0], shape)
    assert shapes.flags == (("weak_evidence",),)
    empty = SimpleNamespace(method="oma", n_channels=2, modes=(
        SimpleNamespace(natural_frequency_hz=3.0, damping_ratio=0.02, modal_constant=None, mode_shape=None),))
    with pytest.raises(ParameterError, match=r"mode 1 \(3 Hz, method 'oma'\) has no shape over the 2 channel"):
        mode_shapes(empty)


def test_normalise_to_the_largest_entry():
    out = normalise([[2j, -4j, 1], [0, 0, 0]])
    np.testing.assert_allclose(out[0], [-0.5, 1, 0.25j])
    np.testing.assert_array_equal(out[1], 0)
    with pytest.raises(ParameterError, match="driving point's entry"):
        normalise([[1, 2]], "unit_modal_mass")


def test_mac_is_scale_and_phase_free_and_zero_for_orthogonal_shapes():
    a = np.array([1.0, 2.0, -1.0])
    b = np.array([1.0, 0.0, 1.0])
    assert mac(a * (3 - 2j), a)[0, 0] == pytest.approx(1.0, abs=1e-15)
    assert mac(a, b)[0, 0] == pytest.approx(0.0, abs=1e-15)
    assert mac([0, 0, 0], a)[0, 0] == 0.0
    # |aᴴc|²/(|a|²|c|²) by hand: a = (1, 2, -1), c = (1, 1, 0): 9 / (6 · 2)
    assert mac(a, [1, 1, 0])[0, 0] == pytest.approx(0.75, rel=1e-15)


def test_auto_and_cross_mac_match_entries_by_point_id():
    one = modal.shapes.ModeShapes(np.array([1.0, 2.0]), np.zeros(2), PHI[:2, :3].astype(complex), np.arange(3),
                                  ("1+Z", "2+Z", "3+Z"), "nls")
    auto = auto_mac(one)
    np.testing.assert_allclose(np.diag(auto), 1.0)
    np.testing.assert_allclose(auto, auto.T)
    # the second test measured points 3 and 1 only, in another order: compared on those two
    other = modal.shapes.ModeShapes(np.array([1.0]), np.zeros(1), PHI[:1, [2, 0]].astype(complex) * 1j,
                                    np.arange(2), ("3+Z", "1+Z"), "global")
    cross = cross_mac(one, other)
    assert cross.shape == (2, 1) and cross[0, 0] == pytest.approx(1.0, abs=1e-14)
    assert cross[1, 0] == pytest.approx(mac(PHI[1, [0, 2]], PHI[0, [0, 2]])[0, 0], rel=1e-14)
    stranger = modal.shapes.ModeShapes(np.array([1.0]), np.zeros(1), np.ones((1, 1), complex), np.arange(1),
                                       ("9+Z",), "nls")
    with pytest.raises(ParameterError, match="share no point id"):
        cross_mac(one, stranger)


def test_mpc_and_mean_phase_deviation():
    real = np.array([1.0, -2.0, 0.5])
    assert mpc(real) == pytest.approx(1.0) and mean_phase_deviation_deg(real) == pytest.approx(0.0, abs=1e-12)
    assert mpc([1.0, 1j]) == pytest.approx(0.0, abs=1e-15)  # circular: no line at all
    # two equal entries 10° apart: the best line lies half-way, each deviates 5°
    tilted = np.array([1.0, np.exp(1j * np.radians(10))])
    assert mean_phase_deviation_deg(tilted) == pytest.approx(5.0, rel=1e-12)
    # Pappa's MPC of that pair by hand: ((sxx - syy)² + 4 sxy²) / (sxx + syy)² = cos²(10°)
    assert mpc(tilted) == pytest.approx(np.cos(np.radians(10)) ** 2, rel=1e-12)


def test_node_displacements_and_animation_frames():
    g = Geometry([1, 2, 3], [[0, 0, 0], [2, 0, 0], [4, 0, 0]], [[1, 2], [2, 3]]).with_channels(["2+Z", "2-X", "3+Y"])
    shape = np.array([1.0, 0.5, 2j])
    disp = node_displacements(g, shape)
    np.testing.assert_allclose(disp, [[0, 0, 0], [-0.5, 0, 1.0], [0, 2j, 0]])  # node 1 has no channel: still
    frames = animation_frames(g, shape, n_frames=4, amplitude=0.1)
    assert frames.shape == (4, 3, 3)
    # largest displacement amplitude (node 3, |2j|) scaled to 10 % of the 4 m extent: 0.4 m, in y at 90°
    scale = 0.4 / 2
    np.testing.assert_allclose(frames[0] - g.coordinates_m, (disp * scale).real, atol=1e-15)
    np.testing.assert_allclose(frames[1] - g.coordinates_m, (disp * 1j * scale).real, atol=1e-15)
    assert frames[1][2, 1] == pytest.approx(-0.4)
    with pytest.raises(ParameterError, match="3 placed channel"):
        node_displacements(g, [1.0, 2.0])
