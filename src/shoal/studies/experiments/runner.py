"""Seeded Monte-Carlo batches: advance many runs of one scenario and keep per-step series.

Run ``i`` of a batch seeded with ``seed`` always draws from child ``i`` of
``SeedSequence(seed)`` (see :mod:`shoal.engine.kinds.swarm`), so a batch may be cut into chunks of
runs, simulated in any order or in other processes, and glued back together: the result
is the same, bit for bit.
"""

from __future__ import annotations

import math
from contextlib import closing
from dataclasses import dataclass, field
from typing import Any, Callable, Hashable, Iterator, Protocol, Sequence, TypeVar, overload

import numpy as np

from shoal.engine.kinds.swarm import Simulation, StepInfo
from shoal.presets.builders.swarm import build_simulation
from shoal.presets.io import load
from shoal.presets.models import Scenario

from ..cost import run_cost
from . import schedulers
from .schedulers import Scheduler

OnStep = Callable[[int, Simulation, StepInfo], None]


@dataclass
class BatchResult:
    """Per-step series of ``runs`` runs (index 0 of the step axis is the initial state).

    ``omega[k]`` and ``c_hat[k]`` are the coefficients in force at ``t[k]``, i.e. the ones
    that command the velocity sampled at ``t[k + 1]``.
    """

    seed: int
    first_run: int
    dt: float
    d: int
    robots: int
    t: np.ndarray  # (K+1,)
    max_speed: np.ndarray  # (K+1, R) highest |u| in each run's swarm
    tracked: np.ndarray  # (K+1, R, d) velocity of the tracked particle
    track: int  # index of the tracked particle
    omega: np.ndarray  # (K+1,)
    c_hat: np.ndarray  # (K+1,) sum of the accelerating coefficients

    @property
    def runs(self) -> int:
        return self.max_speed.shape[1]

    @property
    def steps(self) -> int:
        return self.max_speed.shape[0] - 1

    @property
    def run_index(self) -> np.ndarray:
        return np.arange(self.first_run, self.first_run + self.runs)

    @property
    def run_max(self) -> np.ndarray:
        """Highest |u| over all particles and the whole run, (R,)."""
        return self.max_speed.max(axis=0)

    @property
    def U(self) -> np.ndarray:
        """Asymptotic top speed ĉ√d/(1 − ω) [3.29] of the coefficients in force at ``t``, (K+1,)."""
        return self.c_hat * math.sqrt(self.d) / (1.0 - self.omega)

    @property
    def U_command(self) -> np.ndarray:
        """Top speed of the coefficients that commanded the velocity at ``t[k]`` (k ≥ 1), (K,)."""
        return self.U[:-1]

    def envelope(self, start: float | None = None) -> np.ndarray:
        """Worst-case bound B[k] ≥ |u[k]|: B[0] = ``start`` (default: the observed max at
        t = 0), B[k+1] = ω[k] B[k] + ĉ[k]√d. It equals U while U never drops and decays
        geometrically, as ω^n, to the new U after a drop: ω u carries the old speed."""
        b = np.empty(self.steps + 1)
        b[0] = float(self.max_speed[0].max()) if start is None else start
        root_d = math.sqrt(self.d)
        for k in range(self.steps):
            b[k + 1] = self.omega[k] * b[k] + self.c_hat[k] * root_d
        return b


def _coefficients(info_omega: Any, info_c: Any) -> tuple[float, float]:
    """Scalar (ω, ĉ) of a tick; per-robot policies give their largest values (worst case)."""
    omega = float(np.max(np.asarray(info_omega, dtype=float)))
    c = np.asarray(info_c, dtype=float)
    c_hat = float(np.max(c.reshape(c.shape[0], -1).sum(axis=0))) if c.ndim > 1 else float(c.sum())
    return omega, c_hat


def make_simulation(scenario: Scenario, *, runs: int, seed: int, first_run: int = 0) -> Simulation:
    """``build_simulation`` for runs ``first_run … first_run + runs − 1`` of ``seed``."""
    return build_simulation(scenario, runs=runs, seed=seed, first_run=first_run)


