"""The example plug-in's own tests: Shoal's conformance kit (``shoal.testing``) on the ``gather``
kind, every check that its entry's facts select (it optimises nothing, so ``best_fitness`` is
checked absent), and the plug-in's own promise. Run them with the plug-in installed:

    pip install examples/plugin && python -m pytest examples/plugin/tests
"""

from __future__ import annotations

import shoal
from shoal.testing import check_kind, parametrize_with_kinds


@parametrize_with_kinds(["gather"])
def test_gather_keeps_the_rules_of_a_shoal_kind(kind, check):
    check(kind)


def test_check_kind_runs_every_check_that_applies():
    ran = check_kind("gather")
    assert "check_no_best_fitness" in ran and "check_best_fitness" not in ran
    assert {"check_contract", "check_determinism", "check_live_change", "check_app"} <= set(ran)


def test_the_robots_gather():
    scene = shoal.make("gather-demo", runs=3, seed=2)
    first = scene.row()["spread"].copy()
    scene.run(40)
    assert (scene.row()["spread"] < first).all()
