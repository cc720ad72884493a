"""Equations of motion of the Jeffcott rotor with n balls, batched over parameter sets.

Two formulations of the same Lagrangian model (``adb.md`` sections 1a and 1b):

* **rotating frame** (spinning with the shaft, angle ``theta(t)``): state
  ``[u, v, phi_1..phi_n, u', v', phi_1'..phi_n']`` of length ``4 + 2n``, where ``u + i v`` is
  the rotor centre's displacement seen from the shaft and ``phi_i = b_i - theta`` the
  ball angles relative to the unbalance direction.  At constant speed the system is
  autonomous and the balanced state is a fixed point.
* **fixed frame** (Cartesian, inertial): state
  ``[x, y, phi_1..phi_n, x', y', phi_1'..phi_n', theta]`` of length ``5 + 2n``.  The ball
  angles are still kept relative to the unbalance (so they do not grow like ``omega t``
  and keep their accuracy over long runs); the last component is the rotor angle.

The ball accelerations are eliminated analytically (arrowhead mass matrix): each
evaluation solves one 2x2 system per parameter set by Cramer's rule, whose determinant
is ``M (M + n m) + m^2 (sum s sum c - (sum s c)^2) >= M (M + n m) > 0``.  Every formula uses
only arithmetic, ``sin`` and ``cos``, so a complex state gives the complex-step
derivative: the Jacobians below are exact to rounding.

Shapes: ``state`` is ``(..., N)``; parameter arrays (a :class:`ParameterBatch`) and the
speed broadcast against ``state[..., 0]``.
"""
from __future__ import annotations

import numpy as np

from .parameters import ParameterBatch

__all__ = [
    "rotating_state_size",
    "fixed_state_size",
    "rotating_frame_rhs",
    "fixed_frame_rhs",
    "complex_step_jacobian",
    "rotating_frame_jacobian",
    "fixed_frame_jacobian",
    "rotating_to_fixed",
    "fixed_to_rotating",
    "scalar_rhs",
    "COMPLEX_STEP_H",
]

COMPLEX_STEP_H = 1e-30
"""Complex step (in state units); any value far below rounding of the state works."""


def rotating_state_size(n: int) -> int:
    """Length of the rotating-frame state for ``n`` balls: ``4 + 2n``.

    Parameters
    ----------
    n : int
        Number of balls.
    """
    return 4 + 2 * n


def fixed_state_size(n: int) -> int:
    """Length of the fixed-frame state for ``n`` balls: ``5 + 2n`` (last entry: rotor angle).

    Parameters
    ----------
    n : int
        Number of balls.
    """
    return 5 + 2 * n


def _accelerations(
    px, py, vx, vy, ball_angle_in_frame, relative_rate,
    unbalance_cos, unbalance_sin, frame_speed, frame_acceleration,
    speed, acceleration, p: ParameterBatch,
):
    """Rotor and relative ball accelerations in a frame turning at ``frame_speed``.

    All inputs broadcast; ball arrays carry the ball index last.  Returns
    ``(ax, ay, phi_ddot)`` in the frame.
    """
    M, m, R, e, k, c, D = p.M, p.m, p.R, p.e, p.k, p.c, p.D
    total = M + p.n * m
    nu, nu_dot = frame_speed, frame_acceleration
    s = np.sin(ball_angle_in_frame)
    co = np.cos(ball_angle_in_frame)
    # Transport part of the rotor's absolute acceleration seen in the frame:
    # A0 = 2 i nu w' + i nu' w - nu^2 w
    a0x = -2.0 * nu * vy - nu_dot * py - nu * nu * px
    a0y = 2.0 * nu * vx + nu_dot * px - nu * nu * py
    mb = m[..., None]
    Rb = R[..., None]
    # Ball equation without the unknown rotor acceleration:
    # b'' = h - (ay c - ax s) / R,  h = -D phi'/(m R^2) - Im(A0 e^{-i beta}) / R
    h = -(D[..., None] / (mb * Rb * Rb)) * relative_rate - (a0y[..., None] * co - a0x[..., None] * s) / Rb
    ball_speed = speed[..., None] + relative_rate
    ball_force = ball_speed * ball_speed
    mR = m * R
    unbalance = M * e
    fx = (
        -c * (vx - nu * py) - k * px
        + unbalance * (speed * speed * unbalance_cos + acceleration * unbalance_sin)
        + mR * np.sum(ball_force * co + h * s, axis=-1)
        - total * a0x
    )
    fy = (
        -c * (vy + nu * px) - k * py
        + unbalance * (speed * speed * unbalance_sin - acceleration * unbalance_cos)
        + mR * np.sum(ball_force * s - h * co, axis=-1)
        - total * a0y
    )
    a11 = total - m * np.sum(s * s, axis=-1)
    a22 = total - m * np.sum(co * co, axis=-1)
    a12 = m * np.sum(s * co, axis=-1)
    det = a11 * a22 - a12 * a12
    ax = (a22 * fx - a12 * fy) / det
    ay = (a11 * fy - a12 * fx) / det
    ball_abs_acc = h - (ay[..., None] * co - ax[..., None] * s) / Rb
    phi_ddot = ball_abs_acc - acceleration[..., None]
    return ax, ay, phi_ddot


