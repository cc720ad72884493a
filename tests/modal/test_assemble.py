"""One assembly of results for every method (modal.assemble): the shared flags, k, c, m and the warnings."""
import warnings

import numpy as np
import pytest

from modal.assemble import ModeEstimate, assemble_modes, driving_points
from modal.errors import IdentificationError, QualityWarning, ResolutionWarning
from modal.flags import FLAG_ACTION, FLAG_TEXT, REL_STD_LIMIT
from modal.frf import FRF
from modal.units import TWO_PI
from modal.window_damping import remove_window_damping


def estimate(fn=100.0, zeta=0.01, const=(0.5,), std_zeta=1e-5, flags=(), details=None):
    """A mode as a method would hand it over: pole, constants, a diagonal covariance."""
    const = np.asarray(const, complex)
    cov = np.zeros((const.size, 4, 4))
    cov[:, 0, 0], cov[:, 1, 1] = 1e-4, std_zeta**2
    cov[:, 2, 2] = cov[:, 3, 3] = 1e-8
    return ModeEstimate(TWO_PI * fn, zeta, const, cov, 1e-2, std_zeta, (fn - 5, fn + 5), 101, 10.0, set(flags),
                        details or {})


def assemble(estimates, single=True, driving=(True,), **options):
    return assemble_modes(estimates, method="test", source="x.uff", single=single,
                          driving=np.asarray(driving, bool), **options)


def test_a_driving_point_gets_k_c_m_as_plain_numbers():
    (mode,) = assemble([estimate(const=(0.5,))])
    wn = TWO_PI * 100.0
    # m = 1/|A|, k = m ωn², c = 2ζ m ωn: exact but for one rounding each
    assert mode.mass_kg == pytest.approx(2.0, rel=1e-15)
    assert mode.stiffness_n_per_m == pytest.approx(2.0 * wn**2, rel=1e-15)
    assert mode.damping_n_s_per_m == pytest.approx(2 * 0.01 * 2.0 * wn, rel=1e-15)
    assert type(mode.mass_kg) is float and mode.flags == () and mode.method == "test"


def test_transfer_channels_get_no_k_c_m_and_the_mode_says_why():
    (mode,) = assemble([estimate(const=(0.5, 0.25))], single=False, driving=(True, False))
    assert np.isfinite(mode.mass_kg[0]) and np.isnan(mode.mass_kg[1]) and np.isnan(mode.std.mass_kg[1])
    assert mode.flags == ("not_driving_point",)


def test_high_uncertainty_starts_at_the_limit():
    below, above = 0.99 * REL_STD_LIMIT * 0.01, 1.01 * REL_STD_LIMIT * 0.01
    (quiet,) = assemble([estimate(std_zeta=below)])
    with pytest.warns(QualityWarning, match="high_uncertainty"):
        (flagged,) = assemble([estimate(std_zeta=above)])
    assert "high_uncertainty" not in quiet.flags and "high_uncertainty" in flagged.flags


def test_close_modes_measures_the_overlap_with_every_other_mode():
    # the nearest mode (103 Hz) is narrow; a wide one further away (90 Hz, ζ = 0.09: 2ζωn/Δωn = 1.62) overlaps
    # the 100 Hz mode all the same
    modes = [estimate(90.0, 0.09), estimate(100.0, 1e-4, std_zeta=1e-6), estimate(103.0, 1e-4, std_zeta=1e-6)]
    with pytest.warns(QualityWarning, match="close_modes"):
        wide, middle, narrow = assemble(modes)
    assert "close_modes" in wide.flags and "close_modes" in middle.flags
    assert "close_modes" not in narrow.flags  # 2 max(ζωn)/Δωn = 2·1.03e-2/3 far below 1.5


