"""Operational (output-only) modal analysis: correlations → SSI-cov (or pLSCF on half-spectra) over model
orders → stabilisation and clustering → machine tones apart → error bars; FDD/EFDD quick looks; mass-change
scaling and the merging of several setups. Entry point: ``modal.oma(data, ...)``."""
from .identify import OMA_METHODS, oma
from .scaling import scale_by_mass_change
from .setups import merge_setups

__all__ = ["oma", "OMA_METHODS", "scale_by_mass_change", "merge_setups"]
