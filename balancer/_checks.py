"""Argument checks of ``balancer``, in one place: each returns the value as a clean float (or array)
or raises :class:`~modal.errors.ParameterError` in one line naming the argument, its value (and
unit) and what was expected.

The messages come in the few forms the studies already use:

* :func:`finite`, :func:`positive`, :func:`non_negative`: a value with its unit (the drive, shaft
  and influence modules): ``"power_w = -1.0 W must be > 0"``;
* :func:`bounded`: a value whose unit is in its name (the crank modules):
  ``"crank_radius_m = 0.0: expected a value > 0"``;
* :func:`parameter`: a named physical parameter (the ball balancer's ``M``, ``k``, ...):
  ``"k (support stiffness) = -1.0 N/m: expected > 0"``;
* :func:`count`: a whole number (the ball count);
* :func:`finite_positive`: one message for every way a value can fail (a time, a speed);
* :func:`finite_array`: arrays of readings, naming the first bad entry;
* :func:`scene_number`: a number in a scene file, whose rule reports only what was expected
  (the scene's schema names the file and the key).
"""
from __future__ import annotations

import math

import numpy as np

from modal.errors import ParameterError

__all__ = ["finite", "positive", "non_negative", "bounded", "parameter", "count", "finite_positive", "finite_array",
           "scene_number"]


def _float(value) -> float | None:
    """``float(value)``, or None when ``value`` is not a real number."""
    try:
        return float(value)
    except (TypeError, ValueError):
        return None


def finite(name: str, value: float, unit: str) -> float:
    """``value`` as a finite float (``unit`` names its unit in the message)."""
    number = _float(value)
    if number is None:
        raise ParameterError(f"{name} = {value!r} is not a number; expected a value in {unit}")
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
    number = _float(value)
    if number is None:
        raise ParameterError(f"{name} = {value!r}: expected a real number")
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


def parameter(label: str, value, unit: str, *, positive: bool) -> float:
    """A physical parameter as a finite float, > 0 (``positive``) or >= 0.

    ``label`` names it and says what it is (``"k (support stiffness)"``); ``unit`` is its unit.
    """
    number = _float(value)
    if number is None:
        raise ParameterError(f"{label} = {value!r}: expected a real number in {unit}")
    if not math.isfinite(number):
        raise ParameterError(f"{label} = {number!r}: expected a finite number")
    if positive and not number > 0.0:
        raise ParameterError(f"{label} = {number!r} {unit}: expected > 0")
    if not positive and number < 0.0:
        raise ParameterError(f"{label} = {number!r} {unit}: expected >= 0")
    return number


def count(label: str, value, minimum: int = 1) -> int:
    """``value`` as an int >= ``minimum``; an integral float (``2.0``) is accepted, a boolean is not."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)):
        if isinstance(value, (float, np.floating)) and float(value).is_integer():
            value = int(value)
        else:
            raise ParameterError(f"{label} = {value!r}: expected an integer >= {minimum}")
    if int(value) < minimum:
        raise ParameterError(f"{label} = {value!r}: expected an integer >= {minimum}")
    return int(value)


def finite_positive(name: str, value, expected: str) -> float:
    """``value`` as a finite float > 0; else ``"<name> = <value>: expected <expected>"``, whatever was wrong."""
    number = _float(value)
    if number is None:
        raise ParameterError(f"{name} = {value!r}: expected {expected}")
    if not (math.isfinite(number) and number > 0.0):
        raise ParameterError(f"{name} = {number!r}: expected {expected}")
    return number


def finite_array(values, field: str) -> np.ndarray:
    """``values`` as a float array of finite numbers; the message names ``field`` and the first bad entry."""
    try:
        array = np.asarray(values, dtype=float)
    except (TypeError, ValueError):
        raise ParameterError(f"{field}: expected numbers, got {values!r}") from None
    bad = np.flatnonzero(~np.isfinite(array.ravel()))
    if bad.size:
        raise ParameterError(f"{field}: entry {int(bad[0])} is {array.ravel()[bad[0]]}; expected a finite number")
    return array


def scene_number(value, *, positive: bool = False, nonneg: bool = False) -> float:
    """A scene file's number (an int or float, not a boolean) as a finite float, > 0 (``positive``) or
    >= 0 (``nonneg``); else ``ValueError`` saying what was expected (the scene names the file and key)."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ValueError("a number")
    try:
        number = float(value)
    except OverflowError:  # TOML integers may be arbitrarily long
        raise ValueError("a finite number") from None
    if not math.isfinite(number):
        raise ValueError("a finite number")
    if positive and number <= 0:
        raise ValueError("a number > 0")
    if nonneg and number < 0:
        raise ValueError("a number >= 0")
    return number
