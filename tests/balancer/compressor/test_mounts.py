"""Six-degree-of-freedom compressor body on mounts (balancer.compressor.mounts).

Body and mount data are seed 000's Table 1 and mount table, with the mount
layout read as a triangle below the CG (reference note ``crank_drive.md``
section 2).  Reference-note numbers are checked to half a unit in their last
printed digit.
"""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from balancer.compressor.crank import (
    SliderCrank,
    counterweight_on_curve,
    optimal_counterweight,
    shaking_harmonics,
    slider_crank_from_components,
)
from balancer.compressor.mounts import (
    BalancingComparison,
    Mount,
    MountedBody,
    RigidBody,
    balancing_comparison,
    compressor_response,
    damping_matrix,
    harmonic_response,
    inertia_tensor,
    mass_matrix,
    mount_from_identification,
    natural_modes,
    stiffness_matrix,
)
from modal.errors import ParameterError
from support.identified import identified_mode, within

SPEED_RPM = 2950.0
CRANK_CENTRE_M = (0.005, 0.008, 0.005)
MOUNT_STIFFNESS = (30_500.0, 30_500.0, 63_000.0)
TRIANGLE_M = ((0.0, 0.076, -0.056), (-0.052, -0.060, -0.056), (0.052, -0.060, -0.056))


@pytest.fixture
def body() -> RigidBody:
    return RigidBody(16.3, inertia_tensor(0.0670, 0.0590, 0.0405, ixz_kg_m2=0.0010))


@pytest.fixture
def compressor(body) -> MountedBody:
    return MountedBody(body, tuple(Mount(p, MOUNT_STIFFNESS) for p in TRIANGLE_M),
                       damping_ratio=0.05)


@pytest.fixture
def mech() -> SliderCrank:
    split = slider_crank_from_components(0.0119, 0.050, 0.044, 0.0163, 0.067, 0.134)
    return dataclasses.replace(split, rod_inertia_correction_kg_m2=-2.0487e-5)


# ----------------------------------------------------------------------------- independent checks
def _stiffness_by_virtual_work(mounts) -> np.ndarray:
    """K_jl from the potential energy U(q) = 1/2 sum_i d_i' k_i d_i, d_i = u + phi x p_i.

    U is quadratic, so the polarisation K_jl = U(e_j + e_l) - U(e_j) - U(e_l) is
    exact; it uses np.cross and never builds the T matrices of the module.
    """
    def energy(q):
        total = 0.0
        for mount in mounts:
            d = q[:3] + np.cross(q[3:], mount.position_m)
            total += 0.5 * np.sum(mount.stiffness_n_per_m * d ** 2)
        return total

    eye = np.eye(6)
    return np.array([[energy(eye[j] + eye[l]) - energy(eye[j]) - energy(eye[l])
                      for l in range(6)] for j in range(6)])


def _frequencies_by_cholesky(stiffness, mass) -> np.ndarray:
    """Generalised problem reduced to a standard one: L^-1 K L^-T with M = L L'."""
    chol = np.linalg.cholesky(mass)
    inv = np.linalg.inv(chol)
    return np.sqrt(np.linalg.eigvalsh(inv @ stiffness @ inv.T)) / (2 * np.pi)


def test_stiffness_matrix_equals_virtual_work(compressor):
    # Two constructions of K agree to rounding (entries ~1e5 N/m, eps ~ 1e-16).
    np.testing.assert_allclose(stiffness_matrix(compressor.mounts),
                               _stiffness_by_virtual_work(compressor.mounts), rtol=0, atol=1e-9)