def _as_float_array(value, like):
    return np.asarray(value, dtype=float) + np.zeros(like.shape[:-1])


def rotating_frame_rhs(state, params: ParameterBatch, speed_rad_s, acceleration_rad_s2=0.0):
    """Time derivative of the rotating-frame state.

    Parameters
    ----------
    state : ndarray, shape (..., 4 + 2n)
        ``[u, v, phi_i, u', v', phi_i']`` in m, rad, m/s, rad/s (real or complex).
    params : ParameterBatch
        Arrays broadcasting against ``state[..., 0]``.
    speed_rad_s : float or ndarray
        Shaft speed ``omega`` (rad/s), broadcasting against ``state[..., 0]``.
    acceleration_rad_s2 : float or ndarray
        Shaft angular acceleration ``omega'`` (rad/s^2).

    Returns
    -------
    ndarray, shape (..., 4 + 2n)
        ``d state / dt``.
    """
    n = params.n
    u, v = state[..., 0], state[..., 1]
    phi = state[..., 2:2 + n]
    du, dv = state[..., 2 + n], state[..., 3 + n]
    dphi = state[..., 4 + n:4 + 2 * n]
    speed = _as_float_array(speed_rad_s, state)
    acceleration = _as_float_array(acceleration_rad_s2, state)
    ax, ay, phi_ddot = _accelerations(
        u, v, du, dv, phi, dphi, 1.0, 0.0, speed, acceleration, speed, acceleration, params
    )
    out = np.empty_like(state)
    out[..., 0] = du
    out[..., 1] = dv
    out[..., 2:2 + n] = dphi
    out[..., 2 + n] = ax
    out[..., 3 + n] = ay
    out[..., 4 + n:4 + 2 * n] = phi_ddot
    return out


def fixed_frame_rhs(state, params: ParameterBatch, speed_rad_s, acceleration_rad_s2=0.0):
    """Time derivative of the fixed-frame state.

    Parameters
    ----------
    state : ndarray, shape (..., 5 + 2n)
        ``[x, y, phi_i, x', y', phi_i', theta]`` in m, rad, m/s, rad/s, rad (real or complex);
        ``phi_i`` are ball angles relative to the unbalance, ``theta`` the rotor angle.
    params : ParameterBatch
        Arrays broadcasting against ``state[..., 0]``.
    speed_rad_s : float or ndarray
        Shaft speed ``theta'`` (rad/s) at this time.
    acceleration_rad_s2 : float or ndarray
        Shaft angular acceleration ``theta''`` (rad/s^2) at this time.

    Returns
    -------
    ndarray, shape (..., 5 + 2n)
        ``d state / dt``.
    """
    n = params.n
    x, y = state[..., 0], state[..., 1]
    phi = state[..., 2:2 + n]
    dx, dy = state[..., 2 + n], state[..., 3 + n]
    dphi = state[..., 4 + n:4 + 2 * n]
    theta = state[..., 4 + 2 * n]
    speed = _as_float_array(speed_rad_s, state)
    acceleration = _as_float_array(acceleration_rad_s2, state)
    zero = np.zeros_like(speed)
    ax, ay, phi_ddot = _accelerations(
        x, y, dx, dy, phi + theta[..., None], dphi, np.cos(theta), np.sin(theta),
        zero, zero, speed, acceleration, params,
    )
    out = np.empty_like(state)
    out[..., 0] = dx
    out[..., 1] = dy
    out[..., 2:2 + n] = dphi
    out[..., 2 + n] = ax
    out[..., 3 + n] = ay
    out[..., 4 + n:4 + 2 * n] = phi_ddot
    out[..., 4 + 2 * n] = speed
    return out


def complex_step_jacobian(fun, state, h: float = COMPLEX_STEP_H):
    """Jacobian ``d fun / d state`` by the complex step, exact to rounding.

    Parameters
    ----------
    fun : callable
        ``fun(z)`` with ``z`` of shape ``(B, N, N)`` (complex) returning the same shape; the
        leading axis is the batch, the middle axis the perturbed column.
    state : ndarray, shape (B, N)
        Real state at which to differentiate.
    h : float
        Complex step (state units).

    Returns
    -------
    ndarray, shape (B, N, N)
        ``J[b, i, j] = d f_i / d y_j``.
    """
    state = np.asarray(state, dtype=float)
    size = state.shape[-1]
    perturbed = state[:, None, :] + 1j * h * np.eye(size)[None, :, :]
    values = fun(perturbed)  # (B, N_pert, N)
    return np.swapaxes(values.imag / h, -1, -2)


