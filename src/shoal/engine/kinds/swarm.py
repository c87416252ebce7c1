"""One control tick of a swarm, vectorised over runs × robots × dimensions.

Stages (Rossides §3.5, p. 74): bests → coefficients → velocity → move → record. Run ``i`` draws
from child ``i`` of one ``SeedSequence(seed)``, so it is the same whether it is simulated
alone (``first_run=i, runs=1``) or inside a batch.
"""

from __future__ import annotations

import operator
from dataclasses import dataclass, fields
from typing import TYPE_CHECKING, Any, ClassVar, Literal, get_args

import numpy as np

from ..core import parallel
from ..core.contract import check_live
from ..core.objectives import Objective
from ..core.positions import Oracle, PositionSource
from ..core.rng import BlockDraws, run_generators
from ..core.schema import Column, Schema
from ..core.snapshot import SnapshotError, arrays, integer, part, rng_states, set_rng_states
from ..core.steering import Steering
from ..pso.bests import best_index, global_best, update_personal, warn_unfound
from ..pso.bounds import confine
from ..pso.coeffs import CoefficientPolicy, Constant
from ..pso.laws import LAWS, Law, reachable
from ..pso.laws import motion_heading as _heading

if TYPE_CHECKING:
    from ..core.compiled_draws import CompiledDraws
    from ..pso import kernels
else:
    class _Kernels:
        """The compiled Chapter 3 kernels (numba), imported at their first use: a swarm on its numpy
        tick never loads numba. That first use puts the module itself under this name."""

        def __getattr__(self, name: str) -> Any:
            global kernels
            from ..pso import kernels

            return getattr(kernels, name)

    kernels = _Kernels()

Attractors = Literal["literal", "ahead"]
PbestOrder = Literal["before_velocity", "after_velocity"]

ACTIVE = 0


class Turns:
    """Headings the compiled tick has not worked out yet: for each robot the first two components
    of its last non-zero velocity (one in 1-D) and whether it moved since its heading was last
    worked out. Reading :attr:`SwarmState.heading` works them out with the numpy tick's own
    function, so the bits are the same as working them out every tick."""

    def __init__(self, shape: tuple[int, int, int]) -> None:
        R, N, d = shape
        self.turn = np.zeros((R, N, min(d, 2)))
        self.turned = np.zeros((R, N), bool)
        self.pending = False

    def fits(self, shape: tuple[int, ...]) -> bool:
        return self.turn.shape == shape[:2] + (min(shape[2], 2),)

    def settle(self, heading: np.ndarray) -> np.ndarray:
        self.pending = False
        out = _heading(self.turn, heading, self.turned)
        self.turned[:] = False
        return out


@dataclass
class SwarmState:
    """The whole swarm of every run at step ``k``. The heading after a compiled tick is worked
    out when it is read (:class:`Turns`)."""

    x: np.ndarray  # (R, N, d) position
    u: np.ndarray  # (R, N, d) velocity
    a: np.ndarray  # (R, N, d) acceleration (u[k] − u[k−1])/Δt [3.22]
    y: np.ndarray  # (R, N, d) personal best
    f_y: np.ndarray  # (R, N)
    yg: np.ndarray  # (R, d) global best
    best_fitness: np.ndarray  # (R,) f(y_g)
    f: np.ndarray  # (R, N) fitness at x
    heading: np.ndarray  # (R, N) direction of motion, kept when the robot stops
    status: np.ndarray  # (R, N) int, 0 = active
    k: int = 0

    def copy(self) -> "SwarmState":
        values = {f.name: getattr(self, f.name) for f in fields(self)}
        return SwarmState(**{k: (v.copy() if isinstance(v, np.ndarray) else v) for k, v in values.items()})  # type: ignore[arg-type]

    def turns(self) -> Turns:
        """The pending headings of a compiled tick (new ones if the swarm's shape changed)."""
        t = self.__dict__.get("_turns")
        if t is None or not t.fits(self.x.shape):
            self.heading = self.heading  # works out what is pending
            t = self.__dict__["_turns"] = Turns(self.x.shape)
        return t


