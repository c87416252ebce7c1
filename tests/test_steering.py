"""Steering (engine/core/steering.py): a command from outside the law for one tick, on every
built-in kind. The tick makes the law's draws all the same, limits the command as the kind limits
its law's, and a command the law itself gave passes to the bit."""

from __future__ import annotations

import copy

import numpy as np
import pytest

import shoal
from shoal.engine.core.recorder import metric_table
from shoal.engine.core.steering import SLACK, Steering


def _command(engine) -> np.ndarray:
    """What each robot was commanded in the tick just done (the fleet's before collisions zeroed it)."""
    s = engine.state
    got = getattr(s, "commanded", None)
    return (got if got is not None else s.cmd if hasattr(s, "cmd") else s.u).copy()


def _rng_states(engine) -> list:
    rngs = engine.rngs if hasattr(engine, "rngs") else [g for gs in engine.streams.values() for g in gs]
    return [g.bit_generator.state for g in rngs]


@pytest.mark.parametrize("preset, steps", [("default", 30), ("standard-pso", 10), ("course-dvc", 20),
                                           ("course-nonomni", 20), ("sonar-xb-pso", 8), ("sonar-xb-pso-nonomni", 8),
                                           ("slo-pso-sphere", 8)])
def test_the_laws_own_command_steers_the_same_run_to_the_bit(preset, steps):
    law, steered = (shoal.make(preset, runs=2, seed=5) for _ in range(2))
    for k in range(steps):
        law.engine.step()
        ahead = copy.deepcopy(steered.engine)
        ahead.step()
        steered.engine.steering = Steering(velocity=_command(ahead))
        steered.engine.step()
        a, b = (metric_table(e.state, e.info(), e.t) for e in (law.engine, steered.engine))
        for name in a:
            assert np.array_equal(np.asarray(a[name]), np.asarray(b[name]), equal_nan=True), (preset, k, name)
        assert np.array_equal(law.state.x, steered.state.x), (preset, k)
        assert _rng_states(law.engine) == _rng_states(steered.engine), "the steered tick drew what the law draws"
        assert steered.engine.steering is None, "a steering is for one tick"


def _random_commands(scene, scale: float, rng: np.random.Generator) -> np.ndarray:
    return scale * rng.standard_normal(scene.state.x.shape)


def test_a_swarm_command_stays_in_the_reachable_set_so_U_and_A_plus_hold():
    scene = shoal.make("default", runs=3, seed=1)
    e, rng = scene.engine, np.random.default_rng(0)
    omega, c = e.policy.coefficients(0.0, e.dt, e.d)
    U_j, reach = sum(c) / (1.0 - omega), float(sum(c))
    for _ in range(20):
        before = e.state.u.copy()
        e.steering = Steering(velocity=_random_commands(scene, 50.0, rng))
        e.step()
        u = e.state.u
        assert np.all(np.abs(u) <= U_j * (1 + 1e-12)), "|u_j| <= U_j [3.26]"
        assert np.all(np.abs(u - omega * before) <= reach * (1 + 1e-12)), "one tick moves u by at most c-hat"
    small = 0.01 * np.ones(e.state.x.shape)
    e.steering = Steering(velocity=small + omega * e.state.u)
    u0 = omega * e.state.u + small
    e.step()
    assert np.array_equal(e.state.u, u0), "a command within reach is taken as it is"


@pytest.mark.parametrize("preset", ["course-dvc", "course-rpso"])
def test_a_fleet_command_is_clipped_to_the_top_speed(preset):
    scene = shoal.make(preset, runs=2, seed=2)
    e, rng = scene.engine, np.random.default_rng(1)
    v_max = e.params.v_max
    for _ in range(5):
        e.steering = Steering(velocity=_random_commands(scene, 20.0, rng))
        e.step()
        speed = np.linalg.norm(e.state.commanded, axis=-1)[e.state.status == 0]  # (those still driving decided)
        assert np.all(speed <= v_max * (1 + SLACK)), speed.max()
        assert np.all(np.linalg.norm(e.state.u, axis=-1) <= v_max * (1 + 1e-9)), "the realised velocity too"


