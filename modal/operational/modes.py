"""From chains of stable poles to one estimate per physical mode, with error bars.

Each chain's poles are followed through the record's blocks to first order
(:class:`modal.operational.ssi.Perturbation`); the chain reports the pole of the order where
its frequency is best determined (the smallest standard error): over-fitted orders inflate the
first-order errors of the poles beside their spurious neighbours, and the errors there are larger
too (an estimator whose under-fitted low orders hold biased poles of small error looks only in the upper
half of the chain's orders, ``representative="upper_half"``). Two chains whose representatives agree within their errors in frequency, with one shape, are
one mode: the weaker is dropped.
"""
from __future__ import annotations

import numpy as np

from ..parallel import map_over_threads
from ..units import TWO_PI
from .correlations import MAX_BLOCKS
from .pole import PoleEstimate
from .selection import DETERMINED_SIGMAS, Cluster, shape_mac

__all__ = ["pole_errors", "estimates_from_clusters", "error_blocks", "upper_half", "resolved"]

#: the blocks of the record used for the error bars last at least this many decay times 1/(ζω) of the
#: slowest-decaying mode (their correlation estimates are then nearly independent)...
DECAY_TIMES_PER_BLOCK = 10
#: ... and there are between these many blocks
MIN_ERROR_BLOCKS, MAX_ERROR_BLOCKS = 8, MAX_BLOCKS
#: a chain's pole is reported from an order whose frequency and damping lie within this many of their
#: standard errors from the chain's medians (an under-fitted low order can hold a biased pole of small error)
CONSENSUS_SIGMAS = 2.0
#: the errors are computed at this many orders spread over the sweep
PROBE_ORDERS = 8
#: a chain whose frequency error exceeds this fraction of its half-power bandwidth ζ·fn is a noise pole
UNRESOLVED_FRACTION = 0.5
#: a duplicate lies within this many combined standard errors in frequency and has a MAC above DUPLICATE_MAC
DUPLICATE_SIGMAS, DUPLICATE_MAC = 3.0, 0.9


def pole_errors(pole: np.ndarray, d_pole: np.ndarray):
    """Standard errors of (frequency Hz, damping ratio) of poles λ (rad/s) from their block deviations (blocks, n)."""
    wn = np.abs(pole)
    d_wn = np.real(np.conj(pole) * d_pole) / wn
    d_zeta = -d_pole.real / wn + pole.real * d_wn / wn**2
    return np.sqrt(np.sum(d_wn**2, axis=0)) / TWO_PI, np.sqrt(np.sum(d_zeta**2, axis=0))


def error_blocks(duration_s: float, poles: np.ndarray, n_available: int) -> int:
    """How many blocks the record is cut into for the error bars (see :data:`DECAY_TIMES_PER_BLOCK`).

    Tones (damping ≤ 0.1 %) are left out of the decay time: they never decay and are not modes."""
    sigma = -np.asarray(poles).real
    decaying = sigma[sigma > 1e-3 * np.abs(poles)]
    slowest = 1.0 / decaying.min() if decaying.size else 0.0
    wanted = int(duration_s / (DECAY_TIMES_PER_BLOCK * slowest)) if slowest > 0 else MAX_ERROR_BLOCKS
    return int(min(max(wanted, MIN_ERROR_BLOCKS), MAX_ERROR_BLOCKS, n_available))


def _physical_shape(unit_shape: np.ndarray, d_unit: np.ndarray | None, scale: np.ndarray):
    """The shape in the channels' own units, its largest determined entry 1, and the standard error of each entry.

    ``unit_shape`` was found on unit-RMS channels (its largest entry 1, so its deviations ``d_unit``
    (blocks, channels) vanish there); the channels' RMS ``scale`` brings it back. The entry the shape is
    normalised to is the largest of those the record determines (beyond :data:`DETERMINED_SIGMAS` standard errors
    of zero): a channel of noise only (a disconnected sensor picking up hum, a broken cable) has a large RMS
    and, in its own units, a large entry that is noise, and dividing by it would make every other entry noise
    too.
    """
    raw = unit_shape * scale
    if d_unit is None:
        lead = int(np.argmax(np.abs(raw)))
        return raw / raw[lead], np.full(scale.size, np.nan)
    unit_std = np.sqrt(np.sum(np.abs(d_unit) ** 2, axis=0))
    determined = np.abs(unit_shape) > DETERMINED_SIGMAS * unit_std  # (the unit shape's own lead is, unless NaN)
    lead = int(np.argmax(np.where(determined, np.abs(raw), -1.0) if determined.any() else np.abs(raw)))
    shape = raw / raw[lead]
    d_raw = d_unit * scale[None, :]
    d_shape = (d_raw - shape[None, :] * d_raw[:, lead][:, None]) / raw[lead]
    return shape, np.sqrt(np.sum(np.abs(d_shape) ** 2, axis=0))


