"""Flat 2-D shapes as arrays for viser nodes: disc and wedge meshes (triangle fans facing +z),
and circles, dashes, arrows and trails as line segments ``(S, 2, 2)``. Pure numpy, no viser.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike


def fan_mesh(a0: float, a1: float, segments: int) -> tuple[np.ndarray, np.ndarray]:
    """Vertices (K+2, 3) and faces (K, 3) of a unit-radius fan from angle ``a0`` to ``a1``
    (radians, counter-clockwise), centred at the origin in the z = 0 plane."""
    ang = np.linspace(a0, a1, segments + 1)
    rim = np.column_stack([np.cos(ang), np.sin(ang), np.zeros_like(ang)])
    vertices = np.vstack([np.zeros((1, 3)), rim]).astype(np.float32)
    i = np.arange(1, segments + 1)
    faces = np.column_stack([np.zeros(segments, int), i, i + 1]).astype(np.uint32)
    return vertices, faces


def disc_mesh(segments: int = 32) -> tuple[np.ndarray, np.ndarray]:
    """A unit disc."""
    return fan_mesh(0.0, 2 * math.pi, segments)


def wedge_mesh(angle: float = math.pi / 3, segments: int = 12) -> tuple[np.ndarray, np.ndarray]:
    """A unit wedge from angle 0 to ``angle``."""
    return fan_mesh(0.0, angle, segments)


def yaw_wxyz(angle: np.ndarray) -> np.ndarray:
    """(…, 4) quaternions (w, x, y, z) of rotations by ``angle`` about +z."""
    a = np.asarray(angle, dtype=float) / 2
    out = np.zeros(a.shape + (4,), np.float32)
    out[..., 0], out[..., 3] = np.cos(a), np.sin(a)
    return out


def plane(points: np.ndarray) -> np.ndarray:
    """(…, d) points → (…, 2) in the ground plane: d = 1 lies on the x axis, d = 3 drops z."""
    p = np.asarray(points, dtype=float)
    if p.shape[-1] >= 2:
        return p[..., :2]
    return np.concatenate([p, np.zeros(p.shape[:-1] + (2 - p.shape[-1],))], axis=-1)


def lift(points: np.ndarray, z: float) -> np.ndarray:
    """(…, 2) → (…, 3) float32 at height ``z``."""
    p = np.asarray(points, dtype=float)
    out = np.empty(p.shape[:-1] + (3,), np.float32)
    out[..., :2], out[..., 2] = p[..., :2], z
    return out


def polyline(points: np.ndarray, closed: bool = False) -> np.ndarray:
    """(P, 2) points → (S, 2, 2) segments joining them in order."""
    p = np.asarray(points, dtype=float)
    if closed:
        p = np.vstack([p, p[:1]])
    return np.stack([p[:-1], p[1:]], axis=1)


def trail_segments(trails: np.ndarray) -> np.ndarray:
    """(M, L, d) trails → (S, 2, 2) segments in the ground plane (empty for no trail)."""
    tr = np.asarray(trails, dtype=float)
    if tr.ndim != 3 or not tr.shape[0] or tr.shape[1] < 2:
        return np.zeros((0, 2, 2))
    xy = plane(tr)
    return np.stack([xy[:, :-1], xy[:, 1:]], axis=2).reshape(-1, 2, 2)


def dashes(segs: np.ndarray, parts: int = 9) -> np.ndarray:
    """(S, 2, 2) segments → their dashes: each cut into ``parts`` (odd) pieces, every other one
    kept, the first and the last among them (a dashed line's second cue: not its colour alone)."""
    segs = np.asarray(segs, dtype=float).reshape(-1, 2, 2)
    t = np.linspace(0.0, 1.0, parts + 1)
    a, b = segs[:, None, 0], segs[:, None, 1]
    points = a + (b - a) * t[None, :, None]  # (S, parts + 1, 2)
    return np.stack([points[:, 0:-1:2], points[:, 1::2]], axis=2).reshape(-1, 2, 2)


def grid_segments(lo: np.ndarray, hi: np.ndarray, origin: np.ndarray, cell: float,
                  every: int = 5) -> tuple[np.ndarray, np.ndarray]:
    """The lines of a grid over the box ``lo``–``hi`` at ``origin`` + k ``cell`` (k whole), as
    (S, 2, 2) segments: (the cell lines, the section lines: every ``every``-th, k = 0 among them)."""
    lo, hi, origin = (np.asarray(v, dtype=float) for v in (lo, hi, origin))
    cells: list[np.ndarray] = []
    sections: list[np.ndarray] = []
    for axis in (0, 1):
        first, last = (lo[axis] - origin[axis]) / cell, (hi[axis] - origin[axis]) / cell
        k = np.arange(np.ceil(first - 1e-9), np.floor(last + 1e-9) + 1)
        at = origin[axis] + k * cell
        seg = np.zeros((len(at), 2, 2))
        seg[:, :, axis] = at[:, None]
        seg[:, 0, 1 - axis], seg[:, 1, 1 - axis] = lo[1 - axis], hi[1 - axis]
        section = np.round(k).astype(int) % every == 0
        cells.append(seg[~section])
        sections.append(seg[section])
    return np.concatenate(cells), np.concatenate(sections)


def circle_segments(centre: np.ndarray, radius: float, n: int = 64) -> np.ndarray:
    """(n, 2, 2) segments of a circle."""
    ang = np.linspace(0.0, 2 * math.pi, n, endpoint=False)
    pts = np.asarray(centre, dtype=float) + radius * np.column_stack([np.cos(ang), np.sin(ang)])
    return polyline(pts, closed=True)


def rays(centre: np.ndarray, angles: np.ndarray, r0: float, r1: float) -> np.ndarray:
    """(K, 2, 2) radial segments from radius ``r0`` to ``r1`` at ``angles``."""
    d = np.column_stack([np.cos(angles), np.sin(angles)])
    c = np.asarray(centre, dtype=float)
    return np.stack([c + r0 * d, c + r1 * d], axis=1)


def dashed(a: ArrayLike, b: ArrayLike, dash: float, gap: float) -> np.ndarray:
    """(S, 2, 2) dashes along the segment a → b."""
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    length = float(np.hypot(*(b - a)))
    if length == 0:
        return np.zeros((0, 2, 2))
    unit = (b - a) / length
    starts = np.arange(0.0, length, dash + gap)
    ends = np.minimum(starts + dash, length)
    return np.stack([a + starts[:, None] * unit, a + ends[:, None] * unit], axis=1)


def arrow(start: np.ndarray, vec: np.ndarray, head: float = 0.3, spread: float = 0.45) -> np.ndarray:
    """(3, 2, 2) segments: a shaft from ``start`` along ``vec`` and two head strokes
    (``head`` is the strokes' length as a fraction of the shaft)."""
    s, v = np.asarray(start, dtype=float), np.asarray(vec, dtype=float)
    tip = s + v
    back = -v * head
    c, si = math.cos(spread), math.sin(spread)
    left = np.array([c * back[0] - si * back[1], si * back[0] + c * back[1]])
    right = np.array([c * back[0] + si * back[1], -si * back[0] + c * back[1]])
    return np.stack([[s, tip], [tip, tip + left], [tip, tip + right]])


def ray_ground(origin: Any, direction: Any) -> np.ndarray | None:
    """Where a click ray (scene coordinates) meets the ground z = 0: (x, y), or None if it misses."""
    o, d = np.asarray(origin, dtype=float), np.asarray(direction, dtype=float)
    if abs(d[2]) < 1e-9:
        return None
    t = -o[2] / d[2]
    return None if t < 0 else (o + t * d)[:2]