def _get_heading(s: SwarmState) -> np.ndarray:
    t = s.__dict__.get("_turns")
    if t is not None and t.pending:
        s.__dict__["_heading"] = t.settle(s.__dict__["_heading"])
    return s.__dict__["_heading"]


def _set_heading(s: SwarmState, value: np.ndarray) -> None:
    t = s.__dict__.get("_turns")
    if t is not None and t.pending:
        t.pending = False
        t.turned[:] = False
    s.__dict__["_heading"] = value


SwarmState.heading = property(_get_heading, _set_heading)  # type: ignore[assignment]


COLUMNS: Schema = (
    Column("max_component", "m/s", "float", "highest velocity component |u_j| in the run (m per tick for standard "
                                            "PSO, whose update [2.2] has no Δt)"),
    Column("omega", "", "float", "inertia weight ω in force during the last tick (mean over robots; NaN before the "
                                 "first)"),
    Column("c_hat", "m/s", "float", "ĉ = Σ c_n in force during the last tick (no unit for standard PSO; NaN before "
                                    "the first)"),
)


@dataclass
class StepInfo:
    """Per-run scalars of one tick, for metrics and plots."""

    t: float
    omega: np.ndarray | float  # in force during the last tick (NaN before the first)
    c: np.ndarray  # (n,) or (n, R, N)
    best_fitness: np.ndarray  # (R,)
    max_speed: np.ndarray  # (R,) highest |u| in the swarm
    max_component: np.ndarray  # (R,) highest |u_j|

    def columns(self) -> dict[str, np.ndarray]:
        """The largest velocity component and the coefficients in force (ω, ĉ = Σ c_n; means over
        robots for per-robot coefficients)."""
        R = self.max_speed.shape[0]
        return {"max_component": self.max_component, "omega": _per_run(self.omega, R),
                "c_hat": _per_run(np.sum(self.c, axis=0), R)}


@dataclass
class RunSeries:
    """Per-tick values of :meth:`Simulation.run`, tick j of ``steps`` (after it)."""

    t: np.ndarray  # (steps,)
    omega: list  # coefficients in force during each tick, as StepInfo gives them
    c: list
    best_fitness: np.ndarray  # (steps, R)
    speeds: np.ndarray  # (steps, 2, R): highest |u| and highest |u_j| of each run
    tracked: np.ndarray  # (steps, R, d): velocity of the tracked robot


def check_coefficients(law: Law, policy: CoefficientPolicy) -> None:
    """The law's coefficient rule (:meth:`~shoal.engine.pso.laws.VelocityLaw.check`) for raw
    coefficients; a ``ValueError`` naming them. Physical tuning gives coefficients inside it."""
    if isinstance(policy, Constant):
        why = LAWS[law.name].check(policy.omega, policy.c)
        if why:
            raise ValueError(f"policy: {why}")


def _per_run(value: np.ndarray | float, R: int) -> np.ndarray:
    """A scalar or per-robot ``(R, N)`` coefficient as one value per run (mean over robots)."""
    v = np.asarray(value, dtype=float)
    return np.full(R, float(v)) if v.ndim == 0 else v.reshape(R, -1).mean(axis=1)


