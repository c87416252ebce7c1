"""Two-hydrophone receiver: cross-correlation, lag, ρ, angle of arrival and rays (Rossides §6.3.1,
p. 138; §7.2, p. 151).

Sign convention (docs/readings.md, "Bow, stern and the sign of the lag"): hydrophone 0 is
the bow (s1), hydrophone 1 the stern (s2). R(τ) = mean_t s1(t)·s2(t+τ) peaks at
τ = +D cos α/c, so a source dead ahead gives τ > 0 and α = 0.

From band spectra (``signals``) the correlation is exact at any lag τ:

    R(τ) = Re Σ_k X_k e^{j2π f_k τ},   X_k = conj(S1_k)·S2_k            [6.9]

the mean (÷ n) of the discrete circular xcorr of the two windows (docs/readings.md, "Scale of
the correlation peak ρ"),
so R(0) of a window with itself is its mean-square value and ρ estimates the received
signal intensity (Pa², or (R_ref/r)² in normalised units), comparable with f_A.

Estimators: τ_lag = argmax R on the lag grid [6.10]/[7.4], refined by a 3-point parabola
(or, with ``refine=False``, the grid lag itself, as Alg. 5 lines 28–31 take τ[I_lag]);
ρ = R(τ_lag) evaluated exactly at that lag [6.11]/[7.5];
α = arccos(clip(c·τ_lag/D, −1, 1)) [7.6]; rays r_± = (cos(o ± α), sin(o ± α)) [7.7].
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from ..core.portable import arccos, ordered_matmul
from .band import Band

PLUS, MINUS = 0, 1  # index of r_+ (CCW, left) and r_- (CW, right) in Bearing.rays


@dataclass
class Bearing:
    """Receiver output for every robot of every run."""

    tau: np.ndarray  # (R, N) τ_lag in s, > 0 when the bow hears first
    rho: np.ndarray  # (R, N) ρ = R(τ_lag), intensity units
    alpha: np.ndarray  # (R, N) angle of arrival from the bow, 0..π (theta_aoa)
    rays: np.ndarray  # (R, N, 2, 2) world unit vectors [r_+, r_-], last axis (x, y)
    lags: np.ndarray  # (L,) lag grid in s, increasing
    corr: np.ndarray  # (R, N, L) R(τ) on that grid


def lag_samples(band: Band, D: float, full_lag: bool = False) -> np.ndarray:
    """Integer lags of the search grid: |ℓ| ≤ ceil(D·fs/c) + 1 (docs/readings.md, "Clipping the arccos
    and the lag search"), or with
    ``full_lag`` the whole circular window, −n/2 ≤ ℓ < n/2."""
    if full_lag:
        n = _fft_size(band)
        return np.arange(-(n // 2), n - n // 2)
    L = int(np.ceil(D * band.fs / band.c)) + 1
    return np.arange(-L, L + 1)


def _fft_size(band: Band) -> int:
    """Window length for the full-lag inverse FFT (≥ n, and every band bin below Nyquist)."""
    return max(band.n, 2 * int(band.bins[-1]) + 2)


def cross_spectrum(spectra: np.ndarray) -> np.ndarray:
    """X_k = conj(S1_k)·S2_k (…, K) from bow/stern spectra (…, 2, K)."""
    return np.conj(spectra[..., 0, :]) * spectra[..., 1, :]


def correlate(X: np.ndarray, band: Band, tau: np.ndarray) -> np.ndarray:
    """R(τ) = Re Σ_k X_k e^{j2π f_k τ} at lags ``tau`` (L,) in s: a small inverse DFT over the
    K band bins as one real matrix product, shape (…, L). [6.9]"""
    return _project(X, *_phases(band, tau))


def _phases(band: Band, tau: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """cos and sin of 2π f_k τ, (K, L)."""
    arg = 2.0 * np.pi * np.outer(band.freqs, tau)
    return np.cos(arg), np.sin(arg)


def _project(X: np.ndarray, cos: np.ndarray, sin: np.ndarray, compiled: bool = True) -> np.ndarray:
    """Re X · cos − Im X · sin, each product summed over k in index order: a BLAS product would
    sum in the order of the kernel the CPU gets, and the refined peak would move with it
    (:mod:`~shoal.engine.core.portable`; ``compiled`` or numpy, the same bits)."""
    return ordered_matmul(X.real, cos, compiled) - ordered_matmul(X.imag, sin, compiled)


CACHED_PHASES = 250_000  # K × L of a lag table kept for reuse (cos and sin: 4 MB); a larger one is not kept


def lag_table(band: Band, D: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The search grid of a band and hydrophone separation: lags (L,) in s and the cos and sin
    of 2π f_k τ (K, L) that :func:`correlate` needs (read-only arrays), worked out once and kept
    while small: a process serving many scenes keeps at most 32 tables of 4 MB, not 32 of any
    size (a band of 5,000 bins at 1 MHz made 80 MB each, held until the server stopped)."""
    if band.K * lag_samples(band, D).size > CACHED_PHASES:
        return _lag_table(band, D)
    return _kept_lag_table(band, D)


@lru_cache(maxsize=32)
def _kept_lag_table(band: Band, D: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    return _lag_table(band, D)


def _lag_table(band: Band, D: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    lags = lag_samples(band, D) / band.fs
    table = (lags, *_phases(band, lags))
    for a in table:
        a.setflags(write=False)
    return table


def _correlate_full(X: np.ndarray, band: Band) -> tuple[np.ndarray, np.ndarray]:
    """R on the whole circular window by one zero-padded inverse real FFT: lags (L,) in s,
    increasing, spacing T/n (≈ 1/fs), and R (…, L)."""
    n = _fft_size(band)
    full = np.zeros(X.shape[:-1] + (n // 2 + 1,), dtype=complex)
    full[..., band.bins] = X
    r = np.fft.irfft(full, n, axis=-1) * (n / 2.0)  # Re Σ_k X_k e^{j2πkℓ/n}
    ell = lag_samples(band, 0.0, full_lag=True)
    return ell * (band.T / n), r[..., ell % n]


def _refine(corr: np.ndarray, lags: np.ndarray) -> np.ndarray:
    """τ at the grid maximum, refined by a 3-point parabola (offset clipped to ±½ step);
    a flat R (no signal) gives τ = 0."""
    L = lags.size
    i = np.argmax(corr, axis=-1)
    j = np.clip(i, 1, L - 2) if L >= 3 else i
    y0, y1, y2 = (np.take_along_axis(corr, np.clip(j + d, 0, L - 1)[..., None], -1)[..., 0] for d in (-1, 0, 1))
    denom = y0 - 2.0 * y1 + y2
    inside = (i == j) & (denom < 0)
    delta = np.clip(0.5 * (y0 - y2) / np.where(inside, denom, -1.0), -0.5, 0.5)
    step = lags[1] - lags[0] if L > 1 else 0.0
    tau = lags[i] + np.where(inside, delta, 0.0) * step
    flat = np.max(corr, axis=-1) <= np.min(corr, axis=-1)
    return np.where(flat, 0.0, tau)


def _sample_peak(corr: np.ndarray, lags: np.ndarray) -> np.ndarray:
    """τ at the grid maximum, not refined (Alg. 5 lines 28–31); a flat R gives τ = 0."""
    tau = lags[np.argmax(corr, axis=-1)]
    flat = np.max(corr, axis=-1) <= np.min(corr, axis=-1)
    return np.where(flat, 0.0, tau)


def angle_of_arrival(tau: np.ndarray, D: float, c: float) -> np.ndarray:
    """α = arccos(clip(c·τ/D, −1, 1)) in 0..π from the bow. [7.6]; docs/readings.md,
    "Clipping the arccos and the lag search".
    """
    return arccos(np.clip(c * np.asarray(tau) / D, -1.0, 1.0))  # the C library's: the same bits on every CPU


def rays(alpha: np.ndarray, heading: np.ndarray) -> np.ndarray:
    """World-frame unit rays (…, 2, 2): r_+ = (cos(o+α), sin(o+α)) (CCW, left) and
    r_- = (cos(o−α), sin(o−α)) (CW, right), mirror images across the bow axis. [7.7]"""
    ang = np.stack([heading + alpha, heading - alpha], axis=-1)
    return np.stack([np.cos(ang), np.sin(ang)], axis=-1)


def bearing(spectra: np.ndarray, band: Band, D: float, heading: np.ndarray, full_lag: bool = False,
            refine: bool = True, compiled: bool = True) -> Bearing:
    """Bearing estimate of every robot from its bow/stern spectra (R, N, 2, K).

    ``D``: hydrophone separation (m); ``heading`` (R, N): robot heading o (rad);
    ``full_lag``: search the whole window as MATLAB ``xcorr`` would, so a peak outside
    ±D/c is clipped to α = 0 or π; ``refine``: refine the peak lag by a parabola, else keep
    the sample lag (docs/readings.md, "The lag estimate and the sample rate"); ``compiled``:
    the correlation on the lag grid by a compiled loop, else numpy (the same bits).
    """
    if not D > 0:
        raise ValueError(f"D: hydrophone separation must be > 0, got {D}")
    X = cross_spectrum(np.asarray(spectra))
    if full_lag:
        lags, corr = _correlate_full(X, band)
    else:
        lags, cos, sin = lag_table(band, float(D))
        corr = _project(X, cos, sin, compiled)  # correlate(X, band, lags)
    tau = _refine(corr, lags) if refine else _sample_peak(corr, lags)
    rho = np.sum((X * band.phasor(tau)).real, axis=-1)  # ρ = R(τ_lag) [7.5]
    alpha = angle_of_arrival(tau, D, band.c)
    return Bearing(tau=tau, rho=rho, alpha=alpha, rays=rays(alpha, np.asarray(heading, dtype=float)), lags=lags,
                   corr=corr)
