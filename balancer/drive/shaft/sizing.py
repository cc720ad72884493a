"""Shaft diameter from strength: endurance limit, allowable shear stress, and the report's
Soderberg-type formula and the ASME code form."""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Sequence

from modal.errors import ParameterError

from ..._checks import non_negative, positive
from ..belt import next_standard_size
from .statics import STANDARD_SHAFT_DIAMETERS_M

__all__ = [
    "ShaftSizing",
    "endurance_limit_pa",
    "allowable_shear_stress_pa",
    "asme_allowable_shear_stress_pa",
    "shaft_diameter_soderberg",
    "shaft_diameter_asme",
]


# --------------------------------------------------------------------------- strength
def endurance_limit_pa(ultimate_strength_pa: float, surface_factor: float = 1.0, size_factor: float = 1.0,
                       other_factor: float = 1.0, endurance_ratio: float = 0.5) -> float:
    """Corrected endurance limit ``S_e = ratio * S_u * k_a * k_b * k_c`` (Marin-type factors).

    Parameters
    ----------
    ultimate_strength_pa : float
        Tensile strength used for the endurance limit, Pa.
    surface_factor, size_factor, other_factor : float
        Marin factors k_a, k_b and any further product (dimensionless, in (0, 1]).
    endurance_ratio : float
        Rotating-beam endurance limit over tensile strength (0.5 for steels).

    Returns
    -------
    float
        Endurance limit, Pa.
    """
    value = positive("ultimate_strength_pa", ultimate_strength_pa, "Pa")
    for name, factor in (("surface_factor", surface_factor), ("size_factor", size_factor),
                         ("other_factor", other_factor), ("endurance_ratio", endurance_ratio)):
        f = positive(name, factor, "(dimensionless)")
        if f > 1.0:
            raise ParameterError(f"{name} = {f} must be in (0, 1]")
        value *= f
    return value


def allowable_shear_stress_pa(yield_strength_pa: float, safety_factor: float, shear_yield_ratio: float = 0.577) -> float:
    """Allowable shear stress ``tau = ratio * S_y / N`` (distortion energy: ratio = 1/sqrt(3),
    printed as 0.577 in design tables and in the report).

    Parameters
    ----------
    yield_strength_pa : float
        Tensile yield strength, Pa.
    safety_factor : float
        Factor of safety N (>= 1).
    shear_yield_ratio : float
        Shear yield over tensile yield (default 0.577).

    Returns
    -------
    float
        Allowable shear stress, Pa.
    """
    yield_strength = positive("yield_strength_pa", yield_strength_pa, "Pa")
    n = positive("safety_factor", safety_factor, "(dimensionless)")
    if n < 1.0:
        raise ParameterError(f"safety_factor = {n} must be >= 1")
    ratio = positive("shear_yield_ratio", shear_yield_ratio, "(dimensionless)")
    return ratio * yield_strength / n


def asme_allowable_shear_stress_pa(yield_strength_pa: float, ultimate_strength_pa: float, keyway: bool = True) -> float:
    """ASME shaft-code allowable shear: ``min(0.30 S_y, 0.18 S_u)``, times 0.75 with a keyway.

    Parameters
    ----------
    yield_strength_pa, ultimate_strength_pa : float
        Tensile yield and ultimate strengths, Pa.
    keyway : bool
        Whether the section has a keyway.

    Returns
    -------
    float
        Allowable shear stress, Pa.
    """
    sy = positive("yield_strength_pa", yield_strength_pa, "Pa")
    su = positive("ultimate_strength_pa", ultimate_strength_pa, "Pa")
    return min(0.30 * sy, 0.18 * su) * (0.75 if keyway else 1.0)


@dataclass(frozen=True, slots=True)
class ShaftSizing:
    """Shaft diameter from a combined bending-and-torsion formula.

    Attributes
    ----------
    method : str
        ``"soderberg"`` (the report's eq. 3.20) or ``"asme"`` (ASME code form).
    formula : str
        The formula, in words.
    moment_n_m, torque_n_m : float
        Design bending moment and torque, N m.
    bending_factor, torsion_factor : float
        Factors on M and T (K or K_m; K_t), dimensionless.
    stress_ratio : float
        ``S_y / S_e`` for the Soderberg form; 1 for ASME.
    allowable_shear_pa : float
        Allowable shear stress, Pa.
    equivalent_torque_n_m : float
        ``sqrt((ratio K M)**2 + (K_t T)**2)``, N m.
    diameter_m : float
        Required diameter, m.
    standard_diameter_m : float
        Next standard size, m.
    """

    method: str
    formula: str
    moment_n_m: float
    torque_n_m: float
    bending_factor: float
    torsion_factor: float
    stress_ratio: float
    allowable_shear_pa: float
    equivalent_torque_n_m: float
    diameter_m: float
    standard_diameter_m: float


