"""Objectives: optimum locations and the single comparison predicate."""

import numpy as np
import pytest

from shoal.engine.core.objectives import Objective
from shoal.engine.pso.bests import global_best, update_personal


@pytest.mark.parametrize("name", ["sphere", "rastrigin", "ackley", "griewank"])
def test_benchmarks_are_zero_at_the_source(name):
    obj = Objective(name, source=np.array([3.0, -2.0]), scale=2.0)
    assert obj(np.array([[[3.0, -2.0]]]))[0, 0] == pytest.approx(0.0, abs=1e-12)
    assert obj(np.array([[[5.0, 1.0]]]))[0, 0] > 0


def test_rosenbrock_minimum_is_at_one():
    obj = Objective("rosenbrock", source=np.zeros(2))
    assert obj(np.ones((1, 1, 2)))[0, 0] == 0.0
    assert obj(np.zeros((1, 1, 2)))[0, 0] == 1.0


def test_distance_cost_and_linear_fitness():
    d = Objective("source-distance", source=np.array([3.0, 4.0]))
    assert d(np.zeros((1, 1, 2)))[0, 0] == pytest.approx(5.0)
    lin = Objective("linear")
    assert lin.maximise and not d.maximise
    assert lin.is_better(np.array(2.0), np.array(1.0)) and d.is_better(np.array(1.0), np.array(2.0))


def test_bests_follow_the_objective_sense():
    lin = Objective("linear")
    x = np.array([[[1.0], [5.0], [3.0]]])
    y, f_y = update_personal(x, lin(x), np.zeros_like(x), np.full((1, 3), 2.0), lin)
    assert np.array_equal(y[0, :, 0], [0.0, 5.0, 3.0])  # only improvements are kept
    yg, f_yg = global_best(y, f_y, lin)
    assert yg[0, 0] == 5.0 and f_yg[0] == 5.0
