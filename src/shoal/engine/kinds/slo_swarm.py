"""Simultaneous Localisation and Optimisation (Mai §3, p. 21; Alg. 1, p. 22, run synchronously:
docs/readings.md, "Synchronous update"):
a swarm whose members act only on relative positions they estimate from noisy ranges and
odometry. Motion is SPSO 2011 in each robot's own frame [3.10]–[3.13] or a random walk (Mai §4.5, p. 41).

One :meth:`SLOSwarm.step` = one generation t → t+1 for every run:
PSO or random-walk command from the beliefs at t, perfect move, then at t+1 neighbourhoods
from truth, ranges, odometry, candidates and selection, and the metrics of Tab. 4.2 (Mai p. 39).
Arrays are (runs R, particles N, 2); run i draws from the children of
``SeedSequence(seed, spawn_key=(i,))`` (:mod:`~shoal.engine.core.rng`), one per component.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from functools import cached_property
from typing import Any, ClassVar, Iterable, Literal

import numpy as np

from ..core.compiled_draws import CompiledDraws
from ..core.contract import check_live
from ..core.portable import arctan2
from ..core.rng import component_generators
from ..core.schema import Column, Schema
from ..core.snapshot import SnapshotError, arrays, integer, part
from ..core.steering import Steering
from ..pso.bests import admissible
from ..pso.spso2011 import C_SPSO, OMEGA_SPSO, SPSO2011, Radial, draw
from ..pso.spso_kernels import local_velocity
from ..slo import metrics, ranging
from ..slo.beliefs import (
    Beliefs,
    EntryPolicy,
    Localiser,
    LocaliserParams,
    Selection,
    beliefs_data,
    beliefs_from,
    random_estimates,
    relative_truth,
    restore_streams,
    streams_data,
)
from ..slo.candidates import Candidates
from ..slo.formation import AttractionRepulsion
from ..slo.kernels import local_best
from ..slo.neighbourhoods import Neighbourhood, NeighbourhoodKind
from ..slo.objectives import QUALITY_THRESHOLDS, Fitness, slo_objective
from ..slo.ranging import Ranging, SlotBeliefs, SlotLocaliser
from ..slo.selection import RTSTriangle
from ..slo.sensors import ErrorModel, error_model

Motion = Literal["pso", "random_walk", "formation"]
LocalBest = Literal["current", "pbest"]
PbestShift = Literal["commanded", "measured"]
InitialEstimates = Literal["random", "truth"]

# Figs. 4.2, 4.4 (walks); PSO: docs/readings.md, "Number of PSO generations"
GENERATIONS = {"pso": 1000, "random_walk": 100, "formation": 100}
REPETITIONS = 31  # runs per parameter set (Mai §4.2, p. 36)


@dataclass(frozen=True)
class SLOConfig:
    """Every SLO parameter, with the defaults of Mai Tab. 4.1 (p. 37) where the thesis gives them.

    Distance-type values (additive errors, radius r, walk speed, init area, c4, RTS
    tolerance) are in thesis units and multiplied by ``unit`` = arena width / 100 (docs/readings.md,
    "Thesis units on a scene (ours)"). A quoted comment names the section of docs/readings.md
    behind a default."""

    particles: int = 20  # "Swarm size"
    objective: str | Fitness = "sphere"
    motion: Motion = "pso"
    selection: Selection = "css"  # "Default selection"
    prediction_weight: float = 0.5
    delta_cos: float = 0.03
    delta_v: float = 0.03
    literal_eq_3_1: bool = False  # "The denominator of [3.1]"
    neighbourhood: NeighbourhoodKind = "knn"
    neighbourhood_param: float | None = None  # k, r, n or p; None = default (knn 5, r 25, ring 2, p 0.5)
    errors: str | ErrorModel = "low"
    inertia: float = OMEGA_SPSO  # ω, "Inertia weight ω"
    c1: float = C_SPSO
    c2: float = C_SPSO
    c3: float = 1.0
    c4: float = 0.0
    radial: Radial = "uniform_radius"  # the SPSO 2011 reference code; docs/readings.md
    spso_self_best_halving: bool = False  # "SPSO's own-best rule"
    local_best: LocalBest = "current"  # "Local best from positions or personal bests"
    pbest_shift: PbestShift = "commanded"  # "Shifting the personal best [3.13]" (thesis mode)
    init_area: tuple[float, float] | None = None  # S = [lo, hi]²; None: [−50, 50]² PSO, [0, 100]² walk
    # ("Initial area of the PSO experiment")
    walk_speed: float = 5.0
    entry_policy: EntryPolicy = "geometric_nearest"  # "Estimates of robots outside the neighbourhood (SLO)"
    initial_estimates: InitialEstimates = "random"  # "Initial estimates x̂(−1)"
    measure_all_ranges: bool = True
    max_range: float = np.inf
    rts_triangle: RTSTriangle = "first"  # "Order of Round Trip Selection"
    rts_prefer_geometric: bool = False
    rts_tolerance: float = 1.0
    fitness_noise: float = 0.0  # σ_f, "Fitness noise"
    quality_threshold: float | None = None  # T; None: the benchmark's, "Quality thresholds"
    ar_gain: float = 0.0  # "Attraction–repulsion (external)"; 0 = off
    ar_a: float = 0.01
    ar_b: float = 0.2
    ar_c: float = 25.0  # a squared length: scaled by unit²
    ar_v_max: float = np.inf
    unit: float = 1.0
    ranging: Ranging = "all"  # every pair; "neighbours": docs/readings.md, "Ranging only the neighbours (ours)"
    memory: int | None = None  # neighbours: robots that left a robot's neighbourhood it remembers; None = 4 × its size

    def __post_init__(self) -> None:
        if self.particles < 2:
            raise ValueError(f"particles: need at least 2, got {self.particles}")
        if self.motion not in ("pso", "random_walk", "formation"):
            raise ValueError(f"motion: unknown {self.motion!r}")
        if self.local_best not in ("current", "pbest"):
            raise ValueError(f"local_best: unknown {self.local_best!r}")
        if self.pbest_shift not in ("commanded", "measured"):
            raise ValueError(f"pbest_shift: unknown {self.pbest_shift!r}")
        if self.initial_estimates not in ("random", "truth"):
            raise ValueError(f"initial_estimates: unknown {self.initial_estimates!r}")
        if self.unit <= 0:
            raise ValueError(f"unit: must be > 0, got {self.unit}")
        if self.fitness_noise < 0:
            raise ValueError(f"fitness_noise: must be >= 0, got {self.fitness_noise}")
        error_model(self.errors)
        slo_objective(self.objective)
        if self.ranging not in ranging.RANGINGS:
            raise ValueError(f"ranging: unknown {self.ranging!r}, choose from {ranging.RANGINGS}")
        if self.ranging == "neighbours":
            why = ranging.refusal(selection=self.selection, entry_policy=self.entry_policy,
                                  neighbourhood=self.neighbourhood, motion=self.motion, ar_gain=self.ar_gain)
            if why:
                raise ValueError(f"ranging = 'neighbours': {why}")

    def localiser_params(self) -> LocaliserParams:
        return LocaliserParams(
            selection=self.selection, prediction_weight=self.prediction_weight, delta_cos=self.delta_cos,
            delta_v=self.delta_v, literal_eq_3_1=self.literal_eq_3_1, entry_policy=self.entry_policy,
            measure_all_ranges=self.measure_all_ranges, max_range=self.max_range * self.unit,
            rts_triangle=self.rts_triangle, rts_prefer_geometric=self.rts_prefer_geometric,
            rts_tolerance=self.rts_tolerance * self.unit,
        )

    def spso(self) -> SPSO2011:
        return SPSO2011(self.inertia, self.c1, self.c2, self.c3, self.c4 * self.unit, self.radial,
                        self.spso_self_best_halving)

    def neighbourhood_rule(self) -> Neighbourhood:
        return Neighbourhood(self.neighbourhood, self.neighbourhood_param).scaled(self.unit)

    def formation(self) -> AttractionRepulsion:
        return AttractionRepulsion(self.ar_gain, self.ar_a, self.ar_b, self.ar_c * self.unit**2,
                                   self.ar_v_max * self.unit)

    def area(self) -> tuple[float, float]:
        lo, hi = self.init_area or ((-50.0, 50.0) if self.motion == "pso" else (0.0, 100.0))
        return lo * self.unit, hi * self.unit

    def threshold(self) -> float:
        if self.quality_threshold is not None:
            return float(self.quality_threshold)
        return QUALITY_THRESHOLDS.get(self.objective, -np.inf) if isinstance(self.objective, str) else -np.inf


def _differs(a: object, b: object) -> bool:
    if isinstance(a, (str, ErrorModel)) and isinstance(b, (str, ErrorModel)):
        return error_model(a) != error_model(b) if not (isinstance(a, str) and isinstance(b, str)) else a != b
    return a != b


@dataclass
class SLOState:
    """Truth, PSO memory and beliefs of every run at generation ``k``."""

    x: np.ndarray  # (R, N, 2) true positions
    u: np.ndarray  # (R, N, 2) last command V_i (a displacement per generation)
    P: np.ndarray  # (R, N, 2) personal best relative to the particle [3.13]
    fP: np.ndarray  # (R, N) fitness at the personal best (as sensed)
    f: np.ndarray  # (R, N) true fitness at x
    heading: np.ndarray  # (R, N) direction of the last command
    status: np.ndarray  # (R, N) int8, 0 = active (recorder convention)
    beliefs: Beliefs | SlotBeliefs  # every pair, or each robot's neighbours (ranging = "neighbours")
    best_fitness: np.ndarray  # (R,) best true fitness of the run so far
    k: int = 0

    @property
    def est(self) -> np.ndarray:
        """(R, N, N, 2): i's estimate of the vector to j; ghost of j at x_i + est[i, j]."""
        return self.beliefs.est

    @property
    def valid(self) -> np.ndarray:
        """(R, N, N): the estimate was refreshed this generation (j ∈ N_i)."""
        return self.beliefs.valid

    @property
    def adjacency(self) -> np.ndarray:
        return self.beliefs.adjacency

    @property
    def kind(self) -> np.ndarray:
        """(R, N, N) int8 :class:`~shoal.engine.slo.selection.Kind` of each estimate."""
        return self.beliefs.kind

    @property
    def flag(self) -> np.ndarray:
        """(R, N, N) int8 :class:`~shoal.engine.slo.candidates.Flag` of each candidate set."""
        return self.beliefs.flag

    @property
    def candidates(self) -> Candidates | None:
        return self.beliefs.candidates


