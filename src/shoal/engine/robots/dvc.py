"""Dynamic Velocity Control: per-robot coefficients from sensed gaps (Rossides §4.2.2, §5.2.2).

Input ``gap`` is (R, N, 6): the surface distance (0 = contact) to the closest body in each
60° sector, R_s when a sector is empty (docs/readings.md, "Empty sensor sectors and gaps"). Sector k covers bearings
[−180° + 60k, −120° + 60k) in the robot frame: RIGHT = 0–2, LEFT = 3–5, FRONT = 1–4.
Every policy returns ``(omega (R, N), c (n, R, N))``; the shapes work for any leading dims.
"""

from __future__ import annotations

import math

import numpy as np

from .laws import Inertia, rotational_energy_factor

RIGHT = slice(0, 3)
LEFT = slice(3, 6)
FRONT = slice(1, 5)

# Table 4.1 constant cases (β = 0.9, Δt = 1 s; Rossides p. 95); ω = 1 − β (docs/readings.md,
# "Table 4.1: ω and the tuned speed").
TABLE_4_1: dict[str, dict[str, float]] = {
    "c3-high": {"c1": 0.2864, "c2": 0.2864, "c3": 1.1455, "omega": 0.1},
    "c3-equal": {"c1": 0.4296, "c2": 0.4296, "c3": 0.8591, "omega": 0.1},
    "c3-low": {"c1": 0.5728, "c2": 0.5728, "c3": 0.5728, "omega": 0.1},
}


def _check(alpha: float, beta: float, dt: float, c1_share: float) -> None:
    if not 0.0 < alpha <= 1.0:
        raise ValueError(f"alpha must be in (0, 1], got {alpha!r}")
    if not 0.0 < beta <= 1.0:
        raise ValueError(f"beta must be in (0, 1], got {beta!r}")
    if not (dt > 0 and math.isfinite(dt)):
        raise ValueError(f"dt must be a finite number > 0, got {dt!r}")
    if not 0.0 <= c1_share <= 1.0:
        raise ValueError(f"c1_share must be in [0, 1], got {c1_share!r}")


def _omega(beta: float, shape: tuple[int, ...]) -> np.ndarray:
    return np.full(shape, 1.0 - beta)  # ω = 1 − β [4.9]


def dvc_omni(
    gap: np.ndarray,
    *,
    alpha: float = 0.9,
    beta: float = 0.9,
    dt: float = 1.0,
    c1_share: float = 0.5,
    d: int = 2,
) -> tuple[np.ndarray, np.ndarray]:
    """Algorithm 1 steps 2.3–2.7: (ω (R, N), c = [c1, c2, c3] (3, R, N)).

    Attraction may reach α ν_1, the nearest body's one-step speed; the total α ν_2.
    Closed forms: c1 + c2 = αβ s_1/(Δt√d), c3 = αβ (s_2 − s_1)/(Δt√d), so c3 = 0 exactly
    when the two nearest gaps are equal. Negative gaps (overlap) count as contact.
    """
    _check(alpha, beta, dt, c1_share)
    gap = np.maximum(np.asarray(gap, dtype=float), 0.0)
    if gap.shape[-1] < 2:
        raise ValueError("dvc_omni needs at least two sector gaps")
    s = np.sort(gap, axis=-1)  # s_1 ≤ s_2 ≤ …
    k = alpha * beta / (dt * math.sqrt(d))  # ν = s/Δt [4.13], U = α ν [4.14], ĉ = β U/√d [4.15]
    c12 = k * s[..., 0]  # step 1: U_{1,2} = α ν_1
    c3 = k * (s[..., 1] - s[..., 0])  # step 2: ĉ(α ν_2) − c1 − c2
    c = np.stack([c1_share * c12, (1.0 - c1_share) * c12, c3])  # [4.16] c1 = c2 by default
    return _omega(beta, gap.shape[:-1]), c


def constant_rpso(
    c1: float, c2: float, c3: float, omega: float, shape: tuple[int, ...]
) -> tuple[np.ndarray, np.ndarray]:
    """Constant coefficients (Table 4.1) broadcast to (ω shape, c (3, *shape))."""
    c = np.array([c1, c2, c3], dtype=float).reshape((3,) + (1,) * len(shape))
    return np.full(shape, float(omega)), np.broadcast_to(c, (3, *shape)).copy()


