"""A scene rerun on an earlier archive whose identified numbers are in another unit (edited by hand, or written by
another tool under the same names): refused naming the archive and the field, where the rotor used to take the
stored number as SI."""
import h5py
import pytest

from balancer import run_scene
from modal.errors import ArchiveError

from support.scenes import ROTOR, SYNTH_FRF, scene


def test_an_earlier_archive_with_stiffness_in_kn_per_m_is_refused(tmp_path):
    config = scene(frf=SYNTH_FRF, identify={"method": "nls"}, rotor=ROTOR,
                   outputs={"tables": ["identify"], "archive": True})
    first = tmp_path / "a.h5"
    run_scene(config, out=first)
    with h5py.File(first, "r+") as f:
        f["identify/modes/0/stiffness_n_per_m"].attrs["units"] = "kN/m"
    with pytest.raises(ArchiveError, match=r"a\.h5: /identify/modes/0/stiffness_n_per_m has units 'kN/m'; "
                                           r"expected 'N/m'"):
        run_scene(config, out=tmp_path / "b.h5", archive=first)
    assert not (tmp_path / "b.h5").exists()
