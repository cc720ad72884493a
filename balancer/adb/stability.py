"""Linear stability of the balanced state: eigenvalues over speed, stable speed
intervals, batched stability maps, Routh-Hurwitz for two balls, threshold sensitivity.

The Jacobians are exact (complex step on the rotating-frame equations) and the
eigenvalue problems are solved in one batched ``numpy.linalg.eig`` call per map.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Iterator, Sequence

import numpy as np

from modal.errors import ParameterError

from .equilibria import balanced_state
from .linear import CLASS_NAMES, STABLE, EigenAnalysis, eigen_analysis_nondimensional
from .parameters import STD_ORDER, ADBParameters, ParameterStd

__all__ = [
    "BalancedStability",
    "SpeedIntervals",
    "StabilityMap",
    "RouthHurwitzResult",
    "ThresholdSensitivity",
    "balanced_stability",
    "stable_speed_intervals",
    "stability_map",
    "linearised_matrices",
    "characteristic_polynomial",
    "routh_hurwitz",
    "routh_hurwitz_n2",
    "threshold_sensitivity",
]


def _speeds_array(speeds_rad_s, name: str = "speeds_rad_s") -> np.ndarray:
    speeds = np.atleast_1d(np.asarray(speeds_rad_s, dtype=float)).reshape(-1)
    if speeds.size == 0 or not np.all(np.isfinite(speeds)) or np.any(speeds <= 0.0):
        raise ParameterError(f"{name} = {speeds_rad_s!r}: expected finite speeds > 0 (rad/s)")
    return speeds


def _balanced_companion(members: Sequence[ADBParameters], speeds: np.ndarray, angles: Sequence[np.ndarray]) -> np.ndarray:
    """Nondimensional first-order matrices ``[[0, I], [-M0^-1 K0, -M0^-1 C0]]`` about the
    balanced state for every (member, speed) pair, row-major; shape ``(V S, 2n + 4, 2n + 4)``.

    Vectorised form of :func:`linearised_matrices`; equal to the complex-step Jacobian of
    the rotating-frame equations, rescaled, to rounding (tested).
    """
    n = members[0].n
    size = n + 2
    mu = np.array([p.mass_ratio for p in members])[:, None]
    zeta = np.array([p.damping_ratio for p in members])[:, None]
    beta = np.array([p.drag_ratio for p in members])[:, None]
    Om = speeds[None, :] / np.array([p.natural_frequency_rad_s for p in members])[:, None]
    shape = Om.shape
    mu, zeta, beta = (np.broadcast_to(x, shape).reshape(-1) for x in (mu, zeta, beta))
    Om = Om.reshape(-1)
    phi = np.repeat(np.array(angles, dtype=float), speeds.shape[0], axis=0)  # (B, n)
    return _companion_arrays(mu, zeta, beta, Om, phi)


def _companion_arrays(mu: np.ndarray, zeta: np.ndarray, beta: np.ndarray, Om: np.ndarray, phi: np.ndarray) -> np.ndarray:
    """:func:`_balanced_companion` from per-member arrays ``(B,)`` and ball angles ``(B, n)``."""
    n = phi.shape[1]
    size = n + 2
    s, c = np.sin(phi), np.cos(phi)
    B = Om.shape[0]
    M0 = np.zeros((B, size, size))
    C0 = np.zeros((B, size, size))
    K0 = np.zeros((B, size, size))
    M0[:, 0, 0] = M0[:, 1, 1] = 1.0
    M0[:, 0, 2:] = -mu[:, None] * s
    M0[:, 1, 2:] = mu[:, None] * c
    M0[:, 2:, 0] = -s
    M0[:, 2:, 1] = c
    M0[:, 2:, 2:] = np.eye(n)
    C0[:, 0, 0] = C0[:, 1, 1] = 2 * zeta
    C0[:, 0, 1] = -2 * Om
    C0[:, 1, 0] = 2 * Om
    C0[:, 0, 2:] = -2 * (mu * Om)[:, None] * c
    C0[:, 1, 2:] = -2 * (mu * Om)[:, None] * s
    C0[:, 2:, 0] = 2 * Om[:, None] * c
    C0[:, 2:, 1] = 2 * Om[:, None] * s
    C0[:, 2:, 2:] = beta[:, None, None] * np.eye(n)
    K0[:, 0, 0] = K0[:, 1, 1] = 1 - Om**2
    K0[:, 0, 1] = -2 * zeta * Om
    K0[:, 1, 0] = 2 * zeta * Om
    K0[:, 0, 2:] = (mu * Om**2)[:, None] * s
    K0[:, 1, 2:] = -(mu * Om**2)[:, None] * c
    K0[:, 2:, 0] = (Om**2)[:, None] * s
    K0[:, 2:, 1] = -(Om**2)[:, None] * c
    rhs = np.linalg.solve(M0, np.concatenate([K0, C0], axis=2))
    A = np.zeros((B, 2 * size, 2 * size))
    A[:, :size, size:] = np.eye(size)
    A[:, size:, :] = -rhs
    return A


def _analyse_balanced(members: Sequence[ADBParameters], speeds: np.ndarray, angles: Sequence[np.ndarray],
                      condition_cap: float | None = None) -> EigenAnalysis:
    """Eigen-analysis of the balanced state for every (member, speed) pair, row-major."""
    n = members[0].n
    wn = np.repeat(np.array([p.natural_frequency_rad_s for p in members]), speeds.shape[0])
    return eigen_analysis_nondimensional(_balanced_companion(members, speeds, angles), wn,
                                         n_zero_to_drop=max(n - 2, 0), condition_cap=condition_cap)


@dataclass(frozen=True, slots=True)
class BalancedStability:
    """Linear stability of one balanced state over a set of speeds.

    Attributes
    ----------
    speeds_rad_s : ndarray, shape (S,)
        Shaft speeds (rad/s).
    speed_ratio : ndarray, shape (S,)
        ``Omega = omega / omega_n``.
    ball_angles_rad : ndarray, shape (n,)
        The balanced configuration analysed (rad, relative to the unbalance).
    eigenvalues_per_s : ndarray, shape (S, 4 + n), complex
        Eigenvalues (1/s), decreasing real part, family zeros dropped.
    max_real_part_per_s, rounding_bound_per_s : ndarray, shape (S,)
        Growth rate of the least stable mode and its rounding bound (1/s).
    stability_class : ndarray of int, shape (S,)
        1 stable, 0 marginal, -1 unstable.
    """

    speeds_rad_s: np.ndarray
    speed_ratio: np.ndarray
    ball_angles_rad: np.ndarray
    eigenvalues_per_s: np.ndarray
    max_real_part_per_s: np.ndarray
    rounding_bound_per_s: np.ndarray
    stability_class: np.ndarray


def balanced_stability(params: ADBParameters, speeds_rad_s, *, ball_angles_rad=None) -> BalancedStability:
    """Eigenvalues of the balanced state's linearisation at each speed.

    Parameters
    ----------
    params : ADBParameters
        Parameters (``n m R >= M e`` required).
    speeds_rad_s : array_like
        Shaft speeds (rad/s, > 0).
    ball_angles_rad : array_like, optional
        Balanced member for ``n >= 3``; default the symmetric one.
    """
    speeds = _speeds_array(speeds_rad_s)
    angles = balanced_state(params, ball_angles_rad)[2:2 + params.n]
    analysis = _analyse_balanced([params], speeds, [angles])
    return BalancedStability(
        speeds_rad_s=speeds,
        speed_ratio=speeds / params.natural_frequency_rad_s,
        ball_angles_rad=angles,
        eigenvalues_per_s=analysis.eigenvalues_per_s,
        max_real_part_per_s=analysis.max_real_part_per_s,
        rounding_bound_per_s=analysis.rounding_bound_per_s,
        stability_class=analysis.stability_class,
    )


@dataclass(frozen=True, slots=True)
class SpeedIntervals:
    """Speed intervals where the balanced state is linearly stable.

    Iterating yields ``(low_rad_s, high_rad_s)`` tuples.

    Attributes
    ----------
    intervals_rad_s : ndarray, shape (K, 2)
        Closed intervals (rad/s); boundaries refined to ``xtol_ratio`` in ``Omega``.
    intervals_ratio : ndarray, shape (K, 2)
        The same in units of ``omega_n``.
    natural_frequency_rad_s : float
        ``omega_n`` (rad/s).
    speed_max_rad_s : float
        Upper end of the scan (rad/s).
    reaches_speed_max : bool
        Whether the last interval was still stable at ``speed_max_rad_s`` (open upwards).
    ball_angles_rad : ndarray, shape (n,)
        The balanced member analysed.
    grid_points : int
        Number of speeds scanned before refinement.
    """

    intervals_rad_s: np.ndarray
    intervals_ratio: np.ndarray
    natural_frequency_rad_s: float
    speed_max_rad_s: float
    reaches_speed_max: bool
    ball_angles_rad: np.ndarray
    grid_points: int

    def __iter__(self) -> Iterator[tuple[float, float]]:
        return iter(tuple(map(float, row)) for row in self.intervals_rad_s)

    def __len__(self) -> int:
        return int(self.intervals_rad_s.shape[0])

    def __getitem__(self, index: int) -> tuple[float, float]:
        low, high = self.intervals_rad_s[index]
        return float(low), float(high)

    @property
    def lowest_stable_speed_rad_s(self) -> float:
        """Lower end of the first stable interval (rad/s); inf if there is none."""
        return float(self.intervals_rad_s[0, 0]) if len(self) else math.inf


#: default condition-number cap of :func:`stability_map` (see its ``condition_cap``), also the scan's of
#: :func:`stable_speed_intervals`
CONDITION_CAP = 1e8


def _stable_on_grid(params: ADBParameters, speeds: np.ndarray, angles: np.ndarray) -> np.ndarray:
    """Whether the balanced state is stable at each speed of a scan.

    For ``n >= 2`` the verdicts of :func:`stability_map` with ``margin=False`` (Routh test of
    the closed-form characteristic polynomial, eigenvalues only for points near the boundary:
    ~1.5 ms instead of ~25 ms for 2000 speeds); they are the eigenvalue path's wherever the
    growth rate is clear of its rounding band, and a point inside that band is only moved
    between a grid interval's ends, which the refinement of each boundary does not depend on.
    """
    if params.n < 2:
        return _analyse_balanced([params], speeds, [angles]).stability_class == STABLE
    shape = (1, speeds.shape[0])
    growth, bound, nondim = np.empty(shape), np.empty(shape), np.empty(shape)
    codes = np.empty(shape, dtype=int)
    ratio = speeds[None, :] / params.natural_frequency_rad_s
    _routh_rows([params], [0], [angles], speeds, ratio, CONDITION_CAP, growth, bound, nondim, codes)
    return codes[0] == STABLE


def stable_speed_intervals(
    params: ADBParameters,
    speed_max_rad_s: float,
    *,
    ball_angles_rad=None,
    speed_min_rad_s: float | None = None,
    grid_points: int = 2000,
    xtol_ratio: float = 1e-10,
) -> SpeedIntervals:
    """Speed intervals (rad/s) in which the balanced state is linearly stable.

    The speed range is scanned on a uniform grid (Routh verdicts as in :func:`stability_map`
    with ``margin=False``; batched eigenvalues for ``n = 1``); every change of sign of the
    largest real part (an eigenvalue problem per evaluation) is then refined by Brent's method
    (:func:`scipy.optimize.brentq`).  Intervals narrower than the grid spacing can be
    missed: raise ``grid_points`` if in doubt.

    Parameters
    ----------
    params : ADBParameters
        Parameters (``n m R >= M e`` required).
    speed_max_rad_s : float
        Upper end of the scan (rad/s).
    ball_angles_rad : array_like, optional
        Balanced member for ``n >= 3``; default the symmetric one (balls equally spaced,
        centred opposite the unbalance).
    speed_min_rad_s : float, optional
        Lower end of the scan (rad/s); default ``speed_max_rad_s / grid_points``.
    grid_points : int
        Number of scan speeds.
    xtol_ratio : float
        Absolute tolerance on each boundary in units of ``omega_n``.

    Returns
    -------
    SpeedIntervals
        Iterable of ``(low, high)`` in rad/s.
    """
    speed_max = _speeds_array(speed_max_rad_s, "speed_max_rad_s")[0]
    if int(grid_points) < 2:
        raise ParameterError(f"grid_points = {grid_points!r}: expected an integer >= 2")
    speed_min = speed_max / grid_points if speed_min_rad_s is None else _speeds_array(speed_min_rad_s, "speed_min_rad_s")[0]
    if not speed_min < speed_max:
        raise ParameterError(f"speed_min_rad_s = {speed_min!r}: expected < speed_max_rad_s = {speed_max!r}")
    angles = balanced_state(params, ball_angles_rad)[2:2 + params.n]
    speeds = np.linspace(speed_min, speed_max, int(grid_points))
    stable = _stable_on_grid(params, speeds, angles)
    wn = params.natural_frequency_rad_s

    from scipy.optimize import brentq  # imported when used: a plotting process unpickles this package's results

    def growth(speed: float) -> float:
        return float(_analyse_balanced([params], np.array([speed]), [angles]).max_real_part_per_s[0])

    def boundary(index: int) -> float:
        # sign change of the growth rate between grid points index and index + 1; if one of
        # them is marginal the signs may agree, and the grid point on the stable side is kept
        low, high = speeds[index], speeds[index + 1]
        if growth(low) * growth(high) > 0.0:
            return high if stable[index + 1] else low
        return brentq(growth, low, high, xtol=xtol_ratio * wn, rtol=4 * np.finfo(float).eps)

    intervals = []
    start = speeds[0] if stable[0] else None
    for index in range(len(speeds) - 1):
        if stable[index + 1] and not stable[index]:
            start = boundary(index)
        elif stable[index] and not stable[index + 1]:
            intervals.append((start, boundary(index)))
            start = None
    if start is not None:
        intervals.append((start, speeds[-1]))
    array = np.array(intervals, dtype=float).reshape(-1, 2)
    return SpeedIntervals(
        intervals_rad_s=array,
        intervals_ratio=array / wn,
        natural_frequency_rad_s=wn,
        speed_max_rad_s=float(speed_max),
        reaches_speed_max=bool(stable[-1]),
        ball_angles_rad=angles,
        grid_points=int(grid_points),
    )


@dataclass(frozen=True, slots=True)
class StabilityMap:
    """Stability of the balanced state over speed and a second parameter.

    Attributes
    ----------
    parameter : str
        Name of the varied :class:`ADBParameters` field.
    values : ndarray, shape (V,)
        Its values (SI units of that field).
    speeds_rad_s : ndarray, shape (S,)
        Shaft speeds (rad/s).
    speed_ratio : ndarray, shape (V, S)
        ``omega / omega_n`` (``omega_n`` changes with M, m, n, k).
    max_real_part_per_s, rounding_bound_per_s : ndarray, shape (V, S)
        Growth rate of the least stable mode and its rounding bound (1/s).
    growth_rate_nondimensional : ndarray, shape (V, S)
        Growth rate divided by ``omega_n``.
    stability_class : ndarray of int, shape (V, S)
        1 stable, 0 marginal, -1 unstable.
    """

    parameter: str
    values: np.ndarray
    speeds_rad_s: np.ndarray
    speed_ratio: np.ndarray
    max_real_part_per_s: np.ndarray
    rounding_bound_per_s: np.ndarray
    growth_rate_nondimensional: np.ndarray
    stability_class: np.ndarray

    @property
    def class_counts(self) -> dict[str, int]:
        """How many grid points fall in each class."""
        return {name: int(np.sum(self.stability_class == code)) for code, name in CLASS_NAMES.items()}


_MAP_FIELDS = ("M", "m", "n", "R", "e", "k", "c", "D")


def stability_map(params: ADBParameters, speeds_rad_s, parameter: str, values, *, ball_angles_rad=None,
                  condition_cap: float | None = CONDITION_CAP, margin: bool = True) -> StabilityMap:
    """Balanced-state stability over ``speeds x values``.

    With ``margin=True`` (default) every point is a batched eigenvalue problem and the
    growth rate is returned everywhere.  With ``margin=False`` the verdict comes from the
    closed-form characteristic polynomial and a vectorised Routh test
    (:mod:`balancer.adb.verdict`, about 10x faster than the eigenvalues); only the points
    whose growth rate may lie within the eigenvalue path's screening band of zero (or
    whose Routh array is not clear of rounding) go through the eigenvalue path, which
    keeps its marginal class there.  The verdicts are the same as with ``margin=True``
    wherever the growth rate is clear of that band (tested).

    Parameters
    ----------
    params : ADBParameters
        Base parameters; ``parameter`` is replaced by each of ``values``.
    speeds_rad_s : array_like, shape (S,)
        Shaft speeds (rad/s, > 0).
    parameter : str
        One of ``M, m, n, R, e, k, c, D``.
    values : array_like, shape (V,)
        Values of that parameter (its SI unit).
    ball_angles_rad : array_like, optional
        Balanced member (only with a fixed ``n``); default the symmetric member of each set.
    condition_cap : float or None
        Screening cap on the critical eigenvalue's condition number (see
        :func:`~balancer.adb.linear.eigen_analysis`); None computes every condition number
        (and then ``margin=False`` has no effect: every point is an eigenvalue problem).
    margin : bool
        Whether to compute the growth rate (largest real part) at every point.  False:
        ``max_real_part_per_s``, ``rounding_bound_per_s`` and ``growth_rate_nondimensional``
        are NaN except at the points resolved by the eigenvalue path (near the boundary).

    Returns
    -------
    StabilityMap
    """
    if parameter not in _MAP_FIELDS:
        raise ParameterError(f"parameter = {parameter!r}: expected one of {_MAP_FIELDS}")
    speeds = _speeds_array(speeds_rad_s)
    values = np.atleast_1d(np.asarray(values, dtype=float)).reshape(-1)
    members = [params.replace(**{parameter: int(v) if parameter == "n" else float(v)}) for v in values]
    shape = (len(members), speeds.shape[0])
    growth = np.empty(shape)
    bound = np.empty(shape)
    nondim = np.empty(shape)
    codes = np.empty(shape, dtype=int)
    ratio = np.empty(shape)
    by_count: dict[int, list[int]] = {}
    for index, member in enumerate(members):
        by_count.setdefault(member.n, []).append(index)
    for count, rows in by_count.items():
        group = [members[i] for i in rows]
        angles = [balanced_state(p, ball_angles_rad)[2:2 + count] for p in group]
        ratio[rows] = speeds[None, :] / np.array([p.natural_frequency_rad_s for p in group])[:, None]
        if not margin and condition_cap is not None and count >= 2:
            _routh_rows(group, rows, angles, speeds, ratio[rows], condition_cap, growth, bound, nondim, codes)
            continue
        analysis = _analyse_balanced(group, speeds, angles, condition_cap)
        growth[rows] = analysis.max_real_part_per_s.reshape(len(rows), -1)
        bound[rows] = analysis.rounding_bound_per_s.reshape(len(rows), -1)
        nondim[rows] = analysis.growth_rate_nondimensional.reshape(len(rows), -1)
        codes[rows] = analysis.stability_class.reshape(len(rows), -1)
    return StabilityMap(
        parameter=parameter, values=values, speeds_rad_s=speeds, speed_ratio=ratio,
        max_real_part_per_s=growth, rounding_bound_per_s=bound,
        growth_rate_nondimensional=nondim, stability_class=codes,
    )


def _routh_rows(group, rows, angles, speeds, ratio, condition_cap, growth, bound, nondim, codes) -> None:
    """Fill one ball count's rows of a map from Routh verdicts; eigenvalues only where unresolved."""
    from .verdict import UNRESOLVED, balanced_verdicts

    column = np.ones((len(group), 1))
    rho2 = np.array([abs(np.sum(np.exp(2j * a))) ** 2 for a in angles])[:, None] * column
    mu, zeta, beta = (np.array([getattr(p, name) for p in group])[:, None] * column
                      for name in ("mass_ratio", "damping_ratio", "drag_ratio"))
    n = group[0].n
    verdict = balanced_verdicts(mu, zeta, beta, ratio, rho2, n, condition_cap)
    codes[rows] = verdict
    for array in (growth, bound, nondim):  # no margin where the Routh test decided
        array[rows] = np.nan
    local, cols = np.nonzero(verdict == UNRESOLVED)
    if local.size:
        companion = _companion_arrays(mu[local, 0], zeta[local, 0], beta[local, 0], ratio[local, cols],
                                      np.array(angles, dtype=float)[local])
        # again with the band from the exact norm instead of its bound
        again = balanced_verdicts(mu[local, 0], zeta[local, 0], beta[local, 0], ratio[local, cols], rho2[local, 0],
                                  n, condition_cap, norm=np.linalg.norm(companion, axis=(-2, -1)))
        codes[np.asarray(rows)[local], cols] = again
        keep = again == UNRESOLVED
        local, cols, companion = local[keep], cols[keep], companion[keep]
    if local.size:  # one batched eigenvalue problem for every point still unresolved
        wn = np.array([p.natural_frequency_rad_s for p in group])[local]
        analysis = eigen_analysis_nondimensional(companion, wn, n_zero_to_drop=max(n - 2, 0),
                                                 condition_cap=condition_cap)
        at = (np.asarray(rows)[local], cols)
        growth[at] = analysis.max_real_part_per_s
        bound[at] = analysis.rounding_bound_per_s
        nondim[at] = analysis.growth_rate_nondimensional
        codes[at] = analysis.stability_class


