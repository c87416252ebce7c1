"""The public API (``import shoal``): scenes from presets, files, dicts and keyword overrides;
stepping, state, metrics as a table, live retuning; runs and sweeps in memory giving the numbers
``shoal run`` and ``shoal sweep`` write; any dimension for the Chapter 3 swarm; your own
objective as a Python (or numba) function."""

from __future__ import annotations

import csv
import io
import sys

import numba
import numpy as np
import pytest

import shoal
from shoal.app.cli import main
from shoal.engine.core.objectives import OBJECTIVES, rastrigin
from shoal.engine.core.recorder import write_metrics
from shoal.presets.io import PresetError, load, to_toml
from shoal.studies.sweep.store import fmt

ARGS = ("--runs", "2", "--seed", "7", "--steps", "40")


def test_import_shoal_is_light_and_exports_the_api():
    assert {"make", "run", "sweep", "register", "Scene"} <= set(dir(shoal))
    assert shoal.make is shoal.api.make
    with pytest.raises(AttributeError):
        shoal.nothing  # noqa: B018


def test_make_takes_a_name_a_file_a_dict_or_a_scenario_with_overrides(tmp_path):
    scene = shoal.make("course-dvc", runs=4, seed=7, controller={"alpha": 0.8})
    assert (scene.engine.runs, scene.engine.seed, scene.scenario.controller.alpha) == (4, 7, 0.8)
    assert scene.kind.name == "fleet" and scene.state.x.shape == (4, scene.engine.robots, 2)
    path = tmp_path / "mine.toml"
    path.write_text(to_toml(load("default")), encoding="utf-8")
    from_file = shoal.make(str(path), ["controller.mode=raw"], robots=5)
    assert from_file.scenario.sim.robots == 5 and from_file.scenario.controller.mode == "raw"
    from_dict = shoal.make({"sim": {"robots": 3}})
    assert from_dict.engine.robots == 3
    assert shoal.make(from_dict.scenario).scenario == from_dict.scenario
    with pytest.raises(PresetError, match="^controller.alpha"):
        shoal.make("course-dvc", controller={"alpha": 2.0})
    with pytest.raises(PresetError, match="controller: give a section as a dict"):
        shoal.make("default", controller=0.5)


def test_a_scenes_metrics_are_the_rows_shoal_run_writes(tmp_path, capsys):
    """Byte for byte: the API's table, written as metrics.csv is, is the file of ``shoal run``."""
    for preset in ("default", "course-dvc", "slo-walk"):
        assert main(["run", preset, *ARGS, "--out", str(tmp_path / preset)]) == 0
        scene = shoal.make(preset, runs=2, seed=7, steps=40)
        table = scene.run()
        assert scene.k == 40 and len(table) == 2 * 41
        ordered = {c: np.asarray(table[c]).reshape(41, 2) for c in table.columns}
        buf = io.StringIO()
        write_metrics(buf, {c: v[0] for c, v in ordered.items()}, scene.engine.COLUMNS, header=True)
        for k in range(1, 41):
            write_metrics(buf, {c: v[k] for c, v in ordered.items()}, scene.engine.COLUMNS)
        assert buf.getvalue() == (tmp_path / preset / "metrics.csv").read_text(encoding="utf-8"), preset
    capsys.readouterr()


def test_the_table_is_a_record_array_without_pandas():
    scene = shoal.make("default", runs=2, steps=5)
    frame, records = scene.run(), scene.metrics(pandas=False)
    assert isinstance(records, np.recarray) and list(records.dtype.names) == list(frame.columns)
    np.testing.assert_array_equal(records["best_fitness"], frame["best_fitness"].to_numpy())
    assert records["step"].dtype.kind == "i"


def test_step_state_and_row():
    scene = shoal.make("sonar-xb-pso", runs=3, seed=1)
    info = scene.step(2)
    assert scene.k == 2 and info.t == pytest.approx(scene.t)
    row = scene.row()
    assert list(row) == [c.name for c in scene.columns] and row["com_dist"].shape == (3,)
    with pytest.raises(ValueError, match="n: must be >= 1"):
        scene.step(0)
    scene.reset(seed=2)
    assert scene.k == 0 and scene.engine.seed == 2 and len(scene.metrics()) == 3


def test_retune_live_by_preset_section_or_engine_keyword():
    scene, twin = shoal.make("course-dvc", runs=2, seed=3), shoal.make("course-dvc", runs=2, seed=3)
    scene.step(3), twin.step(3)
    assert scene.retune(controller={"alpha": 0.5}) == ["alpha"]
    assert scene.scenario.controller.alpha == 0.5 and scene.engine.params.alpha == 0.5
    assert twin.retune(alpha=0.5) == ["alpha"]
    scene.step(5), twin.step(5)
    np.testing.assert_array_equal(scene.state.x, twin.state.x)  # the same change, either way
    x = scene.state.x.copy()
    with pytest.raises(ValueError, match="^world: this change needs a new engine"):
        scene.retune(world={"layers": 3})
    with pytest.raises(PresetError, match="controller.alpha"):
        scene.retune(controller={"alpha": 7})
    assert scene.scenario.world.layers == 6 and scene.scenario.controller.alpha == 0.5
    np.testing.assert_array_equal(scene.state.x, x)
    swarm = shoal.make("default", controller={"mode": "raw"})
    assert swarm.retune(controller={"omega": 0.3}) == ["policy"] and swarm.scenario.controller.omega == 0.3


