"""Result dataclasses and k, c, m (modal.results)."""
import warnings

import numpy as np
import pytest

from modal import identify
from modal.synthetic import add_noise, modal_frf
from support.modes import THREE_A, THREE_FN, THREE_ZETA


def test_rows_are_json_ready():
    import json

    result = identify(modal_frf(np.linspace(10, 400, 2001), THREE_FN, THREE_ZETA, THREE_A))
    rows = result.rows()
    assert len(rows) == 3
    text = json.dumps([{k: (str(v) if isinstance(v, complex) else v) for k, v in row.items()} for row in rows])
    # the keys of each mode at the top level of its object (the nested "std" repeats the
    # quantity names, so a search of the text would pass with them missing from the mode)
    quantities = ("natural_frequency_hz", "damping_ratio", "stiffness_n_per_m", "damping_n_s_per_m", "mass_kg")
    for row, truth in zip(json.loads(text), THREE_FN):
        assert set(quantities + ("std", "flags", "channel", "method")) <= set(row)
        assert set(quantities) <= set(row["std"])
        assert row["natural_frequency_hz"] == pytest.approx(truth, rel=1e-9)
        assert all(isinstance(row[q], float) and isinstance(row["std"][q], float) for q in quantities)


@pytest.mark.parametrize("method", ["nls", "halfpower", "circle", "global"])
def test_scalar_results_are_plain_floats_whatever_the_method(method):
    # a mode's scalars are Python floats for every method (the half-power and circle poles came out as numpy
    # scalars): the archive then records them as one type, and scripts that test isinstance(x, float) or
    # serialise them see the same thing from each method
    frf = add_noise(modal_frf(np.linspace(50.0, 150.0, 201), [100.0], [0.02], [1.0]), 0.005, seed=3)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        mode = identify(frf, method).modes[0]
    scalars = {"natural_frequency_hz": mode.natural_frequency_hz, "damping_ratio": mode.damping_ratio,
               "lines_per_bandwidth": mode.lines_per_bandwidth, "chi2": mode.chi2, "quality": mode.quality,
               "window_damping_ratio": mode.window_damping_ratio, "band low": mode.band_hz[0],
               "band high": mode.band_hz[1], "std fn": mode.std.natural_frequency_hz,
               "std zeta": mode.std.damping_ratio, "stiffness": mode.stiffness_n_per_m}
    assert {name: type(value).__name__ for name, value in scalars.items()} == {name: "float" for name in scalars}


def test_physical_covariance_is_the_first_order_propagation():
    from modal.results import physical_covariance, physical_parameters

    # central differences of (k, c, m)(ωn, ζ, Re A, Im A) with steps of 1e-6 relative: their error, ~1e-12
    # relative, is far below the 1e-8 asked
    theta = np.array([2 * np.pi * 50.0, 0.02, 0.4, 0.05])

    def kcm(t):
        (k, c, m), _ = physical_parameters(t[0], t[1], t[2] + 1j * t[3])
        return np.array([k, c, m], float)

    steps = 1e-6 * np.abs(theta)
    jac = np.column_stack([(kcm(theta + e) - kcm(theta - e)) / (2 * h) for e, h in zip(np.diag(steps), steps)])
    rng = np.random.default_rng(0)
    root = rng.standard_normal((4, 4)) * (1e-3 * theta)[:, None]
    cov = root @ root.T
    got = physical_covariance(theta[0], theta[1], theta[2] + 1j * theta[3], cov)
    np.testing.assert_allclose(got, jac @ cov @ jac.T, rtol=1e-8)
    (_, _, _), stds = physical_parameters(theta[0], theta[1], theta[2] + 1j * theta[3], cov)
    np.testing.assert_allclose(np.array(stds, float), np.sqrt(np.diag(got)), rtol=1e-15)


def test_a_mass_line_without_a_finite_0_hz_value_is_refused_there_and_kept_elsewhere():
    from dataclasses import replace

    from modal.errors import ParameterError

    frf = modal_frf(np.linspace(0.0, 200.0, 401), [100.0], [0.02], [1.0], kind="mobility")
    result = replace(identify(frf.cropped(50.0, 150.0), "nls"), residuals=np.array([[1e-6, 2.0]]))
    with pytest.raises(ParameterError, match="mobility model's lower residual .* no finite value at 0 Hz"):
        result.synthesize(frf.frequency_hz)
    above = result.synthesize(frf.frequency_hz[1:])
    # the mass line of a mobility: -L (i omega) / omega**2 = -i L / omega
    omega = frf.frequency_hz[1:] * 2 * np.pi
    no_residual = replace(result, residuals=None).synthesize(frf.frequency_hz[1:])
    assert np.allclose(above.response - no_residual.response, 1e-6 * 1j * omega - 2.0j / omega, rtol=1e-12, atol=0)


def test_a_contradicted_driving_point_flags_its_own_rows_only():
    # two channels declared driving points; the second's constants change sign between the modes (a transfer
    # channel): its rows carry driving_point_contradicted and non_positive_constant and no k, c, m; the first,
    # a true driving point, gives k, c, m and its rows said the other channel's flags as their own
    from modal.flags import contradictions

    frf = modal_frf(np.linspace(50.0, 350.0, 3001), [100.0, 300.0], [0.02, 0.02], [[1.0, 0.6], [0.5, -0.8]])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        rows = identify(frf, "nls", driving_point=[0, 1]).rows()
    for row in rows:
        assert contradictions(row) == [], row
        if row["channel"] == 0:
            assert np.isfinite(row["stiffness_n_per_m"]) and row["flags"] == [], row
        else:
            assert np.isnan(row["stiffness_n_per_m"]) and "driving_point_contradicted" in row["flags"], row
    assert [("non_positive_constant" in row["flags"]) for row in rows if row["channel"] == 1] == [False, True]