# --------------------------------------------------------------------------- Routh-Hurwitz


def linearised_matrices(params: ADBParameters, speed_rad_s: float, ball_angles_rad=None):
    """Nondimensional mass, damping and stiffness matrices about a balanced state.

    Written out by hand (``adb.md`` section 2), independently of the complex-step
    Jacobian: coordinates ``(u/R, v/R, delta phi_i)``, time ``omega_n t``.

    Parameters
    ----------
    params : ADBParameters
        Parameters.
    speed_rad_s : float
        Shaft speed (rad/s).
    ball_angles_rad : array_like, optional
        Balanced member; default the symmetric one.

    Returns
    -------
    tuple of ndarray, each (n + 2, n + 2)
        ``(M0, C0, K0)``.
    """
    angles = balanced_state(params, ball_angles_rad)[2:2 + params.n]
    Om = float(_speeds_array(speed_rad_s)[0]) / params.natural_frequency_rad_s
    mu, zeta, beta, n = params.mass_ratio, params.damping_ratio, params.drag_ratio, params.n
    s, c = np.sin(angles), np.cos(angles)
    size = n + 2
    M0, C0, K0 = np.zeros((size, size)), np.zeros((size, size)), np.zeros((size, size))
    M0[0, 0] = M0[1, 1] = 1.0
    M0[0, 2:] = -mu * s
    M0[1, 2:] = mu * c
    M0[2:, 0] = -s
    M0[2:, 1] = c
    M0[2:, 2:] = np.eye(n)
    C0[0, :2] = [2 * zeta, -2 * Om]
    C0[1, :2] = [2 * Om, 2 * zeta]
    C0[0, 2:] = -2 * mu * Om * c
    C0[1, 2:] = -2 * mu * Om * s
    C0[2:, 0] = 2 * Om * c
    C0[2:, 1] = 2 * Om * s
    C0[2:, 2:] = beta * np.eye(n)
    K0[0, :2] = [1 - Om**2, -2 * zeta * Om]
    K0[1, :2] = [2 * zeta * Om, 1 - Om**2]
    K0[0, 2:] = mu * Om**2 * s
    K0[1, 2:] = -mu * Om**2 * c
    K0[2:, 0] = Om**2 * s
    K0[2:, 1] = -Om**2 * c
    return M0, C0, K0