def w_max(
    v_max: float, dt: float, inertia: Inertia = "pi", body_radius: float | None = None
) -> float:
    """Angular speed limit from the energy budget e_max = v_max²/2 (Rossides §5.2, p. 114).

    ``pi``: √(4 e_max/π) [5.12] as printed; ``disc``: e_r = R_b² w²/4 (docs/readings.md, "Rotational energy [5.12]").
    Capped at π/(2Δt) so one step turns at most 90°.
    """
    if not (dt > 0 and v_max >= 0):
        raise ValueError(f"need dt > 0 and v_max >= 0, got dt={dt!r}, v_max={v_max!r}")
    e_max = 0.5 * v_max**2
    w_energy = math.sqrt(e_max / rotational_energy_factor(inertia, body_radius))
    return float(min(w_energy, math.pi / (2.0 * dt)))


def dvc_nonomni(
    gap: np.ndarray,
    *,
    alpha: float = 0.9,
    beta: float = 0.9,
    dt: float = 1.0,
    sensing_range: float = 3.0,
    w_max: float,
    c1_share: float = 0.5,
    v_max: float | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Algorithm 2 DVC [5.14]–[5.16], typos fixed (docs/readings.md, "Typos in Algorithm 2"): c = [c1..c5] (5, R, N).

    W12 = (s_1/R) w_max, W3 = (1 − sl_1/R) w_max, W4 = (1 − sr_1/R) w_max; c1 + c2 = β W12,
    c3 = β W3, c4 = β W4; U = α sf_1/Δt (≤ v_max if given, an engineering choice), c5 = β U.
    Gaps are clipped to [0, R].
    """
    _check(alpha, beta, dt, c1_share)
    if not sensing_range > 0:
        raise ValueError(f"sensing_range must be > 0, got {sensing_range!r}")
    if not w_max >= 0:
        raise ValueError(f"w_max must be >= 0, got {w_max!r}")
    gap = np.clip(np.asarray(gap, dtype=float), 0.0, sensing_range)
    if gap.shape[-1] != 6:
        raise ValueError(f"dvc_nonomni needs 6 sector gaps, got {gap.shape[-1]}")
    s1 = gap.min(axis=-1)
    sl1 = gap[..., LEFT].min(axis=-1)
    sr1 = gap[..., RIGHT].min(axis=-1)
    sf1 = gap[..., FRONT].min(axis=-1)
    W12 = s1 / sensing_range * w_max  # [5.16]
    W3 = (1.0 - sl1 / sensing_range) * w_max
    W4 = (1.0 - sr1 / sensing_range) * w_max
    U = alpha * sf1 / dt  # [5.15], [4.14]
    if v_max is not None:
        U = np.minimum(U, v_max)
    c12 = beta * W12  # [5.14] with d = 1
    c = np.stack([c1_share * c12, (1.0 - c1_share) * c12, beta * W3, beta * W4, beta * U])
    return _omega(beta, gap.shape[:-1]), c


def approach_guard(
    u: np.ndarray, x: np.ndarray, point: np.ndarray, gap: np.ndarray, *, alpha: float = 0.9, dt: float = 1.0
) -> np.ndarray:
    """Scale each global velocity so one step closes at most α·s_p toward every sensed body.

    DVC bounds the accelerating terms but not the carried-over ω·u, so the thesis'
    "never reaches the nearest body in one step" is approximate (docs/readings.md, "The DVC guard (ours)"). This
    optional guard (ours, not in the thesis) makes it exact for straight-line motion:
    with n_p the unit vector to body p's closest point, Δt·(u·n_p) ≤ α s_p for all p.
    ``u``, ``x``: (R, N, 2); ``point``: (R, N, 6, 2), nan where a sector is empty; ``gap``: (R, N, 6).
    """
    rel = point - x[..., None, :]
    dist = np.linalg.norm(rel, axis=-1)
    seen = np.isfinite(dist) & (dist > 0)
    n = np.where(seen[..., None], rel / np.where(seen, dist, 1.0)[..., None], 0.0)
    closing = np.einsum("rnkd,rnd->rnk", n, u) * dt  # distance closed in one step
    allowed = alpha * np.maximum(gap, 0.0)
    ratio = np.where(seen & (closing > allowed), allowed / np.where(closing > 0, closing, 1.0), 1.0)
    return u * ratio.min(axis=-1, initial=1.0)[..., None]


def forward_guard(v: np.ndarray, gap: np.ndarray, *, alpha: float = 0.9, dt: float = 1.0) -> np.ndarray:
    """Non-omni counterpart of :func:`approach_guard`: v ≤ α·sf_1/Δt including the ω·v carry."""
    sf1 = np.maximum(np.asarray(gap, dtype=float)[..., FRONT].min(axis=-1), 0.0)
    return np.minimum(v, alpha * sf1 / dt)
