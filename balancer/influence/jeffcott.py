"""Model influence coefficients (Jeffcott rotor) and trial-mass sizing.

Jeffcott rotor: a disc of mass ``M`` on a massless shaft of stiffness ``k`` with
damping ``c``.  An unbalance ``U`` (kg m) turning at ``Omega`` drives the orbit
``X = U Omega^2 / (k - M Omega^2 + i c Omega)`` (complex amplitude, angles in the
direction of rotation).  In the lag convention of :mod:`balancer.influence.readings`
(phase lag positive, mass angles against rotation) that is the conjugate, so the
influence coefficient of a displacement sensor is

    alpha = Omega^2 / (k - M Omega^2 - i c Omega)            (m per kg m = 1/kg)

with ``|alpha| = Omega^2 / |k - M Omega^2 + i c Omega|`` and phase lag
``arg(k - M Omega^2 + i c Omega)`` (0 well below the critical speed, 90 deg at it,
towards 180 deg above).  A velocity sensor reads ``i Omega`` times the displacement in
the rotation convention, i.e. ``-i Omega`` times it in the lag convention (the
velocity leads by 90 deg); acceleration ``-Omega^2`` times.  ``k``, ``c`` and ``M`` are
what :func:`modal.identify` gives for a driving-point mode of the support
(``stiffness_n_per_m``, ``damping_n_s_per_m``, ``mass_kg``).
"""
from __future__ import annotations

import numpy as np

from modal.errors import ParameterError
from modal.units import STANDARD_GRAVITY_M_S2, rpm_to_rad_s

from .._checks import non_negative, positive

__all__ = ["jeffcott_influence", "trial_mass_kg", "STANDARD_GRAVITY_M_S2"]



def jeffcott_influence(k: float, c: float, M: float, omega, quantity: str = "displacement") -> np.ndarray:
    """Influence coefficient of a Jeffcott rotor at speed(s) ``omega`` (lag convention).

    Parameters
    ----------
    k : float
        Stiffness (N/m).
    c : float
        Viscous damping (N s/m).
    M : float
        Rotor (modal) mass (kg).
    omega : float or array_like
        Shaft speed (rad/s).
    quantity : {"displacement", "velocity", "acceleration"}
        What the sensor reads.

    Returns
    -------
    complex or ndarray of complex
        Reading per unit unbalance: m/(kg m), (m/s)/(kg m) or (m/s^2)/(kg m).
    """
    k = positive("k", k, "N/m")
    c = non_negative("c", c, "N s/m")
    M = positive("M", M, "kg")
    w = np.asarray(omega, dtype=float)
    if not np.all(np.isfinite(w)) or np.any(w < 0):
        raise ParameterError("omega: expected finite speeds >= 0 (rad/s)")
    if c == 0 and np.any(np.isclose(w * w * M, k, rtol=1e-15, atol=0)):
        raise ParameterError("omega: at the undamped critical speed sqrt(k/M) with c = 0 the response is infinite")
    alpha = w**2 / (k - M * w**2 - 1j * c * w)
    if quantity == "velocity":
        alpha = alpha * (-1j * w)
    elif quantity == "acceleration":
        alpha = alpha * (-(w**2))
    elif quantity != "displacement":
        raise ParameterError(f"quantity = {quantity!r}: expected 'displacement', 'velocity' or 'acceleration'")
    return alpha if alpha.ndim else complex(alpha)


def trial_mass_kg(rotor_mass_kg: float, speed_rpm: float, radius_m: float, n_planes: int = 1,
                  force_fraction: float = 0.1) -> float:
    """Trial mass whose centrifugal force is a fraction of the rotor weight it acts on.

    The field rule (e.g. V. Wowk, *Machinery Vibration: Balancing*, McGraw-Hill, 1995;
    the same figure is in the Schenck and IRD field-balancing guides): a trial mass
    whose centrifugal force is about 10 % of the static load on the bearings changes
    the vibration clearly (typically 20-30 % in amplitude or phase) yet stays far from
    damaging a machine that already runs: ``m_t r Omega^2 = f (m g / n_planes)``.

    Parameters
    ----------
    rotor_mass_kg : float
        Rotor mass (kg).
    speed_rpm : float
        Balancing speed (rpm).
    radius_m : float
        Radius at which the trial mass is fixed (m).
    n_planes : int
        Number of correction planes sharing the rotor weight.
    force_fraction : float
        Fraction ``f`` of the plane's share of the rotor weight (default 0.1).

    Returns
    -------
    float
        Trial mass (kg).
    """
    m = positive("rotor_mass_kg", rotor_mass_kg, "kg")
    omega = float(rpm_to_rad_s(positive("speed_rpm", speed_rpm, "rpm")))
    r = positive("radius_m", radius_m, "m")
    f = positive("force_fraction", force_fraction, "")
    if int(n_planes) != n_planes or n_planes < 1:
        raise ParameterError(f"n_planes = {n_planes!r}: expected an integer >= 1")
    return f * m * STANDARD_GRAVITY_M_S2 / int(n_planes) / (r * omega**2)
