"""What the check run after a correction says: did the influence coefficients hold, and what next.

After the correction is mounted the same readings are taken again (the check run, ``after``).
If the influence coefficients hold and the masses sit where the correction says, the check run
equals the prediction ``initial + alpha @ u`` within the errors of the readings and of ``alpha``
(which the trial runs' reading errors make). How far it may be off is measured on the job
itself, by a parametric bootstrap: every reading is redrawn with a relative circular Gaussian
error of ``reading_noise`` (0.05: 5 % of its amplitude, about 3 deg of phase, a field analyser's
repeatability on a steady machine), ``alpha`` and a least-squares correction are recomputed and
the check run such a correction would give is drawn too; the statistic

    discrepancy = ||after - predicted|| / ||predicted - initial||

(the check run's miss as a fraction of the change the correction was to make) is compared with
the 99th percentile of its bootstrap draws. Above it the check run disagrees with the prediction:
flag ``check_run_disagrees``. Simulated jobs with 2-5 % reading noise and trials changing the
readings by 10-30 % flag 0-2 % of correctly mounted corrections (tests/balancer/influence).

The usual causes in the field each predict their own check run, in the readings' terms
(``D_j = trial_run_j - initial``, ``t_j`` the trial unbalance):

* ``mirrored_angles``: every mass's angle measured with rotation instead of against it, or the
  phases read as lead instead of lag (both give the same readings):
  ``initial + sum_j D_j conj(u_j / t_j)``;
* ``added_where_removed``: the correction removed where it should be added, or mounted 180 deg
  off: ``initial - alpha @ u``;
* ``trial_left_on``: trial mass j not removed: ``initial + alpha @ u + D_j``;
* ``planes_swapped`` (two planes): each plane's correction mounted on the other.

When the check run disagrees and one of these explains it within the bootstrap's limit (and at
least three times better than the prediction), it is named (the best first, with any others that fit as well); a trim is then not offered (mount
the correction as computed first). A check run that agrees gives the usual trim correction from
the same ``alpha``; one that disagrees unexplained gives a trim from ``alpha`` updated by the
check run (the correction itself taken as one more trial: a rank-one, Broyden, update that makes
``alpha @ u`` equal the change measured).
"""
from __future__ import annotations

import copy

from dataclasses import dataclass

import numpy as np

from modal.errors import ParameterError, QualityWarning, warn

from .bootstrap import BOOTSTRAP_DRAWS, redraw, redrawn_jobs
from .coefficients import correction

__all__ = ["CheckRun", "check_run", "check_reading_noise", "DEFAULT_READING_NOISE", "BOOTSTRAP_DRAWS", "CAUSES"]

#: relative standard deviation of a reading assumed by default (amplitude 5 %, phase about 3 deg)
DEFAULT_READING_NOISE = 0.05
_QUANTILE = 0.99
#: a cause is named when it explains the check run at least this many times better than the prediction
_BETTER = 3.0

CAUSES = {
    "mirrored_angles": "the masses' angles measured with rotation instead of against it (or the phases read as "
                       "lead instead of lag)",
    "added_where_removed": "the correction removed where it should be added (or mounted 180 deg off)",
    "trial_left_on": "a trial mass left on",
    "planes_swapped": "the two planes' corrections swapped",
}