def test_natural_frequencies_against_an_independent_eigen_solution(compressor):
    modes = natural_modes(compressor)
    independent = _frequencies_by_cholesky(_stiffness_by_virtual_work(compressor.mounts),
                                           mass_matrix(compressor.body))
    # same problem, different algorithms: agreement to ~1e-12 relative
    np.testing.assert_allclose(modes.natural_frequency_hz, independent, rtol=1e-10)
    # reference note, 2 decimals: 7.63 / 9.56 / 16.62 / 17.23 / 20.17 / 22.06 Hz
    np.testing.assert_allclose(modes.natural_frequency_hz,
                               [7.63, 9.56, 16.62, 17.23, 20.17, 22.06], atol=5e-3)
    # running speed 49.17 Hz is above every mode: the mounts isolate
    assert modes.natural_frequency_hz.max() < SPEED_RPM / 60


def test_mode_shapes_are_mass_normalised_and_share_energy(compressor):
    modes = natural_modes(compressor)
    mass, stiffness = mass_matrix(compressor.body), stiffness_matrix(compressor.mounts)
    phi = modes.mode_shapes
    np.testing.assert_allclose(phi.T @ mass @ phi, np.eye(6), atol=1e-12)
    omega2 = (2 * np.pi * modes.natural_frequency_hz) ** 2
    np.testing.assert_allclose(phi.T @ stiffness @ phi, np.diag(omega2), atol=1e-8 * omega2.max())
    np.testing.assert_allclose(modes.kinetic_energy_share.sum(axis=0), 1.0, atol=1e-12)
    # reference note: mode 1 is x 72 %, phi_y 27 %; mode 2 y 84 %; mode 3 z 88 %; mode 6 phi_x 79 %
    share = modes.kinetic_energy_share
    assert share[0, 0] == pytest.approx(0.72, abs=5e-3)
    assert share[4, 0] == pytest.approx(0.27, abs=5e-3)
    assert share[1, 1] == pytest.approx(0.84, abs=5e-3)
    assert share[2, 2] == pytest.approx(0.88, abs=5e-3)
    assert share[3, 5] == pytest.approx(0.79, abs=5e-3)


def test_frequencies_do_not_depend_on_sign_conventions(body):
    # reference note: same frequencies with -Ixz, mounts above the CG, or mirrored in y
    base = natural_modes(MountedBody(body, tuple(Mount(p, MOUNT_STIFFNESS) for p in TRIANGLE_M)))
    flipped_body = RigidBody(16.3, inertia_tensor(0.0670, 0.0590, 0.0405, ixz_kg_m2=-0.0010))
    above = tuple(Mount((x, y, -z), MOUNT_STIFFNESS) for x, y, z in TRIANGLE_M)
    mirrored = tuple(Mount((x, -y, z), MOUNT_STIFFNESS) for x, y, z in TRIANGLE_M)
    for system in (MountedBody(flipped_body, tuple(Mount(p, MOUNT_STIFFNESS) for p in TRIANGLE_M)),
                   MountedBody(body, above), MountedBody(body, mirrored)):
        np.testing.assert_allclose(natural_modes(system).natural_frequency_hz,
                                   base.natural_frequency_hz, rtol=1e-10)


def test_literal_ocr_mount_signs_give_an_implausible_low_mode(body):
    # All mounts on +y, above the CG, as OCR'd: 1.20 / 5.26 / 11.53 / 13.16 / 24.52 / 26.07 Hz
    literal = ((0.0, 0.076, 0.056), (-0.052, 0.060, 0.056), (0.052, 0.060, 0.056))
    modes = natural_modes(MountedBody(body, tuple(Mount(p, MOUNT_STIFFNESS) for p in literal)))
    np.testing.assert_allclose(modes.natural_frequency_hz,
                               [1.20, 5.26, 11.53, 13.16, 24.52, 26.07], atol=5e-3)


def test_static_sag_under_gravity(compressor):
    # Vertical force balance: the mounts carry m g, so with equal k_z their mean
    # deflection is m g / sum k_z = 16.3 * 9.81 / 189000 = 0.846 mm (reference:
    # 0.85 mm).  The CG is not above the mount centroid, so the body also tilts.
    q = np.linalg.solve(stiffness_matrix(compressor.mounts), [0, 0, -16.3 * 9.81, 0, 0, 0])
    sag = [-(q[:3] + np.cross(q[3:], p))[2] for p in TRIANGLE_M]
    assert np.mean(sag) == pytest.approx(16.3 * 9.81 / (3 * 63_000), rel=1e-12)
    assert np.mean(sag) * 1e3 == pytest.approx(0.85, abs=5e-3)