def run_batch(
    scenario: Scenario,
    runs: int,
    seed: int,
    steps: int,
    on_step: OnStep | None = None,
    *,
    first_run: int = 0,
    track: int = 0,
) -> BatchResult:
    """Advance runs ``first_run …`` of ``scenario`` (seeded by ``seed``) for ``steps`` ticks.

    Keeps, at every step, the swarm's highest speed of each run, the velocity of particle
    ``track`` and the coefficients in force. ``on_step(k, sim, info)`` is called after tick
    ``k`` (1-based).
    """
    if runs < 1 or steps < 0:
        raise ValueError(f"need runs >= 1 and steps >= 0, got runs={runs}, steps={steps}")
    sim = make_simulation(scenario, runs=runs, seed=seed, first_run=first_run)
    if not 0 <= track < sim.robots:
        raise ValueError(f"track must index a particle (0..{sim.robots - 1}), got {track}")
    t = np.empty(steps + 1)
    max_speed = np.empty((steps + 1, runs))
    tracked = np.empty((steps + 1, runs, sim.d))
    omega = np.empty(steps + 1)
    c_hat = np.empty(steps + 1)
    t[0] = sim.t
    max_speed[0] = np.linalg.norm(sim.state.u, axis=-1).max(axis=1)
    tracked[0] = sim.state.u[:, track]
    if on_step is None:  # nobody looks between the ticks: whole blocks of them in one call
        series = sim.run(steps, track)
        t[1:], max_speed[1:], tracked[1:] = series.t, series.speeds[:, 0], series.tracked
        for k, (w, c) in enumerate(zip(series.omega, series.c)):
            omega[k], c_hat[k] = _coefficients(w, c)
    else:
        for k in range(1, steps + 1):
            info = sim.step()
            omega[k - 1], c_hat[k - 1] = _coefficients(info.omega, info.c)
            t[k] = info.t
            max_speed[k] = info.max_speed
            tracked[k] = sim.state.u[:, track]
            on_step(k, sim, info)
    omega[steps], c_hat[steps] = _coefficients(*sim.policy.coefficients(sim.t, sim.dt, sim.d))
    return BatchResult(
        seed=seed, first_run=first_run, dt=sim.dt, d=sim.d, robots=sim.robots, t=t, max_speed=max_speed,
        tracked=tracked, track=track, omega=omega, c_hat=c_hat,
    )


def concat(parts: Sequence[BatchResult]) -> BatchResult:
    """Glue chunks of consecutive runs (in any order) into one result."""
    parts = sorted(parts, key=lambda p: p.first_run)
    first = parts[0]
    expected = first.first_run
    for p in parts:
        if p.first_run != expected or p.seed != first.seed or p.steps != first.steps:
            raise ValueError("chunks must be consecutive runs of the same seed and length")
        expected += p.runs
    return BatchResult(
        seed=first.seed, first_run=first.first_run, dt=first.dt, d=first.d, robots=first.robots, t=first.t,
        max_speed=np.concatenate([p.max_speed for p in parts], axis=1),
        tracked=np.concatenate([p.tracked for p in parts], axis=1),
        track=first.track, omega=first.omega, c_hat=first.c_hat,
    )


# ---------------------------------------------------------------------- many batches
@dataclass(frozen=True)
class Job:
    """One (scenario, seed) batch of ``runs`` runs, named by ``key``. Picklable."""

    key: tuple[str, int]
    preset: str
    overrides: tuple[str, ...]
    seed: int
    runs: int
    steps: int
    track: int = 0

    @property
    def cost(self) -> float:
        """Estimated CPU seconds of one run (:func:`~shoal.studies.cost.run_cost`)."""
        return run_cost(load(self.preset, list(self.overrides)), self.steps)


