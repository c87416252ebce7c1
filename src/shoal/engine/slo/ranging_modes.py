"""Which pairs an SLO robot ranges and localises (``slo.ranging``): every other robot (the
thesis, "all") or the robots of its neighbourhood ("neighbours", ours: :mod:`.ranging`), and
which settings the second cannot run. Plain Python, so a preset is checked without the kernels."""

from __future__ import annotations

from typing import Literal

Ranging = Literal["all", "neighbours"]
RANGINGS: tuple[Ranging, ...] = ("all", "neighbours")
NEIGHBOUR_RULES = ("knn", "radius", "ring")  # the neighbourhoods that use a few robots each
NEIGHBOUR_ENTRY = ("geometric_nearest", "geometric_random", "stale")  # the entry policies without every pair


def refusal(*, selection: str, entry_policy: str, neighbourhood: str, motion: str, ar_gain: float) -> str | None:
    """Why ``ranging = "neighbours"`` cannot run these settings (None: it can)."""
    if selection not in ("css", "perfect"):
        return f"selection {selection!r} compares triangles of pairs; neighbour-only ranging takes css"
    if entry_policy not in NEIGHBOUR_ENTRY:
        return f"entry_policy {entry_policy!r} carries every pair's estimate"
    if neighbourhood not in NEIGHBOUR_RULES:
        return f"a {neighbourhood} neighbourhood uses every robot; neighbour-only ranging takes knn, radius or ring"
    if motion == "formation" or ar_gain > 0:
        return "the formation term reads every pair's estimate"
    return None
