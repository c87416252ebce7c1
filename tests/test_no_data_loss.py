"""No command loses a file it did not write: for each of ``run``, ``sweep``, ``reproduce``,
``export-replay`` and the app's downloads, a user's file sits in the target first and is
there, unchanged, afterwards; a folder holding foreign files is refused before any work,
and ``--out .`` either works or is refused before any work."""

from __future__ import annotations

import json
import os
from pathlib import Path

from shoal.app.cli import main

NOTE = "my notes: do not lose\n"


def _user_file(folder: Path, name: str = "notes.txt") -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / name
    path.write_text(NOTE, encoding="utf-8")
    return path


def _listing(folder: Path) -> list[str]:
    return sorted(str(p.relative_to(folder)) for p in folder.rglob("*"))


def _refused(capsys, *words: str) -> str:
    err = capsys.readouterr().err
    assert err.startswith("shoal: error: ") and err.count("\n") == 1, err
    for w in words:
        assert w in err, err
    return err


# ---------------------------------------------------------------------------- shoal run
def test_run_refuses_a_folder_with_a_user_file_before_any_work(tmp_path, capsys, monkeypatch):
    mine = _user_file(tmp_path / "out")
    ticks = []
    monkeypatch.setattr("shoal.engine.core.runs.run_to_dir", lambda *a, **k: ticks.append(1))
    assert main(["run", "default", "--steps", "5", "--out", str(tmp_path / "out")]) == 2
    _refused(capsys, "notes.txt", "did not write", "choose a new or empty folder")
    assert not ticks  # refused before the run
    assert mine.read_text(encoding="utf-8") == NOTE and _listing(tmp_path / "out") == ["notes.txt"]


def test_run_into_its_own_earlier_output_replaces_it_and_a_user_file_added_later_is_refused(tmp_path, capsys):
    out = tmp_path / "r"
    assert main(["run", "default", "--steps", "3", "--seed", "1", "--out", str(out)]) == 0
    first = (out / "metrics.csv").read_bytes()
    assert main(["run", "default", "--steps", "4", "--seed", "1", "--out", str(out)]) == 0  # ours: replaced
    assert (out / "metrics.csv").read_bytes() != first
    assert _listing(out) == ["metrics.csv", "run.json", "trajectories.csv"]
    capsys.readouterr()
    mine = _user_file(out, "analysis.py")
    before = {p: p.read_bytes() for p in out.iterdir()}
    assert main(["run", "default", "--steps", "5", "--seed", "1", "--out", str(out)]) == 2
    _refused(capsys, "analysis.py")
    assert {p: p.read_bytes() for p in out.iterdir()} == before and mine.read_text(encoding="utf-8") == NOTE


def test_run_out_dot_works_in_an_empty_folder_and_is_refused_beside_user_files(tmp_path, capsys, monkeypatch):
    empty = tmp_path / "empty"
    empty.mkdir()
    monkeypatch.chdir(empty)
    assert main(["run", "default", "--steps", "3", "--out", "."]) == 0
    assert _listing(empty) == ["metrics.csv", "run.json", "trajectories.csv"]  # no hidden partial folder left
    assert main(["run", "default", "--steps", "4", "--out", "."]) == 0  # and again: its own files
    capsys.readouterr()
    mine = _user_file(tmp_path / "busy")
    monkeypatch.chdir(tmp_path / "busy")
    assert main(["run", "default", "--steps", "3", "--out", "."]) == 2
    _refused(capsys, "--out .", "notes.txt")
    assert _listing(tmp_path / "busy") == ["notes.txt"] and mine.read_text(encoding="utf-8") == NOTE


def test_a_run_that_fails_leaves_the_earlier_output_and_the_folder_as_they_were(tmp_path, monkeypatch):
    out = tmp_path / "r"
    assert main(["run", "default", "--steps", "3", "--out", str(out)]) == 0
    before = {p.name: p.read_bytes() for p in out.iterdir()}

    def broken(self):
        raise MemoryError

    monkeypatch.setattr("shoal.engine.kinds.swarm.Simulation.step", broken)
    assert main(["run", "default", "--steps", "3", "--seed", "9", "--out", str(out)]) == 1
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before


# ---------------------------------------------------------------------------- shoal sweep
def test_sweep_refuses_a_folder_with_a_user_file_and_leaves_no_lock_file(tmp_path, capsys):
    mine = _user_file(tmp_path / "s")
    args = ["sweep", "default", "--grid", "controller.omega=0.5,0.6", "--runs", "1", "--steps", "3"]
    assert main([*args, "--out", str(tmp_path / "s")]) == 2
    assert "is not empty" in capsys.readouterr().err
    assert _listing(tmp_path / "s") == ["notes.txt"] and mine.read_text(encoding="utf-8") == NOTE


def test_a_user_file_put_into_a_sweep_folder_survives_a_resume(tmp_path):
    out = tmp_path / "s"
    args = ["sweep", "default", "--grid", "controller.omega=0.5,0.6", "--runs", "1", "--steps", "3", "--out", str(out)]
    assert main(args) == 0
    mine = _user_file(out, "remarks.md")
    assert main(args) == 0  # resumes: writes its own files only
    assert mine.read_text(encoding="utf-8") == NOTE


