"""The Chapter 4–5 fleet: seeded determinism, disabled robots, the DVC guard's one-step
clearance as a property, and contact accounting (collisions beyond a tolerance, stalls)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from shoal.engine.core.recorder import metric_table
from shoal.engine.kinds.fleet import ACTIVE, COLLIDED, STALL_STEPS, Fleet, FleetParams
from shoal.engine.robots.motion import Kinematic, Physics
from shoal.engine.robots.sensing import sense
from shoal.engine.robots.world import RunSpace, WorldSpec, box_walls
from shoal.presets.build import build_fleet
from shoal.presets.io import PresetError, load
from shoal.presets.models import Robot

ALPHA = 0.9


def _state(f: Fleet) -> tuple[np.ndarray, ...]:
    s = f.state
    return s.x, s.heading, s.u, s.cmd, s.y, s.f_y, s.yg, s.status


def test_same_seed_same_trajectories_and_runs_do_not_depend_on_the_batch():
    scenario = load("course-dvc", ["controller.law=rpso", "controller.mode=raw", "controller.omega=0.1"])
    a, b = build_fleet(scenario, runs=3, seed=5), build_fleet(scenario, runs=3, seed=5)
    tail = build_fleet(scenario, runs=2, seed=5, first_run=1)  # runs 1 and 2 on their own
    other = build_fleet(scenario, runs=3, seed=6)
    for _ in range(15):
        ia, ib, it, _io = a.step(), b.step(), tail.step(), other.step()
    for xa, xb in zip(_state(a), _state(b)):
        np.testing.assert_array_equal(xa, xb)
    np.testing.assert_array_equal(a.state.x[1:], tail.state.x)
    np.testing.assert_array_equal(ia.com_fitness, ib.com_fitness)
    np.testing.assert_array_equal(ia.com_fitness[1:], it.com_fitness)
    assert not np.array_equal(a.state.x, other.state.x)


def test_disabled_robots_stay_where_they_stopped_and_are_still_sensed():
    # constant coefficients with little avoidance: robots collide quickly
    scenario = load("course-dvc", ["controller.law=adapted-rpso", "controller.mode=raw", "controller.omega=0.1",
                                   "controller.c1=0.5728", "controller.c2=0.5728", "controller.c3=0.5728"])
    f = build_fleet(scenario, runs=4, seed=1)
    for _ in range(200):
        f.step()
        if (f.state.status == COLLIDED).any() and (f.state.status == ACTIVE).any():
            break
    s = f.state
    dead = s.status == COLLIDED
    assert dead.any() and (~dead).any()
    frozen = s.x.copy()
    for _ in range(5):
        info = f.step()
    assert np.array_equal(f.state.x[dead], frozen[dead])  # they never move again
    assert np.all(f.state.u[dead] == 0.0) and np.all(f.state.cmd[dead] == 0.0)
    assert np.all(f.state.status[dead] == COLLIDED)  # and are never revived
    assert np.array_equal(info.collided, (f.state.status != ACTIVE).sum(axis=1))
    # still a body: a robot placed 0.4 m from a disabled one, on the side away from what it
    # touched, reads a 0.4 m gap to it, with the disabled robot's centre as x_p of [4.4]
    r, i = (int(v) for v in np.argwhere(f.state.status == COLLIDED)[0])
    sp = f.spaces[r]
    np.testing.assert_allclose(sp.positions()[i], f.state.x[r, i], atol=1e-9)
    own = sense(f.spaces, f.state.x, sensing_range=3.0)
    touched = own.point[r, i, int(np.argmin(own.gap[r, i]))]
    away = f.state.x[r, i] - touched
    away /= np.linalg.norm(away)
    j = next(k for k in range(f.robots) if k != i)
    probe = f.state.x.copy()
    probe[r, j] = f.state.x[r, i] + away * (2 * f.params.robot_radius + 0.4)
    sp.set_positions(probe[r])
    reading = sense(f.spaces, probe, sensing_range=3.0)
    sector = int(np.floor((np.arctan2(-away[1], -away[0]) + np.pi) / (np.pi / 3))) % 6
    assert abs(reading.gap[r, j, sector] - 0.4) < 1e-6
    np.testing.assert_allclose(reading.centre[r, j, sector], f.state.x[r, i], atol=1e-9)


def _world(circles: np.ndarray) -> WorldSpec:
    return WorldSpec(
        name="probe", circles=circles, polygons=(), walls=box_walls((-30.0, -30.0, 30.0, 30.0)), wall_radius=0.1,
        start_box=(-25.0, -25.0, -23.0, -23.0), source=(20.0, 3.0), layer_x=np.zeros(0),
        bounds=(-30.0, -30.0, 30.0, 30.0),
    )


circle = st.tuples(
    st.floats(0.01, 2.6),  # surface gap to the robot
    st.floats(-np.pi, np.pi),  # bearing from the robot
    st.floats(0.3, 1.2),  # radius
)


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    circles=st.lists(circle, min_size=1, max_size=5),
    speed=st.floats(0.0, 3.0),
    direction=st.floats(-np.pi, np.pi),
    best=st.tuples(st.floats(-20.0, 20.0), st.floats(-20.0, 20.0)),
    seed=st.integers(0, 2**32 - 1),
)
def test_dvc_with_guard_never_reaches_the_nearest_sensed_body_in_one_step(circles, speed, direction, best, seed):
    r_robot = 0.5
    centres = []
    for gap, bearing, rad in circles:
        d = r_robot + gap + rad
        centres.append([d * np.cos(bearing), d * np.sin(bearing), rad])
    c = np.array(centres)
    # obstacles must not overlap one another (a real course), else "nearest body" is ambiguous
    for a in range(len(c)):
        for b in range(a):
            assume(np.hypot(*(c[a, :2] - c[b, :2])) > c[a, 2] + c[b, 2] + 0.01)
    world = _world(c)
    params = FleetParams(law="adapted-rpso", dvc=True, guard=True, alpha=ALPHA, motion="kinematic")
    f = Fleet(world=world, robots=1, params=params, runs=1, seed=seed)
    s = f.state
    s.x[0, 0] = (0.0, 0.0)
    u0 = speed * np.array([np.cos(direction), np.sin(direction)])
    s.u[0, 0] = s.cmd[0, 0] = u0  # any prior velocity up to the top speed
    s.y[0, 0] = s.yg[0] = best
    s.f_y[0, 0] = s.best_fitness[0] = f.cost(s.y)[0, 0]
    f.spaces[0].set_positions(s.x[0])
    gaps = np.hypot(c[:, 0], c[:, 1]) - c[:, 2] - r_robot
    k = int(np.argmin(gaps))
    s1 = gaps[k]
    f.step()
    x = f.state.x[0, 0]
    after = np.hypot(*(x - c[k, :2])) - c[k, 2] - r_robot
    # the guard lets a step close at most α·s toward every sensed body, so at least (1 − α)·s is left
    assert after >= (1 - ALPHA) * s1 - 1e-9
    assert not (f.state.status[0, 0] == COLLIDED and after <= 1e-6)


def test_kinematic_sweep_stops_at_a_grazing_contact():
    # the centre line passes beside the circle's bounding box, the disc still grazes it
    world = _world(np.array([[1.0, 0.9, 0.5], [10.0, 10.0, 1.0]]))
    sp = RunSpace(world, np.array([[0.0, 0.0]]), robot_radius=0.5)
    moved = Kinematic("holonomic", 3.0).move([sp], np.zeros((1, 1, 2)), np.zeros((1, 1)),
                                            np.array([[[2.0, 0.0]]]), np.ones((1, 1), bool), 1.0)
    assert moved.hit[0, 0]
    contact = 1.0 - np.sqrt(1.0 - 0.9**2)  # centre distance 1 m = sum of the radii
    np.testing.assert_allclose(moved.x[0, 0], [contact, 0.0], atol=1e-5)


def test_without_the_guard_dvc_can_reach_the_nearest_body():
    """docs/readings.md, "The DVC guard (ours)": DVC bounds the new terms, not the carried ω·u. A robot 0.1 m from a
    body, still moving at 3 m/s toward it, with a second body 0.7 m away (small c3): the
    thesis algorithm closes more than α·s in many runs; with the guard in none."""
    world = _world(np.array([[1.6, 0.0, 1.0], [0.0, 2.2, 1.0]]))
    closed = {}
    for guard in (False, True):
        f = Fleet(world=world, robots=1, runs=40, seed=3,
                  params=FleetParams(law="adapted-rpso", dvc=True, guard=guard, alpha=ALPHA))
        s = f.state
        s.x[:, 0] = (0.0, 0.0)
        s.u[:, 0] = s.cmd[:, 0] = (3.0, 0.0)
        s.y[:, 0] = s.yg[:] = (20.0, 0.5)
        s.f_y[:, 0] = s.best_fitness[:] = f.cost(s.y)[:, 0]
        for sp, x in zip(f.spaces, s.x):
            sp.set_positions(x)
        f.step()
        gap = np.hypot(*(f.state.x[:, 0] - (1.6, 0.0)).T) - 1.5
        closed[guard] = int((gap < (1 - ALPHA) * 0.1 - 1e-9).sum())
    assert closed[False] > 0 and closed[True] == 0


# ---------------------------------------------------------------------- contact accounting
TOLERANCE = Robot().contact_tolerance  # the presets' float-noise allowance


def _one_robot_towards_a_circle(step: float, gap: float, motion: str = "kinematic") -> bool:
    """A robot ``gap`` m from a circle's surface moves ``step`` m straight at it; hit?"""
    world = _world(np.array([[2.0, 0.0, 0.5]]))
    x = np.array([[1.0 - gap, 0.0]])
    if motion == "kinematic":
        sp = RunSpace(world, x, robot_radius=0.5)
        mover = Kinematic("holonomic", 3.0, tolerance=TOLERANCE)
    else:
        sp = RunSpace(world, x, robot_radius=0.5, body_type="dynamic")
        mover = Physics("holonomic", 3.0, a_max=1e3, tolerance=TOLERANCE)
    moved = mover.move([sp], x[None], np.zeros((1, 1)), np.array([[[step, 0.0]]]), np.ones((1, 1), bool), 1.0)
    return bool(moved.hit[0, 0])


