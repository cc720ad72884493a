"""Parameter studies built on :func:`~balancer.adb.simulate.simulate` (design questions)."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from modal.errors import ParameterError

from .parameters import ADBParameters
from .simulate import simulate

__all__ = ["SettlingStudy", "settling_study"]

_FIELDS = ("M", "m", "n", "R", "e", "k", "c", "D")


@dataclass(frozen=True, slots=True)
class SettlingStudy:
    """Settling time against one parameter at a fixed speed ratio.

    Attributes
    ----------
    parameter : str
        Name of the varied :class:`ADBParameters` field.
    values : ndarray, shape (V,)
        Its values (SI).
    speed_ratio : float
        ``omega / omega_n`` of every run (``omega_n`` of each parameter set).
    settling_time_s : ndarray, shape (V,)
        Settling times (s); inf where the balls did not settle.
    residual_amplitude_m : ndarray, shape (V,)
        Residual vibration at the end of each run (m).
    final_state : tuple of str
        Final-state class of each run.
    t_end_s : float
        Duration of each run (s).
    """

    parameter: str
    values: np.ndarray
    speed_ratio: float
    settling_time_s: np.ndarray
    residual_amplitude_m: np.ndarray
    final_state: tuple[str, ...]
    t_end_s: float


def settling_study(params: ADBParameters, parameter: str, values, *, speed_ratio: float = 4.0,
                   t_end_s: float = 2.0, initial_ball_angles_rad=None) -> SettlingStudy:
    """Settling time from the same start as one parameter varies (others fixed, D included).

    Parameters
    ----------
    params : ADBParameters
        Base parameters.
    parameter : str
        Field to vary (``M, m, n, R, e, k, c, D``).
    values : array_like
        Its values (SI).
    speed_ratio : float
        ``omega / omega_n`` for every run.
    t_end_s : float
        Duration of each run (s).
    initial_ball_angles_rad : array_like, optional
        Start (default: :func:`~balancer.adb.simulate.default_initial_ball_angles`).
    """
    if parameter not in _FIELDS:
        raise ParameterError(f"parameter = {parameter!r}: expected one of {_FIELDS}")
    values = np.atleast_1d(np.asarray(values, dtype=float))
    times, residuals, finals = [], [], []
    for value in values:
        p = params.replace(**{parameter: int(value) if parameter == "n" else float(value)})
        result = simulate(p, speed_ratio * p.natural_frequency_rad_s, t_end_s, initial_ball_angles_rad,
                          compare_without_balls=False, n_samples=2001)
        times.append(result.settling_time_s)
        residuals.append(result.residual_amplitude_m)
        finals.append(result.final_state)
    return SettlingStudy(parameter=parameter, values=values, speed_ratio=float(speed_ratio),
                         settling_time_s=np.array(times), residual_amplitude_m=np.array(residuals),
                         final_state=tuple(finals), t_end_s=float(t_end_s))
