"""The ``shoal`` command contract (``shoal --help``; README.md), run as a real subprocess."""

import csv
import json
import subprocess
import sys

import numpy as np

from shoal.presets.build import build_simulation


def shoal(*args, cwd=None):
    return subprocess.run([sys.executable, "-m", "shoal", *args], capture_output=True, text=True, cwd=cwd, timeout=300)


def test_presets_list_and_show():
    out = shoal("presets", "list")
    assert out.returncode == 0 and "default" in out.stdout and "fig3-4a" in out.stdout
    show = shoal("presets", "show", "fig3-4b")
    assert show.returncode == 0 and 'A_plus = 4.0' in show.stdout


def test_validate_names_the_bad_field(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text('name = "x"\n[controller]\nomega = 1.7\n[sim]\nrobots = -3\n')
    out = shoal("presets", "validate", str(bad))
    assert out.returncode != 0
    assert "controller.omega" in out.stderr and "sim.robots" in out.stderr
    good = tmp_path / "good.toml"
    good.write_text('name = "x"\n[sim]\nrobots = 3\n')
    assert shoal("presets", "validate", str(good)).returncode == 0


def test_run_writes_the_contract_files_and_matches_the_engine(tmp_path):
    out_dir = tmp_path / "r"
    res = shoal("run", "default", "--runs", "2", "--seed", "11", "--steps", "30", "--set", "sim.robots=7",
                "--out", str(out_dir))
    assert res.returncode == 0, res.stderr
    meta = json.loads((out_dir / "run.json").read_text())
    assert meta["seed"] == 11 and meta["preset"]["sim"]["robots"] == 7 and meta["shoal_version"]
    with open(out_dir / "trajectories.csv") as f:
        rows = list(csv.DictReader(f))
    assert list(rows[0]) == ["run", "step", "t", "robot", "x", "y", "heading", "vx", "vy", "status"]
    assert len(rows) == 2 * 7 * 31
    # the resolved preset in run.json reproduces the trajectories
    from shoal.presets.io import validate

    sim = build_simulation(validate(meta["preset"]))
    for _ in range(30):
        sim.step()
    last = np.array([[float(r["x"]), float(r["y"])] for r in rows if r["step"] == "30"]).reshape(2, 7, 2)
    assert np.allclose(last, sim.state.x, rtol=1e-8, atol=1e-8)
    with open(out_dir / "metrics.csv") as f:
        metrics = list(csv.DictReader(f))
    assert len(metrics) == 2 * 31 and {"run", "step", "t", "best_fitness", "max_speed"} <= set(metrics[0])


def test_run_is_deterministic(tmp_path):
    for name in ("a", "b"):
        res = shoal("run", "smooth-tanh", "--steps", "15", "--seed", "3", "--out", str(tmp_path / name))
        assert res.returncode == 0
    assert (tmp_path / "a" / "trajectories.csv").read_bytes() == (tmp_path / "b" / "trajectories.csv").read_bytes()


def test_bad_set_value_is_refused_and_nothing_is_written(tmp_path):
    out = shoal("run", "default", "--set", "controller.omega=abc", "--out", str(tmp_path / "r"))
    assert out.returncode == 2 and "controller.omega" in out.stderr
    assert not (tmp_path / "r").exists()
    beta = shoal("run", "default", "--set", "controller.A_plus=500", "--out", str(tmp_path / "r"))
    assert beta.returncode == 2 and "faster" in beta.stderr


def test_unknown_preset_and_bad_file(tmp_path):
    assert shoal("run", "nope").returncode == 2
    broken = tmp_path / "broken.toml"
    broken.write_text("[sim\n")
    out = shoal("run", str(broken))
    assert out.returncode == 2 and "TOML syntax" in out.stderr


def test_reproduce_list():
    out = shoal("reproduce", "--list")
    assert out.returncode == 0 and "fig3-4" in out.stdout and "fig3-5" in out.stdout


def test_help_for_every_command():
    for cmd in ("serve", "run", "reproduce", "presets"):
        assert shoal(cmd, "--help").returncode == 0


def test_reproduce_quick_runs_the_classroom_size(tmp_path):
    out = shoal("reproduce", "fig3-5", "--quick", "--out", str(tmp_path / "q"))
    assert out.returncode == 0, out.stderr
    summary = json.loads((tmp_path / "q" / "summary.json").read_text(encoding="utf-8"))
    assert summary["quick"] is True and summary["runs"] == 20


def test_serve_refuses_bad_experiment_settings_in_one_line():
    res = shoal("serve", "--port", "0", "--experiment-workers", "0")
    assert res.returncode == 2
    assert res.stderr.strip().endswith("error: argument --experiment-workers: must be at least 1, got 0")
    res = subprocess.run([sys.executable, "-m", "shoal", "serve", "--port", "0", "--scheduler", "tcp://127.0.0.1:9"],
                         capture_output=True, text=True, timeout=120)
    assert res.returncode != 0 and "cannot reach the Dask scheduler at 'tcp://127.0.0.1:9'" in res.stderr
