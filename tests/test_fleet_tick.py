"""The fleet tick in one compiled call (``robots/tick_kernels.py``) against the numpy tick, to
the byte (dtypes, metrics and the generators' streams too), and batched fleets on every core:
the same bytes on one thread or several, and each run as it is alone."""

from __future__ import annotations

from dataclasses import fields

import numpy as np
import pytest

from shoal.engine.core import parallel
from shoal.engine.kinds.fleet import COLLIDED, Fleet, FleetInfo, FleetParams, FleetState
from shoal.engine.robots.world import forest, obstacle_course

COURSE = obstacle_course(seed=0, length=80.0, width=40.0, start_size=14.0)
MODES = {
    "omni DVC, sequential": FleetParams(),
    "RPSO, constants (collisions)": FleetParams(law="rpso", dvc=False),
    "Adapted RPSO, constants, mecanum, simultaneous": FleetParams(dvc=False, drive="mecanum", c=(0.9, 0.9, 0.5),
                                                                  update="simultaneous"),
    "non-omni DVC, guard, per-robot draws": FleetParams(law="nonomni", drive="differential", guard=True),
    "robot-centred, constants": FleetParams(law="robot-centred", dvc=False, drive="differential", c=(0.5, 0.5)),
}
INFO = ("com_fitness", "collided", "stalled", "operational", "layers_passed", "best_fitness", "max_speed")


@pytest.fixture
def threads():
    yield parallel.set_threads
    parallel.set_threads(None)


def _bytes(a: np.ndarray) -> tuple:
    a = np.asarray(a)
    return a.dtype.str, a.shape, np.ascontiguousarray(a).tobytes()


def _same(a: Fleet, b: Fleet, ia: FleetInfo, ib: FleetInfo, k: int) -> None:
    for f in fields(FleetState):
        va, vb = getattr(a.state, f.name), getattr(b.state, f.name)
        if isinstance(va, np.ndarray):
            assert _bytes(va) == _bytes(vb), f"{f.name}, tick {k}"
    ra, rb = a.state.reading, b.state.reading
    assert (ra is None) == (rb is None), k
    if ra is not None:
        for name in ("gap", "point", "centre", "hit"):
            assert _bytes(getattr(ra, name)) == _bytes(getattr(rb, name)), f"reading.{name}, tick {k}"
    for name in INFO:
        assert _bytes(getattr(ia, name)) == _bytes(getattr(ib, name)), f"info.{name}, tick {k}"
    assert ia.t == ib.t and a.state.k == b.state.k


@pytest.mark.parametrize("mode", list(MODES))
def test_the_fused_tick_gives_the_numpy_ticks_bytes(mode):
    a = Fleet(world=COURSE, robots=25, params=MODES[mode], runs=2, seed=3)
    b = Fleet(world=COURSE, robots=25, params=MODES[mode], runs=2, seed=3, compiled=False)
    assert a._fused_tick() and not b._fused_tick()
    for k in range(40):
        _same(a, b, a.step(), b.step(), k)
    assert [g.random() for g in a.rngs] == [g.random() for g in b.rngs]  # the streams left alike
    if "collisions" in mode:
        assert (a.state.status == COLLIDED).sum() >= 5, "the scene should include collisions"


def test_the_fused_tick_equals_the_kernel_tick_after_edits_and_until_all_have_collided():
    """Against phase B's own kernel (the numpy around it): a world edit, a retune, a robot
    edited in place, and a forest where every robot ends up disabled (no robot senses)."""
    world = forest(seed=2, size=16.0, density=0.3)
    params = FleetParams(law="rpso", dvc=False, c=(1.5, 1.5, 1.5))
    a, b = (Fleet(world=world, robots=30, params=params, runs=2, seed=8) for _ in range(2))
    b._fused_tick = lambda: False  # type: ignore[method-assign]
    for k in range(60):
        if k == 10:
            for f in (a, b):
                f.retune(update="simultaneous", sensing_range=2.0)
                f.set_world(world.with_circle(*a.state.x[0, 0] + (2.0, 0.0), 0.6))
        if k == 20:
            for f in (a, b):
                f.state.x[1, 3] += 0.25  # an edit in place between ticks
        _same(a, b, a.step(), b.step(), k)
    assert (a.state.status == COLLIDED).all() and a.state.reading is None


def test_info_before_and_after_a_fused_tick_is_the_numpy_info():
    f = Fleet(world=COURSE, robots=12, params=FleetParams(), runs=3, seed=1)
    for _ in range(5):
        stepped = f.step()
    again = f.info()
    for name in INFO:
        assert _bytes(getattr(stepped, name)) == _bytes(getattr(again, name)), name


def test_a_batch_of_fleets_is_the_same_on_one_thread_or_three_and_as_each_run_alone(threads):
    params = FleetParams(law="rpso", dvc=False)
    runs = []
    for n in (1, 3):
        threads(n)
        f = Fleet(world=COURSE, robots=20, params=params, runs=5, seed=2)
        infos = [f.step() for _ in range(30)]
        runs.append((f, infos))
    (a, ia), (b, ib) = runs
    for k, (x, y) in enumerate(zip(ia, ib)):
        for name in INFO:
            assert _bytes(getattr(x, name)) == _bytes(getattr(y, name)), (k, name)
    _same(a, b, ia[-1], ib[-1], 29)
    threads(2)
    for i in (0, 3):
        alone = Fleet(world=COURSE, robots=20, params=params, runs=1, seed=2, first_run=i)
        for _ in range(30):
            alone.step()
        for name in ("x", "heading", "u", "status", "y", "f_y"):
            assert getattr(alone.state, name)[0].tobytes() == getattr(b.state, name)[i].tobytes(), (i, name)
        assert alone.rngs[0].random() == b.rngs[i].random()
