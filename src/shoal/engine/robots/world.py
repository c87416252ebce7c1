"""Worlds as data (``WorldSpec``) and the pymunk space of one Monte-Carlo run (``RunSpace``).

A ``WorldSpec`` is an immutable description of an arena: static circles, convex polygons,
thin walls, the start box where robots spawn and the source. Editing returns a new spec.
``RunSpace`` turns a spec plus the robots of one run into a ``pymunk.Space`` that sensing
queries and the physics motion model steps.

Obstacle indices: circles first (``0 .. M-1``), then polygons (``M .. M+P-1``).
"""

from __future__ import annotations

import inspect
from dataclasses import dataclass, field, replace
from typing import Any, Callable, Literal

import numpy as np
import pymunk
import pymunk.batch

Box = tuple[float, float, float, float]

# pymunk collision types
OBSTACLE = 1
ROBOT = 2
DISABLED = 3  # a robot's shape once its body is disabled (RunSpace.disable)
# category bits, for queries that want one kind of body only
CAT_OBSTACLE = 0b001
CAT_WALL = 0b010
CAT_ROBOT = 0b100


def _frozen(a: Any, shape: tuple[int | None, ...], name: str) -> np.ndarray:
    """Float copy of ``a`` with the given shape (None = any length), made read-only."""
    arr = np.array(a, dtype=float)
    if arr.size == 0:
        arr = arr.reshape([0 if s is None else s for s in shape])
    if arr.ndim != len(shape) or any(s is not None and s != n for s, n in zip(shape, arr.shape)):
        raise ValueError(f"{name}: expected shape {shape}, got {arr.shape}")
    arr.setflags(write=False)
    return arr


def _ccw(poly: Any) -> np.ndarray:
    """A polygon as a read-only (V, 2) array in counter-clockwise order."""
    p = _frozen(poly, (None, 2), "polygon")
    if len(p) < 3:
        raise ValueError("polygon: needs at least 3 vertices")
    area2 = np.sum(p[:, 0] * np.roll(p[:, 1], -1) - np.roll(p[:, 0], -1) * p[:, 1])
    if area2 < 0:
        p = _frozen(p[::-1], (None, 2), "polygon")
    return p


def _polygon_distance(poly: np.ndarray, pt: np.ndarray) -> float:
    """Distance from ``pt`` to a convex CCW polygon (0 inside)."""
    a, b = poly, np.roll(poly, -1, axis=0)
    edge = b - a
    rel = pt - a
    cross = edge[:, 0] * rel[:, 1] - edge[:, 1] * rel[:, 0]
    if np.all(cross >= 0):
        return 0.0
    t = np.clip(np.sum(rel * edge, axis=1) / np.sum(edge * edge, axis=1), 0.0, 1.0)
    return float(np.min(np.linalg.norm(rel - t[:, None] * edge, axis=1)))


