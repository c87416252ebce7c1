"""The compiled kernels against their references, bit for bit: pymunk's queries
(:mod:`shoal.engine.robots.queries`), the numpy fleet tick (:func:`kernels.phase_b`, in every
kinematic mode, on seeded scenes with collisions) and the rejection sampling of the spawn."""

from __future__ import annotations

import numpy as np
import pymunk
import pytest

from shoal.engine.kinds.fleet import ACTIVE, COLLIDED, Fleet, FleetParams, spawn_positions
from shoal.engine.kinds.fleet_probe import robot_view
from shoal.engine.robots import queries as q
from shoal.engine.robots.world import empty_arena, forest, obstacle_course
from shoal.presets.build import build_fleet
from shoal.presets.io import load


# ---------------------------------------------------------------------- pymunk's queries
def test_point_and_sweep_queries_give_pymunks_bits():
    rng = np.random.default_rng(1)
    space = pymunk.Space()
    hits = 0
    for _ in range(1500):
        cx, cy = rng.uniform(-3, 3, 2)
        r = rng.uniform(0.2, 1.5)
        a = rng.uniform(-4, 4, 2)
        b = a + rng.uniform(-3, 3, 2) * (rng.random() < 0.9)  # sometimes no motion at all
        sa, sb, sr = rng.uniform(-3, 3, 2), rng.uniform(-3, 3, 2), rng.uniform(0, 0.3)
        rad = rng.uniform(0.0, 0.6)
        circle = pymunk.Circle(space.static_body, r, (cx, cy))
        seg = pymunk.Segment(space.static_body, tuple(sa), tuple(sb), sr)
        space.add(circle, seg)
        nx, ny = q.segment_normal(*sa, *sb)
        for shape, point, sweep in (
            (circle, q.circle_point(*a, cx, cy, r), q.circle_sweep(cx, cy, r, *a, *b, rad)),
            (seg, q.segment_point(*a, *sa, *sb, sr, nx, ny), q.segment_sweep(*sa, *sb, sr, nx, ny, *a, *b, rad)),
        ):
            info = shape.point_query(tuple(a))
            assert (info.distance, *info.point, *info.gradient) == point
            swept = shape.segment_query(tuple(a), tuple(b), rad)
            assert (swept is None and sweep == -1.0) or (swept is not None and swept.alpha == sweep)
            hits += swept is not None
        box = seg.bb
        assert q.segment_box(*sa, *sb, sr) == (box.left, box.bottom, box.right, box.top)
        space.remove(circle, seg)
    assert hits > 300  # the sweeps hit often enough to mean something


# ---------------------------------------------------------------------- the fleet tick
COURSE = obstacle_course(seed=0, length=80.0, width=40.0, start_size=14.0)
MODES = {
    "omni DVC, sequential": FleetParams(),
    "omni DVC, simultaneous": FleetParams(update="simultaneous"),
    "omni DVC, guard and s_min": FleetParams(guard=True, s_min=0.2),
    "RPSO, constants": FleetParams(law="rpso", dvc=False),
    "Adapted RPSO, constants, mecanum": FleetParams(dvc=False, drive="mecanum", c=(0.9, 0.9, 0.5)),
    "Adapted RPSO, constants, simultaneous": FleetParams(dvc=False, update="simultaneous", c=(0.6, 0.6, 0.6)),
    "non-omni DVC, guard": FleetParams(law="nonomni", drive="differential", guard=True),
    "non-omni DVC, r_min, disc inertia": FleetParams(law="nonomni", drive="differential", r_min=0.5,
                                                     rotational_energy="disc"),
    "robot-centred, constants": FleetParams(law="robot-centred", dvc=False, drive="differential", c=(0.5, 0.5)),
}
STATE = ("x", "heading", "u", "cmd", "status", "slow", "y", "f_y", "yg", "best_fitness", "omega", "c", "force")


def _same(a: Fleet, b: Fleet, step: int) -> None:
    for name in STATE:
        np.testing.assert_array_equal(getattr(a.state, name), getattr(b.state, name), err_msg=f"{name}, tick {step}")
    ra, rb = a.state.reading, b.state.reading
    assert (ra is None) == (rb is None)
    if ra is not None:
        for name in ("gap", "point", "centre", "hit"):
            np.testing.assert_array_equal(getattr(ra, name), getattr(rb, name), err_msg=f"reading.{name}, tick {step}")


