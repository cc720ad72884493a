"""Rigid machine body on resilient mounts: six degrees of freedom.

Model (reference note ``crank_drive.md`` section 2; seed 000 eqs. 2-3)
---------------------------------------------------------------------
Coordinates ``q = [u_x, u_y, u_z, phi_x, phi_y, phi_z]`` are the translation
[m] and small rotation [rad] of the body at its centre of gravity, in body
axes.  A point ``p`` (relative to the CG) moves by ``u + phi x p = T(p) q`` with
``T(p) = [I, -[p]x]``.  Mount ``i`` at ``p_i`` has stiffness ``diag(k_i)`` and
damping ``diag(c_i)`` along the body axes, so::

    M = diag(m I, J),  K = sum_i T_i' diag(k_i) T_i,  C = sum_i T_i' diag(c_i) T_i + C_modal

with ``J`` the 3 x 3 inertia tensor about the CG and
``C_modal = M Phi diag(2 zeta omega_r) Phi' M`` (``Phi`` mass-normalised) when a
modal damping ratio ``zeta`` is given.  A harmonic load ``Re(Q e^{i Omega t})``
gives ``X = (K - Omega^2 M + i Omega C)^-1 Q``; the force into the base is
``(K + i Omega C) X`` (its first three rows), and each mount passes
``(diag(k_i) + i Omega diag(c_i)) T_i X``.

A force ``F`` applied at ``p`` loads the CG with ``[F; p x F]``.  For the
compressor, the crank-plane axes of :mod:`balancer.compressor.crank` (x across the stroke,
y along it, z the crank axis) are taken parallel to the body axes.

Mount stiffness and damping may come from identification: any object with
attributes ``stiffness_n_per_m`` and ``damping_n_s_per_m`` (numbers, or arrays
over channels with a ``channel`` index) is accepted by
:func:`mount_from_identification`.
"""
from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from modal.errors import ParameterError

from .crank import SliderCrank, shaking_harmonics

__all__ = [
    "RigidBody",
    "Mount",
    "MountedBody",
    "MountModes",
    "HarmonicResponse",
    "BalancingComparison",
    "inertia_tensor",
    "point_transformation",
    "mass_matrix",
    "stiffness_matrix",
    "damping_matrix",
    "mount_from_identification",
    "natural_modes",
    "harmonic_response",
    "compressor_response",
    "balancing_comparison",
]

DOF_NAMES: tuple[str, ...] = ("u_x", "u_y", "u_z", "phi_x", "phi_y", "phi_z")
# K is singular when its smallest eigenvalue is below this fraction of the largest
# (after scaling rotations by a body length so units match).
_SINGULAR_RTOL = 1e-10


def _vector3(name: str, value, *, nonnegative: bool = False) -> np.ndarray:
    try:
        vec = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise ParameterError(f"{name} = {value!r}: expected 3 real numbers") from None
    if vec.ndim == 0:
        vec = np.full(3, float(vec))
    if vec.shape != (3,):
        raise ParameterError(f"{name} has shape {vec.shape}: expected 3 numbers (x, y, z)")
    if not np.all(np.isfinite(vec)):
        raise ParameterError(f"{name} = {vec.tolist()!r}: expected finite numbers")
    if nonnegative and np.any(vec < 0):
        raise ParameterError(f"{name} = {vec.tolist()!r}: expected values >= 0")
    return vec


@dataclass(frozen=True, eq=False)
class RigidBody:
    """Rigid body: mass and inertia tensor about its centre of gravity.

    Parameters
    ----------
    mass_kg : float
        Mass [kg], > 0.
    inertia_kg_m2 : array_like, shape (3, 3)
        Inertia tensor about the CG in body axes [kg m^2], symmetric positive
        definite (products of inertia enter with the tensor's sign convention).
    """

    mass_kg: float
    inertia_kg_m2: np.ndarray

    def __post_init__(self) -> None:
        mass = float(self.mass_kg) if np.isscalar(self.mass_kg) else float("nan")
        if not (math.isfinite(mass) and mass > 0):
            raise ParameterError(f"mass_kg = {self.mass_kg!r}: expected a finite value > 0")
        try:
            inertia = np.array(self.inertia_kg_m2, dtype=float)
        except (TypeError, ValueError):
            raise ParameterError(
                f"inertia_kg_m2 = {self.inertia_kg_m2!r}: expected a 3 x 3 real matrix") from None
        if inertia.shape != (3, 3) or not np.all(np.isfinite(inertia)):
            raise ParameterError(
                f"inertia_kg_m2 has shape {inertia.shape}: expected a finite 3 x 3 matrix")
        if not np.allclose(inertia, inertia.T, rtol=1e-12, atol=1e-15 * np.abs(inertia).max()):
            raise ParameterError(f"inertia_kg_m2 = {inertia.tolist()!r}: expected a symmetric matrix")
        eig = np.linalg.eigvalsh(inertia)
        if not eig[0] > 0:
            raise ParameterError(
                f"inertia_kg_m2 has principal moments {eig.tolist()!r} kg m^2: expected a positive "
                "definite tensor")
        inertia.setflags(write=False)
        object.__setattr__(self, "mass_kg", mass)
        object.__setattr__(self, "inertia_kg_m2", inertia)


