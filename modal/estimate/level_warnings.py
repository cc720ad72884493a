"""The warnings of the hits' consistency tests (:mod:`.levels`): one message each, naming the channel, the
line, the test's p against its level, and what to do.

- :func:`warn_level_dependence`: the FRF changes with the force of the hit (a nonlinearity);
- :func:`warn_change_dependence`: one record's (or take's) hits change FRF part way through (the hammer or a
  sensor moved, the structure changed);
- :func:`warn_changes_within_takes`: that test for each take of a several-take record;
- :func:`warn_take_dependence`: the takes do not share one FRF.
"""
from __future__ import annotations

import numpy as np

from ..errors import QualityWarning, warn
from .levels import FAMILY_LEVEL, MIN_HITS, change_dependence, level_dependence, take_dependence
from .takes import hit_labels

__all__ = ["warn_level_dependence", "warn_change_dependence", "warn_changes_within_takes", "warn_take_dependence"]


def warn_level_dependence(force, response, starts, length, input_window, output_window, sample_rate_hz, labels,
                           source, spectra) -> None:
    """Warn where the hits' FRFs change with their force level beyond the noise (:mod:`.levels`)."""
    test = level_dependence(force, response, starts, length, input_window, output_window, sample_rate_hz, spectra)
    if test is None or not test.level_dependent:
        return
    low, high = test.force_range
    warn(f"{source}: the FRF changes with the force of the hit beyond its noise (nonlinearity: {test.n_hits} hits "
         f"from {low:.3g} to {high:.3g} in the force's unit; {labels[len(labels) - response.shape[0] + test.output]} "
         f"at {test.frequency_hz:.4g} Hz, F-test p = {test.p_value:.2g} against {test.limit:.2g} over "
         f"{test.n_lines} lines): the average mixes the structure's states; estimate hits of one force level "
         "together, or hit alike", QualityWarning)


def warn_change_dependence(force, response, starts, hit_numbers, hit_times_s, length, input_window, output_window,
                            sample_rate_hz, labels, source, spectra, take: str = "", family_level=FAMILY_LEVEL) -> None:
    """Warn where one record's (or one ``take``'s) hits change FRF part way through beyond the noise
    (:func:`.levels.change_dependence`)."""
    test = change_dependence(force, response, starts, length, input_window, output_window, sample_rate_hz, spectra,
                             family_level)
    if test is None or not test.changed:
        return
    before, after = hit_numbers[test.first_after - 1], hit_numbers[test.first_after]
    at, where = hit_times_s[test.first_after], labels[len(labels) - response.shape[0] + test.output]
    warn(f"{source}: {take}the hits' FRF changes between hit {before} and hit {after} (at {at:.3f} s) beyond its noise "
         f"({where} at {test.frequency_hz:.4g} Hz by {100 * test.change:.0f} %, F-test p = {test.p_value:.2g} "
         f"against {test.limit:.2g} over {test.n_lines} {'resonant ' if test.resonant else ''}lines and "
         f"{test.n_hits - 1} places): the hammer or a sensor moved, or the structure changed, during the record, "
         "and the average mixes two FRFs; estimate the hits before and after apart", QualityWarning)


def warn_changes_within_takes(force, response, starts, take_of_hit, hits, bounds, take_names, length, input_window,
                               output_window, sample_rate_hz, labels, source, spectra) -> None:
    """Test each take of :data:`.levels.MIN_HITS` hits or more for a change part way through, as one record's hits
    are, the family-wise level spread over those takes; hits and times counted within the take."""
    counts = np.bincount(take_of_hit, minlength=bounds.size - 1)
    tested = np.flatnonzero(counts >= MIN_HITS)
    named = hit_labels(hits, bounds, take_names, sample_rate_hz)
    named = [item for item, kept in zip(named, hits.accepted) if kept]
    for t in tested:
        index = np.flatnonzero(take_of_hit == t)
        warn_change_dependence(force, response, starts[index], [named[i]["hit"] for i in index],
                                [named[i]["time_s"] for i in index], length, input_window, output_window,
                                sample_rate_hz, labels, source, None if spectra is None else spectra.of_hits(index),
                                take=f"{take_names[t]}: ", family_level=FAMILY_LEVEL / tested.size)


def warn_take_dependence(force, response, starts, take_of_hit, length, input_window, output_window,
                          sample_rate_hz, labels, take_names, source, spectra) -> None:
    """Warn where the takes' hits do not share one FRF beyond the noise (:func:`.levels.take_dependence`)."""
    test = take_dependence(force, response, starts, take_of_hit, length, input_window, output_window, sample_rate_hz,
                           spectra)
    if test is None or not test.takes_differ:
        return
    names = ", ".join(take_names[t] for t in sorted(set(int(t) for t in take_of_hit)))
    warn(f"{source}: the takes' FRFs differ beyond their noise ({names}: "
         f"{labels[len(labels) - response.shape[0] + test.output]} at {test.frequency_hz:.4g} Hz, F-test p = "
         f"{test.p_value:.2g} against {test.limit:.2g} over {test.n_lines} lines): they do not measure one FRF "
         "(a hit point labelled twice, a sensor moved or the structure changed between them); estimate them apart",
         QualityWarning)
