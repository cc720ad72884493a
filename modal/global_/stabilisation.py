"""Stabilisation diagram: which poles stay put as the model order grows, and the automatic choice.

A pole of order p is *stable* when the previous order has a pole within
``freq_tol`` in frequency and ``damping_tol`` in damping and, with several
references, a participation vector with MAC ≥ ``mac_tol`` (the usual PolyMAX
criteria: 1 %, 5 %, 0.98). The automatic selection clusters the poles stable in frequency
over all orders and keeps the clusters seen in a good part of the sweep:
physical modes stabilise early and stay, mathematical poles wander from order
to order and noise poles stabilise only at the highest orders.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .plscf import PolePack

__all__ = ["StabilisationDiagram", "stabilisation", "select_poles", "outside_band_poles", "pole_chains", "SelectedPole", "vector_mac"]


@dataclass(frozen=True)
class StabilisationDiagram:
    """Every physical pole of every order, with its stability.

    Attributes (one entry per pole, all orders concatenated)
    ----------
    order : ndarray of int
    frequency_hz : ndarray
        Natural frequency, Hz.
    damping_ratio : ndarray
    stable_frequency, stable_damping, stable_vector : ndarray of bool
        Stable against the previous order in frequency, damping and participation (MAC).
    previous : ndarray of int
        Index (in these arrays) of the nearest pole of the previous order, −1 for the first order.
    """

    order: np.ndarray
    frequency_hz: np.ndarray
    damping_ratio: np.ndarray
    stable_frequency: np.ndarray
    stable_damping: np.ndarray
    stable_vector: np.ndarray
    previous: np.ndarray

    @property
    def stable(self) -> np.ndarray:
        """Stable in frequency, damping and vector."""
        return self.stable_frequency & self.stable_damping & self.stable_vector


@dataclass(frozen=True)
class SelectedPole:
    """A pole chosen for the model, with the evidence for it."""

    omega_n: float
    damping_ratio: float
    participation: np.ndarray
    n_stable_orders: int
    n_orders: int
    hinted: bool = False
    found_in_residual: bool = False
    # found_in_residual: a mode the joint fit found in its residual, not in the diagram (no evidence there).
    # n_stable_orders counts the orders of the upper half of the sweep that hold the pole stable in
    # frequency, out of n_orders (the upper half's size)


def vector_mac(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """MAC of complex vectors along the last axis (broadcasting), |aᴴb|²/(|a|²|b|²)."""
    num = np.abs(np.sum(a.conj() * b, axis=-1)) ** 2
    den = np.sum(np.abs(a) ** 2, axis=-1) * np.sum(np.abs(b) ** 2, axis=-1)
    return num / np.where(den > 0, den, np.inf)


def stabilisation(packs: list[PolePack], freq_tol: float = 0.01, damping_tol: float = 0.05,
                  mac_tol: float = 0.98) -> StabilisationDiagram:
    """Classify every pole against the previous order's (see the module docstring)."""
    orders, freqs, zetas, sf, sd, sv, links = [], [], [], [], [], [], []
    previous = None
    offset = 0
    for pack in packs:
        n = pack.omega_n.size
        stable_f = np.zeros(n, bool)
        stable_d = np.zeros(n, bool)
        stable_v = np.zeros(n, bool)
        link = np.full(n, -1)
        if previous is not None and previous.omega_n.size and n:
            rel = np.abs(pack.omega_n[:, None] / previous.omega_n[None, :] - 1)
            nearest = np.argmin(rel, axis=1)
            link = offset - previous.omega_n.size + nearest
            stable_f = rel[np.arange(n), nearest] < freq_tol
            stable_d = np.abs(pack.damping_ratio / previous.damping_ratio[nearest] - 1) < damping_tol
            stable_v = vector_mac(pack.participation, previous.participation[nearest]) >= mac_tol
        orders.append(np.full(n, pack.order))
        freqs.append(pack.omega_n / (2 * np.pi))
        zetas.append(pack.damping_ratio)
        sf.append(stable_f)
        sd.append(stable_d & stable_f)
        sv.append(stable_v & stable_f)
        links.append(link)
        previous = pack
        offset += n
    cat = (lambda x, dtype=float: np.concatenate(x).astype(dtype) if x else np.zeros(0, dtype))
    return StabilisationDiagram(cat(orders, int), cat(freqs), cat(zetas), cat(sf, bool), cat(sd, bool),
                                cat(sv, bool), cat(links, int))


def pole_chains(diagram: StabilisationDiagram) -> list[np.ndarray]:
    """Chains of poles followed from order to order: each pole stable in frequency joins the chain of its
    nearest pole in the previous order. Two modes 1 % apart stay two chains, where clustering by a
    frequency tolerance would merge them. Returns the member indices of every chain of two or more poles."""
    n = diagram.order.size
    parent = np.arange(n)

    def root(i):
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    for i in np.flatnonzero(diagram.stable_frequency & (diagram.previous >= 0)):
        a, b = root(i), root(int(diagram.previous[i]))
        if a != b:
            parent[a] = b
    roots = np.array([root(i) for i in range(n)])
    groups = {}
    for i, r in enumerate(roots):
        groups.setdefault(r, []).append(i)
    return [np.array(g) for g in groups.values() if len(g) > 1]


