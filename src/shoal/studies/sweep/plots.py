"""Pictures of a sweep: the median over runs of each outcome across the grid.

One PNG per outcome, ``median_<name>.png``: a line over a 1-D grid, a heat map over the
first two axes of a 2-D grid. A grid of more axes gets one heat-map panel per combination
of the other axes' values (at most :data:`MAX_FACETS` panels; beyond that the pictures are
skipped and ``medians.csv`` is the record). A first-passage median of +inf (fewer than
half the runs got there) is drawn as a grey "n.c." cell. Outcomes whose median is the same
in every cell are not drawn.
"""

from __future__ import annotations

import itertools
import math
from pathlib import Path
from typing import Any, Sequence

import numpy as np

from ..experiments.output import new_figure, save
from .grid import Axis

MAX_FACETS = 12


def _numeric(axis: Axis) -> bool:
    return all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in axis.values)


def _runs(n: int) -> str:
    return f"{n} run" if n == 1 else f"{n} runs"


def varies(z: np.ndarray) -> bool:
    """Not the same median (or the same missing pattern) in every cell."""
    z = np.asarray(z, dtype=float).ravel()
    known = z[~np.isnan(z)]
    return known.size > 0 and not np.all(known == known[0])


def line_figure(axis: Axis, name: str, z: np.ndarray, runs: int, *,
                band: tuple[np.ndarray, np.ndarray] | None = None, title: str | None = None) -> Any:
    """The median ``z`` of outcome ``name`` along one axis (a grey "n.c." where it is +inf);
    ``band = (lo, hi)`` shades an interval round it where both ends are finite."""
    fig, (ax,) = new_figure(1, 1, 5.0, 3.4)
    x = np.asarray(axis.values, dtype=float) if _numeric(axis) else np.arange(len(axis.values), dtype=float)
    finite = np.isfinite(z)
    if band is not None:
        lo, hi = (np.asarray(b, dtype=float) for b in band)
        ok = np.isfinite(lo) & np.isfinite(hi)
        ax.fill_between(x[ok], lo[ok], hi[ok], color="tab:blue", alpha=0.2, linewidth=0, label="95 % interval")
    ax.plot(x[finite], z[finite], marker="o", color="tab:blue")
    for xi in x[np.isinf(z)]:
        ax.annotate("n.c.", (xi, 1.0), xycoords=("data", "axes fraction"), ha="center", va="top", color="grey")
    if not _numeric(axis):
        ax.set_xticks(x, axis.labels)
    ax.set_xlabel(axis.key)
    ax.set_ylabel(f"median {name}")
    ax.set_title(title or f"median {name} over {_runs(runs)} per cell", fontsize=10)
    ax.grid(alpha=0.3)
    return fig


def heat_figure(axes: Sequence[Axis], name: str, z: np.ndarray, runs: int, *, title: str | None = None) -> Any:
    """The median ``z`` of outcome ``name`` over the first two axes, one panel per
    combination of the others; a cell of +inf is a grey "n.c.", a NaN cell is left blank."""
    ax_x, ax_y, rest = axes[0], axes[1], list(axes[2:])
    facets = list(itertools.product(*(range(len(a.values)) for a in rest)))
    ncols = min(len(facets), 4)
    nrows = math.ceil(len(facets) / ncols)
    fig, panels = new_figure(nrows, ncols, max(3.2, 0.7 * len(ax_x.values) + 1.6),
                             max(2.8, 0.45 * len(ax_y.values) + 1.4))
    finite = z[np.isfinite(z)]
    vmin, vmax = (float(finite.min()), float(finite.max())) if finite.size else (0.0, 1.0)
    im = None
    for ax, idx in zip(panels, facets):
        zz = z[(slice(None), slice(None), *idx)].T  # type: ignore[arg-type]  # rows: second axis, columns: first axis
        im = ax.imshow(np.where(np.isfinite(zz), zz, np.nan), origin="lower", cmap="viridis", vmin=vmin,
                       vmax=vmax, aspect="auto")
        nc = np.isinf(zz)
        ax.imshow(np.where(nc, 1.0, np.nan), origin="lower", cmap="Greys", vmin=0, vmax=2, aspect="auto")
        for (i, k), v in np.ndenumerate(zz):
            if not np.isnan(v):
                light = np.isinf(v) or (v - vmin) > 0.6 * (vmax - vmin)  # viridis turns yellow
                ax.text(k, i, "n.c." if np.isinf(v) else f"{v:.3g}", ha="center", va="center", fontsize=7,
                        color="black" if light else "white")
        ax.set_xticks(range(len(ax_x.values)), ax_x.labels)
        ax.set_yticks(range(len(ax_y.values)), ax_y.labels)
        ax.set_xlabel(ax_x.key)
        ax.set_ylabel(ax_y.key)
        if rest:
            ax.set_title(", ".join(f"{a.key}={a.labels[j]}" for a, j in zip(rest, idx)), fontsize=8)
    for ax in panels[len(facets):]:
        ax.set_visible(False)
    if im is not None:
        fig.colorbar(im, ax=list(panels[: len(facets)]), shrink=0.8, label=f"median {name}")
    fig.suptitle(title or f"median {name} over {_runs(runs)} per cell", fontsize=10)
    return fig


def plot_medians(out: Path, axes: Sequence[Axis], medians: dict[str, np.ndarray], runs: int) -> tuple[list[str], str]:
    """Write ``median_<name>.png`` for every outcome that varies; ``medians[name]`` has the
    grid's shape (one dimension per axis). Returns the file names and a note."""
    facets = math.prod(len(a.values) for a in axes[2:])
    if len(axes) > 2 and facets > MAX_FACETS:
        return [], (f"no pictures: {facets} combinations of the axes after the first two exceed {MAX_FACETS} "
                    "panels; see medians.csv")
    written, flat = [], []
    for name, z in medians.items():
        if not varies(z):
            flat.append(name)
            continue
        fname = f"median_{name}.png"
        fig = line_figure(axes[0], name, z, runs) if len(axes) == 1 else heat_figure(axes, name, z, runs)
        save(fig, out / fname)
        written.append(fname)
    note = "not drawn (same median in every cell): " + ", ".join(flat) if flat else ""
    return written, note
