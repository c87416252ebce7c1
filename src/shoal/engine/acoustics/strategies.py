"""Source-localisation strategies of Chapters 7–8: A-, X-, B-, XB- and GT-PSO (Rossides Ch. 7–8,
pp. 148–189), and their registry :data:`STRATEGIES`.

Every strategy turns one step of sensed arrays into a candidate location and fitness per
robot, updates the personal bests with forgetting [7.2] and forms the global best
afresh. All arrays are shaped (runs R, robots N, …); no per-robot Python loops.

    strategy = make_strategy("xb-pso", a=1.0)
    f_hat, y, y_g, info = strategy.update(f_hat, y, x, Sensed(rho=rho, rays=rays), rngs)

Robots with no candidate this step (no intersection, every intersection rejected, no ray)
keep their personal best and its fitness decays by e^(−a) (docs/readings.md, "No intersection to choose
from").
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar, Literal, Protocol

import numpy as np

from ..core.registry import Registry, shape
from .forgetting import best_of, centroid_of, forget_update, improves
from .intersections import EPS, furthest, intersect, pair_intersections, rho_consistent
from .partners import Rngs, random_partner
from .triangulation import Triangles, triangles


@dataclass(frozen=True)
class Sensed:
    """What the receiver side hands over for one step (only the fields a strategy needs)."""

    intensity: np.ndarray | None = None  # (R, N) mean received power I [7.1], [8.1]
    rho: np.ndarray | None = None  # (R, N) correlation peak ρ [7.5]
    rays: np.ndarray | None = None  # (R, N, 2, 2) world unit rays [r_+, r_−] from x [7.7]

    def need(self, name: str) -> np.ndarray:
        """The named array as float, or a ValueError naming what is missing."""
        v = getattr(self, name)
        if v is None:
            raise ValueError(f"sensed.{name}: required by this strategy")
        return np.asarray(v, dtype=float)


@dataclass(frozen=True)
class LocInfo:
    """What a step decided, for drawing and metrics. Invalid slots hold finite placeholders."""

    candidate: np.ndarray  # (R, N, 2) offered location: own x (A/X) or selected p_s (B/XB/GT)
    fitness: np.ndarray  # (R, N) its fitness (0 where no candidate)
    valid: np.ndarray  # (R, N) bool, a candidate was offered
    improved: np.ndarray  # (R, N) bool, it replaced the personal best
    f_g: np.ndarray | None = None  # (R,) global-best fitness (A/X-PSO)
    partner: np.ndarray | None = None  # (R, N) int partner index, −1 if none
    points: np.ndarray | None = None  # (R, N, K, 2) intersections (K = 4 B/XB, 1 GT)
    forward: np.ndarray | None = None  # (R, N, K) bool, ahead of both rays
    kept: np.ndarray | None = None  # (R, N, K) bool, also passed [7.12] (= forward for B/GT)
    selected: np.ndarray | None = None  # (R, N) int index into K of p_s, −1 if none
    triangles: Triangles | None = None  # GT-PSO triplets, centroids and rays


Update = tuple[np.ndarray, np.ndarray, np.ndarray, LocInfo]
GlobalBest = Literal["best", "centroid"]  # the best robot's y (Alg. 3/4) or the centroid of all y [7.11]


class Strategy(Protocol):
    """One best-location strategy: ``update`` is called once per step."""

    name: ClassVar[str]
    label: ClassVar[str]
    min_robots: ClassVar[int]  # the fewest robots it can work with
    needs: ClassVar[tuple[str, ...]]
    hydrophones: ClassVar[int]
    global_best: ClassVar[GlobalBest]

    @property
    def a(self) -> float: ...  # the forgetting scale [7.2] (a frozen dataclass field)

    def update(self, f_hat: np.ndarray, y: np.ndarray, x: np.ndarray, sensed: Sensed, rng: Rngs) -> Update:
        """``f_hat`` (R, N), ``y`` and ``x`` (R, N, 2) → (f_hat, y, y_g (R, 2), info)."""
        ...


def _own_position(f_hat: np.ndarray, y: np.ndarray, x: np.ndarray, f: np.ndarray, a: float) -> Update:
    """Alg. 3/4: candidate = own position, fitness clamped at 0, y_g = best robot's y; see
    docs/readings.md, "Negative fitness"."""
    x, f_hat = np.asarray(x, dtype=float), np.asarray(f_hat, dtype=float)
    f = np.where(np.isfinite(f), np.maximum(f, 0.0), 0.0)
    valid = np.ones(f.shape, bool)
    better = improves(f_hat, f, x, valid)
    f_hat, y = forget_update(f_hat, y, f, x, valid, a)  # [7.2] / [7.9]
    y_g, f_g = best_of(f_hat, y)
    return f_hat, y, y_g, LocInfo(x, f, valid, better, f_g=f_g)


def _remote(f_hat: np.ndarray, y: np.ndarray, x: np.ndarray, cand: np.ndarray, dist: np.ndarray,
            valid: np.ndarray, a: float) -> tuple[np.ndarray, ...]:
    """Triangulation update: fitness 1/|x − p_s| [7.10]/[8.5], forgetting, centroid [7.11]."""
    valid = valid & (dist > 0)
    fit = np.where(valid, 1.0 / np.where(valid, dist, 1.0), 0.0)
    cand = np.where(valid[..., None], cand, x)
    better = improves(f_hat, fit, cand, valid)
    f_hat, y = forget_update(f_hat, y, fit, cand, valid, a)
    return f_hat, y, centroid_of(y), cand, fit, better, valid


@dataclass(frozen=True)
class APSO:
    """A-PSO (Alg. 3): fitness = mean received intensity at the robot [7.1], [7.2]."""

    a: float = 1.0
    name: ClassVar[str] = "a-pso"
    label: ClassVar[str] = "A-PSO"
    min_robots: ClassVar[int] = 1
    needs: ClassVar[tuple[str, ...]] = ("intensity",)
    hydrophones: ClassVar[int] = 1
    global_best: ClassVar[GlobalBest] = "best"

    def update(self, f_hat: np.ndarray, y: np.ndarray, x: np.ndarray, sensed: Sensed,
               rng: Rngs | None = None) -> Update:
        return _own_position(f_hat, y, x, sensed.need("intensity"), self.a)


@dataclass(frozen=True)
class XPSO:
    """X-PSO (Alg. 4): fitness = correlation peak ρ [7.8], [7.9], negative ρ read as 0 (docs/readings.md,
    "Negative fitness")."""

    a: float = 1.0
    name: ClassVar[str] = "x-pso"
    label: ClassVar[str] = "X-PSO"
    min_robots: ClassVar[int] = 1
    needs: ClassVar[tuple[str, ...]] = ("rho",)
    hydrophones: ClassVar[int] = 2
    global_best: ClassVar[GlobalBest] = "best"

    def update(self, f_hat: np.ndarray, y: np.ndarray, x: np.ndarray, sensed: Sensed,
               rng: Rngs | None = None) -> Update:
        return _own_position(f_hat, y, x, sensed.need("rho"), self.a)


@dataclass(frozen=True)
class BPSO:
    """B-PSO (Alg. 5, Fig. 7-1): furthest intersection with one random partner's rays."""

    a: float = 1.0
    eps: float = EPS
    name: ClassVar[str] = "b-pso"
    label: ClassVar[str] = "B-PSO"
    min_robots: ClassVar[int] = 2  # a robot and a partner
    needs: ClassVar[tuple[str, ...]] = ("rays",)
    hydrophones: ClassVar[int] = 2
    global_best: ClassVar[GlobalBest] = "centroid"

    def _keep(self, d_i: np.ndarray, d_j: np.ndarray, sensed: Sensed, partner: np.ndarray) -> np.ndarray:
        return np.ones(d_i.shape, bool)

    def update(self, f_hat: np.ndarray, y: np.ndarray, x: np.ndarray, sensed: Sensed, rng: Rngs) -> Update:
        x, f_hat = np.asarray(x, dtype=float), np.asarray(f_hat, dtype=float)
        rays = sensed.need("rays")
        if rays.shape != x.shape[:2] + (2, 2):
            raise ValueError(f"sensed.rays: shape {rays.shape}, expected {x.shape[:2] + (2, 2)}")
        partner = random_partner(rng, f_hat.shape)  # Alg. 5 step 2a
        points, d_i, d_j, forward = pair_intersections(x, rays, partner, self.eps)  # step 2b
        kept = forward & self._keep(d_i, d_j, sensed, partner)
        p_s, k, dist = furthest(points, d_i, kept)  # step 2d: p_s = argmax |x^i − p|
        valid = k >= 0  # step 2c: empty set → forgetting only (see docs/readings.md,
        # "No intersection to choose from")
        f_hat, y, y_g, cand, fit, better, valid = _remote(f_hat, y, x, p_s, dist, valid, self.a)
        info = LocInfo(cand, fit, valid, better, partner=partner, points=points, forward=forward,
                       kept=kept, selected=np.where(valid, k, -1))
        return f_hat, y, y_g, info


