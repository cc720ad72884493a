"""Drive study: V-belt stages from motor to rotor, the rotor's shaft, and the report.

* :mod:`balancer.drive.belt`: V-belt stages and drives; every public name is
  re-exported here, so ``from balancer.drive import belt_stage`` works as before
  the drive became a package;
* :mod:`balancer.drive.shaft`: two-bearing shaft statics, sizing, stiffness and the
  hand-over to a ball-balancer study;
* :mod:`balancer.drive.report`: plain-text report and plots (matplotlib; imported
  on demand).
"""
from __future__ import annotations

from .belt import *  # noqa: F401,F403 (belt's __all__)
from . import belt

__all__ = list(belt.__all__)
