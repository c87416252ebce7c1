"""Exported pages (``shoal.app.share``): one HTML file that plays a run with viser's own player.

The pages are read back as viser's player reads them (``share_pages``): the robots drawn in
every frame must be the run's robots at the kept steps, through one fixed map from metres to
the view (a uniform scale and a shift), for every kind of scene and for swarm B.
"""

from __future__ import annotations

import html as html_lib
import os
import re
import subprocess
import sys
import urllib.parse

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from share_pages import data_block, recorded

import shoal
from shoal.app import replay
from shoal.app.cli import main
from shoal.app.share import MAX_FRAMES, preset_html, recording_html, session_html, write_html
from shoal.app.share.draw import new_session
from shoal.app.share.frames import MAX_ROBOT_FRAMES, frame_budget, plan, run_plan
from shoal.app.share.page import SOFTWARE_JS
from shoal.presets import io as presets_io
from shoal.presets.build import build_simulation
from shoal.presets.io import PresetError
from shoal.testing import example_presets, variant_presets

CLIENT_BYTES = 900_000  # viser's client (about 0.82 MB) and the page around it
KINDS = [(p, label) for p, label in variant_presets().items() if p in example_presets().values()]  # every kind


def node(rec, suffix: str) -> str:
    """The one scene node whose name ends in ``/suffix`` (views name their roots differently)."""
    names = {m.get("name") for _, m in rec.messages if isinstance(m.get("name"), str)}
    found = [n for n in names if n.endswith("/" + suffix)]
    assert len(found) == 1, (suffix, sorted(n for n in names if n))
    return found[0]


def fit_view_map(world: list[np.ndarray], drawn: list[np.ndarray]) -> tuple[float, np.ndarray, float]:
    """Scale s and shift c with drawn ≈ s·world + c over every frame; returns (s, c, worst error)."""
    w = np.concatenate([x[:, :2] for x in world])
    v = np.concatenate([p.reshape(-1, 3)[:, :2] for p in drawn])
    a = np.zeros((2 * len(w), 3))
    a[0::2, 0], a[0::2, 1] = w[:, 0], 1.0
    a[1::2, 0], a[1::2, 2] = w[:, 1], 1.0
    sol, *_ = np.linalg.lstsq(a, v.reshape(-1), rcond=None)
    err = float(np.abs(a @ sol - v.reshape(-1)).max())
    return float(sol[0]), sol[1:], err


def run_positions(scenario, steps: int, overrides=None) -> tuple[dict[int, np.ndarray], dict[int, np.ndarray]]:
    """Robots (and swarm B's) at every step of a fresh session of ``scenario``."""
    s = new_session(scenario)
    if overrides:
        s.enable_compare(overrides)
    s.step(steps)
    a = {f.k: f.x.copy() for f in s.frames}
    b = {f.k: f.x.copy() for f in s.twin.frames} if s.twin is not None else {}
    return a, b


def assert_robots_as_run(page: str, positions: dict[int, np.ndarray], suffix: str = "robots") -> np.ndarray:
    """Every frame of the page draws the robots at the kept step; returns the kept steps."""
    info = data_block(page)["run"]
    rec = recorded(page)
    drawn = rec.frames(node(rec, suffix))
    kept = np.array(plan(sorted(positions), info["max_frames"]).steps)
    assert len(drawn) == len(kept) == info["frames"]
    world = [positions[int(k)] for k in kept]
    s, _, err = fit_view_map(world, drawn)
    assert s > 0 and err < 1e-4 * max(1.0, s * np.abs(np.concatenate(world)).max()), (s, err)
    labels = [str(v) for _, v in rec.updates("/shoal_step", "text") if v]
    assert [int(re.match(r"step (\d+)", t).group(1)) for t in labels] == list(kept)
    return kept


# ---------------------------------------------------------------------------- frames kept
@given(first=st.integers(0, 10_000), span=st.integers(0, 20_000), max_frames=st.integers(2, 700))
def test_a_plan_keeps_first_and_last_and_at_most_the_budget(first, span, max_frames):
    steps = np.arange(first, first + span + 1)
    p = plan(steps, max_frames)
    assert p.steps[0] == first and p.steps[-1] == first + span
    assert len(p.steps) <= max_frames and list(p.steps) == sorted(set(p.steps))
    assert all((k - first) % p.stride == 0 for k in p.steps[:-1])
    if span + 1 <= max_frames:
        assert p.steps == tuple(steps)
    assert run_plan(span, max_frames).steps == plan(np.arange(span + 1), max_frames).steps


