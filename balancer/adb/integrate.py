"""Integration of one or a stacked batch of ADB systems with ``solve_ivp``.

* The integrator is chosen by stiffness: DOP853 (explicit, 8th order) unless the ball
  drag rate ``D / (m R^2)`` exceeds ``STIFFNESS_RATIO`` times the fastest dynamic rate
  ``max(omega_n, |omega|)``; then LSODA with the exact (complex-step) Jacobian,
  banded for stacked batches.
* A batch of parameter sets is one stacked ``solve_ivp`` system.  Because ``solve_ivp``
  controls an RMS norm over all components, the tolerances are divided by ``sqrt(B)``,
  which bounds every member's local error estimate by the single-run tolerance.
* A single parameter set uses a plain-float right-hand side (:func:`.equations.scalar_rhs`),
  which avoids numpy's per-call overhead.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np

from modal.errors import ParameterError

from .equations import (
    fixed_frame_jacobian,
    fixed_frame_rhs,
    rotating_frame_jacobian,
    rotating_frame_rhs,
    scalar_rhs,
)
from .parameters import ADBParameters, ParameterBatch
from .speed import ConstantSpeed, LinearRunUp, as_speed_profile, check_profile

__all__ = ["STIFFNESS_RATIO", "IntegrationResult", "choose_method", "integrate"]

STIFFNESS_RATIO = 50.0
"""Ball-drag rate over the fastest dynamic rate above which the drag counts as stiff."""

def choose_method(params: ADBParameters | ParameterBatch, max_speed_rad_s: float) -> str:
    """``"LSODA"`` if the ball drag is stiff, else ``"DOP853"``.

    Parameters
    ----------
    params : ADBParameters or ParameterBatch
        Parameters (for a batch the stiffest member decides).
    max_speed_rad_s : float
        Largest shaft speed of the run (rad/s).
    """
    batch = params if isinstance(params, ParameterBatch) else ParameterBatch.from_parameters(params)
    drag_rate = batch.D / (batch.m * batch.R**2)
    dynamic = np.maximum(batch.natural_frequency_rad_s, abs(max_speed_rad_s))
    return "LSODA" if np.max(drag_rate / dynamic) > STIFFNESS_RATIO else "DOP853"


@dataclass(frozen=True, slots=True)
class IntegrationResult:
    """Sampled states of a (possibly stacked) integration.

    Attributes
    ----------
    time_s : ndarray, shape (T,)
        Sample times (s).
    states : ndarray, shape (B, T, N)
        States in the integration frame.
    frame : str
        ``"rotating"`` or ``"fixed"``.
    method : str
        ``solve_ivp`` method used.
    n_function_evaluations, n_jacobian_evaluations : int
        Counters from ``solve_ivp`` (one evaluation covers the whole batch).
    rtol : float
        Relative tolerance passed to ``solve_ivp`` (after the batch scaling).
    """

    time_s: np.ndarray
    states: np.ndarray
    frame: str
    method: str
    n_function_evaluations: int
    n_jacobian_evaluations: int
    rtol: float


def _absolute_tolerances(batch: ParameterBatch, rtol: float, speed_scale: float, fixed: bool) -> np.ndarray:
    n = batch.n
    rate = np.maximum(batch.natural_frequency_rad_s, abs(speed_scale))[:, None]
    position = 1e-3 * rtol * batch.R[:, None]
    angle = np.full((batch.size, 1), 1e-3 * rtol)
    parts = [position, position, np.repeat(angle, n, 1), position * rate, position * rate, np.repeat(angle * rate, n, 1)]
    if fixed:
        parts.append(np.full((batch.size, 1), rtol))
    return np.concatenate(parts, axis=1).reshape(-1)


def _banded(jac: np.ndarray) -> np.ndarray:
    """Pack a block-diagonal Jacobian (B blocks of N x N) in LSODA's banded format."""
    batch, size, _ = jac.shape
    band = np.zeros((2 * size - 1, batch * size))
    for i in range(size):
        for j in range(size):
            band[i - j + size - 1, j::size] = jac[:, i, j]
    return band


