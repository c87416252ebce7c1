"""Neighbour-only ranging (``slo.ranging = "neighbours"``, ours): each robot ranges, localises
and keeps estimates of the robots in its neighbourhood only, O(N·k) in time and memory
instead of the thesis' every pair (docs/readings.md, "Ranging only the neighbours (ours)").

State per robot is a row of slots (:class:`SlotBeliefs`): the neighbours of this step in
ascending index order, with each one's estimate x̂_ij and range d*_ij. A step (:class:`SlotLocaliser`)
finds the new neighbours through a grid (:mod:`.neighbour_kernels`) and localises each pair
with the thesis' own pair arithmetic (:func:`~.kernels.css_pair`, [3.1]–[3.7]) from:

- a neighbour it had last step: its kept range and estimate, as in the all-pairs step;
- a neighbour that has just arrived: the range it would have measured last step (the
  simulator works it out now, from last step's positions, only for the pairs that use it)
  and its frozen estimate if the robot still remembers it (the last ``memory`` robots that
  left its neighbourhood), else the pair's initial estimate x̂(−1) (the truth at step 0, or
  U(S) − U(S) drawn for the pair from a counter-based stream of the run).

With zero error and true initial estimates a pair whose history has no forgotten departure
gets the all-pairs step's bits; with errors the draws are other numbers of the same
distributions (``tests/test_slo_ranging.py``). Selections RTS and Akcan (triangles of pairs), the
dead-reckoning entry policy (every pair carried), the full and random neighbourhoods (every
pair used) and the formation motion need every pair and keep ``ranging = "all"``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any

import numpy as np

from ..core.compiled import f64, kernel
from ..core.compiled_draws import CompiledDraws
from ..core.rng import Streams
from ..core.snapshot import SnapshotError, arrays, integer, part
from . import neighbour_kernels
from .beliefs import PERFECT, LocaliserParams
from .candidates import Candidates, Flag
from .kernels import css_pair
from .neighbourhoods import Neighbourhood
from .ranging_modes import RANGINGS, Ranging, refusal
from .selection import Kind
from .sensor_kernels import reading
from .sensors import ErrorModel, measure_odometry, permanent_errors, permanent_normals

ENTRY_CODES = {"geometric_nearest": 1, "geometric_random": 2, "stale": 0}
INITIAL, PERFECT_KIND, NONE_KIND, FALLBACK = int(Kind.INITIAL), int(Kind.PERFECT), int(Kind.NONE), int(Flag.FALLBACK)


def neighbour_slots(rule: Neighbourhood, x: np.ndarray) -> np.ndarray:
    """The neighbourhood of every robot as slots (R, N, K) int64, ascending, −1 past the last."""
    x = np.ascontiguousarray(x, dtype=float)
    R, n = x.shape[:2]
    if rule.kind == "knn":
        return neighbour_kernels.knn_slots(x, int(rule.value))
    if rule.kind == "radius":
        return neighbour_kernels.radius_slots(x, float(rule.value))
    if rule.kind == "ring":
        return neighbour_kernels.ring_slots(R, n, int(rule.value))
    raise ValueError(f"neighbourhood: {rule.kind!r} has no neighbour-only form")


# ---------------------------------------------------------------------- initial estimates
@kernel
def _mix(z: np.uint64) -> np.uint64:
    """splitmix64's finaliser."""
    z = (z ^ (z >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
    z = (z ^ (z >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
    return z ^ (z >> np.uint64(31))


@kernel
def _uniform(key: np.uint64, counter: int) -> float:
    """U(0, 1) number ``counter`` of the stream ``key`` (counter-based: any one, in any order)."""
    z = _mix(key + np.uint64(counter) * np.uint64(0x9E3779B97F4A7C15))
    return float(z >> np.uint64(11)) * (1.0 / 9007199254740992.0)


@kernel
def _initial(r: int, i: int, j: int, n: int, truth: bool, x_init: np.ndarray, keys: np.ndarray, lo: float,
             hi: float) -> tuple[float, float]:
    """x̂_ij(−1): x_j − x_i at step 0, or a − b with a, b ~ U([lo, hi]²) (``random_estimates``'s law)."""
    if truth:
        return x_init[r, j, 0] - x_init[r, i, 0], x_init[r, j, 1] - x_init[r, i, 1]
    q = 4 * (i * n + j)
    key = keys[r]
    ax, ay = lo + (hi - lo) * _uniform(key, q), lo + (hi - lo) * _uniform(key, q + 1)
    bx, by = lo + (hi - lo) * _uniform(key, q + 2), lo + (hi - lo) * _uniform(key, q + 3)
    return ax - bx, ay - by


# ---------------------------------------------------------------------- the step
@kernel
def _start(nb: np.ndarray, x: np.ndarray, truth: bool, keys: np.ndarray, lo: float, hi: float, draws: np.ndarray,
           range_params: np.ndarray, perm_m: np.ndarray, perm_a: np.ndarray, est: np.ndarray, rng: np.ndarray) -> None:
    """Step 0: each neighbour's initial estimate and first range."""
    R, n, K = nb.shape
    sigma_m, sigma_a, p_fail, max_range = range_params
    for r in range(R):
        for i in range(n):
            for s in range(K):
                j = nb[r, i, s]
                if j < 0:
                    break
                est[r, i, s, 0], est[r, i, s, 1] = _initial(r, i, j, n, truth, x, keys, lo, hi)
                q = i * K + s
                dx, dy = x[r, j, 0] - x[r, i, 0], x[r, j, 1] - x[r, i, 1]
                rng[r, i, s] = reading(math.sqrt(dx * dx + dy * dy), draws[r, 0, q], draws[r, 1, q], draws[r, 2, q],
                                       sigma_m, sigma_a, perm_m[r, i], perm_a[r, i], p_fail, max_range)


@kernel
def _update(old_nb: np.ndarray, old_est: np.ndarray, old_rng: np.ndarray, old_mem: tuple, nb: np.ndarray,
            x_prev: np.ndarray, x: np.ndarray, v: np.ndarray, k: int, x_init: np.ndarray, truth: bool,
            keys: np.ndarray, lo: float, hi: float, draws: np.ndarray, range_params: np.ndarray,
            perm_m: np.ndarray, perm_a: np.ndarray, measure_all: bool, delta_cos: float, delta_v: float,
            literal: bool, w: float, entry: int, perfect: bool, est: np.ndarray, rng: np.ndarray, kind: np.ndarray,
            flag: np.ndarray, mem: tuple) -> None:
    """One localisation step of every neighbour pair (:class:`SlotLocaliser.update`) at step
    ``k``; ``old_mem`` and ``mem`` are the remembered robots before and after it: (who, their
    frozen estimate, the step they left)."""
    R, n, K = nb.shape
    Ko = old_nb.shape[2]
    old_who, old_frozen, old_left = old_mem
    who, frozen, left = mem
    M = who.shape[2]
    sigma_m, sigma_a, p_fail, max_range = range_params
    for r in range(R):
        for i in range(n):
            for q in range(M):
                who[r, i, q], left[r, i, q] = old_who[r, i, q], old_left[r, i, q]
                frozen[r, i, q, 0], frozen[r, i, q, 1] = old_frozen[r, i, q, 0], old_frozen[r, i, q, 1]
            o = 0
            for s in range(K):
                j = nb[r, i, s]
                if j < 0:
                    kind[r, i, s], flag[r, i, s] = NONE_KIND, FALLBACK
                    continue
                while o < Ko and old_nb[r, i, o] >= 0 and old_nb[r, i, o] < j:  # both rows ascend
                    o += 1
                kept = o < Ko and old_nb[r, i, o] == j
                q = i * K + s
                pm, pa = perm_m[r, i], perm_a[r, i]
                if kept:
                    d0, px, py = old_rng[r, i, o], old_est[r, i, o, 0], old_est[r, i, o, 1]
                else:  # arrived: last step's range, measured now; the remembered or the initial estimate
                    dx, dy = x_prev[r, j, 0] - x_prev[r, i, 0], x_prev[r, j, 1] - x_prev[r, i, 1]
                    d0 = reading(math.sqrt(dx * dx + dy * dy), draws[r, 3, q], draws[r, 4, q], draws[r, 5, q],
                                 sigma_m, sigma_a, pm, pa, p_fail, max_range) if measure_all else 0.0
                    px, py = _initial(r, i, j, n, truth, x_init, keys, lo, hi)
                    for m in range(M):
                        if who[r, i, m] == j:
                            px, py = frozen[r, i, m, 0], frozen[r, i, m, 1]
                            who[r, i, m] = -1
                            break
                dx, dy = x[r, j, 0] - x[r, i, 0], x[r, j, 1] - x[r, i, 1]
                d1 = reading(math.sqrt(dx * dx + dy * dy), draws[r, 0, q], draws[r, 1, q], draws[r, 2, q],
                             sigma_m, sigma_a, pm, pa, p_fail, max_range)
                rng[r, i, s] = d1
                vx, vy = v[r, j, 0] - v[r, i, 0], v[r, j, 1] - v[r, i, 1]  # v*_j − v*_i
                new = entry > 0 and not kept
                res = css_pair(vx, vy, d0, d1, px, py, delta_cos, delta_v, literal, w, new, entry == 2,
                               draws[r, 6, q] < 0.5)
                flag[r, i, s] = res[13]
                if perfect:
                    est[r, i, s, 0], est[r, i, s, 1], kind[r, i, s] = dx, dy, PERFECT_KIND
                else:
                    est[r, i, s, 0], est[r, i, s, 1], kind[r, i, s] = res[10], res[11], res[12]
            if M == 0:
                continue
            s = 0
            for o in range(Ko):  # whoever left is remembered with its last estimate, frozen
                j = old_nb[r, i, o]
                if j < 0:
                    break
                while s < K and nb[r, i, s] >= 0 and nb[r, i, s] < j:
                    s += 1
                if s < K and nb[r, i, s] == j:
                    continue
                q = 0
                for m in range(1, M):  # a free place, else the one who left longest ago
                    if who[r, i, q] < 0:
                        break
                    if who[r, i, m] < 0 or left[r, i, m] < left[r, i, q]:
                        q = m
                who[r, i, q], left[r, i, q] = j, k
                frozen[r, i, q, 0], frozen[r, i, q, 1] = old_est[r, i, o, 0], old_est[r, i, o, 1]


@kernel
def _dense(nb: np.ndarray, slot_est: np.ndarray, who: np.ndarray, frozen: np.ndarray, x_init: np.ndarray,
           truth: bool, keys: np.ndarray, lo: float, hi: float, est: np.ndarray, valid: np.ndarray) -> None:
    """Every pair's estimate: a neighbour's from its slot, a remembered robot's frozen one, any
    other's initial one (where each would start again)."""
    R, n, K = nb.shape
    for r in range(R):
        for i in range(n):
            for j in range(n):
                if j == i:
                    est[r, i, j, 0] = est[r, i, j, 1] = 0.0
                else:
                    est[r, i, j, 0], est[r, i, j, 1] = _initial(r, i, j, n, truth, x_init, keys, lo, hi)
                valid[r, i, j] = False
            for m in range(who.shape[2]):
                j = who[r, i, m]
                if j >= 0:
                    est[r, i, j, 0], est[r, i, j, 1] = frozen[r, i, m, 0], frozen[r, i, m, 1]
            for s in range(K):
                j = nb[r, i, s]
                if j < 0:
                    break
                est[r, i, j, 0], est[r, i, j, 1] = slot_est[r, i, s, 0], slot_est[r, i, s, 1]
                valid[r, i, j] = True


@kernel
def _scatter(nb: np.ndarray, values: np.ndarray, fill: float, out: np.ndarray) -> None:
    """Slot values (R, N, K) into their pairs (R, N, N), ``fill`` elsewhere."""
    R, n, K = nb.shape
    for r in range(R):
        for i in range(n):
            for j in range(n):
                out[r, i, j] = fill
            for s in range(K):
                if nb[r, i, s] >= 0:
                    out[r, i, nb[r, i, s]] = values[r, i, s]


@dataclass
class Start:
    """Where the pairs' initial estimates come from: the step-0 positions (truth) or a counter-based
    stream a run, ``keys``, over S = [lo, hi]²."""

    truth: bool
    x: np.ndarray  # (R, N, 2) positions at step 0
    keys: np.ndarray  # (R,) uint64
    lo: float
    hi: float


@dataclass
class SlotBeliefs:
    """What every robot believes about its neighbours after one step, as slots (R, N, K): the
    neighbour ``nb`` (ascending, −1 past the last), its estimate, range, Kind and Flag. The
    (R, N, N) views of :class:`~.beliefs.Beliefs` (``est``, ``valid``, …) are built when read,
    O(N²): for drawing a few robots and for the metrics that need every pair."""

    nb: np.ndarray  # (R, N, K) int64
    slot_est: np.ndarray  # (R, N, K, 2)
    slot_ranges: np.ndarray  # (R, N, K) d*_ij(t)
    slot_kind: np.ndarray  # (R, N, K) int8
    slot_flag: np.ndarray  # (R, N, K) int8
    odometry: np.ndarray  # (R, N, 2) v*_i(t)
    memory: tuple[np.ndarray, np.ndarray, np.ndarray] = field(repr=False)  # who (R, N, M), frozen (…, 2), left at
    start: Start = field(repr=False)
    triangle: None = None
    round_trip: None = None
    candidates: Candidates | None = None  # not kept: the dense step's inspector only

    @property
    def slot_valid(self) -> np.ndarray:
        """(R, N, K): the slot holds a neighbour."""
        return self.nb >= 0

    @cached_property
    def _dense(self) -> tuple[np.ndarray, np.ndarray]:
        R, n = self.nb.shape[:2]
        est, valid = np.empty((R, n, n, 2)), np.empty((R, n, n), bool)
        st = self.start
        _dense(self.nb, self.slot_est, self.memory[0], self.memory[1], st.x, st.truth, st.keys, st.lo, st.hi, est,
               valid)
        return est, valid

    @property
    def est(self) -> np.ndarray:
        """(R, N, N, 2) x̂_ij; a non-neighbour's is its initial estimate (where it would start)."""
        return self._dense[0]

    @property
    def valid(self) -> np.ndarray:
        return self._dense[1]

    @property
    def adjacency(self) -> np.ndarray:
        return self._dense[1]

    def _scattered(self, values: np.ndarray, fill: float, dtype: type) -> np.ndarray:
        R, n = self.nb.shape[:2]
        out = np.empty((R, n, n))
        _scatter(self.nb, values.astype(float), fill, out)
        return out.astype(dtype)

    @cached_property
    def ranges(self) -> np.ndarray:
        """(R, N, N) d*_ij of the neighbours, 0 (not measured) elsewhere."""
        return self._scattered(self.slot_ranges, 0.0, float)

    @cached_property
    def kind(self) -> np.ndarray:
        return self._scattered(self.slot_kind, float(Kind.NONE), np.int8)

    @cached_property
    def flag(self) -> np.ndarray:
        return self._scattered(self.slot_flag, float(Flag.FALLBACK), np.int8)


SLOT_ARRAYS = ("nb", "slot_est", "slot_ranges", "slot_kind", "slot_flag", "odometry")


def slot_beliefs_data(b: SlotBeliefs) -> dict[str, Any]:
    """``b`` as plain data (:mod:`~shoal.engine.core.snapshot`): the slots, the memory and where
    the initial estimates come from."""
    st = b.start
    return {**{n: getattr(b, n) for n in SLOT_ARRAYS}, "memory": list(b.memory),
            "start": {"truth": st.truth, "x": st.x, "keys": st.keys, "lo": st.lo, "hi": st.hi}}


def slot_beliefs_from(data: Any, runs: int, n: int, where: str = "beliefs") -> SlotBeliefs:
    """The :class:`SlotBeliefs` of :func:`slot_beliefs_data`'s ``data``, for ``runs`` × ``n`` robots."""
    got = {name: arrays(part(data, name, where), f"{where}.{name}") for name in SLOT_ARRAYS}
    nb = got["nb"]
    if nb.ndim != 3 or nb.shape[:2] != (runs, n) or nb.dtype != np.int64:
        raise SnapshotError(f"{where}.nb: expected int64 ({runs}, {n}, K), got {nb.dtype}{nb.shape}")
    K = nb.shape[2]
    want = {"slot_est": (runs, n, K, 2), "slot_ranges": (runs, n, K), "slot_kind": (runs, n, K),
            "slot_flag": (runs, n, K), "odometry": (runs, n, 2)}
    for name, shape in want.items():
        if got[name].shape != shape:
            raise SnapshotError(f"{where}.{name}: expected shape {shape}, got {got[name].shape}")
    if ((nb < -1) | (nb >= n)).any():
        raise SnapshotError(f"{where}.nb: a neighbour outside 0 … {n - 1}")
    mem = part(data, "memory", where)
    if not isinstance(mem, list) or len(mem) != 3:
        raise SnapshotError(f"{where}.memory: expected [who, frozen, left]")
    who, frozen, left = (arrays(v, f"{where}.memory[{i}]") for i, v in enumerate(mem))
    M = who.shape[2] if who.ndim == 3 else -1
    if who.shape != (runs, n, M) or frozen.shape != (runs, n, M, 2) or left.shape != (runs, n, M) \
            or who.dtype != np.int64 or left.dtype != np.int64 or ((who < -1) | (who >= n)).any():
        raise SnapshotError(f"{where}.memory: expected who and left int64 ({runs}, {n}, M), frozen (…, 2)")
    st, at = part(data, "start", where), f"{where}.start"
    x0, keys = arrays(part(st, "x", at), f"{at}.x"), arrays(part(st, "keys", at), f"{at}.keys")
    truth, lo, hi = part(st, "truth", at), part(st, "lo", at), part(st, "hi", at)
    if x0.shape != (runs, n, 2) or keys.shape != (runs,) or keys.dtype != np.uint64 or not isinstance(truth, bool) \
            or not all(isinstance(v, float) for v in (lo, hi)):
        raise SnapshotError(f"{where}.start: expected truth, x ({runs}, {n}, 2), uint64 keys ({runs},), lo and hi")
    start = Start(truth, f64(x0), keys, lo, hi)
    return SlotBeliefs(nb, f64(got["slot_est"]), f64(got["slot_ranges"]), got["slot_kind"].astype(np.int8),
                       got["slot_flag"].astype(np.int8), f64(got["odometry"]), (who, f64(frozen), left), start)


class SlotLocaliser:
    """:class:`~.beliefs.Localiser` for neighbour-only ranging: the same sensors and
    permanent errors, the pairs of each robot's neighbourhood only."""

    def __init__(self, params: LocaliserParams, errors: ErrorModel, streams: Streams, n: int, start: Start,
                 memory: int) -> None:
        if memory < 0:
            raise ValueError(f"memory: need a whole number >= 0, got {memory}")
        self.params, self.errors, self.streams, self.n, self.start_info = params, errors, streams, n, start
        self.memory = int(memory)
        self._z = permanent_normals(streams["permanent"], n)
        self.permanent = permanent_errors(errors, self._z)
        self._range_draws, self._odometry_draws = CompiledDraws(streams["range"]), CompiledDraws(streams["odometry"])
        self._entry_draws = CompiledDraws(streams["entry"])

    def retune(self, params: LocaliserParams | None = None, errors: ErrorModel | None = None) -> None:
        if params is not None:
            self.params = params
        if errors is not None:
            self.errors = errors
            self.permanent = permanent_errors(errors, self._z)

    def snapshot(self) -> dict[str, Any]:
        """The calibration draws (as :meth:`~.beliefs.Localiser.snapshot`)."""
        return {"n": self.n, "z": self._z}

    def restore(self, data: Any) -> None:
        n = integer(part(data, "n", "localiser"), "localiser.n", 1)
        z = arrays(part(data, "z", "localiser"), "localiser.z", dtype=np.floating)
        if z.shape != (self._z.shape[0], self._z.shape[1], n) or n != self.n:
            raise SnapshotError(f"localiser.z: expected shape {self._z.shape}, got {z.shape}")
        self._z = z
        self.permanent = permanent_errors(self.errors, z)

    def adopt(self, b: SlotBeliefs) -> None:
        """Initial estimates from now on as a restored ``b`` says."""
        self.start_info = b.start

    def _range_params(self) -> np.ndarray:
        rg = self.errors.range
        return np.array([rg.sigma_m, rg.sigma_a, rg.p_fail, self.params.max_range], dtype=float)

    def _draws(self, nb: np.ndarray, arrivals: bool) -> np.ndarray:
        """(R, 7, N·K): each slot's failure and two normals for this step's range, the same for
        last step's (an arrival's), and the entry coin."""
        R, n, K = nb.shape
        m = n * K
        d = np.empty((R, 7, m))
        parts = [d[:, 0], d[:, 1], d[:, 2]] + ([d[:, 3], d[:, 4], d[:, 5]] if arrivals else [])
        buf = [np.empty((R, m)) for _ in parts]
        self._range_draws.fill(*buf, normal=(False, True, True) * (len(parts) // 3))
        for dst, src in zip(parts, buf):
            dst[:] = src
        if self.params.entry_policy == "geometric_random":
            coin = np.empty((R, m))
            self._entry_draws.fill(coin, normal=(False,))
            d[:, 6] = coin
        else:
            d[:, 6] = 1.0
        return d

    def start(self, x: np.ndarray, nb: np.ndarray) -> SlotBeliefs:
        """Step 0: ranges to the neighbours, no localisation yet; the initial estimates."""
        R, n, K = nb.shape
        st = self.start_info
        est, rng = np.zeros((R, n, K, 2)), np.zeros((R, n, K))
        _start(nb, f64(x), st.truth, st.keys, st.lo, st.hi, self._draws(nb, False), self._range_params(),
               f64(self.permanent.range_m), f64(self.permanent.range_a), est, rng)
        kind = np.where(nb >= 0, INITIAL, NONE_KIND).astype(np.int8)
        mem = (np.full((R, n, self.memory), -1, np.int64), np.zeros((R, n, self.memory, 2)),
               np.zeros((R, n, self.memory), np.int64))
        return SlotBeliefs(nb, est, rng, kind, np.full(nb.shape, FALLBACK, np.int8), np.zeros(x.shape), mem, st)

    def update(self, b: SlotBeliefs, x_prev: np.ndarray, x: np.ndarray, nb: np.ndarray, k: int) -> SlotBeliefs:
        """One localisation step, step ``k``, at true positions ``x`` after the moves from ``x_prev``."""
        p, st = self.params, self.start_info
        v_meas = measure_odometry(x - x_prev, self.errors.odometry, self.permanent, self._odometry_draws)
        R, n, K = nb.shape
        est, rng = np.empty((R, n, K, 2)), np.empty((R, n, K))
        kind, flag = np.empty((R, n, K), np.int8), np.empty((R, n, K), np.int8)
        M = b.memory[0].shape[2]
        mem = (np.empty((R, n, M), np.int64), np.empty((R, n, M, 2)), np.empty((R, n, M), np.int64))
        _update(b.nb, b.slot_est, b.slot_ranges, b.memory, nb, f64(x_prev), f64(x), f64(v_meas), int(k), st.x,
                st.truth, st.keys, st.lo, st.hi, self._draws(nb, True), self._range_params(),
                f64(self.permanent.range_m), f64(self.permanent.range_a), p.measure_all_ranges, float(p.delta_cos),
                float(p.delta_v), bool(p.literal_eq_3_1), float(p.prediction_weight), ENTRY_CODES[p.entry_policy],
                p.selection == PERFECT, est, rng, kind, flag, mem)
        return SlotBeliefs(nb, est, rng, kind, flag, v_meas, mem, st)


# ---------------------------------------------------------------------- what the swarm reads
@kernel
def _slot_of(nb: np.ndarray, r: int, i: int, j: int) -> int:
    lo, hi = 0, nb.shape[2]
    while lo < hi:  # the row ascends, −1 (empty) at its end
        mid = (lo + hi) // 2
        v = nb[r, i, mid]
        if v < 0 or v > j:
            hi = mid
        elif v < j:
            lo = mid + 1
        else:
            return mid
    return -1


@kernel
def _local_best(f: np.ndarray, fP: np.ndarray, P: np.ndarray, nb: np.ndarray, est: np.ndarray, pbest: bool,
                P_out: np.ndarray, fP_out: np.ndarray, self_best: np.ndarray, L: np.ndarray) -> None:
    R, n = f.shape[0], f.shape[1]
    K = nb.shape[2]
    for r in range(R):
        for i in range(n):  # step 2: the pbest moves to the particle itself
            better = f[r, i] < fP[r, i]
            P_out[r, i, 0], P_out[r, i, 1] = (0.0, 0.0) if better else (P[r, i, 0], P[r, i, 1])
            fP_out[r, i] = f[r, i] if better else fP[r, i]
        score = fP_out[r] if pbest else f[r]
        for i in range(n):  # step 3: numpy's min and argmin over the informants (NaN first), in index order
            best, low = 0, np.inf
            s, first, mine = 0, True, False
            while True:
                nxt = nb[r, i, s] if s < K else -1
                if not mine and (nxt < 0 or i < nxt):
                    j, mine = i, True
                elif nxt >= 0:
                    j = nxt
                    s += 1
                else:
                    break
                if first:
                    first = False
                    if j == 0:
                        best, low = 0, score[0]
                        continue
                elif low != low:
                    break
                v = score[j]
                if v != v or v < low:
                    best, low = j, v
            own = score[i] <= low  # ties go to the particle itself
            self_best[r, i] = own
            jj = i if own else best
            ex = ey = 0.0
            if jj != i:
                q = _slot_of(nb, r, i, jj)
                ex, ey = est[r, i, q, 0], est[r, i, q, 1]
            if pbest:  # x̂_ij* + P_j*, or the own P
                if own:
                    L[r, i, 0], L[r, i, 1] = P_out[r, i, 0], P_out[r, i, 1]
                else:
                    L[r, i, 0], L[r, i, 1] = ex + P_out[r, jj, 0], ey + P_out[r, jj, 1]
            elif own:
                L[r, i, 0], L[r, i, 1] = 0.0, 0.0
            else:
                L[r, i, 0], L[r, i, 1] = ex, ey


def local_best(f: np.ndarray, fP: np.ndarray, P: np.ndarray, b: SlotBeliefs,
               pbest: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """:func:`~.kernels.local_best` on slots: the same P, fP, self_best and L."""
    R, n = f.shape
    P_out, fP_out, self_best, L = np.empty((R, n, 2)), np.empty((R, n)), np.empty((R, n), np.bool_), np.empty((R, n, 2))
    _local_best(f64(f), f64(fP), f64(P), b.nb, b.slot_est, bool(pbest), P_out, fP_out, self_best, L)
    return P_out, fP_out, self_best, L


@kernel
def _slot_errors(x: np.ndarray, nb: np.ndarray, est: np.ndarray, e_abs: np.ndarray, e_rel: np.ndarray,
                 ang: np.ndarray) -> None:
    R, n, K = nb.shape
    for r in range(R):
        for i in range(n):
            for s in range(K):
                j = nb[r, i, s]
                q = i * K + s
                if j < 0:
                    e_abs[r, q] = e_rel[r, q] = ang[r, q] = np.nan
                    continue
                tx, ty = x[r, j, 0] - x[r, i, 0], x[r, j, 1] - x[r, i, 1]
                dx, dy = est[r, i, s, 0] - tx, est[r, i, s, 1] - ty
                ea = math.sqrt(dx * dx + dy * dy)
                dist = math.sqrt(tx * tx + ty * ty)
                e_abs[r, q] = ea
                e_rel[r, q] = ea / dist if dist > 0.0 else np.nan
                ang[r, q] = math.atan2(est[r, i, s, 1], est[r, i, s, 0]) - math.atan2(ty, tx)


def pair_errors(x: np.ndarray, b: SlotBeliefs) -> dict[str, np.ndarray]:
    """e_abs, e_rel and e_ang of the neighbour pairs, (R, N·K) in the order of the dense
    metrics' pairs (observer, then neighbour), NaN in empty slots."""
    R, n, K = b.nb.shape
    e_abs, e_rel, ang = np.empty((R, n * K)), np.empty((R, n * K)), np.empty((R, n * K))
    _slot_errors(f64(x), b.nb, b.slot_est, e_abs, e_rel, ang)
    wrapped = np.pi - np.mod(np.pi - ang, 2.0 * np.pi)
    return {"e_abs": e_abs, "e_rel": e_rel, "e_ang": np.where(np.isnan(ang), np.nan, np.abs(wrapped))}


def initial_keys(streams: Streams) -> np.ndarray:
    """One 64-bit key a run for the pairs' random initial estimates, from its init stream."""
    return np.array([g.integers(0, 2**63, dtype=np.int64) for g in streams["init"]], dtype=np.uint64)


def slot_count(b: SlotBeliefs) -> int:
    """Slots a robot has this step."""
    return int(b.nb.shape[2])


__all__ = ["RANGINGS", "Ranging", "SlotBeliefs", "SlotLocaliser", "Start", "initial_keys", "local_best",
           "neighbour_slots", "pair_errors", "refusal", "slot_count"]

