"""pymunk's point and swept-disc queries for circles and thick segments, compiled (numba).

The compiled fleet tick (:mod:`.kernels`) senses and sweeps without pymunk. These functions
repeat the arithmetic of the physics library inside pymunk 7 (Munk2D, a Chipmunk2D fork)
operation for operation, in the same order, so they return the same bits as
``Space.point_query``, ``Shape.segment_query`` and ``Space.bb_query`` for the shapes a world
is made of (robot and obstacle circles, wall segments); ``tests/test_kernels.py`` checks that
against pymunk on random scenes. Polygons are not here: a world with polygons keeps the
pymunk path.

A circle is its centre and radius; a segment its end points ``a``, ``b``, radius and unit
normal ``n`` (:func:`segment_normal`).
"""

from __future__ import annotations

import math
import sys

from ..core.compiled import kernel

SMALL = 1e-5  # below this distance a point query's gradient falls back to a fixed direction
TINY = sys.float_info.min  # added to a length before dividing, so a zero vector stays zero


@kernel
def clamp01(f: float) -> float:
    """f limited to [0, 1] with the library's comparisons (so NaN becomes 0)."""
    f = f if f < 1.0 else 1.0
    return f if f > 0.0 else 0.0


@kernel
def normalize(x: float, y: float) -> tuple[float, float]:
    """(x, y) scaled to unit length; (0, 0) stays (0, 0)."""
    s = 1.0 / (math.sqrt(x * x + y * y) + TINY)
    return x * s, y * s


@kernel
def segment_normal(ax: float, ay: float, bx: float, by: float) -> tuple[float, float]:
    """The unit normal of segment a→b as the library stores it (b − a turned clockwise)."""
    ux, uy = normalize(bx - ax, by - ay)
    return uy, -ux


@kernel
def circle_point(px: float, py: float, cx: float, cy: float, r: float) -> tuple[float, float, float, float, float]:
    """Point query of a circle: (distance from p to the surface, negative inside; closest
    point x, y; gradient x, y)."""
    dx, dy = px - cx, py - cy
    d = math.sqrt(dx * dx + dy * dy)
    k = r / d if d > 0.0 else r
    qx, qy = cx + dx * k, cy + dy * k
    if d > SMALL:
        inv = 1.0 / d
        return d - r, qx, qy, dx * inv, dy * inv
    return d - r, qx, qy, 0.0, 1.0


@kernel
def segment_point(px: float, py: float, ax: float, ay: float, bx: float, by: float, r: float, nx: float,
                  ny: float) -> tuple[float, float, float, float, float]:
    """Point query of a thick segment, as :func:`circle_point`."""
    ex, ey = ax - bx, ay - by
    t = clamp01((ex * (px - bx) + ey * (py - by)) / (ex * ex + ey * ey))
    cx, cy = bx + ex * t, by + ey * t
    dx, dy = px - cx, py - cy
    d = math.sqrt(dx * dx + dy * dy)
    inv = 1.0 / d if d != 0.0 else math.inf
    gx, gy = dx * inv, dy * inv
    qx, qy = (cx + gx * r, cy + gy * r) if d != 0.0 else (cx, cy)
    if d > SMALL:
        return d - r, qx, qy, gx, gy
    return d - r, qx, qy, nx, ny


@kernel
def _circle_sweep(cx: float, cy: float, r1: float, ax: float, ay: float, bx: float, by: float, r2: float) -> float:
    """First contact (fraction of a→b) of a disc of radius r2 swept from a to b with a circle;
    −1 for none (the library's circle-segment query without the start test)."""
    dax, day = ax - cx, ay - cy
    dbx, dby = bx - cx, by - cy
    rsum = r1 + r2
    aa = dax * dax + day * day
    ab = dax * dbx + day * dby
    bb = dbx * dbx + dby * dby
    qa = aa - 2.0 * ab + bb
    qb = ab - aa
    det = qb * qb - qa * (aa - rsum * rsum)
    if det >= 0.0:
        t = (-qb - math.sqrt(det)) / qa
        if 0.0 <= t and t <= 1.0:
            return t
    return -1.0


@kernel
def circle_sweep(cx: float, cy: float, r: float, ax: float, ay: float, bx: float, by: float, rad: float) -> float:
    """``Shape.segment_query(a, b, rad)`` of a circle: the fraction of a→b at which a disc of
    radius ``rad`` first touches it (0 if it touches at a), −1 for none."""
    if circle_point(ax, ay, cx, cy, r)[0] <= rad:
        return 0.0
    return _circle_sweep(cx, cy, r, ax, ay, bx, by, rad)


@kernel
def segment_sweep(sax: float, say: float, sbx: float, sby: float, sr: float, nx: float, ny: float, ax: float,
                  ay: float, bx: float, by: float, rad: float) -> float:
    """``Shape.segment_query(a, b, rad)`` of a thick segment, as :func:`circle_sweep`."""
    if segment_point(ax, ay, sax, say, sbx, sby, sr, nx, ny)[0] <= rad:
        return 0.0
    d = (sax - ax) * nx + (say - ay) * ny
    r = sr + rad
    fx, fy = (-nx, -ny) if d > 0.0 else (nx, ny)
    ox, oy = fx * r - ax, fy * r - ay
    s_ax, s_ay = sax + ox, say + oy
    s_bx, s_by = sbx + ox, sby + oy
    ex, ey = bx - ax, by - ay
    if (ex * s_ay - ey * s_ax) * (ex * s_by - ey * s_bx) <= 0.0:
        d_offset = d + (-r if d > 0.0 else r)
        ad = -d_offset
        bd = (ex * nx + ey * ny) - d_offset
        if ad * bd < 0.0:
            return ad / (ad - bd)
        return -1.0
    if r != 0.0:
        t1 = _circle_sweep(sax, say, sr, ax, ay, bx, by, rad)
        t2 = _circle_sweep(sbx, sby, sr, ax, ay, bx, by, rad)
        a1 = t1 if t1 >= 0.0 else 1.0  # a miss reads alpha 1, as the library's blank answer
        a2 = t2 if t2 >= 0.0 else 1.0
        return t1 if a1 < a2 else t2
    return -1.0


@kernel
def bb_overlap(l1: float, b1: float, r1: float, t1: float, l2: float, b2: float, r2: float, t2: float) -> bool:
    """Two bounding boxes (left, bottom, right, top) intersect (touching counts)."""
    return l1 <= r2 and l2 <= r1 and b1 <= t2 and b2 <= t1


@kernel
def segment_box(ax: float, ay: float, bx: float, by: float, r: float) -> tuple[float, float, float, float]:
    """The bounding box the library caches for a thick segment."""
    lo_x, hi_x = (ax, bx) if ax < bx else (bx, ax)
    lo_y, hi_y = (ay, by) if ay < by else (by, ay)
    return lo_x - r, lo_y - r, hi_x + r, hi_y + r
