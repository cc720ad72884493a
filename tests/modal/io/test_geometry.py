"""Geometry files: UFF 15/2411/82/164, typed CSV, TOML; bad files give one line naming file and field."""
import numpy as np
import pytest

from modal.errors import FormatError
from modal.geometry import Geometry
from modal.io.geometry import read_geometry, write_geometry_uff


def _plate():
    ids = np.array([1, 2, 3, 4, 5, 6])
    xyz = np.array([[0, 0, 0], [0.5, 0, 0], [1.0, 0, 0], [0, 0.4, 0.1], [0.5, 0.4, 0.1], [1.0, 0.4, 0.1]])
    lines = [[1, 2], [2, 3], [4, 5], [5, 6], [1, 4], [3, 6]]
    return Geometry(ids, xyz, lines, source="plate")


def test_uff_15_and_82_round_trip(tmp_path):
    plate = _plate()
    path = tmp_path / "plate.uff"
    write_geometry_uff(plate, path)
    back = read_geometry(path)
    assert back.node_id.tolist() == plate.node_id.tolist()
    # dataset 15 writes coordinates as E13.5: 6 significant digits
    np.testing.assert_allclose(back.coordinates_m, plate.coordinates_m, rtol=5e-6, atol=1e-12)
    assert sorted(map(tuple, back.lines.tolist())) == sorted(map(tuple, plate.lines.tolist()))


def test_uff_2411_nodes_and_164_length_factor(tmp_path):
    import pyuff

    path = tmp_path / "mm.unv"
    out = pyuff.UFF(str(path))
    # a file in millimetres: dataset 164's length factor 1000 (SI = value / factor)
    out.write_sets({"type": 164, "units_code": 5, "units_description": "mm", "temp_mode": 2, "length": 1000.0,
                    "force": 1.0, "temp": 1.0, "temp_offset": 273.15}, mode="add")
    out.write_sets({"type": 2411, "node_nums": np.array([10, 20]), "def_cs": np.array([0, 0]),
                    "disp_cs": np.array([0, 0]), "color": np.array([1, 1]), "x": np.array([0.0, 250.0]),
                    "y": np.array([0.0, 0.0]), "z": np.array([0.0, 12.5])}, mode="add")
    out.write_sets({"type": 82, "trace_num": 1, "n_nodes": 2, "color": 1, "id": "beam", "nodes": np.array([10, 20])},
                   mode="add")
    g = read_geometry(path)
    assert g.node_id.tolist() == [10, 20]
    np.testing.assert_allclose(g.coordinates_m[1], [0.25, 0.0, 0.0125], rtol=1e-15)
    assert g.lines.tolist() == [[10, 20]]


def test_uff_trace_line_pen_lift_breaks_the_line(tmp_path):
    import pyuff

    plate = _plate()
    path = tmp_path / "lift.uff"
    write_geometry_uff(Geometry(plate.node_id, plate.coordinates_m, source="x"), path)
    pyuff.UFF(str(path)).write_sets({"type": 82, "trace_num": 1, "n_nodes": 5, "color": 1, "id": "two",
                                     "nodes": np.array([1, 2, 0, 4, 5])}, mode="add")
    assert read_geometry(path).lines.tolist() == [[1, 2], [4, 5]]  # no segment 2-4 across the pen lift


def test_uff_without_nodes_is_refused(tmp_path):
    from modal.io import write_frf
    from modal.synthetic import modal_frf

    path = tmp_path / "frf.uff"
    write_frf(modal_frf(np.arange(1.0, 101.0), [40.0], [0.02], [1.0]), path)
    with pytest.raises(FormatError, match=r"frf\.uff: no dataset 15 or 2411 \(nodes\); found dataset types \[58\]"):
        read_geometry(path)


def test_typed_csv_with_units_lines_and_channels(tmp_path):
    path = tmp_path / "g.csv"
    path.write_text("# a frame\nunits, mm\nnode, 1, 0, 0, 0\nnode;2;1000;0;0\nnode 3 1000 500 0\n"
                    "line, 1, 2, 3\nchannel, 2+Z\nchannel, 3-Y\n")
    g = read_geometry(path)
    np.testing.assert_allclose(g.coordinates_m, [[0, 0, 0], [1, 0, 0], [1, 0.5, 0]], rtol=1e-15)
    assert g.lines.tolist() == [[1, 2], [2, 3]]
    assert g.channel_node.tolist() == [2, 3]
    np.testing.assert_array_equal(g.channel_direction, [[0, 0, 1], [0, -1, 0]])


@pytest.mark.parametrize("text, message", [
    ("node, 1, 0, 0\n", r"g\.csv: line 1: 'node' row has 3 fields; expected 4"),
    ("node, 1, 0, x, 0\n", r"line 1: field 'y' is 'x'; expected a number"),
    ("node, 1.5, 0, 0, 0\n", r"field 'id' is '1.5'; expected a positive node number"),
    ("units, furlong\nnode, 1, 0, 0, 0\n", r"line 1: length unit 'furlong'"),
    ("node, 1, 0, 0, 0\nline, 1, 5\n", r"trace line names node 5"),
    ("node, 1, 0, 0, 0\nchannel, 2+Z\n", r"channel 1 \(point '2\+Z'\) stands on node 2"),
    ("point, 1, 0, 0, 0\n", r"row type 'point'; expected node, line, channel or units"),
    ("# nothing\n", r"no 'node' rows"),
])
def test_bad_csv_gives_one_line_naming_file_and_field(tmp_path, text, message):
    path = tmp_path / "g.csv"
    path.write_text(text)
    with pytest.raises(FormatError, match=message):
        read_geometry(path)


def test_toml_geometry(tmp_path):
    path = tmp_path / "g.toml"
    path.write_text('length_unit = "cm"\nnodes = [[1, 0, 0, 0], [2, 100, 0, 0.5]]\nlines = [[1, 2]]\n'
                    'channels = ["1+Z", "2+X"]\n')
    g = read_geometry(path)
    np.testing.assert_allclose(g.coordinates_m[1], [1.0, 0.0, 0.005], rtol=1e-15)
    assert g.channel_node.tolist() == [1, 2]


@pytest.mark.parametrize("text, message", [
    ("nodes = []\n", "field 'nodes' is missing or empty"),
    ("nodes = [[1, 0, 0]]\n", r"field 'nodes' row 0 is \[1, 0, 0\]; expected \[id, x, y, z\]"),
    ("nodes = [[0, 0, 0, 0]]\n", "id is 0; expected a positive integer"),
    ("nodes = [[1, 0, 0, 0]]\nlines = [[1]]\n", r"field 'lines' row 0"),
    ("nodes = [[1, 0, 0, 0]]\nchannels = [1]\n", "field 'channels'"),
    ("nodes = [[1, 0, 0, 0]]\nnodez = 1\n", "unknown key 'nodez'"),
    ("nodes = [[1, 0, 0, 0]\n", "not valid TOML"),
])
def test_bad_toml_gives_one_line(tmp_path, text, message):
    path = tmp_path / "g.toml"
    path.write_text(text)
    with pytest.raises(FormatError, match=message):
        read_geometry(path)


def test_missing_file_and_unknown_extension(tmp_path):
    with pytest.raises(FormatError, match="no such file; expected a geometry file"):
        read_geometry(tmp_path / "none.uff")
    (tmp_path / "g.txt").write_text("node, 1, 0, 0, 0\n")
    with pytest.raises(FormatError, match=r"extension '\.txt' is not a geometry format"):
        read_geometry(tmp_path / "g.txt")
