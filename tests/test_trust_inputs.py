"""Bad control values from a hostile client get a message, never a traceback.

A page only sends values its controls can hold; a client speaking viser's websocket protocol
(``viser_wire.WireClient``) sends anything: text, null or a list to a slider, NaN or 1.5 to a
whole-number control, a seed of 2**70, a dropdown value that is not an option, an update of a
control's options. Each is refused with a red message naming the control, the control shows
the value in force again, the running scene is untouched, and the server prints nothing.
"""

from __future__ import annotations

import math

import pytest

from shoal.app.input_guard import MAX_TEXT, problem

from browser.browser_helpers import wait_until  # noqa: E402  (tests/ is on sys.path)
from viser_wire import WireClient

# (control label, hostile value, words of the refusal)
HOSTILE = [
    ("speed [steps/s]", "fast", "expected a number"),
    ("speed [steps/s]", None, "expected a number"),
    ("speed [steps/s]", [1, 2], "expected a number"),
    ("speed [steps/s]", math.inf, "finite"),
    ("speed [steps/s]", True, "expected a number"),
    ("omega ω", math.nan, "finite"),
    ("robots", math.nan, "whole number"),
    ("robots", 7.5, "whole number"),
    ("robots", "20", "whole number"),
    ("seed", math.nan, "whole number"),
    ("seed", 1.5, "whole number"),
    ("seed", None, "whole number"),
    ("seed", {"a": 1}, "whole number"),
    ("seed", float(2**70), "seed: more than its largest value"),  # the box's range (the model's, sim.seed)
    ("seed", 2**64 - 1, "seed: more than its largest value"),  # the largest integer on the wire
    ("seed", -1, "seed: less than its least value 0"),
    ("seed", 1e308, "seed: more than its largest value"),  # (int(1e308) has 309 digits: msgpack cannot send it)
    ("speed [steps/s]", 1e308, "more than its largest value"),
    ("speed [steps/s]", -1e308, "less than its least value"),
    ("omega ω", 5.0, "more than its largest value"),
    ("preset", "/etc/passwd", "not one of the choices"),
    ("preset", "../../../default", "not one of the choices"),
    ("preset", "x" * 100_000, "not one of the choices"),
    ("preset", 3, "expected text"),
    ("law", "warp-drive", "not one of the choices"),
    ("mode", None, "expected text"),
    ("playback", "Explode", "not one of the choices"),
    ("at the end", "stop at step 1", "not one of the choices"),
    ("at the end", "../loop", "not one of the choices"),
    ("at the end", ["loop"], "expected text"),
    ("view", "Zoom to Mars", "not one of the choices"),
    ("compare with swarm B", "yes", "true or false"),
    ("Export CSV", 1, "true or false"),
    ("light drawing", "yes", "true or false"),  # the Display boxes (hidden until the view row shows them)
    ("projector mode", None, "true or false"),  # (the header's box, once "large text")
    ("3-D view", [True], "true or false"),
]


@pytest.fixture(scope="module")
def client(server):
    c = WireClient(server.port, decode=True)
    wait_until(lambda: c.uuid_of("Export CSV") and len(server.tabs) == 1, what="the tab's panels")
    yield c
    c.close()


def _refusal(client: WireClient, before: int) -> tuple[str, str, str]:
    wait_until(lambda: len(client.notifications()) > before, what="a notification")
    return client.notifications()[-1]


@pytest.mark.parametrize("label, value, words", HOSTILE, ids=[f"{h[0]}={str(h[1])[:12]}" for h in HOSTILE])
def test_a_bad_value_is_refused_by_name_and_the_control_shows_the_value_in_force(server, client, capfd, label,
                                                                                  value, words):
    session = next(iter(server.sessions.values()))
    scenario, sim = session.scenario, session.sim
    display = dict(vars(server.tabs[max(server.tabs)].display))  # how the arena is drawn (the Display boxes)
    uuid = client.wait_uuid(label)
    shown = client.value_of(uuid)
    before = len(client.notifications())
    client.set_value(label, value)
    title, body, color = _refusal(client, before)
    assert color == "red" and title.startswith("Refused: ") and words in body, (title, body)
    assert len(title) < 200 and len(body) < 400 and "Traceback" not in body
    wait_until(lambda: client.value_of(uuid) == shown, what=f"{label} to show {shown!r} again")
    assert session.scenario == scenario and session.sim is sim
    assert vars(server.tabs[max(server.tabs)].display) == display
    assert next(iter(server.sessions.values())) is session
    err = capfd.readouterr().err
    assert "Task exception" not in err and "Traceback" not in err, err[-2000:]


def test_an_update_of_anything_but_the_value_is_refused(server, client):
    from viser import _messages

    uuid = client.uuid_of("preset")
    options = server.tabs[max(server.tabs)].panels.preset.options
    before = len(client.notifications())
    client.send(_messages.GuiUpdateMessage(uuid, {"options": ["/etc/passwd"], "value": "/etc/passwd"}))
    title, body, color = _refusal(client, before)
    assert color == "red" and "only a control's value can be set" in body
    assert server.tabs[max(server.tabs)].panels.preset.options == options


def test_good_values_still_pass(server, client):
    session = next(iter(server.sessions.values()))
    client.set_value("robots", 12.0)  # a whole number sent as a float, as JavaScript may
    wait_until(lambda: session.sim.robots == 12, what="12 robots")
    client.set_value("seed", 5)
    wait_until(lambda: session.scenario.sim.seed == 5, what="seed 5")
    client.set_value("law", "adapted-tanh")
    wait_until(lambda: session.scenario.controller.law == "adapted-tanh", what="the tanh law")


@pytest.mark.parametrize("current, value, ok", [
    (1, 2, True), (1, 2.0, True), (1, 2.5, False), (1, True, False), (1, math.nan, False), (1, "2", False),
    (1.0, 2, True), (1.0, -1e308, False), (1.0, -1e18, True), (1.0, math.inf, False), (1.0, None, False),
    (True, False, True), (True, 1, False),
    ("a", "b", True), ("a", "x" * (MAX_TEXT + 1), False), ("a", b"a", False),
    ((1.0, 2.0), [3, 4], True), ((1.0, 2.0), [3], False), ((1.0, 2.0), [3, "4"], False),
    (None, 1, False),
])
def test_the_check_by_kind_of_control(current, value, ok):
    assert (problem(current, value) is None) is ok


def test_a_dropdown_takes_only_its_options():
    assert problem("a", "b", options=("a", "b")) is None
    assert problem("a", "c", options=("a", "b")) == "not one of the choices"
