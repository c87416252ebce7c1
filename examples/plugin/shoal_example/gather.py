"""The ``gather`` scene kind: robots walk to their centroid at a set speed, with noise. It
optimises nothing, so its metric table has no ``best_fitness``.

One engine (the Engine contract of :mod:`shoal.engine.core.contract`, vectorised over runs and
robots), its preset section's model and its registry entry: all a scene kind needs besides its
app module (:mod:`.gather_app`) and a preset.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any, ClassVar

import numpy as np
from pydantic import BaseModel, ConfigDict, Field

from shoal.engine.core.contract import check_live
from shoal.engine.core.rng import run_generators
from shoal.engine.core.schema import Column, Schema
from shoal.engine.core.steering import Steering
from shoal.presets.kinds import Cap, Live, SceneKind


class GatherSection(BaseModel):
    """The preset section ``[gather]``."""

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False, validate_assignment=True)

    speed: float = Field(1.0, gt=0.0, le=10.0, description="walking speed [m/s]")
    noise: float = Field(0.2, ge=0.0, le=5.0, description="standard deviation of each velocity component's noise [m/s]")
    area: float = Field(20.0, gt=0.0, le=1000.0, description="side of the square the robots start in [m]")
    dt: float = Field(0.1, gt=0.0, le=1.0, description="control period Δt [s]")


@dataclass(frozen=True)
class GatherParams:
    speed: float = 1.0
    noise: float = 0.2
    area: float = 20.0
    dt: float = 0.1


@dataclass
class GatherState:
    x: np.ndarray  # (R, N, 2)
    u: np.ndarray  # (R, N, 2)
    heading: np.ndarray  # (R, N)
    status: np.ndarray  # (R, N) int8, all 0
    k: int = 0


@dataclass
class GatherInfo:
    t: float
    spread: np.ndarray  # (R,)
    radius: np.ndarray  # (R,)

    def columns(self) -> dict[str, np.ndarray]:
        return {"spread": self.spread, "radius": self.radius}


class Gather:
    """``runs`` seeded runs of ``robots`` robots gathering (run i draws from child i of the seed)."""

    LIVE: ClassVar[frozenset[str]] = frozenset({"speed", "noise"})
    steering: Steering | None = None  # a velocity from outside the law for the next tick (shoal.rl's actions)
    COLUMNS: ClassVar[Schema] = (
        Column("spread", "m", "float", "root mean square distance of the robots to their centroid"),
        Column("radius", "m", "float", "largest distance of a robot to the centroid"),
    )

    def __init__(self, params: GatherParams, *, robots: int, runs: int = 1, seed: int = 0, first_run: int = 0) -> None:
        self.params, self._robots = params, robots
        self.runs, self.seed, self.first_run = runs, seed, first_run
        self.reset(seed)

    @property
    def dt(self) -> float:
        return self.params.dt

    @property
    def t(self) -> float:
        return self.state.k * self.dt

    @property
    def robots(self) -> int:
        return self.state.x.shape[1]

    def reset(self, seed: int | None = None) -> None:
        if seed is not None:
            self.seed = int(seed)
        self._rngs = run_generators(self.seed, self.first_run, self.runs)
        self.steering = None
        a = self.params.area
        x = np.stack([a * (g.random((self._robots, 2)) - 0.5) for g in self._rngs])
        R, N = x.shape[:2]
        self.state = GatherState(x=x, u=np.zeros_like(x), heading=np.zeros((R, N)), status=np.zeros((R, N), np.int8))

    def step(self) -> GatherInfo:
        s, p = self.state, self.params
        to_centre = s.x.mean(axis=1, keepdims=True) - s.x
        dist = np.linalg.norm(to_centre, axis=-1, keepdims=True)
        speed = np.minimum(p.speed, dist / p.dt)  # no overshoot
        u = np.divide(to_centre, dist, out=np.zeros_like(to_centre), where=dist > 0) * speed
        steering, self.steering = self.steering, None
        if steering is not None and steering.velocity is not None:  # walks as told, no faster than the law
            given = np.asarray(steering.velocity, dtype=float)
            norm = np.linalg.norm(given, axis=-1, keepdims=True)
            u = given * np.minimum(1.0, np.divide(p.speed, norm, out=np.ones_like(norm), where=norm > 0))
        u = u + p.noise * np.stack([g.standard_normal(s.x.shape[1:]) for g in self._rngs])
        s.x = s.x + p.dt * u
        s.u = u
        s.heading = np.arctan2(u[..., 1], u[..., 0])
        s.k += 1
        return self.info()

    def info(self) -> GatherInfo:
        x = self.state.x
        r = np.linalg.norm(x - x.mean(axis=1, keepdims=True), axis=-1)
        return GatherInfo(t=self.t, spread=np.sqrt((r**2).mean(axis=1)), radius=r.max(axis=1))

    def retune(self, **changes: Any) -> list[str]:
        check_live(self.LIVE, changes)
        for name, value in changes.items():
            if not (isinstance(value, (int, float)) and value >= 0):
                raise ValueError(f"{name}: must be a number >= 0, got {value!r}")
        changed = [k for k, v in changes.items() if getattr(self.params, k) != v]
        self.params = replace(self.params, **{k: float(changes[k]) for k in changed})
        return changed


def params_for(scenario: Any) -> GatherParams:
    sec: GatherSection = scenario.section("gather")
    return GatherParams(speed=sec.speed, noise=sec.noise, area=sec.area, dt=sec.dt)


def build_gather(scenario: Any, *, runs: int | None = None, seed: int | None = None, first_run: int = 0) -> Gather:
    return Gather(params_for(scenario), robots=scenario.sim.robots, runs=runs or scenario.sim.runs,
                  seed=scenario.sim.seed if seed is None else seed, first_run=first_run)


def retune_keywords(old: Any, new: Any) -> dict[str, Any]:
    """The ``Gather.retune`` keywords of ``new`` (the engine keeps what did not change)."""
    p = params_for(new)
    return {"speed": p.speed, "noise": p.noise}


KIND = SceneKind("gather", "gathering swarm (example plug-in)", Gather, build_gather, "gather", model=GatherSection,
                 optimises=False, headline=("spread",), labels={"spread": ("spread at the end", "m")},
                 live=Live(("gather.speed", "gather.noise"), retune_keywords),  # anything else: a new engine
                 caps=(Cap("gathering swarm", 500),), app="shoal_example.gather_app", example="gather-demo")