def test_a_plan_of_a_gappy_history_still_keeps_the_budget():
    steps = np.concatenate([np.arange(0, 50), np.arange(1000, 3000, 3)])
    p = plan(steps, 40)
    assert len(p.steps) <= 40 and p.steps[0] == 0 and p.steps[-1] == steps[-1]


def test_the_frame_budget_shrinks_for_large_swarms():
    assert frame_budget(20) == MAX_FRAMES
    assert frame_budget(1000) == MAX_ROBOT_FRAMES // 1000
    assert frame_budget(10**6) == 50  # still a film
    assert frame_budget(10, max_frames=30) == 30


# ---------------------------------------------------------------------------- every kind of scene
@pytest.mark.parametrize("name, kind", KINDS)
def test_a_seeded_run_of_every_scene_kind_plays_the_robots_as_run(name, kind):
    scenario = presets_io.load(name, ["sim.steps=12", "sim.seed=5"])
    page = preset_html(scenario)
    block = data_block(page)
    run = block["run"]
    assert (run["name"], run["seed"], run["kind"], run["shoal"]) == (name, 5, kind, shoal.__version__)
    assert (run["first"], run["last"], run["frames"], run["stride"]) == (0, 12, 13, 1)
    assert presets_io.validate(block["preset"]) == scenario
    positions, _ = run_positions(scenario, 12)
    assert_robots_as_run(page, positions)
    rec = recorded(page)
    assert rec.duration == pytest.approx(13 / scenario.view.steps_per_second)
    # the page around viser's player: title, the panel, the preset to download
    assert f"<title>{name}, seed 5 · Shoal</title>" in page
    panel = re.search(r'<div id="shoal-run">.*?</div>', page, re.S).group(0)
    assert f"Shoal · {name}, seed 5" in panel and f"shoal {shoal.__version__}" in panel and kind in panel
    href = re.search(r'<a download="[^"]+\.toml" href="([^"]+)"', panel).group(1)
    toml = urllib.parse.unquote(html_lib.unescape(href).split(",", 1)[1])
    assert presets_io.validate(presets_io.parse_text(toml, "toml")) == scenario
    assert len(page) < CLIENT_BYTES + 400_000


def test_a_seeded_run_draws_what_the_app_draws_live():
    page = preset_html(presets_io.load("sonar-gt-pso", ["sim.steps=6"]))
    rec = recorded(page)
    for layer in ("rays_true", "rays_mirror", "pbests", "gbest", "trails", "source", "scale"):
        node(rec, layer)  # drawn by the acoustic view, as in the app
    legend = page[page.index('<p class="legend">'):]
    legend = legend[:legend.index("</p>")]
    for label in ("robot", "source", "GT-PSO triangle", "personal best"):
        assert f"&nbsp;{label}" in legend  # the page's panel names the glyphs it draws
    assert "swarm B" not in legend and "believed position" not in legend


def _about(page: str) -> str:
    about = page[page.index("<summary>About this page</summary>"):]
    return html_lib.unescape(re.sub(r"<[^>]+>", " ", about[:about.index("<details><summary>Preset")]))


@pytest.mark.parametrize("speed, fps, pace", [(20.0, 20, "the app's pace"), (100.0, 30, "0.3× the app's pace")])
def test_the_about_text_says_what_the_player_plays(speed, fps, pace):
    """Frames, frames a second, the clock's end: the numbers of the recording viser's player plays."""
    page = preset_html(presets_io.load("default", ["sim.steps=60", f"view.steps_per_second={speed}"]))
    run, rec = data_block(page)["run"], recorded(page)
    times = sorted({t for t, m in rec.messages if m.get("name", "").endswith("/robots")})
    assert len(times) == run["frames"] == 61 and rec.duration == pytest.approx(61 / fps)
    assert np.diff(times) == pytest.approx(1 / fps) and run["seconds"] == pytest.approx(rec.duration)
    about = " ".join(_about(page).split())
    assert (f"61 frames of a seeded run of 20 robots (every step), steps 0–60. At 1× the page plays {fps} frames "
            f"a second, {pace}: its clock, the number beside ▶, runs from 0 to {61 / fps:.4g} s") in about
    assert "robot positions, so that it stays a few MB" in about  # no budget of its own to mention
    long = preset_html(presets_io.load("default", ["sim.steps=1500", "sim.robots=3"]))
    assert "(every 3rd step and the last), steps 0–1500. At 1× the page plays 20 frames a second, 3× the app's pace" \
        in " ".join(_about(long).split())