def simulate_job(job: Job, first_run: int, runs: int) -> BatchResult:
    """Runs ``first_run … first_run + runs − 1`` of a :class:`Job` (the default ``simulate``)."""
    scenario = load(job.preset, list(job.overrides))
    return run_batch(scenario, runs, job.seed, job.steps, first_run=first_run, track=job.track)


# simulate(job, first_run, runs) -> result of those runs; merge(results of consecutive chunks) -> one result
Simulate = Callable[[Any, int, int], Any]
Merge = Callable[[Sequence[Any]], Any]

K = TypeVar("K", bound=Hashable, covariant=True)
B = TypeVar("B")


class KeyedJob(Protocol[K]):
    """What the runner reads of a job: its ``key`` and its number of ``runs`` (and, if it has
    one, its ``cost``); the rest is for the job's own ``simulate``."""

    @property
    def key(self) -> K: ...

    @property
    def runs(self) -> int: ...


@dataclass(frozen=True)
class _Chunk:
    job: Any  # anything picklable with ``key`` and ``runs``
    first_run: int
    runs: int
    simulate: Simulate


def _simulate_chunk(chunk: _Chunk) -> tuple[Hashable, Any]:
    return chunk.job.key, chunk.simulate(chunk.job, chunk.first_run, chunk.runs)


CHUNKS_PER_WORKER = 4  # so that the last chunks of a batch finish close together


def _chunks(jobs: Sequence[Any], cap: int, simulate: Simulate, workers: int) -> list[_Chunk]:
    """Cut every job's runs into chunks of at most ``cap`` runs, sized by cost: a job's
    ``cost`` (estimated seconds per run; 1 if it has none) decides how many of its runs make a
    chunk, so that with several workers every chunk costs about the same, 1/4 of a worker's
    share, whatever the job (a cheap job batches many runs into one vectorised tick, a costly
    one is spread over the workers). Costliest chunks first, so no worker is left with a long
    one at the end. One worker takes whole jobs (up to ``cap``), in order."""
    cost = [float(getattr(j, "cost", 1.0)) or 1.0 for j in jobs]
    target = sum(c * j.runs for c, j in zip(cost, jobs)) / (CHUNKS_PER_WORKER * workers)
    out = []
    for job, c in zip(jobs, cost):
        size = job.runs if workers == 1 else max(1, round(target / c))
        parts = math.ceil(job.runs / max(1, min(cap, size, job.runs)))
        start = 0
        for p in range(parts):  # as equal as can be
            n = job.runs // parts + (p < job.runs % parts)
            out.append(_Chunk(job, start, n, simulate))
            start += n
    if workers > 1:
        rank = {id(j): c for j, c in zip(jobs, cost)}
        out.sort(key=lambda ch: -rank[id(ch.job)] * ch.runs)  # stable: job order among equals
    return out


@dataclass
class _Progress:
    total: int
    enabled: bool | Callable[[int], None]
    desc: str
    bar: Any = field(default=None, init=False)

    def __enter__(self) -> "_Progress":
        if callable(self.enabled):
            self.bar = None
        elif self.enabled:
            from tqdm import tqdm

            self.bar = tqdm(total=self.total, desc=self.desc, unit="run")
        return self

    def update(self, n: int) -> None:
        if callable(self.enabled):
            self.enabled(n)
        elif self.bar is not None:
            self.bar.update(n)

    def __exit__(self, *exc: Any) -> None:
        if self.bar is not None:
            self.bar.close()


@overload
def iter_jobs(
    jobs: Sequence[Job], *, workers: int = 1, scheduler: Scheduler | None = None,
    progress: bool | Callable[[int], None] = False, chunk: int = 25, desc: str = "runs",
    cancelled: Callable[[], bool] | None = None,
) -> Iterator[tuple[tuple[str, int], BatchResult]]: ...


@overload
def iter_jobs(
    jobs: Sequence[KeyedJob[K]], *, workers: int = 1, scheduler: Scheduler | None = None,
    progress: bool | Callable[[int], None] = False, chunk: int = 25, desc: str = "runs",
    simulate: Callable[[Any, int, int], B], merge: Callable[[Sequence[B]], B],
    cancelled: Callable[[], bool] | None = None,
) -> Iterator[tuple[K, B]]: ...


