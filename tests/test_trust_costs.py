"""Limits that hold on every path (issue 20, cases 3 and 4): one cost function
(``shoal.studies.cost.cost``: steps × robots × runs × kind) checked for a live scene, a
sweep of any field (``sim.steps`` and ``sim.robots`` included), a replay and its Share page;
Cancel and a closed tab stop a running sweep within seconds. Hostile requests go over viser's
raw websocket (``viser_wire.WireClient``)."""

from __future__ import annotations

import dataclasses
import signal
import time

import numpy as np
import pytest

from shoal.app import replay
from shoal.app.experiment.request import AxisRequest, ExperimentRequest, Limits, Refused, resolve
from shoal.app.experiment.service import CANCELLED, FINISHED, RUNNING, ExperimentService, experiment_pool
from shoal.app.kinds.registry import session_for
from shoal.app.limits import LIVE_TICK_SECONDS, MAX_ROBOTS, check_app_limits
from shoal.app.share import session_html
from shoal.presets.io import PresetError, load
from shoal.studies.cost import TICK_COSTS, cost, tick_cost

from app_helpers import wire_tab
from browser.browser_helpers import wait_until


# ---------------------------------------------------------------------------- the one cost function
def test_cost_is_steps_times_robots_times_runs_times_kind():
    sc = load("course-dvc", ["sim.robots=10"])
    one = cost(sc, steps=100, runs=1)
    assert one.variant == "fleet" and one.seconds == pytest.approx(100 * (30e-6 + 10 * 3e-6))
    assert cost(sc, steps=300, runs=4).seconds == pytest.approx(12 * one.seconds)
    assert cost(load("course-physics", ["sim.robots=10"]), steps=100, runs=1).seconds > one.seconds
    assert set(TICK_COSTS) >= {"swarm", "fleet", "fleet/physics", "sonar", "sonar/surrogate", "slo_swarm"}


def test_every_kind_at_its_robot_cap_fits_a_live_tick():
    for name in ("default", "course-dvc", "course-physics", "sonar-xb-pso", "slo-walk", "course-dvc-slo"):
        sc = load(name)
        cap = MAX_ROBOTS[__import__("shoal.app.limits", fromlist=["scene_kind"]).scene_kind(sc)]
        assert tick_cost(sc, robots=cap) <= LIVE_TICK_SECONDS, name
        with pytest.raises(PresetError, match="sim.robots"):
            check_app_limits(load(name, [f"sim.robots={cap + 1}"]))


# ---------------------------------------------------------------------------- the sweep, whatever its fields
@pytest.mark.parametrize("key, values, words", [
    ("sim.steps", "10000000, 9999999", "cell sim.steps=10000000: sim.steps = 10,000,000: this server runs at most "
                                       "10,000 steps per run"),
    ("sim.steps", "10001", "at most 10,000 steps per run"),
    ("sim.robots", "20, 5000", "sim.robots = 5000: the browser app runs at most 2000 robots"),
])
def test_a_swept_field_cannot_pass_the_limits(key, values, words):
    sc = load("default")
    with pytest.raises(Refused) as err:
        resolve(sc, ExperimentRequest(axes=(AxisRequest(key, values=values),), runs=2, steps=100), Limits())
    assert any(words in m for m in err.value.messages), err.value.messages


def test_an_experiment_is_held_to_a_cpu_budget_over_all_its_cells():
    sc = load("course-dvc")
    request = ExperimentRequest(axes=(AxisRequest("sim.robots", values="800, 900, 1000"),), runs=100, steps=10_000)
    with pytest.raises(Refused, match="CPU seconds"):
        resolve(sc, request, Limits(max_experiment_runs=10_000))
    plan, _ = resolve(sc, dataclasses.replace(request, runs=1, steps=100), Limits())
    assert len(plan) == 3


def _field(server, key, c, field: str) -> None:
    """Choose ``field`` as field 1 and wait for the panel's suggestion of its values (it would
    overwrite values sent meanwhile)."""
    axis = server.tabs[key].panels.experiment.axes[0]
    c.set_value("field 1", field)
    wait_until(lambda: axis.field.value == field and field.rsplit(".")[-1] in axis.info.content, what="the field")
    time.sleep(0.3)


def test_steps_swept_on_the_wire_are_refused_and_queue_nothing(server):
    c, key = wire_tab(server, "Run experiment", "Load replay")
    try:
        _field(server, key, c, "sim.steps")
        c.set_value("values 1", "10000000, 9999999")
        c.set_value("Run experiment", True)
        wait_until(lambda: c.saw("at most 10,000 steps per run"), what="the refusal")
        assert server.experiments.queued_runs() == 0
    finally:
        c.close()


# ---------------------------------------------------------------------------- Cancel and a closed tab
LONG = ExperimentRequest(axes=(AxisRequest("sim.robots", values="1000, 999"),), runs=100, steps=10_000)


SHORT = ExperimentRequest(axes=(AxisRequest("controller.U", values="6, 9"),), runs=2, steps=20)


def _service():
    """A service whose worker pool has started (the first experiment starts its forkserver)."""
    service = ExperimentService(experiment_pool(1), Limits(max_seconds=1e6, max_queue_seconds=1e6),
                                owns_scheduler=True)
    warm = service.submit("warm", load("default"), SHORT)
    wait_until(lambda: warm.over, timeout=120, what="a first experiment")
    return service


