"""Headless seeded runs: the engine side of ``shoal run``."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any, Callable

from .atomic import atomic_output_dir
from .contract import Engine
from .recorder import metric_table, trajectory_header, trajectory_rows, write_metrics, write_trajectory


def run_to_dir(
    sim: Engine,
    steps: int,
    out: Path | str,
    meta: dict[str, Any],
    on_step: Callable[[int], None] | None = None,
) -> Path:
    """Advance ``sim`` for ``steps`` ticks and stream ``trajectories.csv`` and ``metrics.csv``
    (step 0 = the initial state) plus ``run.json`` = ``meta``, into ``out``, atomically."""
    with atomic_output_dir(out) as tmp:
        (tmp / "run.json").write_text(json.dumps(meta, indent=2), encoding="utf-8")
        with open(tmp / "trajectories.csv", "w", encoding="utf-8", newline="") as traj, open(
            tmp / "metrics.csv", "w", encoding="utf-8", newline=""
        ) as metrics:
            traj.write(trajectory_header(sim.state.x.shape[-1]) + "\n")
            write_trajectory(traj, trajectory_rows(sim.state, sim.t))
            columns = type(sim).COLUMNS
            write_metrics(metrics, metric_table(sim.state, sim.info(), sim.t), columns, header=True)
            for k in range(steps):
                info = sim.step()
                write_trajectory(traj, trajectory_rows(sim.state, sim.t))
                write_metrics(metrics, metric_table(sim.state, info, sim.t), columns)
                if on_step is not None:
                    on_step(k)
    return Path(out)
