"""A worked example of a Shoal plug-in: one objective, one velocity law and one scene kind.

Shoal finds :func:`register` through the entry point ``shoal.plugins`` of this package and calls
it once, the first time it reads any registry. Nothing here is imported because of a preset's
value: a preset names ``himmelblau``, ``clamped`` or ``[gather]``, and Shoal looks the name up.
"""

from __future__ import annotations

from importlib import resources

import numpy as np

from shoal.engine.core.objectives import OBJECTIVES, ObjectiveFunction
from shoal.engine.pso.laws import LAWS, VelocityLaw, standard_velocity


def himmelblau(z: np.ndarray) -> np.ndarray:
    """Himmelblau's function of the first two coordinates (four minima of 0), vectorised: (..., d) → (...)."""
    x, y = z[..., 0], z[..., 1] if z.shape[-1] > 1 else np.zeros(z.shape[:-1])
    return (x**2 + y - 11.0) ** 2 + (x + y**2 - 7.0) ** 2


V_CLAMP = 2.0  # m per tick: the largest velocity component the clamped law allows


def clamped_velocity(u: np.ndarray, g: np.ndarray, c: np.ndarray, omega: np.ndarray | float, r: np.ndarray,
                     width: float) -> np.ndarray:
    """Standard PSO [2.1] with every component clamped to ±V_CLAMP (the common v_max variant)."""
    return np.clip(standard_velocity(u, g, c, omega, r), -V_CLAMP, V_CLAMP)


def register() -> None:
    """Add this package's objective, law, scene kind and preset to Shoal's registries."""
    from shoal.presets.io import add_presets
    from shoal.presets.kinds import KINDS

    from .gather import KIND

    OBJECTIVES.register(ObjectiveFunction("himmelblau", "Himmelblau (example plug-in)", himmelblau))
    LAWS.register(VelocityLaw("clamped", "Clamped PSO (example plug-in)", adapted=False, velocity=clamped_velocity,
                              omega_range=(-1.0, 1.0), region="order-2", rule="-1 <= omega < 1 [3.9]"))
    KINDS.register(KIND)
    add_presets(resources.files(__name__).joinpath("presets"))
