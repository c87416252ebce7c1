"""Attraction–repulsion between neighbours from relative estimates only (docs/readings.md,
"Attraction–repulsion (external)").

NOT from the Mai thesis, which describes the behaviour only in words (Mai §2.1.2, p. 9; Ch. 5,
p. 61): the form
is Gazi & Passino's swarm aggregation function, the reference the thesis names.
g(y) = −y·(a − b·exp(−‖y‖²/c)), b > a > 0, c > 0; the equilibrium spacing is √(c·ln(b/a)).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..core.portable import exp


@dataclass(frozen=True)
class AttractionRepulsion:
    """Gain ``gain`` (k_ar) and shape a, b, c; ``v_max`` clamps the resulting displacement."""

    gain: float = 0.0
    a: float = 0.01
    b: float = 0.2
    c: float = 25.0
    v_max: float = np.inf

    def __post_init__(self) -> None:
        if not (self.b > self.a > 0 and self.c > 0):
            raise ValueError("attraction-repulsion needs b > a > 0 and c > 0")

    @property
    def spacing(self) -> float:
        """Distance at which attraction and repulsion balance, √(c·ln(b/a))."""
        return float(np.sqrt(self.c * np.log(self.b / self.a)))

    def velocity(self, est: np.ndarray, valid: np.ndarray) -> np.ndarray:
        """V_i = k_ar·Σ_{j∈N_i} g(−x̂_ij), clamped to ``v_max``; est (R, N, N, 2) → (R, N, 2)."""
        y = -est  # x_i − x_j in i's frame
        sq = np.sum(y * y, axis=-1)
        g = -y * (self.a - self.b * exp(-sq / self.c))[..., None]  # the C library's exp: the same bits on any CPU
        v = self.gain * np.where(valid[..., None], g, 0.0).sum(axis=2)
        speed = np.linalg.norm(v, axis=-1, keepdims=True)
        scale = np.minimum(1.0, np.divide(self.v_max, speed, out=np.ones_like(speed), where=speed > 0))
        return v * scale