@dataclass(frozen=True, eq=False)
class Mount:
    """One resilient mount.

    Parameters
    ----------
    position_m : array_like, shape (3,)
        Position relative to the body's CG, body axes [m].
    stiffness_n_per_m : float or array_like, shape (3,)
        Stiffness along x, y, z [N/m], >= 0.
    damping_n_s_per_m : float or array_like, shape (3,)
        Viscous damping along x, y, z [N s/m], >= 0.
    """

    position_m: np.ndarray
    stiffness_n_per_m: np.ndarray
    damping_n_s_per_m: np.ndarray = 0.0  # type: ignore[assignment]

    def __post_init__(self) -> None:
        for name, nonneg in (("position_m", False), ("stiffness_n_per_m", True),
                             ("damping_n_s_per_m", True)):
            vec = _vector3(name, getattr(self, name), nonnegative=nonneg)
            vec.setflags(write=False)
            object.__setattr__(self, name, vec)


def inertia_tensor(ixx_kg_m2: float, iyy_kg_m2: float, izz_kg_m2: float, ixy_kg_m2: float = 0.0,
                   iyz_kg_m2: float = 0.0, ixz_kg_m2: float = 0.0) -> np.ndarray:
    """Inertia tensor from moments and products of inertia (products as ``I_xy = int x y dm``).

    The tensor carries the products with a minus sign:
    ``[[Ixx, -Ixy, -Ixz], [-Ixy, Iyy, -Iyz], [-Ixz, -Iyz, Izz]]``.

    Parameters
    ----------
    ixx_kg_m2, iyy_kg_m2, izz_kg_m2 : float
        Moments of inertia about the CG [kg m^2].
    ixy_kg_m2, iyz_kg_m2, ixz_kg_m2 : float
        Products of inertia [kg m^2].

    Returns
    -------
    ndarray, shape (3, 3)
    """
    values = [ixx_kg_m2, iyy_kg_m2, izz_kg_m2, ixy_kg_m2, iyz_kg_m2, ixz_kg_m2]
    names = ["ixx_kg_m2", "iyy_kg_m2", "izz_kg_m2", "ixy_kg_m2", "iyz_kg_m2", "ixz_kg_m2"]
    for name, value in zip(names, values):
        if not (np.isscalar(value) and math.isfinite(float(value))):
            raise ParameterError(f"{name} = {value!r}: expected a finite number")
    ixx, iyy, izz, ixy, iyz, ixz = (float(v) for v in values)
    return np.array([[ixx, -ixy, -ixz], [-ixy, iyy, -iyz], [-ixz, -iyz, izz]])


def point_transformation(position_m) -> np.ndarray:
    """``T(p) = [I, -[p]x]``: displacement of point ``p`` from CG coordinates, shape (3, 6).

    Parameters
    ----------
    position_m : array_like, shape (3,)
        Point relative to the CG [m].

    Returns
    -------
    ndarray
    """
    x, y, z = _vector3("position_m", position_m)
    skew = np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])
    return np.hstack([np.eye(3), -skew])


def mass_matrix(body: RigidBody) -> np.ndarray:
    """6 x 6 mass matrix ``diag(m I, J)`` [kg, kg m^2].

    Parameters
    ----------
    body : RigidBody

    Returns
    -------
    ndarray
    """
    mass = np.zeros((6, 6))
    mass[:3, :3] = body.mass_kg * np.eye(3)
    mass[3:, 3:] = body.inertia_kg_m2
    return mass


