"""Underwater propagation and SNR (Ch. 6.1, 6.2.4, 7.3.2–7.3.3).

Transmission loss [6.1]–[6.6], the absorption fit of [6.5], the general SNR [6.7] and the
simulation form [7.13]–[7.17] in normalised units (Rossides §7.3.3, p. 162: noise intensity 1,
signal intensity (R_ref/r)²).

Ranges are clamped to ``R_FLOOR_M`` = 1 m, the reference distance of the source level:
inside it the spreading law does not hold, and the clamp keeps r = 0 finite (no NaN or
−inf). A source on top of a receiver is therefore heard at its 1 m level.
"""

from __future__ import annotations

from typing import Literal

import numpy as np

R_FLOOR_M = 1.0  # m: smallest range used anywhere in the acoustics (source level reference)
ALPHA0 = 6.35e-8  # dB/km per (rad/s)^1.5, fit of [6.5] to 0.001 dB/km @ 100 Hz, 1 dB/km @ 10 kHz
ETA = 1.5  # exponent of [6.5]
UPA2 = 1e-12  # Pa² per µPa²

Model = Literal["spherical", "cylindrical", "hybrid"]


def clamp_range(range_m: np.ndarray | float) -> np.ndarray:
    """Range in metres, floored at ``R_FLOOR_M`` (negative ranges map to the floor too)."""
    return np.maximum(np.asarray(range_m, dtype=float), R_FLOOR_M)


def alpha_abs(f_hz: np.ndarray | float) -> np.ndarray:
    """Absorption coefficient in dB/km at frequency ``f_hz``: α = α0·ω^η, ω = 2πf. [6.5]"""
    omega_ang = 2.0 * np.pi * np.abs(np.asarray(f_hz, dtype=float))
    return ALPHA0 * omega_ang**ETA


def received_level_db(
    Ls_db: np.ndarray | float,
    range_m: np.ndarray | float,
    model: Model = "spherical",
    alpha_db_per_km: float = 0.0,
    R1_km: float = 1.0,
    A_db_per_km: float = 0.0,
) -> np.ndarray:
    """Received level L (dB re 1 µPa) of a source of level ``Ls_db`` (dB re 1 µPa·m).

    - ``spherical``: L = Ls − 20 log R − αR − 60  [6.1], [6.3]
    - ``cylindrical``: L = Ls − 10 log R − αR − 60  [6.2], [6.4] (equals hybrid with
      R1 = 1 km; docs/readings.md, "The −60 in the spreading laws")
    - ``hybrid``: spherical to R1, then L = Ls − 10 log R1 − 10 log R − αR − AR − 60 [6.6];
      the two branches meet at R1, and αR + AR apply over the whole range.

    R is in km; ``range_m`` is clamped to 1 m.
    """
    R = clamp_range(range_m) / 1000.0
    Ls = np.asarray(Ls_db, dtype=float)
    absorb = alpha_db_per_km * R
    if model == "spherical":
        return Ls - 20.0 * np.log10(R) - absorb - 60.0
    if model == "cylindrical":
        return Ls - 10.0 * np.log10(R) - absorb - 60.0
    if model == "hybrid":
        spread = np.where(R <= R1_km, 20.0 * np.log10(R), 10.0 * np.log10(R1_km) + 10.0 * np.log10(R))
        return Ls - spread - absorb - A_db_per_km * R - 60.0
    raise ValueError(f"model: must be 'spherical', 'cylindrical' or 'hybrid', got {model!r}")


def snr_general_db(Ls_db: np.ndarray | float, noise_ms_pa2: np.ndarray | float,
                   range_m: np.ndarray | float) -> np.ndarray:
    """SNR [6.7] with NL = 10 log10(N / (1 µPa)²), N the mean-square noise in the band (Pa²);
    spherical spreading, range clamped to 1 m. See docs/readings.md, "Noise level units in the
    SNR [6.7]"."""
    R = clamp_range(range_m) / 1000.0
    nl = 10.0 * np.log10(np.asarray(noise_ms_pa2, dtype=float) / UPA2)
    return np.asarray(Ls_db, dtype=float) - nl - 20.0 * np.log10(R) - 60.0


def source_intensity(psd_s_db: np.ndarray | float, B: np.ndarray | float) -> np.ndarray:
    """Source intensity at 1 m, I_s = 10^(PSD_s/10)·1e-12·B in Pa². [7.14]"""
    return 10.0 ** (np.asarray(psd_s_db, dtype=float) / 10.0) * UPA2 * np.asarray(B, dtype=float)


def noise_intensity(psd_n_db: np.ndarray | float, B: np.ndarray | float) -> np.ndarray:
    """Noise intensity in the band, N = 10^(PSD_n/10)·1e-12·B in Pa² (text after [7.15])."""
    return 10.0 ** (np.asarray(psd_n_db, dtype=float) / 10.0) * UPA2 * np.asarray(B, dtype=float)


def r_ref(psd_s_db: np.ndarray | float, psd_n_db: np.ndarray | float) -> np.ndarray:
    """Range (m) where the SNR is 0 dB: R_ref = sqrt(I_s/N) = 10^((PSD_s−PSD_n)/20). [7.17]"""
    return 10.0 ** ((np.asarray(psd_s_db, dtype=float) - np.asarray(psd_n_db, dtype=float)) / 20.0)


def snr_db(r: np.ndarray | float, psd_s_db: np.ndarray | float, psd_n_db: np.ndarray | float) -> np.ndarray:
    """In-band per-sample SNR at range r (m): 10 log10(I_s/N) − 10 log10(r²). [7.16]
    B cancels; r is clamped to 1 m."""
    gain = np.asarray(psd_s_db, dtype=float) - np.asarray(psd_n_db, dtype=float)
    return gain - 20.0 * np.log10(clamp_range(r))


def source_distance_for_snr(snr0_db: np.ndarray | float, r_ref_m: np.ndarray | float) -> np.ndarray:
    """Source distance d_s giving SNR_0 at the origin: d_s = R_ref·10^(−SNR_0/20) ([7.16], [7.17])."""
    return np.asarray(r_ref_m, dtype=float) * 10.0 ** (-np.asarray(snr0_db, dtype=float) / 20.0)
