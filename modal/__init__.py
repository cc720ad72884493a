"""Experimental modal analysis: FRFs, identification of natural frequency,
damping ratio, modal constant and physical k, c, m, and FRF file I/O."""
from . import errors, units
from .errors import (
    FormatError,
    FRFValidationError,
    IdentificationError,
    ModalError,
    ModalWarning,
    ParameterError,
    QualityWarning,
    ResolutionWarning,
)

__version__ = "0.1.0"
#: Identifies this toolkit's ``modal`` (an unrelated PyPI package has the same import name).
__toolkit_id__ = "modalbal"
