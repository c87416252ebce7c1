"""Every uPlot is framed one way (app/panel/plots.py): never an empty axis range, huge values
drawn in units of 10³ᵏ with the exponent on the axis, y axes as wide as their tick text,
labelled x axes; and the plots of each kind that issue 12 found broken."""

from __future__ import annotations

import numpy as np
import pytest

from shoal.app.panel import plots
from shoal.app.panel.plots import frame, x_scale, y_view


def test_no_axis_range_is_ever_empty():
    assert x_scale((0.0, 0.0))["range"] == (0.0, plots.MIN_SPAN)  # generation 0: one point
    assert x_scale((5.0, float("nan")))["range"] == (5.0, 5.0 + plots.MIN_SPAN)
    for values in ([], [0.0], [0.0, 0.0], [3.0, 3.0], [-2.0], [np.nan, np.inf]):
        v = y_view([np.array(values, dtype=float)])
        lo, hi = v.range()
        assert np.isfinite([lo, hi]).all() and hi > lo, values
    assert y_view([np.array([0.3, 7.2])]).range() == (0.0, 10.0)  # 1-2-5 steps from 0
    assert y_view([np.array([-3.0, 0.4])]).range() == (-5.0, 0.5)


def test_huge_values_are_drawn_with_an_exponent_and_an_axis_wide_enough():
    data = (np.array([0.0, 1.0, 2.0]), np.array([10.0, 4.0e6, 3.3e7]))
    f = frame(data, ({}, {"label": "max |u|"}), x_range=(0.0, 2.0), on_y=(True,))
    lo, hi = f.scales["y"]["range"]
    assert (lo, hi) == (0.0, 50.0)  # 5e7 in units of 10⁶
    np.testing.assert_allclose(f.data[1], data[1] * 1e-6)
    assert "×10⁶" in f.axes[1]["label"]
    small = frame((data[0], np.array([1.0, 2.0, 3.0])), ({}, {}), x_range=(0.0, 2.0), on_y=(True,))
    wide = frame((data[0], np.array([-1500.5, 2.0, 30000.0])), ({}, {}), x_range=(0.0, 2.0), on_y=(True,))
    assert wide.axes[1]["size"] > small.axes[1]["size"]  # "-50,000" needs more room than "4"
    tiny = frame((data[0], np.array([1e-7, 2e-7, 0.0])), ({}, {}), x_range=(0.0, 2.0), on_y=(True,))
    assert "×10⁻⁹" in tiny.axes[1]["label"] and tiny.scales["y"]["range"][1] == pytest.approx(200.0)


def test_a_time_plot_labels_its_x_axis_and_keeps_a_given_y_side():
    f = frame((np.array([0.0, 1.0]), np.array([2.0, 3.0])), ({}, {}), x_range=(0.0, 1.0), on_y=(True,),
              y_range=(0.0, 6.5), x_label="t [s]")
    assert f.axes[0]["label"] == "t [s]" and f.scales["y"]["range"] == (0.0, 6.5)


def _handles(tab, preset: str):
    assert tab.panels.load_preset(preset)
    tab.tick(0.0)
    return tab.panels.handles


def test_a_diverging_standard_swarm_keeps_readable_speed_ticks(tab):
    h = _handles(tab, "standard-pso")
    tab.session.apply({"controller.omega": 1.1})
    tab.session.step(150)
    tab.panels.refresh_plots()
    speed = h["speed"]
    assert float(np.nanmax(speed.data[1])) < 1e3  # drawn in units of 10³ᵏ...
    assert "×10" in speed.axes[1]["label"]  # ...said on the axis
    assert float(np.max(tab.session.metric_arrays()["max_speed"])) > 1e5


def test_slo_generation_0_and_sonar_plots_have_ranges_and_labels(tab):
    h = _handles(tab, "slo-pso-sphere")
    for key in ("error", "distance", "fitness"):
        lo, hi = h[key].scales["x"]["range"]
        assert hi > lo, key  # no all-zero x ticks at generation 0
    h = _handles(tab, "sonar-gt-pso")  # one hydrophone: no bearing, so no R(τ) plot
    assert not h["corr"].visible
    assert h["snr"].axes[0]["label"] == "robot" and h["snr"].axes[0]["size"] > 0
    assert h["dist"].axes[0]["label"] == "t [s]"
    h = _handles(tab, "sonar-xb-pso")
    assert h["corr"].visible and h["corr"].axes[0]["label"] == "τ [ms]"
    lo, hi = h["corr"].scales["x"]["range"]
    assert hi - lo > 0.1  # τ in ms over the window, not every tick "0"


def test_chapter_3_plots_best_f_or_distance_and_the_measured_spread(tab):
    h = _handles(tab, "rastrigin")
    tab.session.step(30)
    tab.panels.refresh_plots()
    assert h["best_f"].visible and not h["best_distance"].visible
    best = tab.session.metric_arrays()["best_fitness"]
    np.testing.assert_allclose(h["best_f"].data[1] * 10.0 ** _exponent(h["best_f"]), np.log10(np.abs(best)),
                               rtol=1e-9)
    x, yg = tab.session.sim.state.x[0], tab.session.sim.state.yg[0]
    spread = tab.session.metric_arrays()["second_moment"]
    assert spread[-1] == pytest.approx(np.mean((x - yg) ** 2))  # the order-2 region's quantity, measured
    h = _handles(tab, "default")  # a source to find: the best position's distance to it
    tab.session.step(5)
    tab.panels.refresh_plots()
    assert h["best_distance"].visible and not h["best_f"].visible


def _exponent(handle) -> int:
    """The 10³ᵏ a framed plot's y values are drawn in (0 without an exponent)."""
    label = handle.axes[1].get("label", "")
    if "×10" not in label:
        return 0
    sup = label.split("×10")[1].split()[0]
    return int(sup.translate(str.maketrans("⁻⁰¹²³⁴⁵⁶⁷⁸⁹", "-0123456789")))


def test_the_last_x_tick_has_room_on_the_right():
    """"1,000" centred on the right edge of an SLO plot at generation 1000 was cut by the card."""
    f = frame((np.array([0.0, 1000.0]), np.array([1.0, 2.0])), ({}, {"label": "y"}), x_range=(0.0, 1000.0),
              on_y=(True,))
    half = plots.CHAR_PX * len("1,000") / 2
    assert f.padding[1] >= half + 2 and f.padding[0] == plots.PADDING[0]
    narrow = frame((np.array([0.0, 90.0]), np.array([1.0, 2.0])), ({}, {"label": "y"}), x_range=(0.0, 90.0),
                   on_y=(True,))
    assert narrow.padding == plots.PADDING  # "80" fits the usual padding


def test_large_text_scales_the_axes_fonts_sizes_and_padding():
    f = frame((np.array([0.0, 1000.0]), np.array([1.0, 2.0])), ({}, {"label": "y"}), x_range=(0.0, 1000.0),
              on_y=(True,), x_label="t [s]", y_label="R(τ)")
    big = plots.scale_text(f, 1.5)
    assert plots.scale_text(f, 1.0) is f
    assert all(a["font"].startswith("18px") and a["labelFont"].startswith("bold 18px") for a in big.axes)
    assert big.axes[0]["size"] == 45 and big.axes[1]["size"] >= 1.5 * f.axes[1]["size"]
    assert big.padding[1] >= 1.5 * f.padding[1] and big.data is f.data and big.scales is f.scales
