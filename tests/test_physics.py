"""Physics mode (pymunk bodies) against its per-body reference, bit for bit.

:class:`ReferencePhysics` is the motion model as it was before the bodies were read and
written a space at a time: a Python loop over the bodies of every run at every substep, and a
collision callback for every pair of shapes, disabled robots' included. The batched
:class:`~shoal.engine.robots.motion.Physics` must give the same positions, headings,
velocities and collisions, tick after tick, on seeded scenes where robots crash into
obstacles, walls and each other.
"""

from __future__ import annotations

import numpy as np
import pymunk
import pytest

from shoal.engine.kinds.fleet import Fleet, FleetParams, spawn_positions
from shoal.engine.robots.laws import wrap_angle
from shoal.engine.robots.motion import Moved, Physics, command_velocity
from shoal.engine.robots.world import DISABLED, OBSTACLE, ROBOT, RunSpace, forest, obstacle_course


class ReferencePhysics(Physics):
    """The per-body motion model (the previous ``Physics``), kept as the reference."""

    COLLIDES_WITH = (OBSTACLE, ROBOT)  # the previous model's callbacks (no DISABLED type)

    def move(self, spaces, x, heading, command, active, dt) -> Moved:
        h = dt / self.substeps
        dv_max = self.a_max * h
        R, N = active.shape
        new_x, new_heading, velocity = np.empty_like(x), np.empty_like(heading), np.zeros_like(x)
        hit = np.zeros((R, N), dtype=bool)
        live = [np.flatnonzero(active[r]).tolist() for r in range(R)]
        for sp in spaces:
            self._hook(sp)
            sp.contacts.clear()
        angles = np.zeros((R, N))
        for _ in range(self.substeps):
            if self.drive != "holonomic":
                for r, sp in enumerate(spaces):
                    bodies = sp.robot_bodies
                    angles[r, live[r]] = [bodies[i].angle for i in live[r]]
            want = command_velocity(self.drive, command, angles, self.v_max)
            for r, sp in enumerate(spaces):
                if live[r]:
                    if self.drive == "differential":
                        self._track_differential(sp, live[r], want[r, live[r]], command[r], h, dv_max)
                    else:
                        self._track_bodies(sp, live[r], want[r, live[r]].tolist(), dv_max)
                sp.space.step(h)
                if sp.contacts:
                    for i in list(sp.contacts):
                        _disable(sp, i)
                    live[r] = [i for i in live[r] if i not in sp.contacts]
        for r, sp in enumerate(spaces):
            hit[r, list(sp.contacts)] = True
            hit[r] &= active[r]
            new_x[r] = [tuple(b.position) for b in sp.robot_bodies]
            new_heading[r] = [b.angle for b in sp.robot_bodies]
            velocity[r] = [tuple(b.velocity) for b in sp.robot_bodies]
        return Moved(new_x, wrap_angle(new_heading), velocity, hit)

    def _track_differential(self, sp: RunSpace, live: list[int], want: np.ndarray, command: np.ndarray, h: float,
                            dv_max: float) -> None:
        for j, i in enumerate(live):
            body = sp.robot_bodies[i]
            if body.body_type != pymunk.Body.DYNAMIC:
                continue
            vel = np.array(body.velocity)
            fwd = np.array([np.cos(body.angle), np.sin(body.angle)])
            vel = fwd * float(vel @ fwd)
            w_err = float(command[i, 1]) - body.angular_velocity
            body.angular_velocity += float(np.clip(w_err, -self.a_max * h * 4, self.a_max * h * 4))
            dv = want[j] - vel
            norm = float(np.hypot(*dv))
            if norm > dv_max:
                dv *= dv_max / norm
            body.velocity = tuple(vel + dv)

    @staticmethod
    def _track_bodies(sp: RunSpace, live: list[int], want: list[list[float]], dv_max: float) -> None:
        dynamic = pymunk.Body.DYNAMIC
        for (wx, wy), i in zip(want, live):
            body = sp.robot_bodies[i]
            if body.body_type != dynamic:
                continue
            vx, vy = body.velocity
            body.angular_velocity = 0.0
            dx, dy = wx - vx, wy - vy
            norm = float(np.hypot(dx, dy))
            if norm > dv_max:
                k = dv_max / norm
                dx, dy = dx * k, dy * k
            body.velocity = (vx + dx, vy + dy)



def _disable(sp: RunSpace, i: int) -> None:
    """The previous disabling: the body only (its shape keeps the collision type ROBOT)."""
    body = sp.robot_bodies[i]
    if body.body_type == pymunk.Body.DYNAMIC:
        body.body_type = pymunk.Body.KINEMATIC
        body.velocity = (0.0, 0.0)
        body.angular_velocity = 0.0


def _bits(a: np.ndarray) -> bytes:
    return np.ascontiguousarray(a).tobytes()


def _scene(seed: int, runs: int, robots: int) -> tuple[list[RunSpace], np.ndarray]:
    world = obstacle_course(seed, length=30.0, width=12.0, layers=3, first_gap=1.5, last_gap=1.0)
    gens = [np.random.default_rng([seed, r]) for r in range(runs)]
    x = np.stack([spawn_positions(g, world.start_box, robots, 0.5, 0.05) for g in gens])
    return [RunSpace(world, x[r], 0.5, body_type="dynamic") for r in range(runs)], x


