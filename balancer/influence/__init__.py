"""Field balancing with influence coefficients.

Measure the 1x vibration, add a trial mass in each plane in turn, measure again,
compute the correction; predict what it leaves and check it against ISO 21940-11.

* :mod:`~balancer.influence.readings`: readings in users' units (µm, mils, mm/s, in/s,
  g) and the phase convention (phase lag positive against the keyphasor; mass angles
  against rotation);
* :mod:`~balancer.influence.coefficients`: :func:`influence_matrix`, :func:`correction`
  (least squares or min-max, weights, a bound per plane);
* :mod:`~balancer.influence.checkrun`: :func:`check_run` (the check run after the correction
  against the prediction, a mounting mistake named, the trim);
* :mod:`~balancer.influence.split`: :func:`split_correction` onto holes or blades;
* :mod:`~balancer.influence.iso`: :func:`permissible_unbalance_kg_m`, :func:`iso_check`;
* :mod:`~balancer.influence.jeffcott`: :func:`jeffcott_influence` (model alpha from
  identified k, c, M) and :func:`trial_mass_kg`.

SI inside: readings in m, m/s or m/s^2, unbalances in kg m (complex: angle in the phase).
"""
from __future__ import annotations

from .checkrun import CheckRun, check_run
from .coefficients import CONDITION_WARNING, CorrectionResult, correction, influence_matrix, predict_residual
from .iso import BALANCE_GRADES_MM_S, IsoCheck, allocate_to_planes, iso_check, permissible_unbalance_kg_m
from .jeffcott import jeffcott_influence, trial_mass_kg
from .readings import READING_UNITS, amplitude_phase, mass_angle, reading_unit, unbalance_kg_m, vibration
from .split import equally_spaced_deg, split_correction

__all__ = [
    "influence_matrix",
    "correction",
    "predict_residual",
    "check_run",
    "CheckRun",
    "CorrectionResult",
    "CONDITION_WARNING",
    "split_correction",
    "equally_spaced_deg",
    "permissible_unbalance_kg_m",
    "allocate_to_planes",
    "iso_check",
    "IsoCheck",
    "BALANCE_GRADES_MM_S",
    "jeffcott_influence",
    "trial_mass_kg",
    "READING_UNITS",
    "reading_unit",
    "vibration",
    "amplitude_phase",
    "unbalance_kg_m",
    "mass_angle",
]
