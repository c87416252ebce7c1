"""Chapters 4–5: robots with bodies in an obstacle world.

One tick (Algorithms 1 and 2): bests → sense → coefficients (constant or DVC) →
velocity (RPSO, Adapted RPSO, robot-centred, non-omni) → move (kinematic or pymunk) →
metrics. Arrays are (runs, robots, …); run ``i`` draws from child ``i`` of
``SeedSequence(seed)``, like :class:`shoal.engine.kinds.swarm.Simulation`.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Any, ClassVar, Literal

import numpy as np

from ..core.contract import check_live
from ..core.rng import run_generators
from ..robots.dvc import approach_guard, dvc_nonomni, dvc_omni, forward_guard, w_max
from ..robots.laws import ROBOT_LAWS, Inertia, Limits
from ..robots.motion import Drive, Kinematic, Physics
from ..robots.sensing import SectorReading, sense, virtual_force
from ..robots.world import RunSpace, WorldSpec
from ..slo.positions import Oracle, PositionSource

ACTIVE, COLLIDED = 0, 1
# A stall (ours, a metric only): an operational robot slower than STALL_SPEED m/s for at
# least STALL_STEPS ticks in a row, e.g. squeezed between bodies it may not approach.
STALL_SPEED = 0.01
STALL_STEPS = 10


@dataclass
class FleetParams:
    """Controller and robot parameters of a fleet (Tables 4.1 and 5.1 by default)."""

    law: str = "adapted-rpso"  # a key of robots.laws.ROBOT_LAWS
    dvc: bool = True
    dt: float = 1.0
    omega: float = 0.1  # constant mode; ω = 1 − β (spec §20 item 17)
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
    contact_tolerance: float = 1e-3  # a collision is an overlap deeper than this [m] (ours)

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
    """n robot centres uniformly in ``box``, at least ``spacing`` apart surface to surface
    (rejection sampling; a grid when the box is too small for that)."""
    xmin, ymin, xmax, ymax = box
    pts: list[np.ndarray] = []
    gap = 2.0 * radius + spacing
    for _ in range(200 * n):
        if len(pts) == n:
            break
        p = rng.uniform([xmin + radius, ymin + radius], [xmax - radius, ymax - radius])
        if all(np.hypot(*(p - q)) >= gap for q in pts):
            pts.append(p)
    if len(pts) < n:  # box too small for random placement: fill a grid, row by row
        cols = max(1, int((xmax - xmin) // gap))
        pts = [np.array([xmin + radius + (i % cols) * gap, ymin + radius + (i // cols) * gap]) for i in range(n)]
    return np.array(pts)


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

    def __init__(self, *, world: WorldSpec, robots: int, params: FleetParams | None = None,
                 runs: int = 1, seed: int = 0, first_run: int = 0, positions: PositionSource | None = None) -> None:
        if robots < 1 or runs < 1:
            raise ValueError("robots and runs must be >= 1")
        self.world, self.params = world, params or FleetParams()
        self.runs, self.first_run, self._robots = runs, first_run, robots
        self.positions: PositionSource = positions or Oracle()
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
        p = self.params
        x = np.stack([spawn_positions(g, self.world.start_box, self._robots, p.robot_radius, p.spawn_gap)
                      for g in self.rngs])
        body = "dynamic" if p.motion == "physics" else "kinematic"
        self.spaces = [RunSpace(self.world, x[r], p.robot_radius, body_type=body) for r in range(self.runs)]
        self.motion = self._motion()
        heading = np.zeros(x.shape[:2])
        f = self.cost(x)
        R, N = f.shape
        best = np.argmin(f, axis=1)
        self.state = FleetState(
            x=x, heading=heading, u=np.zeros_like(x), cmd=np.zeros_like(x), y=x.copy(), f_y=f.copy(),
            yg=x[np.arange(R), best], best_fitness=f[np.arange(R), best], f=f, status=np.zeros((R, N), np.int8),
            slow=np.zeros((R, N), np.int64),
        )
        self.positions.start(x, self.state.y, self.state.k, self.seed, self.first_run)

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
        p, s = self.params, self.state
        body = "dynamic" if p.motion == "physics" else "kinematic"
        self.spaces = [RunSpace(world, s.x[r], p.robot_radius, body_type=body) for r in range(self.runs)]
        if p.motion == "physics":
            self.motion = self._motion()
            for r, sp in enumerate(self.spaces):
                for i, b in enumerate(sp.robot_bodies):
                    b.angle = float(s.heading[r, i])
                    if s.status[r, i] != ACTIVE:
                        Physics._disable(sp, i)

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
        better = active & (s.f < s.f_y)  # disabled robots keep their last best (spec §20 item 20)
        s.y = np.where(better[..., None], s.x, s.y)
        s.f_y = np.where(better, s.f, s.f_y)
        idx = np.argmin(s.f_y, axis=1)
        runs = np.arange(self.runs)
        s.yg, s.best_fitness = s.y[runs, idx], s.f_y[runs, idx]
        self.positions.keep(s.f_y != before)  # a new best is where the robot stands

    def _coefficients(self, gap: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
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
        return self.positions.to_owner(s.x, s.y, np.argmin(s.f_y, axis=1))

    def believed_gbest(self) -> np.ndarray:
        """(R, N, 2) where each robot believes the global best is (y_g itself on true positions)."""
        return self.state.x + self._to_global()

    def _velocity(self, omega: np.ndarray, c: np.ndarray, force: np.ndarray, r: np.ndarray) -> np.ndarray:
        p, s = self.params, self.state
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
        for r, sp in enumerate(self.spaces):
            for i in np.flatnonzero(moved[r]):
                bodies = sp.contacts_of(i, -self.params.contact_tolerance)
                if bodies:
                    out[r, i] = True
                    out[r, [j for j in bodies if j is not None]] = True
        return out & (self.state.status == ACTIVE)

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
        reach = p.sensing_range + 2.0 * p.robot_radius + 2.0 * p.v_max * p.dt
        x = self.state.x
        near = np.linalg.norm(x[:, :, None, :] - x[:, None, :, :], axis=-1) <= reach  # (R, N, N)
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
        p, s = self.params, self.state
        self._update_bests()  # phase A, all robots
        active = s.status == ACTIVE
        r = self._draws()
        n = r.shape[0]
        R, N = active.shape
        omega_all, c_all = np.full((R, N), np.nan), np.zeros((n, R, N))
        force_all = np.zeros_like(s.x)
        gap_all = np.full((R, N, 6), p.sensing_range)
        reading = None
        for group in self._groups(active):  # phase B
            m = group & (s.status == ACTIVE)
            if not m.any():
                continue
            reading = sense(self.spaces, s.x, s.heading, sensing_range=p.sensing_range,
                            robot_frame=p.body_frame, active=m)
            gap = reading.gap
            if p.s_min > 0:  # §5.4: keep a clearance s_min by treating it as contact distance
                gap = np.maximum(gap - p.s_min, 0.0)
            omega, c = self._coefficients(gap)
            force = virtual_force(s.x, reading, p.gamma) if not p.body_frame else np.zeros_like(s.x)
            cmd = self._velocity(omega, c, force, r)
            if p.dvc and p.guard:
                cmd = self._guard(cmd, reading, gap)
            cmd = np.where(m[..., None], cmd, 0.0)
            moved = self.motion.move(self.spaces, s.x, s.heading, cmd, m, p.dt)
            s.x = np.where(m[..., None], moved.x, s.x)
            s.heading = np.where(m, moved.heading, s.heading)
            s.u = np.where(m[..., None], moved.velocity, s.u)
            s.cmd = np.where(m[..., None], cmd, s.cmd)
            s.status = np.where(moved.hit | self._touching(m), COLLIDED, s.status).astype(np.int8)
            omega_all = np.where(m, omega, omega_all)
            c_all = np.where(m, c, c_all)
            force_all = np.where(m[..., None], force, force_all)
            gap_all = np.where(m[..., None], reading.gap, gap_all)
        s.cmd[s.status != ACTIVE] = 0.0
        s.u[s.status != ACTIVE] = 0.0
        slow = (s.status == ACTIVE) & (np.linalg.norm(s.u, axis=-1) < STALL_SPEED)
        s.slow = np.where(slow, s.slow + 1, 0)
        if reading is not None:
            reading.gap = gap_all
        s.reading, s.force, s.omega, s.c = reading, force_all, omega_all, c_all
        s.k += 1
        self.positions.observe(s.x, s.k)  # where the moves ended: current beliefs for drawing
        return self.info()

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