def stiffness_matrix(mounts: Sequence[Mount]) -> np.ndarray:
    """6 x 6 stiffness matrix ``sum_i T_i' diag(k_i) T_i`` at the CG.

    Parameters
    ----------
    mounts : sequence of Mount

    Returns
    -------
    ndarray
    """
    return sum((point_transformation(m.position_m).T @ np.diag(m.stiffness_n_per_m)
                @ point_transformation(m.position_m) for m in mounts), np.zeros((6, 6)))


def _mount_damping_matrix(mounts: Sequence[Mount]) -> np.ndarray:
    return sum((point_transformation(m.position_m).T @ np.diag(m.damping_n_s_per_m)
                @ point_transformation(m.position_m) for m in mounts), np.zeros((6, 6)))


@dataclass(frozen=True, eq=False)
class MountedBody:
    """A rigid body on three or more mounts.

    Parameters
    ----------
    body : RigidBody
    mounts : sequence of Mount
        At least three, not all on one line, so that ``K`` is positive definite.
    damping_ratio : float
        Modal damping ratio ``zeta`` added to the mounts' own dampers, in [0, 1).
    """

    body: RigidBody
    mounts: tuple[Mount, ...]
    damping_ratio: float = 0.0

    def __post_init__(self) -> None:
        if not isinstance(self.body, RigidBody):
            raise ParameterError(f"body = {self.body!r}: expected a RigidBody")
        mounts = tuple(self.mounts)
        if len(mounts) < 3 or not all(isinstance(m, Mount) for m in mounts):
            raise ParameterError(
                f"mounts has {len(mounts)} entries: expected at least three Mount objects")
        zeta = float(self.damping_ratio)
        if not (math.isfinite(zeta) and 0.0 <= zeta < 1.0):
            raise ParameterError(f"damping_ratio = {self.damping_ratio!r}: expected 0 <= zeta < 1")
        _check_restrained(mounts)
        object.__setattr__(self, "mounts", mounts)
        object.__setattr__(self, "damping_ratio", zeta)


def _check_restrained(mounts: Sequence[Mount]) -> None:
    """Raise when the layout leaves a rigid-body motion unrestrained."""
    stiffness = stiffness_matrix(mounts)
    length = max(max(np.linalg.norm(m.position_m) for m in mounts), 1e-3)
    scale = np.diag([1.0, 1.0, 1.0, length, length, length])
    scaled = scale @ stiffness @ scale
    eig, vec = np.linalg.eigh(scaled)
    if eig[0] <= _SINGULAR_RTOL * max(eig[-1], np.finfo(float).tiny):
        free = vec[:, 0]
        names = ", ".join(f"{n} {v:+.2f}" for n, v in zip(DOF_NAMES, free) if abs(v) > 0.05)
        positions = [m.position_m.tolist() for m in mounts]
        raise ParameterError(
            f"singular mount layout: mounts at {positions} m leave the motion ({names}) "
            "unrestrained; expected three or more mounts not on one line, with stiffness in "
            "every direction")


