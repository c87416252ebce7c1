"""The SLO belief store and its per-step update (Mai §3.4–3.5, pp. 25–31; Alg. 1, p. 22):
measure ranges and odometry, build candidates, select an estimate for every neighbour pair.

Shapes: positions (R, N, 2); per ordered pair (observer i, neighbour j) arrays (R, N, N, …),
``est[r, i, j]`` being i's estimate of the vector from i to j in i's (compass-aligned) frame.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property, partial
from typing import Any, Callable, Literal

import numpy as np

from ..core.compiled_draws import CompiledDraws
from ..core.rng import Streams
from ..core.snapshot import SnapshotError, arrays, from_fields, integer, part, rng_states, set_rng_states
from .candidates import Candidates, Flag
from .kernels import carry, localise, pair_candidates
from .neighbourhoods import distances
from .selection import SELECTIONS, Kind, RTSTriangle
from .sensors import ErrorModel, measure_odometry, measure_ranges, permanent_errors, permanent_normals

PERFECT = "perfect"  # the oracle baseline: every estimate is the truth
Selection = str  # a key of selection.SELECTIONS, or PERFECT
# How a robot's estimate of a non-neighbour is kept, and so where a neighbour that arrives
# starts (docs/readings.md, "Estimates of robots outside the neighbourhood"):
# "geometric_nearest" (the default, our reading of Mai §3.5.3, §4.5, §4.5.4) freezes it and starts
# an arriving neighbour on the geometric candidate x1 or x2 nearest its frozen x3, unblended;
# "stale" freezes it and blends as usual; "geometric_random" freezes it and starts an arriving
# neighbour on x1 or x2 at random; "dead_reckoning" (an extension: it assumes every robot's
# odometry is heard) carries it by odometry, x̂ + v*_j − v*_i [3.4].
EntryPolicy = Literal["geometric_nearest", "stale", "geometric_random", "dead_reckoning"]
ENTRY_POLICIES = ("geometric_nearest", "stale", "geometric_random", "dead_reckoning")


@dataclass(frozen=True)
class LocaliserParams:
    """Localisation choices (Mai §3.5, p. 26; Tab. 4.1, p. 37). ``selection`` :data:`PERFECT` is the
    oracle baseline. A quoted comment names the section of docs/readings.md behind a default."""

    selection: Selection = "css"  # "Default selection"
    prediction_weight: float = 0.5  # w of [3.7]
    delta_cos: float = 0.03  # [3.5]; −inf = clip only
    delta_v: float = 0.03  # [3.6]
    literal_eq_3_1: bool = False  # True: the printed denominator d_{t−1}; "The denominator of [3.1]"
    entry_policy: EntryPolicy = "geometric_nearest"
    measure_all_ranges: bool = True  # range to every particle, not only neighbours
    # ("Estimates of robots outside the neighbourhood (SLO)")
    max_range: float = np.inf  # ranging sensor reach (0 beyond)
    rts_triangle: RTSTriangle = "first"  # "Order of Round Trip Selection"
    rts_prefer_geometric: bool = False  # optional runaway remedy; "Order of Round Trip Selection"
    rts_tolerance: float = 1.0  # e_r below which a geometric loop excludes x3

    def __post_init__(self) -> None:
        if self.selection != PERFECT:
            SELECTIONS.pick(self.selection)
        if not 0.0 <= self.prediction_weight <= 1.0:
            raise ValueError(f"prediction_weight: must be in [0, 1], got {self.prediction_weight}")
        if self.entry_policy not in ENTRY_POLICIES:
            raise ValueError(f"entry_policy: unknown {self.entry_policy!r}")
        if self.rts_triangle not in ("first", "best"):
            raise ValueError(f"rts_triangle: unknown {self.rts_triangle!r}")


@dataclass
class Beliefs:
    """What every robot believes about its neighbours after one step."""

    est: np.ndarray  # (R, N, N, 2) x̂_ij; for non-neighbours dead-reckoned or frozen (entry policy)
    valid: np.ndarray  # (R, N, N) estimate refreshed this step (j ∈ N_i)
    adjacency: np.ndarray  # (R, N, N) neighbourhood of this step
    ranges: np.ndarray  # (R, N, N) d*_ij(t), the d*(t−1) of the next step
    kind: np.ndarray  # (R, N, N) int8 :class:`Kind`
    flag: np.ndarray  # (R, N, N) int8 :class:`Flag` (FALLBACK before any localisation)
    odometry: np.ndarray  # (R, N, 2) v*_i(t)
    triangle: np.ndarray | None = None  # (R, N, N) RTS closing vertex, −1 if none
    round_trip: np.ndarray | None = None  # (R, N, N) RTS e_r of the chosen loop
    pairs: Candidates | Callable[[], Candidates] | None = field(default=None, repr=False)  # or how to make them

    @cached_property
    def candidates(self) -> Candidates | None:
        """This step's candidate sets, (R, N, N, 3, 2) points; worked out when first read where
        the selection did not need them (CSS reads only its choice)."""
        return self.pairs() if callable(self.pairs) else self.pairs


def beliefs_data(b: Beliefs) -> dict[str, Any]:
    """``b`` as plain data (:mod:`~shoal.engine.core.snapshot`): its arrays and its candidate sets,
    worked out now if they were left to be worked out when read."""
    out: dict[str, Any] = {name: getattr(b, name) for name in BELIEF_ARRAYS}
    out["triangle"], out["round_trip"] = b.triangle, b.round_trip
    c = b.candidates
    out["candidates"] = None if c is None else {f: getattr(c, f) for f in CANDIDATE_FIELDS}
    return out


def beliefs_from(data: Any, where: str = "beliefs") -> Beliefs:
    """The :class:`Beliefs` of :func:`beliefs_data`'s ``data``."""
    values: dict[str, Any] = {n: arrays(part(data, n, where), f"{where}.{n}") for n in BELIEF_ARRAYS}
    for n in ("triangle", "round_trip"):
        v = part(data, n, where)
        values[n] = None if v is None else arrays(v, f"{where}.{n}")
    c = part(data, "candidates", where)
    if c is not None:
        sets = {f: arrays(part(c, f, f"{where}.candidates"), f"{where}.candidates.{f}") for f in CANDIDATE_FIELDS}
        values["pairs"] = from_fields(Candidates, sets, f"{where}.candidates")
    est = values["est"]
    if est.ndim != 4 or est.shape[-1] != 2 or est.shape[1] != est.shape[2]:
        raise SnapshotError(f"{where}.est: expected (R, N, N, 2), got {est.shape}")
    for n in ("valid", "adjacency", "ranges", "kind", "flag"):
        if values[n].shape != est.shape[:3]:
            raise SnapshotError(f"{where}.{n}: expected shape {est.shape[:3]}, got {values[n].shape}")
    return Beliefs(**values)


