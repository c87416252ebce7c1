"""Velocity laws of the PSO family (Rossides Ch. 2 and 3) and their registry :data:`LAWS`.

Arrays follow one convention: positions and velocities are ``(runs, robots, d)``;
the ``n`` accelerating terms are stacked on a leading axis, so direction inputs and
random draws are ``(n, runs, robots, d)`` and coefficients ``c`` are ``(n,)`` or
``(n, runs, robots)``; ``omega`` is a scalar or ``(runs, robots)``.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import Any, Callable, Literal

import numpy as np

from ..core.registry import Registry
from . import stability

Squash = Literal["sgn", "tanh", "logistic"]


def squash(z: np.ndarray, kind: Squash = "sgn", width: float = 1.0) -> np.ndarray:
    """Bounded per-component direction of ``z``.

    ``sgn`` is [3.12] with sgn(0) = 0; ``tanh`` and ``logistic`` (squashed to (-1, 1))
    are the smooth options of Rossides §3.2.1 (p. 64) against chattering: sgn-like when the attractor is
    far compared with ``width`` (metres), proportional like standard PSO when close.
    """
    if kind == "sgn":
        return np.sign(z)
    if width <= 0:
        raise ValueError(f"smooth width must be > 0, got {width}")
    with np.errstate(over="ignore"):  # z/width = ±inf saturates to ±1, as intended
        if kind == "tanh":
            return np.tanh(z / width)
        if kind == "logistic":
            from scipy.special import expit  # (scipy.special takes a fifth of a second to import: only here)

            return 2.0 * expit(z / width) - 1.0
    raise ValueError(f"unknown squash {kind!r}")


def _coeffs(c: np.ndarray | float, ndim: int) -> np.ndarray:
    """Shape ``c`` of ``(n,)`` or ``(n, runs, robots)`` to broadcast against ``(n, runs, robots, d)``."""
    c = np.asarray(c, dtype=float)
    return c.reshape(c.shape + (1,) * (ndim - c.ndim))


def _omega(omega: np.ndarray | float) -> np.ndarray:
    omega = np.asarray(omega, dtype=float)
    return omega[..., None] if omega.ndim else omega


def standard_velocity(
    u: np.ndarray, g: np.ndarray, c: np.ndarray, omega: np.ndarray | float, r: np.ndarray
) -> np.ndarray:
    """Standard PSO [2.1]: ``u' = ω u + Σ c_n r_n ∘ g_n`` with ``g_n = y_n − x`` (unbounded)."""
    terms = _coeffs(c, g.ndim) * r * g
    return _omega(omega) * u + terms.sum(axis=0)


def adapted_velocity(
    u: np.ndarray,
    g: np.ndarray,
    c: np.ndarray,
    omega: np.ndarray | float,
    r: np.ndarray,
    kind: Squash = "sgn",
    width: float = 1.0,
) -> np.ndarray:
    """Generalised Adapted PSO [3.36]: ``u' = ω u + Σ c_n r_n ∘ sgn(g_n)``.

    With two terms g = (y − x, y_g − x) this is Adapted PSO [3.11]. Each term adds at most
    c_n per component, so |u_j| ≤ ĉ/(1 − ω) [3.26] once it holds, for 0 ≤ ω < 1.
    """
    terms = _coeffs(c, g.ndim) * r * squash(g, kind, width)
    return _omega(omega) * u + terms.sum(axis=0)


def reachable(command: np.ndarray, u: np.ndarray, c: np.ndarray, omega: np.ndarray | float) -> np.ndarray:
    """``command`` clipped, component by component, to what an Adapted law [3.36] can reach from
    ``u`` in one tick: ω u ± Σ |c_n| (each term adds at most c_n). So |u_j| ≤ ĉ/(1 − ω) = U_j holds
    once it holds [3.26], and the acceleration stays within A+ and A− [3.27]–[3.28]. Rounding is
    monotone, so the law's own next velocity lies inside and passes unchanged."""
    wu = _omega(omega) * u
    reach = np.abs(_coeffs(c, u.ndim + 1)).sum(axis=0)
    return np.minimum(np.maximum(command, wu - reach), wu + reach)


# (u, g, c, omega, r, smooth width) → u[k+1]
Velocity = Callable[[np.ndarray, np.ndarray, np.ndarray, "np.ndarray | float", np.ndarray, float], np.ndarray]


Region = Literal["adapted", "order-2"]  # the (ω, ĉ) regions the panel draws: [3.13]/[3.14] or [3.9]


