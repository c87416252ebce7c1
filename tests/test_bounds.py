"""Search-space bounds of a benchmark scene (off by default): the four boundary rules, the preset
fields, and on 50-D Rastrigin bounds help as they do in pyswarms."""

from __future__ import annotations

import numpy as np
import pytest

import shoal
from shoal.api import scenario_of
from shoal.engine.pso.bounds import confine
from shoal.presets.build import objective_for
from shoal.presets.io import PresetError, to_toml

LOW, HIGH = np.array([-1.0, 0.0]), np.array([1.0, 4.0])


def test_inside_keeps_its_bits_and_every_rule_puts_a_robot_back_inside():
    x = np.array([[0.3, 3.9], [1.5, -1.0], [-4.5, 9.5]])
    u = np.array([[1.0, 2.0], [3.0, -4.0], [-5.0, 6.0]])
    for rule in ("clip", "reflect", "absorb", "periodic"):
        xb, ub = confine(x, u, LOW, HIGH, rule)
        assert ((xb >= LOW) & (xb <= HIGH)).all(), rule
        assert xb[0].tobytes() == x[0].tobytes() and ub[0].tobytes() == u[0].tobytes(), rule
    np.testing.assert_array_equal(confine(x, u, LOW, HIGH, "clip")[0][1:], [[1.0, 0.0], [-1.0, 4.0]])
    np.testing.assert_array_equal(confine(x, u, LOW, HIGH, "absorb")[1][1:], [[0.0, 0.0], [0.0, 0.0]])
    xr, ur = confine(x, u, LOW, HIGH, "reflect")
    np.testing.assert_allclose(xr[1:], [[0.5, 1.0], [-0.5, 1.5]])  # one fold each, then two folds each
    np.testing.assert_array_equal(ur[1:], [[-3.0, 4.0], [-5.0, 6.0]])  # reversed by an odd number of folds
    xp, up = confine(x, u, LOW, HIGH, "periodic")
    np.testing.assert_allclose(xp[1:], [[-0.5, 3.0], [-0.5, 1.5]])  # in again from the other side
    np.testing.assert_array_equal(up, u)


STD = {"law": "standard", "mode": "raw", "omega": 0.729, "c1": 1.49, "c2": 1.49}


def rastrigin_50d(**objective):
    scene = shoal.make("rastrigin", d=50, robots=30, runs=6, seed=1, controller=STD,
                       objective={"kind": "rastrigin", "source": [0.0, 0.0], "scale": 1.0, **objective},
                       init={"center": [0.0, 0.0], "spread": 10.24})
    scene.run(1000)
    return scene


def test_bounds_help_on_50d_rastrigin_as_in_pyswarms():
    """pyswarms 1.3 (periodic bounds, its default): 39–61 with bounds, 118–165 without; the issue
    measured 31–48 and 132–200 (docs/readings.md, "Search-space bounds")."""
    free = rastrigin_50d().state.best_fitness
    bounded = rastrigin_50d(bounds=[-5.12, 5.12]).state
    assert (np.abs(bounded.x) <= 5.12).all()
    assert bounded.best_fitness.max() < 80 < 100 < free.min(), (bounded.best_fitness, free)


def test_bounds_are_off_by_default_and_stay_out_of_a_dump():
    scene = shoal.make("rastrigin")
    assert scene.scenario.objective.bounds is None and scene.engine.objective.box(2) is None
    assert "bounds" not in to_toml(scene.scenario) and "boundary" not in to_toml(scene.scenario)


def test_the_bounds_are_in_the_objectives_units():
    scene = shoal.make("rastrigin", objective={"bounds": [-1.0, 2.0], "boundary": "clip", "source": [3.0, -1.0],
                                               "scale": 4.0})
    low, high = scene.engine.objective.box(2)
    np.testing.assert_array_equal(low, [-1.0, -5.0])
    np.testing.assert_array_equal(high, [11.0, 7.0])
    scene.run(50)
    assert ((scene.state.x >= low) & (scene.state.x <= high)).all()


def test_bad_bounds_are_refused_by_field():
    with pytest.raises(PresetError, match="bounds: need lo < hi"):
        shoal.make("rastrigin", objective={"bounds": [2.0, 1.0]})
    with pytest.raises(PresetError, match="boundary: applies to bounds"):
        shoal.make("rastrigin", objective={"boundary": "reflect"})
    with pytest.raises(PresetError, match="objective.boundary"):
        shoal.make("rastrigin", objective={"bounds": [-1.0, 1.0], "boundary": "bounce"})


def test_a_retune_can_bound_a_running_swarm():
    scene = shoal.make("rastrigin", runs=2)
    scene.run(5)
    bounded = scenario_of(scene.scenario, objective={"bounds": [-2.0, 2.0], "boundary": "absorb"})
    assert scene.engine.retune(objective=objective_for(bounded.objective, 2)) == ["objective"]
    scene.run(20)
    low, high = scene.engine.objective.box(2)
    assert ((scene.state.x >= low) & (scene.state.x <= high)).all()