@dataclass(frozen=True, slots=True)
class CheckRun:
    """The check run set against the prediction, and the trim correction.

    Attributes
    ----------
    predicted : ndarray of complex, shape (n_readings,)
        Readings the correction was predicted to leave (SI).
    measured : ndarray of complex, shape (n_readings,)
        The check run (SI).
    discrepancy : float
        ``||measured - predicted|| / ||predicted - initial||``.
    discrepancy_limit : float
        The 99th percentile of the discrepancy under ``reading_noise`` with the correction mounted as computed.
    reading_noise : float
        Relative standard deviation of a reading assumed (1).
    agrees : bool
        ``discrepancy <= discrepancy_limit``.
    cause : str
        One of :data:`CAUSES` that explains a disagreeing check run ("" when none or when it agrees).
    cause_plane : int
        The plane (1-based) the cause concerns (``trial_left_on``); 0 otherwise.
    other_causes : tuple of str
        Further causes that explain the check run as well within the limit (the readings cannot tell them
        apart: a mirrored correction whose masses sit 90 deg from their trials' is also a reversed one).
    trim_kg_m : ndarray of complex, shape (n_planes,)
        Trim correction to add to what is mounted (kg m; empty when a cause was named).
    trim_residual : ndarray of complex, shape (n_readings,)
        Readings the trim is predicted to leave (SI; empty when a cause was named).
    alpha_updated : bool
        Whether the trim used ``alpha`` updated by the check run.
    flags : tuple of str
        ``("check_run_disagrees",)`` or ``()``.
    si_units : str
        The readings' SI unit (m, m/s or m/s^2).
    """

    predicted: np.ndarray
    measured: np.ndarray
    discrepancy: float
    discrepancy_limit: float
    reading_noise: float
    agrees: bool
    cause: str
    cause_plane: int
    other_causes: tuple[str, ...]
    trim_kg_m: np.ndarray
    trim_residual: np.ndarray
    alpha_updated: bool
    flags: tuple[str, ...]
    si_units: str = "m"

    def archive_units(self) -> dict[str, str]:
        """Units the field names cannot say (for the archive)."""
        return {"predicted": self.si_units, "measured": self.si_units, "trim_residual": self.si_units,
                "discrepancy": "1", "discrepancy_limit": "1", "reading_noise": "1", "cause_plane": "1"}

    @property
    def message(self) -> str:
        """One sentence saying what the check run shows."""
        if self.agrees:
            return (f"the check run agrees with the prediction (miss {100 * self.discrepancy:.0f} % of the predicted "
                    f"change; up to {100 * self.discrepancy_limit:.0f} % expected at {100 * self.reading_noise:g} % "
                    "reading noise)")
        text = (f"the check run disagrees with the prediction: it misses by {100 * self.discrepancy:.0f} % of the "
                f"predicted change, where reading errors of {100 * self.reading_noise:g} % explain up to "
                f"{100 * self.discrepancy_limit:.0f} %")
        if self.cause:
            what = " or ".join([CAUSES[self.cause] + (f" (plane {self.cause_plane})" if self.cause_plane else "")]
                               + [CAUSES[c] for c in self.other_causes])
            fix = ("remove it" if self.cause == "trial_left_on" and not self.other_causes
                   else "mount the masses as computed")
            return text + f"; it matches {what}: {fix} and take the check run again"
        return text + ("; no mounting mistake explains it (a nonlinear machine, a speed or load changed between the "
                       "runs, or trial runs too weak); the trim below uses alpha updated by the check run")


def check_reading_noise(reading_noise) -> float:
    """``reading_noise`` as a float, or a one-line error: a fraction in (0, 1), such as 0.05 for 5 %."""
    if isinstance(reading_noise, bool) or not isinstance(reading_noise, (int, float)) or not 0 < reading_noise < 1:
        raise ParameterError(f"reading_noise = {reading_noise!r}: expected the readings' relative repeatability, "
                             "a fraction in (0, 1) such as 0.05 for 5 %")
    return float(reading_noise)


def discrepancy_limit(initial, trial_runs, trial_unbalance_kg_m, reading_noise: float, weights=None,
                      seed: int = 0, draws=None) -> float:
    """The 99th percentile of the check run's discrepancy with the correction mounted as computed (module notes).

    Least-squares corrections are drawn whatever the job's method (min-max's differ from them by far less than
    the reading errors move either). ``draws``: :func:`~balancer.influence.bootstrap.redrawn_jobs` of the same job,
    noise and seed, when already made (its generator is copied, not advanced).
    """
    v0 = np.asarray(initial, dtype=complex)
    alpha = (np.asarray(trial_runs, dtype=complex) - v0).T / np.asarray(trial_unbalance_kg_m, dtype=complex)
    if draws is None:
        draws = redrawn_jobs(v0, trial_runs, trial_unbalance_kg_m, reading_noise, weights, seed)
    v0_b, alpha_b, u_b, rng = draws
    rng = copy.deepcopy(rng)
    predicted_b = v0_b + np.einsum("bij,bj->bi", alpha_b, u_b)
    after_b = redraw(v0 + np.einsum("ij,bj->bi", alpha, u_b), reading_noise, rng, per_draw=True)
    change = np.linalg.norm(predicted_b - v0_b, axis=1)
    ratio = np.linalg.norm(after_b - predicted_b, axis=1) / np.where(change > 0, change, np.inf)
    return float(np.quantile(ratio, _QUANTILE))