def rotating_frame_jacobian(state, params: ParameterBatch, speed_rad_s, acceleration_rad_s2=0.0):
    """Exact Jacobian of :func:`rotating_frame_rhs` (complex step), shape ``(B, N, N)``.

    Parameters
    ----------
    state : ndarray, shape (B, 4 + 2n)
        States (one per batch member), SI units.
    params : ParameterBatch
        Batch of ``B`` parameter sets (arrays of shape ``(B,)``).
    speed_rad_s, acceleration_rad_s2 : float or ndarray of shape (B,)
        Shaft speed (rad/s) and acceleration (rad/s^2).
    """
    state = np.atleast_2d(state)
    batch = state.shape[0]
    col = params.reshaped((params.size, 1))
    speed = np.broadcast_to(np.asarray(speed_rad_s, dtype=float), (batch,))[:, None]
    acc = np.broadcast_to(np.asarray(acceleration_rad_s2, dtype=float), (batch,))[:, None]
    return complex_step_jacobian(lambda z: rotating_frame_rhs(z, col, speed, acc), state)


def fixed_frame_jacobian(state, params: ParameterBatch, speed_rad_s, acceleration_rad_s2=0.0):
    """Exact Jacobian of :func:`fixed_frame_rhs` (complex step), shape ``(B, N, N)``.

    Parameters
    ----------
    state : ndarray, shape (B, 5 + 2n)
        States (one per batch member), SI units.
    params : ParameterBatch
        Batch of ``B`` parameter sets.
    speed_rad_s, acceleration_rad_s2 : float or ndarray of shape (B,)
        Shaft speed (rad/s) and acceleration (rad/s^2) at the time of evaluation.
    """
    state = np.atleast_2d(state)
    batch = state.shape[0]
    col = params.reshaped((params.size, 1))
    speed = np.broadcast_to(np.asarray(speed_rad_s, dtype=float), (batch,))[:, None]
    acc = np.broadcast_to(np.asarray(acceleration_rad_s2, dtype=float), (batch,))[:, None]
    return complex_step_jacobian(lambda z: fixed_frame_rhs(z, col, speed, acc), state)


def rotating_to_fixed(state, theta_rad, speed_rad_s, n: int):
    """Convert rotating-frame states to fixed-frame states (appending the rotor angle).

    Parameters
    ----------
    state : ndarray, shape (..., 4 + 2n)
        Rotating-frame states.
    theta_rad : float or ndarray
        Rotor angle (rad) at the same instants, broadcasting against ``state[..., 0]``.
    speed_rad_s : float or ndarray
        Shaft speed (rad/s) at the same instants.
    n : int
        Ball count.
    """
    theta = np.asarray(theta_rad, dtype=float)
    omega = np.asarray(speed_rad_s, dtype=float)
    u, v = state[..., 0], state[..., 1]
    du, dv = state[..., 2 + n], state[..., 3 + n]
    cos, sin = np.cos(theta), np.sin(theta)
    # z = w e^{i theta};  z' = (w' + i omega w) e^{i theta}
    wx, wy = du - omega * v, dv + omega * u
    out = np.empty(state.shape[:-1] + (fixed_state_size(n),), dtype=np.result_type(state, float))
    out[..., 0] = u * cos - v * sin
    out[..., 1] = u * sin + v * cos
    out[..., 2:2 + n] = state[..., 2:2 + n]
    out[..., 2 + n] = wx * cos - wy * sin
    out[..., 3 + n] = wx * sin + wy * cos
    out[..., 4 + n:4 + 2 * n] = state[..., 4 + n:4 + 2 * n]
    out[..., 4 + 2 * n] = theta
    return out


def fixed_to_rotating(state, speed_rad_s, n: int):
    """Convert fixed-frame states to rotating-frame states (dropping the rotor angle).

    Parameters
    ----------
    state : ndarray, shape (..., 5 + 2n)
        Fixed-frame states (last entry: rotor angle, rad).
    speed_rad_s : float or ndarray
        Shaft speed (rad/s) at the same instants.
    n : int
        Ball count.
    """
    omega = np.asarray(speed_rad_s, dtype=float)
    theta = state[..., 4 + 2 * n]
    cos, sin = np.cos(theta), np.sin(theta)
    x, y = state[..., 0], state[..., 1]
    dx, dy = state[..., 2 + n], state[..., 3 + n]
    u = x * cos + y * sin
    v = -x * sin + y * cos
    # w' = z' e^{-i theta} - i omega w
    zx = dx * cos + dy * sin
    zy = -dx * sin + dy * cos
    out = np.empty(state.shape[:-1] + (rotating_state_size(n),), dtype=np.result_type(state, float))
    out[..., 0] = u
    out[..., 1] = v
    out[..., 2:2 + n] = state[..., 2:2 + n]
    out[..., 2 + n] = zx + omega * v
    out[..., 3 + n] = zy - omega * u
    out[..., 4 + n:4 + 2 * n] = state[..., 4 + n:4 + 2 * n]
    return out


