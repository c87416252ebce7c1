"""Hydrophone signals synthesised in the frequency domain over the occupied band (Rossides §7.3.2,
p. 161; docs/readings.md, "Synthesised hydrophone signals").

Each hydrophone's window of length T is represented by its complex spectrum on the K band
bins f_k = k/T (``Band.bins``), not by its n = T·fs time samples. Spectra are scaled so
that the window's mean-square value is Σ_k |S_k|²: a real sequence x[m] of n samples with
DFT X_k maps to S_k = √2·X_k/n.

Model per run and timestep, in normalised units (noise intensity 1, signal intensity
(R_ref/r)², [7.15], [7.17]):

- one source spectrum S_k, circular complex Gaussian with E|S_k|² = 1/K (a filtered
  Gaussian process of unit power), shared by every hydrophone of every robot of the run;
- hydrophone h at range r_h hears S_k·e^{−j2π f_k (r_h − r̄)/c}·R_ref/r_h, where r̄ is the
  mean range of that robot's hydrophones (only the differences between a robot's own
  hydrophones are observable); r_h is clamped to 1 m in the amplitude only;
- plus its own noise, circular complex Gaussian with E|n_k|² = 1/K, independent between
  hydrophones, robots and runs.

Draw order per run (from that run's generator): source (K), then noise (N, H, K), each as
(…, K, 2) standard normals (real, imaginary). A run's spectra therefore do not depend on
the other runs of the batch.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

from .band import Band
from .propagation import clamp_range

__all__ = ["Band", "hydrophone_positions", "synthesise", "intensity", "to_time"]


def hydrophone_positions(x: np.ndarray, heading: np.ndarray, D: float | None = None) -> np.ndarray:
    """World positions (R, N, H, 2) of each robot's hydrophones.

    ``D=None``: one hydrophone at the robot centre (A-PSO, GT-PSO), H = 1. Otherwise bow
    p1 = x + (D/2)(cos o, sin o) and stern p2 = x − (D/2)(cos o, sin o), H = 2
    (docs/readings.md, "Bow, stern and the sign of the lag").
    """
    x = np.asarray(x, dtype=float)
    if D is None:
        return x[..., None, :]
    o = np.asarray(heading, dtype=float)
    half = 0.5 * float(D) * np.stack([np.cos(o), np.sin(o)], axis=-1)
    return np.stack([x + half, x - half], axis=-2)


def _draw(rngs: Sequence[np.random.Generator], n_src: int, n_noise: int, K: int) -> tuple[np.ndarray, np.ndarray]:
    """Unit-power complex Gaussian spectra: source (R, n_src, K) and noise (R, n_noise, K)."""
    z = np.empty((len(rngs), n_src + n_noise, K, 2))
    if all(type(g.bit_generator) is np.random.PCG64 for g in rngs):  # compiled, the same numbers, every core
        from ..core.compiled_draws import CompiledDraws  # (numba: at first use)

        CompiledDraws(rngs).fill(z, normal=(True,))
    else:
        for g, out in zip(rngs, z):
            g.standard_normal(out=out)
    c = z.view(np.complex128)[..., 0]  # (real, imag) pairs read as complex, no copy
    c *= np.sqrt(0.5 / K)
    return c[:, :n_src], c[:, n_src:]


def _unit_power(s: np.ndarray) -> np.ndarray:
    """Rescale each window (last axis) to mean-square 1; an all-zero window stays zero."""
    p = intensity(s)
    return s / np.sqrt(np.where(p > 0, p, 1.0))[..., None]


def synthesise(
    rngs: Sequence[np.random.Generator],
    hydrophone_pos: np.ndarray,
    source_pos: np.ndarray,
    band: Band,
    r_ref: float | np.ndarray,
    source_per_robot: bool = False,
    renormalise: bool = False,
) -> np.ndarray:
    """Complex band spectra (R, N, H, K) of every hydrophone of every robot of every run.

    ``rngs``: one generator per run (R). ``hydrophone_pos`` (R, N, H, 2) and ``source_pos``
    (R, 2) in metres (the source at this timestep; a moving source is simply a new
    position each step, no Doppler). ``r_ref``: R_ref in metres [7.17], scalar or (R,).
    ``source_per_robot``: draw an independent source window per robot instead of one per
    run (robots far apart hear different stretches of the source; not the default).
    ``renormalise``: rescale every source and noise window to unit power (the literal
    renormalisation to unit variance); the default keeps Gaussian
    fluctuations, so intensity(noise) ~ χ²_{2K}/(2K).
    """
    pos = np.asarray(hydrophone_pos, dtype=float)
    R, N, H, _ = pos.shape
    if len(rngs) != R:
        raise ValueError(f"rngs: need one generator per run ({R}), got {len(rngs)}")
    src = np.asarray(source_pos, dtype=float).reshape(R, 1, 1, 2)
    K = band.K
    s, noise = _draw(rngs, N if source_per_robot else 1, N * H, K)
    noise = noise.reshape(R, N, H, K)
    if renormalise:
        s, noise = _unit_power(s), _unit_power(noise)
    dist = np.linalg.norm(pos - src, axis=-1)  # (R, N, H)
    delay = (dist - dist.mean(axis=-1, keepdims=True)) / band.c
    out = band.phasor(-delay)  # e^{−j2π f_k Δ_h}, (R, N, H, K)
    amp = np.asarray(r_ref, dtype=float).reshape(-1, 1, 1) / clamp_range(dist)  # R_ref/r [7.15]
    out *= amp[..., None]
    out *= s[:, :, None, :]
    out += noise
    return out


def intensity(spectra: np.ndarray) -> np.ndarray:
    """Mean-square value of each window, Σ_k |S_k|² over the last axis (A-PSO fitness
    f_A ≈ I + N, [7.1]); shape (R, N, H) for (R, N, H, K) spectra."""
    s = np.asarray(spectra)
    return np.sum(s.real**2 + s.imag**2, axis=-1)


def to_time(spectra: np.ndarray, band: Band) -> np.ndarray:
    """Real time series (…, n) of the windows at ``band.fs``, for plotting; its mean
    square equals ``intensity(spectra)``."""
    s = np.asarray(spectra)
    n = max(band.n, 2 * int(band.bins[-1]) + 2)
    full = np.zeros(s.shape[:-1] + (n // 2 + 1,), dtype=complex)
    full[..., band.bins] = s * (n / np.sqrt(2.0))
    return np.fft.irfft(full, n, axis=-1)
