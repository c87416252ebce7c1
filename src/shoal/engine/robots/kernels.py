"""The compiled fleet tick (phase B of Algorithms 1 and 2) for kinematic motion.

:meth:`shoal.engine.kinds.fleet.Fleet.step` in numpy senses, decides and moves each group of
robots that cannot interact within a tick, vectorised over the group, through pymunk queries
(:mod:`.sensing`, :mod:`.motion`); a packed swarm makes many small groups, so that path is
mostly Python overhead. :func:`phase_b` does the same per robot in compiled code: the same
greedy colouring into groups, the same order (a group senses and decides, then its robots
move one after another, then contacts are checked), the same equations in the same
floating-point order, and the queries of :mod:`.queries`, which give pymunk's bits. Nearby
robots and obstacles are found through uniform grids (:class:`Grid`), so a tick costs O(N)
for a swarm of constant density.

The numpy tick stays the reference (and the path of physics mode, where pymunk steps the
bodies, and of worlds with polygons); ``tests/test_kernels.py`` runs both on seeded scenes with
collisions in every kinematic mode and requires equal bits. Physics mode senses and checks
contacts with the same queries (:func:`sense_bodies`, :func:`touching_bodies`;
``tests/test_physics.py``). Where they may part, in cases
that need equality to the last bit: sensing breaks an exact tie between two bodies' gaps in
one sector by its own candidate order (pymunk by its tree's), and takes a bearing with the C
library's atan2, which differs from numpy's in the last bit now and then, so a body within
one rounding of a sector border may fall in the other sector.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from ..core.compiled import kernel
from ..core.steering import SLACK
from .queries import bb_overlap, circle_point, circle_sweep, segment_box, segment_normal, segment_point, segment_sweep

# the variants the kernel knows, by their FleetParams names; a code is the index
LAWS = ("rpso", "adapted-rpso", "robot-centred", "nonomni")
DRIVES = ("holonomic", "mecanum", "differential")
RPSO, ADAPTED_RPSO, ROBOT_CENTRED, NONOMNI = range(4)
HOLONOMIC, MECANUM, DIFFERENTIAL = range(3)
CONSTANT, DVC_OMNI, DVC_NONOMNI = range(3)
ACTIVE, COLLIDED = 0, 1
SECTORS = 6
TWO_PI = 2.0 * np.pi
SECTOR_WIDTH = np.pi / 3
STOP_SHORT = 1e-6  # a sweep stops this fraction of its step before the first contact (motion.Kinematic)


class TickParams(NamedTuple):
    """Everything phase B reads besides the arrays (one fleet's FleetParams, resolved)."""

    law: int
    coefficients: int
    drive: int
    sequential: bool
    guard: bool
    body_frame: bool
    terms: int
    dt: float
    sensing_range: float
    radius: float
    v_max: float
    omega: float  # constant mode
    c: tuple[float, float, float, float, float]  # constant mode, padded with zeros
    alpha: float
    beta: float
    gamma: float
    c1_share: float
    s_min: float
    k_omni: float  # αβ/(Δt√d) of [4.13]–[4.15]
    w_max: float
    rot_factor: float  # k in e_r = k w² [5.12]
    r_min: float
    tolerance: float  # contact tolerance
    s_floor: float  # smallest gap in [4.4]
    reach: float  # R_s + 2r + 2 v_max Δt: robots farther apart cannot interact within a tick
    steered: bool = False  # the command is the one in ``cmd`` (core/steering.py), limited as the law limits its own;
    # the robots then sense nothing in the tick (nothing reads it), unless the DVC guard needs the gaps
    given: bool = False  # ω and c are read from ``out`` where they are not NaN (core/steering.py)


class Grid(NamedTuple):
    """A uniform grid of square cells over the arena; points outside fall in the border cells."""

    x0: float
    y0: float
    h: float
    nx: int
    ny: int


def make_grid(bounds: tuple[float, float, float, float], h: float, max_cells: int = 256) -> Grid:
    """Cells of side ``h`` (larger if the arena would need more than ``max_cells`` a side)."""
    x0, y0, x1, y1 = bounds
    h = max(float(h), (x1 - x0) / max_cells, (y1 - y0) / max_cells, 1e-9)
    return Grid(float(x0), float(y0), h, int(math.ceil((x1 - x0) / h)) + 1, int(math.ceil((y1 - y0) / h)) + 1)


class WorldArrays(NamedTuple):
    """A world's static bodies as the kernel reads them: circles in a grid (CSR lists of the
    cells each circle's box covers), walls with the normals and boxes pymunk computes."""

    circles: np.ndarray  # (M, 3)
    cell_start: np.ndarray  # (cells + 1,)
    cell_items: np.ndarray  # circle indices
    walls: np.ndarray  # (W, 4): ax, ay, bx, by
    wall_normal: np.ndarray  # (W, 2)
    wall_box: np.ndarray  # (W, 4)
    wall_radius: float


def world_arrays(circles: np.ndarray, walls: np.ndarray, wall_radius: float, grid: Grid) -> WorldArrays:
    """The static bodies of a world (``WorldSpec.circles``, ``.walls``) for :func:`phase_b`."""
    circles = np.ascontiguousarray(circles, dtype=float).reshape(-1, 3)
    walls = np.ascontiguousarray(walls, dtype=float).reshape(-1, 4)
    start, items = _circle_cells(circles, grid)
    normal = np.array([segment_normal(*w) for w in walls], dtype=float).reshape(-1, 2)
    box = np.array([segment_box(*w, float(wall_radius)) for w in walls],  # type: ignore[call-arg,type-var]
                   dtype=float).reshape(-1, 4)  # (a compiled function: its stub takes no arguments)
    return WorldArrays(circles, start, items, walls, normal, box, float(wall_radius))


# ----------------------------------------------------------------------------- grids
@kernel
def _cell_index(v: float, v0: float, h: float, n: int) -> int:
    t = (v - v0) / h
    if not t >= 0.0:  # also NaN
        return 0
    if t >= n - 1:
        return n - 1
    return int(t)


@kernel
def _cells(lo_x: float, lo_y: float, hi_x: float, hi_y: float, g: Grid) -> tuple[int, int, int, int]:
    """The range of cells (ix0, iy0, ix1, iy1) a box covers."""
    return (_cell_index(lo_x, g.x0, g.h, g.nx), _cell_index(lo_y, g.y0, g.h, g.ny),
            _cell_index(hi_x, g.x0, g.h, g.nx), _cell_index(hi_y, g.y0, g.h, g.ny))


@kernel
def _circle_cells(circles: np.ndarray, g: Grid) -> tuple[np.ndarray, np.ndarray]:
    count = np.zeros(g.nx * g.ny + 1, np.int64)
    for pass_ in range(2):
        if pass_ == 1:
            for c in range(g.nx * g.ny):
                count[c + 1] += count[c]
            fill = count[:-1].copy()
            items = np.empty(count[-1], np.int64)
        for j in range(circles.shape[0]):
            cx, cy, r = circles[j, 0], circles[j, 1], circles[j, 2]
            ix0, iy0, ix1, iy1 = _cells(cx - r, cy - r, cx + r, cy + r, g)
            for iy in range(iy0, iy1 + 1):
                for ix in range(ix0, ix1 + 1):
                    c = iy * g.nx + ix
                    if pass_ == 0:
                        count[c + 1] += 1
                    else:
                        items[fill[c]] = j
                        fill[c] += 1
    return count, items


@kernel
def _grid_insert(i: int, c: int, head: np.ndarray, nxt: np.ndarray, prv: np.ndarray, cell: np.ndarray) -> None:
    cell[i] = c
    prv[i] = -1
    nxt[i] = head[c]
    if head[c] >= 0:
        prv[head[c]] = i
    head[c] = i


@kernel
def _grid_remove(i: int, head: np.ndarray, nxt: np.ndarray, prv: np.ndarray, cell: np.ndarray) -> None:
    if prv[i] >= 0:
        nxt[prv[i]] = nxt[i]
    else:
        head[cell[i]] = nxt[i]
    if nxt[i] >= 0:
        prv[nxt[i]] = prv[i]


@kernel
def _grid_cell(px: float, py: float, g: Grid) -> int:
    return _cell_index(py, g.y0, g.h, g.ny) * g.nx + _cell_index(px, g.x0, g.h, g.nx)


# ----------------------------------------------------------------------------- groups
@kernel
def _colour(xr: np.ndarray, reach: float, g: Grid, head: np.ndarray, nxt: np.ndarray, colour: np.ndarray,
            stamp: np.ndarray) -> int:
    """Greedy colouring of the robots of one run in index order: each takes the smallest
    colour no earlier robot within ``reach`` has (``Fleet._groups``). Returns the colours used."""
    n = xr.shape[0]
    used = 0
    stamp[:] = -1
    for i in range(n):
        xi, yi = xr[i, 0], xr[i, 1]
        ix0, iy0, ix1, iy1 = _cells(xi - reach, yi - reach, xi + reach, yi + reach, g)
        for iy in range(iy0, iy1 + 1):
            for ix in range(ix0, ix1 + 1):
                j = head[iy * g.nx + ix]
                while j >= 0:
                    if j < i:
                        dx, dy = xi - xr[j, 0], yi - xr[j, 1]
                        if math.sqrt(dx * dx + dy * dy) <= reach:
                            stamp[colour[j]] = i
                    j = nxt[j]
        k = 0
        while stamp[k] == i:
            k += 1
        colour[i] = k
        used = max(used, k + 1)
    return used


# ----------------------------------------------------------------------------- sensing
@kernel
def _sector(bx: float, by: float, turn: float) -> int:
    """Sector 0..5 of the bearing of (bx, by), less ``turn`` (sensing.sector_of)."""
    k = math.floor((math.atan2(by, bx) - turn + np.pi) / SECTOR_WIDTH)
    return int(k) % SECTORS


@kernel
def _keep(k: int, g: float, px: float, py: float, cx: float, cy: float, gap: np.ndarray, point: np.ndarray,
          centre: np.ndarray, hit: np.ndarray) -> None:
    if not hit[k] or g < gap[k]:
        gap[k], hit[k] = g, True
        point[k, 0], point[k, 1], centre[k, 0], centre[k, 1] = px, py, cx, cy


@kernel
def _seen(i: int, xi: float, yi: float, turn: float, dist: float, qx: float, qy: float, gx: float, gy: float,
          cx: float, cy: float, p: TickParams, gap: np.ndarray, point: np.ndarray, centre: np.ndarray,
          hit: np.ndarray) -> None:
    """One query hit of robot i (sensing.sense): gap to the surface, sector of its closest
    point (the inward gradient when the centre is inside), closest first."""
    g = _maximum(dist - p.radius, 0.0)
    if not g <= p.sensing_range:
        return
    if dist > 0.0:
        k = _sector(qx - xi, qy - yi, turn)
    else:
        k = _sector(-gx, -gy, turn)
    _keep(k, g, qx, qy, cx, cy, gap, point, centre, hit)


@kernel
def _sense(i: int, xr: np.ndarray, turn: float, p: TickParams, w: WorldArrays, g: Grid, head: np.ndarray,
           nxt: np.ndarray, stamp: np.ndarray, gap: np.ndarray, point: np.ndarray, centre: np.ndarray,
           hit: np.ndarray) -> None:
    """Six-sector reading of robot i of one run (sensing.sense with pymunk's point query):
    every body closer than R_s + r to its centre, the closest per sector."""
    xi, yi = xr[i, 0], xr[i, 1]
    r = p.radius
    max_d = p.sensing_range + r
    gap[:] = p.sensing_range
    point[:] = np.nan
    centre[:] = np.nan
    hit[:] = False
    reach = max_d + r
    ix0, iy0, ix1, iy1 = _cells(xi - reach, yi - reach, xi + reach, yi + reach, g)
    for iy in range(iy0, iy1 + 1):
        for ix in range(ix0, ix1 + 1):
            j = head[iy * g.nx + ix]
            while j >= 0:
                if j != i:
                    cx, cy = xr[j, 0], xr[j, 1]
                    d, qx, qy, gx, gy = circle_point(xi, yi, cx, cy, r)
                    if d < max_d:
                        _seen(i, xi, yi, turn, d, qx, qy, gx, gy, cx, cy, p, gap, point, centre, hit)
                j = nxt[j]
    _static_sense(i, xi, yi, turn, max_d, p, w, g, stamp, gap, point, centre, hit)


@kernel
def _static_sense(i: int, xi: float, yi: float, turn: float, max_d: float, p: TickParams, w: WorldArrays, g: Grid,
                  stamp: np.ndarray, gap: np.ndarray, point: np.ndarray, centre: np.ndarray, hit: np.ndarray) -> None:
    stamp[0] += 1
    mark = stamp[0]
    ix0, iy0, ix1, iy1 = _cells(xi - max_d, yi - max_d, xi + max_d, yi + max_d, g)
    for iy in range(iy0, iy1 + 1):
        for ix in range(ix0, ix1 + 1):
            c = iy * g.nx + ix
            for s in range(w.cell_start[c], w.cell_start[c + 1]):
                j = w.cell_items[s]
                if stamp[j + 1] == mark:
                    continue
                stamp[j + 1] = mark
                cx, cy = w.circles[j, 0], w.circles[j, 1]
                d, qx, qy, gx, gy = circle_point(xi, yi, cx, cy, w.circles[j, 2])
                if d < max_d:
                    _seen(i, xi, yi, turn, d, qx, qy, gx, gy, cx, cy, p, gap, point, centre, hit)
    for k in range(w.walls.shape[0]):
        a = w.walls[k]
        d, qx, qy, gx, gy = segment_point(xi, yi, a[0], a[1], a[2], a[3], w.wall_radius, w.wall_normal[k, 0],
                                          w.wall_normal[k, 1])
        if d < max_d:  # a wall has no centre: [4.4] pushes from its closest point
            _seen(i, xi, yi, turn, d, qx, qy, gx, gy, qx, qy, p, gap, point, centre, hit)


# ----------------------------------------------------------------------------- control
@kernel
def _sgn(v: float) -> float:
    if v > 0.0:
        return 1.0
    if v < 0.0:
        return -1.0
    return v  # 0 (or NaN) as numpy.sign


@kernel
def _maximum(a: float, b: float) -> float:
    return a if (a >= b or a != a) else b


@kernel
def _minimum(a: float, b: float) -> float:
    return a if (a <= b or a != a) else b


@kernel
def _coefficients(gap: np.ndarray, p: TickParams, c: np.ndarray) -> float:
    """ω, and c_1..c_n into ``c``, from the (s_min-adjusted) gaps: dvc.dvc_omni,
    dvc.dvc_nonomni or the constants."""
    if p.coefficients == DVC_OMNI:  # [4.13]–[4.16]
        s1 = s2 = np.inf
        for k in range(SECTORS):
            v = _maximum(gap[k], 0.0)
            if v < s1:
                s1, s2 = v, s1
            elif v < s2:
                s2 = v
        c12 = p.k_omni * s1
        c[0], c[1], c[2] = p.c1_share * c12, (1.0 - p.c1_share) * c12, p.k_omni * (s2 - s1)
        return 1.0 - p.beta
    if p.coefficients == DVC_NONOMNI:  # [5.14]–[5.16]
        rs = p.sensing_range
        s1 = sl1 = sr1 = sf1 = np.inf
        for k in range(SECTORS):
            v = _minimum(_maximum(gap[k], 0.0), rs)
            s1 = min(s1, v)
            if k >= 3:
                sl1 = min(sl1, v)
            else:
                sr1 = min(sr1, v)
            if 1 <= k <= 4:
                sf1 = min(sf1, v)
        w12 = s1 / rs * p.w_max
        w3 = (1.0 - sl1 / rs) * p.w_max
        w4 = (1.0 - sr1 / rs) * p.w_max
        u = _minimum(p.alpha * sf1 / p.dt, p.v_max)
        c12 = p.beta * w12
        c[0], c[1], c[2], c[3], c[4] = p.c1_share * c12, (1.0 - p.c1_share) * c12, p.beta * w3, p.beta * w4, p.beta * u
        return 1.0 - p.beta
    for n in range(5):
        c[n] = p.c[n]
    return p.omega


@kernel
def _virtual_force(xi: float, yi: float, gap: np.ndarray, centre: np.ndarray, hit: np.ndarray,
                   p: TickParams) -> tuple[float, float]:
    """F_t = Σ_p γ (x_i − x_p)/(s_p |x_i − x_p|) over the sectors [4.3], [4.4] (sensing.virtual_force)."""
    fx = fy = 0.0  # numpy's sum starts from +0
    for k in range(SECTORS):
        dx, dy = xi - centre[k, 0], yi - centre[k, 1]
        ok = hit[k] and math.isfinite(dx) and math.isfinite(dy)
        if not ok:
            dx = dy = 0.0
        norm = math.sqrt(dx * dx + dy * dy)
        den = norm if norm > 0.0 else 1.0
        s = _maximum(gap[k] if ok else 1.0, p.s_floor)
        fx, fy = fx + p.gamma * (dx / den) / s, fy + p.gamma * (dy / den) / s
    return fx, fy


@kernel
def _to_body(x: float, y: float, cos: float, sin: float) -> tuple[float, float]:
    return cos * x + sin * y, -sin * x + cos * y


@kernel
def _limited(v: float, w: float, p: TickParams) -> tuple[float, float]:
    """The energy limit [5.11], [5.12] and the minimum turning radius [5.6] (laws._limited)."""
    e_t = 0.5 * (v * v) + p.rot_factor * (w * w)
    e_max = 0.5 * (p.v_max * p.v_max)
    if e_t > e_max:
        lam = math.sqrt(e_max / e_t)
        v, w = v * lam, w * lam
    if p.r_min != 0.0:
        w = _sgn(w) * _minimum(abs(w), abs(v) / p.r_min)
    return v, w


@kernel
def _steered(prev: np.ndarray, p: TickParams) -> tuple[float, float]:
    """A command from outside the law within the law's limits (laws.steered_command): a speed at
    most v_max, or [v, w] forward only (non-omni), within the energy limit and the turning radius;
    each limit where the command exceeds it by more than SLACK."""
    if not p.body_frame:
        ux, uy = prev[0], prev[1]
        speed = math.sqrt(ux * ux + uy * uy)
        if speed > p.v_max * (1.0 + SLACK):
            f = p.v_max / speed
            ux, uy = ux * f, uy * f
        return ux, uy
    v, w = prev[0], prev[1]
    if p.law == NONOMNI:
        v = _maximum(v, 0.0)
    e_t = 0.5 * (v * v) + p.rot_factor * (w * w)
    e_max = 0.5 * (p.v_max * p.v_max)
    if e_t > e_max * (1.0 + SLACK):
        lam = math.sqrt(e_max / e_t)
        v, w = v * lam, w * lam
    if p.r_min != 0.0:
        w = _sgn(w) * _minimum(abs(w), abs(v) / p.r_min)
    return v, w


@kernel
def _command(prev: np.ndarray, gp: np.ndarray, gg: np.ndarray, fx: float, fy: float, heading: float, c: np.ndarray,
             omega: float, r: np.ndarray, p: TickParams) -> tuple[float, float]:
    """The velocity law of robot_laws.ROBOT_LAWS: [4.2] clipped, [4.5], [5.4] and [5.13] (or, steered,
    the command in ``prev`` within the law's limits)."""
    if p.steered:
        return _steered(prev, p)
    if p.law == RPSO or p.law == ADAPTED_RPSO:
        out = np.empty(2)
        for d in range(2):
            g0, g1, g2 = gp[d], gg[d], (fx if d == 0 else fy)
            if p.law == ADAPTED_RPSO:
                g0, g1, g2 = _sgn(g0), _sgn(g1), _sgn(g2)
            s = 0.0 + (c[0] * r[0, d]) * g0 + (c[1] * r[1, d]) * g1 + (c[2] * r[2, d]) * g2  # numpy's sum: from +0
            out[d] = omega * prev[d] + s
        if p.law == RPSO:  # clipped to v_max keeping its direction
            speed = math.sqrt(out[0] * out[0] + out[1] * out[1])
            if speed > p.v_max:
                f = p.v_max / speed
                out[0], out[1] = out[0] * f, out[1] * f
        return out[0], out[1]
    cos, sin = math.cos(heading), math.sin(heading)
    y0 = _to_body(gp[0], gp[1], cos, sin)
    y1 = _to_body(gg[0], gg[1], cos, sin)
    if p.law == ROBOT_CENTRED:
        v = omega * prev[0] + (0.0 + (c[0] * r[0, 0]) * _sgn(y0[0]) + (c[1] * r[1, 0]) * _sgn(y1[0]))
        w = omega * prev[1] + (0.0 + (c[0] * r[0, 1]) * _sgn(y0[1]) + (c[1] * r[1, 1]) * _sgn(y1[1]))
        return _limited(v, w, p)
    cr = np.empty(5)
    for n in range(5):
        cr[n] = c[n] * r[n, 0]
    w = omega * prev[1] + cr[0] * _sgn(y0[1]) + cr[1] * _sgn(y1[1]) - cr[2] + cr[3]  # [5.13] tasks 1–4
    v = _maximum(omega * prev[0] + cr[4], 0.0)  # task 5
    return _limited(v, w, p)


@kernel
def _guard(ux: float, uy: float, xi: float, yi: float, point: np.ndarray, gap: np.ndarray,
           p: TickParams) -> tuple[float, float]:
    """dvc.forward_guard (body frame) or dvc.approach_guard."""
    if p.body_frame:
        sf1 = np.inf
        for k in range(1, 5):
            sf1 = min(sf1, gap[k])
        return _minimum(ux, p.alpha * _maximum(sf1, 0.0) / p.dt), uy
    ratio = 1.0
    for k in range(SECTORS):
        rx, ry = point[k, 0] - xi, point[k, 1] - yi
        dist = math.sqrt(rx * rx + ry * ry)
        seen = math.isfinite(dist) and dist > 0.0
        nx, ny = (rx / dist, ry / dist) if seen else (0.0, 0.0)
        closing = (nx * ux + ny * uy) * p.dt
        allowed = p.alpha * _maximum(gap[k], 0.0)
        if seen and closing > allowed:
            ratio = _minimum(ratio, allowed / closing)
    return ux * ratio, uy * ratio


# ----------------------------------------------------------------------------- motion
@kernel
def _wrap(a: float) -> float:
    """laws.wrap_angle: to (−π, π] with numpy's floating-point modulo."""
    b = np.pi - a
    m = np.fmod(b, TWO_PI)
    if m != 0.0:
        if (m < 0.0) != (TWO_PI < 0.0):
            m += TWO_PI
    else:
        m = math.copysign(0.0, TWO_PI)
    out = np.pi - m
    return out + TWO_PI if out <= -np.pi else out


@kernel
def _sinc(x: float) -> float:
    y = np.pi * (1.0e-20 if x == 0.0 else x)
    return math.sin(y) / y


@kernel
def _target(xi: float, yi: float, heading: float, c0: float, c1: float,
            p: TickParams) -> tuple[float, float, float]:
    """Where a command takes the robot if nothing is in the way, and its new heading
    (motion.Kinematic.move: [4.6], the mecanum limit, the arc [5.5]–[5.10])."""
    if p.drive == DIFFERENTIAL:
        theta = c1 * p.dt
        step = c0 * p.dt
        along = step * _sinc(theta / np.pi)
        lateral = step * math.sin(0.5 * theta) * _sinc(theta / (2.0 * np.pi))
        cos, sin = math.cos(heading), math.sin(heading)
        return xi + (cos * along - sin * lateral), yi + (sin * along + cos * lateral), _wrap(heading + theta)
    if p.drive == MECANUM:  # laws.mecanum_limit: |v_x| + |v_y| ≤ v_max in the body frame
        cos, sin = math.cos(heading), math.sin(heading)
        bx, by = _to_body(c0, c1, cos, sin)
        fastest = max(abs(bx - by), abs(bx + by))
        if fastest > p.v_max:
            f = p.v_max / fastest
            c0, c1 = c0 * f, c1 * f
    return xi + p.dt * c0, yi + p.dt * c1, _wrap(heading)


ROBOT_BODY, CIRCLE_BODY, WALL_BODY = range(3)  # what _first_contact touched


@kernel
def _first_contact(i: int, sx: float, sy: float, ex: float, ey: float, rad: float, xr: np.ndarray,
                   p: TickParams, w: WorldArrays, g: Grid, head: np.ndarray, nxt: np.ndarray,
                   stamp: np.ndarray) -> tuple[float, int, int]:
    """motion.first_contact: the smallest fraction of the step at which robot i's disc (radius
    ``rad``) touches a body whose box meets the swept box (−1 for a free path), and that
    body: its kind (``ROBOT_BODY``, ``CIRCLE_BODY``, ``WALL_BODY``) and index."""
    lo_x, hi_x = min(sx, ex) - rad, max(sx, ex) + rad
    lo_y, hi_y = min(sy, ey) - rad, max(sy, ey) + rad
    best = -1.0
    kind, idx = -1, -1
    r = p.radius
    ix0, iy0, ix1, iy1 = _cells(lo_x - r, lo_y - r, hi_x + r, hi_y + r, g)
    for iy in range(iy0, iy1 + 1):
        for ix in range(ix0, ix1 + 1):
            j = head[iy * g.nx + ix]
            while j >= 0:
                if j != i:
                    cx, cy = xr[j, 0], xr[j, 1]
                    if bb_overlap(lo_x, lo_y, hi_x, hi_y, cx - r, cy - r, cx + r, cy + r):
                        t = circle_sweep(cx, cy, r, sx, sy, ex, ey, rad)
                        if t >= 0.0 and (best < 0.0 or t < best):
                            best, kind, idx = t, ROBOT_BODY, j
                j = nxt[j]
    stamp[0] += 1
    mark = stamp[0]
    ix0, iy0, ix1, iy1 = _cells(lo_x, lo_y, hi_x, hi_y, g)
    for iy in range(iy0, iy1 + 1):
        for ix in range(ix0, ix1 + 1):
            c = iy * g.nx + ix
            for s in range(w.cell_start[c], w.cell_start[c + 1]):
                j = w.cell_items[s]
                if stamp[j + 1] == mark:
                    continue
                stamp[j + 1] = mark
                cx, cy, cr = w.circles[j, 0], w.circles[j, 1], w.circles[j, 2]
                if bb_overlap(lo_x, lo_y, hi_x, hi_y, cx - cr, cy - cr, cx + cr, cy + cr):
                    t = circle_sweep(cx, cy, cr, sx, sy, ex, ey, rad)
                    if t >= 0.0 and (best < 0.0 or t < best):
                        best, kind, idx = t, CIRCLE_BODY, j
    for k in range(w.walls.shape[0]):
        b = w.wall_box[k]
        if bb_overlap(lo_x, lo_y, hi_x, hi_y, b[0], b[1], b[2], b[3]):
            a = w.walls[k]
            t = segment_sweep(a[0], a[1], a[2], a[3], w.wall_radius, w.wall_normal[k, 0], w.wall_normal[k, 1],
                              sx, sy, ex, ey, rad)
            if t >= 0.0 and (best < 0.0 or t < best):
                best, kind, idx = t, WALL_BODY, k
    return best, kind, idx


@kernel
def _sweep_body(kind: int, idx: int, sx: float, sy: float, ex: float, ey: float, rad: float, xr: np.ndarray,
                p: TickParams, w: WorldArrays) -> float:
    """The sweep of a disc of radius ``rad`` from s to e against one body (motion.deeper_than)."""
    if kind == ROBOT_BODY:
        return circle_sweep(xr[idx, 0], xr[idx, 1], p.radius, sx, sy, ex, ey, rad)
    if kind == CIRCLE_BODY:
        return circle_sweep(w.circles[idx, 0], w.circles[idx, 1], w.circles[idx, 2], sx, sy, ex, ey, rad)
    a = w.walls[idx]
    return segment_sweep(a[0], a[1], a[2], a[3], w.wall_radius, w.wall_normal[idx, 0], w.wall_normal[idx, 1],
                         sx, sy, ex, ey, rad)


@kernel
def _touching(i: int, xr: np.ndarray, p: TickParams, w: WorldArrays, g: Grid, head: np.ndarray, nxt: np.ndarray,
              stamp: np.ndarray, touched: np.ndarray) -> bool:
    """RunSpace.contacts_of(i, −tolerance): does robot i overlap a body by more than the
    contact tolerance? Robots it overlaps are marked in ``touched``."""
    xi, yi = xr[i, 0], xr[i, 1]
    r = p.radius
    q = r + -p.tolerance
    any_ = False
    reach = max(q, 0.0) + r
    ix0, iy0, ix1, iy1 = _cells(xi - reach, yi - reach, xi + reach, yi + reach, g)
    for iy in range(iy0, iy1 + 1):
        for ix in range(ix0, ix1 + 1):
            j = head[iy * g.nx + ix]
            while j >= 0:
                if j != i and circle_point(xi, yi, xr[j, 0], xr[j, 1], r)[0] < q:
                    touched[j] = True
                    any_ = True
                j = nxt[j]
    stamp[0] += 1
    mark = stamp[0]
    reach = max(q, 0.0)
    ix0, iy0, ix1, iy1 = _cells(xi - reach, yi - reach, xi + reach, yi + reach, g)
    for iy in range(iy0, iy1 + 1):
        for ix in range(ix0, ix1 + 1):
            c = iy * g.nx + ix
            for s in range(w.cell_start[c], w.cell_start[c + 1]):
                j = w.cell_items[s]
                if stamp[j + 1] != mark:
                    stamp[j + 1] = mark
                    if circle_point(xi, yi, w.circles[j, 0], w.circles[j, 1], w.circles[j, 2])[0] < q:
                        any_ = True
    for k in range(w.walls.shape[0]):
        a = w.walls[k]
        if segment_point(xi, yi, a[0], a[1], a[2], a[3], w.wall_radius, w.wall_normal[k, 0],
                         w.wall_normal[k, 1])[0] < q:
            any_ = True
    if any_:
        touched[i] = True
    return any_


# ----------------------------------------------------------------------------- the tick
class Outputs(NamedTuple):
    """What phase B records of each robot's decision (``FleetState``): ω, c (n, R, N), F_t and
    its six-sector reading. Robots that did not decide keep what the caller put there."""

    omega: np.ndarray  # (R, N)
    c: np.ndarray  # (n, R, N)
    force: np.ndarray  # (R, N, 2)
    gap: np.ndarray  # (R, N, 6)
    point: np.ndarray  # (R, N, 6, 2)
    centre: np.ndarray  # (R, N, 6, 2)
    hit: np.ndarray  # (R, N, 6)


@kernel
def phase_b(x: np.ndarray, heading: np.ndarray, u: np.ndarray, cmd: np.ndarray, status: np.ndarray,
            g_p: np.ndarray, g_g: np.ndarray, draws: np.ndarray, p: TickParams, w: WorldArrays, g: Grid,
            out: Outputs) -> bool:
    """Sense, decide and move every active robot of every run once, in place (x, heading, u,
    cmd, status: the realised velocity, the command and collisions of the movers).

    ``g_p``, ``g_g`` (R, N, 2) are each robot's vectors to its personal and global best,
    ``draws`` (n, R, N, k) its U(0,1) draws (k = 2 per component, 1 per robot). Returns whether
    any robot sensed (False when every robot of every run has collided)."""
    R, N = status.shape
    scratch = _scratch(N, g, w)
    sensed = False
    for r in range(R):
        sensed |= _phase_b_run(r, x, heading, u, cmd, status, g_p[r], g_g[r], draws[:, r], p, w, g, out, scratch)
    return sensed


Scratch = tuple  # what one run's phase B works in (:func:`_scratch`)


@kernel
def _scratch(N: int, g: Grid, w: WorldArrays) -> tuple:
    """Scratch of :func:`_phase_b_run` for N robots: the robot grid, the colouring, the groups,
    each group's commands and contacts."""
    head, nxt, prv, cell, ostamp = _grid_scratch(N, g, w)
    return (head, nxt, prv, cell, ostamp, np.zeros(N, np.int64), np.full(N + 1, -1, np.int64), np.empty(N, np.int64),
            np.empty(N + 2, np.int64), np.empty(N, np.int64), np.empty((N, 2)), np.zeros(N, np.bool_),
            np.zeros(N, np.bool_), np.zeros(5), np.empty(SECTORS))


@kernel
def _phase_b_run(r: int, x: np.ndarray, heading: np.ndarray, u: np.ndarray, cmd: np.ndarray, status: np.ndarray,
                 g_p: np.ndarray, g_g: np.ndarray, draws: np.ndarray, p: TickParams, w: WorldArrays, g: Grid,
                 out: Outputs, scratch: tuple) -> bool:
    """Phase B of run r (:func:`phase_b`); ``g_p``, ``g_g`` (N, 2) and ``draws`` (n, N, k) are
    the run's own. Reads and writes row r of the arrays only. Whether a robot sensed."""
    N = status.shape[1]
    head, nxt, prv, cell, ostamp, colour, stamp, order, start, members, new_cmd, touched, hit, c, adj = scratch
    sensed = False
    xr = x[r]
    head[:] = -1
    for i in range(N):
        _grid_insert(i, _grid_cell(xr[i, 0], xr[i, 1], g), head, nxt, prv, cell)
    if p.sequential:
        groups = _colour(xr, p.reach, g, head, nxt, colour, stamp)
    else:
        colour[:] = 0
        groups = 1
    start[:] = 0  # the active robots of each colour, in index order
    for i in range(N):
        if status[r, i] == ACTIVE:
            start[colour[i] + 2] += 1
    for k in range(groups):
        start[k + 2] += start[k + 1]
    for i in range(N):
        if status[r, i] == ACTIVE:
            order[start[colour[i] + 1]] = i
            start[colour[i] + 1] += 1
    for k in range(groups):
        m = 0
        for s in range(start[k], start[k + 1]):
            i = order[s]
            if status[r, i] == ACTIVE:  # a robot hit earlier in this tick sits out
                members[m] = i
                m += 1
        if m == 0:
            continue
        blind = p.steered and not (p.guard and p.coefficients != CONSTANT)  # a given command needs no sensing
        sensed = sensed or not blind
        for s in range(m):  # everyone in the group senses and decides ...
            i = members[s]
            if blind:
                new_cmd[i, 0], new_cmd[i, 1] = _steered(cmd[r, i], p)
                continue
            turn = heading[r, i] if p.body_frame else 0.0
            gap, point, centre, seen = out.gap[r, i], out.point[r, i], out.centre[r, i], out.hit[r, i]
            _sense(i, xr, turn, p, w, g, head, nxt, ostamp, gap, point, centre, seen)
            for q in range(SECTORS):
                adj[q] = _maximum(gap[q] - p.s_min, 0.0) if p.s_min > 0 else gap[q]
            omega = _coefficients(adj, p, c)
            if p.given:  # ω, c given from outside where not NaN
                if out.omega[r, i] == out.omega[r, i]:
                    omega = out.omega[r, i]
                for n in range(p.terms):
                    if out.c[n, r, i] == out.c[n, r, i]:
                        c[n] = out.c[n, r, i]
            fx = fy = 0.0
            if not p.body_frame:
                fx, fy = _virtual_force(xr[i, 0], xr[i, 1], gap, centre, seen, p)
            cx, cy = _command(cmd[r, i], g_p[i], g_g[i], fx, fy, heading[r, i], c, omega, draws[:, i, :], p)
            if p.guard and p.coefficients != CONSTANT:
                cx, cy = _guard(cx, cy, xr[i, 0], xr[i, 1], point, adj, p)
            new_cmd[i, 0], new_cmd[i, 1] = cx, cy
            out.omega[r, i] = omega
            for n in range(p.terms):
                out.c[n, r, i] = c[n]
            out.force[r, i, 0], out.force[r, i, 1] = fx, fy
        touched[:] = False  # robots a mover collides with, then whoever overlaps a body
        for s in range(m):  # ... then they move one after another ...
            i = members[s]
            sx, sy = xr[i, 0], xr[i, 1]
            ex, ey, new_heading = _target(sx, sy, heading[r, i], new_cmd[i, 0], new_cmd[i, 1], p)
            nx_, ny_ = ex, ey
            hit[i] = False
            if sx != ex or sy != ey:
                t, kind, idx = _first_contact(i, sx, sy, ex, ey, p.radius, xr, p, w, g, head, nxt, ostamp)
                if t >= 0.0:  # stop where the swept disc first touches
                    f = max(t - STOP_SHORT, 0.0)
                    nx_, ny_ = sx + f * (ex - sx), sy + f * (ey - sy)
                    hit[i] = p.tolerance <= 0 or _sweep_body(kind, idx, sx, sy, ex, ey, p.radius - p.tolerance,
                                                             xr, p, w) >= 0.0
                    if hit[i] and kind == ROBOT_BODY:  # both robots of a collision are disabled
                        touched[idx] = True
                _grid_remove(i, head, nxt, prv, cell)
                xr[i, 0], xr[i, 1] = nx_, ny_
                _grid_insert(i, _grid_cell(nx_, ny_, g), head, nxt, prv, cell)
            heading[r, i] = new_heading
            u[r, i, 0], u[r, i, 1] = (nx_ - sx) / p.dt, (ny_ - sy) / p.dt
            cmd[r, i, 0], cmd[r, i, 1] = new_cmd[i, 0], new_cmd[i, 1]
        for s in range(m):  # ... and whoever overlaps a body beyond the tolerance has collided
            _touching(members[s], xr, p, w, g, head, nxt, ostamp, touched)
        for s in range(m):
            if hit[members[s]]:
                status[r, members[s]] = COLLIDED
        for j in range(N):
            if touched[j]:
                status[r, j] = COLLIDED
    return sensed


# ----------------------------------------------------------------------------- physics mode
@kernel
def _grid_scratch(N: int, g: Grid, w: WorldArrays) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Scratch of the robot grid for N robots (cell heads, next/previous links, each robot's
    cell) and the obstacle stamps that keep a circle from being visited twice."""
    return (np.empty(g.nx * g.ny, np.int64), np.empty(N, np.int64), np.empty(N, np.int64), np.empty(N, np.int64),
            np.zeros(w.circles.shape[0] + 1, np.int64))


@kernel
def _robot_grid(xr: np.ndarray, g: Grid, head: np.ndarray, nxt: np.ndarray, prv: np.ndarray,
                cell: np.ndarray) -> None:
    head[:] = -1
    for i in range(xr.shape[0]):
        _grid_insert(i, _grid_cell(xr[i, 0], xr[i, 1], g), head, nxt, prv, cell)


@kernel
def sense_bodies(x: np.ndarray, turn: np.ndarray, active: np.ndarray, p: TickParams, w: WorldArrays, g: Grid,
                 gap: np.ndarray, point: np.ndarray, centre: np.ndarray, hit: np.ndarray) -> None:
    """:func:`shoal.engine.robots.sensing.sense` of the robots with ``active`` (R, N), every
    robot's body at ``x`` (R, N, 2); ``turn`` (R, N) is what bearings are measured from (the
    heading in the robot frame, else 0). Fills the reading (``SectorReading``'s arrays) of the
    active robots only. For physics mode, where pymunk moves the bodies between readings."""
    R, N = active.shape
    head, nxt, prv, cell, ostamp = _grid_scratch(N, g, w)
    for r in range(R):
        _robot_grid(x[r], g, head, nxt, prv, cell)
        for i in range(N):
            if active[r, i]:
                _sense(i, x[r], turn[r, i], p, w, g, head, nxt, ostamp, gap[r, i], point[r, i], centre[r, i],
                       hit[r, i])


@kernel
def touching_bodies(x: np.ndarray, moved: np.ndarray, p: TickParams, w: WorldArrays, g: Grid,
                    touched: np.ndarray) -> None:
    """``Fleet._touching`` for bodies at ``x`` (R, N, 2): ``touched`` (R, N) marks every robot
    with ``moved`` that overlaps a body by more than the contact tolerance, and the robots it
    overlaps (``RunSpace.contacts_of``)."""
    R, N = moved.shape
    head, nxt, prv, cell, ostamp = _grid_scratch(N, g, w)
    for r in range(R):
        _robot_grid(x[r], g, head, nxt, prv, cell)
        for i in range(N):
            if moved[r, i]:
                _touching(i, x[r], p, w, g, head, nxt, ostamp, touched[r])


# ----------------------------------------------------------------------------- spawning
@kernel
def spaced(candidates: np.ndarray, points: np.ndarray, count: int, gap: float, box: np.ndarray, head: np.ndarray,
           nxt: np.ndarray) -> tuple[int, int]:
    """Rejection sampling of points at least ``gap`` apart: take ``candidates`` (K, 2) in
    order, keeping each that is ``gap`` or more from every point kept so far, until ``points``
    (n, 2) is full. ``count`` points are kept already; ``head``/``nxt`` index them in a grid of
    cells of side ``gap`` over ``box`` (x0, y0, nx, ny) and are updated. Returns the points kept
    and the candidates used."""
    n = points.shape[0]
    x0, y0, nx, ny = box[0], box[1], int(box[2]), int(box[3])
    for a in range(candidates.shape[0]):
        if count == n:
            return count, a
        px, py = candidates[a, 0], candidates[a, 1]
        ix, iy = _cell_index(px, x0, gap, nx), _cell_index(py, y0, gap, ny)
        ok = True
        for cy in range(max(iy - 2, 0), min(iy + 3, ny)):  # ±2 cells: safe from rounding at cell edges
            for cx in range(max(ix - 2, 0), min(ix + 3, nx)):
                j = head[cy * nx + cx]
                while j >= 0 and ok:
                    ok = math.hypot(px - points[j, 0], py - points[j, 1]) >= gap
                    j = nxt[j]
        if ok:
            points[count, 0], points[count, 1] = px, py
            c = iy * nx + ix
            nxt[count] = head[c]
            head[c] = count
            count += 1
    return count, candidates.shape[0]