def select_poles(packs: list[PolePack], diagram: StabilisationDiagram, modes_hz=None, cluster_tol: float = 0.01,
                 strong_fraction: float = 0.5, weak_fraction: float = 0.25) -> list[SelectedPole]:
    """Choose the model's poles.

    Without hints: follow the poles stable in frequency from order to order
    (:func:`pole_chains`) and keep every chain seen in at least ``weak_fraction`` of the sweep's
    orders (and at least 5): a physical mode stabilises
    early and stays, a noise pole stabilises only at the top orders. Clusters below
    ``strong_fraction`` are kept for the fit but carry little evidence (``n_stable_orders`` says
    how much; :func:`modal.global_.identify_global` flags them ``weak_evidence``). Each cluster is
    reported by its highest-order fully stable pole (or stable in frequency, when none is).
    With ``modes_hz``: for each hint, the pole nearest in frequency among the highest order's
    that has one within 5 %, whatever its evidence (which is reported).
    """
    n_orders = len(packs)
    if n_orders == 0:
        return []
    order_list = [pk.order for pk in packs]
    stable = diagram.stable
    if modes_hz is not None:
        chosen = []
        for hint in np.atleast_1d(np.asarray(modes_hz, float)):
            best = None
            for pack in reversed(packs):
                if pack.omega_n.size == 0:
                    continue
                k = int(np.argmin(np.abs(pack.omega_n / (2 * np.pi * hint) - 1)))
                if abs(pack.omega_n[k] / (2 * np.pi * hint) - 1) < 0.05:
                    best = (pack, k)
                    break
            if best is None:
                continue
            pack, k = best
            f = pack.omega_n[k] / (2 * np.pi)
            upper = [o for o in order_list if o >= order_list[len(order_list) // 2]]
            near = diagram.stable_frequency & (np.abs(diagram.frequency_hz / f - 1) < cluster_tol) \
                & np.isin(diagram.order, upper)
            count = int(np.unique(diagram.order[near]).size)
            chosen.append(SelectedPole(float(pack.omega_n[k]), float(pack.damping_ratio[k]), pack.participation[k],
                                       count, len(upper), hinted=True))
        return _unique(chosen)
    # noise moves damping and participation more from order to order than frequency: chains follow
    # the poles stable in frequency
    chosen = []
    for members in pole_chains(diagram):
        members = members[diagram.stable_frequency[members]]
        if np.unique(diagram.order[members]).size >= max(5, weak_fraction * n_orders):
            chosen.append(_chain_pole(packs, diagram, members))
    return _unique(chosen)


def _chain_pole(packs: list[PolePack], diagram: StabilisationDiagram, members: np.ndarray) -> SelectedPole:
    """A chain's pole: its highest-order fully stable member (or stable in frequency, when none is), with the
    evidence: how many of the upper half of the sweep's orders (where the model has room for every mode)
    hold it stable."""
    order_list = [pk.order for pk in packs]
    full = members[diagram.stable[members]]
    pool = full if full.size else members
    top = pool[np.argmax(diagram.order[pool])]
    pack = packs[order_list.index(diagram.order[top])]
    k = int(np.argmin(np.abs(pack.omega_n / (2 * np.pi * diagram.frequency_hz[top]) - 1)))
    upper = [o for o in order_list if o >= order_list[len(order_list) // 2]]
    return SelectedPole(float(pack.omega_n[k]), float(pack.damping_ratio[k]), pack.participation[k],
                        int(np.isin(np.unique(diagram.order[members]), upper).sum()), len(upper))


def outside_band_poles(packs: list[PolePack], diagram: StabilisationDiagram, low_hz: float, high_hz: float,
                       selected: list[SelectedPole], min_orders: int = 3) -> list[SelectedPole]:
    """Candidate poles just outside the lines that the selection left out.

    A mode a little above (or below) the band is seen by pLSCF only in a few orders, its frequency
    wandering (seen: a mode at 430 Hz over 20-400 Hz lines as a chain at 405-409 Hz in 4-9 of 17 orders),
    yet the residual terms model it far worse than its pole. Chains stable in frequency in at least
    ``min_orders`` orders whose pole lies outside [low_hz, high_hz] and away (> 1 %) from every selected
    pole are returned, for the joint fit to refine and its significance test to keep or drop.
    """
    taken = np.array([p.omega_n for p in selected])
    out = []
    for members in pole_chains(diagram):
        members = members[diagram.stable_frequency[members]]
        if np.unique(diagram.order[members]).size < min_orders:
            continue
        pole = _chain_pole(packs, diagram, members)
        f = pole.omega_n / (2 * np.pi)
        if low_hz <= f <= high_hz or (taken.size and np.min(np.abs(taken / pole.omega_n - 1)) < 0.01):
            continue
        out.append(pole)
    return _unique(out)


def _unique(poles: list[SelectedPole]) -> list[SelectedPole]:
    """One pole per frequency (two clusters or hints that picked the same pole keep the better evidence)."""
    out: list[SelectedPole] = []
    for pole in sorted(poles, key=lambda p: p.omega_n):
        if out and abs(pole.omega_n / out[-1].omega_n - 1) < 1e-9:
            if pole.n_stable_orders > out[-1].n_stable_orders:
                out[-1] = pole
            continue
        out.append(pole)
    return out