def characteristic_polynomial(params: ADBParameters, speed_rad_s: float, ball_angles_rad=None) -> np.ndarray:
    """Coefficients of ``det(s^2 M0 + s C0 + K0)`` in the nondimensional ``s``, highest first.

    Obtained without any eigenvalue solver: the determinant (an LU factorisation) is
    sampled on a circle and the coefficients read off an FFT.

    Parameters
    ----------
    params : ADBParameters
        Parameters.
    speed_rad_s : float
        Shaft speed (rad/s).
    ball_angles_rad : array_like, optional
        Balanced member; default the symmetric one.

    Returns
    -------
    ndarray, shape (2 n + 5,)
        Real coefficients, degree ``2 (n + 2)``.
    """
    M0, C0, K0 = linearised_matrices(params, speed_rad_s, ball_angles_rad)
    degree = 2 * M0.shape[0]
    samples = 2 * degree + 2
    Om = float(speed_rad_s) / params.natural_frequency_rad_s
    radius = max(1.0, Om)
    points = radius * np.exp(2j * np.pi * np.arange(samples) / samples)
    values = np.linalg.det(points[:, None, None] ** 2 * M0 + points[:, None, None] * C0 + K0)
    coeffs = np.fft.fft(values) / samples / radius ** np.arange(samples)
    return coeffs[:degree + 1].real[::-1].copy()