def test_a_sonar_page_names_the_source_without_offering_a_drag():
    rec = recorded(preset_html(presets_io.load("sonar-xb-pso", ["sim.steps=3"])))
    texts = [v for _, v in rec.updates(node(rec, "source_label"), "text")]
    assert texts and set(texts) == {"source"}


def test_swarm_b_is_drawn_where_it_ran():
    scenario = presets_io.load("default", ["sim.steps=20", "sim.robots=6"])
    overrides = {"controller.law": "standard", "controller.mode": "raw"}
    page = preset_html(scenario, overrides=overrides)
    a, b = run_positions(scenario, 20, overrides)
    assert max(np.abs(a[20] - b[20]).max(), 0) > 0.1  # B really differs
    assert_robots_as_run(page, a)
    assert_robots_as_run(page, b, "twin")
    block = data_block(page)
    assert block["twin"] == {"overrides": overrides} and block["run"]["robots"] == 12
    assert "swarm B" in page and "controller.law=standard" in page
    assert "&nbsp;swarm B" in page[page.index('<p class="legend">'):]  # B in the legend, with Compare


# ---------------------------------------------------------------------------- recorded history
def test_a_session_history_with_swarm_b_is_shared_as_recorded():
    s = new_session(presets_io.load("default", ["sim.robots=5"]))
    s.enable_compare({"sim.robots": 3})
    s.step(25)
    s.apply({"controller.beta": 0.3})  # a live edit: the page says a fresh run differs
    s.step(5)
    page = session_html(s).decode("utf-8")
    assert_robots_as_run(page, {f.k: f.x for f in s.frames})
    assert_robots_as_run(page, {f.k: f.x for f in s.twin.frames}, "twin")
    run = data_block(page)["run"]
    assert run["origin"] == "recorded history" and run["live_edits"] == 1 and run["last"] == 30
    assert "Changed 1 time(s) while it ran" in page


def test_a_loaded_replay_keeps_the_version_that_ran_it():
    src = new_session(presets_io.load("course-dvc", ["sim.steps=40"]))
    src.step(40)
    rec = src.recording()
    rec = replay.Recording(meta={**rec.meta, "shoal": "0.0.9"}, k=rec.k, t=rec.t, n=rec.n, x=rec.x,
                           heading=rec.heading, status=rec.status, metrics=rec.metrics)
    shown = new_session(presets_io.validate(rec.meta["preset"]))
    shown.enter_replay(rec, (None, "not checked"))
    page = session_html(shown).decode("utf-8")
    assert data_block(page)["run"]["shoal"] == "0.0.9"
    assert_robots_as_run(page, {int(k): rec.robots(i)[0] for i, k in enumerate(rec.k)})


def view_map(page: str, positions: dict[int, np.ndarray]) -> tuple[float, np.ndarray]:
    """The page's map from metres to the view (scale, shift), fitted on the robots it draws."""
    kept = plan(sorted(positions), data_block(page)["run"]["max_frames"]).steps
    rec = recorded(page)
    s, c, _ = fit_view_map([positions[k] for k in kept], rec.frames(node(rec, "robots")))
    return s, c


def test_a_loaded_replay_with_swarm_b_is_shared_with_b():
    src = new_session(presets_io.load("default", ["sim.robots=5", "sim.steps=30"]))
    src.enable_compare({"controller.law": "standard", "controller.mode": "raw"})
    src.step(30)
    rec = replay.from_bytes(src.export_replay())
    shown = new_session(presets_io.validate(rec.meta["preset"]))
    shown.enter_replay(rec, (None, "not checked"))
    page = session_html(shown).decode("utf-8")
    assert_robots_as_run(page, {f.k: f.x for f in src.frames})
    assert_robots_as_run(page, {f.k: f.x for f in src.twin.frames}, "twin")
    assert data_block(page)["twin"] == {"overrides": {"controller.law": "standard", "controller.mode": "raw"}}
    assert "&nbsp;swarm B" in page[page.index('<p class="legend">'):]


