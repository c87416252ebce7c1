"""The Experiment tab on a real app server (experiments on its forkserver pool), driven by
setting its handles as the page would: the scene's fields and outcomes, a run with progress
and medians, a cell opened in the arena plays the run behind the number, downloads, Cancel,
refusals in the page, and a tab whose scene changes kind."""

from __future__ import annotations

import numpy as np
import pytest

from shoal.app.experiment.panel import AS_RANGE, NONE
from shoal.app.experiment.service import CANCELLED, FINISHED
from shoal.presets.io import load
from shoal.studies.sweep import catalogue

from app_helpers import shown
from browser.browser_helpers import wait_until


def _settle(panel, timeout=120):
    """Wait until the panel shows its experiment as over (the last change reached it)."""
    wait_until(lambda: panel.experiment is not None and panel.experiment.over and not panel.run.disabled,
               timeout=timeout, what="the experiment over in the panel")
    return panel.experiment


def _ask(panel, field1, values1, field2=NONE, values2="", runs=6, steps=30):
    panel.axes[0].field.value = field1
    panel.axes[0].values.value = values1
    panel.axes[1].field.value = field2
    panel.axes[1].values.value = values2
    panel.runs.value = runs
    panel.steps.value = steps


def test_the_tab_offers_the_fields_and_outcomes_of_its_scene(tab):
    p = tab.panels.experiment
    sc = tab.session.scenario
    keys = tuple(f.key for f in catalogue.fields(sc))
    assert tuple(p.axes[0].field.options) == keys and tuple(p.axes[1].field.options) == (NONE, *keys)
    assert p.axes[0].field.value == "controller.U" and p.axes[1].field.value == NONE
    assert p.axes[0].values.value == "3.0, 5.25, 7.5, 9.75, 12.0"  # half to twice the preset's U = 6
    assert "top speed U" in shown(p.axes[0].info.content) and "0 < U ≤ 1000" in shown(p.axes[0].info.content)
    assert tuple(p.outcome.options) == tuple(o.title for o in catalogue.outcomes(sc))
    assert p.outcome.value == "final best f" and p.steps.value == sc.sim.steps
    p.axes[0].field.value = "controller.law"  # a choice: every law the model accepts here
    assert p.axes[0].values.value == "adapted-sgn, adapted-tanh, adapted-logistic" and not p.axes[0].given.visible
    p.axes[0].field.value = "controller.A_plus"
    p.axes[0].given.value = AS_RANGE
    assert (p.axes[0].start.value, p.axes[0].stop.value) == (15.0, 60.0)
    assert p.axes[0].start.visible and not p.axes[0].values.visible


def test_the_fields_follow_the_scene_as_it_changes(tab):
    p = tab.panels.experiment
    assert "controller.omega" not in p.axes[0].field.options
    assert tab.panels.apply({"controller.mode": "raw"}, "mode")
    tab.tick(1.0)
    assert "controller.omega" in p.axes[0].field.options and "controller.U" not in p.axes[0].field.options
    assert p.axes[0].field.value in p.axes[0].field.options


def test_a_run_shows_progress_medians_cells_and_sends_the_downloads(tab):
    p = tab.panels.experiment
    _ask(p, "controller.U", "6, 9", "controller.A_plus", "10, 20")
    p.run.value = True
    exp = _settle(p)
    assert exp.phase == FINISHED and p.progress.value == 100.0
    assert "finished: 4 cells × 6 runs" in shown(p.status.content)
    heat = p.plot.figure.data[0]
    med, lo, hi = exp.table.summary("best_fitness")
    assert heat.type == "heatmap" and np.allclose(np.array(heat.z, dtype=float), med.T)
    assert len(p.cell.options) == 4 and "A_plus=20" in p.cell.options[3]
    assert "median" in shown(p.cell_info.content) and "95 % interval" in shown(p.cell_info.content)
    assert "--grid controller.U=6,9 --grid controller.A_plus=10,20 --runs 6" in shown(p.command.content)
    p.download_csv.value = True
    p.download_png.value = True
    p.download_preset.value = True
    (csv_name, csv_bytes), (png_name, png_bytes), (toml_name, toml_bytes) = list(tab.downloads)[-3:]
    assert csv_name == "default-experiment.csv" and csv_bytes == exp.table.csv().encode()
    assert png_name == "default-experiment-best_fitness.png" and png_bytes.startswith(b"\x89PNG")
    assert toml_name == "default-experiment.toml" and b"runs = 6" in toml_bytes and b"steps = 30" in toml_bytes
    p.outcome.value = "highest robot speed over the run [m/s]"  # another outcome: no new run
    assert "highest robot speed over the run" in p.plot.figure.layout.title.text
    assert p.experiment is exp and "median" in shown(p.cell_info.content)