def iter_jobs(
    jobs: Sequence[Any], *, workers: int = 1, scheduler: Scheduler | None = None,
    progress: bool | Callable[[int], None] = False, chunk: int = 25, desc: str = "runs",
    simulate: Simulate = simulate_job, merge: Merge = concat, cancelled: Callable[[], bool] | None = None,
) -> Iterator[tuple[Any, Any]]:  # (the overloads above say which)
    """Yield ``(key, result)`` of every job as soon as all its chunks are in (earlier jobs
    tend to finish first). The chunks run on ``scheduler``; by default the one of the
    enclosing :func:`~.schedulers.using` block, else this process (``workers == 1``) or a
    local pool of ``workers`` processes. ``progress`` shows a bar, or is called with the
    number of runs each finished chunk adds. Once ``cancelled()`` is true (asked after every
    chunk) the iteration ends: chunks still running finish, the rest never start."""
    if workers < 1:
        raise ValueError(f"workers must be >= 1, got {workers}")
    if len({j.key for j in jobs}) != len(jobs):
        raise ValueError("job keys must be unique")
    if not jobs:
        return
    sched = scheduler or schedulers.current() or schedulers.local(workers)
    chunks = _chunks(jobs, max(1, chunk), simulate, sched.workers)
    parts: dict[Hashable, list[Any]] = {j.key: [] for j in jobs}
    expected = {j.key: 0 for j in jobs}
    for c in chunks:
        expected[c.job.key] += 1
    with _Progress(sum(j.runs for j in jobs), progress, desc) as bar, \
            closing(sched.map_unordered(_simulate_chunk, chunks)) as results:  # type: ignore[type-var]
        for i, (key, res) in results:
            parts[key].append(res)
            bar.update(chunks[i].runs)
            if len(parts[key]) == expected[key]:
                yield key, merge(parts.pop(key))
            if cancelled is not None and cancelled():
                return


@overload
def run_jobs(
    jobs: Sequence[Job], *, workers: int = 1, scheduler: Scheduler | None = None,
    progress: bool | Callable[[int], None] = False, chunk: int = 25, desc: str = "runs",
) -> dict[tuple[str, int], BatchResult]: ...


@overload
def run_jobs(
    jobs: Sequence[KeyedJob[K]], *, workers: int = 1, scheduler: Scheduler | None = None,
    progress: bool | Callable[[int], None] = False, chunk: int = 25, desc: str = "runs",
    simulate: Callable[[Any, int, int], B], merge: Callable[[Sequence[B]], B],
) -> dict[K, B]: ...


def run_jobs(
    jobs: Sequence[Any], *, workers: int = 1, scheduler: Scheduler | None = None,
    progress: bool | Callable[[int], None] = False, chunk: int = 25, desc: str = "runs",
    simulate: Simulate = simulate_job, merge: Merge = concat,
) -> dict[Any, Any]:  # (the overloads above say which)
    """Simulate every job, split into chunks of at most ``chunk`` runs sized by the jobs'
    estimated cost (:func:`_chunks`); with ``workers > 1`` the chunks go to a process pool,
    with a ``scheduler`` (or inside ``schedulers.using``) wherever it sends them, e.g. a Dask
    cluster. The results do not depend on ``workers``,
    ``chunk`` or the scheduler.

    By default a job is a :class:`Job` and its result a :class:`BatchResult`; other kinds
    of job (e.g. Chapter 4–5 fleets) pass their own module-level, picklable ``simulate``
    and a ``merge`` that glues chunks of consecutive runs, in any order, into one result.
    Returns the results in the order of ``jobs``."""
    done = dict(iter_jobs(jobs, workers=workers, scheduler=scheduler, progress=progress, chunk=chunk, desc=desc,
                          simulate=simulate, merge=merge))
    return {j.key: done[j.key] for j in jobs}
