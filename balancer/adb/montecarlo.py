"""Parameter studies of the ball balancer chunked over a Dask cluster: stability maps, and the
probability of stable operation per speed when k, c, M carry their identification errors.

Every study is cut into the same chunks whether it runs here (``client=None``) or on a cluster
(``client=`` a ``distributed.Client`` or a scheduler address), and each chunk is the same pure
function of its inputs, so both paths give the same numbers (the Monte-Carlo draws are made
once, here, from ``seed``). Chunks are batched eigenvalue problems
(:func:`balancer.adb.stability.stability_map`), a few hundred members each.
"""
from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from modal.errors import ParameterError

from .equilibria import balanced_state
from .parameters import ADBParameters, ParameterStd
from .stability import StabilityMap, _analyse_balanced, _speeds_array, stability_map

__all__ = ["StabilityProbability", "sample_parameters", "stability_probability", "chunked_stability_map"]


@dataclass(frozen=True, slots=True)
class StabilityProbability:
    """Probability that the balanced state is stable, per speed, over the parameters' uncertainty.

    Attributes
    ----------
    speeds_rad_s : ndarray, shape (S,)
        Shaft speeds (rad/s).
    probability_stable : ndarray, shape (S,)
        Fraction of the Monte-Carlo draws whose balanced state is linearly stable (class 1) at that
        speed; a draw without a balanced state (``n m R < M e``) counts as not stable.
    std_probability : ndarray, shape (S,)
        Binomial standard error of that fraction, ``sqrt(p (1 - p) / n_samples)``.
    stable_count : ndarray of int, shape (S,)
        Stable draws per speed.
    n_samples : int
        Draws.
    seed : int
        Seed of the draws (the same seed gives the same draws and the same result).
    std : ParameterStd
        Standard errors of k (N/m), c (N s/m) and M (kg) the draws used.
    """

    speeds_rad_s: np.ndarray
    probability_stable: np.ndarray
    std_probability: np.ndarray
    stable_count: np.ndarray
    n_samples: int
    seed: int
    std: ParameterStd

    def archive_units(self) -> dict[str, str]:
        """Units of the fields whose names do not say them (for :mod:`modal.archive`)."""
        return {"probability_stable": "1", "std_probability": "1", "stable_count": "1", "seed": "1"}


def sample_parameters(params: ADBParameters, std: ParameterStd, n_samples: int, seed: int = 0) -> np.ndarray:
    """Normal draws of k, c, M about ``params`` with standard errors ``std``, correlated as
    ``std.correlation`` says (independent when it is None).

    Draws outside the physical range (k <= 0, M <= 0, c < 0) are drawn again (from the same
    generator, so the result depends on ``seed`` only).

    Parameters
    ----------
    params : ADBParameters
        Centre of the draws (its k, c, M).
    std : ParameterStd
        Standard errors of k (N/m), c (N s/m) and M (kg).
    n_samples : int
        Number of draws (>= 1).
    seed : int
        Seed of the generator.

    Returns
    -------
    ndarray, shape (n_samples, 3)
        Columns k (N/m), c (N s/m), M (kg).
    """
    if isinstance(n_samples, bool) or not isinstance(n_samples, (int, np.integer)) or n_samples < 1:
        raise ParameterError(f"n_samples = {n_samples!r}: expected a whole number >= 1")
    rng = np.random.default_rng(seed)
    centre = np.array([params.k, params.c, params.M])
    sigma = np.array([std.k, std.c, std.M])
    if std.correlation is None:
        def draw(count):
            return centre + sigma * rng.standard_normal((count, 3))
    else:
        # a square root of the correlation that tolerates its singular limit (k, M at +1)
        values, vectors = np.linalg.eigh(std.correlation)
        root = vectors * np.sqrt(np.clip(values, 0.0, None))

        def draw(count):
            return centre + (rng.standard_normal((count, 3)) @ root.T) * sigma
    out = draw(int(n_samples))
    for _ in range(1000):
        bad = (out[:, 0] <= 0) | (out[:, 1] < 0) | (out[:, 2] <= 0)
        if not bad.any():
            return out
        out[bad] = draw(int(bad.sum()))
    raise ParameterError(f"std = {std}: the draws of k, c, M keep leaving the physical range (k > 0, c >= 0, "
                         "M > 0); expected standard errors well below the values")


def stable_counts(params: ADBParameters, speeds_rad_s: np.ndarray, draws: np.ndarray,
                  condition_cap: float | None = 1e8) -> np.ndarray:
    """Stable draws per speed for one chunk of draws (columns k, c, M); the unit of work of
    :func:`stability_probability`."""
    speeds = _speeds_array(speeds_rad_s)
    members = []
    for k, c, M in draws:
        member = params.replace(k=float(k), c=float(c), M=float(M))
        try:
            member.require_balancing()
        except ParameterError:
            continue  # no balanced state: not stable
        members.append(member)
    if not members:
        return np.zeros(speeds.shape[0], dtype=int)
    angles = [balanced_state(p)[2:2 + p.n] for p in members]
    analysis = _analyse_balanced(members, speeds, angles, condition_cap)
    codes = analysis.stability_class.reshape(len(members), speeds.shape[0])
    return np.sum(codes == 1, axis=0).astype(int)