def test_one_field_draws_the_median_and_its_interval_band(tab):
    p = tab.panels.experiment
    _ask(p, "controller.U", "6, 9, 12", runs=8, steps=20)
    p.run.value = True
    exp = _settle(p)
    lower, upper, median = p.plot.figure.data
    med, lo, hi = exp.table.summary("best_fitness")
    assert list(median.x) == [6, 9, 12] and np.allclose(np.array(median.y, dtype=float), med)
    assert upper.fill == "tonexty" and np.allclose(np.array(lower.y, dtype=float), lo)
    assert np.all(lo <= med) and np.all(med <= hi) and np.any(lo < hi)


def test_open_in_arena_plays_the_run_behind_the_number(tab):
    p = tab.panels.experiment
    _ask(p, "controller.U", "6, 9", "controller.A_plus", "10, 20", runs=3, steps=25)
    p.run.value = True
    exp = _settle(p)
    p.cell.value = p.cell.options[3]  # U = 9, A_plus = 20
    p.open.value = True
    sc = tab.session.scenario
    assert (sc.controller.U, sc.controller.A_plus, sc.sim.seed) == (9, 20, load("default").sim.seed)
    assert tab.messages[-1][0] == "Cell opened in the arena"
    for _ in range(25):
        tab.session.step(1)
    arena = tab.session.sim.state.best_fitness[0]
    assert f"{arena:.12g}" == f"{exp.table.runs_of(3, 'best_fitness')[0]:.12g}"  # run 0 of that cell


def test_a_refused_run_says_why_in_the_page(tab):
    p = tab.panels.experiment
    _ask(p, "controller.U", "0, 6")
    p.run.value = True
    assert p.experiment is None and "**Refused:**" in shown(p.status.content) and "0 is outside 0 < U ≤ 1000" in \
        shown(p.status.content)
    title, body, color = tab.messages[-1]
    assert (title, color) == ("Refused: experiment", "red") and "controller.U" in body


def test_cancel_in_the_page_keeps_the_finished_cells(tab):
    p = tab.panels.experiment
    _ask(p, "sim.robots", "20, 30, 40, 50, 60, 70, 80, 90, 100, 110, 120, 130", runs=10, steps=600)
    p.run.value = True
    wait_until(lambda: p.experiment is not None and len(p.experiment.table) >= 1, timeout=120, what="a first cell")
    p.cancel.value = True
    exp = _settle(p)
    assert exp.phase == CANCELLED and 1 <= len(exp.table) < 12
    assert "cells finished and kept" in shown(p.status.content) and len(p.cell.options) == len(exp.table)


def test_a_scene_of_another_kind_still_shows_the_tabs_experiment(tab):
    p = tab.panels.experiment
    _ask(p, "controller.U", "6, 9", runs=2, steps=10)
    p.run.value = True
    exp = _settle(p)
    assert tab.panels.load_preset("sonar-xb-pso")
    q = tab.panels.experiment
    assert q is not p and p.removed and q.experiment is exp and "finished" in shown(q.status.content)
    assert q.axes[0].field.value == "acoustics.algorithm"
    q.axes[0].values.value = "x-pso, xb-pso"
    q.runs.value, q.steps.value = 2, 5
    q.outcome.value = "inertia weight ω at the end"  # the past experiment's, not recorded by this scene:
    q.run.value = True  # the scene's first outcome is asked for instead
    sonar = _settle(q)
    assert sonar is not exp and sonar.outcome == "com_dist" and q.outcome.value.startswith("CoM distance")