def test_modal_damping_matrix_gives_the_damping_ratio(compressor):
    modes = natural_modes(compressor)
    phi = modes.mode_shapes
    modal_c = phi.T @ damping_matrix(compressor) @ phi
    omega = 2 * np.pi * modes.natural_frequency_hz
    np.testing.assert_allclose(modal_c, np.diag(2 * 0.05 * omega), atol=1e-9 * omega.max())


# ----------------------------------------------------------------------------- response
def test_single_dof_limit_with_mount_dampers():
    # Four identical mounts symmetric about the CG in the plane z = 0 and a
    # vertical force at the CG: pure heave, X = F / (4k - W^2 m + i W 4c).
    k, c, m = 50_000.0, 120.0, 10.0
    square = ((0.1, 0.1, 0.0), (-0.1, 0.1, 0.0), (-0.1, -0.1, 0.0), (0.1, -0.1, 0.0))
    system = MountedBody(RigidBody(m, np.diag([0.2, 0.2, 0.3])),
                         tuple(Mount(p, (k, k, k), (c, c, c)) for p in square))
    omega = 2 * np.pi * 30.0
    res = harmonic_response(system, omega, [1, 2], [[0, 0, 100.0], [0, 0, 50.0j]])
    for row, (order, force) in enumerate(((1, 100.0), (2, 50.0j))):
        w = order * omega
        expected = force / (4 * k - w ** 2 * m + 1j * w * 4 * c)
        assert res.displacement[row, 2] == pytest.approx(expected, rel=1e-12)
        np.testing.assert_allclose(np.delete(res.displacement[row], 2), 0, atol=1e-12 * abs(expected))
        # force into the base: each mount passes (k + i w c) * X
        np.testing.assert_allclose(res.mount_force_n[row, :, 2], (k + 1j * w * c) * expected,
                                   rtol=1e-12)
        assert res.base_force_n[row, 2] == pytest.approx(4 * (k + 1j * w * c) * expected, rel=1e-12)


def test_base_force_obeys_newtons_second_law(compressor, mech):
    # F_base = F_applied - m * acceleration = F + W^2 m X_cg (independent of how
    # the damping matrix was built).
    res = compressor_response(compressor, mech, SPEED_RPM, CRANK_CENTRE_M)
    omega = 2 * np.pi * res.frequency_hz
    expected = res.load[:, :3] + (omega ** 2)[:, None] * 16.3 * res.displacement[:, :3]
    np.testing.assert_allclose(res.base_force_n, expected, rtol=1e-9, atol=1e-9)


def test_point_displacements_and_mount_forces(body, mech):
    system = MountedBody(body, tuple(Mount(p, MOUNT_STIFFNESS) for p in TRIANGLE_M),
                         damping_ratio=0.05)
    res = compressor_response(system, mech, SPEED_RPM, CRANK_CENTRE_M, points_m=TRIANGLE_M)
    for index, point in enumerate(TRIANGLE_M):
        # u + phi x p, computed with np.cross
        direct = res.displacement[:, :3] + np.cross(res.displacement[:, 3:], point)
        np.testing.assert_allclose(res.point_displacement_m[:, index], direct, rtol=1e-12,
                                   atol=1e-18)
        # no mount dampers: each mount passes k * d
        np.testing.assert_allclose(res.mount_force_n[:, index], np.asarray(MOUNT_STIFFNESS) * direct,
                                   rtol=1e-12, atol=1e-15)


