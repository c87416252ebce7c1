"""Metric columns as data: each scene kind declares the columns its ``Info.columns()`` gives
(name, unit, dtype, description) once, beside the code that computes them. The recorder
formats ``metrics.csv`` from them, the sweeps know which outcomes are whole numbers, and the
docs' data dictionary lists them.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Iterable, Literal

Dtype = Literal["int", "float"]


@dataclass(frozen=True)
class Column:
    """One metric column: one value per run at each step."""

    name: str
    unit: str  # "" for a pure number, "count", "m", "m/s", ...
    dtype: Dtype  # how it is written: "int" as %d, "float" as %.9g
    description: str


Schema = tuple[Column, ...]

# The columns every kind's metric table starts with (``recorder.metric_table``); ``best_fitness``
# only for a kind that optimises something.
RUN = Column("run", "", "int", "run index i (run i draws from child i of SeedSequence(seed))")
STEP = Column("step", "", "int", "control ticks since the start (0 = the initial state)")
T = Column("t", "s", "float", "time of the step, step × Δt (written to 6 decimals)")
BEST_FITNESS = Column("best_fitness", "objective", "float",
                      "the best objective value the run has found so far (f(y_g); its unit is the objective's)")
MAX_SPEED = Column("max_speed", "m/s", "float", "highest robot speed |u| in the run")
MEAN_SPEED = Column("mean_speed", "m/s", "float", "mean robot speed |u| over the run's robots")


def common_columns(optimises: bool) -> Schema:
    """The columns before a kind's own: run, step, t, [best_fitness,] max_speed, mean_speed."""
    return (RUN, STEP, T, *((BEST_FITNESS,) if optimises else ()), MAX_SPEED, MEAN_SPEED)


def formats(names: Iterable[str], schema: Schema) -> list[str]:
    """``np.savetxt`` formats of ``names``: ``t`` to 6 decimals, an int column as ``%d``, any
    other (or one the schema does not hold) as ``%.9g``."""
    dtypes = {c.name: c.dtype for c in schema}
    return ["%.6f" if n == "t" else ("%d" if dtypes.get(n) == "int" else "%.9g") for n in names]


def integer_names(schema: Iterable[Column]) -> frozenset[str]:
    return frozenset(c.name for c in schema if c.dtype == "int")
