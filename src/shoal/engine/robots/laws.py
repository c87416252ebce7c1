"""Velocity laws and motion helpers of Rossides Ch. 4 (RPSO) and Ch. 5 (robot frame), and the
registry of the fleet's laws :data:`ROBOT_LAWS`.

Shapes follow :mod:`shoal.engine.pso.laws`: positions and velocities ``(runs, robots, 2)``, headings and
scalar speeds ``(runs, robots)``; the ``n`` accelerating terms are stacked on a leading
axis. Body frame: x along the heading, y to the left; w > 0 turns left (CCW); docs/readings.md,
"Body frame and turn direction".
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Literal

import numpy as np

from ..core.registry import Registry
from ..pso.laws import Squash, adapted_velocity, squash, standard_velocity

Inertia = Literal["pi", "disc"]

# --------------------------------------------------------------------------- Chapter 4


def _shrink(size: np.ndarray, limit: float | np.ndarray) -> np.ndarray:
    """Factor min(1, limit/size), computed only where size exceeds the limit."""
    size, limit = np.broadcast_arrays(np.asarray(size, dtype=float), np.asarray(limit, dtype=float))
    return np.divide(limit, size, out=np.ones_like(size), where=size > limit)


def clip_speed(u: np.ndarray, v_max: float | np.ndarray, slack: float = 0.0) -> np.ndarray:
    """Scale each vector of ``u`` (..., d) down to length ``v_max``, keeping its direction (only
    those longer than ``v_max·(1 + slack)``)."""
    speed = np.linalg.norm(u, axis=-1, keepdims=True)
    v_max = np.asarray(v_max, dtype=float)
    if v_max.ndim:
        v_max = v_max[..., None]
    if slack:
        return u * np.divide(v_max, speed, out=np.ones_like(speed), where=speed > v_max * (1.0 + slack))
    return u * _shrink(speed, v_max)


def rpso_velocity(
    u: np.ndarray,
    g_personal: np.ndarray,
    g_global: np.ndarray,
    F_t: np.ndarray,
    c: np.ndarray,
    omega: np.ndarray | float,
    r: np.ndarray,
    v_max: float | None = None,
) -> np.ndarray:
    """Original RPSO [4.2]: ``ω u + c1 r1∘(y − x) + c2 r2∘(y_g − x) + c3 r3∘F_t``.

    ``g_personal`` = y − x and ``g_global`` = y_g − x are (R, N, 2); ``c`` is (3,) or
    (3, R, N); ``r`` is (3, R, N, 2). The law is unbounded; with ``v_max`` the result is
    clipped to that speed keeping its direction (docs/readings.md, "Speed limit of Original RPSO").
    """
    g = np.stack([g_personal, g_global, F_t])
    out = standard_velocity(u, g, c, omega, r)
    return out if v_max is None else clip_speed(out, v_max)


def adapted_rpso_velocity(
    u: np.ndarray,
    g_personal: np.ndarray,
    g_global: np.ndarray,
    F_t: np.ndarray,
    c: np.ndarray,
    omega: np.ndarray | float,
    r: np.ndarray,
    kind: Squash = "sgn",
    width: float = 1.0,
) -> np.ndarray:
    """Adapted RPSO [4.5]: ``ω u + c1 r1∘sgn(y − x) + c2 r2∘sgn(y_g − x) + c3 r3∘sgn(F_t)``."""
    return adapted_velocity(u, np.stack([g_personal, g_global, F_t]), c, omega, r, kind, width)


# --------------------------------------------------------------------------- body frame


def to_body(vec: np.ndarray, heading: np.ndarray | float) -> np.ndarray:
    """Rot(−o)·vec: a world-frame vector (R, N, 2) in the robot frame ([5.4]; docs/readings.md, "Body frame and turn
    direction")."""
    cos, sin = np.cos(heading), np.sin(heading)
    x, y = vec[..., 0], vec[..., 1]
    return np.stack([cos * x + sin * y, -sin * x + cos * y], axis=-1)


def to_world(vec: np.ndarray, heading: np.ndarray | float) -> np.ndarray:
    """Rot(o)·vec: a robot-frame vector (R, N, 2) in the world frame [5.8]."""
    cos, sin = np.cos(heading), np.sin(heading)
    x, y = vec[..., 0], vec[..., 1]
    return np.stack([cos * x - sin * y, sin * x + cos * y], axis=-1)


def wrap_angle(a: np.ndarray | float) -> np.ndarray:
    """Wrap angles to (−π, π]."""
    out = np.pi - np.mod(np.pi - np.asarray(a, dtype=float), 2.0 * np.pi)
    return np.where(out <= -np.pi, out + 2.0 * np.pi, out)


# --------------------------------------------------------------------------- Chapter 5


def robot_centred_velocity(
    vw: np.ndarray,
    y_tilde: np.ndarray,
    c: np.ndarray,
    omega: np.ndarray | float,
    r: np.ndarray,
    kind: Squash = "sgn",
    width: float = 1.0,
) -> np.ndarray:
    """Generalised Adapted PSO in the robot frame [5.4]: ``ũ' = ω∘ũ + Σ c_n∘r_n∘sgn(ỹ_n)``.

    ``vw`` (R, N, 2) is [v; w] (or [v1; v2]); ``y_tilde`` and ``r`` are (n, R, N, 2);
    ``c`` is (n, 2) or (n, R, N, 2); ``omega`` is a scalar, (2,) or (R, N, 2).
    """
    c = np.asarray(c, dtype=float)
    if c.ndim == 2:
        c = c.reshape(c.shape[0], *(1,) * (y_tilde.ndim - 2), c.shape[1])
    return np.asarray(omega, dtype=float) * vw + (c * r * squash(y_tilde, kind, width)).sum(axis=0)


def nonomni_velocity(
    vw: np.ndarray,
    y_tilde: np.ndarray,
    yg_tilde: np.ndarray,
    c: np.ndarray,
    omega: np.ndarray | float,
    r: np.ndarray,
    kind: Squash = "sgn",
    width: float = 1.0,
) -> np.ndarray:
    """Non-omnidirectional controller [5.13], returns [v; w] (R, N, 2).

    ``w' = ω w + c1 r1 sgn(ỹ_2) + c2 r2 sgn(ỹ_g,2) − c3 r3 + c4 r4`` and
    ``v' = ω v + c5 r5``. ``y_tilde``/``yg_tilde`` are body-frame offsets (R, N, 2) of
    which only the lateral component is used; ``c`` is (5,) or (5, R, N); ``r`` is
    (5, R, N); ``omega`` a scalar or (R, N). v is floored at 0 (forward only, Rossides §5.2, p. 114),
    which is a no-op for v ≥ 0, ω ≥ 0, c5 ≥ 0.
    """
    c = np.asarray(c, dtype=float)
    cr = c.reshape(c.shape + (1,) * (r.ndim - c.ndim)) * r
    omega = np.asarray(omega, dtype=float)
    lat = squash(y_tilde[..., 1], kind, width)
    lat_g = squash(yg_tilde[..., 1], kind, width)
    w = omega * vw[..., 1] + cr[0] * lat + cr[1] * lat_g - cr[2] + cr[3]  # [5.13] tasks 1–4
    v = np.maximum(omega * vw[..., 0] + cr[4], 0.0)  # [5.13] task 5
    return np.stack([v, w], axis=-1)


def rotational_energy_factor(inertia: Inertia = "pi", body_radius: float | None = None) -> float:
    """k in e_r = k·w²: π/4 as printed [5.12], or R_b²/4 for a disc (docs/readings.md, "Rotational energy [5.12]")."""
    if inertia == "pi":
        return np.pi / 4.0
    if inertia == "disc":
        if body_radius is None or not body_radius > 0:
            raise ValueError(f"inertia='disc' needs body_radius > 0, got {body_radius!r}")
        return body_radius**2 / 4.0
    raise ValueError(f"unknown inertia reading {inertia!r}")


def energy_limit(
    v: np.ndarray,
    w: np.ndarray,
    v_max: float | np.ndarray,
    inertia: Inertia = "pi",
    body_radius: float | None = None,
    slack: float = 0.0,
) -> tuple[np.ndarray, np.ndarray]:
    """Shrink (v, w) by one factor λ = √(e_max/e_t) where e_t > e_max (docs/readings.md,
    "Scaling v and w to the energy budget"; with ``slack``, only where e_t > e_max·(1 + slack)).

    e_l = v²/2 [5.11], e_r = k w² [5.12], e_max = v_max²/2; the turning radius v/w is kept.
    """
    v, w = np.asarray(v, dtype=float), np.asarray(w, dtype=float)
    e_t = 0.5 * v**2 + rotational_energy_factor(inertia, body_radius) * w**2
    e_max = 0.5 * np.asarray(v_max, dtype=float) ** 2
    over = e_t > (e_max * (1.0 + slack) if slack else e_max)
    lam = np.where(over, np.sqrt(e_max / np.where(over, e_t, 1.0)), 1.0)
    return v * lam, w * lam


def min_turning_radius(v: np.ndarray, w: np.ndarray, r_min: float) -> np.ndarray:
    """Limit |w| so that |v/w| ≥ r_min [5.6], keeping v (Rossides §5.4, p. 125; docs/readings.md, "Minimum
    turning radius and clearance"); r_min = 0 disables."""
    if r_min < 0:
        raise ValueError(f"r_min must be >= 0, got {r_min!r}")
    w = np.asarray(w, dtype=float)
    if r_min == 0:
        return w
    return np.sign(w) * np.minimum(np.abs(w), np.abs(v) / r_min)


def arc_pose_update(
    x: np.ndarray, heading: np.ndarray, v: np.ndarray, w: np.ndarray, dt: float
) -> tuple[np.ndarray, np.ndarray]:
    """Move along a circular arc [5.5]–[5.10]; returns (x (R, N, 2), heading (R, N)).

    With θ = wΔt the body-frame step r·[sin θ; 1 − cos θ], r = v/w, is written as
    vΔt·[sinc θ; sin(θ/2)·sinc(θ/2)], which is exact, needs no division and tends to the
    straight line [5.7] as w → 0. The heading is wrapped to (−π, π].
    """
    theta = np.asarray(w, dtype=float) * dt
    step = np.asarray(v, dtype=float) * dt
    along = step * np.sinc(theta / np.pi)  # r sin θ  [5.5]
    lateral = step * np.sin(0.5 * theta) * np.sinc(theta / (2.0 * np.pi))  # r (1 − cos θ)
    dx = to_world(np.stack([along, lateral], axis=-1), heading)  # [5.8]
    return x + dx, wrap_angle(heading + theta)  # [5.9], [5.10]


# --------------------------------------------------------------------------- mecanum


def _m419(L: float) -> np.ndarray:
    return np.array([[1.0, -1.0, -L], [1.0, 1.0, L], [1.0, 1.0, -L], [1.0, -1.0, L]])


def _m418(L: float) -> np.ndarray:
    return np.array([[1.0, 1.0, 1.0, 1.0], [-1.0, 1.0, 1.0, -1.0], [-1 / L, 1 / L, -1 / L, 1 / L]])


def mecanum_wheels(vx, vy, wz, r_w: float, L: float) -> np.ndarray:
    """Wheel speeds (..., 4) for a body-frame twist [4.19]; L = l_x + l_y, r_w wheel radius."""
    twist = np.stack(np.broadcast_arrays(*(np.asarray(a, dtype=float) for a in (vx, vy, wz))), -1)
    return twist @ _m419(L).T / r_w


def mecanum_body(
    wheels: np.ndarray, r_w: float, L: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Body-frame twist (vx, vy, wz) from wheel speeds (..., 4) [4.18]."""
    twist = np.asarray(wheels, dtype=float) @ _m418(L).T * (r_w / 4.0)
    return twist[..., 0], twist[..., 1], twist[..., 2]


def mecanum_limit(u: np.ndarray, heading: np.ndarray, v_max: float) -> np.ndarray:
    """Scale a world-frame demand (R, N, 2) into the mecanum-reachable set [4.18]–[4.19] (docs/readings.md,
    "Mecanum drive: the reachable set").

    The wheel-speed limit is the one that gives ``v_max`` straight ahead, so with w_z = 0
    the reachable body-frame set is |v_x| + |v_y| ≤ v_max. A demand whose wheel speeds
    [4.19] exceed it is scaled along its direction until the fastest wheel is at the limit.
    r_w and L cancel for w_z = 0, so unit values are used.
    """
    body = to_body(u, heading)
    wheels = mecanum_wheels(body[..., 0], body[..., 1], 0.0, r_w=1.0, L=1.0)
    fastest = np.abs(wheels).max(axis=-1, keepdims=True)
    return u * _shrink(fastest, v_max)


# --------------------------------------------------------------------------- the fleet's laws


@dataclass(frozen=True)
class Limits:
    """What bounds a robot's command: its top speed, the rotational-energy reading [5.12] and
    its radius, and the minimum turning radius [5.6] (0 = off)."""

    v_max: float
    inertia: Inertia = "pi"
    radius: float | None = None
    r_min: float = 0.0


# (cmd, y − x, y_g − x, F_t, heading, c, ω, r, limits) → the next command: a world-frame velocity
# (R, N, 2), or [v, w] (R, N, 2) for a body-frame law
Command = Callable[[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray,
                    Limits], np.ndarray]


@dataclass(frozen=True)
class RobotLaw:
    """One velocity law of the Chapter 4–5 fleet and what the fleet needs to know about it."""

    name: str
    label: str
    terms: int  # accelerating terms n: coefficients c_1..c_n and draws r_1..r_n
    draws: Literal["component", "robot"]  # one U(0,1) draw per velocity component, or per robot
    body_frame: bool  # the command is [v, w] in the robot frame (a differential drive)
    dvc: Literal["omni", "nonomni"] | None  # the DVC form that tunes it ([4.14]–[4.16], [5.14]–[5.16]), if any
    command: Command
    forward: bool = False  # a body-frame law that only drives forward (v ≥ 0, [5.13])


def _rpso(cmd: np.ndarray, g_p: np.ndarray, g_g: np.ndarray, force: np.ndarray, heading: np.ndarray, c: np.ndarray,
          omega: np.ndarray, r: np.ndarray, lim: Limits) -> np.ndarray:
    return rpso_velocity(cmd, g_p, g_g, force, c, omega, r, v_max=lim.v_max)  # clipped (see rpso_velocity)


def _adapted_rpso(cmd: np.ndarray, g_p: np.ndarray, g_g: np.ndarray, force: np.ndarray, heading: np.ndarray,
                  c: np.ndarray, omega: np.ndarray, r: np.ndarray, lim: Limits) -> np.ndarray:
    return adapted_rpso_velocity(cmd, g_p, g_g, force, c, omega, r)


def _limited(vw: np.ndarray, lim: Limits) -> np.ndarray:
    """[v, w] within the energy limit [5.11]–[5.12] and the minimum turning radius (Rossides §5.4,
    p. 125)."""
    v, w = energy_limit(vw[..., 0], vw[..., 1], lim.v_max, lim.inertia, lim.radius)
    w = min_turning_radius(v, w, lim.r_min)
    return np.stack([v, w], axis=-1)


def _robot_centred(cmd: np.ndarray, g_p: np.ndarray, g_g: np.ndarray, force: np.ndarray, heading: np.ndarray,
                   c: np.ndarray, omega: np.ndarray, r: np.ndarray, lim: Limits) -> np.ndarray:
    y = np.stack([to_body(g_p, heading), to_body(g_g, heading)])
    cc = np.repeat(c[..., None], 2, axis=-1)  # the same c_n for v and w
    return _limited(robot_centred_velocity(cmd, y, cc, omega[..., None], r), lim)


def _nonomni(cmd: np.ndarray, g_p: np.ndarray, g_g: np.ndarray, force: np.ndarray, heading: np.ndarray,
             c: np.ndarray, omega: np.ndarray, r: np.ndarray, lim: Limits) -> np.ndarray:
    return _limited(nonomni_velocity(cmd, to_body(g_p, heading), to_body(g_g, heading), c, omega, r), lim)


ROBOT_LAWS: Registry[RobotLaw] = Registry(
    "law",
    RobotLaw("rpso", "Original RPSO", 3, "component", False, None, _rpso),  # [4.2]
    RobotLaw("adapted-rpso", "Adapted RPSO", 3, "component", False, "omni", _adapted_rpso),  # [4.5]
    RobotLaw("robot-centred", "Robot-centred", 2, "component", True, None, _robot_centred),  # [5.4]
    RobotLaw("nonomni", "Non-omni", 5, "robot", True, "nonomni", _nonomni, forward=True),  # [5.13]
)


def steered_command(command: np.ndarray, law: RobotLaw, lim: Limits, slack: float) -> np.ndarray:
    """A command from outside the law (:mod:`shoal.engine.core.steering`) within the limits the
    law's own commands keep: a world-frame velocity at most v_max (as [4.2]'s clip); [v, w] within
    the energy limit [5.11]–[5.12] and the minimum turning radius [5.6], forward only for a law
    that drives forward. Each limit acts where the command exceeds it by more than ``slack``."""
    if not law.body_frame:
        return clip_speed(command, lim.v_max, slack)
    v = np.maximum(command[..., 0], 0.0) if law.forward else command[..., 0]
    v, w = energy_limit(v, command[..., 1], lim.v_max, lim.inertia, lim.radius, slack)
    return np.stack([v, min_turning_radius(v, w, lim.r_min)], axis=-1)