def test_a_shared_run_draws_the_obstacles_as_they_were_at_each_step():
    from shoal.app.kinds import fleet

    src = new_session(presets_io.load("course-dvc", ["sim.steps=20"]))
    d = fleet.driver(src)
    src.step(4)
    n0 = len(src.sim.world.circles)
    d.add_obstacle(src.sim.world.bounds[2] - 4.0, 1.5, 1.25)
    src.step(4)
    d.remove_obstacle_near(*src.sim.world.circles[0, :2], tol=0.0)
    d.remove_obstacle_near(*src.sim.world.circles[0, :2], tol=0.0)
    src.step(4)
    page = session_html(src).decode("utf-8")
    rec = recorded(page)
    steps = {t: int(re.match(r"step (\d+)", str(v)).group(1)) for t, v in rec.updates("/shoal_step", "text") if v}
    edges = [(t, np.asarray(v).reshape(-1, fleet.RIM_SEGMENTS, 2, 3))
             for t, v in rec.updates(node(rec, "obstacle_edges"), "points")]
    seen = [(steps.get(t, 0), len(v)) for t, v in edges]  # (the first is drawn before the first step label)
    assert [n for _, n in seen] == [n0, n0 + 1, n0 - 1] and [k for k, _ in seen[1:]] == [5, 9]
    s, c = view_map(page, {f.k: f.x for f in src.frames})
    centres = edges[-1][1][..., :2].mean(axis=(1, 2))
    np.testing.assert_allclose((centres - c) / s, src.sim.world.circles[:, :2], atol=1e-3)


def test_a_shared_run_draws_a_moving_source_where_it_was():
    src = new_session(presets_io.load("escort-moving", ["sim.steps=15"]))
    src.step(15)
    path = {f.k: f.scene["source"][0] for f in src.frames}
    page = session_html(src).decode("utf-8")
    rec = recorded(page)
    s, c = view_map(page, {f.k: f.x for f in src.frames})
    sources = rec.frames(node(rec, "source"), "batched_positions")
    drawn = np.array([np.asarray(v).reshape(-1, 3)[0, :2] for v in sources])
    assert len(drawn) == 16
    np.testing.assert_allclose((drawn - c) / s, np.array([path[k] for k in range(16)]), atol=1e-3)


def test_a_long_history_is_thinned_to_the_budget_and_stays_small():
    s = new_session(presets_io.load("default", ["sim.steps=3000"]))
    s.step(3000)
    page = session_html(s).decode("utf-8")
    run = data_block(page)["run"]
    assert run["frames"] <= MAX_FRAMES and run["stride"] == 6 and run["last"] == 3000
    assert "every 6th step and the last" in page
    kept = assert_robots_as_run(page, {f.k: f.x for f in s.frames})
    assert kept[0] == 0 and kept[-1] == 3000
    assert len(page) < CLIENT_BYTES + 1_500_000


def test_a_large_swarm_keeps_fewer_frames():
    scenario = presets_io.load("fig3-4a", ["sim.steps=300"])  # 1000 robots
    page = preset_html(scenario)
    run = data_block(page)["run"]
    assert run["max_frames"] == MAX_ROBOT_FRAMES // 1000 and run["frames"] <= run["max_frames"]
    assert len(page) < CLIENT_BYTES + 4_000_000


def test_a_recording_the_app_cannot_show_is_refused():
    s = new_session(presets_io.load("default"))
    s.step(3)
    rec = s.recording()
    bad = replay.Recording(meta={**rec.meta, "preset": {**rec.meta["preset"], "sim": {"robots": -2}}}, k=rec.k,
                           t=rec.t, n=rec.n, x=rec.x, heading=rec.heading, status=rec.status, metrics=rec.metrics)
    with pytest.raises(PresetError, match="preset: sim.robots"):
        recording_html(bad)


# ---------------------------------------------------------------------------- what the page says
def test_a_hostile_preset_name_is_text_in_the_page():
    evil = '</script><script>alert(1)</script><img src=x onerror=alert(2)>'
    scenario = presets_io.validate({**presets_io.load("default", ["sim.steps=3"]).model_dump(mode="json"),
                                    "name": evil})
    page = preset_html(scenario)
    ours = page[page.index('<div id="shoal-run">'):]
    assert "alert" in ours and "<img" not in ours and ours.count("<script") == 2  # the JSON block and ...
    assert ours.endswith(f"<script>{SOFTWARE_JS}</script></body>\n</html>\n")  # ... the fixed toast script
    assert data_block(page)["run"]["name"] == evil
    title = re.search(r"<title>(.*?)</title>", page, re.S).group(1)
    assert "<" not in title and html_lib.unescape(title).startswith(evil)


