"""The analysis band of the acoustic receiver (Rossides §7.3.2, p. 161; Table 7.1, p. 160): f_c, Q,
TBP and what follows.

A window of length T = TBP/B has frequency resolution 1/T, so the band
[f_c − B/2, f_c + B/2] holds about TBP DFT bins f_k = k/T. Waveforms are represented by
their complex spectra on those bins only (see ``signals``).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

_EDGE_TOL = 1e-9  # bins: a bin exactly on a band edge belongs to the band


@dataclass(frozen=True)
class Band:
    """Band-limited signal and noise: centre ``f_c`` (Hz), quality factor ``Q`` = f_c/B
    [7.13], time–bandwidth product ``tbp`` = B·T, sound speed ``c`` (m/s) and the sample
    rate ``fs`` (Hz, 48 kHz by default) that sets the lag grid of the receiver; see
    docs/readings.md, "The lag estimate and the sample rate (Chapter 7)"."""

    f_c: float = 1000.0
    Q: float = 1.5
    tbp: float = 100.0
    c: float = 1500.0
    fs: float = 48_000.0

    def __post_init__(self) -> None:
        for name in ("f_c", "Q", "tbp", "c", "fs"):
            if not getattr(self, name) > 0:
                raise ValueError(f"band.{name}: must be > 0, got {getattr(self, name)}")
        if self.f_c + self.B / 2 >= self.fs / 2:
            raise ValueError(f"band.fs: must exceed 2·(f_c + B/2) = {2 * self.f_c + self.B:g} Hz, got {self.fs:g}")

    @property
    def B(self) -> float:
        """Bandwidth B = f_c/Q (Hz). [7.13]"""
        return self.f_c / self.Q

    @property
    def T(self) -> float:
        """Correlation window T = TBP/B (s)."""
        return self.tbp / self.B

    @property
    def lam_c(self) -> float:
        """Wavelength at the centre frequency, λ_c = c/f_c (m)."""
        return self.c / self.f_c

    @property
    def n(self) -> int:
        """Samples in one window at ``fs``: round(T·fs)."""
        return max(1, int(round(self.T * self.fs)))

    @cached_property
    def bins(self) -> np.ndarray:
        """DFT indices k ≥ 1 with |k/T − f_c| ≤ B/2 (at least the bin nearest f_c)."""
        lo = max(1, int(np.ceil((self.f_c - self.B / 2) * self.T - _EDGE_TOL)))
        hi = int(np.floor((self.f_c + self.B / 2) * self.T + _EDGE_TOL))
        if hi < lo:
            lo = hi = max(1, int(round(self.f_c * self.T)))
        return np.arange(lo, hi + 1)

    @cached_property
    def freqs(self) -> np.ndarray:
        """Bin frequencies f_k = k/T (Hz), shape (K,)."""
        return self.bins / self.T

    @property
    def K(self) -> int:
        """Number of bins in the band (≈ TBP)."""
        return int(self.bins.size)

    def phasor(self, tau: np.ndarray) -> np.ndarray:
        """e^{j2π f_k τ} on every band bin, shape τ.shape + (K,).

        The bins are evenly spaced (f_k = f_0 + k'/T), so a running product of the step
        e^{j2πτ/T} replaces K complex exponentials per τ (rounding ~K·1e-16)."""
        tau = np.asarray(tau, dtype=float)
        w = np.empty(tau.shape + (self.K,), dtype=complex)
        w[..., 0] = np.exp(2j * np.pi * self.freqs[0] * tau)
        w[..., 1:] = np.exp(2j * np.pi * tau / self.T)[..., None]
        return np.cumprod(w, axis=-1, out=w)
