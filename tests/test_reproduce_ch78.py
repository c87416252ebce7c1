"""Chapter 7–8 reproduction targets on tiny runs: files, headers, determinism, workers."""

from __future__ import annotations

import csv
import json

import pytest

from shoal.studies.experiments import TARGETS, reproduce
from shoal.studies.experiments.fig8_4 import CASES as STATIONARY
from shoal.studies.experiments.fig8_5 import CASES as MOVING

CH78 = ("fig7-2", "fig7-4", "fig7-5", "fig8-2", "fig8-4", "fig8-5")


def rows(path):
    with open(path, encoding="utf-8") as fh:
        return list(csv.reader(fh))


def test_targets_are_registered():
    assert set(CH78) <= set(TARGETS)
    assert TARGETS["fig7-2"].default_runs == 100 and TARGETS["fig8-4"].default_runs == 20


def test_fig7_2_tiny_run_files_determinism_and_xb_pso_converges(tmp_path):
    opts = dict(steps=1500, snrs=(10.0,), algorithms=("b-pso", "xb-pso"))
    s1 = reproduce("fig7-2", tmp_path / "a", runs=3, workers=1, progress=False, **opts)
    got = rows(tmp_path / "a" / "runs.csv")
    assert got[0] == ["case", "run", "seed", "snr0_db", "c1_share", "converged", "steps_to_converge"]
    assert len(got) == 1 + 2 * 3 * 2  # both splits of ĉ run as cases
    assert {r[4] for r in got[1:]} == {"0.25", "0.5"}
    xb = [r for r in got[1:] if r[0] == "xb-pso"]
    assert all(r[5] == "1" and 133 <= int(r[6]) <= 1500 for r in xb)  # converges at 10 dB, never faster than a line
    assert {"fig7-2.png", "series.csv", "README.md", "summary.json", "routes.npz"} <= {
        p.name for p in (tmp_path / "a").iterdir()}
    summary = json.loads((tmp_path / "a" / "summary.json").read_text())
    assert summary["target"] == "fig7-2" and all({"name", "thesis", "measured", "pass"} <= set(c) for c in s1["checks"])
    assert summary["c1_share"] == 0.25 and all(c["name"].startswith("[c1:c2 = 1:1]") for c in summary["information"])
    reproduce("fig7-2", tmp_path / "b", runs=3, workers=2, progress=False, **opts)
    for name in ("runs.csv", "series.csv"):
        assert (tmp_path / "a" / name).read_bytes() == (tmp_path / "b" / name).read_bytes(), name


def test_fig8_2_tiny_run_header_and_repeat(tmp_path):
    for out in ("a", "b"):
        reproduce("fig8-2", tmp_path / out, runs=2, workers=1, progress=False, steps=40, snrs=(10.0,))
    got = rows(tmp_path / "a" / "runs.csv")
    assert got[0] == ["case", "run", "seed", "snr0_db", "converged", "steps_to_converge"]
    assert {r[0] for r in got[1:]} == {"gt-pso", "xb-pso"} and len(got) == 5
    assert (tmp_path / "a" / "runs.csv").read_bytes() == (tmp_path / "b" / "runs.csv").read_bytes()


@pytest.mark.parametrize("target, cases", [("fig8-4", STATIONARY[:1] + STATIONARY[4:5]), ("fig8-5", MOVING[:2])])
def test_escort_tiny_runs_write_the_escort_columns(target, cases, tmp_path):
    a = reproduce(target, tmp_path / "a", runs=2, workers=1, progress=False, steps=30, cases=cases)
    b = reproduce(target, tmp_path / "b", runs=2, workers=2, progress=False, steps=30, cases=cases)
    got = rows(tmp_path / "a" / "runs.csv")
    assert got[0] == ["case", "run", "seed", "n_robots", "r", "v_n", "psd_s", "frac_inside_ring",
                      "mean_dist_to_source"]
    assert len(got) == 1 + 2 * len(cases)
    assert (tmp_path / "a" / "runs.csv").read_bytes() == (tmp_path / "b" / "runs.csv").read_bytes()
    assert (tmp_path / "a" / "occupancy.csv").read_bytes() == (tmp_path / "b" / "occupancy.csv").read_bytes()
    assert [c["measured"] for c in a["checks"]] == [c["measured"] for c in b["checks"]]
    assert (tmp_path / "a" / f"{target}.png").is_file()


@pytest.mark.parametrize("target, opts", [
    ("fig7-4", dict(q=(1.5, 10.0), d=(0.5, 1.0))),
    ("fig7-5", dict(q=(1.5, 10.0), u=(2.0, 8.0))),
])
def test_sweep_tiny_runs_write_runs_and_grid(target, opts, tmp_path):
    reproduce(target, tmp_path / "a", runs=1, workers=1, progress=False, steps=20, mode="surrogate", **opts)
    got = rows(tmp_path / "a" / "runs.csv")
    assert got[0] == ["case", "run", "seed", "Q", "d_over_lambda", "U", "c1_share", "converged", "steps_to_converge"]
    grid = rows(tmp_path / "a" / "grid.csv")
    assert grid[0][:5] == ["case", "Q", "d_over_lambda", "U", "c1_share"] and len(grid) == len(got)
    assert (tmp_path / "a" / f"{target}.png").is_file()
    shares = {r[4] for r in grid[1:]}
    assert shares == ({"0.25", "0.5"} if target == "fig7-5" else {"0.25"})  # fig7-5 runs both splits
    if target == "fig7-5":
        assert (tmp_path / "a" / "fig7-5-c1c2-1-1.png").is_file()


def test_fig7_3_reads_the_fig7_2_routes_or_simulates_the_same_runs(tmp_path):
    opts = dict(steps=300)
    reproduce("fig7-2", tmp_path / "all" / "fig7-2", runs=2, workers=1, progress=False, snrs=(10.0,), **opts)
    beside = reproduce("fig7-3", tmp_path / "all" / "fig7-3", runs=2, workers=1, progress=False, **opts)
    alone = reproduce("fig7-3", tmp_path / "alone", runs=2, workers=2, progress=False, **opts)
    assert beside["routes_from"].startswith("read from the fig7-2 run")
    assert alone["routes_from"] == "simulated by this target" and (tmp_path / "alone" / "routes.npz").is_file()
    for name in ("runs.csv", "density.csv"):  # the same runs either way
        assert (tmp_path / "all" / "fig7-3" / name).read_bytes() == (tmp_path / "alone" / name).read_bytes(), name
    got = rows(tmp_path / "alone" / "runs.csv")
    assert got[0] == ["case", "run", "seed", "converged", "steps_to_converge", "path_length", "straightness", "spread"]
    assert {r[0] for r in got[1:]} == {"a-pso", "x-pso", "b-pso", "xb-pso"} and len(got) == 1 + 4 * 2
    assert all(-1.0 <= float(r[6]) <= 1.0 for r in got[1:])
    assert (tmp_path / "alone" / "fig7-3.png").is_file() and len(alone["checks"]) == 3