def _run_chunks(function, chunks: Sequence[tuple], client: Any) -> list:
    """``[function(*chunk) for chunk in chunks]``, here or on a Dask cluster (same chunks, same order)."""
    if client is None:
        return [function(*chunk) for chunk in chunks]
    from modal.batch.cluster import open_client

    with open_client(client) as dask:
        futures = [dask.submit(function, *chunk, pure=False) for chunk in chunks]
        return dask.gather(futures)


def stability_probability(params: ADBParameters, std: ParameterStd, speeds_rad_s, n_samples: int = 2000, *,
                          seed: int = 0, client: Any = None, chunk_size: int = 250,
                          condition_cap: float | None = 1e8) -> StabilityProbability:
    """Monte-Carlo probability of stable operation per speed, propagating the standard errors of
    the identified k, c, M (:func:`balancer.adb.identified_std`) into the stability verdict.

    Parameters
    ----------
    params : ADBParameters
        Nominal parameters (the identified values).
    std : ParameterStd
        Their standard errors and correlation (:func:`balancer.adb.identified_std` carries the
        identification's: k and M from one modal constant are nearly +1 correlated, and
        independent draws would overstate the spread of ``omega_n`` about 4x); the draws are
        normal with that covariance, independent when ``std.correlation`` is None.
    speeds_rad_s : array_like, shape (S,)
        Shaft speeds (rad/s, > 0).
    n_samples : int
        Draws (the standard error of a probability is at most ``0.5 / sqrt(n_samples)``).
    seed : int
        Seed of the draws.
    client : distributed.Client or str, optional
        Run the chunks on this Dask client or scheduler address; default here.
    chunk_size : int
        Draws per chunk (a task on the cluster).
    condition_cap : float or None
        As in :func:`balancer.adb.stability.stability_map`.

    Returns
    -------
    StabilityProbability
    """
    speeds = _speeds_array(speeds_rad_s)
    if isinstance(chunk_size, bool) or not isinstance(chunk_size, (int, np.integer)) or chunk_size < 1:
        raise ParameterError(f"chunk_size = {chunk_size!r}: expected a whole number >= 1")
    draws = sample_parameters(params, std, n_samples, seed)
    chunks = [(params, speeds, draws[i:i + chunk_size], condition_cap) for i in range(0, len(draws), chunk_size)]
    counts = np.sum(_run_chunks(stable_counts, chunks, client), axis=0).astype(int)
    p = counts / len(draws)
    return StabilityProbability(speeds_rad_s=speeds, probability_stable=p,
                                std_probability=np.sqrt(p * (1 - p) / len(draws)), stable_count=counts,
                                n_samples=len(draws), seed=int(seed), std=std)


def chunked_stability_map(params: ADBParameters, speeds_rad_s, parameter: str, values, *, client: Any = None,
                          chunk_size: int = 50, ball_angles_rad=None,
                          condition_cap: float | None = 1e8) -> StabilityMap:
    """:func:`balancer.adb.stability.stability_map` cut into chunks of ``values`` (tasks on a Dask
    cluster with ``client``); the same map as the one-piece call, row for row.

    Parameters
    ----------
    params : ADBParameters
        The rotor and balls.
    speeds_rad_s : array_like, shape (S,)
        Shaft speeds, rad/s.
    parameter : str
        Name of the varied :class:`ADBParameters` field.
    values : array_like, shape (V,)
        Its values (SI units of that field).
    client : dask.distributed.Client, optional
        Cluster to run the chunks on; None runs them here.
    chunk_size : int
        Values per chunk (>= 1).
    ball_angles_rad : array_like, optional
        Balanced member to analyse (default: the symmetric one), rad.
    condition_cap : float or None
        As in :func:`balancer.adb.stability.stability_map`.

    Returns
    -------
    StabilityMap
    """
    values = np.atleast_1d(np.asarray(values, dtype=float)).reshape(-1)
    if isinstance(chunk_size, bool) or not isinstance(chunk_size, (int, np.integer)) or chunk_size < 1:
        raise ParameterError(f"chunk_size = {chunk_size!r}: expected a whole number >= 1")
    chunks = [(params, speeds_rad_s, parameter, values[i:i + chunk_size])
              for i in range(0, len(values), chunk_size)]
    call = _MapChunk(ball_angles_rad, condition_cap)
    parts = _run_chunks(call, chunks, client)
    first = parts[0]
    stacked = {name: np.concatenate([getattr(p, name) for p in parts], axis=0)
               for name in ("values", "speed_ratio", "max_real_part_per_s", "rounding_bound_per_s",
                            "growth_rate_nondimensional", "stability_class")}
    return StabilityMap(parameter=first.parameter, speeds_rad_s=first.speeds_rad_s, **stacked)


@dataclass(frozen=True)
class _MapChunk:
    """One chunk of a stability map (a picklable callable with the keyword options)."""

    ball_angles_rad: Any
    condition_cap: float | None

    def __call__(self, params, speeds_rad_s, parameter, values) -> StabilityMap:
        return stability_map(params, speeds_rad_s, parameter, values, ball_angles_rad=self.ball_angles_rad,
                             condition_cap=self.condition_cap)


