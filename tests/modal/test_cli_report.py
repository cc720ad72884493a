"""`python -m modal report` and `modal fit --geometry`: the plate's archive made as users make it (a subprocess),
the rest through ``modal.cli.main`` in-process (the exit codes, messages and files are the point)."""
import subprocess
import sys

import numpy as np
import pytest

import modal.cli
from modal.archive import read_archive, write_archive
from modal.io import write_frf
from modal.synthetic import modal_frf
from support.cli import run_main
from support.paths import SYNTHETIC

PLATE_FRF = SYNTHETIC / "plate_frf.uff"
PLATE_GEOMETRY = SYNTHETIC / "plate_geometry.uff"


def run_process(*args):
    """``python -m modal ARGS`` in a subprocess."""
    return subprocess.run([sys.executable, "-m", "modal", *map(str, args)], capture_output=True, text=True,
                          timeout=120)


def run(*args):
    """``python -m modal ARGS`` in this process."""
    return run_main(modal.cli.main, args)


@pytest.fixture(scope="module")
def plate_archive(tmp_path_factory):
    path = tmp_path_factory.mktemp("plate") / "plate.h5"
    out = run_process("fit", PLATE_FRF, "--archive", path, "--geometry", PLATE_GEOMETRY)
    assert out.returncode == 0, out.stderr
    return path


