"""The balancing report's polar plot (balancer.influence.plots)."""
from __future__ import annotations

import numpy as np
import pytest

from support.balancing import inline_scene


def test_balance_plot_draws_the_report(tmp_path):
    """What the polar plot draws: the readings, the prediction and the corrections of the report."""
    import balancer
    from balancer.influence.plots import plot_balance

    report = balancer.run_scene(inline_scene(tmp_path), out=tmp_path / "inline.h5").results["balance"].report
    figure = plot_balance(report)
    ax_v, ax_m = figure.axes[:2]
    for values, style in ((report.initial, "-"), (report.residual, "--")):
        amplitude, phase = report.in_user_units(values)
        arrows = [line for line in ax_v.get_lines() if line.get_linestyle() == style and len(line.get_xdata())]
        assert len(arrows) == len(report.sensors)
        for line, a, p in zip(arrows, amplitude, phase):  # from the origin to (phase lag, amplitude)
            np.testing.assert_allclose(line.get_xdata(), [0, np.deg2rad(p)])
            np.testing.assert_allclose(line.get_ydata(), [0, a])
    markers = [line for line in ax_v.get_lines() if line.get_label().startswith("trial plane")]
    assert len(markers) == len(report.trial_runs)
    for line, run in zip(markers, report.trial_runs):
        np.testing.assert_allclose(line.get_ydata(), report.in_user_units(run)[0])
    scale = 1e3 if report.mass_units == "g" else 1.0
    heads = [(text.xy[0], text.xy[1]) for text in ax_m.texts]
    np.testing.assert_allclose(heads, np.column_stack([np.deg2rad(report.correction_angle_deg),
                                                       report.correction_mass_kg * scale]))
    assert ax_m.get_ylim() == pytest.approx((0.0, 1.2 * report.correction_mass_kg.max() * scale))
    assert "[µm]" in ax_v.get_title() and report.mass_units in ax_m.get_title()


def test_balance_plot_legends_name_every_reading_and_the_holes(tmp_path):
    """The legend names each reading's colour (not only the first), the line styles, and the masses on the holes."""
    import balancer
    from balancer.influence.plots import plot_balance

    report = balancer.run_scene(inline_scene(tmp_path), out=tmp_path / "inline.h5").results["balance"].report
    ax_v, ax_m = plot_balance(report).axes[:2]
    entries = {text.get_text() for text in ax_v.get_legend().get_texts()}
    assert set(report.sensors) <= entries and {"initial", f"predicted after ({report.method})"} <= entries
    colours = {h.get_label(): h.get_color() for h in ax_v.get_legend().legend_handles}
    drawn = {line.get_color() for line in ax_v.get_lines() if line.get_linestyle() == "-" and len(line.get_xdata())}
    assert {colours[s] for s in report.sensors} == drawn  # each reading's entry has its arrows' colour
    holes = [t.get_text() for t in ax_m.get_legend().get_texts() if "on holes" in t.get_text()]
    assert len(holes) == report.correction_kg_m.size
    for j, text in enumerate(holes):
        on = report.split_mass_kg[j] > 0
        assert text.count("°") == on.sum()  # one mass and angle per hole used
