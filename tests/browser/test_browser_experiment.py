"""The Experiment tab in Debian's Chromium: a small experiment run from the page shows its
progress bar moving and then the heat map of its medians (the numbers the server computed),
and a cell chosen in the page opens in the arena."""

from __future__ import annotations

import re
import shutil

import pytest

CHROMIUM = shutil.which("chromium")
pytestmark = [
    pytest.mark.browser,
    pytest.mark.skipif(CHROMIUM is None, reason="Debian's chromium is not on PATH (apt-get install chromium)"),
]

from browser_helpers import choose, dismiss_toasts, wait_until  # noqa: E402


def text_box(page, label: str):
    """The input of viser's text field ``label`` (its label points at the wrapper, not the input)."""
    exact = re.compile(rf"^\s*{re.escape(label)}\s*$")
    row = page.locator("label").filter(has_text=exact).first.locator(
        "xpath=ancestor::div[contains(@class, 'mantine-Flex-root')][1]")
    return row.locator("input")


def plain_number(page, label: str):
    exact = re.compile(rf"^\s*{re.escape(label)}\s*$")
    fid = page.locator("label").filter(has_text=exact).first.get_attribute("for")
    return page.locator(f'[id="{fid}"]')


PROGRESS_JS = """() => Array.from(document.querySelectorAll('[role=progressbar]'))
    .map(e => parseFloat(e.getAttribute('aria-valuenow')))"""


def test_an_experiment_run_from_the_page_shows_progress_and_the_result_plot(server, page, cid):
    dismiss_toasts(page)
    page.get_by_role("tab", name="Sweep").click()
    text_box(page, "values 1").fill("6, 8, 10, 12")
    choose(page, "field 2", "controller.A_plus")
    panel = server.tabs[cid].panels.experiment
    wait_until(lambda: panel.axes[1].values.value.startswith("15.0"), what="field 2's values suggested")
    text_box(page, "values 2").fill("10, 20, 30")
    for label, value in (("runs per cell", "10"), ("steps per run", "600")):
        box = plain_number(page, label)
        box.fill(value)
        box.press("Enter")
    wait_until(lambda: (panel.axes[0].values.value, panel.axes[1].values.value, panel.runs.value, panel.steps.value)
               == ("6, 8, 10, 12", "10, 20, 30", 10.0, 600.0), what="the page's values on the server")
    page.get_by_role("button", name="Run experiment").click()

    seen: set[float] = set()

    def progressed():
        seen.update(v for v in page.evaluate(PROGRESS_JS) if v == v)
        return page.get_by_text("finished: 12 cells × 10 runs").count() > 0

    wait_until(progressed, timeout=180, what="the experiment finished in the page")
    wait_until(lambda: 100 in page.evaluate(PROGRESS_JS), what="a full progress bar")
    assert any(0 < v < 100 for v in seen), seen  # the bar moved while cells came in
    exp = panel.experiment
    med = exp.table.summary("best_fitness")[0]
    plot = page.locator(".js-plotly-plot").filter(has_text="over 10 runs per cell")
    wait_until(lambda: plot.count() == 1, what="the heat map in the page")
    shown = set(plot.first.evaluate("e => Array.from(e.querySelectorAll('text')).map(t => t.textContent)"))
    assert {f"{v:.3g}" for v in med.ravel()} <= shown, shown  # the server's medians, in its cells

    choose(page, "cell", next(o for o in panel.cell.options if o.startswith("11:")))
    page.get_by_role("button", name="Open in arena").click()
    wait_until(lambda: server.tabs[cid].session.scenario.controller.U == 12, what="the cell in the arena")
    sc = server.tabs[cid].session.scenario
    assert (sc.controller.A_plus, sc.sim.seed) == (20, exp.plan.base.sim.seed)  # cell 11: U = 12, A+ = 20
