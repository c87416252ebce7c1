"""Uploads the app must survive: too big, not text, not TOML, wrong types, bombs, extremes.

A refused upload shows a red notification that says what is wrong (the field, or the syntax)
and leaves the running scene exactly as it was. Complements the upload cases of
``tests/test_app_session.py`` (bad fields, syntax errors, the size limit, unknown fields).
The tab's panels live on a real viser server's GUI, driven from Python.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from shoal.app.session.upload import MAX_UPLOAD_BYTES
from shoal.presets import io as presets_io

from app_helpers import hand_tab


@pytest.fixture
def tab(server):
    """A hand-ticked tab (the shared ``server`` of conftest.py) four steps into its run."""
    with hand_tab(server) as t:
        t.session.step(4)
        yield t


def refused_untouched(tab, name: str, content: bytes) -> str:
    """Upload; assert it was refused with a red notification and nothing changed. Returns the body."""
    s = tab.session
    sim, scenario, k, x = s.sim, s.scenario, s.sim.state.k, s.sim.state.x.copy()
    assert not tab.panels.upload_preset(name, content)
    title, body, color = tab.messages[-1]
    assert color == "red" and title.startswith("Refused") and body.strip()
    assert len(body) < 2000 and "Traceback" not in body
    assert tab.session is s and s.sim is sim and s.scenario is scenario and s.sim.state.k == k
    np.testing.assert_array_equal(s.sim.state.x, x)
    return body


DEFAULT_TOML = presets_io.to_toml(presets_io.load("default"))


BAD = [
    ("garbage.bin", bytes(range(256)) * 64, "not UTF-8"),
    ("garbage.toml", b"\x89PNG\r\n\x1a\n" + bytes(100), "not UTF-8"),
    ("utf16.toml", DEFAULT_TOML.encode("utf-16"), "not UTF-8"),
    ("empty.json", b"", "JSON syntax"),
    ("list.json", b"[1, 2, 3]", "a preset must be a table"),
    ("bomb.json", b"[" * 100_000 + b"]" * 100_000, "JSON syntax: nested"),
    ("bomb.toml", b"a = " + b"[" * 60_000 + b"]" * 60_000, "TOML syntax: nested"),
    ("deep.json", json.dumps({"sim": {"a": {"b": {"c": {"d": {"e": [[[[[[[[[[[[1]]]]]]]]]]]]}}}}}}).encode(),
     "nested deeper"),
    ("types.toml", b"[sim]\nrobots = \"many\"\n[controller]\nomega = [1, 2]\ndt = true\n", "sim.robots"),
    ("types2.toml", b"sim = 3\n", "sim: Input should be a valid dictionary"),
    ("nan.toml", b"[init]\ncenter = [nan, 0.0]\n", "init.center.0"),
    ("inf.json", b'{"objective": {"source": [1e999, 0]}}', "objective.source.0"),
    ("bigint.json", b'{"sim": {"seed": ' + b"9" * 5000 + b"}}", "JSON syntax"),
    ("date.toml", b"name = 1979-05-27\n", "name: Input should be a valid string"),
    ("longvalue.toml", b"[controller]\nomega = [" + b"1," * 40_000 + b"1]\n", "controller.omega"),
    ("robots.toml", b"[sim]\nrobots = 100000\n", "sim.robots = 100000: the browser app runs at most"),
    ("worldlaw.toml", b"[world]\nkind = \"empty\"\n", "controller.law"),
    ("replay.npz", b"PK\x03\x04" + bytes(200), "TOML syntax"),
    ("exact.toml", b"#" * (MAX_UPLOAD_BYTES + 1), "KiB limit"),
    # tomllib is quadratic in a key's dotted parts: these are refused before it parses (issue 20, case 2)
    ("dotted.toml", b"a" + b".a" * 20_000 + b" = 1\n", "TOML syntax: a key of more than 16 dotted parts (line 1)"),
    ("header.toml", b"[sim]\nrobots = 5\n[" + b"a." * 20_000 + b"a]\n", "more than 16 dotted parts (line 3)"),
    ("tables.toml", b"[[" + b"a." * 20_000 + b"a]]\n", "more than 16 dotted parts"),
    ("inline.toml", b"x = {" + b"a." * 20_000 + b"a = 1}\n", "more than 16 dotted parts"),
    ("quoted.toml", b'"a".' * 20_000 + b'"a" = 1\n', "more than 16 dotted parts"),
    ("longkey.toml", b"a" * 90_000 + b" = 1\n", "a key of 90,000 characters"),
    ("deepinline.toml", b"x = " + b"{a = " * 20_000 + b"1" + b"}" * 20_000, "TOML syntax: nested deeper than 16"),
    ("keys.toml", b"".join(b"k%d = 1\n" % i for i in range(9000)), "more than 2,000 keys"),
]


@pytest.mark.parametrize("name, content, expect", BAD, ids=[b[0] for b in BAD])
def test_bad_uploads_are_refused_with_a_reason_and_the_scene_untouched(tab, name, content, expect):
    body = refused_untouched(tab, name, content)
    assert expect in body, body


def test_a_long_bad_value_is_shown_short(tab):
    body = refused_untouched(tab, "long.toml", b"[controller]\nomega = \"" + b"x" * 100_000 + b"\"\n")
    assert "controller.omega" in body and len(body) < 300


def test_an_upload_at_the_size_limit_is_read(tab):
    text = DEFAULT_TOML.encode()
    content = text + b"\n" + b"#" * (MAX_UPLOAD_BYTES - len(text) - 2) + b"\n"
    assert len(content) == MAX_UPLOAD_BYTES
    assert tab.panels.upload_preset("big-but-fine.toml", content)
    assert tab.messages[-1][2] == "green" and tab.session.sim.state.k == 0


@settings(max_examples=60, suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])
@given(name=st.sampled_from(["x.toml", "x.json", "x", "../../x.toml", "/etc/x.json", "a\x00b.toml"]),
       content=st.one_of(st.binary(max_size=400), st.text(max_size=300).map(str.encode),
                         st.builds(lambda a, b: (a + b).encode(), st.sampled_from([DEFAULT_TOML[:200], DEFAULT_TOML]),
                                   st.text(max_size=40))))
def test_random_uploads_never_break_the_tab(tab, name, content):
    s = tab.session
    sim, k = s.sim, s.sim.state.k
    if tab.panels.upload_preset(name, content):
        assert tab.messages[-1][2] == "green"
        tab.tick(1.0)
    else:
        assert tab.messages[-1][2] == "red" and tab.session.sim is sim and sim.state.k == k


def test_a_replay_whose_positions_are_not_finite_is_refused(tab):
    import dataclasses

    from shoal.app import replay

    rec = replay.from_bytes(tab.session.export_replay())
    x = rec.x.copy()
    x[len(x) // 2, 0] = np.nan
    s = tab.session
    sim, scenario = s.sim, s.scenario
    assert not tab.panels.replay_gui.load("nan.npz", replay.to_bytes(dataclasses.replace(rec, x=x)))
    title, body, color = tab.messages[-1]
    assert color == "red" and title == "Refused: replay nan.npz" and "x: positions must be finite" in body, body
    assert tab.session is s and s.sim is sim and s.scenario is scenario and s.replaying is None