def test_compressor_response_before_and_after_balancing(compressor):
    # The reference note's section-2 table was computed with Table 1's printed
    # (rounded) lumped masses 0.0967 / 0.1483 kg; with those every entry
    # reproduces to half a unit in its last digit.  (With the exact masses
    # 0.096656 / 0.148344 kg the unbalanced 1x x amplitude is 74.547 um, which
    # rounds to 74.5, not 74.6: the table is sensitive to the 0.05 % mass rounding.)
    mech = SliderCrank(0.0119, 0.050, 0.0967, 0.1483, rod_inertia_correction_kg_m2=-2.0487e-5)
    opt = optimal_counterweight(mech, SPEED_RPM)
    paper = counterweight_on_curve(mech, opt, k=0.6218)
    cmp_opt = balancing_comparison(compressor, mech, SPEED_RPM, CRANK_CENTRE_M, paper.mass_kg,
                                   paper.radius_m)
    cmp_full = balancing_comparison(compressor, mech, SPEED_RPM, CRANK_CENTRE_M,
                                    0.0967 + 0.1483, 0.0119)
    assert isinstance(cmp_opt, BalancingComparison)
    # reference note section 2 (1x, peak amplitudes; half a unit in the last digit)
    rows = (
        (cmp_opt.before, (74.6, 189.7), 0.559, (6.50, 18.28)),
        (cmp_opt.after, (67.4, 47.3), 0.131, (6.37, 4.56)),
        (cmp_full.after, (114.6, 0.0), 0.222, (10.64, 0.02)),
    )
    for res, disp_um, rot_mrad, base_n in rows:
        np.testing.assert_allclose(np.abs(res.displacement[0, :2]) * 1e6, disp_um, atol=0.05)
        assert abs(res.displacement[0, 5]) * 1e3 == pytest.approx(rot_mrad, abs=5e-4)
        np.testing.assert_allclose(np.abs(res.base_force_n[0, :2]), base_n, atol=5e-3)
    # balancing cuts the peak 1x force into the base from 18.3 N to 6.4 N
    assert cmp_opt.base_force_amplitude_after_n[0].max() < 0.4 * cmp_opt.base_force_amplitude_before_n[0].max()
    # the 2x line is untouched by any counterweight: 40.1 N excitation, 6.5 um, 0.72 N
    np.testing.assert_allclose(cmp_opt.after.base_force_n[1], cmp_opt.before.base_force_n[1],
                               rtol=1e-12)
    assert abs(cmp_opt.after.load[1, 1]) == pytest.approx(40.1, abs=0.05)
    assert abs(cmp_opt.after.displacement[1, 1]) * 1e6 == pytest.approx(6.5, abs=0.05)
    assert abs(cmp_opt.after.base_force_n[1, 1]) == pytest.approx(0.72, abs=5e-3)


def test_exact_kinematics_response_has_higher_orders(compressor, mech):
    exact = dataclasses.replace(mech, harmonics="exact")
    res = compressor_response(compressor, exact, SPEED_RPM, CRANK_CENTRE_M, max_order=4)
    np.testing.assert_array_equal(res.orders, [1, 2, 3, 4])
    harm = shaking_harmonics(exact, SPEED_RPM, max_order=4)
    # 4x force ~ m_rec r w^2 lam^3 / 4 ~ 0.47 N; 3x only in the couple
    assert abs(harm.force_n[3, 1]) == pytest.approx(
        0.148344 * 0.0119 * (2 * np.pi * SPEED_RPM / 60) ** 2 * (0.238 ** 3 / 4 + 3 * 0.238 ** 5 / 16),
        rel=1e-2)  # O(lam^7) / O(lam^3) ~ 6e-3 truncation of the series
    assert abs(harm.force_n[2, 1]) < 1e-9
    assert abs(res.base_force_n[3]).max() > 0


