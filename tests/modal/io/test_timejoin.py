"""Several time files as one record of takes (modal.io.timejoin.join_takes)."""
from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from modal.errors import FormatError
from modal.io.timejoin import join_takes
from modal.synthetic import DigitalModes, impact_record

PLANT = DigitalModes([40.0, 95.0], [0.03, 0.02], [[1.0, 0.5], [0.6, -0.8]], 1024.0)


def _take(seed, source):
    # noise as every measured take has (noiseless takes of one hit time would be the same samples)
    return replace(impact_record(PLANT, [0.5], 2.0, seed=seed, names=["hammer", "a1", "a2"], force_noise=1e-3,
                                 response_noise=1e-3).record, source=source)


def test_takes_are_joined_end_to_end_and_say_where_each_ends():
    first, second = _take(1, "a.csv"), _take(2, "b.csv")
    joined = join_takes([first, second])
    np.testing.assert_array_equal(joined.signals, np.concatenate([first.signals, second.signals], axis=1))
    assert joined.take_lengths == (first.n_samples, second.n_samples)
    assert joined.take_sources == ("a.csv", "b.csv") and joined.source == "a.csv (+1 file)"
    assert join_takes([first]) is first


@pytest.mark.parametrize("change, fragment", [
    ({"names": ("hammer", "a1", "a3")}, "b.csv: channel 3 (names) is 'a3' where a.csv has 'a2'"),
    ({"units": ("N", "m/s^2", "m/s")}, "b.csv: channel 3 (units) is 'm/s' where a.csv has 'm/s^2'"),
    ({"sample_rate_hz": 2048.0}, "b.csv: sample rate 2048 Hz where a.csv has 1024 Hz"),
    ({"full_scale": (100.0, None, None)}, "b.csv: full scale"),
])
def test_a_take_with_other_channels_is_refused(change, fragment):
    second = replace(_take(2, "b.csv"), **change)
    with pytest.raises(FormatError) as info:
        join_takes([_take(1, "a.csv"), second])
    assert fragment in str(info.value) and "expected" in str(info.value) and "\n" not in str(info.value)


def test_a_take_with_fewer_channels_is_refused():
    second = _take(2, "b.csv")
    second = replace(second, signals=second.signals[:2], names=second.names[:2], quantities=second.quantities[:2],
                     units=second.units[:2])
    with pytest.raises(FormatError, match="b.csv: 2 channel\\(s\\) where a.csv has 3"):
        join_takes([_take(1, "a.csv"), second])


def test_files_measured_at_different_points_are_pointed_to_the_frf_route():
    # a roving hammer saves one file per excitation point: the force channel's point id changes, nothing else;
    # averaging them as takes would mix two FRFs, so they are refused with the way to combine them as channels
    second = replace(_take(2, "b.csv"), names=("hammer2", "a1", "a2"))
    with pytest.raises(FormatError, match=r"roving hammer or sensor\) are not takes.*modal fit A.h5 B.h5"):
        join_takes([_take(1, "a.csv"), second])
    other_unit = replace(_take(2, "b.csv"), names=("hammer2", "a1", "a2"), units=("N", "m/s^2", "m/s"))
    with pytest.raises(FormatError) as info:
        join_takes([_take(1, "a.csv"), other_unit])
    assert "roving" not in str(info.value)  # other units: not the same test moved, another record


def test_one_take_saved_twice_at_another_precision_is_refused():
    # a copy is refused by its bytes before reading; the same take exported again with 7 significant digits
    # (a CSV and a re-export, or two formats) has other bytes and would be averaged with itself
    first = _take(1, "a.csv")
    again = replace(first, signals=np.array([[float(f"{v:.7g}") for v in channel] for channel in first.signals]),
                    source="a_again.csv")
    with pytest.raises(FormatError) as info:
        join_takes([first, _take(2, "b.csv"), again])
    message = str(info.value)
    assert message.startswith("a_again.csv: holds the same samples as a.csv") and "\n" not in message
    # two takes of one hit time and plant differ by their noise alone, and are two takes
    assert join_takes([first, _take(2, "b.csv")]).take_lengths == (first.n_samples,) * 2
