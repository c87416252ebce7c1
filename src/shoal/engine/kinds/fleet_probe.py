"""One robot of a fleet as its controller sees it now: the six-sector reading at its current
position, the coefficients (DVC budget or constants) and the virtual force F_t it gets from
that reading.

This is exactly what the next :meth:`Fleet.step` computes for the robot when all robots
sense before any moves (``update = "simultaneous"``, and always for robot 0); with the
sequential update the robots moved earlier in the same tick can change what it senses.
Nothing in the fleet is changed.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..robots.sensing import sense, virtual_force
from .fleet import Fleet


@dataclass(frozen=True)
class RobotView:
    robot: int
    x: np.ndarray  # (2,) position
    heading: float  # rad
    frame_angle: float  # sectors are measured from this angle: the heading (body frame) or 0
    gap: np.ndarray  # (6,) gap per sector, the sensing range where empty
    point: np.ndarray  # (6, 2) closest point per sector, nan where empty
    hit: np.ndarray  # (6,) bool
    omega: float
    c: np.ndarray  # (n,) coefficients: c1, c2, c3 (omni) or c1..c5 (non-omni)
    force: np.ndarray  # (2,) F_t [4.3] (zero for body-frame laws, which use none)


def robot_view(fleet: Fleet, robot: int, run: int = 0) -> RobotView:
    """What robot ``robot`` of run ``run`` senses now, and the budget that gives it."""
    p, s = fleet.params, fleet.state
    R, N = s.status.shape
    if not (0 <= robot < N and 0 <= run < R):
        raise IndexError(f"robot {robot} of run {run}: the fleet has {N} robots and {R} runs")
    active = np.zeros((R, N), bool)
    active[run, robot] = True
    reading = sense(fleet.spaces, s.x, s.heading, sensing_range=p.sensing_range, robot_frame=p.body_frame,
                    active=active)
    gap = reading.gap
    if p.s_min > 0:  # as in Fleet.step (Rossides §5.4, p. 125)
        gap = np.maximum(gap - p.s_min, 0.0)
    omega, c = fleet._coefficients(gap)
    force = np.zeros_like(s.x) if p.body_frame else virtual_force(s.x, reading, p.gamma)
    heading = float(s.heading[run, robot])
    return RobotView(
        robot=robot, x=s.x[run, robot].copy(), heading=heading, frame_angle=heading if p.body_frame else 0.0,
        gap=reading.gap[run, robot].copy(), point=reading.point[run, robot].copy(),
        hit=reading.hit[run, robot].copy(), omega=float(omega[run, robot]), c=c[:, run, robot].copy(),
        force=force[run, robot].copy(),
    )
