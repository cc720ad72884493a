"""Linear stability of a state (balancer.adb.linear): marginal classes and the rounding bound of
nearly defective eigenvalues."""
from __future__ import annotations

import numpy as np

from balancer.adb import ADBParameters, balanced_stability

from balancer.adb.linear import MARGINAL, STABLE


S1 = ADBParameters(M=1.0, m=0.02, n=2, R=0.05, e=0.5e-3, k=1e4, c=20.0, D=1e-3)
WN = S1.natural_frequency_rad_s


def test_undamped_system_is_marginal():
    # c = D = 0: gyroscopic, conservative linearisation; a stable balanced state has all
    # eigenvalues on the imaginary axis, so it must be classified marginal, not stable.
    p = S1.replace(c=0.0, D=0.0)
    result = balanced_stability(p, [2 * WN, 5 * WN])
    assert list(result.stability_class) == [MARGINAL, MARGINAL]
    assert np.all(np.abs(result.max_real_part_per_s) <= result.rounding_bound_per_s)


def test_rounding_bound_of_a_nearly_defective_eigenvalue_is_its_real_sensitivity():
    # a 2x2 Jordan block at -1e-3: the eigenvalue condition number is infinite (the first-order
    # bound kappa eps ||J|| says nothing), yet rounding-size perturbations move the eigenvalues
    # by about sqrt(eps) ~ 1.5e-8, far below 1e-3: the verdict is stable. At 0 it stays marginal
    from balancer.adb.linear import eigen_analysis_nondimensional

    jordan = np.array([[[-1e-3, 1.0], [0.0, -1e-3]], [[0.0, 1.0], [0.0, 0.0]]])
    analysis = eigen_analysis_nondimensional(jordan, 1.0)
    assert list(analysis.stability_class) == [STABLE, MARGINAL]
    assert analysis.rounding_bound_per_s[0] < 1e-6  # ten times a sqrt(eps)-size change