@dataclass(frozen=True, eq=False)
class WorldSpec:
    """An arena as plain data. Arrays are read-only; editing methods return new specs."""

    name: str
    circles: np.ndarray  # (M, 3): x, y, radius
    polygons: tuple[np.ndarray, ...]  # each (V, 2), convex, counter-clockwise
    walls: np.ndarray  # (W, 2, 2) segments
    wall_radius: float
    start_box: Box  # xmin, ymin, xmax, ymax
    source: tuple[float, float]
    layer_x: np.ndarray = field(default_factory=lambda: np.zeros(0))  # x of each layer
    bounds: Box = (-20.0, -20.0, 20.0, 20.0)  # drawing / arena bounds

    def __post_init__(self) -> None:
        set_ = lambda k, v: object.__setattr__(self, k, v)  # noqa: E731 (frozen dataclass)
        set_("circles", _frozen(self.circles, (None, 3), "circles"))
        if np.any(self.circles[:, 2] <= 0):
            raise ValueError("circles: radii must be > 0")
        set_("polygons", tuple(_ccw(p) for p in self.polygons))
        set_("walls", _frozen(self.walls, (None, 2, 2), "walls"))
        set_("layer_x", _frozen(self.layer_x, (None,), "layer_x"))
        set_("wall_radius", float(self.wall_radius))
        set_("start_box", tuple(float(v) for v in self.start_box))
        set_("source", tuple(float(v) for v in self.source))
        set_("bounds", tuple(float(v) for v in self.bounds))

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, WorldSpec):
            return NotImplemented
        return (
            self.name == other.name
            and np.array_equal(self.circles, other.circles)
            and len(self.polygons) == len(other.polygons)
            and all(np.array_equal(a, b) for a, b in zip(self.polygons, other.polygons))
            and np.array_equal(self.walls, other.walls)
            and self.wall_radius == other.wall_radius
            and self.start_box == other.start_box
            and self.source == other.source
            and np.array_equal(self.layer_x, other.layer_x)
            and self.bounds == other.bounds
        )

    __hash__ = None  # type: ignore[assignment]

    @property
    def n_obstacles(self) -> int:
        return len(self.circles) + len(self.polygons)

    def obstacle_distance(self, x: float, y: float) -> np.ndarray:
        """(M+P,) distance from the point to each obstacle's surface (0 inside)."""
        pt = np.array([x, y], dtype=float)
        d_c = np.maximum(np.hypot(self.circles[:, 0] - x, self.circles[:, 1] - y) - self.circles[:, 2], 0.0)
        d_p = np.array([_polygon_distance(p, pt) for p in self.polygons])
        return np.concatenate([d_c, d_p])

    def nearest_obstacle(self, x: float, y: float, tol: float = 1.0) -> int | None:
        """Index of the obstacle whose surface is closest to (x, y), if within ``tol``."""
        d = self.obstacle_distance(x, y)
        if d.size == 0 or d.min() > tol:
            return None
        return int(np.argmin(d))

    def with_circle(self, x: float, y: float, r: float) -> "WorldSpec":
        """A new spec with one more circle (it becomes circle index M)."""
        return replace(self, circles=np.vstack([self.circles, [[x, y, r]]]))

    def without_obstacle(self, index: int) -> "WorldSpec":
        """A new spec without obstacle ``index`` (circles first, then polygons)."""
        m = len(self.circles)
        if not 0 <= index < self.n_obstacles:
            raise IndexError(f"obstacle index {index} out of range 0..{self.n_obstacles - 1}")
        if index < m:
            return replace(self, circles=np.delete(self.circles, index, axis=0))
        polys = self.polygons[: index - m] + self.polygons[index - m + 1 :]
        return replace(self, polygons=polys)

    def without_obstacle_near(self, x: float, y: float, tol: float = 1.0) -> "WorldSpec":
        """Remove the obstacle closest to (x, y) within ``tol`` m of its surface; else ``self``."""
        i = self.nearest_obstacle(x, y, tol)
        return self if i is None else self.without_obstacle(i)

    def moved_obstacle(self, index: int, x: float, y: float) -> "WorldSpec":
        """Move obstacle ``index``: a circle's centre, or a polygon's vertex mean, to (x, y)."""
        m = len(self.circles)
        if not 0 <= index < self.n_obstacles:
            raise IndexError(f"obstacle index {index} out of range 0..{self.n_obstacles - 1}")
        if index < m:
            c = self.circles.copy()
            c[index, :2] = (x, y)
            return replace(self, circles=c)
        p = self.polygons[index - m]
        moved = p - p.mean(axis=0) + np.array([x, y])
        polys = self.polygons[: index - m] + (moved,) + self.polygons[index - m + 1 :]
        return replace(self, polygons=polys)


def _rng(seed: int | np.random.Generator) -> np.random.Generator:
    return seed if isinstance(seed, np.random.Generator) else np.random.default_rng(seed)


def box_walls(bounds: Box) -> np.ndarray:
    """(4, 2, 2) segments along the edges of ``bounds``: bottom, right, top, left."""
    x0, y0, x1, y1 = bounds
    c = [(x0, y0), (x1, y0), (x1, y1), (x0, y1)]
    return np.array([[c[i], c[(i + 1) % 4]] for i in range(4)], dtype=float)


