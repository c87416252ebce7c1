"""uPlot series for an acoustic swarm: pure functions of numbers, no viser.

* the selected robot's cross-correlation R(τ) over the lag window, τ in ms, with a
  vertical marker at the estimated τ_lag (height ρ);
* the distance from the swarm's centre of mass to the source vs time, with d_c;
* the SNR at every robot against its index (a stepped line: one step per robot).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .fleet_plots import _padded
from .plots import speed_scales

CORR = "rgb(40,90,200)"
MARK = "rgb(220,50,50)"


def corr_series() -> tuple[dict[str, Any], ...]:
    return (
        {"label": "τ [ms]"},
        {"label": "R(τ)", "stroke": CORR, "width": 2},
        {"label": "τ_lag", "stroke": MARK, "width": 2},
    )


def corr_data(lags: np.ndarray, corr: np.ndarray, tau: float, rho: float) -> tuple[np.ndarray, ...]:
    """(τ [ms], R(τ), marker): the lag grid with τ_lag inserted three times so that the marker
    series rises straight up from the floor of the plot to ρ at τ_lag and lies on the floor
    elsewhere. R(τ) is interpolated at the inserted points (so the curve is unchanged)."""
    lags = np.asarray(lags, dtype=float)
    corr = np.asarray(corr, dtype=float)
    if len(lags) < 2:
        return (np.array([0.0, 1e-6]), np.zeros(2), np.zeros(2))
    floor = float(min(corr.min(), 0.0))
    eps = 1e-9 * max(float(lags[-1] - lags[0]), 1e-12)
    extra = np.array([tau - eps, tau, tau + eps])
    x = np.concatenate([lags, extra])
    order = np.argsort(x, kind="stable")
    x = x[order]
    y = np.interp(x, lags, corr)
    mark = np.full(len(x), floor)
    is_peak = np.zeros(len(x), bool)
    is_peak[np.flatnonzero(order == len(lags) + 1)] = True
    mark[is_peak] = rho
    return (x * 1e3, y, mark)


def corr_scales(data: tuple[np.ndarray, ...]) -> dict[str, Any]:
    x, y, mark = data
    lo = float(min(y.min(), mark.min()))
    hi = float(max(y.max(), mark.max()))
    if hi <= lo:
        hi = lo + 1.0
    return {"x": {"time": False, "range": (float(x[0]), float(x[-1]))},
            "y": {"range": (lo, hi + 0.05 * (hi - lo))}}


def dist_series() -> tuple[dict[str, Any], ...]:
    return (
        {"label": "t [s]"},
        {"label": "|CoM − source| [m]", "stroke": "rgb(220,50,50)", "width": 2},
        {"label": "d_c", "stroke": "rgba(120,120,120,0.9)", "width": 1, "dash": (4.0, 4.0)},
    )


def dist_data(t: np.ndarray, dist: np.ndarray, d_c: float) -> tuple[np.ndarray, ...]:
    t, dist = _padded(t, dist)
    return (t, dist, np.full(len(t), float(d_c)))


def dist_scales(t: np.ndarray) -> dict[str, Any]:
    return speed_scales(t)


def snr_series() -> tuple[dict[str, Any], ...]:
    return (
        {"label": "robot"},
        {"label": "SNR [dB]", "stroke": "rgb(30,140,70)", "width": 2, "fill": "rgba(30,140,70,0.25)"},
        {"label": "0 dB", "stroke": "rgba(120,120,120,0.9)", "width": 1, "dash": (4.0, 4.0)},
    )


def snr_data(snr: np.ndarray) -> tuple[np.ndarray, ...]:
    """A bar-like stepped outline: robot i spans [i − 0.4, i + 0.4] at height SNR_i."""
    snr = np.asarray(snr, dtype=float)
    n = len(snr)
    if n == 0:
        return (np.array([0.0, 1.0]), np.zeros(2), np.zeros(2))
    i = np.arange(n, dtype=float)
    x = np.stack([i - 0.45, i - 0.4, i + 0.4, i + 0.45], axis=1).ravel()
    base = float(min(snr.min(), 0.0))
    y = np.stack([np.full(n, base), snr, snr, np.full(n, base)], axis=1).ravel()
    return (x, y, np.zeros(len(x)))


def snr_scales(snr: np.ndarray) -> dict[str, Any]:
    snr = np.asarray(snr, dtype=float)
    n = len(snr)
    lo = float(min(snr.min(initial=0.0), 0.0))
    hi = float(max(snr.max(initial=0.0), 0.0))
    return {"x": {"time": False, "range": (-0.6, n - 0.4)}, "y": {"range": (lo - 1.0, hi + 2.0)}}