def test_a_page_is_written_completely_or_not_at_all(tmp_path, monkeypatch):
    target = tmp_path / "run.html"
    target.write_text("old page")

    def refuse(src, dst):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(os, "replace", refuse)
    with pytest.raises(OSError):
        write_html(target, "<html>" + "x" * 100_000)
    monkeypatch.undo()
    assert target.read_text() == "old page" and sorted(p.name for p in tmp_path.iterdir()) == ["run.html"]
    write_html(target, "<html>new</html>")
    assert target.read_text() == "<html>new</html>"


# ---------------------------------------------------------------------------- the Share button
class Writes:
    """Files this process opens for writing while ``active`` (an audit hook; it cannot be removed)."""

    def __init__(self) -> None:
        self.active = False
        self.seen: list[tuple] = []
        sys.addaudithook(self._hook)

    def _hook(self, event: str, args: tuple) -> None:
        if not self.active:
            return
        if event == "open" and len(args) >= 3 and isinstance(args[0], (str, bytes, os.PathLike)):
            mode, flags = args[1], args[2]
            if (isinstance(mode, str) and any(c in mode for c in "wax+")) or (
                    isinstance(flags, int) and flags & (os.O_WRONLY | os.O_RDWR | os.O_CREAT)):
                self.seen.append(args[:2])
        elif event in ("os.rename", "os.replace", "os.remove", "os.mkdir"):
            self.seen.append((event, args[:2]))


WRITES = Writes()


def test_share_sends_the_history_as_a_page_and_writes_no_file(tab, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    evil = "../../" + "x" * 10 + "/page"
    tab.panels.upload_preset("p.toml", presets_io.to_toml(presets_io.validate(
        {**presets_io.load("default", ["sim.robots=4"]).model_dump(mode="json"), "name": evil})).encode())
    s = tab.session
    s.step(15)
    tab.tick(1.0)
    WRITES.seen.clear()
    WRITES.active = True
    try:
        tab.panels.replay_gui.share.value = True  # a click from Python runs the same callback
    finally:
        WRITES.active = False
    assert WRITES.seen == [] and list(tmp_path.iterdir()) == []
    name, content = tab.downloads[-1]
    assert name == presets_io.file_stem(evil) + "-run.html" and "/" not in name
    page = content.decode("utf-8")
    assert data_block(page)["run"]["name"] == evil
    assert_robots_as_run(page, {f.k: f.x for f in s.frames})


# ---------------------------------------------------------------------------- shoal export-replay
def shoal_cli(*args: str, cwd=None) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "shoal", *args], capture_output=True, text=True, cwd=cwd, timeout=300)


def test_export_replay_writes_a_page_the_preset_in_it_reproduces(tmp_path):
    out = tmp_path / "course" / "run.html"  # a missing folder is made, as `shoal run` does
    res = shoal_cli("export-replay", "default", "--seed", "4", "--steps", "30", "--set", "sim.robots=7",
                    "--out", str(out))
    assert res.returncode == 0, res.stderr
    assert res.stdout.startswith(f"wrote {out} (") and "seed 4" in res.stdout
    page = out.read_text(encoding="utf-8")
    block = data_block(page)
    assert block["run"]["seed"] == 4 and block["preset"]["sim"]["robots"] == 7 and block["run"]["last"] == 30
    sim = build_simulation(presets_io.validate(block["preset"]))  # the engine alone, no app
    positions = {0: sim.state.x[0].copy()}
    for k in range(1, 31):
        sim.step()
        positions[k] = sim.state.x[0].copy()
    assert_robots_as_run(page, positions)


