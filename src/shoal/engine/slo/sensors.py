"""SLO sensor and error model (Mai §3.4, §4.4, Tab. 4.3): noisy inter-robot ranges and
noisy odometry, with stochastic parts redrawn per measurement and permanent parts drawn once
per run and robot.

Every draw is made whatever the error level (a zero σ just scales it away), so the random
streams, and hence the other components, stay aligned between the None, Low and High sets.
"""

from __future__ import annotations

from dataclasses import dataclass, fields, replace
from typing import Literal, Sequence

import numpy as np

from ..core.compiled import f64
from ..core.compiled_draws import CompiledDraws
from . import sensor_kernels

ErrorLevel = Literal["none", "low", "high"]


@dataclass(frozen=True)
class RangeErrors:
    """[4.1]–[4.3]: d* = d·E_m + E_a, E_m = N(1, σ_m) + P_m, E_a = N(0, σ_a) + P_a;
    ``perm_sigma_*`` are σ̂ of the permanent draws P; ``p_fail`` returns 0."""

    sigma_m: float = 0.0
    sigma_a: float = 0.0
    perm_sigma_m: float = 0.0
    perm_sigma_a: float = 0.0
    p_fail: float = 0.0


@dataclass(frozen=True)
class OdometryErrors:
    """[4.4]: per-axis v'_k = v_k·E_m,k + E_a,k, then rotation by θ = N(0, σ_r) + P_r (radians,
    docs/readings.md, "Unit of the rotation error σ_r"); ``p_fail`` zeroes the whole vector."""

    sigma_m: float = 0.0
    sigma_a: float = 0.0
    perm_sigma_m: float = 0.0
    perm_sigma_a: float = 0.0
    p_fail: float = 0.0
    sigma_r: float = 0.0
    perm_sigma_r: float = 0.0


@dataclass(frozen=True)
class ErrorModel:
    """Range and odometry errors; additive parts are in thesis units (100 × 100 area)."""

    range: RangeErrors = RangeErrors()
    odometry: OdometryErrors = OdometryErrors()

    def scaled(self, unit: float) -> "ErrorModel":
        """Additive σ_a, σ̂_a multiplied by ``unit`` = arena width / 100 (docs/readings.md,
        "Thesis units on a scene (ours)")."""
        if unit == 1.0:
            return self
        return ErrorModel(
            replace(self.range, sigma_a=self.range.sigma_a * unit, perm_sigma_a=self.range.perm_sigma_a * unit),
            replace(self.odometry, sigma_a=self.odometry.sigma_a * unit,
                    perm_sigma_a=self.odometry.perm_sigma_a * unit),
        )

    def with_values(self, **changes: float) -> "ErrorModel":
        """A copy with some fields changed, named ``range_<field>`` or ``odometry_<field>``."""
        parts: dict[str, dict[str, float]] = {"range": {}, "odometry": {}}
        known = {"range": {f.name for f in fields(RangeErrors)}, "odometry": {f.name for f in fields(OdometryErrors)}}
        for key, value in changes.items():
            part, _, name = key.partition("_")
            if name not in known.get(part, ()):
                raise ValueError(f"errors: unknown field {key!r}")
            parts[part][name] = float(value)
        return ErrorModel(replace(self.range, **parts["range"]), replace(self.odometry, **parts["odometry"]))


ERROR_PRESETS: dict[str, ErrorModel] = {  # [Tab. 4.3]
    "none": ErrorModel(),
    "low": ErrorModel(
        RangeErrors(sigma_m=0.010, sigma_a=0.050, perm_sigma_m=0.015, perm_sigma_a=0.150, p_fail=0.050),
        OdometryErrors(sigma_m=0.050, sigma_a=0.050, perm_sigma_m=0.015, perm_sigma_a=0.050, p_fail=0.050,
                       sigma_r=0.050, perm_sigma_r=0.050),
    ),
    "high": ErrorModel(
        RangeErrors(sigma_m=0.20, sigma_a=0.30, perm_sigma_m=0.06, perm_sigma_a=1.00, p_fail=0.30),
        OdometryErrors(sigma_m=0.20, sigma_a=0.30, perm_sigma_m=0.06, perm_sigma_a=0.30, p_fail=0.20,
                       sigma_r=0.20, perm_sigma_r=0.20),
    ),
}


