"""Shared machinery of the Chapter 4–5 fleet reproductions (Figs. 4-6, 4-7, 5-4, 5-5).

A *case* is a shipped preset plus ``--set``-style overrides, so every case can also be run
by hand: ``shoal run course-dvc --set controller.law=rpso ...``. A :class:`FleetJob` is one
case (in one motion mode) for ``runs`` seeded runs; :func:`simulate_fleet` advances a chunk
of its runs and records per-step metrics, and :func:`merge` glues chunks back together, so
:func:`shoal.studies.experiments.runner.run_jobs` can spread the runs over processes with
results that do not depend on the number of workers.

Run ``i`` of a case uses child ``i`` of ``SeedSequence(seed)`` where ``seed`` is the preset
seed; every case of a figure shares it (same start positions in run ``i`` of every case).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np

from shoal.engine.kinds.fleet import STALL_SPEED, STALL_STEPS
from shoal.engine.robots.dvc import TABLE_4_1
from shoal.presets.builders.fleet import build_fleet
from shoal.presets.io import load
from shoal.presets.models import Robot, Scenario

from ..cost import run_cost
from .output import num
from .output import percentile_band as band

MODE_OVERRIDES: dict[str, tuple[str, ...]] = {
    # MATLAB-like: ideal particles, exact position update [4.6]
    "kinematic": ("robot.motion=kinematic",),
    # Gazebo-like: pymunk bodies with inertia tracking the velocity demand; mecanum wheels
    # as on the thesis' Summit XL robots (direction-dependent top speed [4.18]/[4.19])
    "physics": ("robot.motion=physics", "robot.drive=mecanum"),
}


@dataclass(frozen=True)
class Case:
    """A named preset with overrides."""

    name: str
    preset: str
    overrides: tuple[str, ...] = ()

    def scenario(self, extra: Sequence[str] = ()) -> Scenario:
        return load(self.preset, [*self.overrides, *extra])

    def command(self, extra: Sequence[str] = ()) -> str:
        """The ``shoal run`` command line that runs this case by hand."""
        sets = " ".join(f"--set {o}" for o in (*self.overrides, *extra))
        return f"shoal run {self.preset} {sets}".strip()


def constant_case(law: str, ratio: str) -> Case:
    """Table 4.1 constant-coefficient case: ``law`` "rpso" or "adapted-rpso", ``ratio`` one
    of "c3-high", "c3-equal", "c3-low" (c3/(c1 + c2) = 2, 1, 0.5; ω = 0.1)."""
    k = TABLE_4_1[ratio]
    prefix = "rpso" if law == "rpso" else "adapted"
    return Case(f"{prefix}-{ratio}", "course-dvc", (
        f"controller.law={law}", "controller.mode=raw", f"controller.omega={k['omega']}",
        f"controller.c1={k['c1']}", f"controller.c2={k['c2']}", f"controller.c3={k['c3']}",
    ))


# The seven Chapter 4 cases (Table 4.1) and the non-omni controller of Chapter 5.
RATIOS = ("c3-high", "c3-equal", "c3-low")
CH4_CASES: tuple[Case, ...] = (
    *(constant_case("rpso", r) for r in RATIOS),
    *(constant_case("adapted-rpso", r) for r in RATIOS),
    Case("adapted-dvc", "course-dvc"),
)
NONOMNI = Case("nonomni-dvc", "course-nonomni")  # DVC guard on (the preset's choice)
NONOMNI_NO_GUARD = Case("nonomni-dvc-noguard", "course-nonomni", ("controller.guard=false",))


# ---------------------------------------------------------------------- simulation
@dataclass(frozen=True)
class FleetJob:
    """One case in one motion mode: ``runs`` runs of ``steps`` ticks. Picklable."""

    key: tuple[str, str]  # (case, mode)
    preset: str
    overrides: tuple[str, ...]
    seed: int
    runs: int
    steps: int
    positions: bool = False  # also keep every robot's position and status at every step

    @property
    def cost(self) -> float:
        """Estimated CPU seconds of one run (:func:`~shoal.studies.cost.run_cost`)."""
        return run_cost(load(self.preset, list(self.overrides)), self.steps)


def fleet_job(case: Case, mode: str, runs: int, duration: float, positions: bool = False) -> FleetJob:
    """The job of ``case`` in ``mode`` ("kinematic"/"physics", or "" for the preset's own
    motion) for ``duration`` seconds of simulated time."""
    extra = MODE_OVERRIDES[mode] if mode else ()
    scenario = case.scenario(extra)
    dt = scenario.controller.dt
    steps = int(round(duration / dt))
    if steps < 1 or abs(steps * dt - duration) > 1e-9 * max(1.0, duration):
        raise ValueError(f"duration {duration} s is not a whole number of ticks of {dt} s")
    return FleetJob((case.name, mode), case.preset, (*case.overrides, *extra), scenario.sim.seed, runs, steps,
                    positions)


@dataclass
class FleetBatch:
    """Per-step metrics of runs ``first_run …`` (step axis first; index 0 = initial state)."""

    seed: int
    first_run: int
    dt: float
    robots: int
    robot_radius: float
    layer_x: np.ndarray  # (L,)
    t: np.ndarray  # (K+1,)
    com: np.ndarray  # (K+1, R) CoM fitness [4.17]
    collided: np.ndarray  # (K+1, R) overlap beyond the contact tolerance
    stalled: np.ndarray  # (K+1, R) operational robots stalled (``fleet.STALL_SPEED``, ``STALL_STEPS``)
    layers: np.ndarray  # (K+1, R) layers with x below the CoM
    x: np.ndarray | None = None  # (K+1, R, N, 2) when the job asked for positions
    status: np.ndarray | None = None  # (K+1, R, N)

    @property
    def runs(self) -> int:
        return self.com.shape[1]

    @property
    def run_index(self) -> np.ndarray:
        return np.arange(self.first_run, self.first_run + self.runs)

    @property
    def operational(self) -> np.ndarray:
        return self.robots - self.collided

    def head(self, runs: int) -> "FleetBatch":
        """The first ``runs`` runs of this batch."""
        cut = lambda a: a[:, :runs]  # noqa: E731
        return FleetBatch(
            seed=self.seed, first_run=self.first_run, dt=self.dt, robots=self.robots, robot_radius=self.robot_radius,
            layer_x=self.layer_x, t=self.t, com=cut(self.com), collided=cut(self.collided), stalled=cut(self.stalled),
            layers=cut(self.layers), x=None if self.x is None else cut(self.x),
            status=None if self.status is None else cut(self.status),
        )

    def median_run(self) -> int:
        """Position (0-based, in this batch) of the run with the median final CoM fitness;
        with an even number of runs the lower of the two middle ones (ties: lower run)."""
        order = np.argsort(self.com[-1], kind="stable")
        return int(order[(self.runs - 1) // 2])


def simulate_fleet(job: FleetJob, first_run: int, runs: int) -> FleetBatch:
    """Runs ``first_run … first_run + runs − 1`` of ``job`` (``simulate`` for ``run_jobs``)."""
    scenario = load(job.preset, list(job.overrides))
    fleet = build_fleet(scenario, runs=runs, seed=job.seed, first_run=first_run)
    K = job.steps
    t = np.empty(K + 1)
    com = np.empty((K + 1, runs))
    collided = np.empty((K + 1, runs), dtype=np.int64)
    stalled = np.empty((K + 1, runs), dtype=np.int64)
    layers = np.empty((K + 1, runs), dtype=np.int64)
    x = np.empty((K + 1, runs, fleet.robots, 2)) if job.positions else None
    status = np.empty((K + 1, runs, fleet.robots), dtype=np.int8) if job.positions else None
    info = fleet.info()
    for k in range(K + 1):
        if k:
            info = fleet.step()
        t[k], com[k], collided[k], layers[k] = info.t, info.com_fitness, info.collided, info.layers_passed
        stalled[k] = info.stalled
        if x is not None and status is not None:
            x[k], status[k] = fleet.state.x, fleet.state.status
    return FleetBatch(
        seed=job.seed, first_run=first_run, dt=fleet.dt, robots=fleet.robots,
        robot_radius=fleet.params.robot_radius, layer_x=np.asarray(fleet.world.layer_x, dtype=float).copy(),
        t=t, com=com, collided=collided, stalled=stalled, layers=layers, x=x, status=status,
    )


def merge(parts: Sequence[FleetBatch]) -> FleetBatch:
    """Glue chunks of consecutive runs (in any order) into one batch (``merge`` for ``run_jobs``)."""
    parts = sorted(parts, key=lambda p: p.first_run)
    first = parts[0]
    expected = first.first_run
    for p in parts:
        if p.first_run != expected or p.seed != first.seed or len(p.t) != len(first.t):
            raise ValueError("chunks must be consecutive runs of the same seed and length")
        expected += p.runs

    def cat(name: str) -> Any:
        arrays = [getattr(p, name) for p in parts]
        return None if arrays[0] is None else np.concatenate(arrays, axis=1)

    return FleetBatch(
        seed=first.seed, first_run=first.first_run, dt=first.dt, robots=first.robots,
        robot_radius=first.robot_radius, layer_x=first.layer_x, t=first.t,
        com=cat("com"), collided=cat("collided"), stalled=cat("stalled"), layers=cat("layers"), x=cat("x"),
        status=cat("status"),
    )


# ---------------------------------------------------------------------- statistics and rows
RUNS_COLUMNS = ("case", "run", "seed", "mode", "com_fitness_final", "layers_passed", "collided", "operational",
                "stalled")
SERIES_COLUMNS = ("case", "mode", "t", "com_fitness_median", "com_fitness_p05", "com_fitness_p95",
                  "collided_mean", "layers_passed_median", "stalled_mean")
CONTACTS = (f"A collision is an overlap deeper than the contact tolerance (`robot.contact_tolerance`, "
            f"{Robot().contact_tolerance:g} m, a float-noise allowance; a shallower touch stops the robot without "
            "disabling it), and both robots of a robot-robot collision are disabled. A robot "
            f"is stalled while it has moved slower than {STALL_SPEED:g} m/s for {STALL_STEPS} ticks in a row "
            "(counted among the operational robots, ours).")


def runs_rows(case: str, mode: str, b: FleetBatch) -> list[list[str]]:
    return [
        [case, str(i), str(b.seed), mode, num(b.com[-1, j]), str(int(b.layers[-1, j])), str(int(b.collided[-1, j])),
         str(int(b.operational[-1, j])), str(int(b.stalled[-1, j]))]
        for j, i in enumerate(b.run_index)
    ]


def series_rows(case: str, mode: str, b: FleetBatch) -> list[list[str]]:
    med, p05, p95 = band(b.com)
    coll, stall = b.collided.mean(axis=1), b.stalled.mean(axis=1)
    lay = np.median(b.layers, axis=1)
    return [
        [case, mode, num(b.t[k]), num(med[k]), num(p05[k]), num(p95[k]), num(coll[k]), num(lay[k]), num(stall[k])]
        for k in range(len(b.t))
    ]


def at_time(b: FleetBatch, t: float) -> int:
    """Step index of time ``t`` (the last step if ``t`` is beyond the run)."""
    return int(min(len(b.t) - 1, max(0, round(t / b.dt))))


@dataclass(frozen=True)
class Outcome:
    """End-of-run statistics of one case in one mode."""

    runs: int
    com_median: float
    layers_median: float
    collided_median_run: int
    operational_median_run: int
    collided_mean: float
    runs_with_collision: int
    collided_total: int
    operational_median: float
    stalled_median_run: int
    stalled_mean: float

    def as_dict(self) -> dict[str, Any]:
        return {k: (round(v, 3) if isinstance(v, float) else v) for k, v in self.__dict__.items()}


def outcome(b: FleetBatch) -> Outcome:
    m = b.median_run()
    end = b.collided[-1]
    return Outcome(
        runs=b.runs, com_median=float(np.median(b.com[-1])), layers_median=float(np.median(b.layers[-1])),
        collided_median_run=int(end[m]), operational_median_run=int(b.robots - end[m]),
        collided_mean=float(end.mean()), runs_with_collision=int((end > 0).sum()), collided_total=int(end.sum()),
        operational_median=float(np.median(b.robots - end)),
        stalled_median_run=int(b.stalled[-1, m]), stalled_mean=float(b.stalled[-1].mean()),
    )


# ---------------------------------------------------------------------- figures
def draw_layers(ax: Any, layer_x: np.ndarray) -> None:
    """Dotted horizontal lines at the layers' x positions (as in the thesis Fig. 4-6),
    named on a right-hand axis. Call after the y limits are set."""
    for lx in layer_x:
        ax.axhline(lx, color="0.45", ls=":", lw=0.9, zorder=0)
    right = ax.twinx()
    right.set_ylim(ax.get_ylim())
    right.set_yticks(list(layer_x), [f"layer {i + 1}" for i in range(len(layer_x))], fontsize=7, color="0.35")
    right.tick_params(length=0)