def test_a_sweep_in_memory_gives_the_numbers_shoal_sweep_writes(tmp_path, capsys):
    grid = {"controller.alpha": [0.5, 0.9], "controller.beta": [0.6, 0.9]}
    table = shoal.sweep("course-dvc", grid, runs=3, seed=5, steps=15, pandas=False)
    args = ["sweep", "course-dvc", "--runs", "3", "--seed", "5", "--steps", "15", "--out", str(tmp_path / "s")]
    assert main([*args, *(f"--grid={k}={','.join(map(str, v))}" for k, v in grid.items())]) == 0
    capsys.readouterr()
    with open(tmp_path / "s" / "results.csv", newline="", encoding="utf-8") as fh:
        rows = list(csv.DictReader(fh))
    assert len(rows) == len(table) == 12
    assert list(rows[0]) == list(table.dtype.names)
    for i, row in enumerate(rows):
        for name, text in row.items():
            value = table[name][i]
            assert (str(value) if name.startswith("controller.") else fmt(name, value)) == text, (i, name)


def test_the_chapter3_swarm_runs_in_any_dimension():
    for d in (10, 200):  # compiled up to 128 dimensions, numpy beyond
        scene = shoal.make("rastrigin", d=d, robots=12, runs=2, seed=1, steps=20)
        table = scene.run()
        assert scene.state.x.shape == (2, 12, d) and np.isfinite(table["best_fitness"]).all()
        assert table["best_fitness"].iloc[-1] <= table["best_fitness"].iloc[1]
    with pytest.raises(PresetError, match=r"sim.d must be 2 with \[world\]"):
        shoal.make("course-dvc", d=3)


def test_your_own_objective_as_a_function_or_a_numba_kernel():
    """A registered vectorised function runs where the built-in one does, with the same numbers."""
    def rastrigin_mine(z: np.ndarray) -> np.ndarray:
        return rastrigin(z)

    @numba.njit
    def sphere_compiled(z):
        return (z * z).sum(axis=-1)

    try:
        mine = shoal.make("rastrigin", d=10, runs=2, seed=4, objective=rastrigin_mine).run(30)
        builtin = shoal.make("rastrigin", d=10, runs=2, seed=4).run(30)
        np.testing.assert_array_equal(mine["best_fitness"], builtin["best_fitness"])
        assert load("rastrigin", ["objective.kind=rastrigin_mine"]).objective.kind == "rastrigin_mine"
        shoal.register_objective("sphere-numba", sphere_compiled)
        compiled = shoal.make("rastrigin", objective="sphere-numba", runs=2, seed=4).run(30)
        python = shoal.make("rastrigin", objective="sphere", runs=2, seed=4).run(30)
        np.testing.assert_allclose(compiled["best_fitness"], python["best_fitness"], rtol=1e-12)
        with pytest.raises(ValueError, match="'sphere-numba' is registered already"):
            shoal.register_objective("sphere-numba", sphere_compiled)
    finally:
        for name in ("rastrigin_mine", "sphere-numba"):
            OBJECTIVES._entries.pop(name, None)
    with pytest.raises(PresetError, match="objective.kind: Input should be"):
        load("rastrigin", ["objective.kind=rastrigin_mine"])


def test_a_name_in_a_preset_is_only_looked_up_never_imported():
    """No preset value imports anything: a module path or an entry point that is not installed
    is an unknown name, refused by field, and no module of that name is loaded."""
    for key, value in (("objective.kind", "json.tool:main"), ("objective.kind", "shoal_evil_plugin"),
                       ("controller.law", "os:system"), ("acoustics.algorithm", "shoal_evil_plugin.strategy")):
        preset = "sonar-xb-pso" if key.startswith("acoustics") else "default"
        with pytest.raises(PresetError, match=f"^{key}: Input should be"):
            load(preset, [f"{key}={value}"])
    assert "json.tool" not in sys.modules and "shoal_evil_plugin" not in sys.modules


def test_retune_of_a_host_swarms_slo_section_moves_the_scenario_with_the_engine():
    """``retune(slo={...})`` goes through the kind's live rule like any section: the running
    swarm's position source takes it and ``scene.scenario`` says so (it stayed stale before)."""
    scene = shoal.make("slo-adapted", runs=2, seed=4)
    scene.step(3)
    assert scene.retune(slo={"errors": "high", "selection": "rts"}) == ["slo"]
    assert (scene.scenario.slo.errors, scene.scenario.slo.selection) == ("high", "rts")
    assert scene.engine.positions.params["selection"] == "rts"
    twin = shoal.make(scene.scenario)  # the same scenario, built afresh: the settings the scene now runs with
    assert twin.engine.positions.params["selection"] == "rts"
    with pytest.raises(ValueError, match="slo: this change needs a new engine"):
        scene.retune(slo={"positions": "oracle"})  # the switch to true positions: a new scene
    assert scene.scenario.slo.positions == "slo"


def test_retune_follows_the_one_live_rule_the_app_follows():
    """What ``Scene.retune`` takes live is what the app's sessions take (the kind's ``live_keywords``)."""
    from shoal.presets.kinds import kind_for

    scene = shoal.make("course-dvc")
    new = shoal.scenario_of(scene.scenario, controller={"beta": 0.5})
    assert kind_for(scene.scenario).live_keywords(scene.scenario, new) is not None
    assert "beta" in scene.retune(controller={"beta": 0.5}) and scene.scenario.controller.beta == 0.5
    with pytest.raises(ValueError, match="robot: this change needs a new engine"):
        scene.retune(robot={"radius": 0.4})  # the robot's body: a new fleet
    assert kind_for(scene.scenario).live_keywords(scene.scenario, shoal.scenario_of(
        scene.scenario, robot={"radius": 0.4})) is None
