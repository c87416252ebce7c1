"""``shoal reproduce --all`` and the REPRODUCTION.md report."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from shoal.studies.experiments.report import REPORT, collect, run_all, write_report

QUICK = ["fig3-5", "fig3-4"]


@pytest.fixture(scope="module")
def reproduced(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("all")
    run_all(out, targets=QUICK, progress=False, quick=True, log=lambda _m: None)  # the classroom size
    return out


def test_quick_runs_every_target_at_its_classroom_size_and_says_so(reproduced: Path) -> None:
    from shoal.studies.experiments import TARGETS

    assert all("runs" in t.quick and t.quick_runs <= t.default_runs for t in TARGETS.values())
    text = (reproduced / REPORT).read_text(encoding="utf-8")
    assert "Quick (classroom) size:" in text
    for name in QUICK:
        summary = json.loads((reproduced / name / "summary.json").read_text(encoding="utf-8"))
        assert summary["quick"] is True and summary["runs"] == TARGETS[name].quick_runs
        assert f"{TARGETS[name].quick_runs} (quick)" in text and f"`shoal reproduce {name} --quick" in text


def test_every_target_gets_a_folder_and_a_section(reproduced: Path) -> None:
    text = (reproduced / REPORT).read_text(encoding="utf-8")
    for name in QUICK:
        summary = json.loads((reproduced / name / "summary.json").read_text(encoding="utf-8"))
        counts = [sum(c["verdict"] == v for c in summary["checks"]) for v in ("holds", "fails", "undecided")]
        assert f"| [{name}](#{name}) |" in text
        assert f"| {len(summary['checks'])} | {counts[0]} | {counts[1]} | {counts[2]} |" in text
        assert f"## {name}:" in text
        for check in summary["checks"]:  # every check is beside the thesis' claim
            assert check["name"].replace("|", "\\|") in text
        for png in (reproduced / name).glob("*.png"):  # figures linked relative to the report
            assert f"]({name}/{png.name})" in text
    assert text.index("## fig3-5:") < text.index("## fig3-4:")  # the order asked for


def test_a_failing_target_is_reported_and_the_others_still_run(tmp_path: Path) -> None:
    (tmp_path / "fig3-5").write_text("not a folder")  # reproduce refuses to replace it
    report = run_all(tmp_path, runs=1, targets=QUICK, progress=False, log=lambda _m: None)
    text = report.read_text(encoding="utf-8")
    assert "fig3-5: exists and is not a folder" in text
    assert "failed to run" in text
    assert (tmp_path / "fig3-4" / "summary.json").is_file()
    assert [o.name for o in collect(tmp_path) if o.error is None] == ["fig3-4"]


def test_resume_keeps_finished_targets_and_reruns_others(tmp_path: Path) -> None:
    run_all(tmp_path, runs=1, targets=["fig3-5"], progress=False, log=lambda _m: None)
    first = (tmp_path / "fig3-5" / "summary.json").stat().st_mtime_ns
    said: list[str] = []
    run_all(tmp_path, runs=1, targets=QUICK, progress=False, resume=True, log=said.append)
    assert (tmp_path / "fig3-5" / "summary.json").stat().st_mtime_ns == first
    assert any("fig3-5: kept" in s for s in said) and (tmp_path / "fig3-4" / "summary.json").is_file()
    run_all(tmp_path, runs=2, targets=["fig3-5"], progress=False, resume=True, log=said.append)  # other runs
    assert json.loads((tmp_path / "fig3-5" / "summary.json").read_text())["runs"] == 2
    run_all(tmp_path, runs=2, targets=["fig3-5"], progress=False, resume=True, quick=True,
            log=said.append)  # the same runs at the other size
    assert json.loads((tmp_path / "fig3-5" / "summary.json").read_text())["quick"] is True


def test_report_is_rebuilt_from_folders_alone(reproduced: Path, tmp_path: Path) -> None:
    dest = write_report(reproduced, dest=tmp_path / "R.md", image_prefix="reproduction/")
    text = dest.read_text(encoding="utf-8")
    assert "](reproduction/fig3-4/" in text
    with pytest.raises(FileNotFoundError, match="no reproduced target"):
        write_report(tmp_path / "empty")


def test_cli_report_and_all_refuse_bad_input(reproduced: Path, tmp_path: Path) -> None:
    run = [sys.executable, "-m", "shoal"]
    ok = subprocess.run([*run, "reproduce", "--report", str(reproduced)], capture_output=True, text=True)
    assert ok.returncode == 0 and REPORT in ok.stdout
    bad = subprocess.run([*run, "reproduce", "--all", "--runs", "0", "--out", str(tmp_path)],
                         capture_output=True, text=True)
    assert bad.returncode == 2 and "argument --runs: must be at least 1, got 0" in bad.stderr
    none = subprocess.run([*run, "reproduce", "--report", str(tmp_path / "nothing")], capture_output=True, text=True)
    assert none.returncode == 2 and "no reproduced target" in none.stderr


def test_information_is_shown_beside_the_checks_but_not_counted() -> None:
    from shoal.studies.experiments.output import check, info
    from shoal.studies.experiments.report import Outcome, render
    from shoal.studies.experiments.verdict import exact

    free = check("median run collision-free", "none", "0", True, exact(True))
    summary = {"runs": 3, "elapsed_s": 1.0, "checks": [free],
               "information": [info("every run collision-free", "none", "2 robots in 1 run", False)]}
    text = render([Outcome("fig4-6", summary=summary)])
    assert "| [fig4-6](#fig4-6) | Rossides, Figs. 4-6 and 4-7 | 3 | 1 | 1 | 0 | 0 | 1.0 |" in text
    assert "of 1 checks 1 hold, 0 fail and 0 are undecided" in text
    assert "information, not counted as checks" in text
    assert "| every run collision-free | none | 2 robots in 1 run | no |" in text
    assert "Every check holds." in text


def test_undecided_checks_are_counted_and_named_apart_from_failures() -> None:
    from shoal.studies.experiments.output import check
    from shoal.studies.experiments.report import Outcome, render
    from shoal.studies.experiments.verdict import Estimate, at_least, exact

    few = Estimate.median([1.0, 2.0, 3.0])  # three runs: no 95 % interval of a median
    many = Estimate.median(list(range(10, 40)))
    checks = [check("a claim three runs cannot settle", "≥ 1", "2", True, at_least(few, 1.0)),
              check("a claim thirty runs settle", "≥ 1", "24.5", True, at_least(many, 1.0)),
              check("an identity that breaks", "equal", "0.5", False, exact(False))]
    text = render([Outcome("fig4-6", summary={"runs": 3, "elapsed_s": 1.0, "checks": checks})])
    assert "| 3 | 1 | 1 | 1 |" in text
    assert "| a claim three runs cannot settle | ≥ 1 | 2 | undecided (3 runs) |" in text
    assert "| a claim thirty runs settle | ≥ 1 | 24.5 | yes (30 runs) |" in text
    assert "| an identity that breaks | equal | 0.5 | **no** (exact) |" in text
    assert "1 of 3 checks fail: *an identity that breaks*" in text
    assert "1 of 3 checks are undecided at 3 runs" in text and "*a claim three runs cannot settle*" in text


def test_the_report_gives_each_targets_wall_and_cpu_time_and_their_totals() -> None:
    from shoal.studies.experiments.report import Outcome, render

    a = {"runs": 3, "elapsed_s": 12.5, "cpu_s": 20.25, "workers": 2, "checks": []}
    b = {"runs": 31, "elapsed_s": 100.0, "cpu_s": 190.0, "workers": 2, "checks": []}
    text = render([Outcome("fig4-6", summary=a), Outcome("slo-pso", summary=b), Outcome("fig3-4", error="boom")])
    assert "| 3 | 0 | 0 | 0 | 0 | 12.5 | 20.25 | 2 |" in text and "| 31 | 0 | 0 | 0 | 0 | 100.0 | 190.0 | 2 |" in text
    assert "| all | | | 0 | 0 | 0 | 0 | 112 | 210 | |" in text


def test_two_reproductions_are_compared_check_by_check(tmp_path: Path) -> None:
    from shoal.studies.experiments.report import agreement

    def write(folder: Path, verdicts: list[str]) -> None:
        (folder / "fig4-6").mkdir(parents=True)
        checks = [{"name": f"c{i}", "thesis": "", "measured": "", "pass": v == "holds", "verdict": v, "runs": 3}
                  for i, v in enumerate(verdicts)]
        (folder / "fig4-6" / "summary.json").write_text(json.dumps({"target": "fig4-6", "runs": 3, "checks": checks}))

    write(tmp_path / "quick", ["holds", "undecided", "fails", "holds"])
    write(tmp_path / "full", ["holds", "fails", "holds", "holds"])
    full = json.loads((tmp_path / "full" / "fig4-6" / "summary.json").read_text())
    full["checks"][3]["name"], full["checks"][3]["verdict"] = "c3 (runs 0-49)", "fails"
    full["checks"][3]["pass"] = False
    (tmp_path / "full" / "fig4-6" / "summary.json").write_text(json.dumps(full))
    quick = json.loads((tmp_path / "quick" / "fig4-6" / "summary.json").read_text())
    quick["checks"][3]["name"] = "c3 (runs 0-3)"  # the same check at another run count
    (tmp_path / "quick" / "fig4-6" / "summary.json").write_text(json.dumps(quick))
    got = agreement(tmp_path / "quick", tmp_path / "full")
    assert got.opposite == [("fig4-6", "c2", "fails", "holds"), ("fig4-6", "c3 (runs 0-3)", "holds", "fails")]
    assert got.one_sided == [("fig4-6", "c1", "undecided", "fails")]



def test_agreement_counts_same_one_sided_and_opposite_verdicts(tmp_path: Path) -> None:
    from shoal.studies.experiments.report import agreement

    def write(folder: Path, verdicts: list[str], names: list[str] | None = None) -> None:
        (folder / "fig7-2").mkdir(parents=True)
        checks = [{"name": (names or [])[i] if names else f"c{i}", "thesis": "", "measured": "",
                   "pass": v == "holds", "verdict": v, "runs": 6} for i, v in enumerate(verdicts)]
        (folder / "fig7-2" / "summary.json").write_text(json.dumps({"target": "fig7-2", "runs": 6, "checks": checks}))

    write(tmp_path / "quick", ["holds", "undecided", "undecided", "fails", "holds", "undecided", "fails"])
    write(tmp_path / "full", ["holds", "holds", "undecided", "fails", "undecided", "fails", "holds", "holds"],
          ["c0", "c1", "c2", "c3", "c4", "c5", "c6", "c9 only here"])
    got = agreement(tmp_path / "quick", tmp_path / "full")
    assert got.same == {"holds": 1, "fails": 1, "undecided": 1}
    assert (got.decided_in_b_only, got.decided_in_a_only) == (2, 1)
    assert got.opposite == [("fig7-2", "c6", "fails", "holds")]
    assert (got.only_in_a, got.only_in_b, got.shared) == (0, 1, 7)

    run = [sys.executable, "-m", "shoal", "reproduce", "--compare"]
    out = subprocess.run([*run, str(tmp_path / "quick"), str(tmp_path / "full")], capture_output=True, text=True)
    assert out.returncode == 1, out.stderr  # one holds what the other fails
    assert "opposite verdicts: 1" in out.stdout and "fig7-2: c6: fails in" in out.stdout
    same = subprocess.run([*run, str(tmp_path / "full"), str(tmp_path / "full")], capture_output=True, text=True)
    assert same.returncode == 0 and "same verdict: 8 (4 holds, 2 fails, 2 undecided)" in same.stdout
    none = subprocess.run([*run, str(tmp_path / "full"), str(tmp_path / "nothing")], capture_output=True, text=True)
    assert none.returncode == 2 and "no reproduced target" in none.stderr


def test_one_target_on_the_command_line_says_its_verdicts(tmp_path: Path) -> None:
    out = subprocess.run([sys.executable, "-m", "shoal", "reproduce", "fig3-5", "--runs", "3", "--out",
                          str(tmp_path / "f")], capture_output=True, text=True)
    summary = json.loads((tmp_path / "f" / "summary.json").read_text(encoding="utf-8"))
    counts = [sum(c["verdict"] == v for c in summary["checks"]) for v in ("holds", "fails", "undecided")]
    assert out.returncode == 0 and counts[2] > 0  # three runs leave every median undecided
    assert (f"({len(summary['checks'])} checks: {counts[0]} hold, {counts[1]} fail, {counts[2]} undecided at 3 "
            "runs)") in out.stdout
    undecided = [c["name"] for c in summary["checks"] if c["verdict"] == "undecided"]
    assert all(f"  undecided: {name}" in out.stdout for name in undecided)