def test_sweep_out_dot_is_refused_beside_user_files(tmp_path, capsys, monkeypatch):
    _user_file(tmp_path)
    monkeypatch.chdir(tmp_path)
    assert main(["sweep", "default", "--grid", "controller.omega=0.5", "--runs", "1", "--steps", "3",
                 "--out", "."]) == 2
    assert "is not empty" in capsys.readouterr().err
    assert _listing(tmp_path) == ["notes.txt"]


# ---------------------------------------------------------------------------- shoal reproduce
def test_reproduce_refuses_a_folder_with_a_user_file(tmp_path, capsys):
    mine = _user_file(tmp_path / "q")
    assert main(["reproduce", "fig3-5", "--quick", "--out", str(tmp_path / "q")]) == 2
    _refused(capsys, "notes.txt")
    assert _listing(tmp_path / "q") == ["notes.txt"] and mine.read_text(encoding="utf-8") == NOTE


def test_reproduce_keeps_a_user_file_put_into_an_earlier_reproduction(tmp_path, capsys):
    """An earlier reproduction lists the files it wrote; anything else in its folder is the user's."""
    out = tmp_path / "q"
    out.mkdir()
    (out / "summary.json").write_text(json.dumps({"target": "fig3-5", "files": ["runs.csv", "fig3-5.png"]}))
    (out / "runs.csv").write_text("old")
    mine = _user_file(out, "my-plot.png")
    assert main(["reproduce", "fig3-5", "--quick", "--out", str(out)]) == 2
    _refused(capsys, "my-plot.png")
    assert mine.read_text(encoding="utf-8") == NOTE and (out / "runs.csv").read_text() == "old"


def test_reproduce_report_refuses_to_overwrite_a_users_report(tmp_path, capsys):
    (tmp_path / "fig3-5").mkdir()
    (tmp_path / "fig3-5" / "summary.json").write_text(json.dumps({"target": "fig3-5", "checks": []}))
    mine = _user_file(tmp_path, "REPRODUCTION.md")
    assert main(["reproduce", "--report", str(tmp_path)]) == 2
    _refused(capsys, "REPRODUCTION.md", "not a report Shoal wrote")
    assert mine.read_text(encoding="utf-8") == NOTE


# ---------------------------------------------------------------------------- shoal export-replay
def test_export_replay_refuses_to_overwrite_a_users_page_before_running(tmp_path, capsys, monkeypatch):
    mine = _user_file(tmp_path, "page.html")
    ran = []
    monkeypatch.setattr("shoal.app.share.export.preset_html", lambda *a, **k: ran.append(1) or "")
    assert main(["export-replay", "default", "--steps", "3", "--out", str(tmp_path / "page.html")]) == 2
    _refused(capsys, "page.html", "not a page shoal export-replay wrote")
    assert not ran and mine.read_text(encoding="utf-8") == NOTE


def test_export_replay_replaces_its_own_page_and_writes_nothing_else(tmp_path, capsys):
    _user_file(tmp_path)
    page = tmp_path / "run.html"
    assert main(["export-replay", "default", "--steps", "3", "--out", str(page)]) == 0
    assert main(["export-replay", "default", "--steps", "4", "--out", str(page)]) == 0  # its own page
    assert _listing(tmp_path) == ["notes.txt", "run.html"]
    assert (tmp_path / "notes.txt").read_text(encoding="utf-8") == NOTE


# ---------------------------------------------------------------------------- the app's downloads
def test_app_downloads_write_no_file_on_the_server(tab, tmp_path, monkeypatch):
    """Every download and export button of a tab: the files go to the browser (which names a
    second copy itself), nothing is written where the server runs or in its home folder."""
    work, home = tmp_path / "work", tmp_path / "home"
    _user_file(work, "default.toml")
    _user_file(home)
    monkeypatch.chdir(work)
    monkeypatch.setenv("HOME", str(home))
    before = _listing(tmp_path)
    buttons = [h for h in _buttons(tab) if any(w in str(h.label) for w in ("Export", "Download", "Share"))]
    assert {"Export CSV", "Export JSON", "Download preset"} <= {str(h.label) for h in buttons}
    for _ in range(5):
        tab.session.step()
    for handle in buttons:
        handle.value = True  # fires its on_click
        tab.tick(1.0)
    assert len(tab.downloads) >= 3
    assert _listing(tmp_path) == before
    assert (work / "default.toml").read_text(encoding="utf-8") == NOTE
    assert all(os.sep not in name and not name.startswith(".") for name, _ in tab.downloads)


def _buttons(tab) -> list:
    """The tab's buttons (viser keeps its input handles by id: tests/test_internals.py)."""
    return [h for h in tab.panels.gui._gui_input_handle_from_uuid.values() if type(h).__name__ == "GuiButtonHandle"]
