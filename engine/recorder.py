"""Per-step records of a swarm or fleet as table rows (trajectories.csv, metrics.csv)."""

from __future__ import annotations

from typing import IO, Any

import numpy as np

from .sim import SwarmState

TRAJECTORY_COLUMNS = ("run", "step", "t", "robot", "x", "y", "heading", "vx", "vy", "status")
_TRAJ_FMT = ["%d", "%d", "%.6f", "%d", "%.9g", "%.9g", "%.9g", "%.9g", "%.9g", "%d"]


def _component(a: np.ndarray, j: int) -> np.ndarray:
    return a[..., j] if a.shape[-1] > j else np.zeros(a.shape[:-1])


def _per_run(value: np.ndarray | float, R: int) -> np.ndarray:
    """A scalar or per-robot ``(R, N)`` coefficient as one value per run (mean over robots)."""
    v = np.asarray(value, dtype=float)
    return np.full(R, float(v)) if v.ndim == 0 else v.reshape(R, -1).mean(axis=1)


def trajectory_rows(state: SwarmState | Any, t: float) -> np.ndarray:
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


def metric_table(state: Any, info: Any, t: float) -> dict[str, np.ndarray]:
    """Per-run metrics at the state's step, one array (R,) per column.

    Common: best fitness and speeds. A Chapter 3 swarm adds the largest component and the
    coefficients in force; a fleet (``FleetInfo``) adds CoM fitness [4.17], collided
    (overlap beyond the contact tolerance), stalled and operational counts and layers passed; an acoustic swarm (``SonarInfo``) adds the CoM,
    the source, |CoM − x_src|, convergence (flag and first step, −1 if none), the fraction
    of robots inside the escort ring, the mean robot–source distance and contacts. An SLO
    swarm (``SLOInfo``) adds every column of :meth:`SLOInfo.columns` (localisation errors,
    pair distances, dead-reckoning share, first generation meeting the quality threshold).
    """
    R = state.x.shape[0]
    speed = np.linalg.norm(state.u, axis=-1)
    cols: dict[str, np.ndarray] = {
        "run": np.arange(R), "step": np.full(R, state.k), "t": np.full(R, t), "best_fitness": state.f_yg,
        "max_speed": speed.max(axis=1), "mean_speed": speed.mean(axis=1),
    }
    if hasattr(info, "e_abs"):
        slo = info.columns()
        cols["generation_best"] = slo.pop("best_fitness")  # min_i f(x_i(t)); best_fitness is the best so far
        cols.update(slo)
    elif hasattr(info, "com_dist"):
        cols.update(com_x=info.com[:, 0], com_y=info.com[:, 1], source_x=info.source[:, 0],
                    source_y=info.source[:, 1], com_dist=info.com_dist, converged=info.converged,
                    steps_to_converge=info.steps_to_converge, frac_inside_ring=info.frac_inside_ring,
                    mean_dist_to_source=info.mean_dist_to_source, contacts=info.contacts)
    elif hasattr(info, "com_fitness"):
        cols.update(com_fitness=info.com_fitness, collided=info.collided, stalled=info.stalled,
                    operational=info.operational, layers_passed=info.layers_passed)
    else:
        cols.update(
            max_component=np.abs(state.u).max(axis=(1, 2)),
            omega=np.full(R, np.nan) if info is None else _per_run(info.omega, R),
            c_hat=np.full(R, np.nan) if info is None else _per_run(np.sum(info.c, axis=0), R),
        )
    return cols


def trajectory_header(d: int) -> str:
    cols = list(TRAJECTORY_COLUMNS) + (["z", "vz"] if d > 2 else [])
    return ",".join(cols)


def write_trajectory(fh: IO[str], rows: np.ndarray) -> None:
    fmt = _TRAJ_FMT + ["%.9g"] * (rows.shape[1] - len(_TRAJ_FMT))
    np.savetxt(fh, rows, fmt=fmt, delimiter=",")


_INT_COLUMNS = {"run", "step", "collided", "stalled", "operational", "layers_passed", "converged", "steps_to_converge", "contacts"}


def write_metrics(fh: IO[str], table: dict[str, np.ndarray], header: bool = False) -> None:
    if header:
        fh.write(",".join(table) + "\n")
    rows = np.stack([np.asarray(v, dtype=float) for v in table.values()], axis=1)
    fmt = ["%d" if k in _INT_COLUMNS else ("%.6f" if k == "t" else "%.9g") for k in table]
    np.savetxt(fh, rows, fmt=fmt, delimiter=",")
