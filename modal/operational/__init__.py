"""Operational (output-only) modal analysis: correlations → SSI-cov (or pLSCF on half-spectra) over model
orders → stabilisation and clustering → machine tones apart → error bars; FDD/EFDD quick looks; mass-change
scaling and the merging of several setups. Entry point: ``modal.oma(data, ...)``."""
from .identify import OMA_METHODS, oma

__all__ = ["oma", "OMA_METHODS"]
