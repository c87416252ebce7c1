"""Search-space bounds of a benchmark scene (ours, off by default; docs/readings.md, "Search-space
bounds"): after each move [3.10]/[2.2], a component of a position outside ``[low, high]`` is put
back by one of three rules, applied component by component:

* ``clip``: the position is clipped to the bound; the velocity is kept;
* ``reflect``: the position is mirrored back inside (folded as often as it takes) and the velocity
  component reversed for every odd number of folds;
* ``absorb``: the position is clipped to the bound and the velocity component set to 0;
* ``periodic``: the box wraps round (a torus): a robot that leaves by one side comes back in by
  the other as far in as it went out; the velocity is kept (pyswarms' default rule).

A component inside its bounds keeps its bits."""

from __future__ import annotations

from typing import Literal

import numpy as np

Boundary = Literal["clip", "reflect", "absorb", "periodic"]
BOUNDARIES: tuple[Boundary, ...] = ("clip", "reflect", "absorb", "periodic")


def confine(x: np.ndarray, u: np.ndarray, low: np.ndarray, high: np.ndarray,
            rule: Boundary) -> tuple[np.ndarray, np.ndarray]:
    """Positions ``x`` and velocities ``u`` (..., d) after the boundary ``rule`` for the box
    ``[low, high]`` (d,)."""
    out = (x < low) | (x > high)
    if not out.any():
        return x, u
    if rule == "clip":
        return np.where(out, np.clip(x, low, high), x), u
    if rule == "absorb":
        return np.where(out, np.clip(x, low, high), x), np.where(out, 0.0, u)
    width = high - low
    if rule == "periodic":
        above = low + np.mod(x - high, width)
        below = high - np.mod(low - x, width)
        return np.where(x > high, above, np.where(x < low, below, x)), u
    if rule != "reflect":
        raise ValueError(f"boundary: unknown {rule!r}, choose from {BOUNDARIES}")
    folds = np.floor((x - low) / width)
    y = (x - low) - folds * width  # in [0, width)
    odd = np.mod(folds, 2.0) != 0.0
    mirrored = low + np.where(odd, width - y, y)
    return np.where(out, np.clip(mirrored, low, high), x), np.where(out & odd, -u, u)