@dataclass(frozen=True)
class VelocityLaw:
    """One Chapter 3 velocity law and what the rest of Shoal needs to know about it: how it
    moves, its coefficient rule and its stability region.

    ``name`` is the preset's ``controller.law``, ``label`` what a panel shows; ``adapted``: bounded
    per-component terms with the position update x + Δt u (the physical tuning U, A+, Δt and the
    speed bounds need it); ``velocity(u, g, c, omega, r, width)``: the next velocities (see
    :func:`standard_velocity`); ``omega_range`` (lo, hi): the raw ω it needs, lo ≤ ω < hi, with
    ``rule`` the rule in words that a refusal names; ``region``: its stability region in the
    (ω, ĉ) plane, ``"adapted"`` [3.13]–[3.14] or ``"order-2"`` [3.9], which the panel draws."""

    name: str
    label: str
    adapted: bool  # bounded per-component terms [3.11] with the position update x + Δt u [3.10]; the
    # physical tuning (U, A+, Δt → ω, ĉ [3.32]–[3.35]) and the speed bounds U, U_j [3.26] apply
    velocity: Velocity
    omega_range: tuple[float, float] | None = None  # raw-mode ω it needs, lo <= ω < hi (None: the model's range)
    region: Region = "order-2"  # its stability region in the (ω, ĉ) plane
    rule: str = ""  # the coefficient rule in words, with its equation (the preset names it when refused)

    def check_omega(self, omega: float) -> str | None:
        """Why raw ``omega`` does not suit this law (None if it does)."""
        if self.omega_range is None:
            return None
        lo, hi = self.omega_range
        return None if lo <= omega < hi else f"omega = {omega:g}: {self.label} needs {self.rule}"

    def check(self, omega: float | np.ndarray, c: Any) -> str | None:
        """The law's coefficient rule, the one place it is applied (the preset model, the engine's
        constructor and retune, so ``make``, ``Scene.retune`` and the app): why raw ``omega`` and
        the coefficients ``c`` do not suit this law, or None. Every c_n must be a finite number
        ≥ 0, and ω within the law's range (``omega_range``, e.g. 0 ≤ ω < 1 [3.14])."""
        cs = np.asarray(c, dtype=float)
        if not np.isfinite(cs).all() or (cs < 0).any():
            return f"c = {np.round(cs.ravel(), 6).tolist()}: {self.label} needs finite coefficients c_n >= 0"
        w = np.asarray(omega, dtype=float)
        if not np.isfinite(w).all():
            return f"omega = {omega}: not a number"
        for value in np.unique(w):
            why = self.check_omega(float(value))
            if why:
                return why
        return None

    def stable(self, omega: float, c_hat: float) -> bool:
        """Is (ω, ĉ) inside this law's stability region?"""
        if self.region == "adapted":
            return bool(stability.adapted_stable(omega, c_hat, robot_subset=True))
        return bool(stability.order2_stable(omega, c_hat))

    @property
    def c_unit(self) -> str:
        """The unit of ĉ = Σ c_n: a speed for a law that moves by Δt u, none for standard PSO."""
        return "m/s" if self.adapted else ""


def _standard(u: np.ndarray, g: np.ndarray, c: np.ndarray, omega: np.ndarray | float, r: np.ndarray,
              width: float) -> np.ndarray:
    return standard_velocity(u, g, c, omega, r)


def _adapted_law(u: np.ndarray, g: np.ndarray, c: np.ndarray, omega: np.ndarray | float, r: np.ndarray,
                 width: float, *, kind: Squash) -> np.ndarray:
    return adapted_velocity(u, g, c, omega, r, kind, width)


def _adapted(kind: Squash) -> Velocity:
    """[3.11] with the squash ``kind``: a partial of a module function, so a law pickles."""
    return functools.partial(_adapted_law, kind=kind)


_ADAPTED_RULE: dict[str, Any] = dict(omega_range=(0.0, 1.0), region="adapted", rule="0 <= omega < 1 [3.14]")
LAWS: Registry[VelocityLaw] = Registry(
    "law",
    VelocityLaw("standard", "Standard PSO", False, _standard),  # [2.1], [2.2]; order-2 region [3.9]
    VelocityLaw("adapted-sgn", "Adapted PSO (sgn)", True, _adapted("sgn"), **_ADAPTED_RULE),  # [3.11]
    VelocityLaw("adapted-tanh", "Adapted PSO (tanh)", True, _adapted("tanh"),  # Rossides §3.2.1 smooth option
                **_ADAPTED_RULE),
    VelocityLaw("adapted-logistic", "Adapted PSO (logistic)", True, _adapted("logistic"), **_ADAPTED_RULE),
)


@dataclass(frozen=True)
class Law:
    """A velocity law of :data:`LAWS` (by name) plus its position update."""

    name: str = "adapted-sgn"
    smooth_width: float = 1.0

    def __post_init__(self) -> None:
        LAWS.pick(self.name)

    @property
    def adapted(self) -> bool:
        return LAWS[self.name].adapted

    def velocity(
        self, u: np.ndarray, g: np.ndarray, c: np.ndarray, omega: np.ndarray | float, r: np.ndarray
    ) -> np.ndarray:
        return LAWS[self.name].velocity(u, g, c, omega, r, self.smooth_width)

    def position(self, x: np.ndarray, u_new: np.ndarray, dt: float) -> np.ndarray:
        """[3.10] ``x + Δt u[k+1]`` for Adapted laws; [2.2] ``x + u[k+1]`` for standard PSO."""
        return x + (dt * u_new if self.adapted else u_new)


def motion_heading(u: np.ndarray, previous: np.ndarray, moving: np.ndarray | None = None) -> np.ndarray:
    """Direction of motion atan2(u_2, u_1) (docs/readings.md, "Heading of an omnidirectional robot"); kept from before
    while the robot is at rest (``moving``: any component of u non-zero). In 1-D: 0 or π by
    the sign of u."""
    if u.shape[-1] < 2:
        h = np.where(u[..., 0] < 0, np.pi, 0.0)
    else:
        h = np.arctan2(u[..., 1], u[..., 0])
    if moving is None:
        moving = np.any(u != 0, axis=-1)
    return np.where(moving, h, previous)