def test_the_window_damping_is_taken_out_of_the_pole():
    tau = 0.2
    one = estimate(100.0, 0.02)
    (mode,) = assemble([one], window_decay_s=tau)
    wn, zeta, *_ = remove_window_damping(one.omega_n, one.damping_ratio, one.covariance, one.std_omega_n,
                                         one.std_damping_ratio, tau)
    assert mode.natural_frequency_hz == wn / TWO_PI and mode.damping_ratio == zeta
    assert mode.window_damping_ratio == pytest.approx(0.02 - zeta, rel=1e-12)
    # a window that makes all the damping: the pole stays as measured, and the mode says so
    with pytest.warns(QualityWarning, match="window_damping_dominates"):
        (kept,) = assemble([one], window_decay_s=0.9 / (0.02 * TWO_PI * 100.0))
    assert kept.damping_ratio == 0.02 and kept.window_damping_ratio == 0.0


def test_a_complex_driving_point_constant_is_flagged_unless_the_method_judges_complexity_itself():
    tilted = 0.5 * np.exp(1j * np.deg2rad(20))
    with pytest.warns(QualityWarning, match="complex_mode"):
        (mode,) = assemble([estimate(const=(tilted,))])
    assert "complex_mode" in mode.flags
    (shape_judged,) = assemble([estimate(const=(tilted,))], phase_check=False)
    assert "complex_mode" not in shape_judged.flags


def test_one_warning_per_flagged_mode_naming_every_flag_and_pointing_at_the_caller():
    details = {"missing_mode": " (near 12.3 Hz, zeta 0.01)"}
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        assemble([estimate(flags={"resolution_limited", "missing_mode"}, details=details),
                  estimate(300.0, flags={"method_bias"})])
        assemble([estimate(400.0)], driving=(False,), driving_known=False)  # informational flags only: no warning
    assert [w.category for w in caught] == [ResolutionWarning, QualityWarning]
    text = str(caught[0].message)
    assert text.startswith("x.uff: test mode near 100 Hz is flagged (")
    assert f"missing_mode: {FLAG_TEXT['missing_mode']}{details['missing_mode']}" in text
    assert f"resolution_limited: {FLAG_TEXT['resolution_limited']}" in text
    assert caught[0].filename == __file__  # the line that called into the toolkit, not the toolkit's own


def test_driving_points_from_the_point_ids_or_the_caller():
    f = np.linspace(1.0, 10.0, 5)
    # one channel without point ids: nothing says it is a driving point, and nothing assumes it
    driving, known = driving_points(FRF(f, np.ones(5)))
    assert driving.tolist() == [False] and not known
    driving, known = driving_points(FRF(f, np.ones(5)), True)  # declared
    assert driving.tolist() == [True] and known
    two = FRF(f, np.ones((2, 5)), response_points=["1", "2"], reference_points="1")
    driving, known = driving_points(two)
    assert driving.tolist() == [True, False] and known
    driving, known = driving_points(two, [False, True])
    assert driving.tolist() == [False, True] and known
    driving, known = driving_points(two, 1)  # a 0-based channel index
    assert driving.tolist() == [False, True] and known
    with pytest.raises(IdentificationError, match=r"no channel 2; expected channel indices 0\.\.1"):
        driving_points(two, [2])


def test_without_a_known_driving_point_no_channel_gets_k_c_m_and_the_mode_says_how_to_declare_one():
    (mode,) = assemble([estimate(const=(0.5,))], driving=(False,), driving_known=False)
    assert np.isnan(mode.mass_kg) and np.isnan(mode.stiffness_n_per_m) and np.isnan(mode.std.mass_kg)
    # the one flag that says why: not "not_driving_point", which would claim a transfer FRF
    assert mode.flags == ("driving_point_unknown",) and mode.ok
    assert "--driving-point" in FLAG_ACTION["driving_point_unknown"]
    assert "driving_point" in FLAG_ACTION["driving_point_unknown"].split("--driving-point")[1]