@pytest.mark.parametrize("drive", ["holonomic", "mecanum", "differential"])
def test_batched_bodies_move_as_the_per_body_reference_bit_for_bit(drive):
    runs, robots, ticks = 3, 10, 10
    (ours, x), (theirs, _) = _scene(3, runs, robots), _scene(3, runs, robots)
    rng = np.random.default_rng(11)
    new, ref = Physics(drive, 3.0, 10.0, tolerance=1e-3), ReferencePhysics(drive, 3.0, 10.0, tolerance=1e-3)
    heading = np.zeros((runs, robots))
    active = np.ones((runs, robots), bool)
    for _ in range(ticks):
        command = rng.uniform(-0.2, 0.6, (runs, robots, 2))  # mostly towards the obstacles
        if drive == "differential":
            command[..., 1] = rng.uniform(-1.0, 1.0, (runs, robots))
        a = new.move(ours, x, heading, command, active, 1.0)
        b = ref.move(theirs, x, heading, command, active, 1.0)
        for got, want in zip((a.x, a.heading, a.velocity, a.hit), (b.x, b.heading, b.velocity, b.hit)):
            assert _bits(got) == _bits(want)
        for sa, sb in zip(ours, theirs):
            assert _bits(sa.bodies()) == _bits(sb.bodies())
            assert [bd.body_type for bd in sa.robot_bodies] == [bd.body_type for bd in sb.robot_bodies]
        x, heading = a.x, a.heading
        active &= ~a.hit
        collided = int((~active).sum())
    assert 0 < collided < runs * robots  # the scenes had collisions, and robots still moving at the end


def test_a_disabled_robot_is_kinematic_still_and_of_the_disabled_collision_type():
    sp = _scene(5, 1, 2)[0][0]
    sp.robot_bodies[0].velocity = (1.0, 2.0)
    sp.disable(0)
    body = sp.robot_bodies[0]
    assert body.body_type == pymunk.Body.KINEMATIC and tuple(body.velocity) == (0.0, 0.0)
    assert sp.robot_shapes[0].collision_type == DISABLED and sp.robot_shapes[1].collision_type == ROBOT
    assert list(sp.dynamic) == [False, True]
    sp.disable(0)  # twice: nothing more happens
    assert list(sp.dynamic) == [False, True]


def test_set_velocities_leaves_every_other_body_as_it_was():
    sp = _scene(2, 1, 4)[0][0]
    sp.robot_bodies[1].velocity = (0.5, -0.25)
    sp.disable(2)
    before = sp.bodies().copy()
    v = np.array([[1.0, 0.0], [0.5, -0.25], [0.0, 0.0], [-2.0, 1.5]])
    sp.set_velocities(v, np.array([0.0, 0.0, 0.0, 3.0]))
    after = sp.bodies()
    assert _bits(after[:, :3]) == _bits(before[:, :3])  # positions and angles untouched
    assert _bits(after[:, 3:5]) == _bits(v) and list(after[:, 5]) == [0.0, 0.0, 0.0, 3.0]
    assert tuple(sp.space.static_body.velocity) == (0.0, 0.0)
    assert [tuple(b.position) for b in sp.robot_bodies] == [tuple(p) for p in after[:, :2]]


def test_a_physics_fleet_runs_as_with_the_per_body_reference():
    # the whole fleet tick (sensing, the law, the move, collisions) over a run long enough for
    # collisions: the reference as the fleet's motion model gives the same bits
    params = FleetParams(law="rpso", dvc=False, omega=0.1, c=(0.4296, 0.4296, 0.2148), motion="physics",
                         drive="mecanum")
    world = obstacle_course(0)
    a, b = (Fleet(world=world, robots=6, runs=2, seed=4, params=params) for _ in range(2))
    b.motion = ReferencePhysics(params.drive, params.v_max, params.a_max, tolerance=params.contact_tolerance)
    for _ in range(60):
        a.step()
        b.step()
        for name in ("x", "heading", "u", "cmd", "status"):
            assert _bits(getattr(a.state, name)) == _bits(getattr(b.state, name))
    assert (a.state.status != 0).any()


# ---------------------------------------------------------------------- compiled queries
CASES = [  # (law, dvc, drive, world, collisions): both sensing frames, every drive, constant and DVC coefficients
    ("rpso", False, "mecanum", "course", True),
    ("adapted-rpso", True, "mecanum", "course", False),  # DVC: collision-free
    ("adapted-rpso", False, "holonomic", "forest", True),
    ("nonomni", True, "differential", "course", True),  # with inertia, the robot frame collides too
]


@pytest.mark.parametrize("law, dvc, drive, world, collisions", CASES)
def test_physics_senses_and_counts_contacts_as_pymunks_queries_bit_for_bit(law, dvc, drive, world, collisions):
    # the compiled sensing and contact check (the default) against pymunk's queries
    # (compiled=False) over seeded runs with collisions, tick after tick
    params = FleetParams(law=law, dvc=dvc, omega=0.1, c=(0.4296, 0.4296, 0.2148), motion="physics", drive=drive)
    spec = obstacle_course(1) if world == "course" else forest(2, size=20.0, density=0.15, min_gap=0.8)
    a, b = (Fleet(world=spec, robots=8, runs=3, seed=9, params=params, compiled=c) for c in (True, False))
    readings = 0
    for _ in range(80):
        a.step()
        b.step()
        for name in ("x", "heading", "u", "cmd", "status", "force", "omega", "c"):
            assert _bits(getattr(a.state, name)) == _bits(getattr(b.state, name)), name
        if a.state.reading is not None:
            readings += int(a.state.reading.hit.sum())
            for name in ("gap", "point", "centre", "hit"):
                assert _bits(getattr(a.state.reading, name)) == _bits(getattr(b.state.reading, name)), name
    assert readings > 0  # bodies were seen
    assert (a.state.status != 0).any() == collisions
