"""Honest bests: NaN is never a best, nor +inf when minimising, nor −inf when maximising, on the
numpy tick and the compiled one, in every kind that keeps bests; a scene with no value that may be
a best says so once, naming its objective."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import shoal
from shoal.engine.pso.bests import admissible, best_of, improves

STANDARD = {"law": "standard", "mode": "raw", "omega": 0.729, "c1": 1.49, "c2": 1.49}


def nan_right_of_two(z):
    """The sphere, NaN where z₁ > 2 (the issue's case: 3–5 of 20 particles start there)."""
    f = np.sum(z * z, axis=-1)
    return np.where(z[..., 0] > 2.0, np.nan, f)


def inf_right_of_two(z):
    """The sphere, +inf (the worst infinity when minimising) where z₁ > 2."""
    f = np.sum(z * z, axis=-1)
    return np.where(z[..., 0] > 2.0, np.inf, f)


def neg_sphere(z):
    """Maximised: −|z|², −inf where z₁ > 2."""
    f = -np.sum(z * z, axis=-1)
    return np.where(z[..., 0] > 2.0, -np.inf, f)


def swarm(f, tick: str, maximise: bool = False, runs: int = 4):
    if maximise:
        f = shoal.register_objective(f"{f.__name__}-max", f, maximise=True, replace=True).name
    scene = shoal.make("default", d=2, robots=20, runs=runs, seed=3, objective={"kind": f, "source": [0.0, 0.0]},
                       controller=STANDARD, init={"center": [0.0, 0.0], "spread": 10.0})
    scene.engine.compiled = tick == "compiled"
    return scene


@pytest.mark.parametrize("tick", ["compiled", "numpy"])
@pytest.mark.parametrize("f", [nan_right_of_two, inf_right_of_two])
def test_the_issues_case_reaches_the_optimum(f, tick):
    """pyswarms 1.3 reaches 1.8e-21 on it; Shoal used to report NaN at every step."""
    scene = swarm(f, tick)
    start = f(scene.state.x)
    assert (~np.isfinite(start)).sum(axis=1).min() >= 1  # some particles start where f is not a best
    table = scene.run(200)
    best = np.asarray(table["best_fitness"])
    assert np.isfinite(best).all()
    assert (scene.state.best_fitness < 1e-12).all(), scene.state.best_fitness
    assert np.isfinite(scene.state.f_y).all()  # every robot found a value that may be a best


def test_numpy_and_compiled_ticks_agree_on_honest_bests():
    a, b = swarm(nan_right_of_two, "compiled"), swarm(nan_right_of_two, "numpy")
    a.run(60)
    b.run(60)
    for n in ("x", "u", "y", "f_y", "yg", "best_fitness"):
        assert getattr(a.state, n).tobytes() == getattr(b.state, n).tobytes(), n


@pytest.mark.parametrize("tick", ["compiled", "numpy"])
def test_minus_inf_is_never_the_best_of_a_maximised_objective(tick):
    scene = swarm(neg_sphere, tick, maximise=True)
    scene.run(150)
    assert np.isfinite(scene.state.best_fitness).all() and (scene.state.best_fitness > -1e-12).all()


def all_nan(z):
    return np.full(z.shape[:-1], np.nan)


@pytest.mark.parametrize("tick", ["compiled", "numpy"])
def test_a_scene_of_nan_says_so_once_naming_the_objective(tick):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        scene = swarm(all_nan, tick, runs=2)
        scene.run(20)
    said = [w for w in caught if issubclass(w.category, RuntimeWarning) and "all_nan" in str(w.message)]
    assert len(said) == 1, [str(w.message) for w in caught]
    assert "NaN is never a best" in str(said[0].message)
    assert np.isnan(scene.state.best_fitness).all()  # no best: said, not hidden


def test_the_rules():
    nan, inf = np.nan, np.inf
    f = np.array([nan, inf, 3.0, -inf, 2.0])
    assert admissible(f, False).tolist() == [False, False, True, True, True]
    assert admissible(f, True).tolist() == [False, True, True, False, True]
    assert best_of(f, False) == 3 and best_of(f, True) == 1
    assert best_of(np.array([nan, nan]), False) == 0  # none admissible: the first stands
    assert improves(np.array([1.0, nan, 5.0, 1.0]), np.array([nan, 1.0, 4.0, inf]), False).tolist() == [
        True, False, False, True]


def test_a_fleet_never_takes_nan_for_a_best():
    """The fleet's cost is a distance; a NaN one (a robot at a NaN place) is never its best."""
    scene = shoal.make("course-dvc", runs=1, seed=2)
    fleet = scene.engine
    fleet.state.f_y[0, 0] = np.nan  # as if robot 0 had started where the cost is NaN
    scene.step()
    assert np.isfinite(fleet.state.f_y).all() and np.isfinite(fleet.state.best_fitness).all()


def test_the_slo_swarm_never_reports_nan_as_a_best():
    scene = shoal.make("slo-pso-sphere", runs=1, seed=2)
    sim = scene.engine
    sim.state.f[0, :3] = np.nan
    sim._last = sim._record()
    assert np.isfinite(sim.info().best_so_far).all() and np.isfinite(sim.info().best_fitness).all()
