"""The field-balancing study on a simulated rotor (balancer.influence.study), as the bundled scene runs it."""
from __future__ import annotations

import numpy as np

from support.balancing import STUDY_SCENE


def test_bundled_study_scene(tmp_path):
    """Identified k, c, M predict alpha within the identification error; both methods cut the vibration
    by an order of magnitude at 5 % reading noise; the ideal ball balancer does better still."""
    import balancer

    run = balancer.run_scene(STUDY_SCENE, out=tmp_path / "s.h5", plots_dir=tmp_path / "p")
    study = run.results["balance"].study
    assert np.all(study.alpha_model_error < 0.02)  # k, c, M identified to < 1 % (their standard errors)
    for left in (study.amplitude_least_squares_m, study.amplitude_minmax_m, study.amplitude_model_only_m):
        assert np.all(left < 0.2 * study.amplitude_before_m)
    assert study.minmax.worst_residual <= study.least_squares.worst_residual
    assert study.adb_speed_rad_s == 250.0 and study.adb_residual_amplitude_m < study.amplitude_minmax_m[-1]
    assert {p.name for p in (tmp_path / "p").iterdir()} == {"balance_polar.png", "balance_comparison.png"}
