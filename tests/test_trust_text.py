"""Hostile text over the raw websocket: a preset, a replay and typed values whose text is HTML
reach the page's markdown escaped, never as markup (issue 20, case 1).

A client that speaks viser's protocol (``viser_wire.WireClient``) uploads a preset whose
``name`` is an ``<iframe srcdoc=<script>>``, a replay whose ``meta.name`` and ``meta.shoal``
are HTML, sets swarm B's overrides and an experiment's values to HTML, and reads every
markdown content the server sends: none holds a tag of the hostile text, and the text is
there, escaped (it shows literally).
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import shoal
from shoal.app import replay
from shoal.app.kinds.registry import session_for
from shoal.presets import io as presets_io

from app_helpers import wire_tab
from browser.browser_helpers import wait_until
from viser_wire import WireClient

IFRAME = '<iframe srcdoc="<script>parent.__pwn=1</script>"></iframe>'
IMG = "<img src=x onerror=\"parent.__pwn=2\">"
TAGS = ("<iframe", "<script", "<img", "onerror=")


def hostile_preset(name: str = IFRAME) -> bytes:
    sc = presets_io.load("default")
    return presets_io.to_toml(sc.model_copy(update={"name": name})).encode()


def hostile_replay(name: str = IFRAME, shoal: str = IMG) -> bytes:
    """A replay of the default scene whose metadata names are HTML."""
    session = session_for(presets_io.load("default"))
    session.step(5)
    rec = replay.from_bytes(session.export_replay())
    preset = {**rec.meta["preset"], "name": name[:80]}  # (a preset's name has at most 80 characters)
    return replay.to_bytes(dataclasses.replace(rec, meta={**rec.meta, "name": name, "shoal": shoal,
                                                          "preset": preset}))


def _no_markup(c: WireClient) -> list[str]:
    texts = c.markdown()
    bad = [t for t in texts if any(tag in t.lower() for tag in TAGS)]
    assert not bad, bad[:3]
    return texts


def test_a_preset_named_with_html_shows_its_name_escaped(server):
    c, key = wire_tab(server, "Upload preset", "Load replay")
    tab = server.tabs[key]
    try:
        c.upload("Upload preset", "evil.toml", hostile_preset())
        wait_until(lambda: tab.session.scenario.name == IFRAME, what="the hostile preset loaded")
        wait_until(lambda: any("&lt;iframe srcdoc" in t for t in c.markdown()), timeout=20,
                   what="the status line with the escaped name")
        _no_markup(c)
    finally:
        c.close()


def test_a_preset_name_that_is_a_markdown_image_reads_no_file(server):
    """Viser turns ``![x](path)`` in markdown into the picture at ``path`` read on the server: a
    preset named so would make the server read any image file it may read and send it to the page."""
    picture = Path(shoal.__file__).parents[2] / "benchmarks" / "memory.png"
    assert picture.is_file()
    c, _ = wire_tab(server, "Upload preset", "Load replay")
    try:
        c.upload("Upload preset", "img.toml", hostile_preset(f"![x]({picture})"))
        wait_until(lambda: any("memory" in t for t in c.markdown()), timeout=20, what="the status line")
        assert not any("data:image" in t for t in c.markdown())
    finally:
        c.close()


def test_a_replay_with_html_in_its_metadata_shows_it_escaped(server):
    c, key = wire_tab(server, "Upload preset", "Load replay")
    tab = server.tabs[key]
    try:
        c.upload("Load replay", "evil.npz", hostile_replay())
        wait_until(lambda: tab.session.replaying is not None, what="the replay loaded")
        wait_until(lambda: any("Replay of &lt;iframe" in t and "&lt;img src" in t for t in c.markdown()),
                   timeout=20, what="the replay badge with the escaped names")
        _no_markup(c)
    finally:
        c.close()


def test_html_typed_into_swarm_b_and_an_experiment_shows_escaped(server):
    c, key = wire_tab(server, "Upload preset", "Load replay")
    tab = server.tabs[key]
    try:
        wait_until(lambda: c.uuid_of("B overrides") and c.uuid_of("values 1"), what="the compare and sweep inputs")
        c.set_value("B overrides", f"controller.omega = 0.6\nname = {IMG}")
        c.set_value("Apply to B", True)
        wait_until(lambda: tab.session.twin is not None, what="swarm B on")
        wait_until(lambda: any("B = A with" in t and "&lt;img src" in t for t in c.markdown()), timeout=20,
                   what="B's overrides, escaped")
        c.set_value("values 1", f"6, {IMG}")
        c.set_value("Run experiment", True)
        wait_until(lambda: any("Refused" in t and "&lt;img" in t for t in c.markdown()), timeout=30,
                   what="the experiment's refusal, escaped")
        _no_markup(c)
    finally:
        c.close()


# ------------------------------------------------------------------ lone surrogates (issue 30, case 3)
LONE = "\ud800"  # valid JSON ("\ud800"), not encodable as UTF-8: msgpack could not send a text holding it


def test_a_replay_whose_meta_holds_a_lone_surrogate_loads_and_keeps_the_tab(server, capfd):
    """It dropped the loading tab (close code 1011) and its run was lost."""
    c, key = wire_tab(server, "Upload preset", "Load replay")
    tab = server.tabs[key]
    try:
        data = hostile_replay(name=f"run {LONE} one", shoal=f"{LONE}x\udfff")
        c.upload("Load replay", "lone.npz", data)
        wait_until(lambda: tab.session.replaying is not None, what="the replay loaded")
        wait_until(lambda: any("Replay of run \ufffd one" in t for t in c.markdown()), timeout=20,
                   what="the replay badge, the surrogate shown as U+FFFD")
        assert not c.closed.is_set() and key in server.tabs
        c.set_value("seed", 11)  # the tab still answers
        wait_until(lambda: tab.session.scenario.sim.seed == 11, what="the tab still answering")
    finally:
        c.close()
    err = capfd.readouterr().err
    assert "Traceback" not in err and "surrogates not allowed" not in err, err[-2000:]


def test_a_json_preset_whose_name_holds_a_lone_surrogate_loads_and_keeps_the_tab(server, capfd):
    import json

    c, key = wire_tab(server, "Upload preset", "Load replay")
    tab = server.tabs[key]
    try:
        raw = presets_io.load("default").model_dump(mode="json")
        text = json.dumps({**raw, "name": f"lone {LONE} name"})  # ASCII: "\ud800" as an escape
        c.upload("Upload preset", "lone.json", text.encode())
        wait_until(lambda: tab.session.scenario.name.startswith("lone"), what="the preset loaded")
        assert tab.session.scenario.name == "lone \ufffd name"
        wait_until(lambda: any("lone \ufffd name" in t for t in c.markdown()), timeout=20, what="the status line")
        assert not c.closed.is_set() and key in server.tabs
    finally:
        c.close()
    err = capfd.readouterr().err
    assert "Traceback" not in err and "surrogates not allowed" not in err, err[-2000:]


def test_every_escaped_text_is_encodable():
    import msgspec

    from shoal.app.markdown import encodable, escape

    for text in (LONE, "\udfff", f"a{LONE}b\udc00", "\ud83d\ude00", "ok"):
        out = escape(text)
        out.encode("utf-8")
        msgspec.msgpack.encode({"content": out})
    assert escape("\ud83d\ude00") == "😀"  # a pair written as two escapes is the character it stands for
    assert encodable(f"a{LONE}b") == "a\ufffdb" and encodable({"k" + LONE: [LONE, 1]}) == {"k\ufffd": ["\ufffd", 1]}
