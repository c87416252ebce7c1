"""A command from outside a scene's own law, for one tick: what a learning controller (``shoal.rl``)
hands an engine in place of what its law would decide.

An engine that can be steered has a ``steering`` attribute (None: its own law). The next
:meth:`step` takes it and clears it, and the tick runs as it always does, with every draw the
law makes (so each run's random stream is left where the law leaves it), except that

* ``velocity`` (R, N, k) replaces the command the law gives each robot: a world-frame velocity,
  or [v, w] in the body frame for a robot that turns (a differential drive, the non-omni
  controller). The kind limits it as it limits its own law's command (speed, acceleration,
  energy, turning radius), so the robots' physical limits hold; a command the law itself gave
  passes unchanged, to the bit;
* ``omega`` (R, N) and ``c`` (n, R, N) are the coefficients in force for the tick (ω, c_1 … c_n);
  a NaN keeps the kind's own value (a constant, the physical tuning, or DVC's), as does a term
  ``c`` leaves out.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

# A limit is applied where a command exceeds it by more than this (relative): rounding in a
# command the law already limited (a speed clipped to v_max, an energy scaled to e_max) must not
# scale it again, or a steered run would part from the law's run in the last bit.
SLACK = 1e-12


@dataclass(frozen=True)
class Steering:
    """One tick's command from outside the law (see the module)."""

    velocity: np.ndarray | None = None  # (R, N, k)
    omega: np.ndarray | None = None  # (R, N); NaN: the kind's own
    c: np.ndarray | None = None  # (n, R, N); NaN (or a term left out): the kind's own

    def runs(self, idx: np.ndarray) -> Steering:
        """The steering of runs ``idx`` only (an engine that advances some runs of a tick)."""
        return Steering(None if self.velocity is None else np.asarray(self.velocity)[idx],
                        None if self.omega is None else np.asarray(self.omega)[idx],
                        None if self.c is None else np.asarray(self.c)[:, idx])

    def coefficients(self, omega: np.ndarray | float, c: np.ndarray, shape: tuple[int, int]
                     ) -> tuple[np.ndarray | float, np.ndarray]:
        """The kind's own ``omega`` (a scalar or (R, N)) and ``c`` ((n,) or (n, R, N)) with the
        given ones in their place; unchanged when none are given."""
        if self.omega is None and self.c is None:
            return omega, c
        own_c: np.ndarray = np.asarray(c, dtype=float)
        n_own = int(own_c.shape[0])
        own_c = own_c.reshape((n_own,) + (1,) * (3 - own_c.ndim) + own_c.shape[1:])
        out_c = np.broadcast_to(own_c, (n_own, *shape)).astype(float)
        if self.c is not None:
            given = np.asarray(self.c, dtype=float)[: out_c.shape[0]]
            n = given.shape[0]
            out_c[:n] = np.where(np.isnan(given), out_c[:n], given)
        out_w: np.ndarray | float = omega
        if self.omega is not None:
            own_w = np.broadcast_to(np.asarray(omega, dtype=float), shape)
            out_w = np.where(np.isnan(self.omega), own_w, self.omega)
        return out_w, out_c


def given_coefficients(steering: Steering | None, terms: int, shape: tuple[int, int]
                       ) -> tuple[np.ndarray, np.ndarray] | None:
    """The given ω (R, N) and c (terms, R, N), NaN where the kind keeps its own; None if none
    are given (for a compiled tick that merges them itself)."""
    if steering is None or (steering.omega is None and steering.c is None):
        return None
    omega = np.full(shape, np.nan) if steering.omega is None else np.array(steering.omega, dtype=float)
    c = np.full((terms,) + shape, np.nan)
    if steering.c is not None:
        given = np.asarray(steering.c, dtype=float)[:terms]
        c[: given.shape[0]] = given
    return omega, c