def _generator():
    import importlib.util

    spec = importlib.util.spec_from_file_location("generate", SYNTHETIC / "generate.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_plate_archive_keeps_its_geometry_and_its_shapes_are_the_plates(plate_archive):
    from modal.shapes import mac, mode_shapes

    archive = read_archive(plate_archive)
    geometry = archive["geometry"]
    assert geometry.n_nodes == 30 and len(geometry.lines) == 49  # 6 x 5 grid: 5*5 + 6*4 segments
    assert archive["source_files"] == [str(PLATE_FRF)]
    result = archive["identify_global"]
    gen = _generator()
    found = np.array([m.natural_frequency_hz for m in result])
    # noise 0.2 % of max |H| on 0.5 Hz lines: the global fit recovers each frequency to well under a line
    np.testing.assert_allclose(found, gen.plate_frequencies_hz(), atol=0.05)
    shapes = mode_shapes(result, archive["frf"].response_points, archive["frf"].reference_points)
    placed = shapes.placed_on(geometry)
    truth = gen.plate_shapes(geometry.coordinates_m[geometry.node_index(placed.channel_node)])
    # the analytical shapes at the measured points: MAC near 1 on the diagonal (noise 0.2 %), near 0 off it
    table = mac(shapes.shapes, truth)
    assert np.all(np.diag(table) > 0.999) and np.all(table[~np.eye(5, dtype=bool)] < 0.01)


def test_report_and_gif_of_the_plate(plate_archive, tmp_path):
    from PIL import Image

    out = run("report", plate_archive, "--out", tmp_path / "plate.html", "--gif", tmp_path / "mode2.gif",
              "--mode", "2")
    assert out.returncode == 0, out.stderr
    text = (tmp_path / "plate.html").read_text(encoding="utf-8")
    assert '<section id="shapes">' in text and "plate_geometry.uff" in text
    with Image.open(tmp_path / "mode2.gif") as gif:
        assert gif.n_frames == 24  # one cycle


@pytest.mark.parametrize("make, expect", [
    (lambda p: write_archive(p, {"batch": {"n_files": 3}}), "is a batch archive (many files)"),
    (lambda p: p.write_text("frequency,re,im\n"), "not a readable HDF5 file"),
    (lambda p: None, "no such archive file"),
    # an FRF file (what modal frf --out writes), not a fit: it failed with "node /frf has unknown type None"
    (lambda p: write_frf(modal_frf(np.linspace(1.0, 100.0, 200), [40.0], [0.02], [1.0]), p),
     "an FRF file (/frf/<name>, as modal frf --out writes it), not an archive of results; expected an archive of a "
     "fit: python -m modal fit"),
])
def test_what_cannot_be_reported_is_one_line_and_exit_1(tmp_path, make, expect):
    path = tmp_path / "x.h5"
    make(path)
    out = run("report", path, "--out", tmp_path / "x.html")
    assert out.returncode == 1
    assert out.stderr.count("\n") == 1 and out.stderr.startswith("error: ") and expect in out.stderr, out.stderr
    assert not (tmp_path / "x.html").exists()


def test_gif_mode_out_of_range_is_one_line(plate_archive, tmp_path):
    out = run("report", plate_archive, "--out", tmp_path / "p.html", "--gif", tmp_path / "p.gif", "--mode", "9")
    assert out.returncode == 1 and "--mode must be 1..5" in out.stderr and not (tmp_path / "p.gif").exists()


def test_a_geometry_that_lacks_a_channels_node_writes_no_archive(tmp_path):
    geometry = tmp_path / "g.csv"
    geometry.write_text("node, 8, 0, 0, 0\nnode, 9, 1, 0, 0\n")
    out = run("fit", PLATE_FRF, "--archive", tmp_path / "a.h5", "--geometry", geometry)
    assert out.returncode == 1 and "stands on node 10, which the geometry does not have" in out.stderr
    assert not (tmp_path / "a.h5").exists()
    out = run("fit", PLATE_FRF, "--geometry", geometry)
    assert out.returncode == 1 and "give --archive" in out.stderr


def test_a_geometry_whose_channel_map_swaps_two_channels_is_warned(plate_archive, tmp_path):
    # the data say channel 1 stands at 8+Z and channel 2 at 9+Z; a CSV geometry's channel rows give them the
    # other way round: the report drew the two swapped with no word
    from modal.io.geometry import read_geometry

    plate = read_geometry(PLATE_GEOMETRY)
    points = list(read_archive(plate_archive)["frf"].response_points)
    rows = [f"node, {i}, {x}, {y}, {z}" for i, (x, y, z) in zip(plate.node_id, plate.coordinates_m)]
    rows += [f"line, {a}, {b}" for a, b in plate.lines]
    rows += [f"channel, {p}" for p in [points[1], points[0], *points[2:]]]
    geometry = tmp_path / "mapped.csv"
    geometry.write_text("\n".join(rows) + "\n")
    # the page and the GIF both place the shapes on it: warned once
    out = run("report", plate_archive, "--out", tmp_path / "r.html", "--geometry", geometry, "--gif",
              tmp_path / "r.gif")
    assert out.returncode == 0, out.stderr
    assert out.stderr.count(f"warning: {geometry}: the geometry's channel map places channel 1 at {points[1]}, the "
                            f"data's point id says '{points[0]}' (2 of {len(points)} channels disagree)") == 1


def test_uff_export_carries_the_geometry_before_the_shapes(tmp_path):
    import pyuff

    from modal.io import read_frf
    from modal.io.geometry import read_geometry

    target = tmp_path / "plate_modes.uff"
    out = run("fit", PLATE_FRF, "--export-uff", target, "--geometry", PLATE_GEOMETRY)
    assert out.returncode == 0, out.stderr
    types = [int(t) for t in pyuff.UFF(str(target)).get_set_types()]
    assert types[0] == 15 and set(types) == {15, 82, 55, 58} and types.index(55) > max(i for i, t in enumerate(types)
                                                                                      if t == 82)
    geometry = read_geometry(target)
    assert geometry.n_nodes == 30
    shapes = [d for d in pyuff.UFF(str(target)).read_sets() if d["type"] == 55]
    assert len(shapes) == 5 and set(shapes[0]["node_nums"].astype(int)) <= set(geometry.node_id.tolist())
    assert read_frf(target).n_channels == 12  # the synthesised FRFs still read as FRFs
