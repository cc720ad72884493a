"""Stabilisation over model orders and clustering of the stable poles: one cluster per physical mode.

A pole of one order is *stable* when the previous order holds a pole within ``freq_tol`` in
frequency and ``damping_tol`` in damping whose shape has a MAC of at least ``mac_tol`` with its
own (frequency, damping and shape together). Each stable pole joins the chain of its partner in
the previous order, one partner per pole (the closest, by relative frequency difference plus
1 − MAC): two close modes with different shapes stay two chains, a mode never takes two poles
of one order. Chains of one mode broken by an order where it wandered are joined again; a chain
that runs beside a longer one of the same frequency and shape is the same mode fitted twice
(over-fitting splits a mode in two at high orders) and is dropped. Chains seen in fewer than
``min_fraction`` of the orders are noise poles: they stabilise only by chance, over a few orders.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .ssi import PoleSet

__all__ = ["OMAStabilisation", "Cluster", "stabilise", "shape_mac", "mpc", "determined_mpc", "DETERMINED_SIGMAS"]

#: stability: relative frequency difference, relative damping difference, MAC of the shapes
FREQ_TOL, DAMPING_TOL, MAC_TOL = 0.01, 0.05, 0.98
#: a chain must hold stable poles in at least this fraction of the orders (and MIN_ORDERS of them)
MIN_FRACTION, MIN_ORDERS = 0.2, 5
#: poles with damping outside (LOWEST_DAMPING, HIGHEST_DAMPING] are not physical (tones may come out
#: slightly negative: they are kept to be recognised as tones)
LOWEST_DAMPING, HIGHEST_DAMPING = -0.02, 0.2


@dataclass(frozen=True)
class OMAStabilisation:
    """Every pole of every order in the band, with its stability and cluster.

    Attributes (one entry per pole, all orders concatenated)
    ----------
    order : ndarray of int
    frequency_hz : ndarray
    damping_ratio : ndarray
    mpc : ndarray
        Modal phase collinearity of the pole's shape.
    stable : ndarray of bool
        Stable in frequency, damping and shape against the previous order.
    cluster : ndarray of int
        Index of the result's mode the pole belongs to (−1: none; see ``cluster_kind``).
    chosen : ndarray of bool
        The pole reported for its mode (or tone).
    tone : ndarray of bool
        The pole belongs to a cluster recognised as a machine tone (``harmonics_hz``).
    method : str
        The estimator that gave the poles.
    """

    order: np.ndarray
    frequency_hz: np.ndarray
    damping_ratio: np.ndarray
    mpc: np.ndarray
    stable: np.ndarray
    cluster: np.ndarray
    chosen: np.ndarray
    tone: np.ndarray
    method: str = "ssi"


@dataclass(frozen=True)
class Cluster:
    """The stable poles of one chain: indices into the flattened poles, and its evidence."""

    members: np.ndarray
    n_orders: int


def shape_mac(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """MAC of shapes along axis 0 (columns), broadcasting the rest: |aᴴb|²/(|a|²|b|²)."""
    num = np.abs(np.einsum("i...,i...->...", a.conj(), b)) ** 2
    den = np.sum(np.abs(a) ** 2, axis=0) * np.sum(np.abs(b) ** 2, axis=0)
    return num / np.where(den > 0, den, np.inf)


#: a shape entry this many standard errors from zero or more is determined by the record: a shape is normalised
#: to the largest of these (:func:`modal.operational.modes._physical_shape`) and its MPC judged on them
DETERMINED_SIGMAS = 3.0


def determined_mpc(shape: np.ndarray, std_shape) -> float:
    """:func:`mpc` of the entries of ``shape`` at least :data:`DETERMINED_SIGMAS` standard errors (``std_shape``)
    from zero; of every entry where the errors are unknown (NaN or None) or none is determined.

    An entry the record does not determine is noise: small, as a node's, it hardly moves the MPC, but a channel
    of noise only (a disconnected sensor picking up hum) is large in its own units, and its random phase would
    make a real mode look complex."""
    shape = np.asarray(shape, complex)
    if std_shape is None:
        return mpc(shape)
    std_shape = np.asarray(std_shape, float)
    with np.errstate(invalid="ignore"):
        determined = np.abs(shape) >= DETERMINED_SIGMAS * std_shape
    return mpc(shape[determined]) if determined.any() else mpc(shape)


def mpc(shape: np.ndarray) -> float:
    """Modal phase collinearity (Pappa et al. 1993) of a complex vector: 1 for a real (normal) mode; NaN
    entries (the channels of a setup that misses the mode) left out."""
    shape = np.asarray(shape, complex)
    shape = shape[np.isfinite(shape)]
    re, im = shape.real, shape.imag
    sxx, syy, sxy = re @ re, im @ im, re @ im
    total = sxx + syy
    return float(((sxx - syy) ** 2 + 4 * sxy**2) / total**2) if total > 0 else float("nan")


@dataclass(frozen=True)
class _Flat:
    order: np.ndarray
    index: np.ndarray  # position in the order's PoleSet
    pole: np.ndarray
    shape: np.ndarray  # (n_outputs, n_poles)
    set_of: np.ndarray  # position of the order in the list

    @property
    def frequency_hz(self):
        return np.abs(self.pole) / (2 * np.pi)

    @property
    def damping_ratio(self):
        return -self.pole.real / np.abs(self.pole)


def _flatten(sets: list[PoleSet], low_hz: float, high_hz: float) -> _Flat:
    orders, index, poles, shapes, set_of = [], [], [], [], []
    for k, ps in enumerate(sets):
        wn = np.abs(ps.poles)
        with np.errstate(invalid="ignore", divide="ignore"):
            zeta = -ps.poles.real / wn
        f = wn / (2 * np.pi)
        keep = np.flatnonzero((ps.poles.imag > 0) & np.isfinite(zeta) & (zeta > LOWEST_DAMPING)
                              & (zeta <= HIGHEST_DAMPING) & (f >= low_hz) & (f <= high_hz))
        keep = keep[np.argsort(f[keep])]
        orders.append(np.full(keep.size, ps.order))
        index.append(keep)
        poles.append(ps.poles[keep])
        shapes.append(ps.shapes[:, keep])
        set_of.append(np.full(keep.size, k))
    n_out = sets[0].shapes.shape[0] if sets else 0
    cat = (lambda x, dtype: np.concatenate(x).astype(dtype) if x else np.zeros(0, dtype))
    return _Flat(cat(orders, int), cat(index, int), cat(poles, complex),
                 np.concatenate(shapes, axis=1) if shapes else np.zeros((n_out, 0), complex), cat(set_of, int))


def _links(flat: _Flat, freq_tol: float, damping_tol: float, mac_tol: float):
    """For each pole, its partner in the previous order (−1: none) and whether it is stable against it."""
    n = flat.pole.size
    partner = np.full(n, -1)
    stable = np.zeros(n, bool)
    f, z = flat.frequency_hz, flat.damping_ratio
    for k in range(1, int(flat.set_of.max(initial=0)) + 1):
        now = np.flatnonzero(flat.set_of == k)
        before = np.flatnonzero(flat.set_of == k - 1)
        if not now.size or not before.size:
            continue
        df = np.abs(f[now][:, None] / f[before][None, :] - 1)
        mac = shape_mac(flat.shape[:, now][:, :, None], flat.shape[:, before][:, None, :])
        distance = df + (1 - mac)
        best = np.argmin(distance, axis=1)
        # one partner per pole: where two poles chose the same one, the closer keeps it
        taken = {}
        for i in np.argsort(distance[np.arange(now.size), best]):
            if best[i] in taken:
                continue
            taken[best[i]] = i
            a, b = now[i], before[best[i]]
            partner[a] = b
            # (below 0.4 % damping, a fixed 2e-4: tones and very light damping scatter by that from order to order)
            zeta_ok = abs(z[a] - z[b]) <= damping_tol * max(abs(z[a]), abs(z[b]), 4e-3)
            stable[a] = df[i, best[i]] < freq_tol and zeta_ok and mac[i, best[i]] >= mac_tol
    return partner, stable


def _chains(partner: np.ndarray, stable: np.ndarray) -> list[np.ndarray]:
    """Members of each chain of stable links (a chain's first pole included)."""
    n = partner.size
    parent = np.arange(n)

    def root(i):
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    for i in np.flatnonzero(stable):
        a, b = root(i), root(int(partner[i]))
        if a != b:
            parent[a] = b
    groups: dict[int, list[int]] = {}
    for i in range(n):
        groups.setdefault(root(i), []).append(i)
    return [np.array(g) for g in groups.values() if len(g) > 1]


def _summary(flat: _Flat, members: np.ndarray):
    """(median frequency, top member's shape, set of orders) of a chain."""
    top = members[np.argmax(flat.order[members])]
    return float(np.median(flat.frequency_hz[members])), flat.shape[:, top], set(flat.order[members].tolist())


def _same_mode(fa, sa, fb, sb, freq_tol, mac_tol) -> bool:
    return abs(fa / fb - 1) < freq_tol and shape_mac(sa, sb) >= mac_tol


def _merge(flat: _Flat, chains: list[np.ndarray], freq_tol: float, mac_tol: float) -> list[np.ndarray]:
    """Join chains of one mode broken at some order; drop a chain running beside a longer one of the same mode."""
    chains = sorted(chains, key=lambda c: -np.unique(flat.order[c]).size)
    kept: list[list] = []  # [members, (median frequency, top shape, orders)]
    for chain in chains:
        fc, sc, oc = _summary(flat, chain)
        for entry in kept:
            fo, so, oo = entry[1]
            if _same_mode(fc, sc, fo, so, freq_tol, mac_tol):
                if not (oc & oo):  # the same mode, at other orders
                    entry[0] = np.concatenate([entry[0], chain])
                    entry[1] = _summary(flat, entry[0])
                break  # a duplicate beside a longer chain: dropped
        else:
            kept.append([chain, (fc, sc, oc)])
    return [entry[0] for entry in kept]


def stabilise(sets: list[PoleSet], low_hz: float, high_hz: float, *, freq_tol: float = FREQ_TOL,
              damping_tol: float = DAMPING_TOL, mac_tol: float = MAC_TOL, min_fraction: float = MIN_FRACTION,
              min_orders: int = MIN_ORDERS):
    """Stability of every pole in the band and the chains that are physical modes.

    Parameters
    ----------
    sets : list of PoleSet
        One per order, in increasing order.
    low_hz, high_hz : float
        The band: poles outside it are left out.

    Returns
    -------
    flat : _Flat
        The poles in the band, all orders (``order``, ``index`` into their PoleSet, ``pole``, ``shape``).
    stable : ndarray of bool
    clusters : list of Cluster
        Sorted by frequency.
    """
    flat = _flatten(sets, low_hz, high_hz)
    if flat.pole.size == 0:
        return flat, np.zeros(0, bool), []
    partner, stable = _links(flat, freq_tol, damping_tol, mac_tol)
    chains = [c[stable[c] | np.isin(c, partner[c[stable[c]]])] for c in _chains(partner, stable)]
    chains = _merge(flat, [c for c in chains if c.size > 1], freq_tol, mac_tol)
    needed = max(min_orders, int(np.ceil(min_fraction * len(sets))))
    clusters = []
    for chain in chains:
        n_orders = int(np.unique(flat.order[chain]).size)
        if n_orders >= needed:
            clusters.append(Cluster(np.sort(chain), n_orders))
    clusters.sort(key=lambda c: float(np.median(flat.frequency_hz[c.members])))
    return flat, stable, clusters
