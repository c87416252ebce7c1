"""The Chapter 7–8 acoustic swarm as an environment: robots localising a sound source."""

from __future__ import annotations

import numpy as np

from ..spec import Coefficients, Command, EnvScene, Part, RLSpec, common_parts, common_values
from .common import body_towards, world_towards


def parts(scene: EnvScene) -> tuple[Part, ...]:
    return common_parts(scene) + (
        Part("intensity", (1,), 0.0, np.inf, "received power I + N [7.1] of the last listen (0 before the first)"),
        Part("rays", (2, 2), -1.0, 1.0, "unit bearings to the source from the two-hydrophone lag, r_+ and its mirror "
                                        "r_− [7.7] (0 with one hydrophone or before the first listen)"),
        Part("memory", (1,), -np.inf, np.inf, "the remembered fitness f̂ of the personal best [7.2]"),
        Part("personal_best", (2,), -np.inf, np.inf, "the robot's personal best y [m]"),
        Part("global_best", (2,), -np.inf, np.inf, "the swarm's global best y_g (the best or the centroid) [m]",
             per="swarm"),
    )


def observe(scene: EnvScene) -> dict[str, np.ndarray]:
    s = scene.engine.state
    R, N = s.x.shape[:2]
    power, rays = np.zeros((R, N)), np.zeros((R, N, 2, 2))
    if s.intensity is not None and len(s.stepped):
        power[s.stepped] = s.intensity.mean(axis=-1)
        if s.bearing is not None:
            rays[s.stepped] = s.bearing.rays
    return {**common_values(scene), "intensity": power[..., None], "rays": rays, "memory": s.f_hat[..., None],
            "personal_best": s.y, "global_best": s.y_g}


def command(scene: EnvScene) -> Command:
    e = scene.engine
    p = e.params
    if p.controller == "nonomni":
        w = float(np.sqrt(0.5 * p.U**2 / (np.pi / 4.0)))  # the energy limit [5.11]-[5.12] at v = 0
        return Command("body", (0.0, -w), (p.U, w), "m/s, rad/s")
    b = float(np.sum(e.c)) / (1.0 - e.omega)  # U_j = ĉ/(1 − ω) = U/√2 [4.15]
    return Command("world", (-b, -b), (b, b))


def towards(scene: EnvScene, waypoint: np.ndarray) -> np.ndarray:
    e = scene.engine
    if e.params.controller == "nonomni":
        return body_towards(e.state.x, e.state.heading, waypoint, e.dt, forward=True)
    return world_towards(e.state.x, waypoint, e.dt)


def _own(scene: EnvScene) -> np.ndarray:
    e = scene.engine
    R, N = e.state.x.shape[:2]
    if e.params.controller == "nonomni":
        return np.full((3, R, N), np.nan)  # the DVC's, per robot, not kept
    return np.stack([np.full((R, N), e.omega), np.full((R, N), e.c[0]), np.full((R, N), e.c[1])])


def coefficients(scene: EnvScene) -> Coefficients:
    top = float(scene.engine.params.U)
    return Coefficients((0.0, 0.0, 0.0), (0.999, top, top), _own)


def _arena(scene: EnvScene) -> tuple[float, float, float, float]:
    e = scene.engine
    reach = float(np.abs(e.source0[0]).max()) + e.params.d0 + e.params.dc
    return (-reach, -reach, reach, reach)


def _terminated(scene: EnvScene) -> np.ndarray:
    e = scene.engine
    if e.params.r_trap > 0:  # escorting goes on round the source
        return np.zeros(e.runs, bool)
    return e.state.first_converged >= 0


SPEC = RLSpec(
    "sonar", "Chapter 7–8 acoustic swarm", parts, observe,
    reward=lambda scene: scene.engine.state.snr_db.mean(axis=1),
    robot_reward=lambda scene: scene.engine.state.snr_db.copy(),
    terminated=_terminated,
    commanded=lambda scene: scene.engine.state.cmd.copy(),
    command=command, towards=towards, coefficients=coefficients, arena=_arena,
    progress=True,
    reward_text="the signal level's rise: how much the mean in-band SNR at the robots [7.16] rose in the tick, in "
                "dB; a robot's own: its SNR's rise",
    end_text="the CoM within d_c of the source, the thesis' convergence (not with an escort ring, which goes on)",
    unheard=("intensity", "rays"),
)
