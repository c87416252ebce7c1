"""Stability regions and the reduced state model of Adapted PSO (Rossides §3.1–3.3).

All functions accept scalars or numpy arrays, so plots and tests share them.
"""

from __future__ import annotations

import numpy as np

DIVERGED = 1e9  # m/s: a robot faster than this (or not a finite number) belongs to a swarm that diverged


def diverged(u: np.ndarray) -> np.ndarray:
    """Per run, has the swarm of velocities ``u`` (R, N, d) diverged: some speed beyond
    :data:`DIVERGED` or not a finite number (an unstable (ω, ĉ) grows without bound)?"""
    speed = np.abs(np.asarray(u, dtype=float))
    return ~np.isfinite(speed).all(axis=(1, 2)) | (speed.max(axis=(1, 2), initial=0.0) > DIVERGED)


def order1_boundary(omega: np.ndarray | float) -> np.ndarray:
    """Upper ĉ of the standard-PSO order-1 region: ĉ < 4(ω + 1) [3.7]."""
    return 4.0 * (np.asarray(omega, dtype=float) + 1.0)


def order2_boundary(omega: np.ndarray | float) -> np.ndarray:
    """Upper ĉ of the standard-PSO order-2 region: ĉ < 24(1 − ω²)/(7 − 5ω) [3.9]."""
    w = np.asarray(omega, dtype=float)
    return 24.0 * (1.0 - w**2) / (7.0 - 5.0 * w)


def order1_stable(omega: np.ndarray | float, c_hat: np.ndarray | float) -> np.ndarray:
    """Standard PSO order-1 region [3.7]: −1 < ω < 1 and 0 < ĉ < 4(ω + 1)."""
    w, c = np.asarray(omega, dtype=float), np.asarray(c_hat, dtype=float)
    return (w > -1) & (w < 1) & (c > 0) & (c < order1_boundary(w))


def order2_stable(omega: np.ndarray | float, c_hat: np.ndarray | float) -> np.ndarray:
    """Standard PSO order-2 region [3.9]: −1 < ω < 1 and 0 < ĉ < 24(1 − ω²)/(7 − 5ω)."""
    w, c = np.asarray(omega, dtype=float), np.asarray(c_hat, dtype=float)
    return (w > -1) & (w < 1) & (c > 0) & (c < order2_boundary(w))


def adapted_stable(
    omega: np.ndarray | float, c_hat: np.ndarray | float, robot_subset: bool = True
) -> np.ndarray:
    """Adapted PSO region: −1 < ω < 1, ĉ > 0 [3.13]; with ``robot_subset`` 0 ≤ ω < 1 [3.14]."""
    w, c = np.asarray(omega, dtype=float), np.asarray(c_hat, dtype=float)
    low = 0.0 if robot_subset else -1.0
    lower_ok = (w >= low) if robot_subset else (w > low)
    return lower_ok & (w < 1) & (c > 0)


def reduced_state_matrix(omega: float, dt: float) -> np.ndarray:
    """M̂ of [3.23]: ẑ = [u; a], ẑ[k+1] = M̂ ẑ[k] + b̂[k]."""
    return np.array([[omega, 0.0], [(omega - 1.0) / dt, 0.0]])


def reduced_state_input(c_hat: float, sign: np.ndarray | float, r: np.ndarray | float, dt: float) -> np.ndarray:
    """b̂ of [3.23]: ĉ · sgn(ŷ − x) · r · [1; 1/Δt] (last axis = (u, a))."""
    scale = c_hat * np.asarray(sign, dtype=float) * np.asarray(r, dtype=float)
    return np.stack([scale, scale / dt], axis=-1)


def reduced_step(
    z: np.ndarray, omega: float, c_hat: float, sign: np.ndarray | float, r: np.ndarray | float, dt: float
) -> np.ndarray:
    """One step of [3.23] for states ``z`` of shape (..., 2)."""
    return z @ reduced_state_matrix(omega, dt).T + reduced_state_input(c_hat, sign, r, dt)


def a1(u: np.ndarray | float, omega: float, dt: float) -> np.ndarray:
    """Line a1 [3.24]: a = (ω − 1)/(ωΔt) · u, the locus of M̂ẑ.

    Undefined at ω = 0, where the locus is the vertical line u = 0 (docs/readings.md, "The stability locus at ω = 0");
    use :func:`line_a1` for drawing. Raises ``ValueError`` at ω = 0.
    """
    if omega * dt == 0:  # also catches subnormal ω
        raise ValueError("a1 is the vertical line u = 0 when omega = 0; use line_a1()")
    return (omega - 1.0) / (omega * dt) * np.asarray(u, dtype=float)


def line_a1(omega: float, dt: float, u_lim: float, a_lim: float) -> np.ndarray:
    """Two end points ((u0, a0), (u1, a1)) of the a1 locus clipped to |u| ≤ u_lim, |a| ≤ a_lim."""
    if omega * dt == 0 or abs((omega - 1.0) / (omega * dt)) > 1e12:
        return np.array([[0.0, -a_lim], [0.0, a_lim]])
    slope = (omega - 1.0) / (omega * dt)
    u_end = u_lim if slope == 0 else min(u_lim, a_lim / abs(slope))
    return np.array([[-u_end, -slope * u_end], [u_end, slope * u_end]])


def a2(u: np.ndarray | float, omega: float, dt: float, c_hat: float) -> np.ndarray:
    """Upper envelope a2 of ẑ[k+1] [3.25]: a1(u − ĉ) + ĉ/Δt."""
    return a1(np.asarray(u, dtype=float) - c_hat, omega, dt) + c_hat / dt


def a3(u: np.ndarray | float, omega: float, dt: float, c_hat: float) -> np.ndarray:
    """Lower envelope a3 of ẑ[k+1]: a1(u + ĉ) − ĉ/Δt."""
    return a1(np.asarray(u, dtype=float) + c_hat, omega, dt) - c_hat / dt


def phase_markers(omega: float, c_hat: float, dt: float) -> dict[str, np.ndarray]:
    """Marked points of Fig. 3-3b in the (u, a) plane, per dimension.

    ``star``: (±U_j, 0) fixed points [3.26]; ``square``: ±(U_j − 2ĉ, −2ĉ/Δt) maximum
    deceleration [3.28]; ``diamond``: ±(ĉ, ĉ/Δt) maximum acceleration from rest [3.27].
    """
    U_j = c_hat / (1.0 - omega)
    star = np.array([[U_j, 0.0], [-U_j, 0.0]])
    square = np.array([[U_j - 2 * c_hat, -2 * c_hat / dt], [-(U_j - 2 * c_hat), 2 * c_hat / dt]])
    diamond = np.array([[c_hat, c_hat / dt], [-c_hat, -c_hat / dt]])
    return {"star": star, "square": square, "diamond": diamond}


def reachable_parallelogram(omega: float, c_hat: float, dt: float) -> np.ndarray:
    """Vertices of the set reachable by ẑ[k+1] from |u| ≤ U_j (Fig. 3-3b, p. 71; Rossides §3.3.3, p. 70)."""
    U_j = c_hat / (1.0 - omega)
    return np.array(
        [
            [U_j, 0.0],
            [U_j - 2 * c_hat, -2 * c_hat / dt],
            [-U_j, 0.0],
            [-U_j + 2 * c_hat, 2 * c_hat / dt],
        ]
    )