def test_cancel_stops_a_running_experiment_within_seconds_and_the_queue_moves_on():
    service = _service()
    try:
        long = service.submit("a", load("default"), LONG)
        short = service.submit("b", load("default"), SHORT)
        wait_until(lambda: long.phase == RUNNING, timeout=60, what="the long experiment running")
        time.sleep(1.0)  # its first chunk is in the worker
        start = time.monotonic()
        service.cancel("a")
        wait_until(lambda: long.over, timeout=15, what="the cancelled experiment over")
        stopped = time.monotonic() - start
        assert long.phase == CANCELLED and stopped < 5.0, stopped
        wait_until(lambda: short.phase == FINISHED, timeout=60, what="the next experiment finished")
    finally:
        service.stop()


def test_stop_ends_a_running_experiment_and_its_workers_within_seconds():
    service = _service()
    exp = service.submit("a", load("default"), LONG)
    wait_until(lambda: exp.phase == RUNNING, timeout=60, what="the experiment running")
    time.sleep(1.0)
    workers = [p for p in (service.scheduler._pool._processes or {}).values()] if service.scheduler._pool else []
    start = time.monotonic()
    service.stop()
    assert time.monotonic() - start < 6.0 and exp.over
    assert not any(p.is_alive() for p in workers)


def test_a_closed_tab_stops_its_running_experiment_within_seconds(server):
    c, key = wire_tab(server, "Run experiment", "Load replay")
    _field(server, key, c, "sim.robots")
    c.set_value("values 1", "1000, 999")
    c.set_value("runs per cell", 60)
    c.set_value("steps per run", 5000)
    c.set_value("Run experiment", True)
    wait_until(lambda: c.saw("running:"), timeout=60, what="the experiment running")
    exp = server.experiments.experiment(key)
    time.sleep(1.0)
    start = time.monotonic()
    c.close()
    wait_until(lambda: exp.over, timeout=15, what="the experiment over after the tab closed")
    assert exp.phase == CANCELLED and time.monotonic() - start < 5.0


# ---------------------------------------------------------------------------- replays and Share
def _replay(robots: int, frames: int = 1, d: int = 2) -> bytes:
    session = session_for(load("default"))
    rec = replay.from_bytes(session.export_replay())
    meta = {**rec.meta}
    xs = [np.zeros((robots, d)) for _ in range(frames)]
    big = replay.from_frames(meta, list(range(frames)), [0.1 * k for k in range(frames)], xs,
                             [np.zeros(robots) for _ in range(frames)], [np.zeros(robots, np.int8) for _ in xs],
                             np.zeros((frames, len(rec.metric_names))))
    return replay.to_bytes(big)


@pytest.mark.parametrize("robots, frames, words", [
    (3_000_000, 1, "x: 3,000,000 robot rows"),  # the audit's file: 12 MiB, 103 MiB sent to the page
    (5_000, 1, "a frame of 5,000 robots; the browser app shows at most 2000"),
    (2_000, 250, "x: 500,000 robot rows"),
])
def test_a_replay_beyond_the_robot_limits_is_refused(server, robots, frames, words):
    data = _replay(robots, frames)
    assert len(data) < replay.MAX_REPLAY_BYTES
    c, key = wire_tab(server, "Run experiment", "Load replay")
    try:
        tab = server.tabs[key]
        c.upload("Load replay", "big.npz", data)
        wait_until(lambda: c.saw(words), timeout=60, what="the refusal")
        assert tab.session.replaying is None
    finally:
        c.close()


def test_share_of_a_recording_beyond_the_limits_is_refused():
    rec = replay.from_bytes(_replay(5_000))
    from shoal.app.share import recording_html

    with pytest.raises(PresetError, match="a frame of 5,000 robots"):
        recording_html(rec)
    session = session_for(load("default"))
    session.step(3)
    assert len(session_html(session)) < 5 * 2**20


# ---------------------------------------------------------------------------- shoal export-replay
@pytest.mark.parametrize("sig, code", [(signal.SIGINT, 130), (signal.SIGTERM, 143)])
def test_a_long_export_says_its_cost_and_stops_on_a_signal_writing_nothing(tmp_path, sig, code):
    import subprocess
    import sys

    out = tmp_path / "long.html"
    proc = subprocess.Popen([sys.executable, "-m", "shoal",
                             "export-replay", "default", "--steps", "10000000", "--out", str(out)],
                            stderr=subprocess.PIPE,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))  # (xdist ignores SIGINT)
    err: list[str] = []
    import os
    import threading

    def read() -> None:
        while chunk := os.read(proc.stderr.fileno(), 4096):
            err.append(chunk.decode("utf-8", "replace"))

    threading.Thread(target=read, daemon=True).start()
    try:
        wait_until(lambda: "10,000,000 steps × 20 robots × 1 runs" in "".join(err), timeout=60, what="the estimate")
        time.sleep(3.0)  # running (the bar shows on a terminal only)
        start = time.monotonic()
        proc.send_signal(sig)
        proc.wait(timeout=30)
        took = time.monotonic() - start
    finally:
        if proc.poll() is None:
            proc.kill()
    text = "".join(err)
    assert proc.returncode == code and took < 10, (proc.returncode, took)
    assert "Traceback" not in text and not out.exists() and not list(tmp_path.iterdir())
