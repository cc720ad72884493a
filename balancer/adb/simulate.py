"""Time responses: constant speed and run-up, single runs and stacked batches.

* Constant speed is integrated in the rotating frame (autonomous; the balanced state
  is a fixed point, so steps grow as the balls settle); rotor coordinates are rotated
  back exactly for the fixed-frame orbit.
* A speed profile (run-up) is integrated in the fixed Cartesian frame.
* Integrator choice and batching: :mod:`.integrate`; settling and final-state classes:
  :mod:`.analysis`.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np

from modal.errors import ParameterError

from .._checks import finite_positive
from .analysis import classify_final_state, settling_time
from .equations import fixed_to_rotating, rotating_to_fixed, scalar_rhs
from .equilibria import balanced_ball_angles
from .integrate import IntegrationResult, _absolute_tolerances, integrate
from .parameters import ADBParameters, ParameterBatch
from .speed import ConstantSpeed, LinearRunUp, SpeedProfile, as_speed_profile, check_profile

__all__ = [
    "SimulationResult",
    "BatchSimulationResult",
    "default_initial_ball_angles",
    "simulate",
    "simulate_batch",
]

def default_initial_ball_angles(n: int) -> np.ndarray:
    """Default start: balls resting near the heavy spot, spread over 0.3-0.5 rad (rad).

    With the rotor at rest this is never an equilibrium (the balls add to the unbalance).

    Parameters
    ----------
    n : int
        Number of balls.

    Returns
    -------
    ndarray, shape (n,)
        Ball angles from the unbalance, rad.
    """
    if n == 1:
        return np.array([0.3])
    return 0.3 + 0.2 * np.arange(n) / (n - 1)


@dataclass(frozen=True, slots=True)
class SimulationResult:
    """One simulated run of the rotor with balls (and without, for comparison).

    Attributes
    ----------
    time_s : ndarray, shape (T,)
        Sample times (s).
    speed_rad_s, rotor_angle_rad : ndarray, shape (T,)
        Shaft speed (rad/s) and rotor angle (rad).
    rotor_x_m, rotor_y_m : ndarray, shape (T,)
        Rotor centre in the fixed frame (m).
    rotor_u_m, rotor_v_m : ndarray, shape (T,)
        Rotor centre in the frame turning with the shaft (m); ``u`` along the unbalance.
    amplitude_m : ndarray, shape (T,)
        Vibration amplitude ``sqrt(x^2 + y^2)`` (m).
    ball_angles_rad, ball_rates_rad_s : ndarray, shape (T, n)
        Ball angles relative to the unbalance direction (rad, continuous: not wrapped, so a
        slipping ball's angle keeps growing) and their rates relative to the race (rad/s).
    balanced_ball_angles_rad : ndarray, shape (n,) or (0,)
        The balanced configuration (symmetric member for n >= 3); empty if impossible.
    settled : bool
        Whether the balls ended within the settling tolerance.
    settling_time_s : float
        Last time outside the tolerance (s); inf if not settled.
    residual_amplitude_m : float
        Largest amplitude over the final window (m).
    final_state : str
        ``"balanced"``, ``"locked"``, ``"whirl"`` or ``"transient"``.
    final_slip_rate_rad_s : ndarray, shape (n,)
        Mean ball rate relative to the race over the final window (rad/s).
    amplitude_without_balls_m : ndarray, shape (T,) or (0,)
        Amplitude of the same rotor with the balls removed (m).
    rotor_x_without_balls_m, rotor_y_without_balls_m : ndarray, shape (T,) or (0,)
        Its orbit (m).
    residual_amplitude_without_balls_m : float
        Its largest amplitude over the final window (m); nan if not computed.
    compared_without_balls : bool
        Whether the run without balls was made (else its arrays are empty).
    window_start_s : float
        Start of the final window (s).
    settle_tolerance : float
        Relative settling tolerance used.
    frame, method : str
        Formulation and integrator.
    rtol : float
        Relative tolerance.
    n_function_evaluations, n_jacobian_evaluations : int
        Integrator counters.
    """

    time_s: np.ndarray
    speed_rad_s: np.ndarray
    rotor_angle_rad: np.ndarray
    rotor_x_m: np.ndarray
    rotor_y_m: np.ndarray
    rotor_u_m: np.ndarray
    rotor_v_m: np.ndarray
    amplitude_m: np.ndarray
    ball_angles_rad: np.ndarray
    ball_rates_rad_s: np.ndarray
    balanced_ball_angles_rad: np.ndarray
    settled: bool
    settling_time_s: float
    residual_amplitude_m: float
    final_state: str
    final_slip_rate_rad_s: np.ndarray
    amplitude_without_balls_m: np.ndarray
    rotor_x_without_balls_m: np.ndarray
    rotor_y_without_balls_m: np.ndarray
    residual_amplitude_without_balls_m: float
    compared_without_balls: bool
    window_start_s: float
    settle_tolerance: float
    frame: str
    method: str
    rtol: float
    n_function_evaluations: int
    n_jacobian_evaluations: int


def _initial_ball_angles(params: ADBParameters, angles) -> np.ndarray:
    if angles is None:
        return default_initial_ball_angles(params.n)
    array = np.asarray(angles, dtype=float).reshape(-1)
    if array.shape[0] != params.n or not np.all(np.isfinite(array)):
        raise ParameterError(
            f"initial_ball_angles_rad = {angles!r}: expected {params.n} finite angles (rad, relative to the unbalance)"
        )
    return array


def _initial_state(n: int, angles, position, velocity, rates, frame: str, speed0: float) -> np.ndarray:
    fixed = np.zeros(5 + 2 * n)
    fixed[0:2] = position
    fixed[2:2 + n] = angles
    fixed[2 + n:4 + n] = velocity
    fixed[4 + n:4 + 2 * n] = rates
    if frame == "fixed":
        return fixed
    return fixed_to_rotating(fixed, speed0, n)


def _pair(value, name: str) -> np.ndarray:
    array = np.asarray(value, dtype=float).reshape(-1)
    if array.shape != (2,) or not np.all(np.isfinite(array)):
        raise ParameterError(f"{name} = {value!r}: expected two finite numbers (x, y)")
    return array


def _sample_times(t_end: float, n_samples: int | None, max_speed: float) -> np.ndarray:
    if n_samples is None:
        per_revolution = 40.0 * max_speed / (2 * math.pi) * t_end
        n_samples = int(min(max(2001, per_revolution), 200_001))
    if int(n_samples) < 3:
        raise ParameterError(f"n_samples = {n_samples!r}: expected >= 3")
    return np.linspace(0.0, t_end, int(n_samples))


def _fixed_outputs(result: IntegrationResult, profile: SpeedProfile, n: int, member: int = 0):
    """Fixed-frame (x, y), rotating (u, v), angles, rates, rotor angle and speed of one member."""
    t = result.time_s
    states = result.states[member]
    if result.frame == "rotating":
        omega = profile.speed
        theta = omega * t
        speed = np.full_like(t, omega)
        fixed = rotating_to_fixed(states, theta, omega, n)
        rot = states
    else:
        speed = np.asarray(profile.speed_rad_s(t), dtype=float)
        theta = states[:, 4 + 2 * n]
        fixed = states
        rot = fixed_to_rotating(states, speed, n)
    return fixed[:, 0], fixed[:, 1], rot[:, 0], rot[:, 1], states[:, 2:2 + n], states[:, 4 + n:4 + 2 * n], theta, speed


def simulate(
    params: ADBParameters,
    speed: Any,
    t_end_s: float,
    initial_ball_angles_rad=None,
    *,
    initial_rotor_position_m=(0.0, 0.0),
    initial_rotor_velocity_m_s=(0.0, 0.0),
    initial_ball_rates_rad_s=None,
    frame: str = "auto",
    method: str = "auto",
    rtol: float = 1e-9,
    n_samples: int | None = None,
    settle_tolerance: float = 0.01,
    final_window_fraction: float = 0.1,
    compare_without_balls: bool = True,
    release_time_s: float | None = None,
) -> SimulationResult:
    """Simulate the rotor with balls at constant speed or along a speed profile.

    Parameters
    ----------
    params : ADBParameters
        Parameters.
    speed : float, callable or SpeedProfile
        Constant shaft speed (rad/s), a function of time returning rad/s, or a profile
        such as :class:`~balancer.adb.speed.LinearRunUp`.
    t_end_s : float
        Duration (s).
    initial_ball_angles_rad : array_like of length n, optional
        Ball angles relative to the unbalance at t = 0 (rad).  Default: balls resting
        near the heavy spot, spread over 0.3-0.5 rad (never an equilibrium).
    initial_rotor_position_m, initial_rotor_velocity_m_s : (float, float)
        Rotor centre position (m) and velocity (m/s) in the fixed frame at t = 0.
    initial_ball_rates_rad_s : array_like of length n, optional
        Ball rates relative to the race at t = 0 (rad/s); default 0 (moving with the race).
    frame : {"auto", "rotating", "fixed"}
        Formulation; "auto" is rotating for a constant speed, fixed for a profile.
    method : str
        "auto" (DOP853, or LSODA with the exact Jacobian for stiff drag) or any
        ``solve_ivp`` method.
    rtol : float
        Relative tolerance.
    n_samples : int, optional
        Number of output samples; default at least 2001 and 40 per revolution.
    settle_tolerance : float
        Relative tolerance for settling (see the module notes).
    final_window_fraction : float
        Fraction of the run, at its end, used for the residual amplitude and the
        final-state classification.
    compare_without_balls : bool
        Also simulate the same rotor with the balls removed.
    release_time_s : float, optional
        Hold the balls at their initial places on the race until this time (s), then let
        them go (Rodrigues et al.'s remedy for run-up: clamp the balls until the speed is
        supercritical).  Default: free from the start.

    Returns
    -------
    SimulationResult
    """
    if not isinstance(params, ADBParameters):
        raise ParameterError(f"params: got {type(params).__name__}; expected ADBParameters")
    t_end = finite_positive("t_end_s", t_end_s, "a finite time > 0 s")
    if not 0.0 < final_window_fraction <= 1.0:
        raise ParameterError(f"final_window_fraction = {final_window_fraction!r}: expected 0 < fraction <= 1")
    if not 0.0 < settle_tolerance < 1.0:
        raise ParameterError(f"settle_tolerance = {settle_tolerance!r}: expected 0 < tolerance < 1")
    profile = as_speed_profile(speed)
    speeds = check_profile(profile, t_end)
    max_speed = float(np.max(np.abs(speeds)))
    if frame == "auto":
        frame = "rotating" if isinstance(profile, ConstantSpeed) else "fixed"
    n = params.n
    angles = _initial_ball_angles(params, initial_ball_angles_rad)
    rates = np.zeros(n) if initial_ball_rates_rad_s is None else np.asarray(initial_ball_rates_rad_s, dtype=float).reshape(-1)
    if rates.shape != (n,) or not np.all(np.isfinite(rates)):
        raise ParameterError(f"initial_ball_rates_rad_s = {initial_ball_rates_rad_s!r}: expected {n} finite rates (rad/s)")
    position = _pair(initial_rotor_position_m, "initial_rotor_position_m")
    velocity = _pair(initial_rotor_velocity_m_s, "initial_rotor_velocity_m_s")
    speed0 = float(speeds[0])
    times = _sample_times(t_end, n_samples, max_speed)
    y0 = _initial_state(n, angles, position, velocity, rates, frame, speed0)
    if release_time_s is None:
        run = integrate(params, profile, y0, times, frame=frame, method=method, rtol=rtol)
    else:
        release = float(release_time_s)
        if not (math.isfinite(release) and 0.0 < release < t_end):
            raise ParameterError(f"release_time_s = {release_time_s!r}: expected 0 < release_time_s < t_end_s = {t_end}")
        if np.any(rates != 0.0):
            raise ParameterError("initial_ball_rates_rad_s: expected zeros when the balls start clamped (release_time_s)")
        run = _integrate_clamped_then_free(params, profile, y0, times, release, frame, method, rtol)
    x, y, u, v, phi, dphi, theta, omega = _fixed_outputs(run, profile, n)
    amplitude = np.hypot(x, y)
    window_start = t_end * (1.0 - final_window_fraction)
    window = run.time_s >= window_start
    settle = settling_time(params, run.time_s, phi, settle_tolerance)
    final_state, slip = classify_final_state(params, run.time_s, phi, dphi, window_start_s=window_start,
                                             final_speed_rad_s=float(omega[-1]), tolerance=settle_tolerance)
    target = balanced_ball_angles(params) if params.can_balance and (n >= 2 or math.isclose(params.unbalance_ratio, 1.0)) else np.zeros(0)
    empty = np.zeros(0)
    x0 = y0n = a0 = empty
    residual0 = math.nan
    if compare_without_balls:
        x0, y0n, a0, residual0 = _without_balls(params, profile, frame, position, velocity, speed0, times, rtol, window)
    return SimulationResult(
        time_s=run.time_s, speed_rad_s=omega, rotor_angle_rad=theta,
        rotor_x_m=x, rotor_y_m=y, rotor_u_m=u, rotor_v_m=v, amplitude_m=amplitude,
        ball_angles_rad=phi, ball_rates_rad_s=dphi, balanced_ball_angles_rad=target,
        settled=bool(math.isfinite(settle)), settling_time_s=settle,
        residual_amplitude_m=float(np.max(amplitude[window])),
        final_state=final_state, final_slip_rate_rad_s=slip,
        amplitude_without_balls_m=a0, rotor_x_without_balls_m=x0, rotor_y_without_balls_m=y0n,
        residual_amplitude_without_balls_m=residual0,
        compared_without_balls=bool(compare_without_balls),
        window_start_s=window_start, settle_tolerance=float(settle_tolerance),
        frame=frame, method=run.method, rtol=float(rtol),
        n_function_evaluations=run.n_function_evaluations, n_jacobian_evaluations=run.n_jacobian_evaluations,
    )


def _integrate_clamped_then_free(params, profile, y0, times, release, frame, method, rtol) -> IntegrationResult:
    """Balls held on the race until ``release`` (rigid point masses), then free."""
    n = params.n
    clamped = scalar_rhs(params.M, params.m, n, params.R, params.e, params.k, params.c, params.D,
                         frame=frame, clamped=True)
    constant = isinstance(profile, ConstantSpeed)

    def fun(t, y):
        if constant:
            return clamped(y, profile.speed, 0.0)
        omega, alpha = float(profile.speed_rad_s(t)), float(profile.acceleration_rad_s2(t))
        if not (math.isfinite(omega) and math.isfinite(alpha)):
            raise ParameterError(f"speed profile is not finite at t = {t!r} s: expected finite values")
        return clamped(y, omega, alpha)

    batch = ParameterBatch.from_parameters(params)
    max_speed = float(np.max(np.abs(profile.speed_rad_s(times)))) if not constant else abs(profile.speed)
    atol = _absolute_tolerances(batch, rtol, max_speed, frame == "fixed")
    before = times[times <= release]
    from scipy.integrate import solve_ivp  # imported when used: a plotting process unpickles these results

    first = solve_ivp(fun, (times[0], release), y0, method="DOP853",
                      t_eval=np.append(before, release) if before[-1] < release else before, rtol=rtol, atol=atol)
    if first.status != 0:
        raise ParameterError(f"integration with clamped balls failed: {first.message}")
    after = times[times > release]
    second = integrate(params, profile, first.y[:, -1], np.concatenate([[release], after]), frame=frame,
                       method=method, rtol=rtol)
    states = np.concatenate([first.y.T[: before.size], second.states[0, 1:]], axis=0)[None]
    return IntegrationResult(
        time_s=times, states=states, frame=frame, method=second.method,
        n_function_evaluations=int(first.nfev) + second.n_function_evaluations,
        n_jacobian_evaluations=second.n_jacobian_evaluations, rtol=second.rtol,
    )


#: Gauss-Legendre nodes per panel of the exact rotor response (error ~ (h/2)^16 / 16! in the
#: phase and decay per panel, h <= _PANEL_RAD: far below rounding)
_GAUSS_NODES = 8
_PANEL_RAD = 0.5


def _rotor_angle(profile, t: np.ndarray) -> np.ndarray:
    """``theta(t) = integral_0^t omega`` (rad) of a constant speed or a linear run-up."""
    if isinstance(profile, ConstantSpeed):
        return profile.speed * t
    t0, duration = profile.start_time_s, profile.duration_s
    w0, rate = profile.start_speed, profile.rate_rad_s2

    def from_start(time):
        tau = np.asarray(time, dtype=float) - t0
        inside = np.clip(tau, 0.0, duration)
        return w0 * np.minimum(tau, 0.0) + w0 * inside + 0.5 * rate * inside**2 + profile.end_speed * np.maximum(
            tau - duration, 0.0)

    return from_start(t) - from_start(0.0)


def _without_balls_exact(params, profile, position, velocity, times):
    """Rotor without balls along a constant speed or a linear run-up, by its two modes.

    ``z = x + i y`` obeys ``z'' + (c/M) z' + (k/M) z = e (omega^2 - i omega') e^{i theta}``: with
    the roots ``lambda_1,2`` of ``s^2 + (c/M) s + k/M``, ``z = p1 + p2`` and
    ``p_j' = lambda_j p_j +- g / (lambda_1 - lambda_2)``, advanced exactly from sample to sample
    (``p <- e^{lambda h} p + integral e^{lambda (t - tau)} g(tau) dtau``); the integrals by
    Gauss-Legendre on panels no longer than ``_PANEL_RAD`` in phase and decay, split at the
    run-up's kinks.  Returns None where the roots nearly coincide (critical damping).
    """
    M, k, c, e = params.M, params.k, params.c, params.e
    roots = np.roots([1.0, c / M, k / M]).astype(complex)
    l1, l2 = complex(roots[0]), complex(roots[1])
    d = l1 - l2
    if abs(d) < 1e-6 * max(abs(l1), abs(l2)):
        return None
    t = np.asarray(times, dtype=float)
    breaks = [] if isinstance(profile, ConstantSpeed) else [profile.start_time_s,
                                                             profile.start_time_s + profile.duration_s]
    edges = np.unique(np.concatenate([t, [b for b in breaks if t[0] < b < t[-1]]]))
    owner = np.searchsorted(t, edges[:-1], side="right") - 1  # sample interval of each piece
    rate = max(abs(l1), abs(l2), float(np.max(np.abs(profile.speed_rad_s(t)))), 1e-300)
    pieces = np.maximum(1, np.ceil(np.diff(edges) * rate / _PANEL_RAD).astype(int))
    # panels: each piece cut into equal parts
    index = np.repeat(np.arange(pieces.size), pieces)
    part = np.arange(index.size) - np.repeat(np.cumsum(pieces) - pieces, pieces)
    width = np.diff(edges)[index] / pieces[index]
    left = edges[:-1][index] + part * width
    nodes, weights = np.polynomial.legendre.leggauss(_GAUSS_NODES)
    tau = left[:, None] + 0.5 * width[:, None] * (nodes[None, :] + 1.0)
    omega = np.asarray(profile.speed_rad_s(tau), dtype=float)
    alpha = np.asarray(profile.acceleration_rad_s2(tau), dtype=float)
    if not isinstance(profile, ConstantSpeed):  # inside a panel the ramp rate is one value
        mid = left + 0.5 * width
        alpha = np.broadcast_to(np.asarray(profile.acceleration_rad_s2(mid), dtype=float)[:, None], tau.shape)
    g = e * (omega**2 - 1j * alpha) * np.exp(1j * _rotor_angle(profile, tau))
    end = t[owner[index] + 1][:, None]  # the sample each panel's integral is carried to
    steps = []
    for lam, sign in ((l1, 1.0), (l2, -1.0)):
        panel = (0.5 * width) * np.sum(weights * np.exp(lam * (end - tau)) * g, axis=1) * (sign / d)
        increment = np.zeros(t.size - 1, dtype=complex)
        np.add.at(increment, owner[index], panel)
        steps.append((np.exp(lam * np.diff(t)), increment))
    z0 = complex(position[0], position[1])
    v0 = complex(velocity[0], velocity[1])
    q1 = (v0 - l2 * z0) / d
    q2 = z0 - q1
    (a1, b1), (a2, b2) = ((a.tolist(), b.tolist()) for a, b in steps)
    out = [z0]
    for i in range(t.size - 1):  # a first-order recurrence: plain complex floats are fastest
        q1 = a1[i] * q1 + b1[i]
        q2 = a2[i] * q2 + b2[i]
        out.append(q1 + q2)
    z = np.array(out)
    return z.real, z.imag


def _without_balls(params, profile, frame, position, velocity, speed0, times, rtol, window):
    """The same rotor (mass M) with the balls removed: the n = 0 case of the equations.

    Along a constant speed or a linear run-up the response is the exact modal solution
    (:func:`_without_balls_exact`); otherwise DOP853 (:func:`scipy.integrate.solve_ivp`).
    """
    if isinstance(profile, (ConstantSpeed, LinearRunUp)):
        exact = _without_balls_exact(params, profile, position, velocity, times)
        if exact is not None:
            x, y = exact
            amplitude = np.hypot(x, y)
            return x, y, amplitude, float(np.max(amplitude[window]))
    bare = scalar_rhs(params.M, params.m, 0, params.R, params.e, params.k, params.c, 0.0, frame=frame)
    wn = math.sqrt(params.k / params.M)
    max_speed = float(np.max(np.abs(profile.speed_rad_s(times)))) if frame == "fixed" else abs(profile.speed)
    rate = max(wn, max_speed)
    position_tol = 1e-3 * rtol * params.R
    if frame == "rotating":
        y0 = _initial_state(0, np.zeros(0), position, velocity, np.zeros(0), "rotating", speed0)
        atol = np.array([position_tol, position_tol, position_tol * rate, position_tol * rate])

        def fun(t, y):
            return bare(y, profile.speed, 0.0)
    else:
        y0 = _initial_state(0, np.zeros(0), position, velocity, np.zeros(0), "fixed", speed0)
        atol = np.array([position_tol, position_tol, position_tol * rate, position_tol * rate, rtol])

        def fun(t, y):
            return bare(y, float(profile.speed_rad_s(t)), float(profile.acceleration_rad_s2(t)))
    from scipy.integrate import solve_ivp

    solution = solve_ivp(fun, (times[0], times[-1]), y0, method="DOP853", t_eval=times, rtol=rtol, atol=atol)
    if solution.status != 0:
        raise ParameterError(f"integration without balls failed: {solution.message}")
    states = solution.y.T
    if frame == "rotating":
        theta = profile.speed * times
        c, s = np.cos(theta), np.sin(theta)
        x = states[:, 0] * c - states[:, 1] * s
        y = states[:, 0] * s + states[:, 1] * c
    else:
        x, y = states[:, 0], states[:, 1]
    amplitude = np.hypot(x, y)
    return x, y, amplitude, float(np.max(amplitude[window]))


@dataclass(frozen=True, slots=True)
class BatchSimulationResult:
    """A batch of runs integrated as one stacked system.

    Attributes
    ----------
    time_s : ndarray, shape (T,)
        Sample times (s).
    rotor_x_m, rotor_y_m : ndarray, shape (B, T)
        Rotor centres in the fixed frame (m).
    ball_angles_rad : ndarray, shape (B, T, n)
        Ball angles relative to the unbalance (rad).
    settling_time_s : ndarray, shape (B,)
        Settling times (s); inf where not settled.
    residual_amplitude_m : ndarray, shape (B,)
        Largest amplitude over the final window (m).
    final_state : tuple of str
        Final-state class of each member.
    method : str
        Integrator.
    rtol : float
        Per-member relative tolerance requested.
    n_function_evaluations : int
        Evaluations of the stacked right-hand side.
    """

    time_s: np.ndarray
    rotor_x_m: np.ndarray
    rotor_y_m: np.ndarray
    ball_angles_rad: np.ndarray
    settling_time_s: np.ndarray
    residual_amplitude_m: np.ndarray
    final_state: tuple[str, ...]
    method: str
    rtol: float
    n_function_evaluations: int


def simulate_batch(
    params: Sequence[ADBParameters],
    speed: Any,
    t_end_s: float,
    initial_ball_angles_rad=None,
    *,
    method: str = "auto",
    rtol: float = 1e-9,
    n_samples: int = 201,
    settle_tolerance: float = 0.01,
    final_window_fraction: float = 0.1,
) -> BatchSimulationResult:
    """Simulate many parameter sets (common ``n``) as one stacked system, rotor starting at rest.

    Parameters
    ----------
    params : sequence of ADBParameters
        The batch (common ball count).
    speed : float, callable or SpeedProfile
        Shaft speed (rad/s) or profile, common to the batch.
    t_end_s : float
        Duration (s).
    initial_ball_angles_rad : array_like, shape (n,) or (B, n), optional
        Initial ball angles relative to the unbalance (rad); default as :func:`simulate`.
    method : str
        "auto" or a ``solve_ivp`` method.
    rtol : float
        Relative tolerance per member (the stacked system uses ``rtol / sqrt(B)``).
    n_samples : int
        Output samples.
    settle_tolerance, final_window_fraction : float
        As in :func:`simulate`.

    Returns
    -------
    BatchSimulationResult
    """
    members = list(params)
    batch = ParameterBatch.from_parameters(members)
    n = batch.n
    t_end = finite_positive("t_end_s", t_end_s, "a finite time > 0 s")
    profile = as_speed_profile(speed)
    speeds = check_profile(profile, t_end)
    frame = "rotating" if isinstance(profile, ConstantSpeed) else "fixed"
    if initial_ball_angles_rad is None:
        angles = np.broadcast_to(default_initial_ball_angles(n), (batch.size, n))
    else:
        angles = np.broadcast_to(np.asarray(initial_ball_angles_rad, dtype=float), (batch.size, n))
        if not np.all(np.isfinite(angles)):
            raise ParameterError("initial_ball_angles_rad: expected finite angles (rad)")
    y0 = np.array([_initial_state(n, a, (0.0, 0.0), (0.0, 0.0), np.zeros(n), frame, float(speeds[0])) for a in angles])
    times = _sample_times(t_end, n_samples, float(np.max(np.abs(speeds))))
    run = integrate(members, profile, y0, times, frame=frame, method=method, rtol=rtol)
    window_start = t_end * (1.0 - final_window_fraction)
    window = run.time_s >= window_start
    xs, ys, phis, settles, residuals, finals = [], [], [], [], [], []
    for index, member in enumerate(members):
        x, y, _, _, phi, dphi, _, omega = _fixed_outputs(run, profile, n, index)
        xs.append(x)
        ys.append(y)
        phis.append(phi)
        settles.append(settling_time(member, run.time_s, phi, settle_tolerance))
        residuals.append(float(np.max(np.hypot(x, y)[window])))
        finals.append(classify_final_state(member, run.time_s, phi, dphi, window_start_s=window_start,
                                           final_speed_rad_s=float(omega[-1]), tolerance=settle_tolerance)[0])
    return BatchSimulationResult(
        time_s=run.time_s, rotor_x_m=np.array(xs), rotor_y_m=np.array(ys), ball_angles_rad=np.array(phis),
        settling_time_s=np.array(settles), residual_amplitude_m=np.array(residuals), final_state=tuple(finals),
        method=run.method, rtol=float(rtol), n_function_evaluations=run.n_function_evaluations,
    )
