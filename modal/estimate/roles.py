"""The roles of a time record's channels: the force and a response swapped.

A hammer's force is a train of short pulses (:func:`~modal.estimate.hits.pulse_train`); an accelerometer's
response to it rings between them. A record whose excitation is no such train while a response is one had
its force and a response swapped, at the recorder or in the file's labels: an impact estimate is refused
(hit detection would read the ringing as hits), a continuous one warned (a tachometer's pulses listed among
the responses look the same and leave the other channels' FRFs sound).
"""
from __future__ import annotations

import numpy as np

from ..errors import ParameterError, QualityWarning, warn
from .hits import pulse_train

__all__ = ["refuse_swapped_channels", "warn_impulsive_responses"]


def refuse_swapped_channels(force, response, sample_rate_hz, labels, source) -> None:
    """An impact record whose excitation is no train of hammer pulses while a response channel is one: the
    force and a response were swapped (at the recorder or in the file's labels). Hit detection would read the
    ringing response as a force and reject every "hit" as a double hit, or pass a response over a force as an
    FRF; refused instead, naming both channels."""
    own = pulse_train(force, sample_rate_hz)
    if own.impulsive:
        return
    for o in range(response.shape[0]):
        other = pulse_train(np.asarray(response[o], dtype=float), sample_rate_hz)
        if other.impulsive:
            raise ParameterError(
                f"{source}: {labels[0]} is no train of hammer pulses ({own.count} pulse(s) filling "
                f"{100 * own.duty:.1f} % of the record) but {labels[len(labels) - response.shape[0] + o]} is "
                f"({other.count} pulse(s), {100 * other.duty:.2f} %): the force and response channels look swapped "
                "(the cables at the recorder or the file's channel labels); expected the hammer's force as the "
                "excitation")


def warn_impulsive_responses(response, sample_rate_hz, labels, source) -> None:
    """A continuous estimate whose excitation is no train of hits while a response is one: the force and a
    response swapped (a hammer record estimated as continuous, so the impact path's refusal never ran), or a
    channel that is no response (a tachometer's once-per-revolution pulses). The FRF of such a pair is the
    inverse of the structure's, or no FRF at all; warned rather than refused, since a tachometer channel
    listed among the responses leaves the other channels' FRFs sound."""
    for o in range(response.shape[0]):
        train = pulse_train(np.asarray(response[o], dtype=float), sample_rate_hz)
        if train.impulsive:
            warn(f"{source}: {labels[len(labels) - response.shape[0] + o]} is {train.count} short pulse(s) holding "
                 f"{100 * train.energy_share:.0f} % of its energy in {100 * train.duty:.2f} % of the record, as hammer "
                 "hits are, while the excitation is none: the force and response channels look swapped (the "
                 "cables at the recorder or the file's channel labels), or the channel is no response (a "
                 "tachometer's pulses); its FRF is no FRF of the structure: check the channels' roles",
                 QualityWarning)
