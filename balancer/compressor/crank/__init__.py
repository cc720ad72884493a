"""Slider-crank shaking forces and the crank counterweight that minimises them.

Model (seed 000, eqs. 1 and 9-11; seed 004, eqs. 3-5)
-----------------------------------------------------
A crank of radius ``r`` turns at a constant angular speed ``omega``; the crank
angle ``theta`` is measured from top dead centre, the piston moves along ``y``
and ``x`` is perpendicular to the stroke in the plane of the crank.  The rod is
split into two lumped masses (:func:`two_mass_split`), so the mechanism is a
rotating mass ``m_rot`` at the crank pin and a reciprocating mass ``m_rec`` at
the wrist pin.  A counterweight of mass ``m_c`` at radius ``r_c`` sits opposite
the crank pin.  The shaking force on the frame is::

    F_x = (m_c r_c - m_rot r) omega**2 sin(theta)
    F_y = (m_rot r - m_c r_c) omega**2 cos(theta) + m_rec r omega**2 A(theta)

with the piston's acceleration factor ``A`` (``-r omega**2 A`` is the piston
acceleration).  Exactly, with ``lam = r / l`` and ``D = sqrt(1 - lam**2 sin**2)``::

    A = cos(theta) + lam cos(2 theta) / D + lam**3 sin(2 theta)**2 / (4 D**3)

or as a harmonic series ``A = sum_h a_h cos(h theta)``.  The papers keep
``h = 1, 2`` with the leading coefficients ``a_1 = 1, a_2 = lam``
(``a_4 = -lam**3/4``, ``a_6 = 9 lam**5/128``).  The rod-inertia couple of the
two-mass model is ``M_z = -J_AB lam omega**2 B(theta)`` with
``B = (1 - lam**2) sin(theta) / D**3`` exactly, or the series
``sin(theta) - (3 lam**2/8) sin(3 theta) + (15 lam**4/128) sin(5 theta)``.

The force depends on the counterweight only through ``u = m_c r_c``.  The
*balance fraction* ``alpha`` is defined by ``u = (m_rot + alpha m_rec) r``.  The
resultant scaled by ``m_rec r omega**2`` depends only on ``alpha`` and
``lam``, so the optimal ``alpha`` does not depend on speed.  The peak resultant
force over a revolution is convex in ``alpha`` (a maximum of norms of affine
maps), so :func:`optimal_counterweight` solves it exactly.

Everything is SI inside (m, kg, N, rad, rad/s); rpm appears only in argument
names ``speed_rpm``.  ``|F|`` is even in ``theta`` for every model here, so
maxima over a revolution are searched on ``[0, pi]``.

The package has three parts: :mod:`~balancer.compressor.crank.model` (the mechanism and its
kinematics), :mod:`~balancer.compressor.crank.forces` (shaking force, harmonics, exact
maxima) and :mod:`~balancer.compressor.crank.counterweight` (evaluation, optimum, grid).
Everything public is importable from ``balancer.compressor.crank``.
"""
from __future__ import annotations

from .model import *  # noqa: F401,F403 (each module's __all__)
from .forces import *  # noqa: F401,F403 (each module's __all__)
from .counterweight import *  # noqa: F401,F403 (each module's __all__)
from .model import Objective  # noqa: F401 (the objective names, for type hints)
from . import counterweight, forces, model

#: every public name, from the modules' own lists (one place to add a name)
__all__ = [*model.__all__, *forces.__all__, *counterweight.__all__]