METRICS = ("e_abs", "e_rel", "e_ang", "distance")  # statistics (metrics.STATS) of pair values
STATS = metrics.STATS
_METRIC_WORDS = {"e_abs": ("unit", "absolute distance error |d̂_ij − d_ij| of neighbour pairs"),
                 "e_rel": ("", "relative distance error of neighbour pairs"),
                 "e_ang": ("rad", "angular error of neighbour pairs' estimated directions"),
                 "distance": ("unit", "distance between particles, over all unordered pairs")}
_STAT_WORDS = {"mean": "mean", "std": "standard deviation", "sem": "standard error of the mean", "median": "median",
               "count": "number of pairs behind the statistics"}
COLUMNS: Schema = (
    Column("generation_best", "objective", "float", "min_i f(x_i) of this generation"),
    Column("best_so_far", "objective", "float", "the best f of any generation so far"),
    Column("quality_met_at", "", "float", "first generation with best ≤ the quality threshold T (inf if not yet)"),
    *(Column(f"{m}_{k}", "count" if k == "count" else unit, "float", f"{_STAT_WORDS[k]} of the {what}"
             + ("" if k == "count" else " (NaN with no pair)") + (" [thesis length units]" if unit == "unit" else ""))
      for m, (unit, what) in _METRIC_WORDS.items() for k in STATS),
    Column("dead_reckoning", "", "float", "share of the estimates carried by dead reckoning (out of range)"),
    Column("round_trip", "unit", "float", "mean round-trip error [3.8] of closed triangles [thesis length units]"),
)


