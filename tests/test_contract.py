"""The engine contract (``shoal.engine.core.contract``): every scene kind is driven the same way —
``reset``/``step``/``info``, ``Info.columns()`` for the metric table and ``retune`` with the
class's ``LIVE`` keywords, refusing anything else without changing the engine."""

from __future__ import annotations

import numpy as np
import pytest

from shoal.engine.core.contract import Engine, Info, State
from shoal.engine.core.recorder import metric_table
from shoal.engine.pso.coeffs import Constant
from shoal.presets.build import build
from shoal.presets.io import list_presets, load
from shoal.presets.kinds import KINDS as SCENE_KINDS
from shoal.presets.kinds import kind_for


def one_preset_per_kind() -> dict[tuple[str, bool], str]:
    """The first shipped preset of each registered scene kind, on true and on SLO positions."""
    out: dict[tuple[str, bool], str] = {}
    for name in list_presets():
        sc = load(name)
        out.setdefault((kind_for(sc).name, sc.slo is not None), name)
    return out


BY_KIND = one_preset_per_kind()
KINDS = tuple(BY_KIND.values())
COMMON = ("run", "step", "t", "best_fitness", "max_speed", "mean_speed")


def test_every_registered_kind_has_a_shipped_preset():
    assert {kind for kind, _ in BY_KIND} == set(SCENE_KINDS)


def engine(preset: str, runs: int = 2):
    return build(load(preset), runs=runs, seed=3)


@pytest.mark.parametrize("preset", KINDS)
def test_every_kind_implements_the_contract(preset):
    sim = engine(preset)
    assert isinstance(sim, Engine) and isinstance(sim.state, State)
    assert isinstance(sim.LIVE, frozenset) and sim.LIVE
    assert (sim.runs, sim.seed, sim.first_run, sim.state.k, sim.t) == (2, 3, 0, 0, 0.0)
    assert sim.robots == sim.state.x.shape[1] and sim.dt > 0
    first = sim.info()
    assert isinstance(first, Info) and first.t == 0.0
    info = sim.step()
    assert isinstance(info, Info) and info.t == sim.t == sim.dt and sim.state.k == 1
    assert list(info.columns()) == list(first.columns()) == list(sim.info().columns())
    for name, col in info.columns().items():
        assert np.shape(col) == (2,), name
    assert sim.state.best_fitness.shape == (2,)


@pytest.mark.parametrize("preset", KINDS)
def test_the_metric_table_is_the_common_columns_then_the_kinds(preset):
    sim = engine(preset)
    info = sim.step()
    table = metric_table(sim.state, info, sim.t)
    assert list(table) == [*COMMON, *info.columns()]
    np.testing.assert_array_equal(table["best_fitness"], sim.state.best_fitness)


@pytest.mark.parametrize("preset", KINDS)
def test_the_kinds_schema_is_its_metric_table(preset):
    """The registry entry's columns are the table's, in order; a kind optimises something exactly
    when its state has a best fitness."""
    kind = kind_for(load(preset))
    sim = engine(preset)
    assert type(sim) is kind.engine_class
    table = metric_table(sim.state, sim.step(), sim.t)
    assert [c.name for c in kind.columns] == list(table)
    assert hasattr(sim.state, "best_fitness") == kind.optimises
    assert all(c.unit is not None and c.description and c.dtype in ("int", "float") for c in kind.columns)


@pytest.mark.parametrize("preset", KINDS)
def test_retune_refuses_a_fixed_keyword_and_changes_nothing(preset):
    sim, twin = engine(preset), engine(preset)
    live = sorted(sim.LIVE)[0]
    with pytest.raises(ValueError, match="^runs: cannot change mid-run"):
        sim.retune(**{live: getattr(sim, live, None)}, runs=5)
    for _ in range(3):
        sim.step(), twin.step()
    np.testing.assert_array_equal(sim.state.x, twin.state.x)


@pytest.mark.parametrize("preset", ("default", "course-dvc", "sonar-xb-pso"))
def test_slo_settings_need_slo_positions(preset):
    with pytest.raises(ValueError, match="^slo: .* true positions"):
        engine(preset).retune(slo={"errors": "high"})


def test_the_chapter3_swarm_retunes_its_controller_and_size():
    sim, twin = engine("default"), engine("default")
    sim.step(), twin.step()
    assert sim.retune(policy=sim.policy, law=sim.law, dt=sim.dt, robots=sim.robots) == []
    n, x = sim.robots, sim.state.x.copy()
    assert sim.retune(policy=Constant(0.5, (0.5, 0.5)), robots=n + 2) == ["policy", "robots"]
    np.testing.assert_array_equal(sim.state.x[:, :n], x)  # the swarm kept, two robots more
    info = sim.step()
    assert sim.robots == n + 2 and info.columns()["omega"][0] == 0.5 and info.columns()["c_hat"][0] == 1.0
    with pytest.raises(ValueError, match="^dt: must be > 0"):
        twin.retune(policy=Constant(0.5, (0.5, 0.5)), dt=0.0)
    assert twin.policy != Constant(0.5, (0.5, 0.5))  # refused: nothing changed


def test_the_chapter3_swarm_reports_no_coefficients_before_its_first_tick():
    sim = engine("default")
    cols = sim.info().columns()
    assert np.isnan(cols["omega"]).all() and np.isnan(cols["c_hat"]).all()
    assert np.isfinite(sim.step().columns()["omega"]).all()


def test_the_fleet_retunes_its_controller_from_the_next_tick():
    sim = engine("course-dvc")
    sim.step()
    assert sim.retune(alpha=0.5, beta=sim.params.beta) == ["alpha"] and sim.params.alpha == 0.5
    with pytest.raises(ValueError, match="^robot_radius: cannot change mid-run"):
        sim.retune(robot_radius=1.0)
    assert sim.params.robot_radius == 0.5


def test_the_acoustic_swarm_retunes_its_tuning_and_lets_a_moving_source_carry_on():
    sim = engine("sonar-xb-pso")
    for _ in range(3):
        sim.step()
    omega, source = sim.omega, sim.state.source.copy()
    assert sim.retune(beta=0.5, v_n=0.2) == ["beta", "v_n"]
    assert sim.omega == pytest.approx(0.5) and sim.omega != omega
    np.testing.assert_array_equal(sim.state.source, source)  # it starts moving from where it is
    sim.step()
    np.testing.assert_allclose(np.linalg.norm(sim.state.source - source, axis=-1), 0.2 * sim.params.U * sim.dt)
    with pytest.raises(ValueError, match="^mode: cannot change mid-run"):
        sim.retune(mode="surrogate")