def _causes(initial: np.ndarray, trial_runs: np.ndarray, trials: np.ndarray, alpha: np.ndarray,
            u: np.ndarray) -> list[tuple[str, int, np.ndarray]]:
    """Each cause's predicted check run (module notes): (name, plane or 0, readings)."""
    change = trial_runs - initial[None, :]
    out = [("mirrored_angles", 0, initial + (change.T * np.conj(u / trials)).sum(axis=1)),
           ("added_where_removed", 0, initial - alpha @ u)]
    out += [("trial_left_on", j + 1, initial + alpha @ u + change[j]) for j in range(trials.size)]
    if trials.size == 2:
        out.append(("planes_swapped", 0, initial + alpha @ u[::-1]))
    return out


def check_run(alpha, initial, trial_runs, trial_unbalance_kg_m, correction_kg_m, after, *, method: str = "least_squares",
              weights=None, reading_noise: float = DEFAULT_READING_NOISE, si_units: str = "m",
              field: str = "after", draws=None) -> CheckRun:
    """Set a check run against the prediction, name a mounting mistake that explains it, and give the trim.

    Parameters
    ----------
    alpha : ndarray of complex, shape (n_readings, n_planes)
        Influence coefficients the correction was computed with.
    initial : ndarray of complex, shape (n_readings,)
    trial_runs : ndarray of complex, shape (n_planes, n_readings)
    trial_unbalance_kg_m : ndarray of complex, shape (n_planes,)
    correction_kg_m : ndarray of complex, shape (n_planes,)
        The correction mounted (kg m).
    after : ndarray of complex, shape (n_readings,)
        The check run, in the readings' unit.
    method, weights
        As for :func:`~balancer.influence.correction` (the trim uses them).
    reading_noise : float
        Relative standard deviation of a reading (0.05: 5 %), from the analyser's repeatability.
    si_units : str
        The readings' SI unit, for the archive.
    field : str
        Name used in messages.
    draws : tuple, optional
        :func:`~balancer.influence.bootstrap.redrawn_jobs` of this job at ``reading_noise`` (seed 0), when the
        caller has them (:func:`~balancer.influence.balance` shares them with the correction's spread).

    Returns
    -------
    CheckRun

    Warns
    -----
    QualityWarning
        When the check run disagrees with the prediction (the message says by how much and, where one fits, why).
    """
    check_reading_noise(reading_noise)
    a = np.asarray(alpha, dtype=complex)
    v0 = np.asarray(initial, dtype=complex)
    runs = np.asarray(trial_runs, dtype=complex)
    trials = np.asarray(trial_unbalance_kg_m, dtype=complex)
    u = np.asarray(correction_kg_m, dtype=complex)
    measured = np.asarray(after, dtype=complex)
    if measured.shape != v0.shape:
        raise ParameterError(f"{field}: {measured.size} readings but initial has {v0.size}; expected the same readings")
    predicted = v0 + a @ u
    scale = float(np.linalg.norm(predicted - v0))
    discrepancy = float(np.linalg.norm(measured - predicted)) / scale if scale > 0 else 0.0
    limit = discrepancy_limit(v0, runs, trials, float(reading_noise), weights, draws=draws)
    agrees = discrepancy <= limit
    cause, plane, others = "", 0, ()
    if not agrees:
        fitting = sorted((float(np.linalg.norm(measured - readings)) / scale, name, j)
                         for name, j, readings in _causes(v0, runs, trials, a, u))
        fitting = [(name, j) for miss, name, j in fitting if miss <= limit and miss * _BETTER <= discrepancy]
        if fitting:
            cause, plane = fitting[0]
            others = tuple(dict.fromkeys(name for name, _ in fitting[1:] if name != cause))
    alpha_trim, updated = a, False
    if not agrees and not cause:
        step = (measured - predicted)[:, None] * np.conj(u)[None, :] / float(np.vdot(u, u).real)
        alpha_trim, updated = a + step, True
    if cause:
        trim, trim_residual = np.zeros(0, dtype=complex), np.zeros(0, dtype=complex)
    else:
        result = correction(alpha_trim, measured, method=method, weights=weights)
        trim, trim_residual = result.unbalance_kg_m, result.residual
    run = CheckRun(predicted=predicted, measured=measured, discrepancy=discrepancy, discrepancy_limit=limit,
                   reading_noise=float(reading_noise), agrees=agrees, cause=cause, cause_plane=plane, other_causes=others,
                   trim_kg_m=trim,
                   trim_residual=trim_residual, alpha_updated=updated,
                   flags=() if agrees else ("check_run_disagrees",), si_units=si_units)
    if not agrees:
        warn(f"{field}: {run.message}", QualityWarning)
    return run
