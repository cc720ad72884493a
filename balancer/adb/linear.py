"""Eigenvalues of linearisations, with a rounding-aware stability class.

The Jacobian is taken in SI units (from :mod:`.equations`) and rescaled to the
nondimensional variables (positions / R, time * omega_n) before the eigenvalue solve,
so that the rounding bound below is computed on a well-scaled matrix.

Classification (``numerics.md`` section 6): let ``lambda_c`` be the eigenvalue with the
largest real part, ``kappa = ||x|| ||y|| / |y^H x|`` its condition number and
``||J||_F`` the Frobenius norm (an upper bound of the 2-norm) of the scaled Jacobian.
The rounding bound is ``10 kappa eps ||J||_F``; the state is *marginal* when
``|Re lambda_c|`` is below it, else stable or unstable by the sign.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = [
    "STABLE",
    "MARGINAL",
    "UNSTABLE",
    "CLASS_NAMES",
    "EigenAnalysis",
    "eigen_analysis",
    "eigen_analysis_nondimensional",
    "state_scales",
]

STABLE = 1
MARGINAL = 0
UNSTABLE = -1
CLASS_NAMES = {STABLE: "stable", MARGINAL: "marginal", UNSTABLE: "unstable"}
_EPS = np.finfo(float).eps


def state_scales(n: int, race_radius_m, natural_frequency_rad_s, *, fixed_frame: bool = False):
    """Per-component scale factors ``S`` turning SI states into nondimensional ones.

    Parameters
    ----------
    n : int
        Ball count.
    race_radius_m, natural_frequency_rad_s : ndarray, shape (B,)
        Race radius (m) and natural frequency (rad/s) per member.
    fixed_frame : bool
        Append the rotor-angle component (scale 1).

    Returns
    -------
    ndarray, shape (B, N)
        Multiply an SI state by this to get ``[u/R, v/R, phi, u'/(R wn), v'/(R wn), phi'/wn]``.
    """
    R = np.atleast_1d(np.asarray(race_radius_m, dtype=float))
    wn = np.atleast_1d(np.asarray(natural_frequency_rad_s, dtype=float))
    ones = np.ones((R.shape[0], n))
    parts = [1.0 / R[:, None], 1.0 / R[:, None], ones,
             1.0 / (R * wn)[:, None], 1.0 / (R * wn)[:, None], ones / wn[:, None]]
    if fixed_frame:
        parts.append(np.ones((R.shape[0], 1)))
    return np.concatenate([np.broadcast_to(p, (R.shape[0], p.shape[1])) for p in parts], axis=1)


@dataclass(frozen=True, slots=True)
class EigenAnalysis:
    """Eigenvalues of a batch of linearisations and their stability class.

    Attributes
    ----------
    eigenvalues_per_s : ndarray, shape (B, N - n_dropped), complex
        Eigenvalues in 1/s, sorted by decreasing real part, after dropping
        ``n_dropped`` eigenvalues of smallest modulus (the exact zeros of a family).
    max_real_part_per_s : ndarray, shape (B,)
        Largest real part (1/s), i.e. the growth rate of the least stable mode.
    growth_rate_nondimensional : ndarray, shape (B,)
        The same divided by ``omega_n``.
    rounding_bound_per_s : ndarray, shape (B,)
        ``10 kappa eps ||J||_F`` in 1/s: real parts smaller than this are not resolved.
        Where that calls the verdict marginal, the smaller of it and ten times the largest
        change of the growth rate when the Jacobian is perturbed at the rounding level
        (:func:`_perturbed_bound`): near a double eigenvalue kappa is huge while the
        eigenvalues themselves move only by about sqrt(eps).
    critical_condition_number : ndarray, shape (B,)
        Condition number ``kappa`` of the critical eigenvalue (inf if defective).
    stability_class : ndarray of int, shape (B,)
        ``STABLE`` (1), ``MARGINAL`` (0) or ``UNSTABLE`` (-1).
    n_dropped : int
        Number of eigenvalues dropped as the family's zero eigenvalues.
    condition_computed : ndarray of bool, shape (B,)
        False where the screening mode skipped the eigenvectors because the growth rate
        was far from zero; there ``critical_condition_number`` holds the assumed cap and
        ``rounding_bound_per_s`` the bound under that cap.
    """

    eigenvalues_per_s: np.ndarray
    max_real_part_per_s: np.ndarray
    growth_rate_nondimensional: np.ndarray
    rounding_bound_per_s: np.ndarray
    critical_condition_number: np.ndarray
    stability_class: np.ndarray
    n_dropped: int
    condition_computed: np.ndarray

    @property
    def class_names(self) -> tuple[str, ...]:
        """Stability class of each member as a word."""
        return tuple(CLASS_NAMES[int(code)] for code in self.stability_class)


def _condition_numbers(vectors: np.ndarray) -> np.ndarray:
    """Eigenvalue condition numbers from unit-norm right eigenvectors (columns)."""
    cond = np.full(vectors.shape[:-1], np.inf)
    # a defective eigenvalue has (nearly) parallel eigenvectors: the inverse and its norm
    # overflow, and inf is the right condition number
    with np.errstate(over="ignore", invalid="ignore"):
        try:
            inverse = np.linalg.inv(vectors)
            cond = np.linalg.norm(inverse, axis=-1)  # rows of X^-1 are y^H with y^H x = 1
        except np.linalg.LinAlgError:
            for index in range(vectors.shape[0]):
                try:
                    cond[index] = np.linalg.norm(np.linalg.inv(vectors[index]), axis=-1)
                except np.linalg.LinAlgError:
                    cond[index] = np.inf
    cond[~np.isfinite(cond)] = np.inf
    return cond


#: perturbed Jacobians tried where the first-order bound calls a verdict marginal
PERTURBATION_TRIALS = 4


def _leading_real_part(values: np.ndarray, n_zero_to_drop: int) -> np.ndarray:
    """Largest real part per row after dropping the ``n_zero_to_drop`` eigenvalues of least modulus."""
    if n_zero_to_drop:
        keep = np.sort(np.argsort(np.abs(values), axis=-1)[:, n_zero_to_drop:], axis=-1)
        values = np.take_along_axis(values, keep, axis=-1)
    return np.max(values.real, axis=-1)


def _perturbed_bound(scaled: np.ndarray, growth: np.ndarray, norm: np.ndarray, n_zero_to_drop: int) -> np.ndarray:
    """Ten times the largest change of the growth rate under rounding-size perturbations.

    The first-order bound ``kappa eps ||J||`` holds for a simple eigenvalue; where two
    eigenvalues nearly coincide kappa grows without limit (4e16 at one speed of a five-ball
    rotor, which split a stable interval at a grid point), while the eigenvalues move only
    by about sqrt(eps ||J|| ||N||). Each trial adds a matrix of independent normal entries
    of standard deviation ``eps ||J||_F``, whose effect on a simple eigenvalue is of the
    size of the first-order bound and on a nearly defective one of the size of the square
    root. The generator is seeded: the verdict is deterministic.
    """
    rng = np.random.default_rng(0)
    change = np.zeros(scaled.shape[0])
    for _ in range(PERTURBATION_TRIALS):
        noise = rng.standard_normal(scaled.shape) * (_EPS * norm)[:, None, None]
        trial = _leading_real_part(np.linalg.eigvals(scaled + noise), n_zero_to_drop)
        change = np.maximum(change, np.abs(trial - growth))
    return 10.0 * change


def eigen_analysis(jacobian_si, n: int, race_radius_m, natural_frequency_rad_s, *,
                   n_zero_to_drop: int = 0, fixed_frame: bool = False,
                   condition_cap: float | None = None) -> EigenAnalysis:
    """Eigenvalues and stability class of a batch of Jacobians.

    Parameters
    ----------
    jacobian_si : ndarray, shape (B, N, N)
        Jacobians of the SI state equations (1/s and mixed units).
    n : int
        Ball count.
    race_radius_m, natural_frequency_rad_s : ndarray, shape (B,) or float
        Scales per member (m, rad/s).
    n_zero_to_drop : int
        How many eigenvalues of smallest modulus to discard (``n - 2`` at a balanced
        state with ``n >= 3``, whose balanced states form an (n-2)-dimensional family).
    fixed_frame : bool
        Whether the Jacobian is of the fixed-frame state (with the rotor angle).
    condition_cap : float, optional
        Screening mode for large maps (about 1.6x faster): eigenvalues only, and
        eigenvectors (for the condition number) only where ``|growth| < 10 cap eps ||J||_F``.
        Elsewhere the class follows the sign, which is right whenever the critical
        condition number is below ``cap`` (1e8 is a safe choice: beyond it an eigenvalue
        is numerically defective).  Default None: condition numbers everywhere.

    Returns
    -------
    EigenAnalysis
    """
    jac = np.asarray(jacobian_si, dtype=float)
    batch = jac.shape[0]
    R = np.broadcast_to(np.asarray(race_radius_m, dtype=float), (batch,))
    wn = np.broadcast_to(np.asarray(natural_frequency_rad_s, dtype=float), (batch,))
    scale = state_scales(n, R, wn, fixed_frame=fixed_frame)
    scaled = scale[:, :, None] * jac / scale[:, None, :] / wn[:, None, None]
    return eigen_analysis_nondimensional(scaled, wn, n_zero_to_drop=n_zero_to_drop, condition_cap=condition_cap)


def eigen_analysis_nondimensional(scaled, natural_frequency_rad_s, *, n_zero_to_drop: int = 0,
                                  condition_cap: float | None = None) -> EigenAnalysis:
    """As :func:`eigen_analysis`, for Jacobians already in nondimensional variables.

    Parameters
    ----------
    scaled : ndarray, shape (B, N, N)
        Jacobians in the variables ``(u/R, v/R, phi, u'/(R wn), v'/(R wn), phi'/wn)``
        and time ``wn t``.
    natural_frequency_rad_s : ndarray, shape (B,) or float
        ``omega_n`` per member (rad/s), to return eigenvalues in 1/s.
    n_zero_to_drop, condition_cap
        As in :func:`eigen_analysis`.
    """
    scaled = np.asarray(scaled, dtype=float)
    batch = scaled.shape[0]
    wn = np.broadcast_to(np.asarray(natural_frequency_rad_s, dtype=float), (batch,))
    if not np.all(np.isfinite(scaled)):
        from modal.errors import ParameterError

        raise ParameterError("Jacobian has non-finite entries; expected finite parameters and state")
    norm = np.linalg.norm(scaled, axis=(-2, -1))
    if condition_cap is None:
        values, vectors = np.linalg.eig(scaled)
        cond = _condition_numbers(vectors)
        computed = np.ones(batch, dtype=bool)
    else:
        values = np.linalg.eigvals(scaled)
        cond = np.full(values.shape, float(condition_cap))
        computed = np.zeros(batch, dtype=bool)
        trial = values
        if n_zero_to_drop:
            keep = np.sort(np.argsort(np.abs(values), axis=-1)[:, n_zero_to_drop:], axis=-1)
            trial = np.take_along_axis(values, keep, axis=-1)
        near = np.abs(np.max(trial.real, axis=-1)) < 10.0 * condition_cap * _EPS * norm
        if np.any(near):
            values_near, vectors_near = np.linalg.eig(scaled[near])
            values[near] = values_near
            cond[near] = _condition_numbers(vectors_near)
            computed[near] = True
    if n_zero_to_drop:
        order = np.argsort(np.abs(values), axis=-1)
        keep = np.sort(order[:, n_zero_to_drop:], axis=-1)
        values = np.take_along_axis(values, keep, axis=-1)
        cond = np.take_along_axis(cond, keep, axis=-1)
    order = np.argsort(-values.real, axis=-1, kind="stable")
    values = np.take_along_axis(values, order, axis=-1)
    cond = np.take_along_axis(cond, order, axis=-1)
    growth = values[:, 0].real
    kappa = cond[:, 0]
    with np.errstate(over="ignore"):  # kappa of a defective eigenvalue: the bound is inf
        bound = 10.0 * kappa * _EPS * norm

    def classify(bound):
        return np.where(growth > bound, UNSTABLE, np.where(growth < -bound, STABLE, MARGINAL)).astype(int)

    codes = classify(bound)
    unresolved = codes == MARGINAL
    if np.any(unresolved):
        bound[unresolved] = np.minimum(bound[unresolved], _perturbed_bound(
            scaled[unresolved], growth[unresolved], norm[unresolved], n_zero_to_drop))
        codes = classify(bound)
    return EigenAnalysis(
        eigenvalues_per_s=values * wn[:, None],
        max_real_part_per_s=growth * wn,
        growth_rate_nondimensional=growth,
        rounding_bound_per_s=bound * wn,
        critical_condition_number=kappa,
        stability_class=codes,
        n_dropped=int(n_zero_to_drop),
        condition_computed=computed,
    )
