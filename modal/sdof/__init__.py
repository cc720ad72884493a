"""Band-wise identification, one mode per band: half-power, circle fit and least squares (``"nls"``).

Entry point: ``modal.identify(frf, method)`` with a band-wise method, which calls
:func:`identify_bands`. The sequence, one module each: the bands' lines and
channels (:mod:`~modal.sdof.bands`) → start values (:mod:`~modal.sdof.starts`) →
half-power / circle per channel and their combination (:mod:`~modal.sdof.estimates`,
over :mod:`~modal.sdof.halfpower`, :mod:`~modal.sdof.circlefit` and the error
propagation :mod:`~modal.sdof.propagate`) or the joint least-squares refinement
(:mod:`~modal.sdof.refine`) → checks (:mod:`~modal.sdof.quality`, over the residual
tests of :mod:`~modal.sdof.checks`) → results (:mod:`modal.assemble`), in
:mod:`~modal.sdof.pipeline`.
"""
from .pipeline import BANDWISE_METHODS, identify_bands

__all__ = ["BANDWISE_METHODS", "identify_bands"]
