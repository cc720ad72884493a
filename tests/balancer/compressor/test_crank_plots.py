"""Figures of the crank study (balancer.compressor.crank_plots): the computed data, drawn without pyplot."""
from __future__ import annotations

import numpy as np
import pytest

from support.crank import SPEED_000_RPM

from balancer.compressor.crank import counterweight_on_curve, optimal_counterweight


# ----------------------------------------------------------------------------- plots
def test_plots_draw_the_computed_data_without_pyplot(seed000):
    import inspect

    from matplotlib.figure import Figure

    from balancer.compressor import crank_plots

    opt = optimal_counterweight(seed000, SPEED_000_RPM, n_curve_points=5)
    light = counterweight_on_curve(seed000, opt)
    fig = crank_plots.plot_force_vs_angle(seed000, SPEED_000_RPM, light.mass_kg, light.radius_m)
    assert isinstance(fig, Figure)
    resultant = fig.axes[0].lines[2].get_ydata()
    # the drawn |F| never exceeds the exact peak, and reaches it at 0 deg
    assert resultant.max() <= opt.max_force_n * (1 + 1e-12)
    assert resultant[0] == pytest.approx(opt.max_force_n, rel=1e-9)

    fig = crank_plots.plot_force_locus(seed000, SPEED_000_RPM, light.mass_kg, light.radius_m)
    before, after = fig.axes[0].lines[:2]
    assert np.hypot(before.get_xdata(), before.get_ydata()).max() == pytest.approx(
        318.3321, abs=5e-5)
    assert np.hypot(after.get_xdata(), after.get_ydata()).max() <= opt.max_force_n * (1 + 1e-12)

    fig = crank_plots.plot_objective(seed000, SPEED_000_RPM, opt)
    marker = fig.axes[0].lines[1]
    assert marker.get_xdata()[0] == opt.balance_fraction
    assert fig.axes[0].lines[0].get_ydata().min() >= opt.max_force_n

    fig = crank_plots.plot_optimal_curve(opt)
    np.testing.assert_allclose(fig.axes[0].lines[0].get_ydata(),
                               opt.curve.counterweight_radius_m * 1e3)
    # drawing on a caller's axes returns that axes' figure
    own = Figure()
    axes = own.add_subplot()
    assert crank_plots.plot_optimal_curve(opt, ax=axes) is own
    # the module never touches pyplot state
    source = inspect.getsource(crank_plots)
    assert "import matplotlib.pyplot" not in source and "plt." not in source