def obstacle_course(
    seed: int | np.random.Generator = 0,
    layers: int = 6,
    length: float = 60.0,
    width: float = 30.0,
    first_gap: float = 4.0,
    last_gap: float = 1.5,
    radius_min: float = 0.5,
    radius_max: float = 1.0,
    jitter: float = 0.15,
    x_jitter: float = 0.3,
    start_size: float = 6.0,
    wall_radius: float = 0.1,
) -> WorldSpec:
    """Layers of circular obstacles between a start square (left) and a source (right),
    in the spirit of the thesis Fig. 4-1, which gives no dimensions (docs/readings.md, "The obstacle course of
    Figure 4-1").

    Layers sit at evenly spaced x; in layer l the mean surface gap between neighbouring
    circles shrinks linearly from ``first_gap`` to ``last_gap``, so the course gets denser
    toward the source. Each gap is the layer mean times ``1 + jitter·(u − ū)``, u ~ U(−1, 1),
    so no gap is below ``(1 − 2·jitter)`` times the mean. Circles are also shifted along x by
    up to ``x_jitter``. Each row keeps at least one mean gap to each wall and splits the
    spare width at random (25–75 %) between the two walls. The start square spans
    x = 0..``start_size``; the left wall is at x = −2, the source 4 m before the right wall.
    """
    if layers < 1:
        raise ValueError("layers: must be >= 1")
    if not 0 < radius_min <= radius_max:
        raise ValueError("radius_min, radius_max: need 0 < radius_min <= radius_max")
    if not 0 <= jitter < 0.5:
        raise ValueError("jitter: must be in [0, 0.5)")
    if first_gap <= 0 or last_gap <= 0:
        raise ValueError("first_gap, last_gap: must be > 0")
    if width < start_size + 2 * wall_radius:
        raise ValueError("width: must exceed start_size")
    rng = _rng(seed)
    half = width / 2
    source = (length - 4.0, 0.0)
    x_first = start_size + first_gap + radius_max + x_jitter + 1.0
    x_last = source[0] - 4.0 - radius_max - x_jitter
    if x_last < x_first:
        raise ValueError(f"length: {length} m is too short for the start square, layers and source")
    layer_x = np.linspace(x_first, x_last, layers)
    gaps = np.linspace(first_gap, last_gap, layers)
    inner = width - 2 * wall_radius  # free width between the walls' surfaces
    circles = []
    for lx, g in zip(layer_x, gaps):
        r = rng.uniform(radius_min, radius_max, size=int(inner / (2 * radius_min + g)) + 2)
        # the most circles whose row, with gap g between them, leaves >= g at both walls
        row = np.cumsum(2 * r) + g * np.arange(len(r))  # row length with n = 1.. circles
        n = int(np.searchsorted(row, inner - 2 * g, side="right"))
        if n == 0:
            continue
        r = r[:n]
        u = rng.uniform(-1.0, 1.0, size=n - 1)
        between = g * (1.0 + jitter * (u - u.mean())) if n > 1 else np.zeros(0)  # mean exactly g
        free = inner - 2 * r.sum() - between.sum()  # left for the two wall gaps, >= 2g
        lo = g + (free - 2 * g) * rng.uniform(0.25, 0.75)  # spare width split between the walls
        y = -half + wall_radius + lo + r[0] + np.concatenate([[0.0], np.cumsum(between + r[:-1] + r[1:])])
        x = lx + rng.uniform(-x_jitter, x_jitter, size=n)
        circles.append(np.column_stack([x, y, r]))
    bounds = (-2.0, -half, float(length), half)
    return WorldSpec(
        name="obstacle-course",
        circles=np.vstack(circles) if circles else np.zeros((0, 3)),
        polygons=(),
        walls=box_walls(bounds),
        wall_radius=wall_radius,
        start_box=(0.0, -start_size / 2, start_size, start_size / 2),
        source=source,
        layer_x=layer_x,
        bounds=bounds,
    )


def _arena(size: float, start_size: float = 6.0) -> tuple[Box, Box, tuple[float, float]]:
    """Bounds, start box (left, centred) and off-centre source of a square arena."""
    h = size / 2
    start = (-h + 2.0, -start_size / 2, -h + 2.0 + start_size, start_size / 2)
    return (-h, -h, h, h), start, (size / 4, size / 8)


def empty_arena(size: float = 40.0, wall_radius: float = 0.1, start_size: float = 6.0) -> WorldSpec:
    """A square arena with walls only; start box on the left, source off-centre."""
    if size <= 12.0:
        raise ValueError("size: must be > 12 m")
    if not 1.0 < start_size < size / 2:
        raise ValueError("start_size: must be in (1, size/2)")
    bounds, start, source = _arena(size, start_size)
    return WorldSpec("empty", np.zeros((0, 3)), (), box_walls(bounds), wall_radius, start, source, np.zeros(0), bounds)


