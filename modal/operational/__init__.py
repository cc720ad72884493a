"""Operational (output-only) modal analysis: correlations → SSI-cov (or pLSCF on half-spectra) over model
orders → stabilisation and clustering → machine tones apart → error bars; FDD/EFDD quick looks; mass-change
scaling and the merging of several setups. Entry point: ``modal.oma(data, ...)``."""
from __future__ import annotations

from ..lazy import lazy_names
from .methods import OMA_METHODS

__all__ = ["oma", "OMA_METHODS", "scale_by_mass_change", "merge_setups"]

#: where each public name lives: loaded when first used (PEP 562), so that a command line listing the methods
#: (modal.operational.methods) does not load the analysis
_HOME = {"oma": "identify", "scale_by_mass_change": "scaling", "merge_setups": "setups"}


__getattr__, __dir__ = lazy_names(__name__, _HOME)