def error_model(errors: str | ErrorModel) -> ErrorModel:
    """An :class:`ErrorModel` from a preset name (None / Low / High) or itself."""
    if isinstance(errors, ErrorModel):
        return errors
    key = str(errors).lower()
    if key not in ERROR_PRESETS:
        raise ValueError(f"errors: unknown preset {errors!r}, expected one of {sorted(ERROR_PRESETS)}")
    return ERROR_PRESETS[key]


@dataclass(frozen=True)
class PermanentErrors:
    """Per-robot calibration offsets of one run (docs/readings.md, "Who owns a permanent error"):
    the ranging sensor of robot i and its odometry (per axis for P_m and P_a)."""

    range_m: np.ndarray  # (R, N)
    range_a: np.ndarray  # (R, N)
    odo_m: np.ndarray  # (R, N, 2)
    odo_a: np.ndarray  # (R, N, 2)
    odo_r: np.ndarray  # (R, N)


def draw_permanent(model: ErrorModel, rngs: Sequence[np.random.Generator], n: int) -> PermanentErrors:
    """Draw P_m, P_a (range), P_m,k, P_a,k, P_r (odometry) once per run [4.2], [4.3], [4.4]."""
    return permanent_errors(model, permanent_normals(rngs, n))


def permanent_normals(rngs: Sequence[np.random.Generator], n: int) -> np.ndarray:
    """The standard-normal draws behind the permanent errors, (R, 7, n), once per run."""
    return np.stack([g.standard_normal(7 * n) for g in rngs]).reshape(len(rngs), 7, n)


def permanent_errors(model: ErrorModel, z: np.ndarray) -> PermanentErrors:
    """Permanent errors of ``model`` from the draws ``z`` of :func:`permanent_normals`: the same
    calibration offsets, scaled by the model's σ̂ (so a live change of the error level keeps them)."""
    rg, od = model.range, model.odometry
    return PermanentErrors(
        range_m=rg.perm_sigma_m * z[:, 0],
        range_a=rg.perm_sigma_a * z[:, 1],
        odo_m=od.perm_sigma_m * np.stack([z[:, 2], z[:, 3]], axis=-1),
        odo_a=od.perm_sigma_a * np.stack([z[:, 4], z[:, 5]], axis=-1),
        odo_r=od.perm_sigma_r * z[:, 6],
    )


Draws = Sequence[np.random.Generator] | CompiledDraws  # one generator per run, drawn by numpy or compiled


def _draw(rngs: Draws, fail: np.ndarray, z: np.ndarray) -> None:
    """fail[r] ~ U(0,1), then z[r] ~ N(0,1), from run r's stream (compiled: the same numbers)."""
    if isinstance(rngs, CompiledDraws):
        rngs.fill(fail, z, normal=(False, True))
        return
    for r, g in enumerate(rngs):  # each run's stream, drawn in place
        g.random(out=fail[r])
        g.standard_normal(out=z[r])


def measure_ranges(
    dist: np.ndarray, model: RangeErrors, perm: PermanentErrors, rngs: Draws, max_range: float = np.inf,
) -> np.ndarray:
    """d*_ij for every ordered pair (R, N, N) from true distances (diagonal ignored).

    Stochastic parts are drawn per measurement, so d*_ij and d*_ji are independent; negative
    readings are clamped to 0 (docs/readings.md, "Negative ranges"); 0 means failure; beyond ``max_range`` reads 0."""
    R, n, _ = dist.shape
    fail, z = np.empty((R, n, n)), np.empty((R, 2, n, n))
    _draw(rngs, fail, z)
    return sensor_kernels.ranges(f64(dist), fail, z, float(model.sigma_m), float(model.sigma_a), f64(perm.range_m),
                                 f64(perm.range_a), float(model.p_fail), float(max_range))  # [4.1]–[4.3], compiled


def measure_odometry(v: np.ndarray, model: OdometryErrors, perm: PermanentErrors, rngs: Draws) -> np.ndarray:
    """v*_i (R, N, 2) from true displacements: per-axis errors, then the rotation R(θ) [4.4];
    a failure gives (0, 0)."""
    R, n = v.shape[:2]
    fail, z = np.empty((R, n)), np.empty((R, 5, n))
    _draw(rngs, fail, z)
    theta = model.sigma_r * z[:, 4] + perm.odo_r
    return sensor_kernels.odometry(f64(v), fail, z, float(model.sigma_m), float(model.sigma_a), f64(perm.odo_m),
                                   f64(perm.odo_a), np.cos(theta), np.sin(theta), float(model.p_fail))  # [4.4]
