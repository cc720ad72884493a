"""The budget of model evaluations an identification's least-squares fits share (modal.work_budget)."""
from types import SimpleNamespace

import pytest

from modal.errors import ParameterError
from modal.work_budget import (MIN_EVALUATIONS, REFINEMENT_WORK, EvaluationBudget, checked_max_evaluations,
                               default_max_evaluations, evaluation_size)


def test_the_default_budget_bounds_the_work_not_the_count():
    # evaluations × the size of one stays within REFINEMENT_WORK wherever the floor does not bind
    for lines, modes, channels in ((4000, 15, 120), (10_000, 40, 1), (60_000, 150, 1)):
        n = default_max_evaluations(lines, modes, channels)
        size = evaluation_size(lines, modes, channels)
        assert n * size <= REFINEMENT_WORK < (n + 1) * size or n == MIN_EVALUATIONS
    # larger problems get fewer evaluations, never fewer than the floor
    assert default_max_evaluations(4000, 15, 120) > default_max_evaluations(200_000, 15, 120)
    assert default_max_evaluations(200_000, 400, 1) == MIN_EVALUATIONS
    # channels beyond one per column and pole parameter cost nothing more: the fit compresses them
    assert evaluation_size(4000, 5, 17) == evaluation_size(4000, 5, 10_000)
    assert evaluation_size(4000, 5, 10) < evaluation_size(4000, 5, 17)


def test_the_budget_counts_each_fit_start_and_its_steps():
    budget = EvaluationBudget(10)
    assert budget.for_fit() == 9 and budget.used == 1  # the start's evaluation is spent
    budget.spend(SimpleNamespace(n_evaluations=6, capped=False))
    assert budget.remaining == 3 and not budget.spent and not budget.capped
    assert budget.for_fit() == 2
    budget.spend(SimpleNamespace(n_evaluations=2, capped=True))
    assert budget.spent and budget.capped and budget.remaining == 0
    assert budget.for_fit() == 0  # a fit after that takes no step


@pytest.mark.parametrize("bad", [0, -3, 2.5, "many", True])
def test_a_budget_must_be_a_whole_number_of_evaluations(bad):
    with pytest.raises(ParameterError, match=rf"max_evaluations = {bad!r}: expected a whole number"):
        checked_max_evaluations(bad)
    assert checked_max_evaluations(None) is None and checked_max_evaluations(7) == 7