@dataclass(frozen=True, slots=True)
class RouthHurwitzResult:
    """Routh array and Hurwitz minors of a real polynomial.

    Attributes
    ----------
    coefficients : ndarray
        Polynomial coefficients, highest power first.
    first_column : ndarray
        First column of the Routh array.
    sign_changes : int
        Number of sign changes in the first column = number of roots with Re > 0
        (when ``regular``).
    hurwitz_minors : ndarray
        Leading principal minors of the Hurwitz matrix (all > 0 iff stable).
    regular : bool
        False if a zero appeared in the first column (an epsilon was substituted;
        the count is then only indicative; roots on or near the imaginary axis).
    stable : bool
        All roots in the open left half-plane.
    """

    coefficients: np.ndarray
    first_column: np.ndarray
    sign_changes: int
    hurwitz_minors: np.ndarray
    regular: bool
    stable: bool


def routh_hurwitz(coefficients) -> RouthHurwitzResult:
    """Routh array and Hurwitz minors of a real polynomial (highest power first).

    Parameters
    ----------
    coefficients : array_like
        Real coefficients, leading one non-zero.
    """
    a = np.asarray(coefficients, dtype=float).reshape(-1)
    if a.size < 2 or a[0] == 0.0 or not np.all(np.isfinite(a)):
        raise ParameterError(f"coefficients = {a!r}: expected finite values with a non-zero leading one")
    if a[0] < 0:
        a = -a
    degree = a.size - 1
    width = degree // 2 + 1
    rows = [np.zeros(width), np.zeros(width)]
    rows[0][: len(a[0::2])] = a[0::2]
    rows[1][: len(a[1::2])] = a[1::2]
    regular = True
    tiny = np.finfo(float).eps * np.max(np.abs(a))
    for _ in range(degree - 1):
        upper, lower = rows[-2], rows[-1]
        if abs(lower[0]) <= tiny:
            regular = False
            lower = lower.copy()
            lower[0] = tiny if lower[0] >= 0 else -tiny
            rows[-1] = lower
        new = np.zeros(width)
        new[:-1] = (lower[0] * upper[1:] - upper[0] * lower[1:]) / lower[0]
        rows.append(new)
    first = np.array([row[0] for row in rows])
    signs = np.sign(first)
    signs[signs == 0] = 1
    changes = int(np.sum(signs[1:] != signs[:-1]))
    hurwitz = np.zeros((degree, degree))
    for i in range(degree):
        for j in range(degree):
            index = 2 * (j + 1) - (i + 1)
            if 0 <= index <= degree:
                hurwitz[i, j] = a[index]
    minors = np.array([np.linalg.det(hurwitz[:k, :k]) for k in range(1, degree + 1)])
    return RouthHurwitzResult(
        coefficients=a, first_column=first, sign_changes=changes, hurwitz_minors=minors,
        regular=regular, stable=bool(regular and changes == 0 and np.all(first > 0)),
    )


