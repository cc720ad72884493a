"""Automatic ball balancer (ADB) on a planar Jeffcott rotor (Chung & Ro model).

Entry points: :class:`ADBParameters`, :func:`stable_speed_intervals`, :func:`simulate`.
Plots live in :mod:`balancer.adb.plots` (imported on demand, so matplotlib is not loaded
by the numerical modules).
SI units and radians throughout; nondimensional groups use ``omega_n = sqrt(k / (M + n m))``.
"""
from __future__ import annotations

from .analysis import classify_final_state, settling_time
from .drag import AIR, LIGHT_OIL, WATER, BallDrag, Fluid, ball_drag, drag_coefficient, flow_regime, with_fluid_drag
from .equilibria import (
    Equilibrium,
    balanced_ball_angles,
    balanced_state,
    find_equilibria,
    symmetric_spacing_rad,
    unbalanced_states,
)
from .integrate import IntegrationResult, choose_method, integrate
from .linear import EigenAnalysis, eigen_analysis
from .parameters import ADBParameters, ParameterBatch, ParameterStd, identified_std
from .simulate import BatchSimulationResult, SimulationResult, default_initial_ball_angles, simulate, simulate_batch
from .speed import CallableSpeed, ConstantSpeed, LinearRunUp, SpeedProfile
from .stability import (
    BalancedStability,
    RouthHurwitzResult,
    SpeedIntervals,
    StabilityMap,
    ThresholdSensitivity,
    balanced_stability,
    characteristic_polynomial,
    linearised_matrices,
    routh_hurwitz,
    routh_hurwitz_n2,
    stability_map,
    stable_speed_intervals,
    threshold_sensitivity,
)
from .studies import SettlingStudy, settling_study

__all__ = [
    "ADBParameters",
    "ParameterBatch",
    "ParameterStd",
    "identified_std",
    "Equilibrium",
    "balanced_ball_angles",
    "balanced_state",
    "find_equilibria",
    "symmetric_spacing_rad",
    "unbalanced_states",
    "EigenAnalysis",
    "eigen_analysis",
    "BalancedStability",
    "RouthHurwitzResult",
    "SpeedIntervals",
    "StabilityMap",
    "ThresholdSensitivity",
    "balanced_stability",
    "characteristic_polynomial",
    "linearised_matrices",
    "routh_hurwitz",
    "routh_hurwitz_n2",
    "stability_map",
    "stable_speed_intervals",
    "threshold_sensitivity",
    "BatchSimulationResult",
    "IntegrationResult",
    "SimulationResult",
    "classify_final_state",
    "default_initial_ball_angles",
    "integrate",
    "choose_method",
    "settling_time",
    "simulate",
    "simulate_batch",
    "CallableSpeed",
    "ConstantSpeed",
    "LinearRunUp",
    "SpeedProfile",
    "AIR",
    "LIGHT_OIL",
    "WATER",
    "BallDrag",
    "Fluid",
    "ball_drag",
    "drag_coefficient",
    "flow_regime",
    "with_fluid_drag",
    "SettlingStudy",
    "settling_study",
]
