"""The caps on the global method's work (max_evaluations, the sweep's default order ceiling): where one binds
the result says so (flag work_capped, a warning naming the cap and how to lift it, result.settings); ordinary
files never reach them and give the results they gave without them."""
from __future__ import annotations


import numpy as np
import pytest

import modal
from modal.global_.identify import MAX_DEFAULT_ORDER
from support.manymodes import fit_global, many_modes_frf, six_modes


def same(a, b) -> bool:
    """Two results with the same modes, bit for bit (every number of every mode)."""
    def numbers(result):
        return [np.asarray(v) for m in result.modes for v in (m.natural_frequency_hz, m.damping_ratio,
                                                               m.modal_constant, m.std.natural_frequency_hz,
                                                               m.std.damping_ratio, m.std.modal_constant)]
    return all(np.array_equal(x, y, equal_nan=True) for x, y in zip(numbers(a), numbers(b))) and \
        [m.flags for m in a.modes] == [m.flags for m in b.modes]


def test_an_ordinary_fit_stays_far_inside_its_budget_and_is_unchanged_by_it():
    frf = six_modes()
    result, messages = fit_global(frf)
    uncapped, _ = fit_global(frf, max_evaluations=10**9)  # the work identify did before it had a budget
    assert same(result, uncapped)
    assert not any("work_capped" in m.flags for m in result.modes) and not messages
    # the default, scaled to the size of one evaluation, leaves a margin of ten at least
    assert 0 < result.settings["evaluations"] <= result.settings["max_evaluations"] / 10
    assert result.settings["order_wanted"] is None


def test_a_refinement_stopped_by_its_budget_is_flagged_and_says_how_to_lift_it():
    frf = six_modes()
    free, _ = fit_global(frf)
    result, messages = fit_global(frf, max_evaluations=3)
    assert result.settings["max_evaluations"] == 3
    # each fit's start counts one; the final fit (for the errors) starts even when the budget is spent: one over
    assert result.settings["evaluations"] <= 3 + 1
    assert all("work_capped" in m.flags and "did_not_converge" not in m.flags for m in result.modes)
    assert not same(result, free)
    budget_lines = [m for m in messages if "stopped at its budget of 3 model evaluations" in m]
    assert len(budget_lines) == 1 and "max_evaluations=N" in budget_lines[0] and "--max-evaluations N" in budget_lines[0]
    assert any("is flagged (work_capped:" in m for m in messages)  # and each mode's own warning
    # lifted to what the free fit used, the same fit as without a cap
    lifted, _ = fit_global(frf, max_evaluations=free.settings["evaluations"])
    assert same(lifted, free)


def test_a_sweep_cut_at_the_default_order_ceiling_says_so():
    # 18 peaks call for order 6 x 18 + 20 = 128 with one reference; the default sweep stops at 120
    frf = many_modes_frf(18, 1000)
    result, messages = fit_global(frf)
    assert result.settings["orders"][1] == MAX_DEFAULT_ORDER and result.settings["order_wanted"] == 128
    assert any(f"stopped at model order {MAX_DEFAULT_ORDER}" in m and "max_order=128" in m for m in messages)
    # an explicit max_order is the user's: no word (a low one, to keep the test short)
    _, quiet = fit_global(frf, max_order=40)
    assert not any("stopped at model order" in m for m in quiet)


@pytest.mark.parametrize("bad", [0, -1, 2.5, "lots"])
def test_a_budget_must_be_a_whole_number_of_evaluations(bad):
    with pytest.raises(modal.ModalError, match="max_evaluations = .*expected a whole number"):
        modal.identify(six_modes(), "global", max_evaluations=bad)
