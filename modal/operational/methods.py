"""The operational methods' names, apart from their code (a command line lists them without loading it)."""
from __future__ import annotations

__all__ = ["OMA_METHODS"]

#: the operational methods: covariance-driven SSI (default), poly-reference LSCF on half-spectra, and the
#: frequency-domain decomposition quick looks
OMA_METHODS = ("ssi", "plscf", "fdd", "efdd")