def test_a_nonomni_command_drives_forward_within_the_energy_limit():
    scene = shoal.make("course-nonomni", runs=2, seed=2)
    e, rng = scene.engine, np.random.default_rng(2)
    p = e.params
    from shoal.engine.robots.laws import rotational_energy_factor

    k = rotational_energy_factor(p.rotational_energy, p.robot_radius)
    for _ in range(5):
        e.steering = Steering(velocity=_random_commands(scene, 5.0, rng))
        e.step()
        live = e.state.status == 0
        v, w = e.state.commanded[..., 0][live], e.state.commanded[..., 1][live]
        assert np.all(v >= 0.0), "forward only [5.13]"
        assert np.all(0.5 * v**2 + k * w**2 <= 0.5 * p.v_max**2 * (1 + 1e-9)), "energy limit [5.11]-[5.12]"


def test_an_acoustic_command_keeps_the_adapted_bound_and_the_nonomni_limits():
    adapted = shoal.make("sonar-xb-pso", runs=2, seed=3)
    e, rng = adapted.engine, np.random.default_rng(3)
    U_j = e.c.sum() / (1.0 - e.omega)
    for _ in range(3):
        e.steering = Steering(velocity=_random_commands(adapted, 30.0, rng))
        e.step()
        assert np.all(np.abs(e.state.u) <= U_j * (1 + 1e-12))
    nonomni = shoal.make("sonar-xb-pso-nonomni", runs=2, seed=3)
    e = nonomni.engine
    for _ in range(3):
        e.steering = Steering(velocity=_random_commands(nonomni, 30.0, rng))
        e.step()
        v, w = e.state.cmd[..., 0], e.state.cmd[..., 1]
        assert np.all(v >= 0.0)
        assert np.all(0.5 * v**2 + np.pi / 4 * w**2 <= 0.5 * e.params.U**2 * (1 + 1e-9))


def test_given_coefficients_are_in_force_and_nan_keeps_the_kinds_own():
    a, b = shoal.make("default", runs=2, seed=4), shoal.make("default", runs=2, seed=4)
    R, N = a.state.x.shape[:2]
    omega, c = a.engine.policy.coefficients(0.0, a.engine.dt, a.engine.d)
    b.engine.steering = Steering(omega=np.full((R, N), np.nan), c=np.full((2, R, N), np.nan))
    a.step(), b.step()
    assert np.array_equal(a.state.x, b.state.x), "NaN everywhere: the policy's own, to the bit"
    given = np.array([[0.3] * N, [0.7] * N])
    b.engine.steering = Steering(omega=given, c=np.full((1, R, N), 0.5))
    b.step()
    info = b.engine.info()
    assert np.allclose(info.columns()["omega"], [0.3, 0.7]), "ω per run"
    assert np.allclose(info.columns()["c_hat"], 0.5 + c[1]), "c1 given, c2 the policy's"


def test_given_coefficients_steer_the_compiled_fleet_as_its_numpy_tick():
    """The kernel reads given ω, c where they are not NaN; the numpy tick merges them the same way."""
    runs = [shoal.make("course-dvc", runs=2, seed=6) for _ in range(2)]
    runs[1].engine.compiled = False
    R, N = runs[0].state.x.shape[:2]
    omega = np.where(np.arange(N) % 2 == 0, 0.5, np.nan) * np.ones((R, N))
    c = np.stack([np.full((R, N), 0.2), np.full((R, N), np.nan)])
    for _ in range(5):
        for scene in runs:
            scene.engine.steering = Steering(omega=omega, c=c)
            scene.step()
    assert np.array_equal(runs[0].state.x, runs[1].state.x)
    o = runs[0].engine.state.omega
    assert np.all(o[:, ::2] == 0.5) and np.allclose(o[:, 1::2], 1 - runs[0].engine.params.beta)
    assert np.all(runs[0].engine.state.c[0] == 0.2)


@pytest.mark.parametrize("compiled", [True, False])
def test_a_steered_fleet_senses_nothing_it_does_not_need(compiled):
    """A given command needs no six-sector reading (the environment senses for its observation);
    the DVC guard still needs the gaps, so with the guard on the robots sense as the law's do."""
    for guard, sensed in ((False, False), (True, True)):
        scene = shoal.make("course-dvc", runs=2, seed=1, controller={"guard": guard})
        scene.engine.compiled = compiled
        scene.engine.steering = Steering(velocity=np.full(scene.state.x.shape, 0.5))
        scene.step()
        assert (scene.engine.state.reading is not None) == sensed
        assert np.all(np.isfinite(scene.state.x))
