"""Equilibria of the rotating-frame equations at constant speed, with their stability.

*Balanced states* (rotor centre on the axis, ``w = 0``): ``sum cos phi_i = -a`` and
``sum sin phi_i = 0`` with ``a = M e / (m R)``.  They exist only if ``a <= n``.

* ``n = 1``: only if ``a = 1`` (ball opposite the unbalance).
* ``n = 2``: ``phi = +-arccos(-a / 2)``, unique up to swapping the balls.
* ``n >= 3``: an (n-2)-dimensional family.  Choose any ``n - 2`` angles freely; the last
  two unit vectors must add up to ``S = -a - sum_free e^{i phi}``, which needs ``|S| <= 2``,
  and then ``phi = arg S +- arccos(|S| / 2)``.  The *symmetric member* has the balls
  equally spaced by ``delta`` and centred opposite the unbalance, with
  ``sin(n delta / 2) / sin(delta / 2) = a``, ``0 <= delta <= 2 pi / n``.

*Unbalanced states* (``w = rho R e^{i gamma}``, ``rho > 0``): every ball lies on the line of the
deflection, ``p`` at ``gamma`` and ``n - p`` at ``gamma + pi``; with ``q = 2p - n`` and
``P = 1 - Omega^2 + 2 i zeta Omega``,
``|P|^2 rho^2 - 2 Re(P) mu Omega^2 q rho + Omega^4 (mu^2 q^2 - eps^2) = 0`` and
``gamma = -arg(P rho - mu Omega^2 q)`` (``adb.md`` section 2).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from modal.errors import ParameterError

from .._checks import finite_positive
from .equations import rotating_frame_jacobian, rotating_frame_rhs, rotating_state_size
from .linear import CLASS_NAMES, eigen_analysis
from .parameters import ADBParameters, ParameterBatch

__all__ = [
    "Equilibrium",
    "symmetric_spacing_rad",
    "balanced_ball_angles",
    "balanced_state",
    "unbalanced_states",
    "find_equilibria",
]


def symmetric_spacing_rad(n: int, unbalance_ratio: float) -> float:
    """Common spacing ``delta`` (rad) of the symmetric balanced member.

    Solves ``sin(n delta / 2) / sin(delta / 2) = a`` on ``[0, 2 pi / n]``, where the left
    side (a Dirichlet kernel) falls monotonically from ``n`` to 0.

    Parameters
    ----------
    n : int
        Ball count (>= 2).
    unbalance_ratio : float
        ``a = M e / (m R)``, with ``0 <= a <= n``.
    """
    a = float(unbalance_ratio)
    if n < 2 or not 0.0 <= a <= n:
        raise ParameterError(f"unbalance ratio a = {a!r} with n = {n}: expected n >= 2 and 0 <= a <= n")
    if n == 2:
        return 2.0 * math.acos(min(1.0, a / 2.0))
    if a == n:
        return 0.0
    if a == 0.0:
        return 2.0 * math.pi / n

    def kernel(delta: float) -> float:
        return math.sin(n * delta / 2.0) / math.sin(delta / 2.0) - a

    from scipy.optimize import brentq  # imported when used: a plotting process unpickles this package's results

    return brentq(kernel, 1e-12, 2.0 * math.pi / n, xtol=1e-15, rtol=4 * np.finfo(float).eps)


def balanced_ball_angles(params: ADBParameters, free_angles_rad=None) -> np.ndarray:
    """Ball angles (rad, relative to the unbalance) of a balanced state.

    Parameters
    ----------
    params : ADBParameters
        Must satisfy ``n m R >= M e``.
    free_angles_rad : array_like of length n - 2, optional
        For ``n >= 3``: the angles of the first ``n - 2`` balls; the last two are solved
        for.  Default: the symmetric member (balls equally spaced, centred opposite the
        unbalance).  Must be omitted for ``n <= 2``.

    Returns
    -------
    ndarray, shape (n,)
        Angles in (-pi, pi]; for ``n = 2`` ``[+phi*, -phi*]`` with ``phi* = arccos(-a/2)``.

    Raises
    ------
    modal.errors.ParameterError
        If balancing is impossible or the free angles admit no balanced completion.
    """
    params.require_balancing()
    n, a = params.n, params.unbalance_ratio
    if n == 1:
        if free_angles_rad is not None:
            raise ParameterError("free_angles_rad: expected None for n = 1")
        return np.array([math.pi])
    if free_angles_rad is None:
        delta = symmetric_spacing_rad(n, a)
        offsets = (np.arange(n) - (n - 1) / 2.0) * delta
        angles = np.angle(-np.exp(1j * offsets))  # centred on pi, wrapped to (-pi, pi]
        if n == 2:
            angles = np.array([abs(angles[0]), -abs(angles[0])])
        return angles
    free = np.asarray(free_angles_rad, dtype=float).reshape(-1)
    if free.shape[0] != n - 2 or not np.all(np.isfinite(free)):
        raise ParameterError(
            f"free_angles_rad has {free.shape[0]} entries {free!r}: expected {n - 2} finite angles (n - 2)"
        )
    target = -a - np.sum(np.exp(1j * free))
    size = abs(target)
    if size > 2.0:
        raise ParameterError(
            f"free_angles_rad = {free!r}: the remaining two balls would have to cancel "
            f"|S| = {size:.6g} > 2 ball unbalances; expected free angles that leave |S| <= 2"
        )
    half = math.acos(min(1.0, size / 2.0))
    direction = np.angle(target)
    return np.concatenate([free, [direction + half, direction - half]])


def balanced_state(params: ADBParameters, ball_angles_rad=None) -> np.ndarray:
    """Rotating-frame state of a balanced equilibrium (rotor on the axis, balls at rest).

    Parameters
    ----------
    params : ADBParameters
        Parameters.
    ball_angles_rad : array_like of length n, optional
        A balanced configuration; default :func:`balanced_ball_angles` (symmetric member).
        Checked: the unbalance residual must vanish to rounding.
    """
    if ball_angles_rad is None:
        angles = balanced_ball_angles(params)
    else:
        params.require_balancing()
        angles = np.asarray(ball_angles_rad, dtype=float).reshape(-1)
        if angles.shape[0] != params.n:
            raise ParameterError(f"ball_angles_rad has {angles.shape[0]} entries: expected n = {params.n}")
        residual = abs(params.unbalance_ratio + np.sum(np.exp(1j * angles)))
        if not residual <= 1e-9 * max(1.0, params.n):
            raise ParameterError(
                f"ball_angles_rad = {angles!r} leave an unbalance residual |a + sum e^(i phi)| = "
                f"{residual:.3g}: expected a balanced configuration (residual <= 1e-9)"
            )
    state = np.zeros(rotating_state_size(params.n))
    state[2:2 + params.n] = angles
    return state


def unbalanced_states(params: ADBParameters, speed_rad_s: float) -> list[tuple[np.ndarray, int]]:
    """All equilibria with the rotor off the axis (balls on the deflection line).

    Parameters
    ----------
    params : ADBParameters
        Parameters.
    speed_rad_s : float
        Constant shaft speed (rad/s, > 0).

    Returns
    -------
    list of (ndarray, int)
        Rotating-frame state and ``p``, the number of balls on the deflection side.
    """
    speed = finite_positive("speed_rad_s", speed_rad_s, "a finite number > 0 (rad/s)")
    Om = speed / params.natural_frequency_rad_s
    zeta, mu, eps = params.damping_ratio, params.mass_ratio, params.eccentricity_ratio
    P = complex(1.0 - Om**2, 2.0 * zeta * Om)
    found = []
    for p in range(params.n + 1):
        q = 2 * p - params.n
        coeffs = [abs(P) ** 2, -2.0 * P.real * mu * Om**2 * q, Om**4 * (mu**2 * q**2 - eps**2)]
        disc = coeffs[1] ** 2 - 4.0 * coeffs[0] * coeffs[2]
        if disc < 0.0:
            continue
        roots = {(-coeffs[1] + sign * math.sqrt(disc)) / (2.0 * coeffs[0]) for sign in (1.0, -1.0)}
        for rho in sorted(roots):
            if not rho > 1e-14:
                continue
            gamma = -np.angle(P * rho - mu * Om**2 * q)
            state = np.zeros(rotating_state_size(params.n))
            state[0] = rho * params.R * math.cos(gamma)
            state[1] = rho * params.R * math.sin(gamma)
            angles = np.full(params.n, gamma + math.pi)
            angles[:p] = gamma
            state[2:2 + params.n] = np.angle(np.exp(1j * angles))
            found.append((state, p))
    return found


@dataclass(frozen=True, slots=True)
class Equilibrium:
    """One equilibrium at constant speed with its linear stability.

    Attributes
    ----------
    kind : str
        ``"balanced"`` (rotor on the axis) or ``"unbalanced"`` (balls on the deflection line).
    speed_rad_s : float
        Shaft speed (rad/s).
    state : ndarray, shape (4 + 2n,)
        Rotating-frame state (m, rad, m/s, rad/s).
    rotor_offset_m : float
        Distance of the rotor centre from the axis (m).
    ball_angles_rad : ndarray, shape (n,)
        Ball angles relative to the unbalance (rad).
    balls_on_deflection_side : int
        ``p`` for unbalanced states; ``-1`` for balanced ones.
    rhs_norm : float
        Largest scaled entry of the right-hand side at the state (should be ~ rounding).
    eigenvalues_per_s : ndarray
        Eigenvalues of the linearisation (1/s), decreasing real part (family zeros dropped).
    max_real_part_per_s : float
        Growth rate of the least stable mode (1/s).
    rounding_bound_per_s : float
        Real parts below this in magnitude are not resolved (1/s).
    stability : str
        ``"stable"``, ``"unstable"`` or ``"marginal"``.
    """

    kind: str
    speed_rad_s: float
    state: np.ndarray
    rotor_offset_m: float
    ball_angles_rad: np.ndarray
    balls_on_deflection_side: int
    rhs_norm: float
    eigenvalues_per_s: np.ndarray
    max_real_part_per_s: float
    rounding_bound_per_s: float
    stability: str


def scaled_rhs_norm(params: ADBParameters, state: np.ndarray, speed_rad_s: float) -> float:
    """Max-norm of the rotating-frame right-hand side, nondimensionalised (positions / R,
    time * omega_n), so that it can be compared with rounding (~1e-16)."""
    batch = ParameterBatch.from_parameters(params)
    rhs = rotating_frame_rhs(state[None, :], batch, speed_rad_s)[0]
    n, wn, R = params.n, params.natural_frequency_rad_s, params.R
    scale = np.concatenate([[1 / (R * wn)] * 2, [1 / wn] * n, [1 / (R * wn**2)] * 2, [1 / wn**2] * n])
    return float(np.max(np.abs(rhs * scale)))


def find_equilibria(params: ADBParameters, speed_rad_s: float, *, ball_angles_rad=None) -> tuple[Equilibrium, ...]:
    """Balanced (if possible) and unbalanced equilibria at a constant speed, with stability.

    Parameters
    ----------
    params : ADBParameters
        Parameters.
    speed_rad_s : float
        Shaft speed (rad/s, > 0).
    ball_angles_rad : array_like, optional
        Balanced member to use for ``n >= 3`` (default: the symmetric one).

    Returns
    -------
    tuple of Equilibrium
        The balanced state first (if ``n m R >= M e`` and it exists), then the unbalanced ones.
    """
    speed = finite_positive("speed_rad_s", speed_rad_s, "a finite number > 0 (rad/s)")
    entries: list[tuple[str, np.ndarray, int]] = []
    if params.can_balance and (params.n >= 2 or math.isclose(params.unbalance_ratio, 1.0, rel_tol=1e-12)):
        entries.append(("balanced", balanced_state(params, ball_angles_rad), -1))
    entries.extend(("unbalanced", state, p) for state, p in unbalanced_states(params, speed))
    if not entries:
        return ()
    states = np.array([state for _, state, _ in entries])
    batch = ParameterBatch.from_parameters([params] * len(entries))
    jac = rotating_frame_jacobian(states, batch, speed)
    drops = [max(params.n - 2, 0) if kind == "balanced" else 0 for kind, _, _ in entries]
    result = []
    for index, (kind, state, p) in enumerate(entries):
        analysis = eigen_analysis(jac[index:index + 1], params.n, params.R, params.natural_frequency_rad_s,
                                  n_zero_to_drop=drops[index])
        result.append(Equilibrium(
            kind=kind,
            speed_rad_s=speed,
            state=state,
            rotor_offset_m=float(math.hypot(state[0], state[1])),
            ball_angles_rad=state[2:2 + params.n].copy(),
            balls_on_deflection_side=p,
            rhs_norm=scaled_rhs_norm(params, state, speed),
            eigenvalues_per_s=analysis.eigenvalues_per_s[0],
            max_real_part_per_s=float(analysis.max_real_part_per_s[0]),
            rounding_bound_per_s=float(analysis.rounding_bound_per_s[0]),
            stability=CLASS_NAMES[int(analysis.stability_class[0])],
        ))
    return tuple(result)