def test_the_contact_tolerance_is_a_float_noise_allowance():
    # docs/readings.md, "What counts as a collision, and stalls": at most a micrometre
    assert 0.0 < TOLERANCE <= 1e-6
    with pytest.raises(PresetError, match="robot.contact_tolerance"):
        load("course-dvc", ["robot.contact_tolerance=0.001"])


def test_a_float_touch_is_not_a_collision_but_a_sub_millimetre_overlap_is():
    # the guard's geometric approach leaves gaps of ~1e-16 m; a path that ends within
    # rounding of the body stops the robot but does not disable it ...
    assert not _one_robot_towards_a_circle(step=1e-13, gap=1e-16)
    # ... while a path 10 µm (or 0.5 mm) into the body is a collision
    assert _one_robot_towards_a_circle(step=1e-5, gap=1e-16)
    assert _one_robot_towards_a_circle(step=5e-4, gap=1e-16)
    assert _one_robot_towards_a_circle(step=0.5, gap=0.2)


def test_physics_counts_a_sub_millimetre_overlap_as_a_collision():
    assert _one_robot_towards_a_circle(step=2e-3, gap=1.5e-3, motion="physics")  # ≤ 0.5 mm deep
    assert _one_robot_towards_a_circle(step=0.5, gap=0.2, motion="physics")
    assert not _one_robot_towards_a_circle(step=1e-3, gap=0.2, motion="physics")  # stops short