BELIEF_ARRAYS = ("est", "valid", "adjacency", "ranges", "kind", "flag", "odometry")
CANDIDATE_FIELDS = ("points", "mask", "flag", "cos_alpha", "thinness")


def streams_data(streams: Streams) -> dict[str, Any]:
    return {name: rng_states(gens) for name, gens in streams.items()}


def restore_streams(streams: Streams, data: Any, where: str = "streams") -> None:
    """Every component's generators put where ``data`` says, in place."""
    if not isinstance(data, dict) or set(data) != set(streams):
        raise SnapshotError(f"{where}: expected the streams {sorted(streams)}")
    for name, gens in streams.items():
        set_rng_states(gens, data[name], f"{where}.{name}")


def relative_truth(x: np.ndarray) -> np.ndarray:
    """r_ij = x_j − x_i for every ordered pair, (R, N, N, 2)."""
    return x[:, None, :, :] - x[:, :, None, :]


def random_estimates(rngs: list[np.random.Generator], n: int, low: float, high: float) -> np.ndarray:
    """x̂_ij(−1) = a_ij − b_ij with a, b ~ U(S), S = [low, high]², (R, N, N, 2); docs/readings.md,
    "Initial estimates x̂(−1)"."""
    est = np.stack([g.uniform(low, high, (n, n, 2)) - g.uniform(low, high, (n, n, 2)) for g in rngs])
    idx = np.arange(n)
    est[:, idx, idx] = 0.0
    return est