@dataclass
class SLOInfo:
    """Per-run metrics of one generation (Mai Tab. 4.2, p. 39), each (R,).

    The localisation errors, distances, dead-reckoning share and round-trip error are worked
    out when first read, from the generation's true positions ``x`` and ``beliefs`` (a step
    replaces both, never changes them in place), so a run that keeps a few series pays for
    those only; the values are the same whenever they are read."""

    k: int
    best_fitness: np.ndarray  # min_i f(x_i(t)), the best of this generation
    best_so_far: np.ndarray
    quality_met_at: np.ndarray  # first generation with best ≤ T, inf if not yet
    x: np.ndarray = field(repr=False)  # (R, N, 2)
    beliefs: Beliefs | SlotBeliefs = field(repr=False)
    _pairs: dict[str, np.ndarray] = field(default_factory=dict, init=False, repr=False, compare=False)  # pair values
    _done: dict[tuple[str, str], np.ndarray] = field(default_factory=dict, init=False, repr=False, compare=False)

    @property
    def t(self) -> float:
        return float(self.k)

    def _values(self, name: str) -> np.ndarray:
        if name not in self._pairs:
            b = self.beliefs
            if isinstance(b, SlotBeliefs) and name != "distance":  # the neighbour pairs' slots
                self._pairs.update(ranging.pair_errors(self.x, b))
            elif name in ("e_abs", "e_rel"):
                self._pairs["e_abs"], self._pairs["e_rel"] = metrics.distance_errors(self.x, b.est, b.valid)
            elif name == "e_ang":
                self._pairs[name] = metrics.angular_errors(self.x, b.est, b.valid)
            else:
                self._pairs[name] = metrics.pair_distances(self.x)
        return self._pairs[name]

    def _stats(self, name: str, keys: Iterable[str] = STATS) -> dict[str, np.ndarray]:
        """Statistics ``keys`` of metric ``name`` (one of :data:`METRICS`), each worked out once."""
        todo = [k for k in keys if (name, k) not in self._done]
        if todo:
            self._done.update({(name, k): v for k, v in metrics.stats(self._values(name), todo).items()})
        return {k: self._done[(name, k)] for k in keys}

    @property
    def e_abs(self) -> dict[str, np.ndarray]:
        """Statistics of e_abs over the neighbour pairs."""
        return self._stats("e_abs")

    @property
    def e_rel(self) -> dict[str, np.ndarray]:
        return self._stats("e_rel")

    @property
    def e_ang(self) -> dict[str, np.ndarray]:
        return self._stats("e_ang")

    @property
    def distance(self) -> dict[str, np.ndarray]:
        """Statistics of the distances of all unordered pairs."""
        return self._stats("distance")

    @cached_property
    def dead_reckoning(self) -> np.ndarray:
        """Share of x3 estimates."""
        b = self.beliefs
        if isinstance(b, SlotBeliefs):
            return metrics.dead_reckoning_share(b.slot_kind, b.slot_valid)
        return metrics.dead_reckoning_share(b.kind, b.valid)

    @cached_property
    def round_trip(self) -> np.ndarray:
        """Mean e_r over the first triangles."""
        return metrics.stats(metrics.round_trip_errors(self.beliefs.est, self.beliefs.adjacency), ["mean"])["mean"]

    def series(self, names: Iterable[str] | None = None) -> dict[str, np.ndarray]:
        """Flat per-run values under Mai's names, e.g. ``best_fitness`` (of this generation),
        ``e_abs_mean``, ``distance_median`` (:meth:`SLOSwarm.run`): all, or only ``names``."""
        want = None if names is None else set(names)
        out: dict[str, np.ndarray] = {}
        for name in ("best_fitness", "best_so_far", "quality_met_at", *METRICS, "dead_reckoning", "round_trip"):
            if name in METRICS:
                keys = [k for k in STATS if want is None or f"{name}_{k}" in want]
                if keys:
                    out.update({f"{name}_{k}": np.asarray(v, dtype=float) for k, v in self._stats(name, keys).items()})
            elif want is None or name in want:
                out[name] = np.asarray(getattr(self, name), dtype=float)
        return out

    def columns(self) -> dict[str, np.ndarray]:
        """The metric columns: :meth:`series` with this generation's best as ``generation_best``
        (in the metric table ``best_fitness`` is the best so far, as for every kind)."""
        out = self.series()
        return {"generation_best": out.pop("best_fitness"), **out}


