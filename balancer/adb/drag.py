"""Ball drag coefficient ``D`` from the fluid in the race.

A ball slips through the fluid (which turns with the race) at ``v = R |phi'|``; with the
sphere drag ``F = 1/2 rho C_D(Re) (pi d^2 / 4) v^2`` and ``Re = rho v d / mu`` the torque
``F R`` per unit slip rate gives

    ``D = 1/2 rho C_D(Re) (pi d^2 / 4) R^3 |phi'|``

which in the Stokes limit (``C_D = 24 / Re``) is ``D = 3 pi mu d R^2``, independent of the
slip.  Correlations (``adb.md`` section 3):

* Stokes: ``C_D = 24 / Re`` (creeping flow; within 4 % of the others for Re < 0.1).
* Abraham (1970): ``C_D = (24 / 9.06^2) (1 + 9.06 / sqrt(Re))^2``.
* Turton & Levenspiel (1986): ``C_D = 24/Re (1 + 0.173 Re^0.657) + 0.413 / (1 + 16300 Re^-1.09)``,
  for Re <= 2e5.

They are for a free sphere in an unbounded fluid, so for a ball rolling in a partly
filled race they are only rough (Rodrigues et al. could not measure the drag at all).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from modal.errors import ParameterError

__all__ = [
    "Fluid",
    "LIGHT_OIL",
    "WATER",
    "AIR",
    "CORRELATIONS",
    "REYNOLDS_LIMIT",
    "BallDrag",
    "drag_coefficient",
    "flow_regime",
    "ball_drag",
    "with_fluid_drag",
]

CORRELATIONS = ("turton_levenspiel", "abraham", "stokes")
REYNOLDS_LIMIT = 2.0e5
"""Upper Reynolds number of the Turton-Levenspiel fit (drag crisis beyond)."""


@dataclass(frozen=True, slots=True)
class Fluid:
    """A Newtonian fluid.

    Attributes
    ----------
    density_kg_m3 : float
        Density (kg/m^3, > 0).
    viscosity_pa_s : float
        Dynamic viscosity (Pa s, > 0).
    name : str
        Label.
    """

    density_kg_m3: float
    viscosity_pa_s: float
    name: str = ""

    def __post_init__(self) -> None:
        for field_name, unit in (("density_kg_m3", "kg/m^3"), ("viscosity_pa_s", "Pa s")):
            value = float(getattr(self, field_name))
            if not (math.isfinite(value) and value > 0.0):
                raise ParameterError(f"{field_name} = {value!r}: expected a finite value > 0 {unit}")
            object.__setattr__(self, field_name, value)


LIGHT_OIL = Fluid(870.0, 0.03, "light oil")
WATER = Fluid(998.0, 1.0e-3, "water (20 C)")
AIR = Fluid(1.204, 1.81e-5, "air (20 C)")


def drag_coefficient(reynolds, correlation: str = "turton_levenspiel"):
    """Sphere drag coefficient ``C_D`` against Reynolds number.

    Parameters
    ----------
    reynolds : float or ndarray
        Reynolds number(s), > 0 and <= ``REYNOLDS_LIMIT``.
    correlation : {"turton_levenspiel", "abraham", "stokes"}
        Correlation.

    Returns
    -------
    float or ndarray
        ``C_D`` (-).
    """
    if correlation not in CORRELATIONS:
        raise ParameterError(f"correlation = {correlation!r}: expected one of {CORRELATIONS}")
    re = np.asarray(reynolds, dtype=float)
    if not np.all(np.isfinite(re)) or np.any(re <= 0.0):
        raise ParameterError(f"reynolds = {reynolds!r}: expected finite values > 0")
    if np.any(re > REYNOLDS_LIMIT):
        raise ParameterError(
            f"reynolds up to {float(np.max(re)):.3g}: expected <= {REYNOLDS_LIMIT:.0e} (beyond the drag crisis "
            f"the correlations do not apply)"
        )
    if correlation == "stokes":
        value = 24.0 / re
    elif correlation == "abraham":
        value = (24.0 / 9.06**2) * (1.0 + 9.06 / np.sqrt(re)) ** 2
    else:
        value = 24.0 / re * (1.0 + 0.173 * re**0.657) + 0.413 / (1.0 + 16300.0 * re**-1.09)
    return value if np.ndim(reynolds) else float(value)


def flow_regime(reynolds: float) -> str:
    """Name of the flow regime around a sphere: ``"stokes"`` (Re < 0.1), ``"intermediate"``
    (0.1-1000), ``"newton"`` (1000-2e5).

    Parameters
    ----------
    reynolds : float
        Reynolds number (>= 0).
    """
    if reynolds < 0.1:
        return "stokes"
    if reynolds < 1000.0:
        return "intermediate"
    return "newton"


@dataclass(frozen=True, slots=True)
class BallDrag:
    """Ball drag coefficient and the flow it comes from.

    Attributes
    ----------
    drag_n_m_s : ndarray
        ``D`` per slip rate (N m s).
    stokes_drag_n_m_s : float
        The Stokes-limit value ``3 pi mu d R^2`` (N m s).
    reynolds : ndarray
        Reynolds numbers ``rho R |phi'| d / mu``.
    drag_coefficient : ndarray
        ``C_D`` used (inf at zero slip, where D is the Stokes limit).
    regime : tuple of str
        Flow regime per slip rate.
    slip_rate_rad_s : ndarray
        Slip rates (rad/s).
    correlation : str
        Correlation used.
    fluid_name : str
        The fluid's label.
    """

    drag_n_m_s: np.ndarray
    stokes_drag_n_m_s: float
    reynolds: np.ndarray
    drag_coefficient: np.ndarray
    regime: tuple[str, ...]
    slip_rate_rad_s: np.ndarray
    correlation: str
    fluid_name: str


def ball_drag(fluid: Fluid, ball_diameter_m: float, race_radius_m: float, slip_rate_rad_s,
              correlation: str = "turton_levenspiel") -> BallDrag:
    """Ball drag coefficient ``D`` (N m s) at representative slip rates.

    Parameters
    ----------
    fluid : Fluid
        Fluid in the race.
    ball_diameter_m : float
        Ball diameter (m, > 0).
    race_radius_m : float
        Race radius to the ball centre (m, > 0).
    slip_rate_rad_s : float or array_like
        Ball rate relative to the race (rad/s); 0 gives the Stokes limit.
    correlation : {"turton_levenspiel", "abraham", "stokes"}
        Drag-coefficient correlation.

    Returns
    -------
    BallDrag
    """
    if not isinstance(fluid, Fluid):
        raise ParameterError(f"fluid: got {type(fluid).__name__}; expected a Fluid")
    d = float(ball_diameter_m)
    R = float(race_radius_m)
    for name, value in (("ball_diameter_m", d), ("race_radius_m", R)):
        if not (math.isfinite(value) and value > 0.0):
            raise ParameterError(f"{name} = {value!r}: expected a finite length > 0 m")
    slip = np.abs(np.atleast_1d(np.asarray(slip_rate_rad_s, dtype=float)))
    if not np.all(np.isfinite(slip)):
        raise ParameterError(f"slip_rate_rad_s = {slip_rate_rad_s!r}: expected finite rates (rad/s)")
    rho, mu = fluid.density_kg_m3, fluid.viscosity_pa_s
    stokes = 3.0 * math.pi * mu * d * R**2
    reynolds = rho * R * slip * d / mu
    moving = reynolds > 0.0
    cd = np.full(slip.shape, np.inf)
    drag = np.full(slip.shape, stokes)
    if np.any(moving):
        cd[moving] = drag_coefficient(reynolds[moving], correlation)
        drag[moving] = 0.5 * rho * cd[moving] * (math.pi * d * d / 4.0) * R**3 * slip[moving]
    return BallDrag(
        drag_n_m_s=drag, stokes_drag_n_m_s=stokes, reynolds=reynolds, drag_coefficient=cd,
        regime=tuple(flow_regime(float(re)) for re in reynolds), slip_rate_rad_s=slip,
        correlation=correlation, fluid_name=fluid.name,
    )


def with_fluid_drag(params, fluid: Fluid, ball_diameter_m: float, slip_rate_rad_s: float = 0.0,
                    correlation: str = "turton_levenspiel"):
    """Parameters whose ball drag ``D`` comes from a fluid at a representative slip rate.

    Parameters
    ----------
    params : ADBParameters
        Parameters whose ``D`` is replaced (``R`` is used as the race radius).
    fluid : Fluid
        Fluid in the race.
    ball_diameter_m : float
        Ball diameter (m).
    slip_rate_rad_s : float
        Representative ball rate relative to the race (rad/s); 0 gives the Stokes limit.
    correlation : {"turton_levenspiel", "abraham", "stokes"}
        Drag-coefficient correlation.

    Returns
    -------
    (ADBParameters, BallDrag)
        The new parameters and the drag computation (Reynolds number, regime).
    """
    drag = ball_drag(fluid, ball_diameter_m, params.R, [slip_rate_rad_s], correlation)
    return params.replace(D=float(drag.drag_n_m_s[0])), drag