class Simulation:
    """A seeded swarm: positions, velocities and bests of ``runs`` independent runs.

    Implements :class:`~shoal.engine.core.contract.Engine`; :meth:`retune` takes the controller
    (``policy``, ``law``, ``dt``), the swarm size (``robots``), the bests' bookkeeping
    (``attractors``, ``pbest_order``), the ``objective`` and, on SLO positions, the localisation
    keywords (``slo``).

    ``positions`` says where the robots' positions come from: the truth (``Oracle``, the
    default) or their SLO estimates (``Estimated``, :mod:`shoal.engine.slo.positions`). Only the
    "literal" attractors read positions; fitness is always read at the true position."""

    LIVE: ClassVar[frozenset[str]] = frozenset(
        {"policy", "law", "dt", "slo", "robots", "attractors", "pbest_order", "objective"})
    COLUMNS: ClassVar[Schema] = COLUMNS
    steering: Steering | None = None  # the next tick's command from outside the law (core/steering.py)

    def __init__(
        self,
        *,
        robots: int,
        d: int = 2,
        dt: float = 0.1,
        law: Law | None = None,
        policy: CoefficientPolicy,
        objective: Objective | None = None,
        runs: int = 1,
        seed: int = 0,
        first_run: int = 0,
        attractors: Attractors = "literal",
        pbest_order: PbestOrder = "before_velocity",
        ahead_direction: np.ndarray | None = None,
        init_center: np.ndarray | None = None,
        init_spread: float = 1.0,
        init_speed: float = 0.0,
        positions: PositionSource | None = None,
        compiled: bool = True,
    ) -> None:
        """``compiled`` False keeps the numpy tick, the reference of the compiled one."""
        if robots < 1 or runs < 1 or d < 1:
            raise ValueError("robots, runs and d must be >= 1")
        if dt <= 0:
            raise ValueError(f"dt must be > 0, got {dt}")
        self.d, self.dt, self.runs, self.seed, self.first_run = d, float(dt), runs, seed, first_run
        self.law = law or Law()
        check_coefficients(self.law, policy)
        self.policy = policy
        self.objective = objective or Objective()
        self.attractors: Attractors = attractors
        self.pbest_order: PbestOrder = pbest_order
        direction = np.zeros(d) if ahead_direction is None else np.asarray(ahead_direction, float)[:d]
        if ahead_direction is None:
            direction[0] = 1.0
        self.ahead_direction = direction
        self.init_center = np.zeros(d) if init_center is None else np.asarray(init_center, float)[:d]
        self.init_spread, self.init_speed = float(init_spread), float(init_speed)
        self._robots = robots
        self.positions: PositionSource = positions or Oracle()
        self.compiled = compiled
        self.reset(seed)

    # ------------------------------------------------------------------ state
    @property
    def robots(self) -> int:
        return self.state.x.shape[1]

    @property
    def t(self) -> float:
        return self.state.k * self.dt

    def reset(self, seed: int | None = None) -> None:
        """Start again from step 0 with ``seed`` (or the current seed)."""
        if seed is not None:
            self.seed = int(seed)
        self._rngs = run_generators(self.seed, self.first_run, self.runs)
        self.steering = None
        self._block: BlockDraws | None = None
        self._setup: tuple | None = None
        x, u = self._spawn(self._robots)
        self.state = self._fresh_state(x, u)
        self._coefficients: tuple[np.ndarray | float, np.ndarray] = (np.nan, np.full(1, np.nan))
        s = self.state
        self.positions.start(s.x, s.y, s.k, self.seed, self.first_run)
        self._warned = False
        self._honest()

    def _honest(self) -> None:
        """Say once if some run has no best yet (every value NaN or the worst infinity)."""
        self._warned = warn_unfound(self.state.best_fitness, self.objective.maximise, self.objective.name,
                                    self._warned)

    @property
    def rngs(self) -> list[np.random.Generator]:
        """One generator per run, where one call a tick would have left it (the compiled tick
        draws several ticks ahead: :class:`~shoal.engine.core.rng.BlockDraws`)."""
        if self._block is not None:
            self._block.settle()
            self._block = None
        return self._rngs

    def _spawn(self, n: int) -> tuple[np.ndarray, np.ndarray]:
        shape = (n, self.d)
        x = np.stack([self.init_center + self.init_spread * (g.random(shape) - 0.5) for g in self.rngs])
        u = np.stack([self.init_speed * (2.0 * g.random(shape) - 1.0) for g in self.rngs])
        box = self.objective.box(self.d)
        return (x, u) if box is None else (np.clip(x, box[0], box[1]), u)  # bounded: the start inside

    def _fresh_state(self, x: np.ndarray, u: np.ndarray) -> SwarmState:
        f = self.objective(x)
        yg, f_yg = global_best(x, f, self.objective)
        return SwarmState(
            x=x, u=u, a=np.zeros_like(u), y=x.copy(), f_y=f.copy(), yg=yg, best_fitness=f_yg, f=f,
            heading=_heading(u, np.zeros(x.shape[:2])), status=np.full(x.shape[:2], ACTIVE, dtype=np.int8),
        )

    def set_robots(self, n: int) -> None:
        """Grow or shrink the swarm in place: new robots spawn in the start region. On SLO
        positions kept robots keep their beliefs and believed bests."""
        if n < 1:
            raise ValueError(f"need at least one robot, got {n}")
        s, cur = self.state, self.robots
        self._robots = n
        if n == cur:
            return
        if n < cur:
            for name in ("x", "u", "a", "y", "f_y", "f", "heading", "status"):
                setattr(s, name, getattr(s, name)[:, :n].copy())
        else:
            x, u = self._spawn(n - cur)
            new = self._fresh_state(x, u)
            for name in ("x", "u", "a", "y", "f_y", "f", "heading", "status"):
                setattr(s, name, np.concatenate([getattr(s, name), getattr(new, name)], axis=1))
        s.yg, s.best_fitness = global_best(s.y, s.f_y, self.objective)
        self.positions.resize(s.x, s.k)

    def set_objective(self, objective: Objective) -> None:
        """Swap the objective and re-score the bests at the current positions."""
        self.objective = objective
        s = self.state
        s.f = objective(s.x)
        s.y, s.f_y = s.x.copy(), s.f.copy()
        s.yg, s.best_fitness = global_best(s.y, s.f_y, objective)
        self.positions.keep(np.ones(s.f.shape, bool))  # every best is where its robot stands

    def retune(self, **changes: Any) -> list[str]:
        """Change :data:`LIVE` settings from the next tick on, keeping the swarm; returns the names
        that changed. A new ``objective`` re-scores the bests at the current positions, new
        ``robots`` spawn in the start region. Refused (``ValueError``, nothing changed) for
        other keywords or bad values."""
        check_live(self.LIVE, changes)
        if "dt" in changes and not changes["dt"] > 0:
            raise ValueError(f"dt: must be > 0, got {changes['dt']}")
        if "robots" in changes and changes["robots"] < 1:
            raise ValueError(f"robots: need at least one robot, got {changes['robots']}")
        for name, kind in (("attractors", Attractors), ("pbest_order", PbestOrder)):
            if name in changes and changes[name] not in get_args(kind):
                raise ValueError(f"{name}: unknown {changes[name]!r}, choose from {get_args(kind)}")
        if "policy" in changes or "law" in changes:
            check_coefficients(changes.get("law", self.law), changes.get("policy", self.policy))
        slo = changes.pop("slo", None)
        now = {"policy": self.policy, "law": self.law, "dt": self.dt, "robots": self.robots,
               "attractors": self.attractors, "pbest_order": self.pbest_order, "objective": self.objective}
        changed = [k for k, v in changes.items() if now[k] != v]
        if slo:
            self.positions.retune(**slo)
            changed.append("slo")
        for name in ("policy", "law", "attractors", "pbest_order"):
            if name in changed:
                setattr(self, name, changes[name])
        if "dt" in changed:
            self.dt = float(changes["dt"])
        if "robots" in changed:
            self.set_robots(int(changes["robots"]))
        if "objective" in changed:
            self.set_objective(changes["objective"])
        return changed

    # ------------------------------------------------------------------ tick
    def _update_bests(self) -> None:
        s = self.state
        self.positions.observe(s.x, s.k)
        before = s.f_y.copy()
        s.f = self.objective(s.x)
        s.y, s.f_y = update_personal(s.x, s.f, s.y, s.f_y, self.objective)
        s.yg, s.best_fitness = global_best(s.y, s.f_y, self.objective)
        self.positions.keep(s.f_y != before)  # a new best is where the robot stands

    def _directions(self) -> np.ndarray:
        """Direction inputs g_n of the accelerating terms, (2, R, N, d): the vectors to the
        personal and the global best, as the robots know them."""
        s = self.state
        if self.attractors == "ahead":  # both attractors always ahead: docs/readings.md, "Attractors in Figure 3-4"
            g = np.broadcast_to(self.ahead_direction, s.x.shape)
            return np.stack([g, g])
        self.positions.observe(s.x, s.k)
        return np.stack([self.positions.to_personal(s.x, s.y), self._to_global()])

    def _to_global(self) -> np.ndarray:
        s = self.state
        return self.positions.to_owner(s.x, s.y, best_index(s.f_y, self.objective))

    def believed_gbest(self) -> np.ndarray:
        """(R, N, d) where each robot believes the global best is (y_g itself on true positions)."""
        return self.state.x + self._to_global()

    def _draw(self, n_terms: int) -> np.ndarray:
        """Fresh U(0,1) draws per term, robot and component [3.1]/[3.37], (n, R, N, d)."""
        shape = (n_terms, self.robots, self.d)
        return np.stack([g.random(shape) for g in self.rngs], axis=1)

    def step(self) -> StepInfo:
        """Advance every run by one control tick Δt (steered by :attr:`steering`, if set)."""
        steering, self.steering = self.steering, None
        if self._compiled_tick() and (steering is None or steering.velocity is None):
            info = self._compiled_step(steering)
        else:
            info = self._numpy_step(steering)
        if not self._warned:
            self._honest()
        return info

    def _numpy_step(self, steering: Steering | None = None) -> StepInfo:
        """The tick of :meth:`step` in numpy (the reference of the compiled one)."""
        s = self.state
        if self.pbest_order == "before_velocity":  # Algorithm 1 phase A first
            self._update_bests()
        omega, c = self._tick_coefficients(steering)
        self._coefficients = (omega, np.asarray(c))
        g = self._directions()
        u_new = self.law.velocity(s.u, g, c, omega, self._draw(g.shape[0]))
        if steering is not None and steering.velocity is not None:  # the law's draws are made all the same
            command = np.asarray(steering.velocity, dtype=float)
            u_new = reachable(command, s.u, c, omega) if self.law.adapted else command
        if self.pbest_order == "after_velocity":  # the velocity saw last tick's bests
            self._update_bests()
        x_new = self.law.position(s.x, u_new, self.dt)
        box = self.objective.box(self.d)
        if box is not None:  # the search-space bounds (pso/bounds.py)
            x_new, u_new = confine(x_new, u_new, box[0], box[1], self.objective.boundary)  # type: ignore[arg-type]
        s.a = (u_new - s.u) / self.dt  # [3.22]
        s.x = x_new
        s.u = u_new
        s.heading = _heading(u_new, s.heading)
        s.k += 1
        self.positions.observe(s.x, s.k)  # where the moves ended: current beliefs for drawing
        return self.info()

    def _tick_coefficients(self, steering: Steering | None) -> tuple[np.ndarray | float, np.ndarray]:
        """ω and c of this tick: the policy's, or those of ``steering`` where it gives them."""
        omega, c = self.policy.coefficients(self.t, self.dt, self.d)
        if steering is None:
            return omega, c
        return steering.coefficients(omega, c, self.state.x.shape[:2])

    def _compiled_tick(self) -> bool:
        """:func:`kernels.swarm_step` does the tick: the laws it knows (standard, Adapted with
        sgn) in up to 128 dimensions, on true positions and float64 states, unless the swarm was
        made with ``compiled=False``."""
        s = self.state
        return (self.compiled and self.law.name in ("standard", "adapted-sgn") and self.d <= kernels.MAX_TERMS
                and self.objective.bounds is None
                and isinstance(self.positions, Oracle) and s.x.dtype == s.u.dtype == s.y.dtype == np.float64)

    # U(0,1) draws a block holds at most (R × ticks × 2N d), and its ticks at most
    BLOCK_DRAWS, BLOCK_TICKS = 1 << 16, 64

    def _draws(self, shape: tuple[int, ...]) -> BlockDraws:
        """The block of draws the next compiled tick takes its own from."""
        block = self._block
        if block is None or block.spent or block.shape != shape:
            rngs = self.rngs  # settles a block of another shape
            per_tick = len(rngs) * int(np.prod(shape))
            ticks = max(1, min(self.BLOCK_TICKS, self.BLOCK_DRAWS // per_tick))
            block = self._block = BlockDraws(rngs, shape, ticks)
        return block

    def _kernel_setup(self) -> tuple:
        """What the compiled tick needs from the objective, law, attractors and bests order,
        worked out again only when one of them changed."""
        obj, d = self.objective, self.d
        key = (obj, obj.name, obj.scale, obj.source, self.law, self.attractors, self.pbest_order,
               self.ahead_direction, d)
        cached = self._setup
        if cached is not None and all(map(operator.is_, cached[0], key)):
            return cached[1]
        source = np.ascontiguousarray(obj.source[:d], dtype=float)
        code = kernels.OBJECTIVES.index(obj.name) if obj.name in kernels.OBJECTIVES else kernels.GIVEN
        if source.shape != (d,) and code != kernels.LINEAR:
            code = kernels.GIVEN  # numpy says what is wrong with it
        ahead = self.ahead_direction
        if ahead.shape != (d,):
            ahead = np.ascontiguousarray(np.broadcast_to(ahead, (d,)), dtype=float)
        setup = (ahead, self.attractors == "literal", self.law.adapted, self.pbest_order == "before_velocity",
                 obj.maximise, code, source if code != kernels.LINEAR else np.zeros(d), float(obj.scale))
        # kept while the same objects are in place (a source edited in place is seen through the view)
        self._setup = (key, setup) if np.shares_memory(source, obj.source) else None
        return setup

    def _compiled_step(self, steering: Steering | None = None) -> StepInfo:
        """The tick of :meth:`step` in one compiled call; the same numbers."""
        s, d = self.state, self.d
        R, N = s.x.shape[:2]
        omega, c = self._tick_coefficients(steering)
        c = np.asarray(c, dtype=float)
        self._coefficients = (omega, c)
        block = self._draws((2, N, d))
        setup = self._kernel_setup()
        code = setup[5]
        f = np.empty((R, N)) if code != kernels.GIVEN else self.objective(s.x)
        new, speeds = np.empty((3,) + s.x.shape), np.empty((2, R))
        y, f_y, yg, best = s.y.copy(), s.f_y.copy(), s.yg.copy(), s.best_fitness.copy()
        if not isinstance(omega, float) and np.ndim(omega) or c.ndim > 1:  # coefficients per robot
            w_robots = np.ascontiguousarray(np.broadcast_to(omega, (R, N)), dtype=float)
            c_robots = np.ascontiguousarray(np.broadcast_to(c.reshape(c.shape + (1,) * (3 - c.ndim)), (2, R, N)))
            w, c_terms = 0.0, c_robots[:, 0, 0].copy()
        else:
            w_robots, c_robots = kernels.NONE2, kernels.NONE3
            w, c_terms = float(omega), c if c.shape == (2,) else np.ascontiguousarray(np.broadcast_to(c, (2,)))
        turns = s.turns()
        ahead, literal, adapted, before, maximise, code, source, scale = setup
        kernels.swarm_step(s.x, s.u, y, f_y, f, block.draws, block.take(), w, w_robots, c_terms, c_robots, ahead,
                           literal, adapted, self.dt, before, maximise, code, source, scale, new, yg, best,
                           turns.turn, turns.turned, speeds)
        turns.pending = True
        s.f, s.y, s.f_y, s.yg, s.best_fitness = f, y, f_y, yg, best
        s.x, s.u, s.a = new
        s.k += 1
        return StepInfo(t=self.t, omega=omega, c=c, best_fitness=best.copy(), max_speed=speeds[0],
                        max_component=speeds[1])

    def run(self, steps: int, track: int = 0) -> RunSeries:
        """Advance ``steps`` ticks without a caller between them (headless use): the same
        numbers as ``steps`` calls of :meth:`step`. Where the compiled tick applies and the
        coefficients are the same for every robot, all the ticks of a block of runs go in one
        compiled call (:func:`kernels.swarm_runs`), the blocks on every core; other ticks go
        through :meth:`step` (a steered tick too)."""
        if steps < 0 or not 0 <= track < self.robots:
            raise ValueError(f"need steps >= 0 and 0 <= track < {self.robots}, got {steps}, {track}")
        R, d = self.runs, self.d
        out = RunSeries(t=np.empty(steps), omega=[], c=[], best_fitness=np.empty((steps, R)),
                        speeds=np.empty((steps, 2, R)), tracked=np.empty((steps, R, d)))
        k = 0
        while k < steps:
            k += self._run_compiled(k, steps, track, out) or self._run_step(k, track, out)
        return out

    def _run_step(self, k: int, track: int, out: RunSeries) -> int:
        info = self.step()
        out.t[k], out.best_fitness[k], out.tracked[k] = info.t, info.best_fitness, self.state.u[:, track]
        out.speeds[k] = info.max_speed, info.max_component
        out.omega.append(info.omega)
        out.c.append(info.c)
        return 1

    # ticks one compiled call of :meth:`run` takes at most (bounds the coefficient lists)
    RUN_TICKS = 1 << 14

    def _run_compiled(self, k: int, steps: int, track: int, out: RunSeries) -> int:
        """Ticks k … of :meth:`run` in compiled calls while the coefficients are the same for
        every robot (and no steering is set), each block of runs in its own thread
        (:mod:`~shoal.engine.core.parallel`), drawing from the runs' own generators; 0 if none."""
        if not self._compiled_tick() or self.steering is not None:
            return 0
        ahead, literal, adapted, before, maximise, code, source, scale = self._kernel_setup()
        if code == kernels.GIVEN:
            return 0
        s, d, dt = self.state, self.d, self.dt
        R, N = s.x.shape[:2]
        omegas, cs = [], []
        for j in range(min(steps - k, self.RUN_TICKS)):
            omega, c = self.policy.coefficients((s.k + j) * dt, dt, d)  # self.t at that tick
            c = np.asarray(c, dtype=float)
            if not isinstance(omega, float) or c.shape != (2,):
                break
            omegas.append(omega)
            cs.append(c)
        n = len(omegas)
        if not n:
            return 0
        gen = self._compiled_draws()  # settles a block of draws of the single-tick path first
        new, f = np.empty((2, 3) + s.x.shape), np.empty((R, N))
        y, f_y, yg, best = s.y.copy(), s.f_y.copy(), s.yg.copy(), s.best_fitness.copy()
        turns = s.turns()
        w, c_all = np.array(omegas), np.array(cs)
        speeds, bests, tracked = out.speeds[k:k + n], out.best_fitness[k:k + n], out.tracked[k:k + n]

        def block(lo: int, hi: int) -> int:
            return kernels.swarm_runs(lo, hi, s.x, s.u, y, f_y, f, gen.address, gen.states, w, c_all, ahead,
                                      literal, adapted, dt, before, maximise, code, source, scale, new, yg, best,
                                      turns.turn, turns.turned, speeds, bests, track, tracked)

        parallel.each_block(block, R)
        turns.pending = True
        s.f, s.y, s.f_y, s.yg, s.best_fitness = f, y, f_y, yg, best
        s.x, s.u, s.a = new[(n - 1) % 2]
        out.t[k:k + n] = [(s.k + j + 1) * dt for j in range(n)]
        out.omega += omegas
        out.c += cs
        s.k += n
        self._coefficients = (omegas[-1], cs[-1])
        if not self._warned:
            self._honest()
        return n

    def _compiled_draws(self) -> "CompiledDraws":
        """The runs' generators as a kernel draws from them (where one call a tick leaves them)."""
        from ..core.compiled_draws import CompiledDraws  # (numba: imported with the kernels, at first use)

        rngs = self.rngs
        kept = self.__dict__.get("_gen")
        if kept is None or kept[0] is not rngs:
            kept = self._gen = (rngs, CompiledDraws(rngs))
        return kept[1]

    # ------------------------------------------------------------------ snapshot
    STATE = ("x", "u", "a", "y", "f_y", "yg", "best_fitness", "f", "heading", "status")

    def snapshot(self) -> dict[str, Any]:
        """Everything the runs depend on beyond the settings they were built with, as plain data
        (:mod:`~shoal.engine.core.snapshot`); settles draws taken ahead and pending headings first,
        which changes no number."""
        s = self.state
        rngs, _ = self.rngs, s.heading  # (both settle)
        omega, c = self._coefficients
        return {"k": s.k, "seed": self.seed, "dt": self.dt, "state": {n: getattr(s, n).copy() for n in self.STATE},
                "rngs": rng_states(rngs), "omega": omega, "c": np.array(c), "positions": self.positions.snapshot()}

    def restore(self, data: dict[str, Any]) -> None:
        """Continue from :meth:`snapshot`'s ``data`` (of a swarm built with the same settings and runs)."""
        st = part(data, "state")
        got = {n: arrays(part(st, n, "state"), f"state.{n}") for n in self.STATE}
        R, N, d = got["x"].shape if got["x"].ndim == 3 else (0, 0, 0)
        shapes = {"x": (R, N, d), "u": (R, N, d), "a": (R, N, d), "y": (R, N, d), "f_y": (R, N), "yg": (R, d),
                  "best_fitness": (R,), "f": (R, N), "heading": (R, N), "status": (R, N)}
        if (R, d) != (self.runs, self.d) or N < 1:
            raise SnapshotError(f"state.x: expected ({self.runs}, robots, {self.d}), got {got['x'].shape}")
        for n, shape in shapes.items():
            if got[n].shape != shape:
                raise SnapshotError(f"state.{n}: expected shape {shape}, got {got[n].shape}")
        omega = part(data, "omega")
        omega = arrays(omega, "omega") if isinstance(omega, np.ndarray) else omega
        if not isinstance(omega, (float, np.ndarray)):  # an array: ω per robot (a steered tick)
            raise SnapshotError("omega: expected a float or an array")
        k, seed, dt = integer(part(data, "k"), "k"), integer(part(data, "seed"), "seed"), part(data, "dt")
        if not isinstance(dt, float) or not dt > 0:
            raise SnapshotError(f"dt: expected a float > 0, got {dt!r}")
        c = arrays(part(data, "c"), "c", dtype=np.floating)
        set_rng_states(self._rngs, part(data, "rngs"), "rngs")
        self.positions.restore(part(data, "positions"), got["x"])
        self.seed, self.dt, self._robots = seed, dt, N
        self._block, self._setup = None, None
        self.state = SwarmState(**got, k=k)
        self._coefficients = (omega, c)

    def info(self) -> StepInfo:
        """The metrics of the current step, with the coefficients of the last tick."""
        s = self.state
        omega, c = self._coefficients
        return StepInfo(t=self.t, omega=omega, c=c, best_fitness=s.best_fitness.copy(),
                        max_speed=np.linalg.norm(s.u, axis=-1).max(axis=1),
                        max_component=np.abs(s.u).max(axis=(1, 2)))