# ----------------------------------------------------------------------------- identification
# Fed real identification results: modal.identify on the receptance of a known mount
# (0.1 % noise); the mount takes the identified values as they are, and those are the truth
# within their own errors.
def test_mount_from_identification_single_and_per_direction():
    mode = identified_mode(1.0, 30_500.0, 12.0)
    assert within(mode.stiffness_n_per_m, 30_500.0, mode.std.stiffness_n_per_m)
    assert within(mode.damping_n_s_per_m, 12.0, mode.std.damping_n_s_per_m)
    one = mount_from_identification((0, 0.1, -0.05), mode)
    np.testing.assert_array_equal(one.stiffness_n_per_m, [mode.stiffness_n_per_m] * 3)
    np.testing.assert_array_equal(one.damping_n_s_per_m, [mode.damping_n_s_per_m] * 3)
    modes = [identified_mode(1.0, k, c, seed=s) for s, (k, c) in enumerate(((30_500.0, 10.0), (31_000.0, 11.0),
                                                                             (63_000.0, 20.0)))]
    per_dir = mount_from_identification((0, 0.1, -0.05), modes)
    np.testing.assert_array_equal(per_dir.stiffness_n_per_m, [m.stiffness_n_per_m for m in modes])
    np.testing.assert_array_equal(per_dir.damping_n_s_per_m, [m.damping_n_s_per_m for m in modes])
    assert within(per_dir.stiffness_n_per_m, [30_500.0, 31_000.0, 63_000.0], [m.std.stiffness_n_per_m for m in modes])
    # three driving-point channels of one mount (masses 1, 0.5, 2 kg per channel): k, c per channel
    channels = identified_mode(np.array([1.0, 0.5, 2.0]), 1e4, 1.0)
    assert channels.stiffness_n_per_m.shape == (3,)
    picked = mount_from_identification((0, 0, 0), channels, channel=2)
    np.testing.assert_array_equal(picked.stiffness_n_per_m, [channels.stiffness_n_per_m[2]] * 3)
    np.testing.assert_array_equal(picked.damping_n_s_per_m, [channels.damping_n_s_per_m[2]] * 3)
    assert within(picked.stiffness_n_per_m, 2e4, channels.std.stiffness_n_per_m[2])
    assert within(picked.damping_n_s_per_m, 2.0, channels.std.damping_n_s_per_m[2])


def test_identified_mounts_drive_the_response(body, mech):
    # Mounts whose k and c come from identification results must behave exactly as the same
    # mounts given directly (bit-for-bit: same arithmetic), and, the identified values being
    # the truth within ~1e-4, like the design mounts within that.
    identified = [identified_mode(1.0, k, c, seed=s)
                  for s, (k, c) in enumerate(((30_500.0, 15.0), (30_500.0, 15.0), (63_000.0, 22.0)))]
    from_id = MountedBody(body, tuple(mount_from_identification(p, identified) for p in TRIANGLE_M))
    direct = MountedBody(body, tuple(Mount(p, [m.stiffness_n_per_m for m in identified],
                                           [m.damping_n_s_per_m for m in identified]) for p in TRIANGLE_M))
    design = MountedBody(body, tuple(Mount(p, MOUNT_STIFFNESS, (15.0, 15.0, 22.0)) for p in TRIANGLE_M))
    a = compressor_response(from_id, mech, SPEED_RPM, CRANK_CENTRE_M)
    b = compressor_response(direct, mech, SPEED_RPM, CRANK_CENTRE_M)
    np.testing.assert_array_equal(a.base_force_n, b.base_force_n)
    assert np.all(np.abs(a.base_force_n[:, :2]).max(axis=1) > 0)
    # relative errors of the identified k: ~3e-4 (0.1 % noise); the base force, far from the
    # mount resonances, moves by about as much: 1e-2 is a loose bound that a wrong k, c
    # order (x, y, z) or unit would still break
    rel = max(m.std.stiffness_n_per_m / m.stiffness_n_per_m for m in identified)
    assert rel < 1e-3
    c = compressor_response(design, mech, SPEED_RPM, CRANK_CENTRE_M)
    np.testing.assert_allclose(np.abs(a.base_force_n), np.abs(c.base_force_n), rtol=1e-2,
                               atol=1e-6 * np.abs(c.base_force_n).max())


