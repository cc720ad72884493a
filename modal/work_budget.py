"""The work an identification may do, capped by design: a budget of model evaluations shared by its fits.

A least-squares refinement (:func:`modal.nls.fit_modes`) spends its time in evaluations of the model: a
design of lines × columns (one column per mode, and the background's) and its projection of the channels
fitted. A pathological FRF (hundreds of modes on hundreds of thousands of lines, noise the refinement keeps
chasing) multiplies evaluations, each one expensive, and refits. :class:`EvaluationBudget` counts the
evaluations of every fit of one identification (each fit's start included) and gives each fit what is left;
where it runs out, the fit stops where it stands (``NLSFit.capped``), the modes are flagged ``work_capped`` and
the result says which budget bound and how to lift it. The default budget scales with the size of one
evaluation (:func:`default_max_evaluations`), so that the work, not the count, is bounded: ordinary files use
a tenth of it at most and their results are the same as without it.
"""
from __future__ import annotations

from dataclasses import dataclass

from .errors import ParameterError

__all__ = ["EvaluationBudget", "REFINEMENT_WORK", "MIN_EVALUATIONS", "evaluation_size", "default_max_evaluations",
           "checked_max_evaluations"]

#: the default budget: evaluations of the start's model of at most this many line-column products in all
#: (:func:`evaluation_size` each). The ordinary files use a tenth of it at most (the benchmarks' wide case, 120
#: channels × 4000 lines × 15 modes: 112 evaluations of 4.3e6 products, 4.8e8), while 100 modes on 50 000
#: lines by nls reach it after 28 evaluations instead of running for minutes (benchmarks/bench_caps.py)
REFINEMENT_WORK = 5e9
#: ... and at least this many evaluations, however large each: a fit takes a few steps from its start
MIN_EVALUATIONS = 20


def evaluation_size(n_lines: int, n_modes: int, n_channels: int, n_background: int = 2) -> float:
    """Line-column products of one evaluation of a model: lines × columns × (columns + channels fitted), with a
    column per mode and ``n_background`` more (the global model's two residual terms, a band-wise model's
    offset per region), and the channels compressed to at most one per column and pole parameter
    (:func:`modal.nls.fit_modes` fits many channels on fewer combinations)."""
    columns = n_modes + n_background
    return float(n_lines) * columns * (columns + min(n_channels, columns + 2 * n_modes))


def default_max_evaluations(n_lines: int, n_modes: int, n_channels: int, n_background: int = 2) -> int:
    """The default budget of model evaluations for a model of ``n_modes`` modes (and ``n_background`` columns)
    on ``n_lines`` lines and ``n_channels`` channels: :data:`REFINEMENT_WORK` over :func:`evaluation_size`, at
    least :data:`MIN_EVALUATIONS`."""
    size = evaluation_size(n_lines, n_modes, n_channels, n_background)
    return max(MIN_EVALUATIONS, int(REFINEMENT_WORK // size))


def checked_max_evaluations(value, error=ParameterError) -> int | None:
    """``max_evaluations`` as given by a caller: None (the default budget) or an int ≥ 1; else ``error`` naming it."""
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, int) or value < 1:
        raise error(f"max_evaluations = {value!r}: expected a whole number of model evaluations >= 1 (or None for "
                    "the default budget)")
    return int(value)


@dataclass
class EvaluationBudget:
    """Model evaluations left to the fits of one identification.

    Attributes
    ----------
    limit : int
        Evaluations in all (each fit's start counts one).
    used : int
        Evaluations spent so far.
    capped : bool
        A fit stopped at the budget before converging.
    """

    limit: int
    used: int = 0
    capped: bool = False

    @property
    def remaining(self) -> int:
        """Evaluations left (0 when spent)."""
        return max(self.limit - self.used, 0)

    @property
    def spent(self) -> bool:
        """Whether nothing is left: the fits still to come start where they are and take no step."""
        return self.used >= self.limit

    def for_fit(self) -> int:
        """Evaluations a fit may take beyond its start (which this counts as spent)."""
        self.used += 1
        return self.remaining

    def spend(self, fit) -> None:
        """Count a fit's evaluations (its ``n_evaluations``) and whether it was capped."""
        self.used += int(fit.n_evaluations)
        self.capped |= bool(fit.capped)