def estimates_from_clusters(flat, clusters: list[Cluster], perturb, n_orders_swept: int,
                            scale: np.ndarray, representative: str = "consensus", workers: int = 1
                            ) -> tuple[list[PoleEstimate], list[int], list[Cluster]]:
    """One estimate per cluster, from its member with the smallest frequency error among a few probed orders
    that agrees with the cluster's medians (:data:`CONSENSUS_SIGMAS`), with the representative
    member's index (into ``flat``) and its cluster. Duplicates within their errors are dropped.

    Parameters
    ----------
    flat
        The flattened poles of :func:`modal.operational.selection.stabilise`.
    clusters : list of Cluster
    perturb : callable (order, indices) -> dict, or None
        The deviations of the poles ``indices`` of ``order`` per block: ``"pole"`` (blocks, n) and ``"shape"``
        (blocks, channels, n) of the unit-RMS shapes (None: the method finds shapes later, from all its poles
        together).
    n_orders_swept : int
    scale : ndarray
        Each channel's RMS (the shapes were found on unit-RMS channels).
    representative : {"consensus", "upper_half"}
        Where the reporting member is looked for. ``"consensus"``: the probed orders, among the members
        that agree with the cluster's medians. ``"upper_half"``: every order of the upper half of the
        cluster's own orders (:func:`upper_half`), for an estimator whose under-fitted low orders hold biased
        poles of small error (ranked by their errors, they would be chosen).
    workers : int
        Threads among which the probed orders' deviations are computed (``perturb`` must allow it).
    """
    # the errors are computed at a few orders spread over the sweep (one perturbation per order serves every
    # cluster), and at each cluster's top order when it has no pole at those; or at every order of the
    # clusters' upper halves
    upper = [upper_half(flat, c) for c in clusters] if representative == "upper_half" else None
    if upper is not None:
        probe = {int(o) for members in upper for o in flat.order[members]}
    else:
        swept = np.unique(flat.order)
        probe = set(swept[np.unique(np.linspace(0, swept.size - 1, PROBE_ORDERS).round().astype(int))].tolist())
    for cluster in clusters:
        own = set(flat.order[cluster.members].tolist())
        if not own & probe:
            probe.add(max(own))
    errors = {}  # member -> (sf, sz, d_shape, unit shape, d_pole)
    probed = []  # (order, members of the clusters at it)
    for order in sorted(probe):
        at = np.concatenate([c.members[flat.order[c.members] == order] for c in clusters]) if clusters else []
        if not len(at):
            continue
        if perturb is None:
            for member in at:
                errors[int(member)] = (np.nan, np.nan, None, flat.shape[:, member], None)
            continue
        probed.append((int(order), at))
    # each order's deviations are independent of the others'
    deviations = map_over_threads(lambda job: perturb(job[0], flat.index[job[1]]), probed, workers)
    for (order, at), dev in zip(probed, deviations):
        sf, sz = pole_errors(flat.pole[at], dev["pole"])
        for j, member in enumerate(at):
            unit = flat.shape[:, member]
            d_shape = None if dev["shape"] is None else dev["shape"][:, :, j]
            errors[int(member)] = (sf[j], sz[j], d_shape, unit, dev["pole"][:, j])
    candidates = []
    for k, cluster in enumerate(clusters):
        members = cluster.members
        f_mid = float(np.median(flat.frequency_hz[members]))
        z_mid = float(np.median(flat.damping_ratio[members]))
        probed = [int(m) for m in members if int(m) in errors]

        def agrees(m):  # with the chain's consensus, within its own errors (an under-fitted order does not)
            sf, sz = errors[m][:2]
            return (abs(flat.frequency_hz[m] - f_mid) <= CONSENSUS_SIGMAS * sf
                    and abs(flat.damping_ratio[m] - z_mid) <= CONSENSUS_SIGMAS * sz)

        if upper is not None:
            eligible = [int(m) for m in upper[k] if np.isfinite(errors[int(m)][0])]
        else:
            eligible = [m for m in probed if np.isfinite(errors[m][0]) and agrees(m)]
        if eligible:
            member = min(eligible, key=lambda m: errors[m][0])
        else:
            member = min(probed, key=lambda m: abs(flat.frequency_hz[m] / f_mid - 1)
                         + abs(flat.damping_ratio[m] - z_mid) / max(abs(z_mid), 1e-3))
        sf, sz, d_unit, unit, d_pole = errors[member]
        shape, shape_std = _physical_shape(unit, d_unit, scale)
        candidates.append((PoleEstimate(complex(flat.pole[member]), shape, float(sf), float(sz), shape_std,
                                        cluster.n_orders, n_orders_swept, int(flat.order[member]),
                                        pole_deviation=d_pole), member, cluster))
    kept = []
    for estimate, member, cluster in sorted(candidates, key=lambda c: -c[0].n_orders):
        duplicate = False
        for other, _, _ in kept:
            sigma = np.hypot(estimate.std_frequency_hz, other.std_frequency_hz)
            close = abs(estimate.natural_frequency_hz - other.natural_frequency_hz)
            limit = DUPLICATE_SIGMAS * sigma if np.isfinite(sigma) else 0.01 * other.natural_frequency_hz
            if close <= limit and shape_mac(estimate.shape, other.shape) >= DUPLICATE_MAC:
                duplicate = True
                break
        if not duplicate:
            kept.append((estimate, member, cluster))
    kept.sort(key=lambda c: abs(c[0].pole))
    return [k[0] for k in kept], [k[1] for k in kept], [k[2] for k in kept]


def upper_half(flat, cluster: Cluster) -> np.ndarray:
    """The cluster's members (indices into ``flat``) at or above the middle of its orders."""
    members = cluster.members
    orders = np.unique(flat.order[members])
    return members[flat.order[members] >= orders[orders.size // 2]]


def resolved(estimate: PoleEstimate, duration_s: float) -> bool:
    """Whether an estimate's frequency is determined within :data:`UNRESOLVED_FRACTION` of its own half-power
    bandwidth, or of twice the record's resolution 2/T for a pole of (nearly) no damping such as a tone; True
    when the method gives no error bars."""
    sf = estimate.std_frequency_hz
    if not np.isfinite(sf):
        return True
    width = max(max(estimate.damping_ratio, 0.0) * estimate.natural_frequency_hz, 2.0 / duration_s)
    return sf <= UNRESOLVED_FRACTION * width