def test_bad_identification_input():
    channels = identified_mode(np.array([1.0, 0.5, 2.0]), 1e4, 1.0)
    with pytest.raises(ParameterError, match="has 3 channels: pass channel="):
        mount_from_identification((0, 0, 0), channels)
    with pytest.raises(ParameterError, match="channel = 5"):
        mount_from_identification((0, 0, 0), channels, channel=5)
    # a transfer channel has no k, c (NaN, flag not_driving_point)
    transfer = identified_mode(np.array([1.0, 0.5]), 1e4, 1.0, driving_point=[True, False])
    assert "not_driving_point" in transfer.flags
    with pytest.raises(ParameterError, match="stiffness_n_per_m = nan"):
        mount_from_identification((0, 0, 0), transfer, channel=1)
    mode = identified_mode(1.0, 1e4, 1.0)
    with pytest.raises(ParameterError, match="damping_n_s_per_m = -1.0"):
        mount_from_identification((0, 0, 0), dataclasses.replace(mode, damping_n_s_per_m=-1.0))
    with pytest.raises(ParameterError, match="no attribute 'stiffness_n_per_m'"):
        mount_from_identification((0, 0, 0), object())
    with pytest.raises(ParameterError, match="identified has 2 results"):
        mount_from_identification((0, 0, 0), [mode] * 2)


# ----------------------------------------------------------------------------- bad input
def test_singular_mount_layouts_raise(body):
    on_a_line = tuple(Mount((x, 0.0, -0.05), MOUNT_STIFFNESS) for x in (-0.1, 0.0, 0.1))
    with pytest.raises(ParameterError, match="singular mount layout.*phi_x"):
        MountedBody(body, on_a_line)
    no_vertical = tuple(Mount(p, (30_500.0, 30_500.0, 0.0)) for p in TRIANGLE_M)
    with pytest.raises(ParameterError, match="singular mount layout.*u_z"):
        MountedBody(body, no_vertical)
    with pytest.raises(ParameterError, match="mounts has 2 entries"):
        MountedBody(body, tuple(Mount(p, MOUNT_STIFFNESS) for p in TRIANGLE_M[:2]))
    with pytest.raises(ParameterError, match="damping_ratio = 1.5"):
        MountedBody(body, tuple(Mount(p, MOUNT_STIFFNESS) for p in TRIANGLE_M), damping_ratio=1.5)


def test_bad_body_and_mount_raise():
    with pytest.raises(ParameterError, match="mass_kg = -1"):
        RigidBody(-1, np.eye(3))
    with pytest.raises(ParameterError, match="expected a symmetric matrix"):
        RigidBody(1.0, [[1, 0.5, 0], [0, 1, 0], [0, 0, 1]])
    with pytest.raises(ParameterError, match="positive definite"):
        RigidBody(1.0, np.diag([1.0, -1.0, 1.0]))
    with pytest.raises(ParameterError, match="inertia_kg_m2 has shape"):
        RigidBody(1.0, np.eye(2))
    with pytest.raises(ParameterError, match="stiffness_n_per_m = .*expected values >= 0"):
        Mount((0, 0, 0), (-1.0, 1.0, 1.0))
    with pytest.raises(ParameterError, match="position_m has shape"):
        Mount((0, 0), 1e4)


def test_undamped_resonance_raises(body):
    system = MountedBody(body, tuple(Mount(p, MOUNT_STIFFNESS) for p in TRIANGLE_M))
    fn = natural_modes(system).natural_frequency_hz[0]
    with pytest.raises(ParameterError, match="coincides with an undamped natural frequency"):
        harmonic_response(system, 2 * np.pi * fn, [1], [[1.0, 0, 0]])
    with pytest.raises(ParameterError, match="speed_rad_s = 0"):
        harmonic_response(system, 0, [1], [[1.0, 0, 0]])
    with pytest.raises(ParameterError, match="force_n has shape"):
        harmonic_response(system, 100.0, [1, 2], [[1.0, 0, 0]])
    with pytest.raises(ParameterError, match=r"orders = \[1\.5\]: expected"):
        harmonic_response(system, 100.0, [1.5], [[1.0, 0, 0]])
