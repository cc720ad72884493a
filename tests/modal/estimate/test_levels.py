"""The hits' FRFs tested against their force levels (modal.estimate.levels): nonlinearity in an impact test."""
from __future__ import annotations

import re
import warnings

import numpy as np
import pytest

import modal
from modal.estimate.levels import FAMILY_LEVEL, change_dependence, level_dependence
from modal.synthetic import DigitalModes, impact_record

FS = 1024.0
LEVELS_N = [30.0, 60.0, 120.0, 240.0]


def _levelled(shift, seed=0, noise=1e-3):
    """Two hits at each force level; the structure's frequencies rise by ``shift`` (a fraction) from no force to
    the strongest hit (a hardening joint), each hit answered by the linear structure of its own level."""
    force, response = [], []
    for k, level in enumerate(LEVELS_N):
        scale = 1 + shift * level / LEVELS_N[-1]
        plant = DigitalModes([40.0 * scale, 95.0 * scale], [0.01, 0.02], [[1.0, 0.5]], FS)
        record = impact_record(plant, [0.5, 4.5], 8.0, amplitude_n=level, seed=seed + k, response_noise=noise,
                               force_noise=noise).record
        force.append(record.signals[0])
        response.append(record.signals[1:])
    return np.concatenate(force), np.concatenate(response, axis=1), [record.n_samples] * len(LEVELS_N)


def _estimate(force, response, takes, window="force", **options):
    return modal.estimate_frf(force, response, FS, impact=True, window=window, kind="accelerance",
                              take_lengths=takes, **options)


def test_hits_of_a_structure_that_stiffens_with_the_force_are_warned_of():
    # frequencies 1 % higher at 240 N than at 0 N: averaged, the 30-240 N hits gave 40.349 ± 0.008 Hz (no flag)
    # where the structure is at 40.05-40.4 Hz
    force, response, takes = _levelled(0.01)
    with pytest.warns(modal.QualityWarning) as caught:
        _estimate(force, response, takes)
    said = [str(w.message) for w in caught]
    assert any("changes with the force of the hit beyond its noise (nonlinearity: 8 hits from 30 to 240" in m
               for m in said)
    # each take at its own level: the takes differ too, and are said to
    assert any("the takes' FRFs differ beyond their noise (take 1, take 2, take 3, take 4" in m for m in said)


def test_a_linear_structure_hit_at_many_levels_raises_no_warning():
    # the same hits on the linear structure: the test's family-wise false alarm is FAMILY_LEVEL per record; hits
    # whose force and pulse width scatter widely (a factor 8 in force), with or without an exponential window
    assert FAMILY_LEVEL <= 1e-4
    for seed in range(6):
        force, response, takes = _levelled(0.0, seed=10 * seed)
        with warnings.catch_warnings():
            warnings.simplefilter("error", modal.QualityWarning)
            _estimate(force, response, takes)
            _estimate(force, response, takes, window="exponential", exponential_decay_s=0.5)
    plant = DigitalModes([40.0, 95.0], [0.01, 0.02], [[1.0, 0.5], [0.6, -0.8]], FS)
    record = impact_record(plant, [0.5 + 4 * k for k in range(8)], 33.0, seed=3, amplitude_variation=0.6,
                           width_variation=0.3, response_noise=1e-4, force_noise=1e-4).record
    with warnings.catch_warnings():
        warnings.simplefilter("error", modal.QualityWarning)
        modal.estimate_frf(record.signals[0], record.signals[1:], FS, impact=True, window="force", kind="accelerance")


def test_the_test_says_nothing_where_it_cannot():
    force, response, takes = _levelled(0.01)
    starts = np.array([512 - 8, 4608 - 8])
    window = np.ones(2048)
    # two hits: no degrees of freedom for the noise once the level's slope is fitted
    assert level_dependence(force, response, starts, 2048, window, window, FS) is None
    # hits of one force level: no spread to test against
    plant = DigitalModes([40.0, 95.0], [0.01, 0.02], [[1.0, 0.5]], FS)
    same = impact_record(plant, [0.5 + 4 * k for k in range(6)], 25.0, seed=1, response_noise=1e-3).record
    starts = np.array([int(0.5 * FS) + 4096 * k - 8 for k in range(6)])
    assert level_dependence(same.signals[0], same.signals[1:], starts, 2048, window, window, FS) is None


