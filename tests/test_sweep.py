"""``shoal sweep``: grid parsing, the tidy table, pictures, resuming, refusals, every scene kind,
and a local pool that loses a worker process."""

from __future__ import annotations

import csv
import functools
import json
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from shoal.engine.core.recorder import metric_table
from shoal.presets.build import build
from shoal.presets.io import load
from shoal.studies.sweep import SweepError, run_sweep, simulate_cell
from shoal.studies.sweep.grid import parse_axis, parse_values

GRID = ["controller.U=2,4", "controller.A_plus=5,10"]
RUNS, STEPS = 2, 20


def _sweep(out: Path, grid=GRID, **kw):
    kw = {"runs": RUNS, "steps": STEPS, "progress": False, **kw}
    return run_sweep("default", grid, out, **kw)


def _rows(path: Path) -> list[dict[str, str]]:
    with open(path, newline="", encoding="utf-8") as fh:
        return list(csv.DictReader(fh))


def _mtimes(out: Path) -> dict[str, int]:
    return {p.name: p.stat().st_mtime_ns for p in sorted((out / "cells").iterdir())}


@pytest.fixture(scope="module")
def swept(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("sweep") / "s"
    report = _sweep(out)
    assert report.cells == 4 and report.computed == 4
    return out


def test_grid_values_are_toml_literals_or_bare_words():
    assert parse_values("1,1.5,3") == [1, 1.5, 3]
    assert parse_values("b-pso,xb-pso") == ["b-pso", "xb-pso"]
    assert parse_values("[0,0],[1.5,2]") == [[0, 0], [1.5, 2]]
    assert parse_values('"a,b",c') == ["a,b", "c"]
    assert parse_values("true,false") == [True, False]
    axis = parse_axis("acoustics.Q = 1, 10")
    assert axis.key == "acoustics.Q" and axis.labels == ("1", "10")
    bad_grids = (("acoustics.Q", "expected"), ("acoustics.Q=1,,2", "empty value"), ("acoustics.Q=1,1", "repeated"))
    for bad, words in bad_grids:
        with pytest.raises(SweepError, match=words):
            parse_axis(bad)


def test_results_table_has_one_row_per_cell_and_run(swept):
    rows = _rows(swept / "results.csv")
    cols = list(rows[0])
    assert cols[:4] == ["controller.U", "controller.A_plus", "run", "seed"]
    assert {"step", "t", "peak_speed", "best_fitness", "max_speed", "omega", "c_hat"} <= set(cols)
    assert len(rows) == 4 * RUNS
    assert sorted((r["controller.U"], r["controller.A_plus"], r["run"]) for r in rows) == sorted(
        (u, a, str(k)) for u in ("2", "4") for a in ("5", "10") for k in range(RUNS))
    assert {r["seed"] for r in rows} == {str(load("default").sim.seed)}
    assert {r["step"] for r in rows} == {str(STEPS)}
    medians = _rows(swept / "medians.csv")
    assert len(medians) == 4 and all(m["runs"] == str(RUNS) for m in medians)


def test_outcomes_are_those_of_the_preset_built_like_shoal_run(swept):
    """Cell (U = 4, A+ = 10) equals the same preset with the same overrides, built and stepped directly."""
    scenario = load("default", ["controller.U=4", "controller.A_plus=10", f"sim.steps={STEPS}"])
    sim = build(scenario, runs=RUNS, seed=scenario.sim.seed)
    peak = np.linalg.norm(sim.state.u, axis=-1).max(axis=1)
    for _ in range(STEPS):
        info = sim.step()
        peak = np.maximum(peak, np.linalg.norm(sim.state.u, axis=-1).max(axis=1))
    table = metric_table(sim.state, info, sim.t)
    rows = [r for r in _rows(swept / "results.csv") if r["controller.U"] == "4" and r["controller.A_plus"] == "10"]
    for r in rows:
        k = int(r["run"])
        assert float(r["best_fitness"]) == pytest.approx(table["best_fitness"][k], rel=1e-11)
        assert float(r["max_speed"]) == pytest.approx(table["max_speed"][k], rel=1e-11)
        assert float(r["peak_speed"]) == pytest.approx(peak[k], rel=1e-11)


def test_pictures_and_manifest(swept):
    pngs = sorted(p.name for p in swept.glob("median_*.png"))
    assert "median_peak_speed.png" in pngs and "median_best_fitness.png" in pngs
    assert all((swept / p).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" for p in pngs)
    meta = json.loads((swept / "sweep.json").read_text())
    assert meta["preset_name"] == "default" and meta["runs"] == RUNS and meta["shoal_version"]
    assert meta["grid"] == {"controller.U": ["2", "4"], "controller.A_plus": ["5", "10"]}
    assert meta["seed"] == load("default").sim.seed and meta["status"] == "finished"
    assert set(meta["files"]) >= {"results.csv", "medians.csv", *pngs}


def test_rerun_skips_every_finished_cell(swept, tmp_path):
    out = tmp_path / "again"
    shutil.copytree(swept, out)
    before = _mtimes(out)
    report = _sweep(out)
    assert report.computed == 0
    assert _mtimes(out) == before
    assert (out / "results.csv").read_bytes() == (swept / "results.csv").read_bytes()


def test_a_missing_cell_is_the_only_one_recomputed(swept, tmp_path):
    out = tmp_path / "half"
    shutil.copytree(swept, out)
    (out / "results.csv").unlink()
    (out / "cells" / "cell-00002.csv").unlink()
    before = _mtimes(out)
    report = _sweep(out)
    assert report.computed == 1
    after = _mtimes(out)
    assert {k: v for k, v in after.items() if k != "cell-00002.csv"} == before
    assert (out / "results.csv").read_bytes() == (swept / "results.csv").read_bytes()


def test_bad_grid_key_or_value_is_refused_before_anything_runs(tmp_path):
    out = tmp_path / "bad"
    with pytest.raises(SweepError) as err:
        _sweep(out, ["controller.bogus=1,2", "controller.A_plus=5,-1"])
    text = "\n".join(err.value.messages)
    assert "controller.bogus" in text and "controller.A_plus" in text and "(got -1)" in text
    assert not out.exists()
    with pytest.raises(SweepError, match="sim.runs"):
        _sweep(out, ["sim.runs=1,2"])
    with pytest.raises(SweepError, match="controller.U: given twice"):
        _sweep(out, ["controller.U=2", "controller.U=4"])
    with pytest.raises(SweepError, match="also fixed"):
        _sweep(out, ["controller.U=2,4"], sets=["controller.U=3"])
    assert not out.exists()


def test_a_different_sweep_into_the_same_folder_is_refused(swept, tmp_path):
    out = tmp_path / "other"
    shutil.copytree(swept, out)
    before = _mtimes(out)
    with pytest.raises(SweepError, match="different sweep.*grid"):
        _sweep(out, ["controller.U=2,4", "controller.A_plus=5,8"])
    with pytest.raises(SweepError, match="different sweep.*runs"):
        _sweep(out, runs=3)
    assert _mtimes(out) == before
    stranger = tmp_path / "stranger"
    stranger.mkdir()
    (stranger / "notes.txt").write_text("mine")
    with pytest.raises(SweepError, match="holds no sweep.json"):
        _sweep(stranger)


@pytest.mark.parametrize("preset, grid, extra", [
    ("course-dvc", "controller.alpha=0.5,0.9", {"com_fitness", "collided", "operational", "layers_passed"}),
    ("sonar-xb-pso", "acoustics.algorithm=b-pso,xb-pso",
     {"com_dist", "converged", "steps_to_converge", "time_to_converge_s", "frac_inside_ring"}),
    ("slo-walk", "slo.prediction_weight=0,0.5", {"e_abs_mean", "quality_met_at", "dead_reckoning"}),
])
def test_every_scene_kind_sweeps(tmp_path, preset, grid, extra):
    out = tmp_path / "k"
    report = run_sweep(preset, [grid], out, runs=2, steps=8, progress=False)
    rows = _rows(out / "results.csv")
    assert len(rows) == 4 and extra <= set(rows[0])
    assert report.plots and all((out / p).is_file() for p in report.plots)


def test_three_axes_give_faceted_heat_maps(tmp_path):
    out = tmp_path / "3d"
    report = _sweep(out, GRID + ["controller.dt=0.05,0.1"], runs=1, steps=5)
    assert report.cells == 8 and len(_rows(out / "results.csv")) == 8
    assert "median_peak_speed.png" in report.plots


def die_once(marker: str, job, first_run: int, runs: int):
    """Kill this worker process the first time cell 1 is simulated (the marker records it)."""
    if job.key == 1 and not Path(marker).exists():
        Path(marker).write_text(str(os.getpid()))
        os._exit(1)
    return simulate_cell(job, first_run, runs)


def test_a_local_pool_that_loses_a_worker_retries_the_unfinished_cells(swept, tmp_path):
    marker = tmp_path / "killed"
    out = tmp_path / "pool"
    report = _sweep(out, workers=2, simulate=functools.partial(die_once, str(marker)))
    assert marker.exists() and int(marker.read_text()) != os.getpid()
    assert report.computed == 4
    assert (out / "results.csv").read_bytes() == (swept / "results.csv").read_bytes()


def test_cli_sweep_writes_and_names_bad_fields(tmp_path):
    out = tmp_path / "cli"
    run = [sys.executable, "-m", "shoal", "sweep", "default", "--grid", "controller.U=6,8", "--runs", "2",
           "--steps", "10", "--out", str(out)]
    res = subprocess.run(run, capture_output=True, text=True, timeout=300)
    assert res.returncode == 0, res.stderr
    assert "2 cells x 2 runs" in res.stdout and len(_rows(out / "results.csv")) == 4
    assert (out / "median_peak_speed.png").is_file()  # 1-D grid: a line
    bad = subprocess.run([*run[:6], "controller.U=6,-8", *run[7:]], capture_output=True, text=True, timeout=300)
    assert bad.returncode == 2 and "controller.U" in bad.stderr and "different sweep" not in bad.stderr


def test_killed_or_interrupted_sweeps_keep_their_finished_cells(tmp_path):
    """Cell 0 takes 5 steps, cell 1 ten million: stop the sweep while it is in cell 1."""
    out = tmp_path / "stop"
    cmd = [sys.executable, "-m", "shoal", "sweep", "default", "--grid", "sim.steps=5,10000000", "--runs", "2",
           "--out", str(out)]

    def start_and_wait_for_cell_0() -> subprocess.Popen:
        # a pytest-xdist worker ignores SIGINT and a child would inherit that: give it a shell's default
        proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                                preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
        deadline = time.monotonic() + 120
        while not (out / "cells" / "cell-00001.csv").exists() and time.monotonic() < deadline:
            if (out / "cells" / "cell-00000.csv").exists() and proc.poll() is None:
                return proc
            time.sleep(0.02)
        proc.kill()
        pytest.fail("cell 0 never finished")

    proc = start_and_wait_for_cell_0()
    proc.send_signal(signal.SIGKILL)
    proc.communicate(timeout=60)
    first = (out / "cells" / "cell-00000.csv").stat().st_mtime_ns
    assert [p.name for p in (out / "cells").iterdir()] == ["cell-00000.csv"]
    assert len(_rows(out / "cells" / "cell-00000.csv")) == 2
    opened = (out / "sweep.json").stat().st_mtime_ns
    proc = start_and_wait_for_cell_0()  # resumes: cell 0 is kept, cell 1 starts
    deadline = time.monotonic() + 60
    while (out / "sweep.json").stat().st_mtime_ns == opened and proc.poll() is None and time.monotonic() < deadline:
        time.sleep(0.02)  # until the rerun has opened the folder (rewritten its manifest)
    time.sleep(1.0)
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 130 and "rerun the same command to resume" in err
    assert [p.name for p in (out / "cells").iterdir()] == ["cell-00000.csv"]
    assert (out / "cells" / "cell-00000.csv").stat().st_mtime_ns == first
    assert not (out / "results.csv").exists()