def _generalised_eigh(stiffness: np.ndarray, mass: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Eigenvalues (ascending) and mass-normalised eigenvectors of ``K v = lambda M v``.

    ``M`` symmetric positive definite: with ``M = L L^T`` (Cholesky), the symmetric
    ``L^-1 K L^-T w = lambda w`` and ``v = L^-T w`` (what LAPACK's ``sygv`` does, here in numpy:
    6 x 6, so ``scipy.linalg``'s import, ~30 ms, would cost more than the solve).
    """
    lower_inv = np.linalg.inv(np.linalg.cholesky(mass))
    reduced = lower_inv @ stiffness @ lower_inv.T
    eig, vectors = np.linalg.eigh(0.5 * (reduced + reduced.T))
    return eig, lower_inv.T @ vectors


def damping_matrix(system: MountedBody) -> np.ndarray:
    """6 x 6 damping matrix: mount dampers plus modal damping ``zeta`` [N s/m, ...].

    Parameters
    ----------
    system : MountedBody

    Returns
    -------
    ndarray
    """
    damping = _mount_damping_matrix(system.mounts)
    if system.damping_ratio > 0.0:
        mass = mass_matrix(system.body)
        eig, shapes = _generalised_eigh(stiffness_matrix(system.mounts), mass)
        omega = np.sqrt(eig)
        damping = damping + mass @ shapes @ np.diag(2 * system.damping_ratio * omega) @ shapes.T @ mass
    return damping


def _identified_value(obj, attribute: str, channel: int | None, *, positive: bool) -> float:
    if not hasattr(obj, attribute):
        raise ParameterError(
            f"identified result {obj!r} has no attribute {attribute!r}: expected an "
            "identification result with stiffness_n_per_m and damping_n_s_per_m")
    try:
        value = np.asarray(getattr(obj, attribute), dtype=float)
    except (TypeError, ValueError):
        raise ParameterError(f"{attribute} = {getattr(obj, attribute)!r}: expected numbers") from None
    if value.ndim == 1:
        if channel is None:
            raise ParameterError(
                f"{attribute} has {value.size} channels: pass channel= to choose one")
        if not (isinstance(channel, (int, np.integer)) and -value.size <= channel < value.size):
            raise ParameterError(
                f"channel = {channel!r}: expected an integer index into {value.size} channels")
        value = value[channel]
    elif value.ndim != 0:
        raise ParameterError(
            f"{attribute} has shape {value.shape}: expected a number or a 1-D array over channels")
    number = float(value)
    bad = not math.isfinite(number) or (number <= 0 if positive else number < 0)
    if bad:
        expected = "> 0" if positive else ">= 0"
        raise ParameterError(f"{attribute} = {number!r}: expected a finite value {expected}")
    return number


def mount_from_identification(position_m, identified, *, channel: int | None = None) -> Mount:
    """A mount whose stiffness and damping come from identification results.

    Parameters
    ----------
    position_m : array_like, shape (3,)
        Mount position relative to the CG [m].
    identified : object or sequence of three objects
        Result(s) with attributes ``stiffness_n_per_m`` [N/m] and
        ``damping_n_s_per_m`` [N s/m], for example from a mount's FRF.  One
        object sets all three directions; three objects set x, y, z.
    channel : int, optional
        Index into the attributes when they are arrays over channels.

    Returns
    -------
    Mount
    """
    if isinstance(identified, (list, tuple)):
        if len(identified) != 3:
            raise ParameterError(
                f"identified has {len(identified)} results: expected one, or three (x, y, z)")
        results = tuple(identified)
    else:
        results = (identified,) * 3
    stiffness = [_identified_value(r, "stiffness_n_per_m", channel, positive=True) for r in results]
    damping = [_identified_value(r, "damping_n_s_per_m", channel, positive=False) for r in results]
    return Mount(position_m, stiffness, damping)


@dataclass(frozen=True)
class MountModes:
    """Undamped modes of the mounted body.

    Attributes
    ----------
    natural_frequency_hz : ndarray, shape (6,)
        Ascending natural frequencies [Hz].
    mode_shapes : ndarray, shape (6, 6)
        Mass-normalised mode shapes, one per column (``Phi' M Phi = I``).
    kinetic_energy_share : ndarray, shape (6, 6)
        ``Phi_jr (M Phi_r)_j``: share of mode r's kinetic energy in DOF j
        (rows ``u_x .. phi_z``); each column sums to 1.
    dof_names : tuple of str
        Names of the rows.
    """

    natural_frequency_hz: np.ndarray
    mode_shapes: np.ndarray
    kinetic_energy_share: np.ndarray
    dof_names: tuple[str, ...] = DOF_NAMES


def natural_modes(system: MountedBody) -> MountModes:
    """Natural frequencies and mass-normalised mode shapes (generalised symmetric eigenproblem).

    Parameters
    ----------
    system : MountedBody

    Returns
    -------
    MountModes
    """
    mass = mass_matrix(system.body)
    eig, shapes = _generalised_eigh(stiffness_matrix(system.mounts), mass)
    share = shapes * (mass @ shapes)
    return MountModes(np.sqrt(np.clip(eig, 0.0, None)) / (2 * np.pi), shapes, share)


@dataclass(frozen=True)
class HarmonicResponse:
    """Steady-state response to harmonic loads, one row per harmonic order.

    Complex amplitudes: a quantity is ``Re(X e^{i h omega t})``.

    Attributes
    ----------
    orders : ndarray of int, shape (n,)
        Harmonic orders ``h``.
    frequency_hz : ndarray, shape (n,)
        Excitation frequencies ``h omega / 2 pi`` [Hz].
    load : ndarray, complex, shape (n, 6)
        Generalised load at the CG: force [N] and moment [N m].
    displacement : ndarray, complex, shape (n, 6)
        CG translation [m] and rotation [rad].
    point_displacement_m : ndarray, complex, shape (n, n_points, 3)
        Displacement of the requested points [m].
    mount_force_n : ndarray, complex, shape (n, n_mounts, 3)
        Force each mount passes into the base (spring and own damper) [N].
    base_force_n : ndarray, complex, shape (n, 3)
        Total force into the base, including modal damping [N].
    points_m : ndarray, shape (n_points, 3)
        The requested points relative to the CG [m].
    """

    orders: np.ndarray
    frequency_hz: np.ndarray
    load: np.ndarray
    displacement: np.ndarray
    point_displacement_m: np.ndarray
    mount_force_n: np.ndarray
    base_force_n: np.ndarray
    points_m: np.ndarray

    def archive_units(self) -> dict[str, str]:
        """Units of the fields whose names do not say them (for :mod:`modal.archive`)."""
        return {"load": "N (columns 0-2), N m (columns 3-5)", "displacement": "m (columns 0-2), rad (columns 3-5)"}


def _points(points_m) -> np.ndarray:
    if points_m is None:
        return np.zeros((0, 3))
    pts = np.asarray(points_m, dtype=float)
    if pts.ndim == 1:
        pts = pts[None, :]
    if pts.ndim != 2 or pts.shape[1] != 3 or not np.all(np.isfinite(pts)):
        raise ParameterError(f"points_m has shape {pts.shape}: expected finite (n, 3) positions")
    return pts


def harmonic_response(system: MountedBody, speed_rad_s: float, orders, force_n, couple_n_m=None,
                      load_point_m=(0.0, 0.0, 0.0), points_m=None) -> HarmonicResponse:
    """Steady-state response to a force (and couple) applied at a point, per harmonic.

    Parameters
    ----------
    system : MountedBody
    speed_rad_s : float
        Fundamental angular speed ``omega`` [rad/s], > 0.
    orders : array_like of int, shape (n,)
        Harmonic orders ``h``; order ``h`` excites at ``h omega``.
    force_n : array_like, complex, shape (n, 3)
        Force amplitudes at ``load_point_m`` [N].
    couple_n_m : array_like, complex, shape (n, 3), optional
        Couple amplitudes [N m].
    load_point_m : array_like, shape (3,)
        Where the force acts, relative to the CG [m].
    points_m : array_like, shape (n_points, 3), optional
        Points whose displacement is wanted [m].

    Returns
    -------
    HarmonicResponse
    """
    omega = float(speed_rad_s)
    if not (math.isfinite(omega) and omega > 0):
        raise ParameterError(f"speed_rad_s = {speed_rad_s!r}: expected a finite value > 0")
    try:
        order_values = np.atleast_1d(np.asarray(orders, dtype=float))
    except (TypeError, ValueError):
        raise ParameterError(f"orders = {orders!r}: expected positive integer orders") from None
    if (order_values.ndim != 1 or not np.all(np.isfinite(order_values))
            or np.any(order_values < 1) or np.any(order_values != np.round(order_values))):
        raise ParameterError(f"orders = {orders!r}: expected a 1-D array of positive integers")
    order_arr = order_values.astype(int)
    force = np.atleast_2d(np.asarray(force_n, dtype=complex))
    couple = (np.zeros_like(force) if couple_n_m is None
              else np.atleast_2d(np.asarray(couple_n_m, dtype=complex)))
    if force.shape != (order_arr.size, 3) or couple.shape != force.shape:
        raise ParameterError(
            f"force_n has shape {force.shape} and couple_n_m {couple.shape}: expected "
            f"({order_arr.size}, 3), one row per order")
    if not (np.all(np.isfinite(force)) and np.all(np.isfinite(couple))):
        raise ParameterError("force_n or couple_n_m contains NaN or infinity: expected finite")
    point = _vector3("load_point_m", load_point_m)
    pts = _points(points_m)
    load = np.hstack([force, np.cross(point, force) + couple])
    mass, stiffness, damping = (mass_matrix(system.body), stiffness_matrix(system.mounts),
                                damping_matrix(system))
    transforms = [point_transformation(m.position_m) for m in system.mounts]
    disp = np.zeros((order_arr.size, 6), dtype=complex)
    base = np.zeros((order_arr.size, 3), dtype=complex)
    mount_force = np.zeros((order_arr.size, len(system.mounts), 3), dtype=complex)
    for row, order in enumerate(order_arr):
        big_omega = order * omega
        dynamic = stiffness - big_omega ** 2 * mass + 1j * big_omega * damping
        if np.linalg.cond(dynamic) > 1e13:
            raise ParameterError(
                f"order {order} at {big_omega / (2 * np.pi):.6g} Hz coincides with an undamped "
                "natural frequency: expected damping (damping_ratio or mount dampers) or another speed")
        disp[row] = np.linalg.solve(dynamic, load[row])
        base[row] = ((stiffness + 1j * big_omega * damping) @ disp[row])[:3]
        for index, (mount, t_matrix) in enumerate(zip(system.mounts, transforms)):
            mount_force[row, index] = (mount.stiffness_n_per_m + 1j * big_omega
                                       * mount.damping_n_s_per_m) * (t_matrix @ disp[row])
    point_disp = np.einsum("pij,nj->npi", np.array([point_transformation(p) for p in pts])
                           .reshape(-1, 3, 6), disp) if pts.size else np.zeros((order_arr.size, 0, 3),
                                                                                 dtype=complex)
    return HarmonicResponse(order_arr, order_arr * omega / (2 * np.pi), load, disp, point_disp,
                            mount_force, base, pts)


def compressor_response(system: MountedBody, mech: SliderCrank, speed_rpm: float, crank_centre_m,
                        counterweight_mass_kg: float = 0.0, counterweight_radius_m: float = 0.0,
                        points_m=None, max_order: int = 6) -> HarmonicResponse:
    """Response of the mounted compressor to each harmonic of its shaking force and couple.

    The shaking force (:func:`balancer.compressor.crank.shaking_harmonics`) acts at the
    crank centre; the crank-plane axes are the body axes.

    Parameters
    ----------
    system : MountedBody
    mech : SliderCrank
    speed_rpm : float
        Crank speed [rev/min], > 0.
    crank_centre_m : array_like, shape (3,)
        Crank centre relative to the body's CG [m].
    counterweight_mass_kg, counterweight_radius_m : float
        Counterweight [kg], [m].
    points_m : array_like, shape (n_points, 3), optional
        Points whose displacement is wanted [m].
    max_order : int
        Highest order for exact kinematics.

    Returns
    -------
    HarmonicResponse
    """
    harmonics = shaking_harmonics(mech, speed_rpm, counterweight_mass_kg, counterweight_radius_m,
                                  max_order=max_order)
    return harmonic_response(system, harmonics.speed_rad_s, harmonics.orders, harmonics.force_n,
                             harmonics.couple_n_m, crank_centre_m, points_m)


@dataclass(frozen=True)
class BalancingComparison:
    """Mounted-body response before and after balancing.

    Attributes
    ----------
    before, after : HarmonicResponse
    base_force_amplitude_before_n, base_force_amplitude_after_n : ndarray, shape (n, 3)
        ``|base_force_n|`` per order and direction [N].
    """

    before: HarmonicResponse
    after: HarmonicResponse
    base_force_amplitude_before_n: np.ndarray
    base_force_amplitude_after_n: np.ndarray


def balancing_comparison(system: MountedBody, mech: SliderCrank, speed_rpm: float, crank_centre_m,
                         counterweight_mass_kg: float, counterweight_radius_m: float,
                         points_m=None) -> BalancingComparison:
    """Response without counterweight and with the given one.

    Parameters
    ----------
    system : MountedBody
    mech : SliderCrank
    speed_rpm : float
        Crank speed [rev/min], > 0.
    crank_centre_m : array_like, shape (3,)
        Crank centre relative to the CG [m].
    counterweight_mass_kg, counterweight_radius_m : float
        The balancing counterweight [kg], [m].
    points_m : array_like, shape (n_points, 3), optional
        Points whose displacement is wanted [m].

    Returns
    -------
    BalancingComparison
    """
    before = compressor_response(system, mech, speed_rpm, crank_centre_m, points_m=points_m)
    after = compressor_response(system, mech, speed_rpm, crank_centre_m, counterweight_mass_kg,
                                counterweight_radius_m, points_m=points_m)
    return BalancingComparison(before, after, np.abs(before.base_force_n),
                               np.abs(after.base_force_n))
