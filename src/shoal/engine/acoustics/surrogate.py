"""APPROXIMATE fast acoustics: draw the receiver statistics without spectra
("surrogate" mode, ours, not in the thesis; docs/readings.md, "The fast surrogate receiver
(ours)"). Validate against the waveform mode (``signals`` +
``receiver``) before comparing numbers with the thesis; tests/test_receiver.py does.

It mirrors the waveform model's second-order statistics, per robot, with K = band bins
(≈ TBP), a_h = R_ref/r_h (r clamped to 1 m) and P_s ~ χ²_{2K}/(2K) the source window
power (one per run, as in ``synthesise``):

- intensity: f_A,h = a_h²·P_s + sqrt(2·a_h²·P_s/K)·z + χ²_{2K}/(2K)  (signal, signal×noise,
  noise), whose mean is I + N and std ≈ (I + N)/sqrt(K), i.e. (I+N)·χ²_{2K}/(2K);
- correlation: R(τ) near the carrier peaks d + m/f_c inside the search window has mean
  a1·a2·P_s·g(m/f_c) and noise covariance σ²·g((m − m')/f_c), with
  g(δ) = mean_k cos(2π f_k δ) and σ² = (a1² + a2² + 1)/(2K); the highest candidate wins,
  so narrowband signals with D > λ_c/2 slip by whole carrier cycles (Rossides §6.3.2, p. 139);
- lag: τ = d + m*/f_c + e, e ~ N(0, 1/((2π f_rms)²·2K·SNR_eff)),
  SNR_eff = (a1·a2)²/(a1² + a2² + 1), f_rms² = mean_k f_k²; τ is kept inside the
  search grid, then α = arccos(clip(cτ/D)) [7.6] and rays [7.7] as in the receiver;
- ρ = the winning candidate's value [7.5].

No correlation function is produced (``Bearing.corr`` has zero lags).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np

from .band import Band
from .propagation import clamp_range
from .receiver import Bearing, angle_of_arrival, lag_samples, rays


@dataclass
class SurrogateReading:
    """Approximate receiver output: intensities (R, N, H) and, for pairs, a Bearing."""

    intensity: np.ndarray  # (R, N, H) f_A per hydrophone
    bearing: Bearing | None  # None for single-hydrophone robots


def _g(band: Band, delta: np.ndarray) -> np.ndarray:
    """Normalised band autocorrelation g(δ) = mean_k cos(2π f_k δ)."""
    return np.mean(np.cos(2.0 * np.pi * band.freqs * np.asarray(delta)[..., None]), axis=-1)


def _cycles(band: Band, D: float) -> np.ndarray:
    """Carrier-cycle offsets m a peak can slip by inside the search window."""
    m = int(np.ceil(2.0 * lag_samples(band, D)[-1] / band.fs * band.f_c)) + 1
    return np.arange(-m, m + 1)


def surrogate(
    rngs: Sequence[np.random.Generator],
    hydrophone_pos: np.ndarray,
    source_pos: np.ndarray,
    band: Band,
    r_ref: float | np.ndarray,
    heading: np.ndarray | None = None,
    D: float | None = None,
    source_per_robot: bool = False,
    refine: bool = True,
) -> SurrogateReading:
    """APPROXIMATE intensities and (for H = 2, given ``heading`` and ``D``) bearings, with
    the shapes of the waveform mode: ``hydrophone_pos`` (R, N, H, 2), ``source_pos`` (R, 2),
    one generator per run. ``refine=False`` rounds the lag to the sample grid, as the
    waveform receiver does without peak refinement."""
    pos = np.asarray(hydrophone_pos, dtype=float)
    R, N, H, _ = pos.shape
    if len(rngs) != R:
        raise ValueError(f"rngs: need one generator per run ({R}), got {len(rngs)}")
    K = band.K
    pair = H == 2 and D is not None and heading is not None
    m = _cycles(band, D) if pair and D is not None else np.zeros(0, dtype=int)
    M = m.size
    n_src = N if source_per_robot else 1
    ps, z_cross, chi, z_peak, z_lag = (np.empty((R,) + s) for s in ((n_src,), (N, H), (N, H), (N, M), (N,)))
    for i, g in enumerate(rngs):  # fixed draw order per run: batching does not change a run
        ps[i] = g.gamma(K, 1.0 / K, n_src)
        z_cross[i] = g.standard_normal((N, H))
        chi[i] = g.gamma(K, 1.0 / K, (N, H))
        z_peak[i] = g.standard_normal((N, M))
        z_lag[i] = g.standard_normal(N)
    ps = np.broadcast_to(ps, (R, N))
    dist = np.linalg.norm(pos - np.asarray(source_pos, dtype=float).reshape(R, 1, 1, 2), axis=-1)
    a = np.asarray(r_ref, dtype=float).reshape(-1, 1, 1) / clamp_range(dist)  # (R, N, H)
    sig = a**2 * ps[..., None]
    f_a = sig + np.sqrt(2.0 * sig / K) * z_cross + chi
    if not pair or D is None:
        return SurrogateReading(intensity=f_a, bearing=None)

    d = (dist[..., 1] - dist[..., 0]) / band.c  # true lag, bow hears first → d > 0
    I = a[..., 0] * a[..., 1]
    var = (a[..., 0] ** 2 + a[..., 1] ** 2 + 1.0) / (2.0 * K)
    edge = lag_samples(band, D)[-1] / band.fs
    cand = d[..., None] + m / band.f_c  # (R, N, M)
    G = _g(band, (m[:, None] - m[None, :]) / band.f_c)
    w, V = np.linalg.eigh(G)
    root = V * np.sqrt(np.maximum(w, 0.0))  # G = root·rootᵀ (G may be near-singular)
    value = (I * ps)[..., None] * _g(band, m / band.f_c) + np.sqrt(var)[..., None] * (z_peak @ root.T)
    value = np.where(np.abs(cand) <= edge, value, -np.inf)
    win = np.argmax(value, axis=-1)
    rho = np.take_along_axis(value, win[..., None], -1)[..., 0]
    rho = np.where(np.isfinite(rho), rho, 0.0)  # no candidate inside the window: only if |d| > edge
    snr_eff = I**2 / (a[..., 0] ** 2 + a[..., 1] ** 2 + 1.0)
    f_rms = np.sqrt(np.mean(band.freqs**2))
    sd = 1.0 / (2.0 * np.pi * f_rms * np.sqrt(2.0 * K * np.maximum(snr_eff, 1e-300)))
    lag = np.take_along_axis(cand, win[..., None], -1)[..., 0]
    tau = np.clip(lag + np.minimum(sd, 1e3 * edge) * z_lag, -edge, edge)
    if not refine:
        tau = np.round(tau * band.fs) / band.fs
    alpha = angle_of_arrival(tau, D, band.c)
    head = np.asarray(heading, dtype=float)
    b = Bearing(tau=tau, rho=rho, alpha=alpha, rays=rays(alpha, head), lags=np.zeros(0), corr=np.zeros((R, N, 0)))
    return SurrogateReading(intensity=f_a, bearing=b)