def test_an_output_only_method_hands_over_shapes_and_gets_the_shared_rules_without_k_c_m():
    # no input measured: shapes instead of scaled constants, no driving point; the pole's rules still apply
    shape = np.array([1.0, -0.5 + 0.01j, 0.25])
    modes = [ModeEstimate(TWO_PI * 20.0, 0.02, None, None, 0.01, 1.01 * REL_STD_LIMIT * 0.02,
                          (15.0, 25.0), 200, 20.0, mode_shape=shape),
             ModeEstimate(TWO_PI * 40.0, 0.01, None, None, 0.01, 1e-5, (35.0, 45.0), 200, 20.0, mode_shape=shape)]
    with pytest.warns(QualityWarning, match="high_uncertainty"):
        first, second = assemble_modes(modes, method="oma", source="run.h5", single=False, driving=None)
    assert first.flags == ("high_uncertainty",) and second.flags == ()
    assert np.all(np.isnan(first.mass_kg)) and np.all(np.isnan(first.modal_constant))
    assert first.driving_point.tolist() == [False] * 3 and first.kcm_correlation is None
    assert np.array_equal(first.mode_shape, shape) and first.natural_frequency_hz == pytest.approx(20.0, rel=1e-15)


def test_a_driving_point_whose_constants_change_sign_gives_no_k_c_m_for_any_mode():
    # a transfer channel declared a driving point (its modes' constants 0.5 and -0.8, errors 1e-4): the second mode
    # was flagged non_positive_constant, but the first got k, c, m from a channel that cannot be a driving point
    # (a driving point's constants are all positive, A = φ²); the other, true driving point keeps them
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", QualityWarning)
        modes = assemble([estimate(100.0, const=(1.0, 0.5)), estimate(300.0, const=(0.6, -0.8))], single=False,
                         driving=(True, True))
    for mode in modes:
        assert np.isfinite(mode.mass_kg[0]) and np.isnan(mode.mass_kg[1])
        assert np.isnan([mode.stiffness_n_per_m[1], mode.damping_n_s_per_m[1], mode.std.stiffness_n_per_m[1],
                         mode.std.mass_kg[1]]).all() and np.isnan(mode.kcm_correlation[1]).all()
        assert "driving_point_contradicted" in mode.flags
    assert "non_positive_constant" not in modes[0].flags and "non_positive_constant" in modes[1].flags
    with warnings.catch_warnings(record=True) as said:
        warnings.simplefilter("always")
        (one, _) = assemble([estimate(100.0, const=(0.5,)), estimate(300.0, const=(-0.8,))])
    assert np.isnan(one.mass_kg) and "driving_point_contradicted" in one.flags
    texts = [str(w.message) for w in said]
    assert any("mode near 100 Hz is flagged (driving_point_contradicted: the channel taken as a driving point" in t
               for t in texts), texts
    # a transfer FRF's constants change sign; a sign error turns them all: the warning says which it looks like
    assert not any("every mode's constant lies below zero" in t for t in texts)
    with warnings.catch_warnings(record=True) as said:
        warnings.simplefilter("always")
        assemble([estimate(100.0, const=(-0.5,)), estimate(300.0, const=(-0.8,))])
    texts = [str(w.message) for w in said]
    assert len(texts) == 2 and all("every mode's constant lies below zero: the force and the response point "
                                   "opposite ways" in t for t in texts), texts


def test_a_driving_points_constant_within_three_errors_of_zero_contradicts_nothing():
    # a mode near a node of the driving point: its constant -2.9e-4 with errors 1e-4 is zero within 3 of them
    # (noise), the other mode keeps k, c, m; at -3.1e-4 the sign is significant
    for const, contradicted in ((-2.9e-4, False), (-3.1e-4, True)):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", QualityWarning)
            first, second = assemble([estimate(100.0, const=(0.5,)), estimate(300.0, const=(const,))])
        assert np.isfinite(first.mass_kg) != contradicted
        assert ("driving_point_contradicted" in second.flags) == contradicted
        assert "non_positive_constant" in second.flags
