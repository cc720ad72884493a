"""OMAOptions: the one vocabulary of the operational options (command line, scene, batch)."""
from __future__ import annotations

import argparse

import pytest

from modal.cli_oma import add_oma_options
from modal.errors import ParameterError
from modal.operational.files import OMAOptions


def test_options_from_the_command_line_keep_their_names():
    parser = argparse.ArgumentParser()
    add_oma_options(parser)
    options = OMAOptions.from_args(parser.parse_args(["--band", "1", "30", "--reference-channels", "2", "A1+Z",
                                                      "--rotor-speed-hz", "4.8"]))
    assert options == OMAOptions(band_hz=(1.0, 30.0), reference_channels=("2", "A1+Z"), rotor_speed_hz=4.8)
    assert options.settings() == {"band_hz": [1.0, 30.0], "method": "ssi", "reference_channels": ["2", "A1+Z"],
                                  "rotor_speed_hz": 4.8}
    # the settings hash changes with any option (a cache keyed on it never mixes results)
    assert options.settings_hash() != OMAOptions(band_hz=(1.0, 31.0), reference_channels=("2", "A1+Z"),
                                                 rotor_speed_hz=4.8).settings_hash()
    assert OMAOptions.from_args(parser.parse_args([])) == OMAOptions()


@pytest.mark.parametrize("kwargs, message", [({"method": "magic"}, "'method' is 'magic'"),
                                             ({"band_hz": (1.0,)}, "expected two frequencies"),
                                             ({"band_hz": (30.0, 10.0)}, "expected 0 <= FMIN < FMAX")])
def test_bad_options_are_refused(kwargs, message):
    with pytest.raises(ParameterError, match=message):
        OMAOptions(**kwargs)
