"""Reproduction targets fig3-4 and fig3-5: outputs, determinism, key claims, atomic writes.

Small seeded runs (few runs, swarms of at most 30 particles) keep the whole file quick.
"""

from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np
import pytest

from shoal.presets.io import load
from shoal.studies.experiments import TARGETS, OutputDirError, chapter3, reproduce, run_batch, run_jobs
from shoal.studies.experiments.runner import Job

HEADER = "case,run,seed,swarm_size,U,A_plus,dt,beta,max_speed"
SMALL = {"sizes": (10, 30)}


@pytest.fixture(scope="module")
def fig34(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("r") / "fig3-4"
    reproduce("fig3-4", out, runs=3, progress=False, **SMALL)
    return out


@pytest.fixture(scope="module")
def fig35(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("r") / "fig3-5"
    reproduce("fig3-5", out, runs=3, progress=False, **SMALL)
    return out


def _rows(path: Path) -> list[dict[str, str]]:
    with open(path, newline="", encoding="utf-8") as fh:
        return list(csv.DictReader(fh))


def _checks(out: Path) -> dict[str, dict]:
    return {c["name"]: c for c in json.loads((out / "summary.json").read_text(encoding="utf-8"))["checks"]}


def test_registry_names_both_targets():
    assert {"fig3-4", "fig3-5"} <= set(TARGETS)
    for t in TARGETS.values():
        assert t.description and t.default_runs >= 1


@pytest.mark.parametrize("fixture, files", [
    ("fig34", ["summary.json", "runs.csv", "series.csv", "fig3-4.png", "fig3-4-literal.png", "README.md"]),
    ("fig35", ["summary.json", "runs.csv", "series.csv", "fig3-5.png", "README.md"]),
])
def test_outputs_exist_with_the_exact_runs_header(fixture, files, request):
    out: Path = request.getfixturevalue(fixture)
    for name in files:
        assert (out / name).is_file() and (out / name).stat().st_size > 0, name
    assert (out / "runs.csv").read_text(encoding="utf-8").splitlines()[0] == HEADER
    assert (out / "series.csv").read_text(encoding="utf-8").splitlines()[0] == ",".join(chapter3.SERIES_COLUMNS)
    summary = json.loads((out / "summary.json").read_text(encoding="utf-8"))
    assert summary["target"] == out.name and summary["runs"] == 3 and summary["elapsed_s"] >= 0
    assert summary["cpu_s"] > 0
    for c in summary["checks"]:
        assert set(c) == {"name", "thesis", "measured", "pass", "verdict", "runs"} and isinstance(c["pass"], bool)
        assert c["verdict"] in ("holds", "fails", "undecided") and c["runs"] in (None, 3)
    assert not [p for p in out.parent.iterdir() if p.name.startswith(".")]  # no partial folders left


def test_runs_csv_has_one_row_per_case_size_and_run(fig34, fig35):
    rows = _rows(fig34 / "runs.csv")
    assert len(rows) == 8 * 2 * 3
    assert {r["case"] for r in rows} == {f"3-4{p}/{m}" for p in "abcd" for m in ("ahead", "literal")}
    rows5 = _rows(fig35 / "runs.csv")
    assert len(rows5) == 3 * 2 * 3
    assert {r["U"] for r in rows5} == {"20;4;20"}


def test_same_seed_gives_identical_files_and_workers_do_not_matter(fig34, tmp_path):
    again = tmp_path / "again"
    reproduce("fig3-4", again, runs=3, progress=False, **SMALL)
    pooled = tmp_path / "pooled"
    reproduce("fig3-4", pooled, runs=3, workers=2, progress=False, **SMALL)
    for name in ("runs.csv", "series.csv"):
        ref = (fig34 / name).read_bytes()
        assert (again / name).read_bytes() == ref
        assert (pooled / name).read_bytes() == ref


def test_chunking_of_runs_does_not_change_results():
    jobs = [Job(("3-5b", 12), "fig3-5b", ("sim.robots=12",), seed=9, runs=5, steps=40, track=3)]
    whole = run_jobs(jobs, chunk=5)[("3-5b", 12)]
    pieces = run_jobs(jobs, chunk=2)[("3-5b", 12)]
    assert np.array_equal(whole.max_speed, pieces.max_speed)
    assert np.array_equal(whole.tracked, pieces.tracked)


def test_fig3_4_key_claims(fig34):
    rows = _rows(fig34 / "runs.csv")
    speed = lambda case: [float(r["max_speed"]) for r in rows if r["case"] == case]  # noqa: E731
    assert all(float(r["max_speed"]) <= float(r["U"]) for r in rows)  # never above U
    ahead_a = max(speed("3-4a/ahead"))
    assert 19.0 <= ahead_a <= 20.0
    for p in "abcd":
        assert max(speed(f"3-4{p}/literal")) <= 10.0 + 1e-9  # U/2
    assert max(speed("3-4b/ahead")) < ahead_a and max(speed("3-4c/ahead")) < ahead_a
    checks = _checks(fig34)
    assert checks["no speed above U = 20 m/s (every run, case, swarm size, iteration)"]["pass"]
    per_iteration = [c for n, c in checks.items() if "per iteration" in n]
    assert len(per_iteration) == 2 and all(c["measured"] == 0.0 and c["pass"] for c in per_iteration)


def test_equal_beta_cases_are_identical_per_iteration():
    """3-4b (A+ = 4, Δt = 1) and 3-4c (A+ = 20, Δt = 0.2) share ω = 0.8 and ĉ = 4."""
    b = run_batch(load("fig3-4b", ["sim.robots=25"]), runs=3, seed=11, steps=100, track=7)
    c = run_batch(load("fig3-4c", ["sim.robots=25"]), runs=3, seed=11, steps=100, track=7)
    assert np.array_equal(b.max_speed, c.max_speed)
    assert np.array_equal(b.tracked, c.tracked)
    assert b.t[-1] == pytest.approx(100.0) and c.t[-1] == pytest.approx(20.0)  # same iterations, 5× the time


def test_fig3_5_bounds_and_fast_responses(fig35):
    checks = _checks(fig35)
    envelope = [c for n, c in checks.items() if n.startswith("every speed within the worst-case envelope")]
    decayed = [c for n, c in checks.items() if n.startswith("no speed above the U that commanded it")]
    assert envelope[0]["pass"] and decayed[0]["pass"]
    fast = [c for n, c in checks.items() if "high β follows at once" in n]
    assert len(fast) == 4 and all(c["pass"] for c in fast)
    series = _rows(fig35 / "series.csv")
    at = {(r["case"], r["swarm_size"], float(r["t"])): r for r in series}
    assert float(at[("3-5a/ahead", "30", 50.0)]["U"]) == 4.0
    assert float(at[("3-5a/ahead", "30", 80.0)]["U"]) == 20.0


def test_envelope_allows_the_transient_after_a_drop_of_U():
    """After U drops 20 → 4 with ω = 0.8 the speed exceeds the new U for a while but never B."""
    res = run_batch(load("fig3-5b", ["sim.robots=50"]), runs=2, seed=4, steps=60)
    b = res.envelope()
    assert np.all(res.max_speed <= b[:, None] + 1e-12)
    after = res.t[1:] == 36.0  # two iterations after the switch at 34 s
    assert np.all(res.max_speed[1:][after] > res.U_command[after, None])  # still above U = 4
    assert b[36] == pytest.approx(4.0 + 0.8**2 * 16.0)


def test_a_failed_run_leaves_no_output_and_keeps_an_earlier_one(tmp_path, monkeypatch):
    def broken(*args, **kwargs):
        raise RuntimeError("disk full")

    monkeypatch.setattr(chapter3, "save_figure", broken)  # fails after runs.csv and series.csv are written
    fresh = tmp_path / "fresh"
    with pytest.raises(RuntimeError, match="disk full"):
        reproduce("fig3-5", fresh, runs=2, progress=False, sizes=(10,))
    assert not fresh.exists()
    assert list(tmp_path.iterdir()) == []  # no partial folder either

    monkeypatch.undo()
    kept = tmp_path / "kept"
    reproduce("fig3-5", kept, runs=2, progress=False, sizes=(10,))
    before = {p.name: p.read_bytes() for p in kept.iterdir()}
    monkeypatch.setattr(chapter3, "save_figure", broken)
    with pytest.raises(RuntimeError):
        reproduce("fig3-5", kept, runs=3, progress=False, sizes=(10,))
    assert {p.name: p.read_bytes() for p in kept.iterdir()} == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["kept"]


def test_refuses_to_replace_a_folder_that_is_not_a_reproduction(tmp_path):
    (tmp_path / "notes.txt").write_text("mine", encoding="utf-8")
    with pytest.raises(OutputDirError):
        reproduce("fig3-5", tmp_path, runs=1, progress=False, sizes=(10,))
    assert (tmp_path / "notes.txt").read_text(encoding="utf-8") == "mine"


def test_bad_arguments_are_refused(tmp_path):
    with pytest.raises(KeyError):
        reproduce("fig9-9", tmp_path / "x", progress=False)
    with pytest.raises(ValueError):
        reproduce("fig3-5", tmp_path / "x", runs=0, progress=False)
    with pytest.raises(ValueError):
        reproduce("fig3-5", tmp_path / "x", workers=0, progress=False)
    assert not (tmp_path / "x").exists()