def routh_hurwitz_n2(params: ADBParameters, speed_rad_s: float) -> RouthHurwitzResult:
    """Routh-Hurwitz test of the two-ball balanced state (independent of the eigen-solver).

    Parameters
    ----------
    params : ADBParameters
        Parameters with ``n = 2``.
    speed_rad_s : float
        Shaft speed (rad/s).
    """
    if params.n != 2:
        raise ParameterError(f"n = {params.n}: routh_hurwitz_n2 expects n = 2 (the polynomial of degree 8)")
    return routh_hurwitz(characteristic_polynomial(params, speed_rad_s))


# --------------------------------------------------------------------------- sensitivity


@dataclass(frozen=True, slots=True)
class ThresholdSensitivity:
    """Sensitivity of the lowest stable speed to the identified rotor parameters.

    Attributes
    ----------
    threshold_rad_s : float
        Lower end of the first stable interval (rad/s).
    derivative_k, derivative_c, derivative_M : float
        Partial derivatives of the threshold: (rad/s)/(N/m), (rad/s)/(N s/m), (rad/s)/kg.
    std_rad_s : float
        Standard error propagated linearly from the covariance of the parameters (rad/s):
        √(gᵀ Σ g), g the derivatives, Σ = ``ParameterStd.covariance`` (their standard
        errors and correlation; independent when it has none).
    """

    threshold_rad_s: float
    derivative_k: float
    derivative_c: float
    derivative_M: float
    std_rad_s: float