def _two_points():
    """Three hits at one point, then three with the hammer at another (the structure's other shape there):
    each part's record, and the two joined (force, responses)."""
    first = impact_record(DigitalModes([40.0, 95.0], [0.01, 0.02], [[1.0, 0.5]], FS), [0.5, 4.5, 8.5], 12.0,
                          seed=1, response_noise=1e-3, force_noise=1e-3).record
    other = impact_record(DigitalModes([40.0, 95.0], [0.01, 0.02], [[0.6, -0.8]], FS), [0.5, 4.5, 8.5], 12.0,
                          seed=2, response_noise=1e-3, force_noise=1e-3).record
    force = np.concatenate([first.signals[0], other.signals[0]])
    response = np.concatenate([first.signals[1:], other.signals[1:]], axis=1)
    return first, other, force, response


def test_takes_that_do_not_measure_one_frf_are_warned_of():
    # two takes of three hits each, the second with the hammer at another point of the structure: averaged as
    # takes of one test they mixed two FRFs, and nothing said so
    first, other, force, response = _two_points()
    with pytest.warns(modal.QualityWarning, match=r"the takes' FRFs differ beyond their noise \(a.csv, b.csv"):
        modal.estimate_frf(force, response, FS, impact=True, window="force", kind="accelerance",
                           take_lengths=[first.n_samples, other.n_samples], take_names=["a.csv", "b.csv"])
    # the same point in both takes: one FRF, no warning
    again = impact_record(DigitalModes([40.0, 95.0], [0.01, 0.02], [[1.0, 0.5]], FS), [0.5, 4.5, 8.5], 12.0,
                          seed=2, response_noise=1e-3, force_noise=1e-3).record
    with warnings.catch_warnings():
        warnings.simplefilter("error", modal.QualityWarning)
        modal.estimate_frf(np.concatenate([first.signals[0], again.signals[0]]),
                           np.concatenate([first.signals[1:], again.signals[1:]], axis=1), FS, impact=True,
                           window="force", kind="accelerance", take_lengths=[first.n_samples, again.n_samples])


def test_a_record_whose_hammer_moved_part_way_through_is_warned_of():
    # one file, the hammer moved to the next point after hit 3: the six hits' average is of two FRFs, as smooth
    # as either; nls then gave the 40 Hz mode's constant 0.80 ± 0.09 (the points' 1.0 and 0.6 averaged), a
    # stiffness 25 % off the first point's, lost the 95 Hz mode (0.5 and -0.8 averaged), and nothing said so
    _, _, force, response = _two_points()
    with pytest.warns(modal.QualityWarning, match=r"the hits' FRF changes between hit 3 and hit 4 \(at 12\.50\d s\)"):
        modal.estimate_frf(force, response, FS, impact=True, window="force", kind="accelerance")
    # the test needs four hits (two parameters per line and noise left over): with three it says nothing
    assert change_dependence(force, response, np.array([512, 4608, 8704]) - 8, 2048, np.ones(2048), np.ones(2048),
                             FS) is None


