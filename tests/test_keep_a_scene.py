"""A scene a researcher can keep: its trajectories as a tidy table (``trajectories.csv``'s
columns), ``shoal.run(..., trajectories=True)``, a pickled scene that goes on the same, and
``scene.save_preset`` that loads back to an equal scenario."""

from __future__ import annotations

import io
import pickle

import numpy as np
import pytest

import shoal
from shoal.engine.core.recorder import trajectory_header, write_trajectory
from shoal.engine.core.runs import run_to_dir
from shoal.presets.build import build
from shoal.presets.io import list_presets, load


def test_trajectories_are_the_rows_of_trajectories_csv(tmp_path):
    scene = shoal.make("course-dvc", runs=2, seed=3, trajectories=True)
    scene.run(5)
    table = scene.trajectories(pandas=False)
    assert list(table.dtype.names) == trajectory_header(2).split(",")
    assert len(table) == 6 * 2 * scene.engine.robots  # steps 0..5, every run and robot
    assert table["run"].dtype == table["step"].dtype == table["robot"].dtype == table["status"].dtype == np.int64
    last = table[table["step"] == 5]
    np.testing.assert_array_equal(last["x"], scene.state.x[..., 0].ravel())
    np.testing.assert_array_equal(last["vy"], scene.state.u[..., 1].ravel())
    frame = scene.trajectories()  # pandas by default
    assert list(frame.columns) == list(table.dtype.names) and frame["step"].max() == 5


def test_trajectories_match_what_shoal_run_writes(tmp_path):
    """The rows of the command's trajectories.csv, to the digits it writes."""
    scene = shoal.make("course-dvc", runs=2, seed=3, steps=4, trajectories=True)
    scene.run()
    run_to_dir(build(scene.scenario), 4, tmp_path / "run", {})
    written = np.loadtxt(tmp_path / "run" / "trajectories.csv", delimiter=",", skiprows=1)
    table = scene.trajectories(pandas=False)
    buf = io.StringIO()
    write_trajectory(buf, np.stack([np.asarray(table[n], dtype=float) for n in table.dtype.names], axis=1))
    np.testing.assert_array_equal(np.loadtxt(io.StringIO(buf.getvalue()), delimiter=","), written)


def test_three_dimensions_add_z_and_vz():
    scene = shoal.make("default", d=3, runs=1, robots=4, trajectories=True)
    scene.step(2)
    table = scene.trajectories(pandas=False)
    assert table.dtype.names[-2:] == ("z", "vz")
    np.testing.assert_array_equal(table[table["step"] == 2]["z"], scene.state.x[0, :, 2])


def test_a_scene_without_trajectories_says_how_to_keep_them():
    with pytest.raises(ValueError, match=r"trajectories=True"):
        shoal.make("default").trajectories()


def test_run_with_trajectories_gives_both_tables():
    out = shoal.run("default", runs=2, steps=3, trajectories=True, pandas=False)
    metrics, paths = out
    assert out.metrics is metrics and len(metrics) == 4 * 2
    assert len(paths) == 4 * 2 * shoal.make("default").engine.robots and paths["step"].max() == 3
    assert len(shoal.run("default", runs=2, steps=3, pandas=False)) == 8  # without: the metrics, as before


def test_trajectories_come_back_with_a_snapshot():
    scene = shoal.make("slo-walk", runs=1, seed=2, trajectories=True)
    scene.run(3)
    again = shoal.make(snapshot=scene.snapshot().to_bytes())
    scene.run(4)
    again.run(4)
    np.testing.assert_array_equal(np.asarray(again.trajectories(pandas=False).tolist()),
                                  np.asarray(scene.trajectories(pandas=False).tolist()))


PICKLE_PRESETS = ["default", "smooth-tanh", "course-dvc", "course-physics", "escort-moving", "slo-walk", "slo-adapted",
                  "course-dvc-slo"]


@pytest.mark.parametrize("preset", PICKLE_PRESETS)
def test_a_pickled_scene_goes_on_the_same(preset):
    scene = shoal.make(preset, runs=2, seed=6, trajectories=True)
    scene.run(4)
    copy = pickle.loads(pickle.dumps(scene))
    assert copy.kind is scene.kind and copy.scenario == scene.scenario
    scene.run(20)
    copy.run(20)
    for n in ("x", "u", "status"):
        assert np.asarray(getattr(copy.state, n)).tobytes() == np.asarray(getattr(scene.state, n)).tobytes()
    a, b = scene.metrics(pandas=False), copy.metrics(pandas=False)
    assert all(np.asarray(a[n]).tobytes() == np.asarray(b[n]).tobytes() for n in a.dtype.names)


def test_the_laws_pickle():
    from shoal.engine.pso.laws import LAWS

    for law in LAWS.values():
        back = pickle.loads(pickle.dumps(law.velocity))
        u = np.zeros((1, 2, 2))
        g = np.ones((2, 1, 2, 2))
        r = np.full((2, 1, 2, 2), 0.5)
        np.testing.assert_array_equal(back(u, g, np.array([1.0, 1.0]), 0.5, r, 1.0),
                                      law.velocity(u, g, np.array([1.0, 1.0]), 0.5, r, 1.0))


@pytest.mark.parametrize("preset", list_presets())
def test_save_preset_round_trips_to_an_equal_scenario(preset, tmp_path):
    scene = shoal.make(preset)
    path = scene.save_preset(tmp_path / f"{preset}.toml")
    assert load(path) == scene.scenario
    assert shoal.make(path).scenario == scene.scenario


def test_save_preset_keeps_a_retune_and_never_overwrites_unasked(tmp_path):
    scene = shoal.make("course-dvc", runs=3, seed=9)
    scene.retune(controller={"alpha": 0.55})
    path = tmp_path / "mine.toml"
    path.write_text("# my notes\n")
    with pytest.raises(FileExistsError, match="exists already"):
        scene.save_preset(path)
    assert path.read_text() == "# my notes\n"
    scene.save_preset(path, overwrite=True)
    back = load(path)
    assert back == scene.scenario and back.controller.alpha == 0.55 and back.sim.runs == 3
    assert sorted(p.name for p in tmp_path.iterdir()) == ["mine.toml"]
