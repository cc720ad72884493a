"""The stabilisation sweep's work, capped by design: the orders and the lines pLSCF takes on a huge FRF.

pLSCF (:func:`modal.global_.plscf.plscf_poles`) builds its normal equations from the basis z^d of every line
for d = −p_max…p_max: (2·p_max + 1) × lines complex numbers in memory (200 000 lines at order 120: 770 MB,
1.5 GB at its peak), products of that basis with every channel, and for each order of the sweep the
eigenvalues of a companion matrix of p·m rows (m references), whose work grows with (p·m)³. Ordinary files
(thousands of lines, orders up to the default ceiling of 120) use a small part of each budget below. Where a
sweep would exceed one (hundreds of thousands of lines, or a high ``max_order`` asked for), :func:`plan_sweep`
keeps the sweep within them: first the sweep's lines are thinned (:func:`sweep_lines`: the strongest line and
the first of each block of lines, so every resolved peak keeps its top), then, where even the fewest lines the
orders need do not fit, the orders are lowered. The sweep only proposes poles: the refinement that follows
fits them on every line. A capped sweep may miss modes, so the result's modes are flagged ``work_capped``.

The refinement and its projections (the linear fits of every mode's column on every line) grow with the lines
times the square of the modes: :func:`refinement_mode_limit` bounds the modes the sweep may propose to it (a
high ``max_order`` on a huge file proposes hundreds), and :func:`most_stable` keeps those with the most
evidence.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..work_budget import MIN_EVALUATIONS, REFINEMENT_WORK, evaluation_size

__all__ = ["SWEEP_BASIS", "SWEEP_PRODUCTS", "SWEEP_EIGEN", "LINES_PER_ORDER", "SweepPlan", "sweep_orders",
           "plan_sweep", "sweep_lines", "refinement_mode_limit", "most_stable"]

#: the z-basis of the sweep: at most this many complex numbers, (2·p_max + 1) × lines (128 MiB; the default
#: ceiling's 241 orders of the basis on 34 800 lines). The benchmark cases take 4e5, 40 modes on 10 000 lines 2.4e6
SWEEP_BASIS = 2**23
#: ... at most this many complex products of the basis with the channels, (2·p_max + 1) × lines × (outputs ×
#: references + references²) (the benchmark case, 120 channels × 4000 lines at order 49: 5e7)
SWEEP_PRODUCTS = 5e9
#: ... and eigenvalue work of at most this much over the sweep's orders, Σ (p·m)³: each order's companion matrix
#: of k = p·m rows and its normal equations take some 30 k³ ns on one core (orders 88-354 of one reference,
#: 2e9: 57 s at load 8 on 2 cores). The default ceiling 120 takes 2.6e7 with one reference, 7e8 with three;
#: with one reference this allows orders up to 300
SWEEP_EIGEN = 1e9
#: the sweep's lines are not thinned below this many per model order (pLSCF needs more lines than its order;
#: a few times more keeps its least squares well over-determined)
LINES_PER_ORDER = 4


def sweep_orders(p_max: int) -> list[int]:
    """The orders of a sweep up to ``p_max``: from a quarter of it, in steps of 2 when it is long (the diagram
    compares each order with the previous one computed)."""
    step = 2 if p_max - p_max // 4 > 30 else 1
    return list(range(max(1, p_max // 4), p_max + 1, step))


@dataclass(frozen=True)
class SweepPlan:
    """The sweep :func:`plan_sweep` allows.

    Attributes
    ----------
    orders : list of int
        The model orders to solve (those asked for, or fewer and lower where the eigenvalue work or the
        lines bind).
    n_lines : int
        Lines the sweep may take (all of them when nothing binds; :func:`sweep_lines` takes at most these).
    capped : bool
        A budget bound: lines thinned or orders lowered.
    reason : str
        What bound, for the warning ("" when nothing did).
    """

    orders: list
    n_lines: int
    capped: bool
    reason: str = ""


def _lines_allowed(p_max: int, n_columns: int) -> int:
    """Lines the basis and product budgets allow a sweep to order ``p_max`` on ``n_columns`` columns."""
    basis = 2 * p_max + 1
    return int(min(SWEEP_BASIS // basis, SWEEP_PRODUCTS // (basis * n_columns)))


def _eigen_work(orders, m: int) -> float:
    return float(sum((p * m) ** 3 for p in orders))


def plan_sweep(orders, n_lines: int, n_outputs: int, n_references: int) -> SweepPlan:
    """The sweep within the budgets (:data:`SWEEP_BASIS`, :data:`SWEEP_PRODUCTS`, :data:`SWEEP_EIGEN`).

    ``orders``: the orders asked for (a sweep of :func:`sweep_orders`, or one order and the one below it);
    ``n_lines``: the band's lines; ``n_outputs`` × ``n_references``: the pLSCF matrix. Where the orders'
    eigenvalue work or the fewest lines they need (:data:`LINES_PER_ORDER` per order) do not fit, the highest
    order is lowered to the largest that does (a sweep, as :func:`sweep_orders` builds it; a single order
    keeps its neighbour below); then the lines are thinned to what the basis and product budgets allow.
    """
    orders = sorted({int(p) for p in orders})
    m = int(n_references)
    columns = int(n_outputs) * m + m * m
    reasons = []

    def fits(candidate) -> bool:
        top = candidate[-1]
        return (_eigen_work(candidate, m) <= SWEEP_EIGEN
                and _lines_allowed(top, columns) >= min(n_lines, LINES_PER_ORDER * top))

    if not fits(orders):
        single = len(orders) <= 2 and orders[-1] - orders[0] <= 1
        rebuild = (lambda p: [p - 1, p] if p > 1 else [p]) if single else sweep_orders
        low, high = 1, orders[-1]  # the largest top order that fits (fits is monotone in it)
        while low < high:
            mid = (low + high + 1) // 2
            low, high = (mid, high) if fits(rebuild(mid)) else (low, mid - 1)
        asked, orders = orders[-1], rebuild(low)
        reasons.append(f"model orders up to {orders[-1]} instead of {asked}")
    allowed = _lines_allowed(orders[-1], columns)
    if allowed < n_lines:
        reasons.append(f"at most {allowed} of its {n_lines} lines")
    return SweepPlan(orders, min(allowed, n_lines), bool(reasons), ", ".join(reasons))


def sweep_lines(power_per_line: np.ndarray, n_keep: int) -> np.ndarray:
    """Indices (increasing) of at most ``n_keep`` lines for a thinned sweep: in each block of consecutive lines,
    its first and its strongest (``power_per_line``: the weighted |H|² summed over the channels), and the last
    line of all (so that the basis' Nyquist frequency, set by the highest line, stays where it was)."""
    n = power_per_line.size
    if n_keep >= n:
        return np.arange(n)
    block = int(np.ceil(2 * n / max(n_keep - 3, 1)))  # 2 per block and the last: at most n_keep
    starts = np.arange(0, n, block)
    padded = np.full(starts.size * block, -np.inf)
    padded[:n] = power_per_line
    strongest = starts + np.argmax(padded.reshape(starts.size, block), axis=1)
    return np.unique(np.concatenate([starts, strongest, [n - 1]]))


def refinement_mode_limit(n_lines: int, n_channels: int) -> int:
    """The most modes the joint refinement takes on ``n_lines`` lines and ``n_channels`` channels: those whose
    fewest evaluations (:data:`~modal.work_budget.MIN_EVALUATIONS`) fit its default budget
    (:data:`~modal.work_budget.REFINEMENT_WORK` line-column products), at least one. Ordinary files are far from
    it (10 000 lines, one channel: 155 modes; 120 channels × 4000 lines: 195); 200 000 lines take 32."""
    low, high = 1, max(int(n_lines), 1)
    while low < high:  # the largest count that fits (the size grows with it)
        mid = (low + high + 1) // 2
        fits = evaluation_size(n_lines, mid, n_channels) * MIN_EVALUATIONS <= REFINEMENT_WORK
        low, high = (mid, high) if fits else (low, mid - 1)
    return low


def most_stable(poles: list, limit: int) -> list:
    """The ``limit`` poles of ``poles`` (:class:`~modal.global_.stabilisation.SelectedPole`, in frequency order)
    stable in the most orders, in frequency order (ties: the lower frequency first)."""
    if len(poles) <= limit:
        return poles
    ranked = sorted(range(len(poles)), key=lambda i: -poles[i].n_stable_orders)[:limit]
    return [poles[i] for i in sorted(ranked)]