class SLOSwarm:
    """Seeded SLO swarms of ``runs`` runs (``first_run`` … ``first_run + runs − 1``).

    Keyword parameters are the fields of :class:`SLOConfig`. Implements
    :class:`~shoal.engine.core.contract.Engine` (one tick is one generation); :meth:`retune` takes the
    localisation choices, the errors, the neighbourhood, the objective, the walk speed and the
    quality threshold."""

    LIVE: ClassVar[frozenset[str]] = frozenset(
        {"selection", "prediction_weight", "delta_cos", "delta_v", "literal_eq_3_1", "entry_policy", "neighbourhood",
         "neighbourhood_param", "errors", "objective", "walk_speed", "quality_threshold"})
    COLUMNS: ClassVar[Schema] = COLUMNS
    steering: Steering | None = None  # the next generation's command from outside the law (core/steering.py)

    def __init__(self, *, runs: int = 1, seed: int = 0, first_run: int = 0, **params) -> None:
        if runs < 1:
            raise ValueError(f"runs: must be >= 1, got {runs}")
        self.config = SLOConfig(**params)
        self.runs, self.first_run = int(runs), int(first_run)
        self.fitness = slo_objective(self.config.objective)
        self.errors: ErrorModel = error_model(self.config.errors).scaled(self.config.unit)
        self.spso = self.config.spso()
        self.rule = self.config.neighbourhood_rule()
        self.formation = self.config.formation()
        self.reset(seed)

    def retune(self, **changes: Any) -> list[str]:
        """Change :data:`LIVE` settings mid-run and return the names that changed.

        Positions, commands and beliefs are kept, so a learner sees the same swarm react.
        A new objective restarts the bests (personal bests, best so far, threshold
        generation) at the current positions; new errors keep each robot's calibration
        offsets, rescaled. Refused (``ValueError``, nothing changed) for other fields."""
        check_live(self.LIVE, changes)
        cfg = replace(self.config, **changes)  # validates
        changed = [k for k in changes if _differs(getattr(self.config, k), getattr(cfg, k))]
        if not changed:
            return []
        params = cfg.localiser_params()  # these validate before anything changes
        errors = error_model(cfg.errors).scaled(cfg.unit) if "errors" in changed else None
        rule = cfg.neighbourhood_rule()
        fitness = slo_objective(cfg.objective)
        self.config, self.rule = cfg, rule
        if errors is not None:
            self.errors = errors
        self.localiser.retune(params, errors)
        if "objective" in changed:
            s = self.state
            self.fitness = fitness
            s.f, s.P, s.fP = self.fitness(s.x), np.zeros_like(s.P), np.full_like(s.fP, np.inf)
            s.best_fitness = np.full(self.runs, np.inf)
        if {"objective", "quality_threshold"} & set(changed):
            self._met = np.full(self.runs, np.inf)
            self._last = self._record()
        return changed

    @property
    def t(self) -> float:
        return float(self.state.k)

    @property
    def dt(self) -> float:
        """One generation."""
        return 1.0

    @property
    def robots(self) -> int:
        return self.config.particles

    def reset(self, seed: int | None = None) -> None:
        """Generation 0 with ``seed`` (or the current one): new positions, commands, beliefs."""
        if seed is not None:
            self.seed = int(seed)
        cfg, n = self.config, self.config.particles
        self.streams = component_generators(self.seed, self.first_run, self.runs)
        self.steering = None
        lo, hi = cfg.area()
        init = self.streams["init"]
        x = np.stack([g.uniform(lo, hi, (n, 2)) for g in init])
        u = np.stack([g.uniform(lo, hi, (n, 2)) - g.uniform(lo, hi, (n, 2)) for g in init])  # RandomMovement()
        self._pso_draws = CompiledDraws(self.streams["pso"])  # compiled, the same numbers
        beliefs: Beliefs | SlotBeliefs
        self.localiser: Localiser | SlotLocaliser
        if cfg.ranging == "neighbours":  # no N × N array: the pairs' initial estimates are drawn as used
            truth, keys = cfg.initial_estimates == "truth", ranging.initial_keys(self.streams)
            start = ranging.Start(truth, x.copy(), keys, lo, hi)
            nb = ranging.neighbour_slots(self.rule, x)
            memory = 4 * nb.shape[2] if cfg.memory is None else cfg.memory
            self.localiser = SlotLocaliser(cfg.localiser_params(), self.errors, self.streams, n, start, memory)
            beliefs = self.localiser.start(x, nb)
        else:
            est = random_estimates(init, n, lo, hi) if cfg.initial_estimates == "random" else relative_truth(x)
            self.localiser = Localiser(cfg.localiser_params(), self.errors, self.streams, n)
            beliefs = self.localiser.start(x, self.rule.adjacency(x, self.streams["topology"]), est)
        shape = (self.runs, n)
        self.state = SLOState(
            x=x, u=u, P=np.zeros_like(x), fP=np.full(shape, np.inf), f=self.fitness(x),
            heading=arctan2(u[..., 1], u[..., 0]), status=np.zeros(shape, dtype=np.int8), beliefs=beliefs,
            best_fitness=np.full(self.runs, np.inf),
        )
        self._met = np.full(self.runs, np.inf)
        self._last = self._record()

    # ------------------------------------------------------------------ snapshot
    STATE = ("x", "u", "P", "fP", "f", "heading", "status", "best_fitness")

    def snapshot(self) -> dict[str, Any]:
        """Everything the runs depend on beyond the settings they were built with, as plain data
        (:mod:`~shoal.engine.core.snapshot`): truth, PSO memory, beliefs, calibration, every stream."""
        s = self.state
        return {"k": s.k, "seed": self.seed, "state": {n: np.array(getattr(s, n)) for n in self.STATE},
                "beliefs": ranging.slot_beliefs_data(s.beliefs) if isinstance(s.beliefs, SlotBeliefs)
                else beliefs_data(s.beliefs), "met": self._met.copy(), "localiser": self.localiser.snapshot(),
                "streams": streams_data(self.streams)}

    def restore(self, data: dict[str, Any]) -> None:
        """Continue from :meth:`snapshot`'s ``data`` (of a swarm built with the same settings and runs)."""
        st = part(data, "state")
        got: dict[str, Any] = {n: arrays(part(st, n, "state"), f"state.{n}") for n in self.STATE}
        R, N = self.runs, self.config.particles
        for n in self.STATE:
            want = (R, N, 2) if n in ("x", "u", "P") else (R,) if n == "best_fitness" else (R, N)
            if got[n].shape != want:
                raise SnapshotError(f"state.{n}: expected shape {want}, got {got[n].shape}")
        got["status"] = got["status"].astype(np.int8)
        beliefs: Beliefs | SlotBeliefs
        if isinstance(self.localiser, SlotLocaliser):
            beliefs = ranging.slot_beliefs_from(part(data, "beliefs"), R, N)
        else:
            beliefs = beliefs_from(part(data, "beliefs"))
            if beliefs.est.shape != (R, N, N, 2):
                raise SnapshotError(f"beliefs.est: expected shape {(R, N, N, 2)}, got {beliefs.est.shape}")
        met = arrays(part(data, "met"), "met", dtype=np.floating)
        if met.shape != (R,):
            raise SnapshotError(f"met: expected shape {(R,)}, got {met.shape}")
        k, seed = integer(part(data, "k"), "k"), integer(part(data, "seed"), "seed")
        self.localiser.restore(part(data, "localiser"))
        if isinstance(self.localiser, SlotLocaliser):
            assert isinstance(beliefs, SlotBeliefs)
            self.localiser.adopt(beliefs)
        restore_streams(self.streams, part(data, "streams"))
        self.seed, self._met = seed, met
        self.state = SLOState(**got, beliefs=beliefs, k=k)
        self._last = self._record()

    def info(self) -> SLOInfo:
        """Metrics of the current generation."""
        return self._last

    def run(self, generations: int, names: Iterable[str] | None = None) -> dict[str, np.ndarray]:
        """Advance ``generations`` steps; per-generation values of :meth:`SLOInfo.series` (all,
        or only ``names``) stacked to (generations + 1, R), the current generation first."""
        rows = [self._last.series(names)] + [self.step().series(names) for _ in range(generations)]
        return {k: np.stack([r[k] for r in rows]) for k in rows[0]}

    # ------------------------------------------------------------------ behaviour
    def _sensed_fitness(self) -> np.ndarray:
        f = self.state.f
        if self.config.fitness_noise > 0:
            z = np.stack([g.standard_normal(f.shape[1]) for g in self.streams["fitness"]])
            f = f + self.config.fitness_noise * z
        return f

    def _pso_command(self, steering: Steering | None = None) -> np.ndarray:
        """The PSO part of Alg. 1 (Mai §3.6, p. 32) for every particle: pbest update, local best, [3.10]–[3.11]
        (with the inertia ω and c1, c2 of ``steering`` where it gives them: the numpy update, the same bits)."""
        s, cfg = self.state, self.config
        f = self._sensed_fitness()
        # steps 2–4, compiled: pbest update, best informant, local best (see SLOConfig.local_best)
        if isinstance(s.beliefs, SlotBeliefs):
            s.P, s.fP, self_best, L = ranging.local_best(f, s.fP, s.P, s.beliefs, cfg.local_best == "pbest")
        else:
            s.P, s.fP, self_best, L = local_best(f, s.fP, s.P, s.adjacency, s.est, cfg.local_best == "pbest")
        n = f.shape[1]
        draws = draw(self._pso_draws, n)
        if steering is not None and (steering.omega is not None or steering.c is not None):
            law = self.spso
            omega, c = steering.coefficients(law.inertia, np.array([law.c1, law.c2]), f.shape)
            per = np.asarray(omega, dtype=float)[..., None]
            law = replace(law, inertia=per, c1=c[0][..., None], c2=c[1][..., None])  # type: ignore[arg-type]
            return law.local_velocity(s.u, s.P, L, draws, self_best)
        return local_velocity(self.spso, s.u, s.P, L, draws, self_best)  # steps 5–7, compiled

    def _walk_command(self) -> np.ndarray:
        """Random walk (Mai §4.5, p. 41): speed ~ U(0, walk_speed), direction ~ U(0, 2π)."""
        n = self.config.particles
        top = self.config.walk_speed * self.config.unit
        sv = np.stack([g.random((2, n)) for g in self.streams["motion"]])
        speed, theta = top * sv[:, 0], 2.0 * np.pi * sv[:, 1]
        return speed[..., None] * np.stack([np.cos(theta), np.sin(theta)], axis=-1)

    # ------------------------------------------------------------------ tick
    def step(self) -> SLOInfo:
        """Advance every run by one generation and return its metrics (steered by :attr:`steering`:
        its velocity is the whole displacement of the generation)."""
        s, cfg = self.state, self.config
        steering, self.steering = self.steering, None
        if cfg.motion == "pso":
            v_new = self._pso_command(steering)
        elif cfg.motion == "random_walk":
            v_new = self._walk_command()
        else:
            v_new = self.formation.velocity(s.est, s.valid)
        if cfg.motion != "formation" and cfg.ar_gain > 0:  # collision-avoidance term (Mai §2.1.2, p. 9)
            v_new = v_new + self.formation.velocity(s.est, s.valid)
        if steering is not None and steering.velocity is not None:  # the law's draws are made all the same
            v_new = np.array(np.broadcast_to(steering.velocity, s.x.shape), dtype=float)
        x_prev = s.x
        s.x = s.x + v_new  # [3.12], perfect movement (Mai §3.1, p. 21)
        s.u = v_new
        moving = np.any(v_new != 0, axis=-1)
        s.heading = np.where(moving, arctan2(v_new[..., 1], v_new[..., 0]), s.heading)
        if cfg.pbest_shift == "commanded":
            s.P = s.P - v_new  # [3.13]
        if isinstance(self.localiser, SlotLocaliser):
            assert isinstance(s.beliefs, SlotBeliefs)
            s.beliefs = self.localiser.update(s.beliefs, x_prev, s.x, ranging.neighbour_slots(self.rule, s.x), s.k + 1)
        else:
            assert isinstance(s.beliefs, Beliefs)
            adjacency = self.rule.adjacency(s.x, self.streams["topology"])
            s.beliefs = self.localiser.update(s.beliefs, x_prev, s.x, adjacency)
        if cfg.pbest_shift == "measured":
            s.P = s.P - s.beliefs.odometry  # "Shifting the personal best [3.13]", physical mode
        s.f = self.fitness(s.x)
        s.k += 1
        self._last = self._record()
        return self._last

    def _record(self) -> SLOInfo:
        s = self.state
        best = np.where(admissible(s.f, False), s.f, np.inf).min(axis=1)  # NaN is never a best (pso/bests.py)
        s.best_fitness = np.minimum(s.best_fitness, best)
        self._met = np.where(np.isinf(self._met) & (best <= self.config.threshold()), float(s.k), self._met)
        return SLOInfo(k=s.k, best_fitness=best, best_so_far=s.best_fitness.copy(), quality_met_at=self._met.copy(),
                       x=s.x, beliefs=s.beliefs)
