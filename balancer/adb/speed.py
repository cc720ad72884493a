"""Shaft speed profiles: constant speed, linear run-up, or any function of time.

A profile gives the speed ``omega(t)`` (rad/s) and the angular acceleration
``omega'(t)`` (rad/s^2).  Plain callables are wrapped; their acceleration is taken by a
central difference (step 1e-6 s: truncation ~1e-12 omega''', rounding ~2e-10 omega;
forward difference for t < 1e-6 s, so the function is never called at negative times).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Callable, Protocol, runtime_checkable

import numpy as np

from modal.errors import ParameterError

__all__ = ["SpeedProfile", "ConstantSpeed", "LinearRunUp", "CallableSpeed", "as_speed_profile", "check_profile"]


@runtime_checkable
class SpeedProfile(Protocol):
    """Anything with ``speed_rad_s(t)`` and ``acceleration_rad_s2(t)`` (vectorised over t)."""

    def speed_rad_s(self, time_s): ...

    def acceleration_rad_s2(self, time_s): ...


@dataclass(frozen=True, slots=True)
class ConstantSpeed:
    """Constant shaft speed.

    Parameters
    ----------
    speed : float
        Shaft speed (rad/s), finite.
    """

    speed: float

    def __post_init__(self) -> None:
        value = float(self.speed)
        if not math.isfinite(value):
            raise ParameterError(f"speed = {self.speed!r}: expected a finite constant speed in rad/s")
        object.__setattr__(self, "speed", value)

    def speed_rad_s(self, time_s):
        """Speed (rad/s) at ``time_s``."""
        return np.full(np.shape(time_s), self.speed) if np.ndim(time_s) else self.speed

    def acceleration_rad_s2(self, time_s):
        """Angular acceleration (rad/s^2): zero."""
        return np.zeros(np.shape(time_s)) if np.ndim(time_s) else 0.0


@dataclass(frozen=True, slots=True)
class LinearRunUp:
    """Speed ramping linearly from ``start_speed`` to ``end_speed``, constant outside the ramp.

    Parameters
    ----------
    start_speed : float
        Speed before and at ``start_time_s`` (rad/s).
    end_speed : float
        Speed at and after ``start_time_s + duration_s`` (rad/s).
    duration_s : float
        Ramp duration (s, > 0).
    start_time_s : float
        Start of the ramp (s).
    """

    start_speed: float
    end_speed: float
    duration_s: float
    start_time_s: float = 0.0

    def __post_init__(self) -> None:
        for name in ("start_speed", "end_speed", "duration_s", "start_time_s"):
            value = float(getattr(self, name))
            if not math.isfinite(value):
                raise ParameterError(f"{name} = {value!r}: expected a finite number")
            object.__setattr__(self, name, value)
        if not self.duration_s > 0.0:
            raise ParameterError(f"duration_s = {self.duration_s!r}: expected > 0 s")

    @property
    def rate_rad_s2(self) -> float:
        """Angular acceleration during the ramp (rad/s^2)."""
        return (self.end_speed - self.start_speed) / self.duration_s

    def speed_rad_s(self, time_s):
        """Speed (rad/s) at ``time_s``."""
        if isinstance(time_s, float):  # one time (the integrator's case): plain floats, the same arithmetic
            fraction = min(max((time_s - self.start_time_s) / self.duration_s, 0.0), 1.0)
            return self.start_speed + (self.end_speed - self.start_speed) * fraction
        fraction = np.clip((np.asarray(time_s, dtype=float) - self.start_time_s) / self.duration_s, 0.0, 1.0)
        value = self.start_speed + (self.end_speed - self.start_speed) * fraction
        return value if np.ndim(time_s) else float(value)

    def acceleration_rad_s2(self, time_s):
        """Angular acceleration (rad/s^2); the ramp rate inside ``[start, end)``, else 0."""
        if isinstance(time_s, float):
            inside = self.start_time_s <= time_s < self.start_time_s + self.duration_s
            return self.rate_rad_s2 if inside else 0.0
        t = np.asarray(time_s, dtype=float)
        inside = (t >= self.start_time_s) & (t < self.start_time_s + self.duration_s)
        value = np.where(inside, self.rate_rad_s2, 0.0)
        return value if np.ndim(time_s) else float(value)


class CallableSpeed:
    """Wrap a function ``omega(t)`` (rad/s); acceleration by central differences.

    Parameters
    ----------
    function : callable
        ``function(t)`` returning the speed (rad/s) for a float time (s).
    step_s : float
        Central-difference step (s).
    """

    __slots__ = ("function", "step_s")

    def __init__(self, function: Callable[[float], float], step_s: float = 1e-6) -> None:
        self.function = function
        self.step_s = float(step_s)

    def _call(self, t: float) -> float:
        value = float(self.function(float(t)))
        if not math.isfinite(value):
            raise ParameterError(f"speed profile returned {value!r} at t = {float(t)!r} s: expected a finite speed (rad/s)")
        return value

    def speed_rad_s(self, time_s):
        """Speed (rad/s) at ``time_s``."""
        if np.ndim(time_s):
            return np.array([self._call(t) for t in np.asarray(time_s, dtype=float).ravel()]).reshape(np.shape(time_s))
        return self._call(time_s)

    def acceleration_rad_s2(self, time_s):
        """Angular acceleration (rad/s^2) by a central difference (forward one before t = h,
        so that the function is never called at negative times)."""
        if np.ndim(time_s):
            t = np.asarray(time_s, dtype=float)
            return np.array([self._derivative(float(x)) for x in t.ravel()]).reshape(t.shape)
        return self._derivative(float(time_s))

    def _derivative(self, t: float) -> float:
        h = self.step_s
        if t < h:
            return (self._call(t + h) - self._call(t)) / h
        return (self._call(t + h) - self._call(t - h)) / (2.0 * h)


def as_speed_profile(speed: Any) -> SpeedProfile:
    """Turn a number, a callable or a profile object into a speed profile.

    Parameters
    ----------
    speed : float, callable or SpeedProfile
        Constant speed (rad/s), a function of time returning rad/s, or a profile.
    """
    if isinstance(speed, SpeedProfile):
        return speed
    if callable(speed):
        return CallableSpeed(speed)
    try:
        return ConstantSpeed(float(speed))
    except (TypeError, ValueError) as exc:
        if isinstance(exc, ParameterError):
            raise
        raise ParameterError(
            f"speed = {speed!r}: expected a constant speed in rad/s, a function of time or a speed profile"
        ) from exc


def check_profile(profile: SpeedProfile, t_end_s: float, samples: int = 1001) -> np.ndarray:
    """Sample a profile on ``[0, t_end_s]`` and raise if any speed or acceleration is not finite.

    Parameters
    ----------
    profile : SpeedProfile
        The profile.
    t_end_s : float
        End of the run (s).
    samples : int
        Number of sample times.

    Returns
    -------
    ndarray
        The sampled speeds (rad/s).
    """
    times = np.linspace(0.0, t_end_s, samples)
    speeds = np.asarray(profile.speed_rad_s(times), dtype=float)
    accelerations = np.asarray(profile.acceleration_rad_s2(times), dtype=float)
    bad = ~(np.isfinite(speeds) & np.isfinite(accelerations))
    if np.any(bad):
        t = times[np.argmax(bad)]
        raise ParameterError(
            f"speed profile is not finite at t = {t!r} s (speed {speeds[np.argmax(bad)]!r} rad/s, "
            f"acceleration {accelerations[np.argmax(bad)]!r} rad/s^2): expected finite values on [0, {t_end_s}] s"
        )
    return speeds
