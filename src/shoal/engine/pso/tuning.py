"""Physical tuning of Adapted PSO (Rossides §3.3–3.4, [3.26]–[3.35], [4.11]–[4.12]).

Convert between the controller's coefficients (ω, ĉ, Δt) and the robot's limits
(U, A+, A−) through the sensitivity factor β = A+Δt/U.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass


class TuningError(ValueError):
    """Raised when requested limits cannot be met by an Adapted PSO controller."""


@dataclass(frozen=True)
class Tuning:
    """One consistent set of controller coefficients and robot limits."""

    dt: float
    d: int
    omega: float
    c_hat: float
    beta: float
    U: float  # vector top speed [3.29]
    A_plus: float  # vector top acceleration [3.30]
    A_minus: float  # vector top deceleration (magnitude) [3.31]

    @property
    def U_j(self) -> float:
        """Per-component top speed ĉ/(1 − ω) [3.26]."""
        return self.U / math.sqrt(self.d)

    @property
    def A_plus_j(self) -> float:
        """Per-component top acceleration ĉ/Δt [3.27]."""
        return self.A_plus / math.sqrt(self.d)

    @property
    def A_minus_j(self) -> float:
        """Per-component top deceleration 2ĉ/Δt [3.28] (magnitude; docs/readings.md, "The sign of the top
        deceleration A−")."""
        return self.A_minus / math.sqrt(self.d)

    def as_dict(self) -> dict[str, float]:
        out = asdict(self)
        out.update(U_j=self.U_j, A_plus_j=self.A_plus_j, A_minus_j=self.A_minus_j)
        return out


def _check_positive(**values: float) -> None:
    for name, value in values.items():
        if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
            raise TuningError(f"{name} must be a finite number > 0, got {value!r}")


def from_limits(
    dt: float, U: float, A_plus: float | None = None, A_minus: float | None = None, d: int = 1
) -> Tuning:
    """Guideline of §3.4: from (Δt, U, A+ or A−, d) compute β [3.34], ω [3.35] and ĉ [3.32].

    Refuses β outside (0, 1]: β > 1 would need ω < 0, i.e. the controller is too slow
    for the requested acceleration and Δt must shrink.
    """
    if (A_plus is None) == (A_minus is None):
        raise TuningError("give exactly one of A_plus or A_minus")
    if A_plus is None:
        _check_positive(A_minus=A_minus)  # type: ignore[arg-type]
        A_plus = A_minus / 2.0  # type: ignore[operator]  # [3.31] (A_minus checked just above)
    _check_positive(dt=dt, U=U, A_plus=A_plus)
    if d < 1:
        raise TuningError(f"d must be >= 1, got {d}")
    beta = A_plus * dt / U  # [3.34]
    if beta > 1.0 + 1e-12:
        raise TuningError(
            f"beta = A+·dt/U = {beta:.3g} > 1: the controller must be faster "
            f"(dt <= U/A+ = {U / A_plus:.3g} s) or the acceleration lower "
            f"(A+ <= U/dt = {U / dt:.3g} m/s²)"
        )
    beta = min(beta, 1.0)
    return Tuning(
        dt=dt,
        d=d,
        omega=1.0 - beta,  # [3.35]
        c_hat=A_plus * dt / math.sqrt(d),  # [3.32]
        beta=beta,
        U=U,
        A_plus=A_plus,
        A_minus=2.0 * A_plus,  # [3.31]
    )


def from_beta(dt: float, U: float, beta: float, d: int = 1) -> Tuning:
    """Choose β directly (docs/readings.md, "Setting β directly"): A+ = βU/Δt, ĉ = βU/√d [4.15]."""
    _check_positive(dt=dt, U=U, beta=beta)
    return from_limits(dt, U, A_plus=beta * U / dt, d=d)


def from_coefficients(omega: float, c_hat: float, dt: float, d: int = 1) -> Tuning:
    """Inverse: the limits an Adapted PSO with (ω, ĉ, Δt) imposes, [3.29]–[3.31]."""
    _check_positive(c_hat=c_hat, dt=dt)
    if not (0.0 <= omega < 1.0):
        raise TuningError(f"omega must be in [0, 1) for bounded speed [3.14], got {omega!r}")
    root_d = math.sqrt(d)
    return Tuning(
        dt=dt,
        d=d,
        omega=omega,
        c_hat=c_hat,
        beta=1.0 - omega,
        U=c_hat * root_d / (1.0 - omega),
        A_plus=c_hat * root_d / dt,
        A_minus=2.0 * c_hat * root_d / dt,
    )


def split(c_hat: float, c1_share: float) -> tuple[float, float]:
    """Split ĉ = c1 + c2 with c1 = share·ĉ (the thesis leaves the split open:
    docs/readings.md, "Unstated settings of Section 3.5")."""
    if not 0.0 <= c1_share <= 1.0:
        raise TuningError(f"c1_share must be in [0, 1], got {c1_share!r}")
    return c_hat * c1_share, c_hat * (1.0 - c1_share)


def term_budget(c_n: float, beta: float, dt: float, d: int = 1) -> tuple[float, float]:
    """Per-term limits (U_n, A_n+) of [4.11]–[4.12]."""
    _check_positive(beta=beta, dt=dt)
    A_n = c_n * math.sqrt(d) / dt
    return A_n * dt / beta, A_n