def _sizing(method: str, formula: str, moment: float, torque: float, bending: float, torsion: float,
            ratio: float, tau: float, standard_diameters_m: Sequence[float]) -> ShaftSizing:
    equivalent = math.hypot(ratio * bending * moment, torsion * torque)
    if equivalent == 0.0:
        raise ParameterError("moment_n_m and torque_n_m are both 0; expected a loaded shaft")
    diameter = (16.0 * equivalent / (math.pi * tau)) ** (1.0 / 3.0)
    return ShaftSizing(
        method=method,
        formula=formula,
        moment_n_m=moment,
        torque_n_m=torque,
        bending_factor=bending,
        torsion_factor=torsion,
        stress_ratio=ratio,
        allowable_shear_pa=tau,
        equivalent_torque_n_m=equivalent,
        diameter_m=diameter,
        standard_diameter_m=next_standard_size(diameter, standard_diameters_m, "diameter_m"),
    )


def shaft_diameter_soderberg(moment_n_m: float, torque_n_m: float, yield_strength_pa: float,
                             endurance_limit_pa: float, allowable_shear_pa: float, bending_factor: float = 1.0,
                             standard_diameters_m: Sequence[float] = STANDARD_SHAFT_DIAMETERS_M) -> ShaftSizing:
    """Diameter by the report's fatigue formula (eq. 3.20, Soderberg-type maximum shear):
    ``tau_allow = 16 / (pi d**3) * sqrt(((S_y/S_e) K M)**2 + T**2)``.

    Parameters
    ----------
    moment_n_m : float
        Design (resultant) bending moment, N m (>= 0).
    torque_n_m : float
        Torque, N m (>= 0).
    yield_strength_pa : float
        Tensile yield strength S_y, Pa.
    endurance_limit_pa : float
        Corrected endurance limit S_e, Pa (see :func:`endurance_limit_pa`).
    allowable_shear_pa : float
        Allowable shear stress, Pa (see :func:`allowable_shear_stress_pa`).
    bending_factor : float
        Fatigue stress-concentration factor K on the moment (the report uses 1.8).
    standard_diameters_m : sequence of float
        Standard sizes, m, for the rounded-up diameter.

    Returns
    -------
    ShaftSizing
        Diameter and next standard size (method ``"soderberg"``).
    """
    moment = non_negative("moment_n_m", moment_n_m, "N m")
    torque = non_negative("torque_n_m", torque_n_m, "N m")
    sy = positive("yield_strength_pa", yield_strength_pa, "Pa")
    se = positive("endurance_limit_pa", endurance_limit_pa, "Pa")
    tau = positive("allowable_shear_pa", allowable_shear_pa, "Pa")
    k = positive("bending_factor", bending_factor, "(dimensionless)")
    return _sizing("soderberg", "d = [16/(pi tau) sqrt(((Sy/Se) K M)^2 + T^2)]^(1/3)",
                   moment, torque, k, 1.0, sy / se, tau, standard_diameters_m)


def shaft_diameter_asme(moment_n_m: float, torque_n_m: float, allowable_shear_pa: float, bending_factor: float = 1.5,
                        torsion_factor: float = 1.0,
                        standard_diameters_m: Sequence[float] = STANDARD_SHAFT_DIAMETERS_M) -> ShaftSizing:
    """Diameter by the ASME code form: ``d**3 = 16/(pi tau) sqrt((K_m M)**2 + (K_t T)**2)``.

    Parameters
    ----------
    moment_n_m, torque_n_m : float
        Design bending moment and torque, N m (>= 0).
    allowable_shear_pa : float
        Allowable shear, Pa (see :func:`asme_allowable_shear_stress_pa`).
    bending_factor, torsion_factor : float
        Combined shock and fatigue factors K_m and K_t (defaults 1.5 and 1.0, the
        values commonly tabulated for a rotating shaft with gradually applied load;
        take them from your code's table).
    standard_diameters_m : sequence of float
        Standard sizes, m.

    Returns
    -------
    ShaftSizing
        Diameter and next standard size (method ``"asme"``).
    """
    moment = non_negative("moment_n_m", moment_n_m, "N m")
    torque = non_negative("torque_n_m", torque_n_m, "N m")
    tau = positive("allowable_shear_pa", allowable_shear_pa, "Pa")
    km = positive("bending_factor", bending_factor, "(dimensionless)")
    kt = positive("torsion_factor", torsion_factor, "(dimensionless)")
    return _sizing("asme", "d = [16/(pi tau) sqrt((Km M)^2 + (Kt T)^2)]^(1/3)",
                   moment, torque, km, kt, 1.0, tau, standard_diameters_m)
