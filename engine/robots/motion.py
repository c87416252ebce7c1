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
from .world import OBSTACLE, ROBOT, RunSpace

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


def first_contact(sp: RunSpace, start: tuple[float, float], end: tuple[float, float], i: int,
                  inset: float = 0.0) -> float | None:
    """Fraction of the way from ``start`` to ``end`` at which robot ``i``'s disc, shrunk by
    ``inset`` metres, first touches another body of ``sp`` (None: a free path). With an
    inset it answers whether the full disc would overlap a body by more than ``inset``.

    ``Space.segment_query_first`` with a radius is not used: its broad phase tests the bare
    centre line against the bounding boxes, so it misses a body that the disc grazes while
    the line passes beside its box. Candidates come from a bounding-box query of the whole
    swept disc instead, and each is tested exactly with ``Shape.segment_query``.
    """
    rad = sp.robot_radius - inset
    bb = pymunk.BB(min(start[0], end[0]) - rad, min(start[1], end[1]) - rad,
                   max(start[0], end[0]) + rad, max(start[1], end[1]) + rad)
    best = None
    for shape in sp.space.bb_query(bb, sp.filters[i]):
        q = shape.segment_query(start, end, rad)
        if q is not None and (best is None or q.alpha < best):
            best = q.alpha
    return best


class Kinematic:
    """Exact position update ([3.10]/[4.6], or the arc [5.5]–[5.10] for differential drive).

    Contacts: each robot's path is swept as a disc against the world and the other
    robots (:func:`first_contact`) and stops at the first contact. The contact is a
    collision (``hit``) only when the path would have carried the disc more than
    ``tolerance`` metres into the body; a shallower touch just stops the robot. Robots are
    moved one after another in the space, so a later sweep sees an earlier robot's new
    position; the space must hold every robot at ``x`` when ``move`` is called.
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
        for r, sp in enumerate(spaces):  # the space holds every robot at x (kept in sync)
            for i in np.flatnonzero(active[r]):
                start, end = tuple(x[r, i]), tuple(target[r, i])
                if start != end:
                    alpha = first_contact(sp, start, end, i)
                    if alpha is not None:  # stop where the swept disc first touches
                        new_x[r, i] = x[r, i] + max(alpha - 1e-6, 0.0) * (target[r, i] - x[r, i])
                        hit[r, i] = self.tolerance <= 0 or first_contact(sp, start, end, i, self.tolerance) is not None
                    sp.move_robot(i, new_x[r, i])
        velocity = (new_x - x) / dt
        return Moved(new_x, wrap_angle(new_heading), velocity, hit)


class Physics:
    """pymunk bodies with mass that track the commanded velocity within ``a_max``.

    Each control tick is split into ``substeps``; per substep the body velocity moves
    toward the drive's realisable velocity by at most a_max·h, differential-drive bodies
    also turn toward the commanded rate and lose their sideways velocity (no skid).
    Contacts come from pymunk's collision callback: a contact whose overlap exceeds
    ``tolerance`` metres in some substep is a collision, and a collided body becomes
    kinematic with zero velocity, i.e. it stays where it stopped.
    """

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

        sp.space.on_collision(ROBOT, OBSTACLE, pre_solve=pre_solve)
        sp.space.on_collision(ROBOT, ROBOT, pre_solve=pre_solve)
        self._hooked.add(id(sp))

    def move(
        self, spaces: Sequence[RunSpace], x: np.ndarray, heading: np.ndarray, command: np.ndarray,
        active: np.ndarray, dt: float,
    ) -> Moved:
        h = dt / self.substeps
        dv_max = self.a_max * h
        R, N = active.shape
        new_x, new_heading, velocity = np.empty_like(x), np.empty_like(heading), np.zeros_like(x)
        hit = np.zeros((R, N), dtype=bool)
        live = [np.flatnonzero(active[r]).tolist() for r in range(R)]
        for sp in spaces:
            self._hook(sp)
            sp.contacts.clear()  # type: ignore[attr-defined]
        angles = np.zeros((R, N))
        for _ in range(self.substeps):  # the runs are independent: every run's substep, then the next
            if self.drive != "holonomic":
                for r, sp in enumerate(spaces):
                    bodies = sp.robot_bodies
                    angles[r, live[r]] = [bodies[i].angle for i in live[r]]
            want = command_velocity(self.drive, command, angles, self.v_max)  # elementwise: one call for all
            for r, sp in enumerate(spaces):
                if live[r]:
                    if self.drive == "differential":
                        self._track_differential(sp, live[r], want[r, live[r]], command[r], h, dv_max)
                    else:
                        self._track(sp, live[r], want[r, live[r]].tolist(), dv_max)
                sp.space.step(h)
                if sp.contacts:  # type: ignore[attr-defined]
                    for i in list(sp.contacts):  # type: ignore[attr-defined]
                        self._disable(sp, i)
                    live[r] = [i for i in live[r] if i not in sp.contacts]  # type: ignore[attr-defined]
        for r, sp in enumerate(spaces):
            hit[r, list(sp.contacts)] = True  # type: ignore[attr-defined]
            hit[r] &= active[r]
            new_x[r] = sp.positions()
            new_heading[r] = [b.angle for b in sp.robot_bodies]
            velocity[r] = [tuple(b.velocity) for b in sp.robot_bodies]
        return Moved(new_x, wrap_angle(new_heading), velocity, hit)

    @staticmethod
    def _track(sp: RunSpace, live: list[int], want: list[list[float]], dv_max: float) -> None:
        """Each dynamic body's velocity one step of at most ``dv_max`` toward ``want`` (plain
        floats: this runs for every body at every substep)."""
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

    def _track_differential(self, sp: RunSpace, live: list[int], want: np.ndarray, command: np.ndarray, h: float,
                            dv_max: float) -> None:
        """:meth:`_track` for a differential drive: no skid (only the forward part of the
        velocity is kept) and the turn rate tracks the commanded one."""
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
    def _disable(sp: RunSpace, i: int) -> None:
        body = sp.robot_bodies[i]
        if body.body_type == pymunk.Body.DYNAMIC:
            body.body_type = pymunk.Body.KINEMATIC
            body.velocity = (0.0, 0.0)
            body.angular_velocity = 0.0