def scalar_rhs(M: float, m: float, n: int, R: float, e: float, k: float, c: float, D: float, *, frame: str,
               clamped: bool = False):
    """Right-hand side for a single parameter set in plain Python floats (fast for small n).

    Same equations as :func:`rotating_frame_rhs` / :func:`fixed_frame_rhs` (tested equal to
    rounding); numpy's per-call overhead dominates for one small system, so ``solve_ivp``
    runs of a single set use this instead.  ``n = 0`` gives the rotor without balls.

    Parameters
    ----------
    M, m, n, R, e, k, c, D : float, float, int, float, float, float, float, float
        As in :class:`~balancer.adb.ADBParameters` (SI).
    frame : {"rotating", "fixed"}
        Formulation (state layouts as in this module).
    clamped : bool
        Balls held at their places on the race (``phi' = phi'' = 0``): the rotor then carries
        them as rigid point masses, ``(M + n m) z'' = ... + m R sum (omega^2 - i omega') e^{i b}``.

    Returns
    -------
    callable
        ``f(y, speed_rad_s, acceleration_rad_s2) -> ndarray``.
    """
    import math

    total = M + n * m
    mR = m * R
    unbalance = M * e
    drag = D / (m * R * R) if m > 0 else 0.0
    inv_R = 1.0 / R
    rotating = frame == "rotating"
    size = 4 + 2 * n + (0 if rotating else 1)
    sin, cos = math.sin, math.cos

    def rhs(state, omega: float, alpha: float):
        y = state.tolist()
        px, py, vx, vy = y[0], y[1], y[2 + n], y[3 + n]
        if rotating:
            nu, nu_dot, uc, us, offset = omega, alpha, 1.0, 0.0, 0.0
        else:
            theta = y[4 + 2 * n]
            nu, nu_dot, uc, us, offset = 0.0, 0.0, cos(theta), sin(theta), theta
        a0x = -2.0 * nu * vy - nu_dot * py - nu * nu * px
        a0y = 2.0 * nu * vx + nu_dot * px - nu * nu * py
        sum_x = sum_y = s_ss = s_cc = s_sc = 0.0
        balls = []
        if clamped:
            for i in range(n):
                b = y[2 + i] + offset
                s, co = sin(b), cos(b)
                sum_x += omega * omega * co + alpha * s
                sum_y += omega * omega * s - alpha * co
            fx = (-c * (vx - nu * py) - k * px + unbalance * (omega * omega * uc + alpha * us)
                  + mR * sum_x - total * a0x)
            fy = (-c * (vy + nu * px) - k * py + unbalance * (omega * omega * us - alpha * uc)
                  + mR * sum_y - total * a0y)
            out = [0.0] * size
            out[0], out[1], out[2 + n], out[3 + n] = vx, vy, fx / total, fy / total
            if not rotating:
                out[4 + 2 * n] = omega
            return np.array(out)
        for i in range(n):
            b = y[2 + i] + offset
            s, co = sin(b), cos(b)
            rate = y[4 + n + i]
            h = -drag * rate - (a0y * co - a0x * s) * inv_R
            speed = omega + rate
            force = speed * speed
            sum_x += force * co + h * s
            sum_y += force * s - h * co
            s_ss += s * s
            s_cc += co * co
            s_sc += s * co
            balls.append((s, co, h))
        fx = (-c * (vx - nu * py) - k * px + unbalance * (omega * omega * uc + alpha * us)
              + mR * sum_x - total * a0x)
        fy = (-c * (vy + nu * px) - k * py + unbalance * (omega * omega * us - alpha * uc)
              + mR * sum_y - total * a0y)
        a11 = total - m * s_ss
        a22 = total - m * s_cc
        a12 = m * s_sc
        det = a11 * a22 - a12 * a12
        ax = (a22 * fx - a12 * fy) / det
        ay = (a11 * fy - a12 * fx) / det
        out = [0.0] * size
        out[0], out[1], out[2 + n], out[3 + n] = vx, vy, ax, ay
        for i, (s, co, h) in enumerate(balls):
            out[2 + i] = y[4 + n + i]
            out[4 + n + i] = h - (ay * co - ax * s) * inv_R - alpha
        if not rotating:
            out[4 + 2 * n] = omega
        return np.array(out)

    return rhs