@pytest.mark.parametrize("bad", ["name", "sim.seed", "../x", ""])
def test_a_field_that_is_not_offered_is_refused(tab, bad):
    p = tab.panels.experiment
    p.axes[0].field.value = bad  # viser takes any value set on a dropdown; the service does not
    p.run.value = True
    assert p.experiment is None and "Refused" in tab.messages[-1][0]


def test_the_panel_stands_alone_and_its_plot_keeps_up_with_the_cells(server):
    """The panel module on a bare viser GUI with its own service: while a cell is held back,
    the plot already shows every cell finished before it."""
    import threading

    from shoal.app.experiment import ExperimentService
    from shoal.app.experiment.panel import ExperimentPanel
    from shoal.studies.experiments.schedulers import InProcess

    import gates as held

    held.reset()
    held.GATES[2] = threading.Event()
    service = ExperimentService(InProcess(), simulate=held.gated)
    sent, said = [], []
    panel = ExperimentPanel(server.viser.gui, service, "alone", scenario=lambda: load("default"),
                            open_cell=lambda sc: None, notify=lambda *m: said.append(m),
                            send_file=lambda name, data: sent.append(name))
    try:
        _ask(panel, "controller.U", "6, 8, 10, 12", runs=2, steps=5)
        panel.run.value = True
        wait_until(lambda: 2 in held.STARTED, what="cell 2 held back")

        def drawn():
            data = panel.plot.figure.data  # the median is the last trace (none before a cell is in)
            return sum(v is not None for v in data[-1].y) if data else 0

        wait_until(lambda: drawn() == 2, timeout=30, what="the plot with the two finished cells")  # (held 60 s)
        assert "running: 2 of 4 cells" in shown(panel.status.content) and panel.run.disabled
        held.GATES[2].set()
        exp = _settle(panel)
        assert drawn() == 4 and exp.phase == FINISHED and not said
        panel.download_csv.value = True
        assert sent == ["default-experiment.csv"]
    finally:
        held.reset()
        panel.remove()
        service.stop()
        server.viser.gui.reset()


def test_a_grid_with_an_invalid_cell_is_offered_without_it_and_named_by_labels_and_units(tab):
    p = tab.panels.experiment
    _ask(p, "controller.U", "2, 6", "controller.A_plus", "10, 30", runs=2, steps=5)  # β = 30·0.1/2 > 1
    p.run.value = True
    assert p.experiment is None and "1 of 4 cells cannot run" in p.status.content
    assert p.skip.visible and p.skip.label == "Run the other 3 of 4 cells"
    p.skip.value = True
    exp = _settle(p)
    assert not p.skip.visible and "finished: 3 cells × 2 runs (1 invalid left out)" in p.status.content
    heat = p.plot.figure.data[0]
    assert heat.text[1][0] == "invalid" and heat.text[0][0] not in ("", "invalid")  # U = 2, A+ = 30 left out
    layout = p.plot.figure.layout
    assert layout.xaxis.title.text == "top speed U [m/s]" and layout.yaxis.title.text == "top acceleration A+ [m/s²]"
    assert "controller." not in heat.hovertemplate and len(p.cell.options) == 3
    assert exp.plan.axes[0].name == "top speed U [m/s]"
    _ask(p, "controller.U", "2, 6", "controller.A_plus", "10, 30", runs=2, steps=5)
    p.run.value = True
    assert p.skip.visible
    p.axes[1].field.value = "controller.dt"  # another grid: the offer goes
    assert not p.skip.visible
