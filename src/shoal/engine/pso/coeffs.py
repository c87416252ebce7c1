"""Coefficient policies: how ω and c_1..c_n are set each control step (Rossides §3.4, p. 73;
§4.2.2, p. 90).

A policy is asked once per tick for ``(omega, c)`` with ``c`` of shape ``(n,)``; later
policies (DVC) return per-robot arrays ``(n, runs, robots)`` through the same call.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property
from typing import Protocol

import numpy as np

from . import tuning


class CoefficientPolicy(Protocol):
    def coefficients(self, t: float, dt: float, d: int) -> tuple[np.ndarray | float, np.ndarray]: ...


@dataclass(frozen=True)
class Constant:
    """Raw coefficients chosen by the user (ω, c1, c2, ...)."""

    omega: float
    c: tuple[float, ...]

    @cached_property
    def _c(self) -> np.ndarray:
        c = np.asarray(self.c, dtype=float)
        c.setflags(write=False)
        return c

    def coefficients(self, t: float, dt: float, d: int) -> tuple[float, np.ndarray]:
        return self.omega, self._c


@dataclass(frozen=True)
class Segment:
    """From time ``t_start`` on, the robot limits are U and A+ (the step changes of Fig. 3-5, p. 78;
    docs/readings.md, "Step changes in Figures 3-5b and 3-5c")."""

    t_start: float
    U: float
    A_plus: float


@dataclass(frozen=True)
class Physical:
    """Physical tuning: from (U, A+, Δt, d) derive ω, ĉ [3.32]–[3.35], split c1:c2.

    Several segments make the step changes of Fig. 3-5; with one segment it is the
    plain guideline of Rossides §3.4 (p. 73). ``c1_share`` = c1/ĉ.
    """

    segments: tuple[Segment, ...]
    c1_share: float = 0.5
    _cache: dict = field(default_factory=dict, compare=False, repr=False)

    def __post_init__(self) -> None:
        if not self.segments:
            raise ValueError("Physical policy needs at least one segment")

    def segment_at(self, t: float) -> Segment:
        current = self.segments[0]
        for seg in self.segments:
            if t + 1e-9 >= seg.t_start:
                current = seg
        return current

    def tuning_at(self, t: float, dt: float, d: int) -> tuning.Tuning:
        seg = self.segment_at(t)
        key = (seg, dt, d)
        if key not in self._cache:
            self._cache[key] = tuning.from_limits(dt, seg.U, A_plus=seg.A_plus, d=d)
        return self._cache[key]

    def coefficients(self, t: float, dt: float, d: int) -> tuple[float, np.ndarray]:
        tun = self.tuning_at(t, dt, d)
        return tun.omega, np.asarray(tuning.split(tun.c_hat, self.c1_share))
