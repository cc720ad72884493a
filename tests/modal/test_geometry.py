"""The test geometry: nodes, trace lines, channels placed by their point ids."""
import numpy as np
import pytest

import warnings

from modal.errors import ParameterError, QualityWarning
from modal.geometry import Geometry, direction_vector, line_geometry


def _square():
    ids = np.array([1, 2, 3, 4])
    xyz = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float)
    return Geometry(ids, xyz, [[1, 2], [2, 3], [3, 4], [4, 1]], source="square")


def test_point_ids_place_channels_on_their_nodes_and_directions():
    g = _square().with_channels(["3+Z", "1-X", "4+Y", "2", "2+RX"])
    assert g.channel_node.tolist() == [3, 1, 4, 2, 2]
    expected = [[0, 0, 1], [-1, 0, 0], [0, 1, 0], [0, 0, 1], [0, 0, 0]]  # bare node: +Z; rotation: nothing drawn
    np.testing.assert_array_equal(g.channel_direction, expected)
    np.testing.assert_array_equal(g.coordinates_m[g.node_index(g.channel_node)][0], [1, 1, 0])


def test_a_point_on_a_node_the_geometry_lacks_is_a_one_line_error():
    # channels are counted from 1 in messages, as on the command line and in tables
    with pytest.raises(ParameterError, match=r"square: channel 2 \(point '9\+Z'\) stands on node 9.*nodes 1\.\.4"):
        _square().with_channels(["1+Z", "9+Z"])
    with pytest.raises(ParameterError, match="channel 1: point id 'abc'"):
        _square().with_channels(["abc"])


def test_bad_nodes_and_lines_are_refused():
    with pytest.raises(ParameterError, match="repeats node 2"):
        Geometry([1, 2, 2], np.zeros((3, 3)))
    with pytest.raises(ParameterError, match="trace line names node 7"):
        Geometry([1, 2], np.zeros((2, 3)), [[1, 7]])
    with pytest.raises(ParameterError, match="coordinates_m"):
        Geometry([1, 2], [[0, 0, 0], [np.nan, 0, 0]])


def test_without_a_geometry_channels_stand_on_a_line_in_file_order():
    g = line_geometry(4)
    assert g.node_id.tolist() == [1, 2, 3, 4] and g.channel_node.tolist() == [1, 2, 3, 4]
    np.testing.assert_array_equal(g.coordinates_m[:, 0], [0, 1, 2, 3])
    assert g.lines.tolist() == [[1, 2], [2, 3], [3, 4]]
    assert np.all(g.channel_direction == [0, 0, 1])


def test_placed_for_uses_the_geometry_map_else_the_point_ids():
    square = _square()
    mapped = square.with_channels(["1+Z", "2+Z"])
    with pytest.warns(QualityWarning, match=r"square: the geometry's channel map places channel 1 at 1\+Z, the data's "
                                            r"point id says '3\+Z' \(2 of 2 channels disagree\)"):
        assert mapped.placed_for(2, ["3+Z", "4+Z"]) is mapped  # the file's own map wins, and says so
    with pytest.raises(ParameterError, match="places 2 channel"):
        mapped.placed_for(3, None)
    assert square.placed_for(1, ["4-Z"]).channel_node.tolist() == [4]
    with pytest.raises(ParameterError, match="no point ids"):
        square.placed_for(2, None)


def test_a_channel_map_that_disagrees_with_the_data_is_warned_naming_the_first_channel():
    # a map written for another channel order, or with a sensor's sign flipped, placed the shapes where the
    # map says with no word: a sign drawn wrong at one node looks like a real mode shape
    mapped = _square().with_channels(["1+Z", "2+Z", "3-X"])
    with pytest.warns(QualityWarning, match=r"places channel 3 at 3-X, the data's point id says '3\+X' \(1 of 3"):
        mapped.placed_for(3, ["1+Z", "2+Z", "3+X"])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert mapped.placed_for(3, ["1+Z", "2+Z", "3-X"]) is mapped  # the same places: no word
        assert mapped.placed_for(3, ["11+Z", "12+Z", "13+Z"]) is mapped  # ids on no node of it: a renaming
        assert mapped.placed_for(3, None) is mapped


def test_direction_vector_of_every_translation():
    assert direction_vector("12-Y")[0] == 12
    np.testing.assert_array_equal(direction_vector("12-Y")[1], [0, -1, 0])


def test_geometry_round_trips_through_the_archive(tmp_path):
    from modal.archive import read_archive, write_archive

    g = _square().with_channels(["1+Z", "3-X"])
    write_archive(tmp_path / "a.h5", {"geometry": g})
    back = read_archive(tmp_path / "a.h5")["geometry"]
    assert isinstance(back, Geometry)
    for name in ("node_id", "coordinates_m", "lines", "channel_node", "channel_direction"):
        np.testing.assert_array_equal(getattr(back, name), getattr(g, name))
    import h5py

    with h5py.File(tmp_path / "a.h5") as f:
        assert f["geometry/coordinates_m"].attrs["units"] == "m"  # every archived number carries its units
