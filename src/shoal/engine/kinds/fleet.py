"""Chapters 4–5: robots with bodies in an obstacle world.

One tick (Algorithms 1 and 2): bests → sense → coefficients (constant or DVC) →
velocity (RPSO, Adapted RPSO, robot-centred, non-omni) → move (kinematic or pymunk) →
metrics. Arrays are (runs, robots, …); run ``i`` draws from child ``i`` of
``SeedSequence(seed)``, like :class:`shoal.engine.kinds.swarm.Simulation`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Any, ClassVar, Literal, cast

import numpy as np

from ..core import parallel
from ..core.compiled_draws import CompiledDraws
from ..core.contract import check_live
from ..core.positions import Oracle, PositionSource
from ..core.rng import run_generators
from ..core.schema import Column, Schema
from ..core.snapshot import SnapshotError, arrays, fields_of, from_fields, integer, part, rng_states, set_rng_states
from ..core.steering import SLACK, Steering, given_coefficients
from ..pso.bests import best_of, improves
from ..robots import kernels, tick_kernels
from ..robots.dvc import approach_guard, dvc_nonomni, dvc_omni, forward_guard, w_max
from ..robots.laws import ROBOT_LAWS, Inertia, Limits, rotational_energy_factor, steered_command
from ..robots.motion import Drive, Kinematic, Physics
from ..robots.sensing import S_FLOOR, SECTORS, SectorReading, sense, virtual_force
from ..robots.world import RunSpace, WorldSpec

ACTIVE, COLLIDED = 0, 1
# A stall (ours, a metric only): an operational robot slower than STALL_SPEED m/s for at
# least STALL_STEPS ticks in a row, e.g. squeezed between bodies it may not approach.
STALL_SPEED = 0.01
STALL_STEPS = 10
STATE_DTYPES = (float, float, float, float, np.int8, np.int64, float, float)  # of tick_kernels.STATE


@dataclass
class FleetParams:
    """Controller and robot parameters of a fleet (Tables 4.1 and 5.1 by default)."""

    law: str = "adapted-rpso"  # a key of robots.laws.ROBOT_LAWS
    dvc: bool = True
    dt: float = 1.0
    omega: float = 0.1  # constant mode; ω = 1 − β: docs/readings.md, "Table 4.1: ω and the tuned speed"
    c: tuple[float, ...] = (0.4296, 0.4296, 0.8591)  # constant c1, c2, c3
    alpha: float = 0.9
    beta: float = 0.9
    gamma: float = 1.0
    c1_share: float = 0.5
    sensing_range: float = 3.0
    robot_radius: float = 0.5
    v_max: float = 3.0
    a_max: float = 10.0
    motion: Literal["kinematic", "physics"] = "kinematic"
    drive: Drive = "holonomic"
    r_min: float = 0.0
    s_min: float = 0.0
    rotational_energy: Inertia = "pi"
    update: Literal["sequential", "simultaneous"] = "sequential"
    guard: bool = False  # DVC inertia guard (ours): see dvc.approach_guard
    spawn_gap: float = 0.3  # free space between robots at the start [m]
    contact_tolerance: float = 1e-9  # [m] float-noise allowance: a deeper overlap is a collision (docs/readings.md)

    def __post_init__(self) -> None:
        if ROBOT_LAWS.pick(self.law).dvc is None and self.dvc:
            raise ValueError(f"dvc: law {self.law!r} has no DVC form")
        if not self.dt > 0:
            raise ValueError(f"dt: must be > 0, got {self.dt}")

    @property
    def body_frame(self) -> bool:
        return ROBOT_LAWS[self.law].body_frame

    @property
    def limits(self) -> Limits:
        return Limits(self.v_max, self.rotational_energy, self.robot_radius, self.r_min)

    def tick_params(self) -> kernels.TickParams:
        """These parameters as the compiled tick reads them (:func:`kernels.phase_b`)."""
        law = ROBOT_LAWS[self.law]
        coefficients = {None: kernels.CONSTANT, "omni": kernels.DVC_OMNI, "nonomni": kernels.DVC_NONOMNI}[
            law.dvc if self.dvc else None]
        c = cast(tuple[float, float, float, float, float],
                 (tuple(float(v) for v in self.c) + (0.0,) * 5)[: law.terms] + (0.0,) * (5 - law.terms))
        wm = w_max(self.v_max, self.dt, self.rotational_energy, self.robot_radius) if coefficients else 0.0
        return kernels.TickParams(
            law=kernels.LAWS.index(self.law), coefficients=coefficients, drive=kernels.DRIVES.index(self.drive),
            sequential=self.update == "sequential", guard=self.guard, body_frame=law.body_frame, terms=law.terms,
            dt=float(self.dt), sensing_range=float(self.sensing_range), radius=float(self.robot_radius),
            v_max=float(self.v_max), omega=float(self.omega), c=c, alpha=float(self.alpha), beta=float(self.beta),
            gamma=float(self.gamma), c1_share=float(self.c1_share), s_min=float(self.s_min),
            k_omni=self.alpha * self.beta / (self.dt * math.sqrt(2)), w_max=wm,
            rot_factor=float(rotational_energy_factor(self.rotational_energy, self.robot_radius))
            if law.body_frame else 0.0,
            r_min=float(self.r_min), tolerance=float(self.contact_tolerance), s_floor=S_FLOOR, reach=self.reach)

    @property
    def reach(self) -> float:
        """R_s + 2r + 2·v_max·Δt: robots farther apart can neither see nor reach each other in a tick."""
        return self.sensing_range + 2.0 * self.robot_radius + 2.0 * self.v_max * self.dt


@dataclass
class FleetState:
    x: np.ndarray  # (R, N, 2)
    heading: np.ndarray  # (R, N)
    u: np.ndarray  # (R, N, 2) world-frame velocity (realised)
    cmd: np.ndarray  # (R, N, 2) controller state: global u, or body-frame [v, w]
    y: np.ndarray  # (R, N, 2) personal bests
    f_y: np.ndarray  # (R, N)
    yg: np.ndarray  # (R, 2)
    best_fitness: np.ndarray  # (R,) cost of y_g
    f: np.ndarray  # (R, N) cost at x
    status: np.ndarray  # (R, N) int8: 0 active, 1 collided
    slow: np.ndarray  # (R, N) ticks in a row an active robot has moved slower than STALL_SPEED
    k: int = 0
    reading: SectorReading | None = None
    force: np.ndarray | None = None  # (R, N, 2) F_t [4.3]
    omega: np.ndarray | None = None  # (R, N)
    c: np.ndarray | None = None  # (n, R, N) coefficients in force this tick
    a: np.ndarray = field(default_factory=lambda: np.zeros(0))
    commanded: np.ndarray | None = None  # (R, N, 2) each robot's command this tick (before a collision zeroed it)


COLUMNS: Schema = (
    Column("com_fitness", "m", "float", "CoM fitness [4.17]: the mean x_1 of all robots"),
    Column("collided", "count", "int", "robots disabled by a collision (an overlap deeper than "
                                        "robot.contact_tolerance)"),
    Column("stalled", "count", "int", "operational robots slower than the stall speed for the stall time"),
    Column("operational", "count", "int", "robots not disabled"),
    Column("layers_passed", "count", "int", "obstacle layers whose x lies below the CoM"),
)


@dataclass
class FleetInfo:
    t: float
    com_fitness: np.ndarray  # (R,) mean x_1 of all robots [4.17]
    collided: np.ndarray  # (R,)
    stalled: np.ndarray  # (R,) operational robots stalled (slower than STALL_SPEED for STALL_STEPS ticks)
    operational: np.ndarray  # (R,)
    layers_passed: np.ndarray  # (R,) layers with x below the CoM
    best_fitness: np.ndarray  # (R,) distance of the global best to the source
    max_speed: np.ndarray  # (R,)

    def columns(self) -> dict[str, np.ndarray]:
        """CoM fitness [4.17], collided (overlap beyond the contact tolerance), stalled and
        operational robots, obstacle layers passed."""
        return {"com_fitness": self.com_fitness, "collided": self.collided, "stalled": self.stalled,
                "operational": self.operational, "layers_passed": self.layers_passed}


def spawn_positions(
    rng: np.random.Generator, box: tuple[float, float, float, float], n: int, radius: float, spacing: float = 0.3
) -> np.ndarray:
    """n robot centres uniformly in ``box``, at least ``spacing`` apart surface to surface:
    up to 200·n uniform candidates, each kept if it is far enough from every one kept before
    (a grid when the box is too small for that). Compiled (:func:`kernels.spaced`); the
    generator is left exactly as after drawing the candidates used, one pair at a time."""
    xmin, ymin, xmax, ymax = box
    gap = 2.0 * radius + spacing
    low, high = [xmin + radius, ymin + radius], [xmax - radius, ymax - radius]
    pts = np.empty((n, 2))
    cells = np.array([xmin, ymin, (xmax - xmin) // gap + 1, (ymax - ymin) // gap + 1], dtype=float)
    head, nxt = np.full(int(cells[2] * cells[3]), -1, np.int64), np.empty(n, np.int64)
    count, left = 0, 200 * n
    while count < n and left > 0:
        state = rng.bit_generator.state
        block = rng.uniform(low, high, size=(min(left, 4 * n + 64), 2))
        count, used = kernels.spaced(block, pts, count, gap, cells, head, nxt)
        if used < len(block):  # give back the candidates not looked at
            rng.bit_generator.state = state
            rng.uniform(low, high, size=(used, 2))
        left -= used
    if count < n:  # box too small for random placement: fill a grid, row by row
        cols = max(1, int((xmax - xmin) // gap))
        return np.array([[xmin + radius + (i % cols) * gap, ymin + radius + (i // cols) * gap] for i in range(n)])
    return pts


class Fleet:
    """A seeded swarm of robots in a world, for ``runs`` Monte-Carlo runs at once.

    Implements :class:`~shoal.engine.core.contract.Engine`; :meth:`retune` takes the
    :class:`FleetParams` of the controller and the sensing (in force from the next tick) and, on
    SLO positions, the localisation keywords (``slo``). The world, the robots' bodies and drive
    and their number need a new fleet.

    ``positions``: true (the default) or SLO-estimated positions. On SLO positions only the two
    attractors use positions; obstacle sensing stays local (six range sectors need none), the
    cost is read at the true position, and a collided robot stays in the swarm as a still robot:
    still ranged, still ranging the others, its personal best still a candidate global best."""

    LIVE: ClassVar[frozenset[str]] = frozenset(
        {"law", "dvc", "dt", "omega", "c", "alpha", "beta", "gamma", "c1_share", "sensing_range", "r_min", "s_min",
         "rotational_energy", "update", "guard", "slo"})
    COLUMNS: ClassVar[Schema] = COLUMNS
    steering: Steering | None = None  # the next tick's command from outside the law (core/steering.py)

    def __init__(self, *, world: WorldSpec, robots: int, params: FleetParams | None = None,
                 runs: int = 1, seed: int = 0, first_run: int = 0, positions: PositionSource | None = None,
                 compiled: bool = True) -> None:
        """``compiled`` False keeps the numpy tick (the reference the compiled one is tested
        against) in kinematic mode too."""
        if robots < 1 or runs < 1:
            raise ValueError("robots and runs must be >= 1")
        self.world, self.params = world, params or FleetParams()
        self.runs, self.first_run, self._robots = runs, first_run, robots
        self.positions: PositionSource = positions or Oracle()
        self.compiled = compiled
        self.reset(seed)

    # ------------------------------------------------------------------ setup
    @property
    def dt(self) -> float:
        return self.params.dt

    @property
    def t(self) -> float:
        return self.state.k * self.dt

    @property
    def robots(self) -> int:
        return self.state.x.shape[1]

    @property
    def source(self) -> np.ndarray:
        return np.asarray(self.world.source, dtype=float)

    def reset(self, seed: int | None = None) -> None:
        if seed is not None:
            self.seed = int(seed)
        self.rngs = run_generators(self.seed, self.first_run, self.runs)
        self.steering = None
        self._steered: tuple[bool, tuple[np.ndarray, np.ndarray] | None] = (False, None)
        p = self.params
        x = np.stack([spawn_positions(g, self.world.start_box, self._robots, p.robot_radius, p.spawn_gap)
                      for g in self.rngs])
        self._spaces: list[RunSpace] | None = None
        self._stale = False
        self._world_arrays: tuple[kernels.WorldArrays, kernels.Grid] | None = None
        self._tick_params: tuple[FleetParams | None, kernels.TickParams | None] = (None, None)
        self.motion = self._motion()
        heading = np.zeros(x.shape[:2])
        f = self.cost(x)
        R, N = f.shape
        best = best_of(f, False, axis=1)
        self.state = FleetState(
            x=x, heading=heading, u=np.zeros_like(x), cmd=np.zeros_like(x), y=x.copy(), f_y=f.copy(),
            yg=x[np.arange(R), best], best_fitness=f[np.arange(R), best], f=f, status=np.zeros((R, N), np.int8),
            slow=np.zeros((R, N), np.int64),
        )
        self.positions.start(x, self.state.y, self.state.k, self.seed, self.first_run)
        if p.motion == "physics":
            self._build_spaces()

    @property
    def spaces(self) -> list[RunSpace]:
        """One pymunk space per run with every robot's body where the robot is. Physics mode
        steps them; the numpy tick queries them; the compiled tick needs none, so they are
        built, or brought up to date, only when read."""
        if self._spaces is None:
            self._build_spaces()
        elif self._stale:
            for sp, x in zip(self._spaces, self.state.x):
                sp.set_positions(x)
            self._stale = False
        return self._spaces  # type: ignore[return-value]

    def _build_spaces(self) -> None:
        p, s = self.params, self.state
        body: Literal["kinematic", "dynamic"] = "dynamic" if p.motion == "physics" else "kinematic"
        self._spaces = [RunSpace(self.world, s.x[r], p.robot_radius, body_type=body) for r in range(self.runs)]
        self._stale = False
        if p.motion == "physics":
            self.motion = self._motion()
            for r, sp in enumerate(self._spaces):
                for i, b in enumerate(sp.robot_bodies):
                    b.angle = float(s.heading[r, i])
                    if s.status[r, i] != ACTIVE:
                        sp.disable(i)

    def _motion(self) -> Kinematic | Physics:
        p = self.params
        if p.motion == "physics":
            return Physics(p.drive, p.v_max, p.a_max, tolerance=p.contact_tolerance)
        return Kinematic(p.drive, p.v_max, tolerance=p.contact_tolerance)

    def retune(self, **changes: Any) -> list[str]:
        """Change :data:`LIVE` settings from the next tick on, keeping the fleet; returns the names
        that changed. Refused (``ValueError``, nothing changed) for other keywords."""
        check_live(self.LIVE, changes)
        slo = changes.pop("slo", None)
        params = replace(self.params, **changes)  # validates
        changed = [k for k in changes if getattr(params, k) != getattr(self.params, k)]
        if slo:
            self.positions.retune(**slo)
            changed.append("slo")
        self.params = params
        return changed

    def cost(self, x: np.ndarray) -> np.ndarray:
        """Distance to the source, the cost of Algorithms 1 and 2."""
        return np.linalg.norm(x - self.source, axis=-1)

    def set_world(self, world: WorldSpec) -> None:
        """Replace the static obstacles of every run at once (robots keep their state)."""
        self.world = world
        self._world_arrays = None
        self._spaces = None
        if self.params.motion == "physics":
            self._build_spaces()

    # ------------------------------------------------------------------ tick
    def _draw(self, shape: tuple[int, ...]) -> np.ndarray:
        """U(0,1) draws of shape (n, R, N, …), one generator per run."""
        return np.stack([g.random((shape[0],) + shape[2:]) for g in self.rngs], axis=1)

    def _update_bests(self) -> None:
        """Phase A: localise (on SLO positions), then the bests, scored at the true positions."""
        s = self.state
        self.positions.observe(s.x, s.k)
        before = s.f_y.copy()
        active = s.status == ACTIVE
        s.f = self.cost(s.x)
        better = active & improves(s.f, s.f_y, False)  # disabled robots keep their last best: docs/readings.md,
        # "Disabled robots"; NaN is never a best (pso/bests.py)
        s.y = np.where(better[..., None], s.x, s.y)
        s.f_y = np.where(better, s.f, s.f_y)
        idx = best_of(s.f_y, False, axis=1)
        runs = np.arange(self.runs)
        s.yg, s.best_fitness = s.y[runs, idx], s.f_y[runs, idx]
        self.positions.keep(s.f_y != before)  # a new best is where the robot stands

    def _coefficients(self, gap: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        omega, c = self._own_coefficients(gap)
        given = self._steered[1]
        if given is None:
            return omega, c
        return np.where(np.isnan(given[0]), omega, given[0]), np.where(np.isnan(given[1]), c, given[1])

    def _own_coefficients(self, gap: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        p, shape = self.params, gap.shape[:2]
        law = ROBOT_LAWS[p.law]
        if p.dvc and law.dvc == "nonomni":
            wm = w_max(p.v_max, p.dt, p.rotational_energy, p.robot_radius)
            return dvc_nonomni(gap, alpha=p.alpha, beta=p.beta, dt=p.dt, sensing_range=p.sensing_range,
                               w_max=wm, c1_share=p.c1_share, v_max=p.v_max)
        if p.dvc and law.dvc == "omni":
            return dvc_omni(gap, alpha=p.alpha, beta=p.beta, dt=p.dt, c1_share=p.c1_share)
        c = np.asarray((tuple(p.c) + (0.0,) * law.terms)[: law.terms], dtype=float)  # constant c_1..c_n
        return np.full(shape, p.omega), np.broadcast_to(c.reshape((-1, 1, 1)), (c.size,) + shape).copy()

    def _draws(self) -> np.ndarray:
        """This tick's U(0,1) draws for every robot, drawn once so the update order does not
        change the random stream."""
        shape, law = self.state.x.shape, ROBOT_LAWS[self.params.law]
        return self._draw((law.terms,) + (shape[:2] if law.draws == "robot" else shape))

    def _attractors(self) -> tuple[np.ndarray, np.ndarray]:
        """Each robot's vectors to its personal best and to the global best, (R, N, 2) each, as
        the robots know them (true or SLO positions)."""
        s = self.state
        return self.positions.to_personal(s.x, s.y), self._to_global()

    def _to_global(self) -> np.ndarray:
        s = self.state
        return self.positions.to_owner(s.x, s.y, best_of(s.f_y, False, axis=1))

    def believed_gbest(self) -> np.ndarray:
        """(R, N, 2) where each robot believes the global best is (y_g itself on true positions)."""
        return self.state.x + self._to_global()

    def _velocity(self, omega: np.ndarray, c: np.ndarray, force: np.ndarray, r: np.ndarray) -> np.ndarray:
        p, s = self.params, self.state
        if self._steered[0]:  # the command in s.cmd, from outside the law
            return steered_command(s.cmd, ROBOT_LAWS[p.law], p.limits, SLACK)
        g_p, g_g = self._attractors()
        return ROBOT_LAWS[p.law].command(s.cmd, g_p, g_g, force, s.heading, c, omega, r, p.limits)

    def _guard(self, cmd: np.ndarray, reading: SectorReading, gap: np.ndarray) -> np.ndarray:
        p = self.params
        if p.body_frame:
            return np.stack([forward_guard(cmd[..., 0], gap, alpha=p.alpha, dt=p.dt), cmd[..., 1]], axis=-1)
        return approach_guard(cmd, self.state.x, reading.point, gap, alpha=p.alpha, dt=p.dt)

    def _touching(self, moved: np.ndarray) -> np.ndarray:
        """Robots overlapping a body by more than the contact tolerance after a move: the
        movers and whatever they overlap (only a mover can have made a new contact)."""
        out = np.zeros_like(moved)
        if self._compiled_queries():
            world, grid = self._kernel_world()
            kernels.touching_bodies(self._body_positions(), moved, self._kernel_params(), world, grid, out)
            return out & (self.state.status == ACTIVE)
        for r, sp in enumerate(self.spaces):
            for i in map(int, np.flatnonzero(moved[r])):
                bodies = sp.contacts_of(i, -self.params.contact_tolerance)
                if bodies:
                    out[r, i] = True
                    out[r, [j for j in bodies if j is not None]] = True
        return out & (self.state.status == ACTIVE)

    def _sense(self, m: np.ndarray) -> SectorReading:
        """The six-sector reading of the robots ``m`` where they stand, the others where their
        bodies are: pymunk's queries (:func:`sense`), or their compiled twins in physics mode."""
        p, s = self.params, self.state
        if self._compiled_queries():
            x = self._body_positions()
            if np.array_equal(x[m].view(np.uint64), s.x[m].view(np.uint64)):  # always, between ticks
                R, N = m.shape
                reading = SectorReading(gap=np.full((R, N, SECTORS), float(p.sensing_range)),
                                        point=np.full((R, N, SECTORS, 2), np.nan),
                                        centre=np.full((R, N, SECTORS, 2), np.nan), hit=np.zeros((R, N, SECTORS), bool))
                turn = np.array(s.heading, dtype=float) if p.body_frame else np.zeros((R, N))
                world, grid = self._kernel_world()
                kernels.sense_bodies(x, turn, m, self._kernel_params(), world, grid, reading.gap, reading.point,
                                     reading.centre, reading.hit)
                return reading
        return sense(self.spaces, s.x, s.heading, sensing_range=p.sensing_range, robot_frame=p.body_frame, active=m)

    def sense_now(self) -> SectorReading:
        """The six-sector reading of every robot where it stands now, as if all sensed before any
        moved (what a controller outside the law observes; nothing changes). Compiled queries in a
        world of circles and walls, pymunk's otherwise: the same gaps."""
        p, s = self.params, self.state
        R, N = s.status.shape
        everyone = np.ones((R, N), bool)
        if self.world.polygons or p.law not in kernels.LAWS or p.drive not in kernels.DRIVES:
            return sense(self.spaces, s.x, s.heading, sensing_range=p.sensing_range, robot_frame=p.body_frame,
                         active=everyone)
        reading = SectorReading(gap=np.full((R, N, SECTORS), float(p.sensing_range)),
                                point=np.full((R, N, SECTORS, 2), np.nan), centre=np.full((R, N, SECTORS, 2), np.nan),
                                hit=np.zeros((R, N, SECTORS), bool))
        turn = np.array(s.heading, dtype=float) if p.body_frame else np.zeros((R, N))
        x = self._body_positions() if p.motion == "physics" else np.ascontiguousarray(s.x, dtype=float)
        world, grid = self._kernel_world()
        kernels.sense_bodies(x, turn, everyone, self._kernel_params(), world, grid, reading.gap, reading.point,
                             reading.centre, reading.hit)
        return reading

    def _compiled_queries(self) -> bool:
        """Physics mode senses and checks contacts through :func:`kernels.sense_bodies` and
        :func:`kernels.touching_bodies` (pymunk's bits: ``tests/test_physics.py``) in worlds of
        circles and walls, unless the fleet was made with ``compiled=False``."""
        p = self.params
        return (self.compiled and p.motion == "physics" and not self.world.polygons
                and p.law in kernels.LAWS and p.drive in kernels.DRIVES)

    def _body_positions(self) -> np.ndarray:
        """(R, N, 2) where every robot's body is in its run's space."""
        return np.stack([sp.bodies()[:, :2] for sp in self.spaces])

    def _kernel_world(self) -> tuple[kernels.WorldArrays, kernels.Grid]:
        """The world's static bodies and the uniform grid the kernels read (built once per world)."""
        if self._world_arrays is None:
            grid = kernels.make_grid(self.world.bounds, self.params.sensing_range + 2.0 * self.params.robot_radius)
            w = self.world
            self._world_arrays = (kernels.world_arrays(w.circles, w.walls, w.wall_radius, grid), grid)
        return self._world_arrays

    def _kernel_params(self) -> kernels.TickParams:
        """These parameters as the kernels read them, built again after a retune (or a change in place)."""
        p = self.params
        if self._tick_params[0] != p:
            self._tick_params = (replace(p), p.tick_params())
        return self._tick_params[1]  # type: ignore[return-value]

    def _groups(self, active: np.ndarray) -> list[np.ndarray]:
        """Which robots decide and move together.

        ``sequential`` (Algorithms 1–2 as written: a loop over robots, each sensing the ones
        already moved). Robots farther apart than R_s + 2r + 2·v_max·Δt cannot see or reach
        each other within one tick, so any order among them gives the same result; a greedy
        colouring of the "can interact" graph (vectorised over runs) gives a few groups that
        are processed one after another, which is a sequential update in colour order.
        ``simultaneous`` and physics move everyone at once.
        """
        p = self.params
        if p.update == "simultaneous" or p.motion == "physics":
            return [active]
        x = self.state.x
        near = np.linalg.norm(x[:, :, None, :] - x[:, None, :, :], axis=-1) <= p.reach  # (R, N, N)
        R, N = active.shape
        colour = np.full((R, N), -1)
        rows = np.arange(R)
        for i in range(N):  # greedy: the smallest colour no earlier neighbour has
            taken = np.zeros((R, N + 1), dtype=bool)
            nb = near[:, i, :i] & (colour[:, :i] >= 0)
            taken[np.repeat(rows, i)[nb.ravel()], colour[:, :i][nb]] = True
            colour[:, i] = np.argmin(taken, axis=1)
        return [active & (colour == k) for k in range(int(colour.max()) + 1)]

    def step(self) -> FleetInfo:
        """Advance every run by one control tick (steered by :attr:`steering`, if set)."""
        if self.steering is None and self._fused_tick():
            return self._fused_step()
        p, s = self.params, self.state
        steering, self.steering = self.steering, None
        self._update_bests()  # phase A, all robots
        r = self._draws()
        R, N = s.status.shape
        out = kernels.Outputs(
            omega=np.full((R, N), np.nan), c=np.zeros((r.shape[0], R, N)), force=np.zeros_like(s.x),
            gap=np.full((R, N, SECTORS), p.sensing_range), point=np.full((R, N, SECTORS, 2), np.nan),
            centre=np.full((R, N, SECTORS, 2), np.nan), hit=np.zeros((R, N, SECTORS), bool))
        given = given_coefficients(steering, r.shape[0], (R, N))
        if given is not None:  # the kernel reads them from out
            out.omega[:], out.c[:] = given
        steered = steering is not None and steering.velocity is not None
        if steering is not None and steering.velocity is not None:
            given_cmd = np.broadcast_to(np.asarray(steering.velocity, dtype=float), s.x.shape)
            s.cmd = np.where((s.status == ACTIVE)[..., None], given_cmd, s.cmd)  # a disabled robot has none
        self._steered = (steered, given)
        try:
            sensed = self._compiled_phase_b(r, out) if self._compiled_tick() else self._phase_b(r, out)
        finally:
            self._steered = (False, None)
        s.commanded = s.cmd.copy()
        s.cmd[s.status != ACTIVE] = 0.0
        s.u[s.status != ACTIVE] = 0.0
        slow = (s.status == ACTIVE) & (np.linalg.norm(s.u, axis=-1) < STALL_SPEED)
        s.slow = np.where(slow, s.slow + 1, 0)
        s.reading = SectorReading(out.gap, out.point, out.centre, out.hit) if sensed else None
        s.force, s.omega, s.c = out.force, out.omega, out.c
        s.k += 1
        self.positions.observe(s.x, s.k)  # where the moves ended: current beliefs for drawing
        return self.info()

    def _phase_b(self, r: np.ndarray, out: kernels.Outputs) -> bool:
        """Phase B in numpy, one group of robots at a time (:meth:`_groups`): the group senses
        (pymunk queries), decides and moves; ``out`` gets each robot's decision. Whether any
        robot sensed."""
        p, s = self.params, self.state
        sensed = False
        blind = self._steered[0] and not (p.dvc and p.guard)  # a given command needs no sensing
        for group in self._groups(s.status == ACTIVE):
            m = group & (s.status == ACTIVE)
            if not m.any():
                continue
            if blind:
                self._move(m, np.where(m[..., None], steered_command(s.cmd, ROBOT_LAWS[p.law], p.limits, SLACK), 0.0))
                continue
            sensed = True
            reading = self._sense(m)
            gap = reading.gap
            if p.s_min > 0:  # Rossides §5.4 (p. 125): keep a clearance s_min by treating it as contact distance
                gap = np.maximum(gap - p.s_min, 0.0)
            omega, c = self._coefficients(gap)
            force = virtual_force(s.x, reading, p.gamma) if not p.body_frame else np.zeros_like(s.x)
            cmd = self._velocity(omega, c, force, r)
            if p.dvc and p.guard:
                cmd = self._guard(cmd, reading, gap)
            self._move(m, np.where(m[..., None], cmd, 0.0))
            out.omega[m], out.c[:, m], out.force[m] = omega[m], c[:, m], force[m]
            out.gap[m], out.point[m], out.centre[m], out.hit[m] = (
                reading.gap[m], reading.point[m], reading.centre[m], reading.hit[m])
        return sensed

    def _move(self, m: np.ndarray, cmd: np.ndarray) -> None:
        """Move the robots ``m`` by their commands ``cmd`` (zero for the others); a contact disables."""
        p, s = self.params, self.state
        moved = self.motion.move(self.spaces, s.x, s.heading, cmd, m, p.dt)
        s.x = np.where(m[..., None], moved.x, s.x)
        s.heading = np.where(m, moved.heading, s.heading)
        s.u = np.where(m[..., None], moved.velocity, s.u)
        s.cmd = np.where(m[..., None], cmd, s.cmd)
        struck = moved.hit if moved.struck is None else moved.hit | moved.struck
        s.status = np.where(struck | self._touching(m), COLLIDED, s.status).astype(np.int8)

    def _compiled_tick(self) -> bool:
        """Kinematic motion through :func:`kernels.phase_b` (unless the fleet was made with
        ``compiled=False``): every law and drive of the kernel, in worlds of circles and walls."""
        p = self.params
        return (self.compiled and p.motion == "kinematic" and not self.world.polygons
                and p.law in kernels.LAWS and p.drive in kernels.DRIVES)

    def _compiled_phase_b(self, r: np.ndarray, out: kernels.Outputs) -> bool:
        """Phase B by :func:`kernels.phase_b`, which updates the state's arrays in place."""
        s = self.state
        world, grid = self._kernel_world()
        g_p, g_g = (np.ascontiguousarray(a, dtype=float) for a in self._attractors())
        draws = np.ascontiguousarray(r if r.ndim == 4 else r[..., None])
        s.x, s.heading, s.u, s.cmd = (np.array(a, dtype=float) for a in (s.x, s.heading, s.u, s.cmd))
        s.status = np.array(s.status, dtype=np.int8)
        params = self._kernel_params()
        if self._steered[0] or self._steered[1] is not None:
            params = params._replace(steered=self._steered[0], given=self._steered[1] is not None)
        sensed = kernels.phase_b(s.x, s.heading, s.u, s.cmd, s.status, g_p, g_g, draws, params, world, grid, out)
        self._stale = True
        return bool(sensed)

    def _fused_tick(self) -> bool:
        """The whole tick by :func:`tick_kernels.fleet_runs`: the compiled kinematic tick on true
        positions, float64 states and a point source."""
        s = self.state
        return (self._compiled_tick() and type(self.positions) is Oracle and len(self.world.source) == 2
                and s.x.dtype == s.y.dtype == s.u.dtype == s.cmd.dtype == np.float64)

    def _fused_step(self) -> FleetInfo:
        """:meth:`step` in one compiled call per block of runs (the blocks on every core): the
        same numbers, the generators left as the numpy tick leaves them."""
        s = self.state
        R, N = s.status.shape
        terms, per_component = self._draw_layout()
        gen = self._compiled_draws()
        old: tuple[np.ndarray, ...] = (s.x, s.heading, s.u, s.cmd, s.status, s.slow, s.y, s.f_y)  # tick_kernels.STATE
        if not all(a.flags.c_contiguous for a in old) or s.status.dtype != np.int8 or s.slow.dtype != np.int64:
            old = tuple(np.ascontiguousarray(a, dtype=t) for a, t in zip(old, STATE_DTYPES))
        new = (np.empty((R, N, 2)), np.empty((R, N)), np.empty((R, N, 2)), np.empty((R, N, 2)),
               np.empty((R, N), np.int8), np.empty((R, N), np.int64), np.empty((R, N, 2)), np.empty((R, N)),
               np.empty((R, N, 2)))  # ..., commanded
        f, yg, best, com, max_speed = np.empty((R, N)), np.empty((R, 2)), np.empty(R), np.empty(R), np.empty(R)
        counts = np.empty((4, R), np.int64)
        out = (np.empty((R, N)), np.empty((terms, R, N)), np.empty((R, N, 2)), np.empty((R, N, SECTORS)),
               np.empty((R, N, SECTORS, 2)), np.empty((R, N, SECTORS, 2)), np.empty((R, N, SECTORS), bool))  # Outputs
        source, layers, params, world, grid = self._kernel_constants()
        sensed = False

        def block(lo: int, hi: int) -> None:
            nonlocal sensed
            if tick_kernels.fleet_runs(lo, hi, old, new, f, yg, best, source, gen.address, gen.states, terms,
                                       per_component, params, world, grid, out, layers, STALL_SPEED, STALL_STEPS,
                                       com, max_speed, counts):
                sensed = True

        parallel.each_block(block, R)
        s.x, s.heading, s.u, s.cmd, s.status, s.slow, s.y, s.f_y, s.commanded = new
        s.f, s.yg, s.best_fitness = f, yg, best
        omega, c, force, gap, point, centre, hit = out
        s.reading = SectorReading(gap, point, centre, hit) if sensed else None
        s.force, s.omega, s.c = force, omega, c
        s.k += 1
        self._stale = True
        return FleetInfo(s.k * self.params.dt, com, counts[0], counts[1], counts[2], counts[3], best.copy(), max_speed)

    def _draw_layout(self) -> tuple[int, bool]:
        """The law's U(0,1) draws a robot takes a tick: how many terms, and two (one a component) or one each."""
        law = ROBOT_LAWS[self.params.law]
        return law.terms, law.draws != "robot"

    def _compiled_draws(self) -> CompiledDraws:
        """The runs' generators as a kernel draws from them (rebuilt when they are replaced)."""
        kept = self.__dict__.get("_gen")
        if kept is None or kept[0] is not self.rngs:
            kept = self._gen = (self.rngs, CompiledDraws(self.rngs))
        return kept[1]

    def _kernel_constants(self) -> tuple[np.ndarray, np.ndarray, tuple, tuple, tuple]:
        """The source and the obstacle layers' x as float64 arrays, and the tick's parameters,
        world and grid as the plain tuples :func:`tick_kernels.fleet_runs` takes."""
        params = self._kernel_params()
        kept = self.__dict__.get("_constants")
        if kept is None or kept[0] is not self.world or kept[1] is not params:  # a world spec is frozen
            world, grid = self._kernel_world()
            kept = self._constants = (self.world, params, np.array(self.world.source, dtype=float),
                                      np.array(self.world.layer_x, dtype=float).reshape(-1), tuple(params),
                                      tuple(world), tuple(grid))
        return kept[2:]

    # ------------------------------------------------------------------ snapshot
    STATE = ("x", "heading", "u", "cmd", "y", "f_y", "yg", "best_fitness", "f", "status", "slow", "a")
    OPTIONAL = ("force", "omega", "c", "commanded")  # the last tick's decisions (None before the first)

    def snapshot(self) -> dict[str, Any]:
        """Everything the runs depend on beyond the settings they were built with, as plain data
        (:mod:`~shoal.engine.core.snapshot`): the state, the world as edited, every generator, and
        in physics mode every body's motion."""
        s = self.state
        state: dict[str, Any] = {n: np.array(getattr(s, n)) for n in self.STATE}
        state.update({n: None if getattr(s, n) is None else np.array(getattr(s, n)) for n in self.OPTIONAL})
        state["reading"] = None if s.reading is None else fields_of(s.reading)
        world = fields_of(self.world)
        world["polygons"] = list(world["polygons"])
        bodies = np.stack([sp.bodies() for sp in self.spaces]) if self.params.motion == "physics" else None
        return {"k": s.k, "seed": self.seed, "state": state, "world": world, "rngs": rng_states(self.rngs),
                "bodies": bodies, "positions": self.positions.snapshot()}

    def restore(self, data: dict[str, Any]) -> None:
        """Continue from :meth:`snapshot`'s ``data`` (of a fleet built with the same settings and runs):
        the world as it was edited, the pymunk spaces built again round the robots."""
        st = part(data, "state")
        got: dict[str, Any] = {n: arrays(part(st, n, "state"), f"state.{n}") for n in self.STATE}
        x = got["x"]
        if x.ndim != 3 or x.shape[0] != self.runs or x.shape[2] != 2 or x.shape[1] != self.robots:
            raise SnapshotError(f"state.x: expected shape {self.state.x.shape}, got {x.shape}")
        R, N = x.shape[:2]
        for n in self.STATE:
            want = (R, N, 2) if n in ("x", "u", "cmd", "y") else (R, 2) if n == "yg" else (R,) if n == "best_fitness" \
                else (R, N)
            if n != "a" and got[n].shape != want:
                raise SnapshotError(f"state.{n}: expected shape {want}, got {got[n].shape}")
        got["status"] = got["status"].astype(np.int8)
        for n in self.OPTIONAL:
            v = part(st, n, "state")
            got[n] = None if v is None else arrays(v, f"state.{n}")
        got["reading"] = None if part(st, "reading", "state") is None else from_fields(
            SectorReading, {k: arrays(v, f"state.reading.{k}") for k, v in part(st, "reading", "state").items()},
            "state.reading")
        raw = dict(part(data, "world"))
        raw["polygons"] = tuple(arrays(p, "world.polygons") for p in part(raw, "polygons", "world"))
        world = from_fields(WorldSpec, raw, "world")
        bodies = part(data, "bodies")
        if (bodies is None) != (self.params.motion != "physics"):
            raise SnapshotError("bodies: the snapshot and this fleet differ in motion (kinematic or physics)")
        if bodies is not None:
            bodies = arrays(bodies, "bodies", dtype=np.floating)
            if bodies.shape != (R, N, 6):
                raise SnapshotError(f"bodies: expected shape {(R, N, 6)}, got {bodies.shape}")
        k, seed = integer(part(data, "k"), "k"), integer(part(data, "seed"), "seed")
        set_rng_states(self.rngs, part(data, "rngs"), "rngs")
        self.positions.restore(part(data, "positions"), x)
        self.seed = seed
        self.state = FleetState(**got, k=k)
        self.world, self._world_arrays, self._spaces, self._stale = world, None, None, False
        self._tick_params = (None, None)
        if bodies is not None:
            self._place_bodies(bodies)

    def _place_bodies(self, bodies: np.ndarray) -> None:
        """Physics mode: new pymunk spaces round the robots (disabled ones kinematic), every body
        at its pose and velocity of ``bodies`` (R, N, 6)."""
        self._build_spaces()
        for sp, b in zip(self.spaces, bodies):
            for body, (bx, by, angle) in zip(sp.robot_bodies, b[:, :3].tolist()):
                body.position, body.angle = (bx, by), angle
                sp.space.reindex_shapes_for_body(body)
            sp.bodies()
            sp.set_velocities(b[:, 3:5], b[:, 5])

    def __getstate__(self) -> dict[str, Any]:
        """A fleet pickles without its pymunk spaces (built again on unpickling, as on :meth:`restore`)."""
        state = dict(self.__dict__)
        physics = self.params.motion == "physics"
        state["_bodies"] = np.stack([sp.bodies() for sp in self.spaces]) if physics else None
        state.update(_spaces=None, _stale=False, motion=None)
        return state

    def __setstate__(self, state: dict[str, Any]) -> None:
        bodies = state.pop("_bodies", None)
        self.__dict__.update(state)
        self.motion = self._motion()
        if bodies is not None:
            self._place_bodies(bodies)

    def info(self) -> FleetInfo:
        s = self.state
        com = s.x[..., 0].mean(axis=1)  # [4.17]
        collided = (s.status != ACTIVE).sum(axis=1)
        stalled = (s.slow >= STALL_STEPS).sum(axis=1)  # only active robots count up
        layers = np.asarray(self.world.layer_x)
        passed = (layers[None, :] < com[:, None]).sum(axis=1) if layers.size else np.zeros(self.runs, int)
        return FleetInfo(
            t=self.t, com_fitness=com, collided=collided, stalled=stalled, operational=self.robots - collided,
            layers_passed=passed, best_fitness=s.best_fitness.copy(),
            max_speed=np.linalg.norm(s.u, axis=-1).max(axis=1),
        )
