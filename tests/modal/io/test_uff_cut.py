"""A UFF file cut between datasets: the FRF datasets ending inside a group of channels their own order implies
is said (a cut file otherwise reads as a smaller complete one); complete grids and single groups are not."""
from __future__ import annotations

import warnings

import numpy as np
import pytest

from modal.errors import ModalWarning
from modal.io import read_frf, write_frf
from modal.synthetic import modal_frf

FREQ = 2.0 + 0.25 * np.arange(41)
CUT = "may be cut between datasets"


def _grid(tmp_path, responses, references, order="reference", keep=None):
    """A UFF file of a roving-hammer grid: every response for each reference (``order="reference"``) or every
    reference for each response, written whole, then the file cut after its first ``keep`` datasets at a
    dataset boundary (what a copy or transfer stopped there leaves: a well-formed, smaller file)."""
    pairs = ([(r, q) for q in references for r in responses] if order == "reference"
             else [(r, q) for r in responses for q in references])
    const = np.linspace(1.0, 2.0, 2 * len(pairs)).reshape(len(pairs), 2)
    frf = modal_frf(FREQ, [5.0, 9.0], [0.02, 0.03], const, kind="accelerance",
                    response_points=[r for r, _ in pairs], reference_points=[q for _, q in pairs])
    path = tmp_path / "grid.uff"
    write_frf(frf, path)
    if keep is not None:
        data = path.read_bytes()
        starts = [i for i in range(len(data)) if data.startswith(b"    -1\n    58", i)]
        # each dataset opens with '    -1' then its type line; cut just before dataset keep+1 opens
        path.write_bytes(data[:starts[keep]])
    return path


def _read(path):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        frf = read_frf(path)
    return frf, [str(w.message) for w in caught if issubclass(w.category, ModalWarning)]


REFS = [f"{k}+Z" for k in range(1, 13)]


def test_cut_inside_a_reference_group_is_said(tmp_path):
    # two accelerometers, roving hammer over 12 points, written reference by reference; cut after 13 datasets:
    # the last reference (7+Z) has 1+Z but not 12+Z
    path = _grid(tmp_path, ["1+Z", "12+Z"], REFS, keep=13)
    frf, said = _read(path)
    assert frf.n_channels == 13
    (msg,) = [m for m in said if CUT in m]
    assert str(path) in msg and "dataset 13" in msg and "\n" not in msg
    assert "reference 7+Z has 1 response(s) where each of the other 6 has 2 (missing 12+Z)" in msg


def test_cut_inside_a_response_group_is_said(tmp_path):
    # the same grid written response by response, cut at 18 of 24: the second accelerometer has 6 of 12 hits
    path = _grid(tmp_path, ["1+Z", "12+Z"], REFS, order="response", keep=18)
    frf, said = _read(path)
    assert frf.n_channels == 18
    (msg,) = [m for m in said if CUT in m]
    assert "response 12+Z has 6 reference(s) where each of the other 1 has 12 (missing 7+Z, 8+Z" in msg


@pytest.mark.parametrize("order", ["reference", "response"])
def test_complete_grids_read_without_a_word(tmp_path, order):
    frf, said = _read(_grid(tmp_path, ["1+Z", "12+Z"], REFS, order=order))
    assert frf.n_channels == 24 and not said


def test_legitimate_ragged_files_read_without_a_word(tmp_path):
    # two setups with a reference each and their own roving accelerometers (not one grid): groups differ,
    # no group is the start of another
    responses = [f"{k}+Z" for k in range(1, 13)]
    pairs = [(r, "1+Z") for r in responses[:6]] + [(r, "7+Z") for r in responses[6:]]
    frf = modal_frf(FREQ, [5.0, 9.0], [0.02, 0.03], np.ones((12, 2)), kind="accelerance",
                    response_points=[r for r, _ in pairs], reference_points=[q for _, q in pairs])
    path = tmp_path / "setups.uff"
    write_frf(frf, path)
    assert not _read(path)[1]
    # a cut exactly between groups, or a single group cut anywhere, is not decidable from the file: it reads
    # as the smaller complete file it looks like (the channel count is printed by `modal fit`)
    for keep, responses_, refs in ((12, ["1+Z", "12+Z"], REFS), (6, ["1+Z"], REFS)):
        frf, said = _read(_grid(tmp_path, responses_, refs, keep=keep))
        assert frf.n_channels == keep and not said
