"""The history's rings (``app/session/ring.py``, ``history.py``): what they give back is what a
list of the same frames gives (the list functions are the reference), and their size is capped
in numbers stored, not rows."""

from __future__ import annotations

import numpy as np
import pytest

from shoal.app.kinds.registry import session_for
from shoal.app.session.history import TRAIL_DIMS, TRAIL_LIMITS, Frame, History, frame_rows, robots_at, trail_array
from shoal.presets import io as presets_io

from app_helpers import shown


def _frames(n: int, d: int, seed: int = 0, robots: tuple[int, ...] = (7,)) -> list[Frame]:
    """``n`` frames of steps 3, 4, … with times whose step changes on the way (a Δt changed
    mid-run) and robot counts cycling through ``robots`` (a robots slider moved)."""
    rng = np.random.default_rng(seed)
    frames, t = [], 0.0
    for i in range(n):
        t += 0.1 if i < n // 2 else 0.05
        m = robots[(i // 9) % len(robots)]
        scene = {"source": rng.normal(size=(1, 2))} if i % 5 == 0 else {}
        frames.append(Frame(k=3 + i, t=t, x=rng.normal(size=(m, d)), u=rng.normal(size=(m, d)),
                            heading=rng.normal(size=m), status=rng.integers(0, 2, m).astype(np.int8),
                            a=rng.normal(size=(m, d)), scene=scene))
    return frames


def _filled(frames: list[Frame], **limits: int) -> History:
    h = History(("t", "f"), **limits)
    for f in frames:
        h.record(f, (f.t, float(f.k) ** 0.5))
    return h


@pytest.mark.parametrize("d", [1, 2, 3, 5])
@pytest.mark.parametrize("robots", [(7,), (7, 4, 9)])
def test_trails_from_the_ring_are_the_old_trail_array_of_the_same_frames(d, robots):
    frames = _frames(400, d, seed=d, robots=robots)
    h = _filled(frames, max_steps=300)
    kept = frames[-300:]
    assert [f.k for f in h.frames] == [f.k for f in kept]
    for upto in (0, 1, 2, 57, 150, 299):
        for horizon in (0.0, 0.3, 2.0, 7.5, 100.0):
            for max_trails, max_points in ((80, 40), (3, 8), (5, 2)):
                t_now = kept[upto].t
                want = trail_array(kept[: upto + 1], t_now, horizon, max_trails, max_points)
                got = h.trails(t_now, horizon, max_trails, max_points, upto=upto)
                np.testing.assert_array_equal(got.points, want[..., :TRAIL_DIMS])
                assert got.epoch == h.epoch and len(got.steps) == got.shape[1]
                if got.shape[1]:  # each column is the frame of its step
                    at = {f.k: f for f in kept}
                    for j, k in enumerate(got.steps):
                        np.testing.assert_array_equal(got.points[:, j], at[int(k)].x[: len(got), :TRAIL_DIMS])
                    assert got.steps[-1] == kept[upto].k
                    assert all(int(k) % got.stride == 0 for k in got.steps[:-1])


def test_frames_rows_and_robots_at_read_back_what_was_recorded():
    frames = _frames(120, 2, robots=(5, 8, 3))
    h = _filled(frames, max_steps=100)
    kept = frames[-100:]
    for got, want in zip(h.frames, kept):
        assert (got.k, got.t) == (want.k, want.t)
        for name in ("x", "u", "heading", "status", "a"):
            np.testing.assert_array_equal(getattr(got, name), getattr(want, name))
        assert got.scene is want.scene
    np.testing.assert_array_equal(h.rows(), frame_rows(kept))
    assert h.frames[-1].k == kept[-1].k and h.frames[3].k == kept[3].k
    assert [f.k for f in h.frames[-4:]] == [f.k for f in kept[-4:]]
    k = kept[60].k
    x, trails = h.robots_at(k, 2.0)
    x_ref, trails_ref = robots_at(kept, k, 2.0)
    np.testing.assert_array_equal(x, x_ref)
    np.testing.assert_array_equal(trails.points, trails_ref)
    assert h.robots_at(10_000, 2.0) is None and h.index_of(kept[0].k - 1) is None
    got = h.frames[0]
    got.x[:] = 99.0  # a frame read is a copy: the ring is not written through it
    assert not np.any(h.frames[0].x == 99.0)


def test_metric_rows_come_back_as_the_last_rows_and_interpolate_as_all_of_them():
    frames = _frames(300, 2)
    h = _filled(frames, max_metrics=250)
    t = np.array([f.t for f in frames])[-250:]
    f = np.sqrt([float(fr.k) for fr in frames])[-250:]
    m = h.metric_arrays()
    np.testing.assert_array_equal(m["t"], t)
    np.testing.assert_array_equal(m["f"], f)
    np.testing.assert_array_equal(h.metric_table(), np.column_stack([t, f]))
    np.testing.assert_array_equal(h.metric_tail(10)["f"], f[-10:])
    assert len(h.metrics) == 250 and h.metrics[-1] == (t[-1], f[-1]) and list(h.metrics)[0] == (t[0], f[0])
    at = np.linspace(t[100] - 0.01, t[-1] + 1.0, 77)  # B's metric at A's times, from B's rows around them
    part = h.metric_around(float(at[0]))
    np.testing.assert_array_equal(np.interp(at, part["t"], part["f"]), np.interp(at, t, f))


def test_a_cleared_or_replaced_history_is_a_new_epoch_and_keeps_every_frame_of_a_recording():
    frames = _frames(50, 2)
    h = _filled(frames, max_steps=20)
    first = h.epoch
    h.clear()
    assert h.epoch != first and len(h.frames) == 0 and len(h.metrics) == 0
    h.replace(frames, [(f.t, 0.0) for f in frames], motion=False)  # a recording: all of it, no velocities
    assert len(h.frames) == 50 and len(h.metrics) == 50 and h.epoch not in (first,)
    np.testing.assert_array_equal(h.frames[7].u, np.zeros_like(frames[7].x))
    np.testing.assert_array_equal(h.frames[7].x, frames[7].x)
    h.clear()
    for f in frames:  # a live run again: back to max_steps
        h.record(f, (f.t, 0.0))
    assert len(h.frames) == 20


def test_the_budget_counts_numbers_and_a_run_that_reaches_it_goes_on_with_a_shorter_history():
    rng = np.random.default_rng(3)
    budget = 400_000
    h = History(("t",), max_steps=5000, budget=budget)
    n, d = 200, 50  # 200 robots in 50 dimensions: about 20,000 numbers a frame (x, u, a), not 200 rows
    for k in range(40):
        x = rng.normal(size=(n, d))
        h.record(Frame(k=k, t=0.1 * k, x=x, u=x, heading=np.zeros(n), status=np.zeros(n, np.int8), a=x), (0.1 * k,))
        assert h.allocated() <= budget
    kept = len(h.frames)
    assert 5 <= kept < 40 and h.frames[-1].k == 39 and h.frames[0].k == 40 - kept  # the newest steps kept
    assert h.shortened is not None and f"the last {kept} steps" in h.shortened and "memory budget" in h.shortened
    assert len(h.metrics) == 40  # (metric rows are small: all of them)
    small = _filled(_frames(60, 2))
    assert small.shortened is None  # 7 robots in the plane: nowhere near it


def test_a_huge_frame_keeps_one_frame_and_the_scene_parts_count_too():
    h = History(("t",), budget=1_000)
    x = np.zeros((100, 30))
    for k in range(3):
        h.record(Frame(k=k, t=float(k), x=x, u=x, heading=np.zeros(100), status=np.zeros(100, np.int8)), (float(k),))
    assert len(h.frames) == 1 and h.frames[-1].k == 2 and h.shortened is not None
    h = History(("t",), budget=80_000)  # 1/8 of it for scene parts that change: 10,000 numbers
    for k in range(30):
        part = {"obstacles": np.full((1_000, 3), float(k))}  # a new obstacle array every step
        h.record(Frame(k=k, t=float(k), x=np.zeros((2, 2)), u=np.zeros((2, 2)), heading=np.zeros(2),
                       status=np.zeros(2, np.int8), scene=part), (float(k),))
    assert len(h.frames) == 3 and h.frames[0].scene["obstacles"][0, 0] == 27.0 and h.shortened is not None


def test_a_session_with_swarm_b_shares_the_tab_budget_and_gives_it_back():
    s = session_for(presets_io.load("default"))
    assert s.history.budget == s.history_budget
    s.enable_compare({"controller.U": 3.0})
    assert s.history.budget == s.twin.history.budget == s.history_budget // 2
    s.step(5)
    s.disable_compare()
    assert s.history.budget == s.history_budget


def test_a_session_too_big_for_its_budget_plays_on_and_says_so_in_the_status_line(tab):
    s = tab.replace(presets_io.load("default", ["sim.robots=300", "sim.d=10", "sim.steps=100000"]))
    s.history.budget = 300_000  # (a server's smaller budget, as a test can afford to fill)
    s.step(60)
    assert s.k == 60 and 1 <= len(s.frames) < 60 and s.frames[-1].k == 60
    tab.panels.refresh_status()
    said = shown(tab.panels.status.content)
    assert f"the history keeps the last {len(s.frames)} steps (the tab's memory budget" in said, said
    assert TRAIL_LIMITS[0] >= len(s.snapshot().trails)


def test_the_largest_scene_a_tab_may_run_holds_its_budget_not_its_row_cap():
    """2,000 robots in 10 dimensions (the app's caps) are 64,000 numbers a frame: the row cap alone
    would keep 200 of them (100 MB). The budget keeps what fits in 32 MiB and says so; the run
    goes on."""
    from shoal.app.session.history import HISTORY_BUDGET

    s = session_for(presets_io.load("default", ["sim.robots=2000", "sim.d=10", "sim.steps=100000"]))
    s.step(90)
    h = s.history
    assert s.k == 90 and 30 <= len(s.frames) < 90 and s.frames[-1].k == 90 and h.shortened is not None
    assert h.allocated() <= HISTORY_BUDGET
    assert s.trajectory_rows().shape[0] == 2000 * len(s.frames)  # the exports read what is kept