def _twins(make, steps: int) -> tuple[Fleet, Fleet]:
    """A compiled fleet and its numpy twin, stepped side by side and compared every tick."""
    a, b = make(True), make(False)
    assert a._compiled_tick() and not b._compiled_tick()
    for k in range(steps):
        np.testing.assert_array_equal(a.step().columns()["collided"], b.step().columns()["collided"])
        _same(a, b, k)
    return a, b


@pytest.mark.parametrize("mode", list(MODES))
def test_compiled_tick_equals_the_numpy_tick_bit_for_bit(mode):
    a, _ = _twins(lambda compiled: Fleet(world=COURSE, robots=25, params=MODES[mode], runs=2, seed=3,
                                         compiled=compiled), steps=40)
    if "constants" in mode or "r_min" in mode:  # DVC keeps the others clear of every body
        assert (a.state.status == COLLIDED).sum() >= 5, "the scene should include collisions"


@pytest.mark.parametrize("world", [forest(seed=2, size=30.0, density=0.08), empty_arena(20.0)], ids=["forest", "empty"])
def test_compiled_tick_equals_the_numpy_tick_in_other_worlds(world):
    params = FleetParams(dvc=False, c=(0.6, 0.6, 0.9))  # constants: the robots collide with trees and each other
    a, _ = _twins(lambda compiled: Fleet(world=world, robots=30, params=params, runs=2, seed=8, compiled=compiled),
                  steps=30)
    assert (a.state.status == COLLIDED).any()


def test_compiled_tick_equals_the_numpy_tick_on_slo_positions():
    scenario = load("course-dvc-slo", ["sim.robots=12"])

    def make(compiled: bool) -> Fleet:
        f = build_fleet(scenario, runs=2, seed=4)
        f.compiled = compiled
        return f

    _twins(make, steps=25)


def test_retune_and_world_edits_keep_the_two_ticks_equal():
    def make(compiled: bool) -> Fleet:
        return Fleet(world=COURSE, robots=20, params=FleetParams(), runs=1, seed=6, compiled=compiled)

    a, b = _twins(make, steps=5)
    for f in (a, b):
        f.retune(update="simultaneous", sensing_range=2.0, guard=True)
        f.set_world(COURSE.with_circle(*a.state.x[0, 0] + (2.0, 0.0), 0.6))
    for k in range(15):
        a.step(), b.step()
        _same(a, b, k)


def test_the_pymunk_spaces_follow_the_compiled_tick():
    f = Fleet(world=COURSE, robots=15, params=FleetParams(), runs=2, seed=1)
    for _ in range(10):
        f.step()
    for sp, x in zip(f.spaces, f.state.x):
        np.testing.assert_array_equal(sp.positions(), x)
    reference = Fleet(world=COURSE, robots=15, params=FleetParams(), runs=2, seed=1, compiled=False)
    for _ in range(10):
        reference.step()
    for robot in (0, 7):  # the probe queries pymunk: same view as on the numpy tick
        va, vb = robot_view(f, robot, run=1), robot_view(reference, robot, run=1)
        np.testing.assert_array_equal(va.gap, vb.gap)
        np.testing.assert_array_equal(va.force, vb.force)
    assert (f.state.status == ACTIVE).all()


# ---------------------------------------------------------------------- spawning
def _spawn_loop(rng, box, n, radius, spacing=0.3):
    """The rejection sampling as first written: one candidate pair at a time."""
    xmin, ymin, xmax, ymax = box
    pts: list[np.ndarray] = []
    gap = 2.0 * radius + spacing
    for _ in range(200 * n):
        if len(pts) == n:
            break
        p = rng.uniform([xmin + radius, ymin + radius], [xmax - radius, ymax - radius])
        if all(np.hypot(*(p - q)) >= gap for q in pts):
            pts.append(p)
    if len(pts) < n:
        cols = max(1, int((xmax - xmin) // gap))
        pts = [np.array([xmin + radius + (i % cols) * gap, ymin + radius + (i // cols) * gap]) for i in range(n)]
    return np.array(pts)


@pytest.mark.parametrize("n, box", [(1, (0, 0, 1.2, 1.2)), (6, (0, -3, 6, 3)), (40, (0, -3, 6, 3)),
                                    (60, (0, -7, 14, 7)), (150, (-10, -10, 10, 10))])
def test_spawn_positions_equal_the_one_at_a_time_loop_and_leave_the_generator_alike(n, box):
    for seed in range(2):
        a, b = np.random.default_rng(seed), np.random.default_rng(seed)
        np.testing.assert_array_equal(spawn_positions(a, box, n, 0.5), _spawn_loop(b, box, n, 0.5))
        assert a.random() == b.random()
