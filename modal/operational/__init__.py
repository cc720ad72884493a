"""Operational (output-only) modal analysis: correlations → SSI-cov (or pLSCF on half-spectra) over model
orders → stabilisation and clustering → machine tones apart → error bars; FDD/EFDD quick looks; mass-change
scaling and the merging of several setups. Entry point: ``modal.oma(data, ...)``."""
from __future__ import annotations

from .methods import OMA_METHODS

__all__ = ["oma", "OMA_METHODS", "scale_by_mass_change", "merge_setups"]

#: where each public name lives: loaded when first used (PEP 562), so that a command line listing the methods
#: (modal.operational.methods) does not load the analysis
_HOME = {"oma": "identify", "scale_by_mass_change": "scaling", "merge_setups": "setups"}


def __getattr__(name: str):
    if name not in _HOME:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    import importlib

    value = getattr(importlib.import_module(f".{_HOME[name]}", __name__), name)
    globals()[name] = value
    return value


def __dir__():
    return sorted({*globals(), *_HOME})
