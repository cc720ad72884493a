"""Ball-balancer parameter studies on Dask (balancer.adb.montecarlo): the probability of stable operation
per speed from the identified standard errors of k, c, M (Monte-Carlo), and stability maps cut into chunks;
the same numbers here and on a real Dask cluster (the session fixture ``dask_cluster``)."""
from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.stats import norm

from balancer.adb import ADBParameters, ParameterStd, balanced_stability, stability_map, threshold_sensitivity
from balancer.adb.montecarlo import chunked_stability_map, sample_parameters, stability_probability
from modal.errors import ParameterError

S1 = ADBParameters(M=1.0, m=0.02, n=2, R=0.05, e=0.5e-3, k=1e4, c=20.0, D=1e-3)
WN = S1.natural_frequency_rad_s
STD = ParameterStd(k=200.0, c=1.0, M=0.02)


def test_probability_follows_the_linearised_threshold():
    """With small errors the lowest stable speed is normal with the linearly propagated standard error
    (threshold_sensitivity assumes independent errors, as the draws do), so P(stable at threshold + z sigma)
    = Phi(z). The draws' binomial error is <= 0.011 (2000 draws); the linearisation's error is second order in
    the 2 % relative spread of the threshold (~1e-3 in probability): 4 binomial standard errors bound both."""
    sens = threshold_sensitivity(S1, STD, 10 * WN)
    z = np.array([-1.5, -0.5, 0.0, 0.5, 1.5])
    result = stability_probability(S1, STD, sens.threshold_rad_s + z * sens.std_rad_s, 2000, seed=1)
    assert result.n_samples == 2000 and np.array_equal(result.stable_count, np.round(result.probability_stable * 2000))
    np.testing.assert_array_less(np.abs(result.probability_stable - norm.cdf(z)),
                                 4 * np.sqrt(norm.cdf(z) * norm.sf(z) / 2000))
    np.testing.assert_allclose(result.std_probability,
                               np.sqrt(result.probability_stable * (1 - result.probability_stable) / 2000))


def test_no_error_gives_the_nominal_verdict_and_the_seed_fixes_the_draws():
    speeds = np.linspace(0.5, 6.0, 23) * WN
    result = stability_probability(S1, ParameterStd(), speeds, 40, chunk_size=7)
    nominal = balanced_stability(S1, speeds).stability_class == 1
    assert nominal.any() and not nominal.all()
    np.testing.assert_array_equal(result.probability_stable, nominal.astype(float))
    np.testing.assert_array_equal(sample_parameters(S1, STD, 50, seed=3), sample_parameters(S1, STD, 50, seed=3))
    assert (sample_parameters(S1, ParameterStd(k=9e3, c=30.0, M=0.9), 500, seed=0) > [0, -1e-300, 0]).all()


def test_draws_without_a_balanced_state_count_as_not_stable():
    """e = 1.8 mm: the balls can balance M e only while M <= n m R / e = 1.111 kg; with sigma_M = 0.1 kg a
    fraction 1 - Phi(1.11) of the draws has no balanced state. At 3 omega_n every balanceable draw is stable
    (checked on the extremes of M), so 1 - P(stable) is that fraction, within 4 binomial standard errors."""
    params = S1.replace(e=1.8e-3)
    std = ParameterStd(M=0.1)
    speed = 3 * WN
    for M in (0.6, 1.11):
        assert balanced_stability(params.replace(M=M), [speed]).stability_class[0] == 1
    result = stability_probability(params, std, [speed], 2000, seed=2)
    expected = norm.sf((params.n * params.m * params.R / params.e - params.M) / std.M)
    assert abs((1 - result.probability_stable[0]) - expected) < 4 * math.sqrt(expected * (1 - expected) / 2000)


def test_cluster_gives_the_same_numbers(dask_cluster):
    """Same chunks, same pure function of the same draws: identical counts and identical maps (each matrix's
    eigenvalues are computed alone, whatever else is in its batch or process)."""
    address = dask_cluster[0]
    speeds = np.linspace(0.8, 4.0, 17) * WN
    here = stability_probability(S1, STD, speeds, 600, seed=5, chunk_size=100)
    there = stability_probability(S1, STD, speeds, 600, seed=5, chunk_size=100, client=address)
    np.testing.assert_array_equal(here.stable_count, there.stable_count)
    values = np.linspace(1.0, 40.0, 30)
    whole = stability_map(S1, speeds, "c", values)
    chunked = chunked_stability_map(S1, speeds, "c", values, chunk_size=8, client=address)
    for name in ("values", "speed_ratio", "max_real_part_per_s", "rounding_bound_per_s", "growth_rate_nondimensional",
                 "stability_class"):
        np.testing.assert_array_equal(getattr(chunked, name), getattr(whole, name), err_msg=name)


def test_bad_arguments_are_parameter_errors():
    with pytest.raises(ParameterError, match="n_samples"):
        stability_probability(S1, STD, [WN], 0)
    with pytest.raises(ParameterError, match="chunk_size"):
        stability_probability(S1, STD, [WN], 10, chunk_size=0)
    with pytest.raises(ParameterError, match="speeds"):
        stability_probability(S1, STD, [-1.0], 10)
