"""A scene archive's balancing stages as report sections: the stage's numbers with units, and its figures."""
import pytest

from modal.archive import read_archive


@pytest.fixture(scope="module")
def demo_archive(tmp_path_factory):
    from balancer.scene import run_scene
    from support.paths import SYNTHETIC

    folder = tmp_path_factory.mktemp("demo")
    run_scene(SYNTHETIC / "demo_scene.toml", out=folder / "demo.h5", plots_dir=folder / "plots")
    return folder / "demo.h5"


def test_each_balancing_stage_is_a_section_with_its_numbers_and_figures(demo_archive):
    from balancer.scene.report import report_sections
    from balancer.scene.summary import digest

    archive = read_archive(demo_archive)
    sections = {s.title: s for s in report_sections(archive)}
    assert "identify" not in sections and "frf" not in sections  # the report draws these itself
    assert {"rotor", "adb_stability", "adb_response", "compressor", "mounts"} <= set(sections)
    rows = dict(sections["compressor"].rows)
    expected = digest("compressor", archive["compressor"])
    assert rows["max_force_n"] == f"{expected['max_force_n']:.5g} N"  # unit from the field's name
    assert rows["balance_fraction"] == f"{expected['balance_fraction']:.5g}"  # dimensionless: no unit
    captions = [caption for caption, _ in sections["compressor"].images]
    assert captions == ["compressor: force_locus", "compressor: objective"]
    assert all(png.startswith(b"\x89PNG") for _, png in sections["adb_response"].images)


def test_the_report_of_a_scene_archive_has_a_scene_section(demo_archive, tmp_path):
    from modal.report import write_report

    text = write_report(demo_archive, tmp_path / "demo.html").read_text(encoding="utf-8")
    # the demo's balancing figures: stability, response, force locus, objective, base force
    assert '<section id="scene">' in text and text.count("data:image/png;base64,") == 5