class Localiser:
    """Sensors plus estimator for ``n`` robots in every run; keeps the permanent errors. The
    sensor draws are made compiled (:class:`~shoal.engine.core.compiled_draws.CompiledDraws`),
    from the same streams, the same numbers."""

    def __init__(self, params: LocaliserParams, errors: ErrorModel, streams: Streams, n: int) -> None:
        self.params, self.errors, self.streams, self.n = params, errors, streams, n
        self._z = permanent_normals(streams["permanent"], n)
        self.permanent = permanent_errors(errors, self._z)
        self._range_draws, self._odometry_draws = CompiledDraws(streams["range"]), CompiledDraws(streams["odometry"])

    def retune(self, params: LocaliserParams | None = None, errors: ErrorModel | None = None) -> None:
        """Change the localisation choices or the sensor errors mid-run; beliefs are kept and
        each robot keeps its calibration offsets (rescaled to the new σ̂)."""
        if params is not None:
            self.params = params
        if errors is not None:
            self.errors = errors
            self.permanent = permanent_errors(errors, self._z)

    def resize(self, n: int) -> None:
        """The swarm now has ``n`` robots, the first ones kept: they keep their calibration
        offsets; robots beyond the old count get fresh ones from the permanent stream."""
        m = min(n, self.n)
        z = self._z[:, :, :m]
        if n > m:
            z = np.concatenate([z, permanent_normals(self.streams["permanent"], n - m)], axis=2)
        self._z, self.n = z, n
        self.permanent = permanent_errors(self.errors, z)

    def snapshot(self) -> dict[str, Any]:
        """The calibration draws (the offsets follow from them and the errors; the streams belong to
        whoever made them)."""
        return {"n": self.n, "z": self._z}

    def restore(self, data: Any) -> None:
        n = integer(part(data, "n", "localiser"), "localiser.n", 1)
        z = arrays(part(data, "z", "localiser"), "localiser.z", dtype=np.floating)
        if z.shape != (self._z.shape[0], self._z.shape[1], n):
            raise SnapshotError(f"localiser.z: expected shape {(self._z.shape[0], self._z.shape[1], n)}, got {z.shape}")
        self._z, self.n = z, n
        self.permanent = permanent_errors(self.errors, z)

    def _ranges(self, x: np.ndarray, adjacency: np.ndarray) -> np.ndarray:
        d = measure_ranges(distances(x), self.errors.range, self.permanent, self._range_draws, self.params.max_range)
        return d if self.params.measure_all_ranges else np.where(adjacency, d, 0.0)

    def start(self, x: np.ndarray, adjacency: np.ndarray, initial: np.ndarray) -> Beliefs:
        """t = 0: measure ranges, no localisation yet (docs/readings.md, "The first step");
        ``initial`` = x̂(−1)."""
        shape = adjacency.shape
        return Beliefs(
            est=initial.copy(), valid=adjacency.copy(), adjacency=adjacency.copy(),
            ranges=self._ranges(x, adjacency),
            kind=np.where(adjacency, Kind.INITIAL, Kind.NONE).astype(np.int8),
            flag=np.full(shape, Flag.FALLBACK, dtype=np.int8), odometry=np.zeros(x.shape),
        )

    def update(self, b: Beliefs, x_prev: np.ndarray, x: np.ndarray, adjacency: np.ndarray) -> Beliefs:
        """One localisation step at true positions ``x`` after the moves from ``x_prev``."""
        p = self.params
        ranges = self._ranges(x, adjacency)
        v_meas = measure_odometry(x - x_prev, self.errors.odometry, self.permanent, self._odometry_draws)
        entry = coin = None
        if p.entry_policy in ("geometric_random", "geometric_nearest"):
            entry = adjacency & ~b.adjacency
        if p.entry_policy == "geometric_random":
            coin = np.stack([g.random(adjacency.shape[1:]) < 0.5 for g in self.streams["entry"]])
        # candidates [3.1]–[3.6] of every pair from v*_j − v*_i, and their CSS choice [3.7], compiled
        reads = p.selection != PERFECT and SELECTIONS[p.selection].reads_candidates
        loc = localise(b.ranges, ranges, v_meas, b.est, delta_cos=p.delta_cos, delta_v=p.delta_v,
                       literal_eq_3_1=p.literal_eq_3_1, prediction_weight=p.prediction_weight, entry=entry, coin=coin,
                       candidates=reads)
        pairs = loc.candidates if reads else partial(pair_candidates, b.ranges, ranges, v_meas, b.est, p.delta_cos,
                                                     p.delta_v, p.literal_eq_3_1)
        if p.selection == PERFECT:
            new, kind = relative_truth(x), np.full(adjacency.shape, Kind.PERFECT, dtype=np.int8)
            triangle = round_trip = None
        else:  # CSS, and the others fall back on it
            base = (loc.est, loc.kind)
            new, kind, triangle, round_trip = SELECTIONS[p.selection].select(
                loc.candidates, adjacency, ranges, base, p)  # type: ignore[arg-type]  # (None: a selection reads none)
        # non-neighbours: dead reckoning x3 = x̂(t−1) + v*_j − v*_i [3.4], or the stale estimate
        est, kind = carry(adjacency, new, kind, b.est, v_meas, p.entry_policy == "dead_reckoning")
        return Beliefs(
            est=est, valid=adjacency.copy(), adjacency=adjacency.copy(), ranges=ranges, kind=kind, flag=loc.flag,
            odometry=v_meas,
            triangle=triangle, round_trip=round_trip, pairs=pairs,
        )


