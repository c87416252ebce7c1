"""The Experiment tab against a hostile page: values no page would send, spoken on viser's raw
websocket, are refused with messages (by the server's input guard, or by the experiment
service) and queue nothing; a flood of Run clicks queues one experiment; a tab that closes
cancels its experiment."""

from __future__ import annotations

import pytest
from viser import _messages as m

from shoal.app.server import start_server

from browser.browser_helpers import wait_until
from viser_wire import WireClient

# Values no control of the tab can hold: the server's input guard refuses them before the tab
# sees them (wrong kind, not finite, not among a dropdown's options), and the control keeps
# the value in force.
MALFORMED = [
    ("field 1", "name"), ("field 1", "view.trail_seconds"), ("field 1", {"$gt": ""}), ("field 2", "../x"),
    ("values 1 as", "cubes"), ("outcome", "../../etc/passwd"), ("runs per cell", float("inf")),
    ("runs per cell", "lots"), ("from 1", float("nan")), ("values 1", ["6", "9"]),
    # (the boxes carry their ranges, so these too are refused by name as they arrive)
    ("runs per cell", -5), ("runs per cell", 10**12), ("runs per cell", 0), ("from 1", -1e300),
]
# Values the controls can hold that the experiment service refuses (then Run), with its message.
HOSTILE = [
    ([("values 1", "6, 1e400")], "controller.U: inf is not a finite number"),
    ([("values 1", "6, " + "9" * 5000)], "longer than 1000 characters"),
    ([("values 1", "[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[")], "controller.U"),
    ([("values 1", ", ".join(str(6 + i) for i in range(40)))], "40 values; this server takes at most 12"),
    ([("steps per run", 2.5)], "steps per run: 2.5 is not a whole number"),
    ([("values 1 as", "range and count"), ("count 1", 10**9)], "count: 1000000000 is outside 2..12"),
    ([("values 1 as", "range and count"), ("from 1", -1e6)], "controller.U: -1e+06 is outside 0 < U ≤ 1000"),
    ([("field 2", "controller.U")], "controller.U: chosen twice"),
]


@pytest.fixture(scope="module")
def served():
    srv = start_server("default", port=0)
    yield srv
    srv.stop()


def _tab(srv, with_tab=False):
    """A new tab, once the server has built it (its handles reach the page a little earlier);
    with ``with_tab``, also the server's side of it."""
    before = set(srv.tabs)
    c = WireClient(srv.port, decode=True)
    wait_until(lambda: set(srv.tabs) - before and c.uuid_of("Run experiment"), what="the Experiment tab")
    if with_tab:
        (key,) = set(srv.tabs) - before
        return c, srv.tabs[key]
    return c


def _set(c, label, value):
    c.send(m.GuiUpdateMessage(c.wait_uuid(label), {"value": value}))


@pytest.mark.parametrize("label, value", MALFORMED)
def test_values_no_control_can_hold_are_refused_before_the_tab_sees_them(served, label, value):
    c, tab = _tab(served, with_tab=True)
    try:
        panel = tab.panels.experiment
        handle = {"field 1": panel.axes[0].field, "field 2": panel.axes[1].field, "values 1 as": panel.axes[0].given,
                  "outcome": panel.outcome, "runs per cell": panel.runs, "from 1": panel.axes[0].start,
                  "values 1": panel.axes[0].values}[label]
        before = handle.value
        _set(c, label, value)
        wait_until(lambda: c.saw(f"Refused: {label} = "), what="the input guard's refusal")
        assert handle.value == before and served.experiments.queued_runs() == 0
    finally:
        c.close()


@pytest.mark.parametrize("changes, words", HOSTILE)
def test_hostile_values_on_the_wire_are_refused_with_messages(served, changes, words):
    c = _tab(served)
    try:
        _set(c, "values 1", "6, 9")
        for label, value in changes:
            _set(c, label, value)
        _set(c, "Run experiment", True)
        wait_until(lambda: c.saw("Refused: experiment"), what="a refusal in the page")
        assert c.saw(words), [t for t in c.texts if "Refused" in t or ":" in t][-4:]
        assert served.experiments.queued_runs() == 0
        assert all(served.experiments.experiment(cid) is None for cid in served.tabs)
    finally:
        c.close()


def test_after_refusals_the_same_tab_runs_an_experiment(served):
    c = _tab(served)
    try:
        _set(c, "values 1", "6, 9")
        _set(c, "steps per run", 5)
        _set(c, "runs per cell", 0)  # (refused by the box's range)
        wait_until(lambda: c.saw("runs per cell: less than its least value 1 (got 0)"), what="a refusal")
        _set(c, "values 1", "6, 1e400")  # (refused by the experiment service)
        _set(c, "Run experiment", True)
        wait_until(lambda: c.saw("controller.U: inf is not a finite number"), what="a refusal")
        _set(c, "values 1", "6, 9")
        _set(c, "runs per cell", 2)
        _set(c, "Run experiment", True)
        wait_until(lambda: c.saw("finished: 2 cells × 2 runs"), timeout=120, what="the experiment finished")
    finally:
        c.close()


def test_forty_run_clicks_on_the_wire_queue_one_experiment(served):
    c = _tab(served)
    try:
        _set(c, "values 1", "6, 9")
        _set(c, "runs per cell", 2)
        _set(c, "steps per run", 200)
        for _ in range(40):
            _set(c, "Run experiment", True)
        wait_until(lambda: c.saw("finished: 2 cells × 2 runs"), timeout=120, what="the experiment finished")
        numbers = {t for t in c.texts if t.startswith("**Experiment ")}
        assert len({t.split("**")[1] for t in numbers}) == 1  # every other click was refused
        assert c.saw("already has an experiment queued or running")
    finally:
        c.close()


def test_a_tab_that_closes_cancels_its_experiment(served):
    c = _tab(served)
    _set(c, "field 1", "sim.robots")
    _set(c, "values 1", "20, 40, 60, 80, 100, 120, 140, 160, 180, 200, 220, 240")
    _set(c, "runs per cell", 20)
    _set(c, "steps per run", 2000)
    _set(c, "Run experiment", True)
    wait_until(lambda: c.saw("running:"), timeout=60, what="the experiment running")
    (cid,) = [k for k, t in served.tabs.items() if t.panels.experiment and t.panels.experiment.experiment]
    exp = served.experiments.experiment(cid)
    c.close()
    wait_until(lambda: exp.over, timeout=120, what="the experiment over after the tab closed")
    assert exp.phase == "cancelled" and len(exp.table) < 12
    assert served.experiments.experiment(cid) is None and served.experiments.queued_runs() == 0