@dataclass(frozen=True)
class XBPSO(BPSO):
    """XB-PSO (Alg. 6): B-PSO keeping only points nearer the robot with larger ρ [7.12]."""

    name: ClassVar[str] = "xb-pso"
    label: ClassVar[str] = "XB-PSO"
    needs: ClassVar[tuple[str, ...]] = ("rays", "rho")

    def _keep(self, d_i: np.ndarray, d_j: np.ndarray, sensed: Sensed, partner: np.ndarray) -> np.ndarray:
        rho = sensed.need("rho")
        rho_j = rho[np.arange(rho.shape[0])[:, None], np.maximum(partner, 0)]
        return rho_consistent(d_i, d_j, rho[..., None], rho_j[..., None])  # [7.12], ties dropped


@dataclass(frozen=True)
class GTPSO:
    """GT-PSO (Alg. 7, Fig. 8-1): gradient rays from nearest-neighbour triplets [8.2]–[8.6].

    The partner is drawn from every robot outside i's own triplet; the candidate is the
    forward intersection of the two triplet rays, its fitness 1/|x^i − p_s| from the robot
    itself [8.5]. ``maximise=False`` treats the field as a cost (rays point downhill).
    """

    a: float = 1.0
    eps: float = EPS
    maximise: bool = True
    name: ClassVar[str] = "gt-pso"
    label: ClassVar[str] = "GT-PSO"
    min_robots: ClassVar[int] = 4  # a triplet and a partner outside it
    needs: ClassVar[tuple[str, ...]] = ("intensity",)
    hydrophones: ClassVar[int] = 1
    global_best: ClassVar[GlobalBest] = "centroid"

    def update(self, f_hat: np.ndarray, y: np.ndarray, x: np.ndarray, sensed: Sensed, rng: Rngs) -> Update:
        x, f_hat = np.asarray(x, dtype=float), np.asarray(f_hat, dtype=float)
        R, N = f_hat.shape
        tri = triangles(x, sensed.need("intensity"), self.maximise)  # Alg. 7 step 2
        ids = np.arange(N)
        own = (tri.members[..., None] == ids).any(axis=-2)  # (R, N, N): i's triplet
        partner = random_partner(rng, (R, N), exclude=own)  # step 3: o ∉ {i, j, h}
        o = np.maximum(partner, 0)
        runs = np.arange(R)[:, None]
        p, _, _, forward = intersect(tri.centroid, tri.direction, tri.centroid[runs, o], tri.direction[runs, o],
                                     self.eps)
        forward = forward & (partner >= 0) & tri.valid & tri.valid[runs, o]
        dist = np.linalg.norm(x - p, axis=-1)
        valid = forward & (dist > self.eps)  # fitness 1/0 is not offered
        f_hat, y, y_g, cand, fit, better, valid = _remote(f_hat, y, x, p, dist, valid, self.a)
        p = np.where(forward[..., None], p, x)
        info = LocInfo(cand, fit, valid, better, partner=partner, points=p[:, :, None, :],
                       forward=forward[..., None], kept=forward[..., None],
                       selected=np.where(valid, 0, -1), triangles=tri)
        return f_hat, y, y_g, info


STRATEGIES: Registry[type[Strategy]] = Registry[type[Strategy]](
    "strategy", APSO, XPSO, BPSO, XBPSO, GTPSO,
    check=shape("update", min_robots=int, needs=tuple, hydrophones=int, global_best=frozenset({"best", "centroid"})))


def make_strategy(name: str, **params: float | bool) -> Strategy:
    """The strategy called ``name`` (a key of ``STRATEGIES``) with its parameters."""
    return STRATEGIES.pick(name)(**params)


def initial_memory(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Initial memories f̂ = 0 and y = x[0] (docs/readings.md, "Initial state and partners").
    Returns ``f_hat`` (R, N) and ``y`` (R, N, 2)."""
    x = np.asarray(x, dtype=float)
    return np.zeros(x.shape[:2]), x.copy()
