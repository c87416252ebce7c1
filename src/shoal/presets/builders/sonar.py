"""The Chapter 7–8 acoustic swarm of a scenario (:class:`~shoal.engine.kinds.sonar.AcousticSwarm`),
and the keywords that retune a running one."""

from __future__ import annotations

from typing import Any

import numpy as np

from shoal.engine.kinds.sonar import AcousticSwarm, SonarParams

from ..models import Acoustics, Scenario, required
from .positions import positions_for


def sonar_params_for(a: Acoustics) -> SonarParams:
    """The engine parameters of an ``[acoustics]`` section (angles in degrees → radians)."""
    return SonarParams(
        algorithm=a.algorithm, controller=a.controller, mode=a.mode, snr0_db=a.snr0_db, psd_s_db=a.psd_s,
        psd_n_db=a.psd_n, f_c=a.f_c, Q=a.Q, tbp=a.tbp, c=a.c, fs=a.fs, d_over_lambda=a.d_over_lambda,
        full_lag=a.full_lag, lag_peak=a.lag_peak, a=a.a, d0=a.d_0, dc=a.d_c, U=a.U, dt=a.dt, beta=a.beta,
        c1_share=a.c1_share,
        alpha_dvc=a.alpha_dvc, sensing_range=a.sensing_range, robot_radius=a.robot_radius, r_trap=a.r, v_n=a.v_n,
        source_heading=np.deg2rad(a.source_heading_deg),
        source_bearing=None if a.source_bearing_deg is None else float(np.deg2rad(a.source_bearing_deg)),
        source=None if a.source is None else (float(a.source[0]), float(a.source[1])),
        start=a.start, guard=a.guard, stop_on_converge=a.stop_on_converge,
    )


def build_sonar(scenario: Scenario, *, runs: int | None = None, seed: int | None = None,
                first_run: int = 0) -> AcousticSwarm:
    """A Chapter 7–8 acoustic swarm (needs an ``[acoustics]`` section; on SLO positions with
    ``[slo] swarm = "host"``)."""
    acoustics = required(scenario.acoustics, "acoustics")
    return AcousticSwarm(sonar_params_for(acoustics), robots=scenario.sim.robots,
                         runs=runs or scenario.sim.runs, seed=scenario.sim.seed if seed is None else seed,
                         first_run=first_run, positions=positions_for(scenario))


def sonar_keywords(s: Scenario) -> dict[str, Any]:
    """The ``AcousticSwarm.retune`` keywords of a scenario (its :class:`SonarParams` in ``LIVE``)."""
    params = sonar_params_for(required(s.acoustics, "acoustics"))
    return {k: getattr(params, k) for k in AcousticSwarm.LIVE - {"slo"}}


def sonar_retune(old: Scenario, new: Scenario) -> dict[str, Any]:
    """The keywords that take a running acoustic swarm to ``new`` (all of them: the engine keeps
    what did not change)."""
    return sonar_keywords(new)
