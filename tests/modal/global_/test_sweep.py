"""The stabilisation sweep's work budget (modal/global_/sweep.py): ordinary sweeps untouched, a huge one thinned
to its budget, too high orders lowered, and the refinement's modes bounded; where one binds the result says so."""
from __future__ import annotations


import numpy as np
import pytest

from modal.global_ import sweep
from modal.global_.identify import MAX_DEFAULT_ORDER
from modal.global_.stabilisation import SelectedPole
from modal.work_budget import MIN_EVALUATIONS, REFINEMENT_WORK, evaluation_size
from support.manymodes import fit_global, six_modes


@pytest.mark.parametrize("top, lines, outputs, references", [
    (49, 4000, 60, 2),                   # the benchmark case: 120 channels, 15 modes
    (MAX_DEFAULT_ORDER, 32000, 1, 1),    # the default ceiling on 32 000 lines
    (MAX_DEFAULT_ORDER, 4000, 20, 3),    # ... with three references
])
def test_ordinary_sweeps_are_within_every_budget(top, lines, outputs, references):
    plan = sweep.plan_sweep(sweep.sweep_orders(top), lines, outputs, references)
    assert not plan.capped and plan.orders == sweep.sweep_orders(top) and plan.n_lines == lines and not plan.reason


def test_a_huge_file_thins_the_sweeps_lines_to_its_budget():
    plan = sweep.plan_sweep(sweep.sweep_orders(MAX_DEFAULT_ORDER), 200_000, 1, 1)
    assert plan.capped and plan.orders == sweep.sweep_orders(MAX_DEFAULT_ORDER)  # the orders stay
    assert (2 * MAX_DEFAULT_ORDER + 1) * plan.n_lines <= sweep.SWEEP_BASIS  # the basis' memory is bounded
    assert plan.n_lines > sweep.SWEEP_BASIS / (2 * MAX_DEFAULT_ORDER + 1) - 1  # and used
    assert f"at most {plan.n_lines} of its 200000 lines" in plan.reason
    # many channels: the products with the channels bind before the basis
    wide = sweep.plan_sweep(sweep.sweep_orders(40), 100_000, 1000, 1)
    assert 81 * 100_000 <= sweep.SWEEP_BASIS  # (the basis alone would fit)
    assert wide.capped and 81 * wide.n_lines * (1000 + 1) <= sweep.SWEEP_PRODUCTS


def test_too_high_orders_are_lowered_to_the_eigenvalue_budget():
    asked = sweep.sweep_orders(644)  # what the peaks of 400 modes call for
    plan = sweep.plan_sweep(asked, 200_000, 1, 1)
    top = plan.orders[-1]
    assert plan.capped and top < asked[-1] and plan.orders in (sweep.sweep_orders(top), sweep.sweep_orders(top + 1))
    assert sum(float(p) ** 3 for p in plan.orders) <= sweep.SWEEP_EIGEN
    assert sum(float(p) ** 3 for p in sweep.sweep_orders(top + 2)) > sweep.SWEEP_EIGEN  # the highest that fits
    assert plan.n_lines >= sweep.LINES_PER_ORDER * plan.orders[-1]
    assert f"model orders up to {plan.orders[-1]} instead of {asked[-1]}" in plan.reason
    # one order asked for keeps the order below it, for its stability
    single = sweep.plan_sweep([1999, 2000], 200_000, 1, 1)
    assert single.capped and single.orders[1] - single.orders[0] == 1 and single.orders[-1] < 2000


def test_the_thinned_lines_keep_every_blocks_strongest_line_and_both_ends():
    rng = np.random.default_rng(0)
    power = rng.random(10_000)
    spikes = [17, 4321, 9998]
    power[spikes] = 10.0
    kept = sweep.sweep_lines(power, 500)
    assert kept.size <= 500 and np.all(np.diff(kept) > 0)
    assert kept[0] == 0 and kept[-1] == 9999 and set(spikes) <= set(kept)
    assert np.array_equal(sweep.sweep_lines(power, 10_000), np.arange(10_000))  # nothing to thin


def test_the_refinement_takes_at_most_the_modes_its_budget_allows_the_most_stable_ones():
    for lines, channels in ((10_000, 1), (4000, 120), (200_000, 1)):
        limit = sweep.refinement_mode_limit(lines, channels)
        assert evaluation_size(lines, limit, channels) * MIN_EVALUATIONS <= REFINEMENT_WORK
        assert evaluation_size(lines, limit + 1, channels) * MIN_EVALUATIONS > REFINEMENT_WORK
    poles = [SelectedPole(float(w), 0.01, np.ones(1), n, 20) for w, n in zip(range(1, 7), [5, 20, 3, 20, 9, 1])]
    assert [p.omega_n for p in sweep.most_stable(poles, 3)] == [2.0, 4.0, 5.0]  # in frequency order
    assert sweep.most_stable(poles, 6) is poles


def test_an_ordinary_global_fit_reports_its_sweep_unthinned():
    result, messages = fit_global(six_modes())
    # (the sweep proposes more poles than modes: the significance test drops those that only fit noise)
    assert result.settings["sweep_lines"] == 1500 and result.settings["modes_proposed"] >= len(result.modes)
    assert not any("work_capped" in m.flags for m in result.modes) and not messages


def test_a_thinned_sweep_still_finds_the_modes_and_says_it_was_capped(monkeypatch):
    frf = six_modes()
    free, _ = fit_global(frf)
    # a budget that holds a third of this file's lines: the sweep thins them, the refinement fits every line
    monkeypatch.setattr(sweep, "SWEEP_BASIS", (2 * free.settings["orders"][1] + 1) * 500)
    result, messages = fit_global(frf)
    # (a block's first and strongest line, at least one per block: at least half of those allowed)
    assert (500 - 3) / 2 <= result.settings["sweep_lines"] <= 500
    assert result.settings["orders"] == free.settings["orders"]
    assert [round(m.natural_frequency_hz) for m in result.modes] == [60, 120, 200, 260, 330, 420]
    # the same modes within their errors: both refinements fit every line of the same data from nearby starts
    # (3 standard errors of one fit bound their difference)
    for capped, unthinned in zip(result.modes, free.modes):
        difference = abs(capped.natural_frequency_hz - unthinned.natural_frequency_hz)
        assert difference < 3 * unthinned.std.natural_frequency_hz
    assert all("work_capped" in m.flags for m in result.modes)
    assert sum("the stabilisation sweep took at most 500 of its 1500 lines, within its work budget" in m
               for m in messages) == 1


def test_a_refinement_given_fewer_modes_than_proposed_flags_them(monkeypatch):
    frf = six_modes()
    proposed = fit_global(frf)[0].settings["modes_proposed"]
    # a refinement budget whose fewest evaluations hold three modes on these lines
    monkeypatch.setattr(sweep, "REFINEMENT_WORK", evaluation_size(1500, 3, 1) * MIN_EVALUATIONS)
    result, messages = fit_global(frf)
    assert result.settings["modes_proposed"] == proposed > 3 and all("work_capped" in m.flags for m in result.modes)
    assert 1 <= len(result.modes) <= 3 + 3 * 4  # and the missing-mode rounds' additions (3 rounds of at most 4)
    assert sum(f"the refinement took the 3 most stable of the {proposed} modes the sweep proposed" in m
               for m in messages) == 1