def _sensor_changed(n_hits: int, second_mode: float, seed: int):
    """``n_hits`` hits 4 s apart whose sensor's second constant falls from 0.5 to ``second_mode`` from hit
    n/2 + 1 on: the force, the response and each hit's first sample (8 before its trigger)."""
    hits = [0.5 + 4 * k for k in range(n_hits)]
    duration = 4.0 * n_hits + 1.0
    before, after = (impact_record(DigitalModes([40.0, 95.0], [0.01, 0.02], [[1.0, second]], FS), hits, duration,
                                   seed=seed, response_noise=1e-3, force_noise=1e-3).record
                     for second in (0.5, second_mode))
    cut = int((4.0 * (n_hits // 2) + 0.3) * FS)  # between hit n/2 and the next
    response = np.concatenate([before.signals[1:, :cut], after.signals[1:, cut:]], axis=1)
    return before.signals[0], response, np.array([int(t * FS) - 8 for t in hits])


def test_a_change_within_one_record_is_placed_and_sized():
    # the sensor's second mode halves from hit 5 of 8 on (a magnet base sliding towards a node)
    force, response, starts = _sensor_changed(8, 0.25, seed=5)
    test = change_dependence(force, response, starts, 2048, np.ones(2048), np.ones(2048), FS)
    assert test.changed and test.first_after == 4
    # found where the second mode's change tells most: each group's FRF a third of that mode's part off the
    # average's (0.5 and 0.25 against 0.375), more of the FRF near the zero below it, where the first mode's part
    # cancels much of the second's
    assert 70.0 < test.frequency_hz < 130.0
    assert test.change > 0.25


def test_the_resonant_lines_find_a_change_every_lines_family_misses(monkeypatch):
    # four hits, the sensor's second mode falls from 0.5 to 0.2 from hit 3 on: F(2, 4) over ~1000 lines asks for
    # a change about a hundred times a line's noise; over the ~40 resonant lines, a few times less. With every
    # line alone, even at the whole family-wise level, the change is missed (p 9e-8 against 3.3e-8 here); the
    # resonant family at half the level finds it (against 4.4e-7)
    import modal.estimate.levels as levels

    force, response, starts = _sensor_changed(4, 0.2, seed=4)
    window = np.ones(2048)
    test = change_dependence(force, response, starts, 2048, window, window, FS)
    assert test.changed and test.resonant and test.first_after == 2
    monkeypatch.setattr(levels, "RESONANT_POWER_RATIO", np.inf)  # no resonant line: every line's family alone ...
    monkeypatch.setattr(levels, "FAMILY_LEVEL", 2 * FAMILY_LEVEL)  # ... at the whole level
    assert not change_dependence(force, response, starts, 2048, window, window, FS).changed


def test_a_change_within_one_take_of_several_is_warned_of():
    # two takes (files) of six hits at one point; in the second the sensor's second constant falls from 0.5 to 0.25
    # from its hit 4 on. The takes' test compares the takes' averages (the second's a mix of the two) and said
    # nothing; each take of four hits or more is now tested as one record is, the level spread over the takes
    first = impact_record(DigitalModes([40.0, 95.0], [0.01, 0.02], [[1.0, 0.5]], FS), [0.5 + 4 * k for k in range(6)],
                          25.0, seed=7, response_noise=1e-3, force_noise=1e-3).record
    for second_mode, changed in ((0.25, True), (0.5, False)):
        force, response, _ = _sensor_changed(6, second_mode, seed=8)
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            modal.estimate_frf(np.concatenate([first.signals[0], force]),
                               np.concatenate([first.signals[1:], response], axis=1), FS, impact=True,
                               window="force", kind="accelerance", take_lengths=[first.n_samples, force.size],
                               take_names=["a.csv", "b.csv"])
        said = [str(w.message) for w in caught if issubclass(w.category, modal.QualityWarning)]
        found = [m for m in said if "the hits' FRF changes between" in m]
        if changed:
            assert len(found) == 1 and re.search(r"b\.csv: the hits' FRF changes between hit 3 and hit 4 "
                                                 r"\(at 12\.50\d s\)", found[0])
        else:
            assert said == []


def test_the_hits_spectra_are_computed_once_for_the_level_and_change_tests(monkeypatch):
    # the level and change tests read the same transforms of the hits' records: each channel's records are cut once
    import modal.estimate.levels as levels

    force, response, _ = _sensor_changed(6, 0.5, seed=9)
    cut = []
    original = levels._records
    monkeypatch.setattr(levels, "_records", lambda channel, *args: cut.append(1) or original(channel, *args))
    modal.estimate_frf(force, response, FS, impact=True, window="force", kind="accelerance")
    assert len(cut) == 1 + response.shape[0]
