"""SLO candidate positions of a neighbour (Mai §3.5.1–3.5.2): the mirror pair x1, x2 from
the triangle (A, B_{t−1}, B_t) and dead reckoning x3, with the mitigation tests.

Vectorised over any leading shape (typically runs × observers × neighbours). Every singular
input (zero or failed range, |v| = 0, cos α outside [−1, 1], non-finite values) falls back to
x3 and never yields NaN. :class:`Flag` says why a set is what it is, :class:`Kind` which
candidate an estimate took.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import IntEnum

import numpy as np


class Flag(IntEnum):
    """Why a candidate set is what it is (for the triangle inspector)."""

    GEOMETRIC = 0  # {x1, x2, x3}
    FALLBACK = 1  # range failure, |v| = 0 or non-finite input: {x3}
    MITIGATED_V = 2  # thin triangle [3.6]: {x3}
    MITIGATED_COS = 3  # arccos singularity [3.5]: {x3}


class Kind(IntEnum):
    """Where an estimate came from (for the ghost overlay and the dead-reckoning share)."""

    NONE = 0  # no estimate held this step (not a neighbour)
    X1 = 1  # geometric candidate x1 (CSS: blended with x3 by w)
    X2 = 2  # geometric candidate x2
    X3 = 3  # dead reckoning
    INITIAL = 4  # the initial estimate, before any localisation
    PERFECT = 5  # oracle baseline


@dataclass(frozen=True)
class Candidates:
    """Candidate sets of many ordered pairs."""

    points: np.ndarray  # (..., 3, 2): x1, x2, x3
    mask: np.ndarray  # (..., 3) which candidates exist (x3 always)
    flag: np.ndarray  # (...) int8, :class:`Flag`
    cos_alpha: np.ndarray  # (...) cos α before clipping, NaN where not computed
    thinness: np.ndarray  # (...) min(|v|/d0, |v|/d1), NaN where not computed

    @property
    def geometric(self) -> np.ndarray:
        return self.mask[..., 0]

    @property
    def x3(self) -> np.ndarray:
        return self.points[..., 2, :]


def candidates(
    d0: np.ndarray,
    d1: np.ndarray,
    v: np.ndarray,
    prev: np.ndarray,
    delta_cos: float = 0.03,
    delta_v: float = 0.03,
    literal_eq_3_1: bool = False,
) -> Candidates:
    """Candidates for ranges ``d0`` = d*(t−1), ``d1`` = d*(t), relative displacement
    ``v`` = v*_j − v*_i (..., 2) and previous estimate ``prev`` (..., 2).

    cos α = (d1² + |v|² − d0²)/(2|v|·d1) (docs/readings.md, "The denominator of [3.1]";
    ``literal_eq_3_1`` keeps the printed d0 in the denominator);
    x1,2 = d1·(c·u ± s·u⊥) [3.2]–[3.3] in vector form; x3 = prev + v [3.4].
    ``delta_cos = -inf`` only clips cos α to [−1, 1] (footnote of Mai §3.5.2, p. 28)."""
    d0 = np.asarray(d0, dtype=float)
    d1 = np.asarray(d1, dtype=float)
    v = np.asarray(v, dtype=float)
    prev = np.asarray(prev, dtype=float)
    with np.errstate(all="ignore"):
        x3 = prev + v  # [3.4]; see docs/readings.md, "The index of v* in [3.4]"
        speed = np.linalg.norm(v, axis=-1)
        ok = (d0 > 0) & (d1 > 0) & (speed > 0) & np.isfinite(d0) & np.isfinite(d1) & np.isfinite(speed)
        ok &= np.all(np.isfinite(x3), axis=-1)
        s0, s1, sv = np.where(ok, d0, 1.0), np.where(ok, d1, 1.0), np.where(ok, speed, 1.0)
        thin = np.minimum(sv / s0, sv / s1)
        thin_ok = ~(thin <= delta_v)  # [3.6]; see docs/readings.md, '"And" or "or" in [3.6]'
        denom = 2.0 * sv * (s0 if literal_eq_3_1 else s1)  # [3.1]; "The denominator of [3.1]"
        c = (s1**2 + sv**2 - s0**2) / denom
        c = np.where(np.isfinite(c), c, 2.0)
        cos_ok = ~(1.0 - np.abs(c) <= delta_cos)  # [3.5]
        geometric = ok & thin_ok & cos_ok
        cc = np.clip(c, -1.0, 1.0)
        sn = np.sqrt(1.0 - cc**2)
        u = v / sv[..., None]
        perp = np.stack([u[..., 1], -u[..., 0]], axis=-1)
        along = (s1 * cc)[..., None] * u
        across = (s1 * sn)[..., None] * perp
        x1 = np.where(geometric[..., None], along + across, x3)
        x2 = np.where(geometric[..., None], along - across, x3)
    flag = np.full(geometric.shape, Flag.MITIGATED_COS, dtype=np.int8)
    flag[geometric] = Flag.GEOMETRIC
    flag[ok & ~thin_ok] = Flag.MITIGATED_V
    flag[~ok] = Flag.FALLBACK
    mask = np.stack([geometric, geometric, np.ones_like(geometric)], axis=-1)
    return Candidates(
        points=np.stack([x1, x2, x3], axis=-2),
        mask=mask,
        flag=flag,
        cos_alpha=np.where(ok, c, np.nan),
        thinness=np.where(ok, thin, np.nan),
    )
