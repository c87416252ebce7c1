"""SPSO 2011 velocity update (Mai §2.1.1, §3.6): the global reference form [eq. 2.1–2.5]
and the robot-centred form SLO uses [eq. 3.10–3.13], with sampling in the 2-D
hypersphere H(G, r).

Arrays are ``(..., 2)`` (typically runs × particles × 2); random draws are passed in
(:class:`SPSODraws`), so the laws are pure functions and each run keeps its own stream.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal, Sequence

import numpy as np

from ..core.compiled_draws import CompiledDraws

OMEGA_SPSO = 1.0 / (2.0 * np.log(2.0))  # SPSO 2011 default; docs/readings.md, "Inertia weight ω"
C_SPSO = 0.5 + np.log(2.0)  # [Tab. 4.1] c1 = c2

Radial = Literal["uniform_radius", "uniform_area"]


@dataclass(frozen=True)
class SPSODraws:
    """Random inputs of one update: U1, U2 ~ U(0,1)^2, a Gaussian direction and ρ ~ U(0,1)."""

    u1: np.ndarray  # (..., 2)
    u2: np.ndarray  # (..., 2)
    normal: np.ndarray  # (..., 2)
    rho: np.ndarray  # (...)


def draw(rngs: Sequence[np.random.Generator] | CompiledDraws, n: int) -> SPSODraws:
    """Fresh draws for ``n`` particles of every run, (R, n, …): per particle per step
    (docs/readings.md, "How often errors are drawn"); from each run's generator, by numpy or
    compiled (:class:`~shoal.engine.core.compiled_draws.CompiledDraws`, the same numbers)."""
    R = len(rngs.rngs) if isinstance(rngs, CompiledDraws) else len(rngs)
    d = SPSODraws(np.empty((R, n, 2)), np.empty((R, n, 2)), np.empty((R, n, 2)), np.empty((R, n)))
    if isinstance(rngs, CompiledDraws):
        rngs.fill(d.u1, d.u2, d.normal, d.rho, normal=(False, False, True, False))
        return d
    for r, g in enumerate(rngs):  # each run's stream, drawn in place
        g.random(out=d.u1[r])
        g.random(out=d.u2[r])
        g.standard_normal(out=d.normal[r])
        g.random(out=d.rho[r])
    return d


def sample_hypersphere(
    centre: np.ndarray, radius: np.ndarray, normal: np.ndarray, rho: np.ndarray, radial: Radial = "uniform_radius"
) -> np.ndarray:
    """H(G, r) [3.11] (docs/readings.md, "The point in the hypersphere (SPSO 2011)"):
    G + r·ρ·g/‖g‖, ρ ~ U(0,1) as the reference code, or √ρ (uniform in
    area). Returns G where r ≤ 0 or the direction is degenerate."""
    norm = np.linalg.norm(normal, axis=-1, keepdims=True)
    direction = np.divide(normal, norm, out=np.zeros_like(normal), where=norm > 0)
    scale = np.sqrt(rho) if radial == "uniform_area" else rho
    r = np.maximum(np.asarray(radius, dtype=float), 0.0)
    return centre + (r * scale)[..., None] * direction


@dataclass(frozen=True)
class SPSO2011:
    """Coefficients of the SLO swarm behaviour (Mai §3.6, p. 32; Tab. 4.1, p. 37): ``inertia`` is ω; c3, c4 scale and
    offset the sampling radius; ``spso_self_best_halving`` is SPSO's own-best rule (docs/readings.md,
    "SPSO's own-best rule")."""

    inertia: float = OMEGA_SPSO
    c1: float = C_SPSO
    c2: float = C_SPSO
    c3: float = 1.0
    c4: float = 0.0
    radial: Radial = "uniform_radius"
    spso_self_best_halving: bool = False

    def centre(
        self, p: np.ndarray, l: np.ndarray, d: SPSODraws, self_best: np.ndarray | None = None
    ) -> np.ndarray:
        """G relative to the particle: (c1·U1⊗P + c2·U2⊗L)/3 [3.10]; (c1·U1⊗P)/2 where the
        particle is its own best informant and the halving flag is set."""
        cog = self.c1 * d.u1 * p
        g = (cog + self.c2 * d.u2 * l) / 3.0
        if self.spso_self_best_halving and self_best is not None:
            g = np.where(np.asarray(self_best)[..., None], cog / 2.0, g)
        return g

    def local_velocity(
        self, v: np.ndarray, p: np.ndarray, l: np.ndarray, d: SPSODraws, self_best: np.ndarray | None = None
    ) -> np.ndarray:
        """Robot-centred update (X ≡ 0): V' = ω·V + H(G, c3·‖G‖ + c4) [3.10]–[3.11].

        ``p`` and ``l`` are the personal and local bests relative to the particle."""
        g = self.centre(p, l, d, self_best)
        r = self.c3 * np.linalg.norm(g, axis=-1) + self.c4
        return self.inertia * v + sample_hypersphere(g, r, d.normal, d.rho, self.radial)

    def global_velocity(
        self, x: np.ndarray, v: np.ndarray, p: np.ndarray, l: np.ndarray, d: SPSODraws,
        self_best: np.ndarray | None = None,
    ) -> np.ndarray:
        """Reference form in global coordinates [2.1]–[2.4], with the "− X" of docs/readings.md,
        "The missing − X in [2.4]":
        p' = X + c1·U1⊗(P − X), l' = X + c2·U2⊗(L − X), G = (X + p' + l')/3,
        V' = ω·V + H(G, c3·‖G − X‖ + c4) − X. Position update [2.5]: X + V'."""
        p_ = x + self.c1 * d.u1 * (p - x)  # [2.1]
        l_ = x + self.c2 * d.u2 * (l - x)  # [2.2]
        g = (x + p_ + l_) / 3.0  # [2.3]
        if self.spso_self_best_halving and self_best is not None:
            g = np.where(np.asarray(self_best)[..., None], (x + p_) / 2.0, g)
        r = self.c3 * np.linalg.norm(g - x, axis=-1) + self.c4
        return self.inertia * v + sample_hypersphere(g, r, d.normal, d.rho, self.radial) - x  # [2.4]