def forest(
    seed: int | np.random.Generator = 0,
    size: float = 40.0,
    density: float = 0.05,
    radius: tuple[float, float] = (0.3, 0.8),
    min_gap: float = 1.2,
    source_clear: float = 3.0,
    wall_radius: float = 0.1,
    max_tries: int = 20000,
    start_size: float = 6.0,
) -> WorldSpec:
    """Random non-overlapping circles ("trees") in the square arena of ``empty_arena``.

    ``density`` is the target fraction of the arena area covered by trees. Trees keep a
    surface gap of at least ``min_gap`` to each other and to the walls, stay out of the
    start box (plus ``min_gap``) and out of a disc of ``source_clear`` m round the source.
    Sampling stops at the target cover or after ``max_tries`` draws.
    """
    if size <= 12.0:
        raise ValueError("size: must be > 12 m")
    if not 0 < density < 1:
        raise ValueError("density: must be in (0, 1)")
    if not 0 < radius[0] <= radius[1]:
        raise ValueError("radius: need 0 < min <= max")
    if not 1.0 < start_size < size / 2:
        raise ValueError("start_size: must be in (1, size/2)")
    rng = _rng(seed)
    bounds, start, source = _arena(size, start_size)
    h = size / 2
    target = density * size * size
    sx0, sy0, sx1, sy1 = start
    trees = np.zeros((0, 3))
    covered = 0.0
    for _ in range(max_tries):
        if covered >= target:
            break
        r = rng.uniform(*radius)
        lim = h - wall_radius - min_gap - r
        x, y = rng.uniform(-lim, lim, size=2)
        if sx0 - min_gap - r < x < sx1 + min_gap + r and sy0 - min_gap - r < y < sy1 + min_gap + r:
            continue
        if np.hypot(x - source[0], y - source[1]) < source_clear + r:
            continue
        if len(trees) and np.any(np.hypot(trees[:, 0] - x, trees[:, 1] - y) < trees[:, 2] + r + min_gap):
            continue
        trees = np.vstack([trees, [[x, y, r]]])
        covered += np.pi * r * r
    return WorldSpec("forest", trees, (), box_walls(bounds), wall_radius, start, source, np.zeros(0), bounds)


GENERATORS: dict[str, Callable[..., WorldSpec]] = {
    "obstacle-course": obstacle_course,
    "empty": empty_arena,
    "forest": forest,
}


def world_from_name(name: str, ignore_unknown: bool = False, **params: Any) -> WorldSpec:
    """Build a preset world by name. With ``ignore_unknown`` parameters the generator does
    not take (e.g. ``layers`` for "forest") are dropped instead of raising ``TypeError``."""
    try:
        gen = GENERATORS[name]
    except KeyError:
        raise ValueError(f"unknown world {name!r}; choose one of {sorted(GENERATORS)}") from None
    if ignore_unknown:
        accepted = inspect.signature(gen).parameters
        params = {k: v for k, v in params.items() if k in accepted}
    return gen(**params)


BodyType = Literal["kinematic", "dynamic"]


BODY_FIELDS = (pymunk.batch.BodyFields.POSITION | pymunk.batch.BodyFields.ANGLE | pymunk.batch.BodyFields.VELOCITY
               | pymunk.batch.BodyFields.ANGULAR_VELOCITY)  # x, y, angle, vx, vy, w in the buffer, body by body
MOTION_FIELDS = pymunk.batch.BodyFields.VELOCITY | pymunk.batch.BodyFields.ANGULAR_VELOCITY


