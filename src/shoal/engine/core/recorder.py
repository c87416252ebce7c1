"""Per-step records of any engine as table rows (trajectories.csv, metrics.csv)."""

from __future__ import annotations

from typing import IO

import numpy as np

from .contract import Info, State
from .schema import Column, Schema, common_columns, formats

TRAJECTORY_SCHEMA: Schema = (
    Column("run", "", "int", "run index"),
    Column("step", "", "int", "control ticks since the start (0 = the initial state)"),
    Column("t", "s", "float", "time of the step"),
    Column("robot", "", "int", "robot index"),
    Column("x", "m", "float", "position, first axis"),
    Column("y", "m", "float", "position, second axis (0 in one dimension)"),
    Column("heading", "rad", "float", "direction the robot faces (of its motion, for an omnidirectional robot)"),
    Column("vx", "m/s", "float", "velocity, first axis (m per tick for standard PSO)"),
    Column("vy", "m/s", "float", "velocity, second axis"),
    Column("status", "", "int", "0 active; 1 disabled by a collision (a fleet)"),
    Column("z", "m", "float", "position, third axis (only when sim.d ≥ 3)"),
    Column("vz", "m/s", "float", "velocity, third axis (only when sim.d ≥ 3)"),
)
TRAJECTORY_COLUMNS = tuple(c.name for c in TRAJECTORY_SCHEMA[:10])
_TRAJ_FMT = ["%d", "%d", "%.6f", "%d", "%.9g", "%.9g", "%.9g", "%.9g", "%.9g", "%d"]


def _component(a: np.ndarray, j: int) -> np.ndarray:
    return a[..., j] if a.shape[-1] > j else np.zeros(a.shape[:-1])


def trajectory_rows(state: State, t: float) -> np.ndarray:
    """One row per (run, robot) at the state's step, columns :data:`TRAJECTORY_COLUMNS`
    (a 3rd dimension, if any, is appended as ``z, vz``)."""
    R, N, d = state.x.shape
    run, robot = np.meshgrid(np.arange(R), np.arange(N), indexing="ij")
    cols = [
        run, np.full((R, N), state.k), np.full((R, N), t), robot,
        _component(state.x, 0), _component(state.x, 1), state.heading,
        _component(state.u, 0), _component(state.u, 1), state.status,
    ]
    if d > 2:
        cols += [state.x[..., 2], state.u[..., 2]]
    return np.stack([np.asarray(c, dtype=float).ravel() for c in cols], axis=1) + 0.0  # no "-0"


def metric_table(state: State, info: Info, t: float) -> dict[str, np.ndarray]:
    """Per-run metrics at the state's step, one array (R,) per column: the common ones (run, step,
    t, best fitness so far, highest and mean speed), then the kind's own (:meth:`Info.columns`).
    A kind that optimises nothing has no ``best_fitness`` in its state, nor in its table."""
    R = state.x.shape[0]
    speed = np.linalg.norm(state.u, axis=-1)
    best = getattr(state, "best_fitness", None)
    common = {"run": np.arange(R), "step": np.full(R, state.k), "t": np.full(R, t),
              **({"best_fitness": best} if best is not None else {}),
              "max_speed": speed.max(axis=1), "mean_speed": speed.mean(axis=1)}
    return common | info.columns()


def trajectory_header(d: int) -> str:
    cols = list(TRAJECTORY_COLUMNS) + (["z", "vz"] if d > 2 else [])
    return ",".join(cols)


def write_trajectory(fh: IO[str], rows: np.ndarray) -> None:
    fmt = _TRAJ_FMT + ["%.9g"] * (rows.shape[1] - len(_TRAJ_FMT))
    np.savetxt(fh, rows, fmt=fmt, delimiter=",")


def write_metrics(fh: IO[str], table: dict[str, np.ndarray], columns: Schema, header: bool = False) -> None:
    """Rows of ``table`` as CSV, each column formatted by its dtype in ``columns`` (the kind's own
    columns; the common ones are known here)."""
    if header:
        fh.write(",".join(table) + "\n")
    rows = np.stack([np.asarray(v, dtype=float) for v in table.values()], axis=1)
    np.savetxt(fh, rows, fmt=formats(table, common_columns(True) + tuple(columns)), delimiter=",")