def integrate(
    params: ADBParameters | Sequence[ADBParameters],
    speed: Any,
    initial_states,
    t_eval_s,
    *,
    frame: str = "rotating",
    method: str = "auto",
    rtol: float = 1e-9,
    atol=None,
) -> IntegrationResult:
    """Integrate one or a stacked batch of systems from given states.

    Parameters
    ----------
    params : ADBParameters or sequence of ADBParameters
        One parameter set or a batch (common ``n``).
    speed : float, callable or SpeedProfile
        Shaft speed (rad/s); the rotating frame needs a constant speed.
    initial_states : ndarray, shape (N,) or (B, N)
        States at ``t_eval_s[0]`` in the chosen frame (see :mod:`.equations`).
    t_eval_s : array_like, shape (T,)
        Increasing sample times (s); the run spans ``[t_eval_s[0], t_eval_s[-1]]``.
    frame : {"rotating", "fixed"}
        Formulation.
    method : str
        ``"auto"`` (by stiffness) or any ``solve_ivp`` method.
    rtol : float
        Relative tolerance per member (divided by ``sqrt(B)`` for the stacked system).
    atol : float or ndarray, optional
        Absolute tolerance per component; default scaled from ``rtol`` (positions
        ``1e-3 rtol R``, angles ``1e-3 rtol`` rad, rates times ``max(omega_n, |omega|)``).

    Returns
    -------
    IntegrationResult
    """
    members = [params] if isinstance(params, ADBParameters) else list(params)
    batch = ParameterBatch.from_parameters(members)
    profile = as_speed_profile(speed)
    times = np.asarray(t_eval_s, dtype=float).reshape(-1)
    if times.size < 2 or not np.all(np.isfinite(times)) or np.any(np.diff(times) <= 0):
        raise ParameterError(f"t_eval_s: expected at least 2 finite, increasing times; got {times.size} values")
    speeds = check_profile(profile, float(times[-1]))
    if frame not in ("rotating", "fixed"):
        raise ParameterError(f"frame = {frame!r}: expected 'rotating' or 'fixed'")
    if frame == "rotating" and not isinstance(profile, ConstantSpeed):
        raise ParameterError("frame = 'rotating' needs a constant speed; use frame='fixed' for a speed profile")
    if not (math.isfinite(rtol) and 0.0 < rtol < 1.0):
        raise ParameterError(f"rtol = {rtol!r}: expected 0 < rtol < 1")
    y0 = np.atleast_2d(np.asarray(initial_states, dtype=float))
    size = y0.shape[-1]
    expected = 4 + 2 * batch.n + (frame == "fixed")
    if size != expected or y0.shape[0] not in (1, batch.size):
        raise ParameterError(f"initial_states has shape {y0.shape}: expected ({batch.size}, {expected})")
    if not np.all(np.isfinite(y0)):
        raise ParameterError("initial_states: expected finite values")
    y0 = np.broadcast_to(y0, (batch.size, size))
    max_speed = float(np.max(np.abs(speeds)))
    chosen = choose_method(batch, max_speed) if method == "auto" else method
    scale = math.sqrt(batch.size)
    rtol_eff = rtol / scale
    atol_eff = (_absolute_tolerances(batch, rtol, max_speed, frame == "fixed") if atol is None
                else np.broadcast_to(np.asarray(atol, dtype=float), (batch.size * size,))) / scale
    rhs = rotating_frame_rhs if frame == "rotating" else fixed_frame_rhs
    jacobian = rotating_frame_jacobian if frame == "rotating" else fixed_frame_jacobian
    constant = isinstance(profile, ConstantSpeed)

    def speed_at(t: float) -> tuple[float, float]:
        if constant:
            return profile.speed, 0.0
        return float(profile.speed_rad_s(t)), float(profile.acceleration_rad_s2(t))

    if batch.size == 1:
        single = scalar_rhs(*(float(getattr(batch, name)[0]) for name in ("M", "m")), batch.n,
                            *(float(getattr(batch, name)[0]) for name in ("R", "e", "k", "c", "D")), frame=frame)

        if isinstance(profile, LinearRunUp):
            # LinearRunUp.speed_rad_s / acceleration_rad_s2 of one float, inlined (the same arithmetic;
            # finite by construction): the run-up's right-hand side is called ~16 000 times
            t0, t1, duration = profile.start_time_s, profile.start_time_s + profile.duration_s, profile.duration_s
            w0, dw, rate = profile.start_speed, profile.end_speed - profile.start_speed, profile.rate_rad_s2

            def fun(t, y):
                omega = w0 + dw * min(max((t - t0) / duration, 0.0), 1.0)
                return single(y, omega, rate if t0 <= t < t1 else 0.0)
        else:
            def fun(t, y):
                omega, alpha = speed_at(t)
                if not (math.isfinite(omega) and math.isfinite(alpha)):
                    raise ParameterError(f"speed profile is not finite at t = {t!r} s: expected finite values")
                return single(y, omega, alpha)
    else:
        def fun(t, y):
            omega, alpha = speed_at(t)
            if not (math.isfinite(omega) and math.isfinite(alpha)):
                raise ParameterError(f"speed profile is not finite at t = {t!r} s: expected finite values")
            return rhs(y.reshape(batch.size, size), batch, omega, alpha).reshape(-1)

    options: dict[str, Any] = {}
    if chosen in ("LSODA", "Radau", "BDF"):
        def jac(t, y):
            omega, alpha = speed_at(t)
            blocks = jacobian(y.reshape(batch.size, size), batch, omega, alpha)
            if chosen == "LSODA" and batch.size > 1:
                return _banded(blocks)
            if batch.size == 1:
                return blocks[0]
            from scipy.sparse import block_diag

            return block_diag(list(blocks), format="csc")

        options["jac"] = jac
        if chosen == "LSODA" and batch.size > 1:
            options["lband"] = options["uband"] = size - 1
    from scipy.integrate import solve_ivp  # imported when used: a plotting process unpickles these results

    solution = solve_ivp(fun, (times[0], times[-1]), y0.reshape(-1), method=chosen, t_eval=times,
                         rtol=rtol_eff, atol=atol_eff, **options)
    if solution.status != 0:
        raise ParameterError(f"integration failed ({chosen}): {solution.message}")
    states = solution.y.reshape(batch.size, size, -1).transpose(0, 2, 1)
    return IntegrationResult(
        time_s=solution.t, states=states, frame=frame, method=chosen,
        n_function_evaluations=int(solution.nfev), n_jacobian_evaluations=int(getattr(solution, "njev", 0)),
        rtol=rtol_eff,
    )
