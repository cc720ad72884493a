"""Global (poly-reference) identification: pLSCF poles over model orders, a stabilisation
diagram with automatic pole selection, and a joint refinement of all poles, modal constants
and residual terms. Entry point: ``modal.identify(frf, method="global")``."""
from .identify import channel_grid, identify_global, mpc
from .plscf import PolePack, plscf_poles
from .stabilisation import SelectedPole, StabilisationDiagram, select_poles, stabilisation, vector_mac

__all__ = ["identify_global", "channel_grid", "mpc", "plscf_poles", "PolePack", "stabilisation",
           "select_poles", "StabilisationDiagram", "SelectedPole", "vector_mac"]
