"""The data dictionary: every output file's columns with their units, written from the schemas
the scene kinds declare (so it cannot drift from what the files hold).

    SHOAL_PLUGINS=off python -m shoal.api.dictionary > docs/data-dictionary.md
"""

from __future__ import annotations

from shoal.engine.core.recorder import TRAJECTORY_SCHEMA
from shoal.engine.core.schema import Schema, common_columns
from shoal.presets.kinds import KINDS
from shoal.studies.sweep.outcomes import SWEEP_COLUMNS

UNITS = {"": "–", "objective": "of f", "unit": "thesis units", "count": "count"}


def _table(columns: Schema) -> list[str]:
    rows = ["| column | unit | type | meaning |", "|---|---|---|---|"]
    rows += [f"| `{c.name}` | {UNITS.get(c.unit, c.unit)} | {c.dtype} | {c.description.replace('|', chr(92) + '|')} |"
             for c in columns]
    return rows


def data_dictionary() -> str:
    """The data dictionary as Markdown."""
    out = [
        "# Data dictionary",
        "",
        "Every file Shoal writes, column by column. Generated from the scene kinds' schemas "
        "(`SHOAL_PLUGINS=off python -m shoal.api.dictionary > docs/data-dictionary.md`; a test checks it is "
        "current; an installed plug-in's kind adds its own section). "
        "Units: m, s, rad; *of f* is the objective's own unit; *thesis units* are Mai's lengths on a "
        "100-wide area; – is a pure number.",
        "",
        "## `shoal run`: `trajectories.csv`",
        "",
        "One row per run, step and robot; `z` and `vz` follow `status` when `sim.d` ≥ 3.",
        "",
        *_table(TRAJECTORY_SCHEMA),
        "",
        "## `shoal run`: `metrics.csv`",
        "",
        "One row per run and step: the common columns, then the scene kind's own. "
        "`best_fitness` only for a kind that optimises something.",
        "",
        *_table(common_columns(True)),
        "",
    ]
    for kind in KINDS.values():
        what = f"`[{kind.section}]`" if kind.section else "no kind section"
        out += [f"### {kind.label} (`{kind.name}`, {what})", ""]
        out += ["Optimises nothing: no `best_fitness`.", ""] if not kind.optimises else []
        out += [*_table(kind.columns[len(common_columns(kind.optimises)):]), ""]
    out += [
        "## `shoal run`: `run.json`",
        "",
        "| key | meaning |",
        "|---|---|",
        "| `shoal_version` | the version that wrote it |",
        "| `preset` | the whole validated preset, every field (a section it does not set, such as `[world]` in a "
        "Chapter 3 scene, is left out) |",
        "| `seed`, `runs`, `steps` | as run |",
        "",
        "## `shoal sweep`: `results.csv` and `cells/cell-NNNNN.csv`",
        "",
        "One row per cell and run: the grid's fields (their values as given), `run`, `seed` (the cell's), "
        "then the run's outcomes: its last metric row (as in `metrics.csv`, without `run`; `step` and `t` "
        "say where it ended) and these:",
        "",
        *_table(SWEEP_COLUMNS),
        "",
        "Values have 12 significant digits; a missing one is empty. `shoal.sweep(...)` returns the same "
        "columns at full precision.",
        "",
        "## `shoal sweep`: `medians.csv`",
        "",
        "One row per cell: the grid's fields, `runs`, then the median over runs of every outcome but "
        "`run`, `seed`, `step` and `t` (a first-passage time that never happened counts as +inf).",
        "",
        "## `shoal sweep`: `sweep.json`",
        "",
        "The sweep's identity (preset, grid, runs, seed, steps: a rerun with the same resumes), its cells "
        "and, when finished, the files written and the last call's timing.",
        "",
    ]
    return "\n".join(out)


if __name__ == "__main__":
    print(data_dictionary(), end="")
