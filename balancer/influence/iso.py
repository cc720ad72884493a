"""ISO 21940-11 (formerly ISO 1940-1) balance tolerances for rotors with rigid behaviour.

* Permissible residual unbalance ``U_per = G m / Omega`` (kg m), with the balance
  quality grade ``G`` = ``e_per Omega`` in mm/s (given in mm/s, used in m/s), the
  rotor mass ``m`` (kg) and the maximum service speed ``Omega`` (rad/s, from rpm).
* Allocation to two tolerance planes (the bearing planes A and B, mass centre
  between them): the lever rule ``U_per,A = U_per L_B / L``, ``U_per,B = U_per L_A / L``
  with ``L_A``, ``L_B`` the distances from the mass centre to A and B and
  ``L = L_A + L_B``; for a mass centre close to one bearing the standard limits the
  shares to 30 %-70 % of ``U_per`` (each share at least 0.3 and at most 0.7 ``U_per``).
  Rotors with the mass centre outside the bearings (overhung) need the standard's
  other cases and are refused here.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from modal.errors import ParameterError
from modal.units import rpm_to_rad_s

from .._checks import non_negative, positive

__all__ = ["BALANCE_GRADES_MM_S", "IsoCheck", "permissible_unbalance_kg_m", "allocate_to_planes", "iso_check"]

BALANCE_GRADES_MM_S = (0.4, 1.0, 2.5, 6.3, 16.0, 40.0, 100.0, 250.0, 630.0, 1600.0, 4000.0)
"""The standard's balance quality grades G (mm/s)."""


def permissible_unbalance_kg_m(grade_mm_s: float, rotor_mass_kg: float, speed_rpm: float) -> float:
    """Permissible residual unbalance ``U_per = G m / Omega`` (kg m), ISO 21940-11.

    Parameters
    ----------
    grade_mm_s : float
        Balance quality grade G (mm/s), e.g. 2.5 for G 2.5.
    rotor_mass_kg : float
        Rotor mass (kg).
    speed_rpm : float
        Maximum service speed (rpm).

    Returns
    -------
    float
        ``U_per`` in kg m (multiply by 1e6 for g mm).
    """
    g = positive("grade_mm_s", grade_mm_s, "mm/s") * 1e-3
    m = positive("rotor_mass_kg", rotor_mass_kg, "kg")
    omega = float(rpm_to_rad_s(positive("speed_rpm", speed_rpm, "rpm")))
    return g * m / omega


def allocate_to_planes(u_per_kg_m: float, distance_a_m: float, distance_b_m: float) -> tuple[float, float]:
    """Share ``U_per`` between bearing planes A and B (lever rule, limited to 30 %-70 %).

    Parameters
    ----------
    u_per_kg_m : float
        Total permissible residual unbalance (kg m).
    distance_a_m, distance_b_m : float
        Distances from the rotor's mass centre to planes A and B (m), mass centre
        between them.

    Returns
    -------
    (float, float)
        ``(U_per,A, U_per,B)`` in kg m.
    """
    u = positive("u_per_kg_m", u_per_kg_m, "kg m")
    la = non_negative("distance_a_m", distance_a_m, "m")
    lb = non_negative("distance_b_m", distance_b_m, "m")
    if la + lb <= 0:
        raise ParameterError("distance_a_m + distance_b_m must be > 0 (the bearing span)")
    share_a = min(max(lb / (la + lb), 0.3), 0.7)
    return u * share_a, u * (1.0 - share_a)


@dataclass(frozen=True, slots=True)
class IsoCheck:
    """Residual unbalance per plane against an ISO 21940-11 grade.

    Attributes
    ----------
    grade_mm_s : float
        Grade G (mm/s).
    permissible_unbalance_kg_m : float
        ``U_per`` for the whole rotor (kg m).
    permissible_per_plane_kg_m : ndarray, shape (n_planes,)
        Allocation to each tolerance plane (kg m).
    residual_unbalance_kg_m : ndarray, shape (n_planes,)
        Magnitude of the residual unbalance in each plane (kg m).
    ratio : ndarray, shape (n_planes,)
        ``residual / permissible`` (1: at the limit).
    passes : ndarray of bool, shape (n_planes,)
        Plane meets the grade.
    verdict : str
        ``"pass"`` when every plane passes, else ``"fail"``.
    """

    grade_mm_s: float
    permissible_unbalance_kg_m: float
    permissible_per_plane_kg_m: np.ndarray
    residual_unbalance_kg_m: np.ndarray
    ratio: np.ndarray
    passes: np.ndarray
    verdict: str

    def archive_units(self) -> dict[str, str]:
        """Units the field names cannot say (for the archive)."""
        return {"grade_mm_s": "mm/s", "ratio": "1", "passes": "1"}


def iso_check(residual_unbalance_kg_m, grade_mm_s: float, rotor_mass_kg: float, speed_rpm: float,
              distances_m: tuple[float, float] | None = None) -> IsoCheck:
    """Check residual unbalances against a grade (one plane: all of ``U_per``; two: allocated).

    Parameters
    ----------
    residual_unbalance_kg_m : array_like, shape (1,) or (2,)
        Residual unbalance in each tolerance plane (kg m; complex or magnitudes).
    grade_mm_s, rotor_mass_kg, speed_rpm : float
        See :func:`permissible_unbalance_kg_m`.
    distances_m : (float, float), optional
        Distances from the mass centre to planes A and B (m); default: mass centre
        midway (equal shares).

    Returns
    -------
    IsoCheck
    """
    residual = np.abs(np.atleast_1d(np.asarray(residual_unbalance_kg_m, dtype=complex)))
    if residual.ndim != 1 or residual.size not in (1, 2) or not np.all(np.isfinite(residual)):
        raise ParameterError(f"residual_unbalance_kg_m: {residual.size} value(s); expected 1 or 2 finite values "
                             "(one per tolerance plane)")
    u_per = permissible_unbalance_kg_m(grade_mm_s, rotor_mass_kg, speed_rpm)
    if residual.size == 1:
        per_plane = np.array([u_per])
    else:
        la, lb = distances_m if distances_m is not None else (1.0, 1.0)
        per_plane = np.array(allocate_to_planes(u_per, la, lb))
    ratio = residual / per_plane
    passes = ratio <= 1.0
    return IsoCheck(grade_mm_s=float(grade_mm_s), permissible_unbalance_kg_m=u_per, permissible_per_plane_kg_m=per_plane,
                    residual_unbalance_kg_m=residual, ratio=ratio, passes=passes,
                    verdict="pass" if bool(np.all(passes)) else "fail")
