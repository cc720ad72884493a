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

from ._version import __version__  # noqa: E402
#: Identifies this toolkit's ``modal`` (an unrelated PyPI package has the same import name).
__toolkit_id__ = "modalbal"
from .frf import FRF, FRF_KINDS  # noqa: E402
from .identify import METHODS, identify  # noqa: E402
from .io import read_frf, write_frf  # noqa: E402
from .estimate import EstimatedFRF, estimate_frf  # noqa: E402
from .flags import FLAG_TEXT  # noqa: E402
from .results import IdentificationResult, ModeResult, ModeStd, physical_parameters  # noqa: E402
from .synthetic import (  # noqa: E402
    DigitalModes, add_noise, impact_record, matrix_frf, modal_frf, random_record, sdof_frf,
)
from .geometry import Geometry, line_geometry  # noqa: E402
from .io.geometry import read_geometry  # noqa: E402
# operational (output-only) analysis: the package is modal.operational, so that the name modal.oma is the
# function (a package modal/oma/ would be bound to that attribute on its first import, over the function)
from .operational import merge_setups, oma, scale_by_mass_change  # noqa: E402

__all__ = [
    "FRF", "FRF_KINDS", "identify", "oma", "scale_by_mass_change", "merge_setups", "estimate_frf", "EstimatedFRF", "read_frf", "write_frf", "METHODS", "IdentificationResult", "ModeResult", "ModeStd",
    "FLAG_TEXT", "physical_parameters", "Geometry", "line_geometry", "read_geometry", "modal_frf", "matrix_frf", "sdof_frf", "add_noise",
    "DigitalModes", "impact_record", "random_record",
    "errors", "units", "ModalError", "FRFValidationError", "FormatError", "IdentificationError",
    "ParameterError", "ModalWarning", "ResolutionWarning", "QualityWarning",
]
