"""Source entrapment and escorting (Rossides §8.2, p. 182; [8.7], [8.8]).
See docs/readings.md, "The escort ring's gap".

The global best y_g is handed to the non-omnidirectional controller as a virtual circular
obstacle of radius r_trap, so ordinary collision avoidance holds the swarm on a ring.
Sectors follow the sensing module: sector k covers bearings [−180° + 60k, −120° + 60k)
relative to the heading. The ring's gap is s_ring = max(|x − y_g| − r_trap, 0),
placed in the sector of the bearing to y_g; a robot inside the ring therefore reads contact
(gap 0) toward y_g, and its repulsion points outward. A robot exactly at y_g sees it dead ahead.
"""

from __future__ import annotations

import numpy as np

from ..robots.sensing import SECTORS, SectorReading, sector_of


def _centre(yg: np.ndarray) -> np.ndarray:
    """The ring's centre per robot: y_g (R, 2) shared by the swarm, or (R, N, 2) where each
    robot believes it is (SLO positions), broadcastable against (R, N, 2)."""
    yg = np.asarray(yg, dtype=float)
    return yg if yg.ndim == 3 else yg[:, None, :]


def _ring(x: np.ndarray, heading: np.ndarray, yg: np.ndarray, r_trap: float, robot_radius: float):
    """Per robot: surface gap to the ring, sector index, and the vector to y_g."""
    x = np.asarray(x, dtype=float)
    to = _centre(yg) - x  # (R, N, 2)
    dist = np.linalg.norm(to, axis=-1)
    gap = np.maximum(dist - r_trap - robot_radius, 0.0)
    bearing = np.where(dist > 0, np.arctan2(to[..., 1], to[..., 0]) - np.asarray(heading, dtype=float), 0.0)
    return gap, sector_of(bearing), to, dist


def escort_gap(
    x: np.ndarray,
    heading: np.ndarray,
    yg: np.ndarray,
    r_trap: float,
    *,
    sensing_range: float = np.inf,
    robot_radius: float = 0.0,
) -> np.ndarray:
    """(R, N, 6) gaps the ring at ``yg`` (R, 2) adds, for ``x`` (R, N, 2) and ``heading`` (R, N);
    ``yg`` may be (R, N, 2), each robot's own belief of the ring's centre.

    Every sector but the ring's reads ``sensing_range`` (and so does the ring's when it is
    further), so ``np.minimum(reading.gap, escort_gap(...))`` merges it into a reading.
    ``robot_radius`` (default 0: the gap from the robot's centre) makes the gap surface to surface.
    """
    gap, k, _, _ = _ring(x, heading, yg, r_trap, robot_radius)
    here = np.arange(SECTORS) == k[..., None]
    seen = here & (gap <= sensing_range)[..., None]
    return np.where(seen, gap[..., None], float(sensing_range))


def with_escort(
    reading: SectorReading,
    x: np.ndarray,
    heading: np.ndarray,
    yg: np.ndarray,
    r_trap: float,
    *,
    sensing_range: float,
    robot_radius: float = 0.0,
) -> SectorReading:
    """A copy of ``reading`` where the ring replaces the body of its sector if it is closer.

    Its closest point is on the ring toward the robot (y_g itself from inside) and its
    centre x_p [4.4] is y_g, so the virtual force pushes away from y_g.
    """
    gap, k, to, dist = _ring(x, heading, yg, r_trap, robot_radius)
    here = np.arange(SECTORS) == k[..., None]
    closer = here & (gap <= sensing_range)[..., None] & (gap[..., None] < reading.gap)
    unit = np.where((dist > 0)[..., None], to / np.where(dist > 0, dist, 1.0)[..., None], 0.0)
    outside = (dist > r_trap)[..., None]
    y = np.broadcast_to(_centre(yg), to.shape)
    point = np.where(outside, y - r_trap * unit, y)
    c = closer[..., None]
    return SectorReading(
        gap=np.where(closer, gap[..., None], reading.gap),
        point=np.where(c, point[:, :, None, :], reading.point),
        centre=np.where(c, y[:, :, None, :], reading.centre),
        hit=reading.hit | closer,
    )


def moving_source(
    x0: np.ndarray, heading: float | np.ndarray, v_n: float, v_max: float, dt: float, k: int | np.ndarray
) -> np.ndarray:
    """Source position after ``k`` steps at speed v_s = v_n·v_max [8.8] along ``heading``.

    The thesis moves it to the right (``heading`` = 0). ``x0`` (…, 2); ``k`` broadcasts.
    """
    v_s = v_n * v_max  # [8.8]
    h = np.asarray(heading, dtype=float)
    step = np.stack([np.cos(h), np.sin(h)], axis=-1) * v_s * dt
    return np.asarray(x0, dtype=float) + np.asarray(k, dtype=float)[..., None] * step
