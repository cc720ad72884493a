"""Input checks shared by the crank, drive and shaft modules: a clear ``ParameterError`` naming
the argument, its value (and unit), and what was expected."""
from __future__ import annotations

import math

from modal.errors import ParameterError

__all__ = ["finite", "positive", "non_negative", "bounded"]


def finite(name: str, value: float, unit: str) -> float:
    """``value`` as a finite float (``unit`` names its unit in the message)."""
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise ParameterError(f"{name} = {value!r} is not a number; expected a value in {unit}") from None
    if not math.isfinite(number):
        raise ParameterError(f"{name} = {number} {unit} is not finite; expected a finite value")
    return number


def positive(name: str, value: float, unit: str) -> float:
    """``value`` as a finite float > 0."""
    number = finite(name, value, unit)
    if number <= 0.0:
        raise ParameterError(f"{name} = {number} {unit} must be > 0")
    return number


def non_negative(name: str, value: float, unit: str) -> float:
    """``value`` as a finite float >= 0."""
    number = finite(name, value, unit)
    if number < 0.0:
        raise ParameterError(f"{name} = {number} {unit} must be >= 0")
    return number


def bounded(name: str, value, *, minimum: float | None = None, strict: bool = False,
            maximum: float | None = None) -> float:
    """``value`` as a finite float within [minimum, maximum] (``strict``: above ``minimum``).

    The unit is in ``name`` (``crank_radius_m``), as the crank module names its arguments.
    """
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise ParameterError(f"{name} = {value!r}: expected a real number") from None
    if not math.isfinite(number):
        raise ParameterError(f"{name} = {value!r}: expected a finite number")
    if minimum is not None:
        if strict and not number > minimum:
            raise ParameterError(f"{name} = {number!r}: expected a value > {minimum}")
        if not strict and not number >= minimum:
            raise ParameterError(f"{name} = {number!r}: expected a value >= {minimum}")
    if maximum is not None and number > maximum:
        raise ParameterError(f"{name} = {number!r}: expected a value <= {maximum}")
    return number
