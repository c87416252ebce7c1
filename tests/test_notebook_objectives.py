"""Objectives as a notebook user writes them: a cell run again redefines its function (keyed by
module and qualname, not the bare name), a function may share a built-in's name, and a function of
the wrong shape is told so on its first call, before anything compiles."""

from __future__ import annotations

import time

import numba
import numpy as np
import pytest

import shoal
from shoal.engine.core.objectives import OBJECTIVES


@pytest.fixture(autouse=True)
def forget_mine():
    before = set(OBJECTIVES)
    yield
    for name in set(OBJECTIVES) - before:
        OBJECTIVES.unregister(name)


def cell(offset: float):
    """One notebook cell: defines ``my_obj`` (the same module and qualname every time it runs)."""
    def my_obj(z):
        return np.sum((z - offset) ** 2, axis=-1)
    return my_obj


def test_running_a_cell_again_redefines_the_objective():
    first = shoal.make("rastrigin", d=3, runs=1, seed=2, objective=cell(0.0))
    second = shoal.make("rastrigin", d=3, runs=1, seed=2, objective=cell(5.0))  # raised "names another" before
    assert first.scenario.objective.kind == second.scenario.objective.kind
    o, x = second.engine.objective, second.state.x
    z = (x - o.source[:3]) / o.scale
    np.testing.assert_array_equal(o(x), np.sum((z - 5.0) ** 2, axis=-1))
    assert sum(1 for n in OBJECTIVES if n.endswith("my_obj")) == 1


def test_a_function_may_be_called_like_a_builtin():
    def rastrigin(z):  # the user's own, not Shoal's
        return np.sum(np.abs(z), axis=-1)

    scene = shoal.make("rastrigin", d=2, runs=1, seed=1, objective=rastrigin)
    name = scene.scenario.objective.kind
    assert name != "rastrigin" and name.endswith("test_a_function_may_be_called_like_a_builtin.<locals>.rastrigin")
    o, x = scene.engine.objective, scene.state.x
    np.testing.assert_array_equal(o(x), np.sum(np.abs((x - o.source[:2]) / o.scale), axis=-1))
    assert OBJECTIVES["rastrigin"].label == "Rastrigin"  # the built-in is untouched
    assert shoal.make("rastrigin", objective=rastrigin).scenario.objective.kind == name  # found again


def test_two_modules_functions_of_one_name_are_two_objectives():
    def a(z):
        return np.sum(z, axis=-1)

    def b(z):
        return -np.sum(z, axis=-1)

    b.__name__ = "a"  # the same bare name, another qualname
    na = shoal.make("default", objective=a).scenario.objective.kind
    nb = shoal.make("default", objective=b).scenario.objective.kind
    assert na == "a" and nb != na and nb.endswith(".b")


@pytest.mark.parametrize("f, got", [
    (lambda z: np.sum(z, axis=0), "shape (20, 2)"),  # wrong axis
    (lambda z: float(np.sum(z)), "shape ()"),  # a scalar function
    (lambda z: z, "shape (1, 20, 2)"),  # no reduction
])
def test_a_function_of_the_wrong_shape_is_told_so_on_its_first_call(f, got):
    def wrong(z):
        return f(z)

    t0 = time.perf_counter()
    with pytest.raises(ValueError, match=r"f must map \(\.\.\., d\) to \(\.\.\.\).*given an array of shape "
                                         rf"\(1, 20, 2\) it returned {got.replace('(', '[(]').replace(')', '[)]')}"):
        shoal.make("rastrigin", runs=1, robots=20, objective=wrong)
    assert time.perf_counter() - t0 < 20  # (no 30 s compile first; generous for a loaded machine)


def test_a_numba_function_of_the_wrong_shape_is_told_so_too():
    @numba.njit
    def flat(z):
        return z.sum()

    with pytest.raises(ValueError, match=r"f must map .* returned shape \(\)"):
        shoal.make("rastrigin", runs=1, objective=flat)