class RunSpace:
    """One ``pymunk.Space`` for one Monte-Carlo run: static obstacles and walls, plus one
    circular body per robot. Robot ``i``'s shape has ``ShapeFilter(group=i + 1)``, so a query
    made with ``self.filters[i]`` skips the robot's own shape.

    The robots' bodies are the space's first ``N`` bodies in pymunk's own order (they are added
    first and never removed; a body turned kinematic keeps its place), which lets
    :meth:`bodies` and :meth:`set_velocities` read and write them all in one call."""

    def __init__(
        self,
        spec: WorldSpec,
        positions: np.ndarray,
        robot_radius: float = 0.5,
        body_type: BodyType = "kinematic",
        mass: float = 1.0,
        collision_slop: float = 0.01,
    ) -> None:
        pos = np.asarray(positions, dtype=float)
        if pos.ndim != 2 or pos.shape[1] != 2:
            raise ValueError(f"positions: expected (N, 2), got {pos.shape}")
        if robot_radius <= 0:
            raise ValueError("robot_radius: must be > 0")
        if body_type not in ("kinematic", "dynamic"):
            raise ValueError(f"body_type: {body_type!r} is not 'kinematic' or 'dynamic'")
        self.robot_radius = float(robot_radius)
        self.body_type: BodyType = body_type
        self.space = pymunk.Space()
        self.space.gravity = (0.0, 0.0)
        self.space.collision_slop = collision_slop  # default 0.1 m would allow visible overlap
        self._spec = spec
        sb = self.space.static_body
        self.wall_shapes: list[pymunk.Segment] = []
        for a, b in spec.walls:
            s = pymunk.Segment(sb, tuple(a), tuple(b), spec.wall_radius)
            self._tag(s, OBSTACLE, CAT_WALL)
            self.wall_shapes.append(s)
        self.circle_shapes = [self._circle_shape(*c) for c in spec.circles]
        self.polygon_shapes = [self._poly_shape(p) for p in spec.polygons]
        self.space.add(*self.wall_shapes, *self.circle_shapes, *self.polygon_shapes)
        self.robot_bodies: list[pymunk.Body] = []
        self.robot_shapes: list[pymunk.Circle] = []
        self.filters: list[pymunk.ShapeFilter] = []
        for i, p in enumerate(pos):
            if body_type == "dynamic":
                body = pymunk.Body(mass, pymunk.moment_for_circle(mass, 0.0, self.robot_radius))
            else:
                body = pymunk.Body(body_type=pymunk.Body.KINEMATIC)
            body.position = (float(p[0]), float(p[1]))
            shape = pymunk.Circle(body, self.robot_radius)
            self._tag(shape, ROBOT, CAT_ROBOT, group=i + 1)
            self.space.add(body, shape)
            self.robot_bodies.append(body)
            self.robot_shapes.append(shape)
            self.filters.append(pymunk.ShapeFilter(group=i + 1))
        self._robot_index: dict[pymunk.Shape, int] = {s: i for i, s in enumerate(self.robot_shapes)}
        self._keys: dict[pymunk.Shape, int] | None = None
        self.dynamic = np.full(len(self.robot_bodies), body_type == "dynamic")  # (N,) bool: not disabled
        self._read, self._write = pymunk.batch.Buffer(), pymunk.batch.Buffer()
        self._last = np.zeros((0, 6))

    @staticmethod
    def _tag(shape: pymunk.Shape, ctype: int, cat: int, group: int = 0) -> None:
        shape.collision_type = ctype
        shape.filter = pymunk.ShapeFilter(group=group, categories=cat)

    def _circle_shape(self, x: float, y: float, r: float) -> pymunk.Circle:
        s = pymunk.Circle(self.space.static_body, float(r), (float(x), float(y)))
        self._tag(s, OBSTACLE, CAT_OBSTACLE)
        return s

    def _poly_shape(self, poly: np.ndarray) -> pymunk.Poly:
        s = pymunk.Poly(self.space.static_body, [tuple(v) for v in poly])
        self._tag(s, OBSTACLE, CAT_OBSTACLE)
        return s

    @property
    def spec(self) -> WorldSpec:
        """The world as it is now, edits included."""
        return self._spec

    @property
    def n_robots(self) -> int:
        return len(self.robot_bodies)

    @property
    def obstacle_shapes(self) -> list[pymunk.Shape]:
        """Obstacle shapes in spec index order (circles, then polygons)."""
        return [*self.circle_shapes, *self.polygon_shapes]

    def robot_of(self, shape: pymunk.Shape) -> int | None:
        """Index of the robot owning ``shape`` (None for obstacles and walls)."""
        return self._robot_index.get(shape)

    def body_keys(self) -> dict[pymunk.Shape, int]:
        """Shape → key: robot index (0..N−1) or N + circle index; walls and polygons absent."""
        if self._keys is None:
            n = self.n_robots
            self._keys = dict(self._robot_index)
            self._keys.update((s, n + j) for j, s in enumerate(self.circle_shapes))
        return self._keys

    def positions(self) -> np.ndarray:
        """(N, 2) robot positions."""
        return self.bodies()[:, :2].copy()

    def bodies(self) -> np.ndarray:
        """(N, 6) every robot body's x, y, angle, vx, vy and angular velocity, read in one
        call (``pymunk.batch``); the rows of the space's other bodies are kept for
        :meth:`set_velocities`."""
        self._read.clear()
        pymunk.batch.get_space_bodies(self.space, BODY_FIELDS, self._read)
        self._last = np.frombuffer(self._read.float_buf(), dtype=float).reshape(-1, 6).copy()
        return self._last[: self.n_robots]

    def set_velocities(self, velocity: np.ndarray, spin: np.ndarray) -> None:
        """Give every robot body the velocity (N, 2) and angular velocity (N,) in one call. The
        call writes every body of the space, so the other bodies get back what the last
        :meth:`bodies` read of them; a body given its own values is unchanged (the space
        never sleeps, so waking a body does nothing)."""
        n = self.n_robots
        out = self._last[:, 3:6].copy()
        out[:n, :2], out[:n, 2] = velocity, spin
        self._write.set_float_buf(out.reshape(-1))
        pymunk.batch.set_space_bodies(self.space, MOTION_FIELDS, self._write)

    def disable(self, i: int) -> None:
        """Robot ``i`` stops where it is for good: its body becomes kinematic with no velocity
        and its shape takes the collision type ``DISABLED``. A body that is not dynamic (a
        kinematic space's) is left as it is."""
        if not self.dynamic[i]:
            return
        body = self.robot_bodies[i]
        body.body_type = pymunk.Body.KINEMATIC
        body.velocity = (0.0, 0.0)
        body.angular_velocity = 0.0
        self.robot_shapes[i].collision_type = DISABLED
        self.dynamic[i] = False

    def set_positions(self, x: np.ndarray) -> None:
        """Teleport every robot to ``x`` (N, 2) and reindex its shape for queries."""
        x = np.asarray(x, dtype=float)
        if x.shape != (self.n_robots, 2):
            raise ValueError(f"x: expected {(self.n_robots, 2)}, got {x.shape}")
        for b, p in zip(self.robot_bodies, x.tolist()):
            b.position = p
            self.space.reindex_shapes_for_body(b)

    def move_robot(self, i: int, p: np.ndarray) -> None:
        """Teleport robot ``i`` to ``p`` and reindex its shape for queries."""
        body = self.robot_bodies[i]
        body.position = (float(p[0]), float(p[1]))
        self.space.reindex_shapes_for_body(body)

    def contacts_of(self, i: int, tol: float = 0.0) -> list[int | None]:
        """Bodies within ``tol`` of robot ``i``'s surface: robot indices, or None for obstacles."""
        x, y = self.robot_bodies[i].position
        hits = self.space.point_query((x, y), self.robot_radius + tol, self.filters[i])
        return [self.robot_of(h.shape) for h in hits]

    def touching(self, tol: float = 0.0) -> np.ndarray:
        """(N,) bool: robot i is within ``tol`` m of (or overlapping) any other body."""
        q = self.space.point_query_nearest
        return np.array(
            [q((b.position[0], b.position[1]), self.robot_radius + tol, f) is not None
             for b, f in zip(self.robot_bodies, self.filters)],
            dtype=bool,
        )

    def add_circle(self, x: float, y: float, r: float) -> int:
        """Add a static circle; returns its obstacle index."""
        spec = self._spec.with_circle(x, y, r)
        s = self._circle_shape(x, y, r)
        self.space.add(s)
        self.circle_shapes.append(s)
        self._spec, self._keys = spec, None
        return len(self.circle_shapes) - 1

    def remove_obstacle(self, index: int) -> None:
        """Remove obstacle ``index`` (circles first, then polygons)."""
        spec = self._spec.without_obstacle(index)
        m = len(self.circle_shapes)
        shape = self.circle_shapes.pop(index) if index < m else self.polygon_shapes.pop(index - m)
        self.space.remove(shape)
        self._spec, self._keys = spec, None

    def remove_obstacle_near(self, x: float, y: float, tol: float = 1.0) -> int | None:
        """Remove the obstacle closest to (x, y) within ``tol``; returns its index or None."""
        i = self._spec.nearest_obstacle(x, y, tol)
        if i is not None:
            self.remove_obstacle(i)
        return i

    def move_obstacle(self, index: int, x: float, y: float) -> None:
        """Move obstacle ``index`` to (x, y) (polygon: its vertex mean), keeping its index."""
        spec = self._spec.moved_obstacle(index, x, y)
        m = len(self.circle_shapes)
        old: pymunk.Shape
        new: pymunk.Shape
        if index < m:
            old, circle = self.circle_shapes[index], self._circle_shape(*spec.circles[index])
            self.circle_shapes[index] = new = circle
        else:
            old, poly = self.polygon_shapes[index - m], self._poly_shape(spec.polygons[index - m])
            self.polygon_shapes[index - m] = new = poly
        self.space.remove(old)
        self.space.add(new)
        self._spec, self._keys = spec, None