@pytest.mark.parametrize("args, words", [
    (["nope"], "bad preset: no preset or file named 'nope'"),
    (["default", "--set", "sim.robots=-1"], "bad preset: sim.robots"),
    (["default", "--set", "sim.robots=5000"], "sim.robots = 5000: the browser app runs at most"),
    (["default", "--set", "controller.mode=dvc"], "bad preset: controller"),
])
def test_export_replay_refuses_a_bad_preset_in_one_line_and_leaves_out_as_it_was(tmp_path, capsys, args, words):
    out = tmp_path / "run.html"
    old = '<script type="application/json" id="shoal-run-data">{}</script> the old page'  # one it wrote
    out.write_text(old)
    assert main(["export-replay", *args, "--steps", "3", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("shoal: error: ") and words in err and err.count("\n") == 1, err
    assert out.read_text() == old and [p.name for p in tmp_path.iterdir()] == ["run.html"]


def test_export_replay_refuses_a_bad_out_before_running(tmp_path, capsys):
    (tmp_path / "a-file").write_text("x")
    (tmp_path / "a-folder").mkdir()
    for out, words in ((tmp_path / "a-folder", "is a folder"), (tmp_path / "a-file" / "run.html", "is not a folder"),
                       (tmp_path / "run.txt", "ending in .html")):
        assert main(["export-replay", "default", "--steps", "3", "--out", str(out)]) == 2
        err = capsys.readouterr().err
        assert err.startswith(f"shoal: error: --out {out}: ") and words in err and err.count("\n") == 1, err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a-file", "a-folder"]


def test_share_on_a_busy_server_is_refused_and_sends_nothing(tab):
    from shoal.app.share import page

    tab.session.step(5)
    held = [page._QUEUE.acquire(blocking=False) for _ in range(2)]  # one export running, one waiting
    try:
        assert all(held)
        tab.panels.replay_gui.share.value = True
    finally:
        for _ in held:
            page._QUEUE.release()
    title, body, color = tab.messages[-1]
    assert color == "red" and title == "Refused: share" and "try again in a moment" in body
    assert not tab.downloads
    tab.panels.replay_gui.share.value = True  # free again
    assert tab.downloads[-1][0] == "default-run.html"


def test_a_tab_that_floods_share_gets_refusals_and_the_other_tabs_go_on():
    """A hostile page is not limited to one click at a time: forty Share clicks sent on the wire
    at once take at most two export slots; the rest are refused at once, so viser's callback
    threads stay free and another tab's Pause still lands."""
    from viser import _messages as m

    from shoal.app.server import start_server

    from browser.browser_helpers import wait_until
    from viser_wire import WireClient

    srv = start_server("default", port=0)
    flood, other = WireClient(srv.port, decode=True), WireClient(srv.port, decode=True)
    try:
        wait_until(lambda: flood.uuid_of("Share") and other.uuid_of("playback") and len(srv.tabs) == 2, what="two tabs")
        wait_until(lambda: all(s.playing for s in srv.sessions.values()), what="both tabs playing")
        share = flood.uuid_of("Share")
        for _ in range(40):
            flood.send(m.GuiUpdateMessage(share, {"value": True}))
        other.send(m.GuiUpdateMessage(other.wait_uuid("playback"), {"value": "Pause"}))
        wait_until(lambda: sum(not s.playing for s in srv.sessions.values()) == 1, timeout=60, what="the other pause")

        def outcomes():
            tab = next(t for t in srv.tabs.values() if t.session.playing)
            refused = sum("try again in a moment" in body for _, body, _ in tab.messages)
            return (refused, len(tab.downloads)) if refused + len(tab.downloads) == 40 else None

        refused, sent = wait_until(outcomes, timeout=120, what="every Share answered")
        assert refused >= 1 and sent >= 1
    finally:
        flood.close()
        other.close()
        srv.stop()


def test_a_shared_page_offers_the_preset_with_the_hand_edits():
    """The Share page's preset is the one Download preset writes: an obstacle added by hand is
    in it, and the page of a run without edits offers the preset as loaded."""
    from shoal.app.kinds import fleet

    src = new_session(presets_io.load("course-dvc", ["sim.steps=10"]))
    src.step(3)
    plain = data_block(session_html(src).decode("utf-8"))
    assert plain["preset"]["world"].get("obstacles") is None
    fleet.driver(src).add_obstacle(src.sim.world.bounds[2] - 4.0, 1.5, 1.25)
    src.step(3)
    page = session_html(src).decode("utf-8")
    edited = data_block(page)["preset"]["world"]["obstacles"]
    assert [src.sim.world.bounds[2] - 4.0, 1.5, 1.25] in edited
    assert html_lib.escape(presets_io.to_toml(src.kept_scenario())) in page  # the TOML shown and downloaded
