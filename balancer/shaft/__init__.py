"""Two-bearing shaft: reactions, bending moments and torque from point loads in
two planes; diameter by the report's Soderberg-type formula and by the ASME
code form; bending stiffness at the rotor, first critical speed (Dunkerley) and
the hand-over of speed and stiffness to a ball-balancer study.

Conventions
-----------
* The shaft runs along x from 0 to ``length_m``; bearing A at ``bearing_a_m``,
  bearing B at ``bearing_b_m`` (simple supports).  Loads outside the bearings are
  overhung.
* Forces are components along two perpendicular transverse axes called
  "vertical" and "horizontal"; a load given by magnitude and angle has
  ``vertical = F cos(angle)``, ``horizontal = F sin(angle)``, as in the report's
  free-body diagrams.  Reactions are the signed forces the bearings apply, in
  the same axes.
* Bending moment at x: ``M(x) = sum over forces left of x of F_j (x - x_j)``;
  shear ``V(x) = sum of F_j left of x`` (value just right of x at a station).
* SI inside: m, N, N m, Pa, kg, rad/s.  rpm and degrees only in names that say so.

The package has four parts: :mod:`~balancer.shaft.statics` (inputs, reactions,
moments), :mod:`~balancer.shaft.sizing` (diameter from strength),
:mod:`~balancer.shaft.stiffness` (stiffness, critical speed, margin) and
:mod:`~balancer.shaft.handover` (speed and stiffness for a ball-balancer study).
Everything public is importable from ``balancer.shaft``.
"""
from __future__ import annotations

from .statics import (
    PointLoad,
    STANDARD_SHAFT_DIAMETERS_M,
    STEEL_DENSITY_KG_M3,
    STEEL_YOUNGS_MODULUS_PA,
    ShaftAnalysis,
    ShaftDiagram,
    ShaftGeometry,
    analyse_shaft,
    bending_moment_at,
    shaft_diagram,
    shaft_torque_n_m,
)
from .sizing import (
    ShaftSizing,
    allowable_shear_stress_pa,
    asme_allowable_shear_stress_pa,
    endurance_limit_pa,
    shaft_diameter_asme,
    shaft_diameter_soderberg,
)
from .stiffness import (
    CriticalSpeed,
    SpeedMargin,
    bending_stiffness_n_per_m,
    critical_speed,
    rotor_layout,
    second_moment_of_area_m4,
    span_critical_speed_rad_s,
    speed_margin,
)
from .handover import (
    RotorHandover,
    rotor_handover,
)

__all__ = [
    "STANDARD_SHAFT_DIAMETERS_M",
    "STEEL_YOUNGS_MODULUS_PA",
    "STEEL_DENSITY_KG_M3",
    "PointLoad",
    "ShaftGeometry",
    "ShaftAnalysis",
    "ShaftDiagram",
    "ShaftSizing",
    "CriticalSpeed",
    "SpeedMargin",
    "RotorHandover",
    "analyse_shaft",
    "bending_moment_at",
    "shaft_diagram",
    "shaft_torque_n_m",
    "endurance_limit_pa",
    "allowable_shear_stress_pa",
    "asme_allowable_shear_stress_pa",
    "shaft_diameter_soderberg",
    "shaft_diameter_asme",
    "second_moment_of_area_m4",
    "rotor_layout",
    "bending_stiffness_n_per_m",
    "span_critical_speed_rad_s",
    "critical_speed",
    "speed_margin",
    "rotor_handover",
]
