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

The package has four parts: :mod:`~balancer.drive.shaft.statics` (inputs, reactions,
moments), :mod:`~balancer.drive.shaft.sizing` (diameter from strength),
:mod:`~balancer.drive.shaft.stiffness` (stiffness, critical speed, margin) and
:mod:`~balancer.drive.shaft.handover` (speed and stiffness for a ball-balancer study).
Everything public is importable from ``balancer.drive.shaft``.
"""
from __future__ import annotations

from .statics import *  # noqa: F401,F403 (each module's __all__)
from .sizing import *  # noqa: F401,F403 (each module's __all__)
from .stiffness import *  # noqa: F401,F403 (each module's __all__)
from .handover import *  # noqa: F401,F403 (each module's __all__)
from . import handover, sizing, statics, stiffness

#: every public name, from the modules' own lists (one place to add a name)
__all__ = [*statics.__all__, *sizing.__all__, *stiffness.__all__, *handover.__all__]
