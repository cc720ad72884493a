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
from .geometry import Geometry, line_geometry  # noqa: E402
from .io.geometry import read_geometry  # noqa: E402

#: names whose module is imported when the name is first used (PEP 562): the synthesisers (modal.synthetic
#: with its time-record and ambient generators) and operational analysis (the package is modal.operational, so
#: that the name modal.oma is the function: a package modal/oma/ would be bound to that attribute on its first
#: import, over the function) are not used by a fit, a scene run, a plotting process or a Dask worker, each of
#: which imported them with ``import modal``
_HOME = {**dict.fromkeys(("DigitalModes", "add_noise", "impact_record", "matrix_frf", "modal_frf", "random_record",
                          "sdof_frf"), "synthetic"),
         **dict.fromkeys(("merge_setups", "oma", "scale_by_mass_change"), "operational")}


from .lazy import lazy_names  # noqa: E402

__getattr__, __dir__ = lazy_names(__name__, _HOME)


__all__ = [
    "FRF", "FRF_KINDS", "identify", "oma", "scale_by_mass_change", "merge_setups", "estimate_frf", "EstimatedFRF", "read_frf", "write_frf", "METHODS", "IdentificationResult", "ModeResult", "ModeStd",
    "FLAG_TEXT", "physical_parameters", "Geometry", "line_geometry", "read_geometry", "modal_frf", "matrix_frf", "sdof_frf", "add_noise",
    "DigitalModes", "impact_record", "random_record",
    "errors", "units", "ModalError", "FRFValidationError", "FormatError", "IdentificationError",
    "ParameterError", "ModalWarning", "ResolutionWarning", "QualityWarning",
]
