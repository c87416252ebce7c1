"""Six-sector range sensing and virtual repulsive forces (Figs. 4-3, 5-3; [4.3], [4.4]).

Each robot splits its surroundings into six 60° sectors and keeps only the closest body
(obstacle, wall or other robot, disabled robots included) in each, as a LiDAR would
(Rossides §4.3.2, p. 96). Sector k (0-based) covers bearings [−180° + 60k, −120° + 60k), measured
from the world x-axis, or from the robot's heading with ``robot_frame=True`` (docs/readings.md,
"Sectors fixed to the world in Chapter 4", "Sector layout of the non-omnidirectional
controller"). The thesis numbers them 1–6; sectors 1–3 are on the right, 4–6 on the left.

Choices the thesis leaves open (docs/readings.md, "Empty sensor sectors and gaps"):

- a gap is surface to surface (robot radius subtracted), clipped at 0, and kept if it is
  at most the sensing range; an empty sector reads the range;
- a body belongs to the sector of the bearing to its closest point, so a circle that
  straddles a sector border counts once, in the sector of its closest point. When the
  robot's centre lies inside a body (deep overlap after a collision) that bearing is taken
  along the body's inward distance gradient instead.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Iterable, Sequence

import numpy as np

from .world import RunSpace

SECTORS = 6
RIGHT = (0, 1, 2)
LEFT = (3, 4, 5)
FRONT = (1, 2, 3, 4)
S_FLOOR = 1e-3  # m: smallest gap used in [4.4], so contact (s_p = 0) gives a finite force


@dataclass
class SectorReading:
    """The closest body in each of the six sectors of every robot of every run."""

    gap: np.ndarray  # (R, N, 6) gap to that body, 0 = contact, sensing range if empty
    point: np.ndarray  # (R, N, 6, 2) its closest point (nan where empty)
    centre: np.ndarray  # (R, N, 6, 2) x_p of [4.4]: circle/robot centre, else the closest point
    hit: np.ndarray  # (R, N, 6) bool, a body was seen


def sector_of(bearing: np.ndarray) -> np.ndarray:
    """Sector index 0..5 of bearings in radians (any range; +180° falls in sector 0)."""
    k = np.floor((np.asarray(bearing) + np.pi) / (np.pi / 3)).astype(int)
    return np.mod(k, SECTORS)


def _query(space: RunSpace, x: np.ndarray, todo: Iterable[int], max_d: float, base: int, key0: int, out: tuple) -> None:
    """pymunk point queries for the robots ``todo`` at ``x`` (N, 2), appended to ``out``:
    flat robot row (``base + i``), body key, and per hit closest point (2), gradient (2) and
    distance from the robot centre. Keys index the centre table: ``key0`` + robot index,
    ``key0 + N`` + circle index, or −1 (walls, polygons: no centre)."""
    rows, keys, nums = out
    key_of = space.body_keys()
    query, filters, xs = space.space.point_query, space.filters, x.tolist()
    for i in todo:
        hits = query(xs[i], max_d, filters[i])
        if not hits:
            continue
        rows.extend([base + i] * len(hits))
        for h in hits:
            k = key_of.get(h.shape, -1)
            keys.append(k + key0 if k >= 0 else -1)
            nums.append((*h.point, *h.gradient, h.distance))


def _robot_centres(space: RunSpace, keys: list[int], key0: int) -> np.ndarray:
    """(N, 2) centre table of the robots of ``space``: the bodies' positions for the robots
    some query hit (keys ``key0 … key0 + N − 1``), zeros for the rest (never read). Reading
    only those bodies keeps a sequential tick of many small groups from reading every body
    per group."""
    n = space.n_robots
    k = np.asarray(keys, dtype=np.int64) - key0
    seen = np.unique(k[(k >= 0) & (k < n)]).tolist()
    table = np.zeros((n, 2))
    if seen:
        bodies = space.robot_bodies
        table[seen] = [tuple(bodies[i].position) for i in seen]
    return table


def sense(
    spaces: Sequence[RunSpace],
    x: np.ndarray,
    heading: np.ndarray | None = None,
    *,
    sensing_range: float = 3.0,
    robot_frame: bool = False,
    active: np.ndarray | None = None,
) -> SectorReading:
    """Six-sector reading of every robot at ``x`` (R, N, 2) in run r's space ``spaces[r]``.

    Queries start at ``x``; the other robots are wherever their bodies are in the space
    (keep them in sync with ``RunSpace.set_positions``). Robots with ``active`` False
    (R, N) are not queried and read empty sectors, but still count as bodies for others.
    ``heading`` (R, N) is needed only with ``robot_frame``.
    """
    x = np.asarray(x, dtype=float)
    R, N = x.shape[:2]
    if len(spaces) != R:
        raise ValueError(f"spaces: {len(spaces)} spaces for {R} runs")
    if sensing_range <= 0:
        raise ValueError("sensing_range: must be > 0")
    if robot_frame and heading is None:
        raise ValueError("heading: needed with robot_frame=True")
    act = np.ones((R, N), bool) if active is None else np.broadcast_to(np.asarray(active, bool), (R, N))
    out: tuple[list, list, list] = ([], [], [])
    table: list[np.ndarray] = []  # centres: each run's robots, then its circles
    key0 = 0
    radius = np.empty(R)
    for r, sp in enumerate(spaces):
        if sp.n_robots != N:
            raise ValueError(f"spaces[{r}]: {sp.n_robots} robots, x has {N}")
        radius[r] = sp.robot_radius
        n_before = len(out[0])
        _query(sp, x[r], np.flatnonzero(act[r]).tolist(), sensing_range + sp.robot_radius, r * N, key0, out)
        if len(out[0]) > n_before:
            table.append(_robot_centres(sp, out[1][n_before:], key0))
            table.append(sp.spec.circles[:, :2])
        else:
            table.append(np.zeros((N + len(sp.spec.circles), 2)))  # keeps key offsets, never read
        key0 += N + len(sp.spec.circles)
    gap = np.full((R * N * SECTORS,), float(sensing_range))
    point = np.full((R * N * SECTORS, 2), np.nan)
    centre = np.full((R * N * SECTORS, 2), np.nan)
    hit = np.zeros(R * N * SECTORS, bool)
    rows, keys, nums = out
    if rows:
        row, key, nums_ = np.asarray(rows), np.asarray(keys), np.asarray(nums, dtype=float)
        pts, grad, dist = nums_[:, :2], nums_[:, 2:4], nums_[:, 4]
        ctr = np.vstack(table)[np.maximum(key, 0)]
        ctr = np.where((key >= 0)[:, None], ctr, pts)  # walls and polygons: the closest point
        g = np.maximum(dist - np.repeat(radius, N)[row], 0.0)
        keep = g <= sensing_range
        origin = x.reshape(R * N, 2)[row]
        to_pt = np.where((dist > 0)[:, None], pts - origin, -grad)  # inside a body: inward gradient
        bearing = np.arctan2(to_pt[:, 1], to_pt[:, 0])
        if robot_frame:
            bearing = bearing - np.asarray(heading, dtype=float).reshape(R * N)[row]
        cell = row * SECTORS + sector_of(bearing)
        idx = np.flatnonzero(keep)
        idx = idx[np.lexsort((g[idx], cell[idx]))]  # by cell, closest first
        first = idx[np.r_[True, cell[idx][1:] != cell[idx][:-1]]] if idx.size else idx
        c = cell[first]
        gap[c], point[c], centre[c], hit[c] = g[first], pts[first], ctr[first], True
    return SectorReading(
        gap=gap.reshape(R, N, SECTORS),
        point=point.reshape(R, N, SECTORS, 2),
        centre=centre.reshape(R, N, SECTORS, 2),
        hit=hit.reshape(R, N, SECTORS),
    )


def virtual_force(x: np.ndarray, reading: SectorReading, gamma: float = 1.0, s_floor: float = S_FLOOR) -> np.ndarray:
    """(R, N, 2) total virtual force F_t = Σ_p γ (x_i − x_p)/(s_p |x_i − x_p|) over the kept
    bodies [4.3], [4.4]. s_p is floored at ``s_floor`` (contact stays finite) and the direction
    is zero when x_i = x_p."""
    diff = np.asarray(x, dtype=float)[:, :, None, :] - reading.centre  # (R, N, 6, 2)
    ok = reading.hit & np.all(np.isfinite(diff), axis=-1)
    diff = np.where(ok[..., None], diff, 0.0)
    norm = np.linalg.norm(diff, axis=-1)
    unit = diff / np.where(norm > 0, norm, 1.0)[..., None]
    s = np.maximum(np.where(ok, reading.gap, 1.0), s_floor)
    return np.sum(gamma * unit / s[..., None], axis=2)  # [4.4] summed [4.3]


def sorted_gaps(reading: SectorReading, sectors: Sequence[int] | None = None) -> np.ndarray:
    """(R, N, k) gaps of ``sectors`` (default all six) sorted ascending: the s, sr, sl, sf
    lists of Algorithm 2 (Rossides §5.2.2, p. 119) with sectors ``None``, ``RIGHT``, ``LEFT``, ``FRONT``."""
    g = reading.gap if sectors is None else reading.gap[..., list(sectors)]
    return np.sort(g, axis=-1)
