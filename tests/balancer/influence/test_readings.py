"""Readings as users give them (balancer.influence.readings): units, phases, trial masses, bad readings."""
from __future__ import annotations

import numpy as np
import pytest

from balancer.influence import correction, influence_matrix, unbalance_kg_m, vibration
from modal.errors import ParameterError
from support.balancing import polar, HS_INITIAL, HS_RUNS, HS_TRIALS


def test_readings_in_users_units():
    z = vibration([100.0, 2.0], [30.0, 390.0], "µm")
    np.testing.assert_allclose(z, polar([100e-6, 2e-6], [30.0, 30.0]), rtol=1e-14)
    np.testing.assert_allclose(vibration(1.0, 0.0, "g"), 9.80665)
    np.testing.assert_allclose(vibration(1.0, 0.0, "mil"), 25.4e-6)
    np.testing.assert_allclose(unbalance_kg_m(10.0, 0.1, 90.0, "g"), 1e-3j, atol=1e-18)


# ---------------------------------------------------------------- bad readings
def assert_one_line_error(call, field):
    """Assert that ``call`` raises a ParameterError whose message is one line naming ``field``."""
    with pytest.raises(ParameterError) as info:
        call()
    message = str(info.value)
    assert "\n" not in message and field in message, message
    return message


def test_bad_readings_give_one_line_errors_naming_the_field():
    alpha = influence_matrix(HS_INITIAL, HS_RUNS, HS_TRIALS)
    assert_one_line_error(lambda: influence_matrix(HS_INITIAL, HS_RUNS[:1], HS_TRIALS), "trial_runs")  # fewer runs than planes
    assert_one_line_error(lambda: influence_matrix(HS_INITIAL, np.array([HS_RUNS[0], HS_INITIAL]), HS_TRIALS), "trial_runs[1]")
    nan_initial = HS_INITIAL.copy()
    nan_initial[1] = np.nan
    assert_one_line_error(lambda: influence_matrix(nan_initial, HS_RUNS, HS_TRIALS), "initial[1]")
    assert_one_line_error(lambda: influence_matrix(HS_INITIAL, HS_RUNS[:, :1], HS_TRIALS), "trial_runs")  # mismatched shapes
    assert_one_line_error(lambda: correction(alpha, HS_INITIAL[:1]), "alpha")
    assert_one_line_error(lambda: influence_matrix(HS_INITIAL, HS_RUNS, [1.15, 0.0]), "trial_unbalances[1]")
    singular = np.column_stack([alpha[:, 0], 2 * alpha[:, 0]])
    assert_one_line_error(lambda: correction(singular, HS_INITIAL), "alpha")
    assert_one_line_error(lambda: correction(alpha, HS_INITIAL, method="l1"), "method")
    assert_one_line_error(lambda: vibration([1.0], [1.0], "furlongs"), "units")
