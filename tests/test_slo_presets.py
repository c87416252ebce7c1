"""SLO scenes as presets: the [slo] section, build() dispatch and `shoal run` on them."""

from __future__ import annotations

import csv

import numpy as np
import pytest

from shoal.app.cli import main
from shoal.engine.kinds.slo_swarm import SLOSwarm
from shoal.engine.kinds.swarm import Simulation
from shoal.presets.build import build
from shoal.presets.io import PresetError, list_presets, load

SLO_PRESETS = ("slo-walk", "slo-pso-sphere", "slo-adapted")


@pytest.mark.parametrize("name", SLO_PRESETS)
def test_shipped_slo_presets_validate_and_build(name):
    assert name in list_presets()
    scenario = load(name)
    sim = build(scenario, runs=1)
    expected = Simulation if name == "slo-adapted" else SLOSwarm
    assert type(sim) is expected and (expected is SLOSwarm or not sim.positions.exact)
    sim.step()
    assert np.isfinite(sim.state.x).all()


def test_slo_fields_reach_the_engine():
    sw = build(load("slo-walk", ["slo.selection=rts", "slo.errors=high", "slo.error_values.range_sigma_m=0.4",
                                 "slo.neighbourhood=ring", "slo.neighbourhood_param=3", "slo.prediction_weight=0.25",
                                 "slo.entry_policy=geometric_random"]))
    cfg = sw.config
    chosen = (cfg.selection, cfg.neighbourhood, cfg.neighbourhood_param, cfg.prediction_weight)
    assert chosen == ("rts", "ring", 3, 0.25)
    assert cfg.entry_policy == "geometric_random" and build(load("slo-walk")).config.entry_policy == "geometric_nearest"
    for other in ("stale", "dead_reckoning"):  # an older reading, an extension
        assert build(load("slo-walk", [f"slo.entry_policy={other}"])).config.entry_policy == other
    assert cfg.motion == "random_walk" and sw.errors.range.sigma_m == 0.4
    assert sw.errors.range.sigma_a == 0.30  # the rest of the High set stays


@pytest.mark.parametrize(
    ("override", "field"),
    [
        ("slo.selection=gdl", "slo.selection"),
        ("slo.entry_policy=nearest", "slo.entry_policy"),
        ("slo.prediction_weight=1.5", "slo.prediction_weight"),
        ("slo.error_values.range_p_fail=2", "slo.error_values.range_p_fail"),
        ("slo.error_values.bogus=1", "slo.error_values.bogus"),
        ("slo.colour=1", "slo.colour"),
    ],
)
def test_bad_slo_field_is_named(override, field):
    with pytest.raises(PresetError) as err:
        load("slo-walk", [override])
    assert any(m.startswith(field) for m in err.value.messages), err.value.messages


def test_inconsistent_slo_settings_say_why():
    with pytest.raises(PresetError, match="probability"):
        load("slo-walk", ["slo.neighbourhood=random", "slo.neighbourhood_param=3"])
    with pytest.raises(PresetError, match="swarm = 'host'"):
        load("slo-walk", ["slo.positions=oracle"])


def test_oracle_switch_same_seed():
    oracle = build(load("slo-adapted", ["slo.positions=oracle"]))
    exact = build(load("slo-adapted", ["slo.errors=none"]))
    noisy = build(load("slo-adapted", ["slo.errors=high"]))
    assert type(oracle) is type(exact) is Simulation and oracle.positions.exact and not exact.positions.exact
    for _ in range(15):
        oracle.step(), exact.step(), noisy.step()
    np.testing.assert_allclose(exact.state.x, oracle.state.x, atol=1e-9)
    assert not np.allclose(noisy.state.x, oracle.state.x)


def test_shoal_run_slo_walk_writes_the_contract_files(tmp_path):
    out = tmp_path / "walk"
    assert main(["run", "slo-walk", "--steps", "5", "--out", str(out)]) == 0
    assert (out / "run.json").is_file()
    with open(out / "trajectories.csv", encoding="utf-8") as fh:
        rows = list(csv.DictReader(fh))
    for col in ("run", "step", "t", "robot", "x", "y", "heading", "vx", "vy", "status"):
        assert col in rows[0]
    assert len(rows) == 6 * 20
    with open(out / "metrics.csv", encoding="utf-8") as fh:
        metrics = list(csv.DictReader(fh))
    assert [int(m["step"]) for m in metrics] == list(range(6))
    assert {"e_abs_mean", "e_rel_median", "distance_median", "generation_best"} <= set(metrics[0])


def test_the_presets_entry_policies_are_the_localisers():
    """``slo.entry_policy`` lists the localiser's policies (models.py keeps its own copy, so that
    validating a preset loads no SLO code)."""
    from typing import get_args

    from shoal.engine.slo.beliefs import EntryPolicy
    from shoal.presets import models

    assert get_args(models.EntryPolicy) == get_args(EntryPolicy)