@pytest.mark.parametrize("compiled", [True, False])
def test_both_robots_of_a_robot_robot_collision_are_disabled(compiled: bool):
    # robot 0 drives at 3 m/s at robot 1, which stands 0.5 m away: "a robot that touches
    # anything is disabled" (Algorithm 1) holds for the robot it hits as well
    world = _world(np.zeros((0, 3)))
    f = Fleet(world=world, robots=2, runs=1, seed=0, compiled=compiled,
              params=FleetParams(law="adapted-rpso", dvc=False, omega=1.0 - 1e-9, c=(0.0, 0.0, 0.0)))
    s = f.state
    s.x[0] = ((0.0, 0.0), (1.5, 0.0))
    s.u[0] = s.cmd[0] = ((3.0, 0.0), (0.0, 0.0))
    s.y = s.x.copy()
    s.f_y = f.cost(s.y)
    for sp, x in zip(f.spaces, s.x):
        sp.set_positions(x)
    f.step()
    assert f.state.status[0].tolist() == [COLLIDED, COLLIDED]
    gap = np.hypot(*(f.state.x[0, 1] - f.state.x[0, 0])) - 1.0
    assert 0.0 <= gap < 1e-5  # the mover stopped at the contact


def test_kinematic_move_reports_the_robot_a_mover_struck():
    world = _world(np.zeros((0, 3)))
    x = np.array([[0.0, 0.0], [1.5, 0.0], [10.0, 0.0]])
    sp = RunSpace(world, x, robot_radius=0.5)
    moved = Kinematic("holonomic", 3.0, tolerance=TOLERANCE).move(
        [sp], x[None], np.zeros((1, 3)), np.array([[[3.0, 0.0], [0.0, 0.0], [0.0, 0.0]]]),
        np.array([[True, False, False]]), 1.0)
    assert moved.hit[0].tolist() == [True, False, False]
    assert moved.struck[0].tolist() == [False, True, False]


def test_a_robot_standing_still_counts_as_stalled_after_stall_steps_ticks():
    # run 0: one robot at its own best with nothing in sensing range; every attractor is
    # zero, so it does not move. Run 1: its best is the source, 35 m away; it keeps moving
    world = _world(np.zeros((0, 3)))
    f = Fleet(world=world, robots=1, runs=2, seed=0, params=FleetParams(law="adapted-rpso", dvc=True))
    s = f.state
    s.x[:, 0] = np.asarray(world.source) - (35.0, 0.0)
    s.y = s.x.copy()
    s.y[1, 0] = world.source
    s.f_y = f.cost(s.y)
    for sp, x in zip(f.spaces, s.x):
        sp.set_positions(x)
    stalled = [f.step().stalled.tolist() for _ in range(STALL_STEPS)]
    assert stalled[-2] == [0, 0] and stalled[-1] == [1, 0]
    table = metric_table(f.state, f.info(), f.t)
    assert table["stalled"].tolist() == [1, 0] and table["collided"].tolist() == [0, 0]
