"""Per-step records of a swarm as table rows (trajectories.csv, metrics.csv)."""

from __future__ import annotations

from typing import IO

import numpy as np

from .sim import StepInfo, SwarmState

TRAJECTORY_COLUMNS = ("run", "step", "t", "robot", "x", "y", "heading", "vx", "vy", "status")
METRIC_COLUMNS = ("run", "step", "t", "best_fitness", "max_speed", "mean_speed", "max_component", "omega", "c_hat")
_TRAJ_FMT = ["%d", "%d", "%.6f", "%d", "%.9g", "%.9g", "%.9g", "%.9g", "%.9g", "%d"]
_METRIC_FMT = ["%d", "%d", "%.6f", "%.9g", "%.9g", "%.9g", "%.9g", "%.9g", "%.9g"]


def _component(a: np.ndarray, j: int) -> np.ndarray:
    return a[..., j] if a.shape[-1] > j else np.zeros(a.shape[:-1])


def _per_run(value: np.ndarray | float, R: int) -> np.ndarray:
    """A scalar or per-robot ``(R, N)`` coefficient as one value per run (mean over robots)."""
    v = np.asarray(value, dtype=float)
    return np.full(R, float(v)) if v.ndim == 0 else v.reshape(R, -1).mean(axis=1)


def trajectory_rows(state: SwarmState, t: float) -> np.ndarray:
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


def metric_rows(state: SwarmState, info: StepInfo | None, t: float) -> np.ndarray:
    """One row per run at the state's step, columns :data:`METRIC_COLUMNS`."""
    R = state.x.shape[0]
    speed = np.linalg.norm(state.u, axis=-1)
    omega = np.nan if info is None else _per_run(info.omega, R)
    c_hat = np.nan if info is None else _per_run(np.sum(info.c, axis=0), R)
    cols = [
        np.arange(R), np.full(R, state.k), np.full(R, t), state.f_yg, speed.max(axis=1), speed.mean(axis=1),
        np.abs(state.u).max(axis=(1, 2)), np.broadcast_to(omega, (R,)), np.broadcast_to(c_hat, (R,)),
    ]
    return np.stack([np.asarray(c, dtype=float) for c in cols], axis=1)


def trajectory_header(d: int) -> str:
    cols = list(TRAJECTORY_COLUMNS) + (["z", "vz"] if d > 2 else [])
    return ",".join(cols)


def write_trajectory(fh: IO[str], rows: np.ndarray) -> None:
    fmt = _TRAJ_FMT + ["%.9g"] * (rows.shape[1] - len(_TRAJ_FMT))
    np.savetxt(fh, rows, fmt=fmt, delimiter=",")


def write_metrics(fh: IO[str], rows: np.ndarray) -> None:
    np.savetxt(fh, rows, fmt=_METRIC_FMT, delimiter=",")
