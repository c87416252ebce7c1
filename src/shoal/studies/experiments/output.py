"""Writing reproduction outputs: CSV files, checks, number formatting, shared plot pieces.

Used by every target (Chapter 3 and Chapters 4–5) so that their files look alike.
"""

from __future__ import annotations

import csv
import io
from pathlib import Path
from typing import Any, Sequence

import numpy as np

from shoal.engine.core.atomic import atomic_write_bytes

from .verdict import FAILS, HOLDS, UNDECIDED, Verdict


def num(v: float) -> str:
    """A number for a CSV cell: 12 significant digits, ``-0`` written as ``0``."""
    return f"{float(v) + 0.0:.12g}"  # + 0.0 turns -0.0 into 0.0


def write_csv(path: Path, header: Sequence[str], rows: Sequence[Sequence[str]]) -> None:
    with open(path, "w", encoding="utf-8", newline="") as fh:
        w = csv.writer(fh, lineterminator="\n")
        w.writerow(header)
        w.writerows(rows)


def check(name: str, thesis: Any, measured: Any, passed: bool, verdict: Verdict) -> dict[str, Any]:
    """One entry of ``summary.json`` → ``checks``: a thesis claim beside what was measured,
    judged by the thesis' own metric. ``passed`` is the point estimate; ``verdict`` says
    whether the claim holds, fails or is undecided at this run count
    (:mod:`.verdict`), and ``runs`` how many runs decided it (None: exact)."""
    if verdict.outcome == HOLDS and not passed or verdict.outcome == FAILS and passed:
        raise ValueError(f"check {name!r}: verdict {verdict.outcome!r} contradicts the point estimate")
    return {"name": name, "thesis": thesis, "measured": measured, "pass": bool(passed), "verdict": verdict.outcome,
            "runs": verdict.runs}


def verdict_of(c: dict[str, Any]) -> str:
    """A check's verdict (a summary written before verdicts existed: its point estimate)."""
    return c.get("verdict") or (HOLDS if c.get("pass") else FAILS)


def verdict_cell(c: dict[str, Any]) -> str:
    """The "holds" cell of a check: yes, **no** or undecided, with the runs that decided it."""
    v = verdict_of(c)
    word = {HOLDS: "yes", FAILS: "**no**", UNDECIDED: "undecided"}[v]
    runs = c.get("runs")
    return f"{word} ({'exact' if runs is None else f'{runs} runs'})" if "verdict" in c else word


def info(name: str, thesis: Any, measured: Any, holds: bool) -> dict[str, Any]:
    """One entry of ``summary.json`` → ``information``: a stricter or other measure of a
    claim than the thesis' own (e.g. over every run, not the median one), reported beside
    the checks but not counted in them."""
    return {"name": name, "thesis": thesis, "measured": measured, "holds": bool(holds)}


def r3(v: float) -> float:
    return round(float(v), 3)


def cell(v: Any) -> str:
    """A value for a markdown table cell (pipes escaped, one line)."""
    return str(v).replace("|", "\\|").replace("\n", " ")


def checks_table(checks: Sequence[dict[str, Any]]) -> str:
    """The checks as a markdown table (for a target's README.md)."""
    rows = [f"| {cell(c['name'])} | {cell(c['thesis'])} | {cell(c['measured'])} | {verdict_cell(c)} |"
            for c in checks]
    return "| check | thesis | measured | holds |\n|---|---|---|---|\n" + "\n".join(rows)


def information_table(entries: Sequence[dict[str, Any]]) -> str:
    """The ``information`` entries as a markdown table (not counted as checks); "" if none."""
    if not entries:
        return ""
    rows = [f"| {cell(c['name'])} | {cell(c['thesis'])} | {cell(c['measured'])} | {'yes' if c['holds'] else 'no'} |"
            for c in entries]
    return ("Also measured (information, not counted as checks):\n\n| measure | thesis | measured | holds |\n"
            "|---|---|---|---|\n" + "\n".join(rows))


def percentile_band(values: np.ndarray, axis: int = 1) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Median, 5th and 95th percentiles of ``values`` over ``axis`` (the runs)."""
    med = np.median(values, axis=axis)
    p05, p95 = np.percentile(values, [5, 95], axis=axis)
    return med, p05, p95


def new_figure(nrows: int, ncols: int, width: float, height: float) -> tuple[Any, np.ndarray]:
    """A matplotlib figure (Agg canvas, no pyplot, no display needed) and its axes, flattened."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width * ncols, height * nrows), layout="constrained")
    axes = np.atleast_1d(fig.subplots(nrows, ncols)).ravel()
    return fig, axes


def save(fig: Any, path: Path, dpi: int = 120) -> None:
    """Write the figure as a PNG completely or not at all (a full disk leaves no empty or cut
    picture: drawn in memory, then written beside ``path`` and renamed)."""
    atomic_write_bytes(path, png_bytes(fig, dpi))


def png_bytes(fig: Any, dpi: int = 120) -> bytes:
    """The figure as PNG bytes, as :func:`save` would write them (nothing touches the disk)."""
    buf = io.BytesIO()
    fig.savefig(buf, dpi=dpi, format="png", metadata={"Software": None})
    return buf.getvalue()
