"""Synthetic time data with an exactly known FRF, for the estimator tests.

The structures are :class:`modal.synthetic.DigitalModes` (impulse invariance: a
record filtered through them has the FRF :meth:`~modal.synthetic.DigitalModes.frf`
with no model error) and the hammer pulses :func:`modal.synthetic.hammer_force`;
both are re-exported here under the names the tests use.
"""
from __future__ import annotations

from modal.synthetic import DigitalModes, hammer_force

__all__ = ["DigitalModes", "hammer_force"]
