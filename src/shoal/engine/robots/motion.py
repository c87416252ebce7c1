"""Motion models: kinematic (ideal particle, as in MATLAB) and physics (pymunk, as in Gazebo).

Every model moves the robots of all runs one control tick and reports new contacts.
A robot that touches an obstacle or another robot is disabled and stays where it
stopped (Ch. 4); disabled robots remain bodies that others sense and hit.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal, Sequence

import numpy as np
import pymunk

from .laws import arc_pose_update, mecanum_limit, to_world, wrap_angle
from .world import DISABLED, OBSTACLE, ROBOT, RunSpace

Drive = Literal["holonomic", "mecanum", "differential"]


def command_velocity(drive: Drive, command: np.ndarray, heading: np.ndarray, v_max: float) -> np.ndarray:
    """The world-frame velocity a drive can realise for a command.

    holonomic: the global velocity u as commanded; mecanum: u limited by the wheel speeds
    [4.18]/[4.19] (direction-dependent top speed); differential: [v; w] → v along the heading.
    """
    if drive == "differential":
        return to_world(np.stack([command[..., 0], np.zeros_like(command[..., 0])], axis=-1), heading)
    if drive == "mecanum":
        return mecanum_limit(command, heading, v_max)
    return command


@dataclass
class Moved:
    x: np.ndarray  # (R, N, 2)
    heading: np.ndarray  # (R, N)
    velocity: np.ndarray  # (R, N, 2) realised world-frame velocity
    hit: np.ndarray  # (R, N) bool, collided this tick (overlap beyond the contact tolerance)
    struck: np.ndarray | None = None  # (R, N) bool, robots a mover collided with this tick (kinematic)


def first_contact(sp: RunSpace, start: tuple[float, float], end: tuple[float, float], i: int,
                  inset: float = 0.0) -> tuple[float, pymunk.Shape] | None:
    """Fraction of the way from ``start`` to ``end`` at which robot ``i``'s disc, shrunk by
    ``inset`` metres, first touches another body of ``sp``, and that body's shape (None: a
    free path).

    ``Space.segment_query_first`` with a radius is not used: its broad phase tests the bare
    centre line against the bounding boxes, so it misses a body that the disc grazes while
    the line passes beside its box. Candidates come from a bounding-box query of the whole
    swept disc instead, and each is tested exactly with ``Shape.segment_query``.
    """
    rad = sp.robot_radius - inset
    bb = pymunk.BB(min(start[0], end[0]) - rad, min(start[1], end[1]) - rad,
                   max(start[0], end[0]) + rad, max(start[1], end[1]) + rad)
    best: tuple[float, pymunk.Shape] | None = None
    for shape in sp.space.bb_query(bb, sp.filters[i]):
        q = shape.segment_query(start, end, rad)
        if q is not None and (best is None or q.alpha < best[0]):
            best = (q.alpha, shape)
    return best


def deeper_than(sp: RunSpace, shape: pymunk.Shape, start: tuple[float, float], end: tuple[float, float],
                tolerance: float) -> bool:
    """Would the path carry the robot's disc more than ``tolerance`` metres into ``shape``?
    (docs/readings.md, "What counts as a collision, and stalls")"""
    return tolerance <= 0 or shape.segment_query(start, end, sp.robot_radius - tolerance) is not None


class Kinematic:
    """Exact position update ([3.10]/[4.6], or the arc [5.5]–[5.10] for differential drive).

    Contacts: each robot's path is swept as a disc against the world and the other
    robots (:func:`first_contact`) and stops at the first contact. The contact is a
    collision (``hit``) only when the path would have carried the disc more than
    ``tolerance`` metres into the body it touched (:func:`deeper_than`); a shallower touch
    just stops the robot. A robot the mover collided with has collided too (``struck``):
    "a robot that touches anything is disabled" holds for both of them. Robots are moved one
    after another in the space, so a later sweep sees an earlier robot's new position; the
    space must hold every robot at ``x`` when ``move`` is called.
    """

    def __init__(self, drive: Drive = "holonomic", v_max: float = 3.0, tolerance: float = 0.0) -> None:
        self.drive, self.v_max, self.tolerance = drive, v_max, tolerance

    def move(
        self, spaces: Sequence[RunSpace], x: np.ndarray, heading: np.ndarray, command: np.ndarray,
        active: np.ndarray, dt: float,
    ) -> Moved:
        if self.drive == "differential":
            v = np.where(active, command[..., 0], 0.0)
            w = np.where(active, command[..., 1], 0.0)
            target, new_heading = arc_pose_update(x, heading, v, w, dt)
        else:
            u = np.where(active[..., None], command_velocity(self.drive, command, heading, self.v_max), 0.0)
            target, new_heading = x + dt * u, heading  # [4.6]
        new_x = target.copy()
        hit = np.zeros(active.shape, dtype=bool)
        struck = np.zeros(active.shape, dtype=bool)
        for r, sp in enumerate(spaces):  # the space holds every robot at x (kept in sync)
            for i in map(int, np.flatnonzero(active[r])):
                start, end = tuple(x[r, i]), tuple(target[r, i])
                if start != end:
                    contact = first_contact(sp, start, end, i)
                    if contact is not None:  # stop where the swept disc first touches
                        alpha, body = contact
                        new_x[r, i] = x[r, i] + max(alpha - 1e-6, 0.0) * (target[r, i] - x[r, i])
                        hit[r, i] = deeper_than(sp, body, start, end, self.tolerance)
                        j = sp.robot_of(body)
                        if hit[r, i] and j is not None:
                            struck[r, j] = True
                    sp.move_robot(i, new_x[r, i])
        velocity = (new_x - x) / dt
        return Moved(new_x, wrap_angle(new_heading), velocity, hit, struck)


class Physics:
    """pymunk bodies with mass that track the commanded velocity within ``a_max``.

    Each control tick is split into ``substeps``; per substep the body velocity moves
    toward the drive's realisable velocity by at most a_max·h, differential-drive bodies
    also turn toward the commanded rate and lose their sideways velocity (no skid).
    Contacts come from pymunk's collision callback: a contact whose overlap exceeds
    ``tolerance`` metres in some substep is a collision, and a collided body becomes
    kinematic with zero velocity, i.e. it stays where it stopped.

    The bodies are read and written a whole space at a time (:meth:`RunSpace.bodies`,
    :meth:`RunSpace.set_velocities`) and tracked in numpy over all runs at once, with the same
    operations in the same order as one body at a time (``tests/test_physics.py`` holds the
    per-body version and requires equal bits). A disabled robot's shape takes the collision
    type ``DISABLED``, which has a callback only against live robots: a disabled robot resting
    against an obstacle or another disabled robot costs no Python call per substep (those
    contacts could only name robots that are disabled already).
    """

    COLLIDES_WITH = (OBSTACLE, ROBOT, DISABLED)  # what a live robot's contacts are checked against

    def __init__(self, drive: Drive = "holonomic", v_max: float = 3.0, a_max: float = 10.0, substeps: int = 10,
                 tolerance: float = 0.0) -> None:
        self.drive, self.v_max, self.a_max, self.substeps = drive, v_max, a_max, substeps
        self.tolerance = tolerance
        self._hooked: set[int] = set()

    def _hook(self, sp: RunSpace) -> None:
        if id(sp) in self._hooked:
            return
        hits: set[int] = set()
        sp.contacts = hits  # type: ignore[attr-defined]

        def pre_solve(arbiter: pymunk.Arbiter, _space: pymunk.Space, _data: object) -> None:
            depth = -min((p.distance for p in arbiter.contact_point_set.points), default=0.0)
            if depth <= self.tolerance:  # a touch within the tolerance is not a collision
                return
            for shape in arbiter.shapes:
                i = sp.robot_of(shape)
                if i is not None:
                    hits.add(i)

        for other in self.COLLIDES_WITH:
            sp.space.on_collision(ROBOT, other, pre_solve=pre_solve)
        self._hooked.add(id(sp))

    def move(
        self, spaces: Sequence[RunSpace], x: np.ndarray, heading: np.ndarray, command: np.ndarray,
        active: np.ndarray, dt: float,
    ) -> Moved:
        h = dt / self.substeps
        dv_max = self.a_max * h
        R, N = active.shape
        live = np.array(active, dtype=bool)
        for sp in spaces:
            self._hook(sp)
            sp.contacts.clear()  # type: ignore[attr-defined]
        dynamic = np.stack([sp.dynamic for sp in spaces])
        angles = np.zeros((R, N))
        used: bytes | None = None  # the angles ``want`` was last computed from
        for _ in range(self.substeps):  # the runs are independent: every run's substep, then the next
            state = np.stack([sp.bodies() for sp in spaces])  # (R, N, 6): x, y, angle, vx, vy, w
            if self.drive != "holonomic":
                angles = np.where(live, state[..., 2], angles)
            if used != angles.tobytes():  # elementwise in the angles: the same angles, the same want
                want = command_velocity(self.drive, command, angles, self.v_max)  # one call for all
                used = angles.tobytes()
            velocity, spin = self._track(state, want, command, live & dynamic, h, dv_max)
            for r, sp in enumerate(spaces):
                sp.set_velocities(velocity[r], spin[r])
                sp.space.step(h)
                if sp.contacts:  # type: ignore[attr-defined]
                    for i in list(sp.contacts):  # type: ignore[attr-defined]
                        sp.disable(i)
                        live[r, i] = False
                        dynamic[r, i] = sp.dynamic[i]
        hit = np.zeros((R, N), dtype=bool)
        for r, sp in enumerate(spaces):
            hit[r, list(sp.contacts)] = True  # type: ignore[attr-defined]
        hit &= active
        state = np.stack([sp.bodies() for sp in spaces])
        return Moved(state[..., 0:2].copy(), wrap_angle(state[..., 2]), state[..., 3:5].copy(), hit)

    def _track(self, state: np.ndarray, want: np.ndarray, command: np.ndarray, track: np.ndarray, h: float,
               dv_max: float) -> tuple[np.ndarray, np.ndarray]:
        """The velocities (R, N, 2) and angular velocities (R, N) the bodies get this substep
        (``state``: :meth:`RunSpace.bodies` of every run). A tracked body's velocity moves one
        step of at most ``dv_max`` toward ``want``; holonomic and mecanum bodies do not spin, a
        differential one keeps only the forward part of its velocity (no skid) and turns toward
        the commanded rate. The others keep theirs."""
        velocity, spin = state[..., 3:5], state[..., 5]
        if self.drive == "differential":
            fwd = np.stack([np.cos(state[..., 2]), np.sin(state[..., 2])], axis=-1)
            along = velocity[..., 0] * fwd[..., 0] + velocity[..., 1] * fwd[..., 1]
            start = fwd * along[..., None]
            to_spin = spin + np.clip(command[..., 1] - spin, -self.a_max * h * 4, self.a_max * h * 4)
        else:
            start, to_spin = velocity, np.zeros_like(spin)
        d = want - start
        norm = np.hypot(d[..., 0], d[..., 1])
        over = norm > dv_max
        k = np.divide(dv_max, norm, out=np.ones_like(norm), where=over)
        d = np.where(over[..., None], d * k[..., None], d)
        return np.where(track[..., None], start + d, velocity), np.where(track, to_spin, spin)
