"""Six-sector sensing in an open sea: robots are the only bodies (Rossides Ch. 8, §8.1, p. 174;
§8.2, p. 182).

The same reading as :func:`shoal.engine.robots.sensing.sense` gives for a world without circles,
polygons or walls, where every robot is a disc of radius ``robot_radius``, computed from
pairwise distances in numpy instead of pymunk point queries (about 50× cheaper per
robot-step; tests/test_sonar.py checks both agree):

- the gap to robot j is |x_j − x_i| − 2·radius, clipped at 0, kept if ≤ the sensing range;
- its sector is that of the bearing to x_j (the closest point of a disc lies on that line;
  a robot exactly on top of another sees it at −90°, as pymunk's circle query does);
- ``point`` is the closest point of j's disc, ``centre`` is x_j; ties in gap go to the
  lower robot index.
"""

from __future__ import annotations

import numpy as np

from .sensing import SECTORS, SectorReading, sector_of


def pairwise(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Offsets d[r, i, j] = x_j − x_i (R, N, N, 2) and their lengths (R, N, N)."""
    x = np.asarray(x, dtype=float)
    d = x[:, None, :, :] - x[:, :, None, :]
    return d, np.linalg.norm(d, axis=-1)


def contacts(dist: np.ndarray, robot_radius: float) -> np.ndarray:
    """(R,) number of robots whose disc touches or overlaps another's, from ``pairwise`` lengths."""
    N = dist.shape[-1]
    touching = (dist < 2.0 * robot_radius) & ~np.eye(N, dtype=bool)
    return touching.any(axis=-1).sum(axis=-1)


def sense_robots(
    x: np.ndarray,
    heading: np.ndarray | None = None,
    *,
    robot_radius: float,
    sensing_range: float,
    robot_frame: bool = True,
    pair: tuple[np.ndarray, np.ndarray] | None = None,
) -> SectorReading:
    """Six-sector reading (R, N, 6) of robots at ``x`` (R, N, 2) that sense only each other.

    ``heading`` (R, N) is needed with ``robot_frame`` (sectors relative to the bow);
    ``pair`` may pass precomputed :func:`pairwise` output.
    """
    x = np.asarray(x, dtype=float)
    R, N = x.shape[:2]
    if sensing_range <= 0:
        raise ValueError("sensing_range: must be > 0")
    if robot_frame and heading is None:
        raise ValueError("heading: needed with robot_frame=True")
    d, dist = pairwise(x) if pair is None else pair
    gap = np.maximum(dist - 2.0 * robot_radius, 0.0)
    seen = (gap <= sensing_range) & ~np.eye(N, dtype=bool)
    here = dist > 0
    bearing = np.where(here, np.arctan2(d[..., 1], d[..., 0]), -0.5 * np.pi)  # pymunk: gradient (0, 1)
    if robot_frame:
        bearing = bearing - np.asarray(heading, dtype=float)[..., None]
    sec = sector_of(bearing)  # (R, N, N)
    cand = np.where(seen[..., None, :] & (sec[..., None, :] == np.arange(SECTORS)[:, None]), gap[..., None, :], np.inf)
    j = np.argmin(cand, axis=-1)  # (R, N, 6), first (lowest index) of equal gaps
    g = np.take_along_axis(cand, j[..., None], -1)[..., 0]
    hit = np.isfinite(g)
    runs = np.arange(R)[:, None, None]
    centre = x[runs, j]  # (R, N, 6, 2)
    unit = np.where(here[..., None], -d / np.where(here, dist, 1.0)[..., None], np.array([0.0, 1.0]))  # j → i
    point = centre + robot_radius * unit[runs, np.arange(N)[None, :, None], j]
    nan = np.full(point.shape, np.nan)
    return SectorReading(
        gap=np.where(hit, g, float(sensing_range)),
        point=np.where(hit[..., None], point, nan),
        centre=np.where(hit[..., None], centre, nan),
        hit=hit,
    )