def threshold_sensitivity(params: ADBParameters, std: ParameterStd, speed_max_rad_s: float,
                          *, relative_step: float = 1e-4) -> ThresholdSensitivity:
    """Propagate standard errors of ``k, c, M`` to the lowest stable speed.

    Central differences of :func:`stable_speed_intervals`' first boundary (refined to
    1e-12 ``omega_n``, so the difference quotients carry ~1e-8 relative error).

    Parameters
    ----------
    params : ADBParameters
        Nominal parameters.
    std : ParameterStd
        Standard errors of k (N/m), c (N s/m) and M (kg), and their correlation.
    speed_max_rad_s : float
        Upper end of the speed scan (rad/s).
    relative_step : float
        Finite-difference step relative to each parameter.
    """

    def threshold(p: ADBParameters) -> float:
        result = stable_speed_intervals(p, speed_max_rad_s, xtol_ratio=1e-12)
        if not len(result):
            raise ParameterError(
                f"no stable speed below speed_max_rad_s = {speed_max_rad_s!r}: the threshold is undefined"
            )
        return result.lowest_stable_speed_rad_s

    nominal = threshold(params)
    derivatives = {}
    for name in ("k", "c", "M"):
        value = getattr(params, name)
        step = relative_step * value if value > 0 else relative_step
        up = threshold(params.replace(**{name: value + step}))
        down = threshold(params.replace(**{name: max(value - step, 0.0)}))
        derivatives[name] = (up - down) / (value + step - max(value - step, 0.0))
    # g^T Σ g with the covariance of (k, c, M): identified from one mode they are strongly
    # correlated (k and M nearly +1), which a sum of independent terms would ignore
    gradient = np.array([derivatives[name] for name in STD_ORDER])
    sigma = math.sqrt(max(float(gradient @ std.covariance @ gradient), 0.0))
    return ThresholdSensitivity(
        threshold_rad_s=nominal,
        derivative_k=derivatives["k"],
        derivative_c=derivatives["c"],
        derivative_M=derivatives["M"],
        std_rad_s=sigma,
    )
