"""Every numeric control of every kind of scene, given hostile numbers over the raw websocket.

A page only sends what its sliders and number boxes can hold; a client speaking viser's
protocol sends anything. For each shipped kind of scene, every slider and number box of its
panels is sent 1e308, NaN, ±inf, −1e308 and a value just outside its range (the fleet's
budget ratio at −1 raised ``ZeroDivisionError``; a number box given 1e308 and then NaN
dropped the tab: a 309-digit integer that msgpack cannot encode). Each is refused with a red
message naming the control, the tab stays open and answers, and the server prints no
traceback. A camera report holding NaN or inf is dropped in one line, not a traceback.
"""

from __future__ import annotations

import math
import time
from typing import Any

import pytest
from viser import _messages

from shoal.app.server import start_server

from browser.browser_helpers import wait_until  # noqa: E402  (tests/ is on sys.path)
from viser_wire import WireClient

# One shipped preset for each kind of scene the app shows (and the fleet's physics).
PRESETS = ("default", "course-rpso", "course-dvc", "sonar-xb-pso", "slo-walk")
HOSTILE = (1e308, math.nan, math.inf, -math.inf, -1e308)
NUMERIC = ("GuiSliderMessage", "GuiNumberMessage")


def numeric_controls(c: WireClient) -> dict[str, dict[str, Any]]:
    """Label → props (as last updated: a timeline's range grows) of every slider and number box
    the page was given."""
    with c._lock:
        props = {m["uuid"]: dict(m["props"]) for m in c.gui if m.get("type") in NUMERIC}
        for m in c.gui:
            if m.get("type") == "GuiUpdateMessage" and m.get("uuid") in props:
                props[m["uuid"]].update(m.get("updates") or {})
    return {str(p["label"]): p for p in props.values()}


def outside(props: dict[str, Any]) -> list[float]:
    """Values outside a control's range (where it has one; a timeline's end grows as the run does)."""
    lo, hi = props.get("min"), props.get("max")
    return [v for v in (lo - 1 if lo is not None else None, hi + 1000 if hi is not None else None) if v is not None]


@pytest.fixture(scope="module", params=PRESETS)
def tab(request):
    srv = start_server(request.param, port=0)
    c = WireClient(srv.port, decode=True)
    wait_until(lambda: c.uuid_of("seed") and len(srv.tabs) == 1, what="the tab's panels")
    wait_until(lambda: len(numeric_controls(c)) > 3, what="the kind's controls")
    yield srv, c
    c.close()
    srv.stop()


def alive(srv: Any, c: WireClient) -> None:
    """The tab still answers: a good value of the seed box is taken and shown."""
    seed = next(iter(srv.sessions.values())).scenario.sim.seed
    new = 7 if seed != 7 else 8
    c.set_value("seed", new)
    wait_until(lambda: next(iter(srv.sessions.values())).scenario.sim.seed == new, what=f"seed {new} taken")
    assert not c.closed.is_set()


def test_every_numeric_control_refuses_hostile_numbers_by_name(tab, capfd):
    srv, c = tab
    controls = numeric_controls(c)
    assert "seed" in controls
    tried, failed = 0, []
    for label, props in controls.items():
        if props.get("disabled"):
            continue
        for value in (*HOSTILE, *outside(numeric_controls(c)[label])):
            before = len(c.notifications())
            c.set_value(label, value)
            end = time.monotonic() + 3
            while time.monotonic() < end and len(c.notifications()) <= before and not c.closed.is_set():
                time.sleep(0.02)
            assert not c.closed.is_set(), f"{label} = {value!r} dropped the tab (after {failed})"
            title, body, color = c.notifications()[-1] if len(c.notifications()) > before else ("", "", "")
            if not (color == "red" and title.startswith(f"Refused: {label}") and len(title) < 200
                    and len(body) < 400 and "Traceback" not in body):
                failed.append((label, value, title[:80], body[:120]))
            tried += 1
    assert not failed, failed
    alive(srv, c)
    err = capfd.readouterr().err
    assert "Traceback" not in err and "Task exception" not in err and "failed" not in err, err[-3000:]
    assert tried >= 5 * len(controls) - 5


@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf])
def test_a_camera_report_with_a_non_finite_number_is_dropped_in_one_line(tab, capfd, bad):
    srv, first = tab
    c = WireClient(srv.port, decode=True)  # (a connection's malformed messages are said once every few seconds)
    wait_until(lambda: len(srv.tabs) == 2, what="a second tab")
    camera = _messages.ViewerCameraMessage(
        wxyz=(1.0, 0.0, 0.0, 0.0), position=(0.0, bad, 40.0), fov=0.6, near=0.01, far=1000.0,
        image_height=800, image_width=1280, look_at=(0.0, 0.0, bad), up_direction=(0.0, 1.0, 0.0))
    c.send(camera)
    c.send(_messages.ViewerCameraMessage(
        wxyz=(1.0, 0.0, 0.0, 0.0), position=(0.0, 0.0, 40.0), fov=bad, near=0.01, far=1000.0,
        image_height=0, image_width=1280, look_at=(0.0, 0.0, 0.0), up_direction=(0.0, 1.0, 0.0)))
    alive(srv, first)
    assert not c.closed.is_set() and len(srv.tabs) == 2
    c.close()
    wait_until(lambda: len(srv.tabs) == 1, what="the second tab to close")
    err = capfd.readouterr().err
    assert "Traceback" not in err and "Task exception" not in err and "handler failed" not in err, err[-3000:]
    assert "a camera report with a number that is not finite" in err, err[-3000:]


def test_the_budget_split_checks_its_own_values_on_a_hand_tab():
    """The fleet's budget split (ĉ and c3/(c1+c2)) refuses a ratio of −1 (it divided by 1 + ratio)
    and any non-finite or negative value by name, even where no input guard stands (a hand tab)."""
    from shoal.app.kinds.fleet import _budget

    from app_helpers import hand_tab

    srv = start_server("course-rpso", port=0)
    try:
        with hand_tab(srv) as t:
            before = t.session.scenario.controller
            for total, ratio, name in ((None, -1.0, "c3 / (c1 + c2)"), (None, math.nan, "c3 / (c1 + c2)"),
                                       (math.inf, None, "ĉ"), (-2.0, None, "ĉ"), (1e308, None, "ĉ")):
                n = len(t.messages)
                _budget(t.panels, total=total, ratio=ratio)
                assert len(t.messages) > n, (total, ratio)
                title, body, *_ = t.messages[-1]
                assert title.startswith("Refused: ") and name in body, (total, ratio, title, body)
            assert t.session.scenario.controller == before
    finally:
        srv.stop()
