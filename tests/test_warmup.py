"""Nothing waits for the kernels: a scene runs on its numpy tick while they compile and changes
over between two ticks with the same numbers; SLO scenes, which have no numpy tick, run their
kernels as Python meanwhile and say so (tests/test_compiled.py: the same bits); ``shoal run``
and ``shoal warmup`` (app/warmup.py)."""

from __future__ import annotations

import hashlib
import subprocess
import sys

import numpy as np
import pytest

from shoal.app.cli import main
from shoal.app.kinds.registry import session_for
from shoal.app.warmup import NUMPY_TICK, ORDER, Warmup, group_of, groups
from shoal.presets.build import build
from shoal.presets.io import list_presets, load


def _state(sim) -> list[np.ndarray]:
    info = sim.info().columns()
    return [np.array(sim.state.x), np.array(sim.state.heading), np.array(sim.state.best_fitness),
            *(np.asarray(info[c]) for c in sorted(info))]


NUMPY_TICKED = [p for p in list_presets() if group_of(load(p)) in NUMPY_TICK]


@pytest.mark.parametrize("preset", NUMPY_TICKED)
def test_a_run_that_changes_from_numpy_to_compiled_gives_the_compiled_numbers(preset):
    compiled = build(load(preset, ["sim.runs=2", "sim.seed=5"]))
    changing = build(load(preset, ["sim.runs=2", "sim.seed=5"]))
    changing.compiled = False
    for k in range(20):
        if k == 7:
            changing.compiled = True
        compiled.step()
        changing.step()
        assert all(np.array_equal(a, b, equal_nan=True) for a, b in zip(_state(compiled), _state(changing))), k


def test_groups_cover_every_preset_with_kernels():
    grouped = {p for names in groups().values() for p in names}
    assert grouped == set(list_presets())
    assert group_of(load("slo-walk")) == "slo" and group_of(load("course-dvc-slo")) == "slo"
    assert group_of(load("course-dvc")) == "fleet" and group_of(load("default")) == "swarm"


@pytest.fixture
def cold(monkeypatch) -> Warmup:
    """A warm-up that has started and compiled nothing yet, seen by the sessions and panels."""
    w = Warmup()
    w.started, w.scheduled = 0.0, set(ORDER)
    w.total = 30
    for module in ("shoal.app.session.session", "shoal.app.panel.panel", "shoal.app.tab"):
        monkeypatch.setattr(f"{module}.WARMUP", w)
    return w


def test_a_fleet_session_runs_on_numpy_until_its_kernels_are_ready_with_the_same_numbers(cold):
    s = session_for(load("course-dvc"))
    reference = build(load("course-dvc"))
    for k in range(12):
        if k == 5:
            cold.ready["fleet"].set()
        s.step()
        reference.step()
        assert s.sim.compiled == (k >= 5)
    assert all(np.array_equal(a, b, equal_nan=True) for a, b in zip(_state(s.sim), _state(reference)))


def test_an_slo_scene_plays_while_its_kernels_compile_and_the_status_says_how(cold, server):
    from app_helpers import hand_tab

    server.scenario = load("slo-walk")
    with hand_tab(server) as tab:
        s = tab.session
        assert s.step(3) == 3 and s.k == 3  # no numpy tick, and yet it never waits
        tab.panels.refresh_status()
        assert "compiling kernels in the background (scene 1 of 30" in tab.panels.status.content
        assert "Python meanwhile (slower), the same numbers" in tab.panels.status.content
        cold.ready["slo"].set()
        assert s.step(3) == 3
        tab.panels.refresh_status()
        assert "kernels" not in tab.panels.status.content


def test_the_status_line_says_a_scene_runs_on_numpy_while_kernels_compile(cold, server):
    from app_helpers import hand_tab

    server.scenario = load("course-dvc")
    with hand_tab(server) as tab:
        assert tab.session.step(2) == 2  # never waits
        tab.panels.refresh_status()
        assert "compiling kernels in the background (scene 1 of 30" in tab.panels.status.content
        assert "numpy meanwhile, the same numbers" in tab.panels.status.content
        cold.ready["fleet"].set()
        tab.panels.refresh_status()
        assert "compiling" not in tab.panels.status.content


def test_shoal_run_gives_the_same_files_with_the_kernels_cold_or_ready(tmp_path, monkeypatch, capsys):
    args = ["run", "course-nonomni", "--runs", "2", "--steps", "15", "--seed", "2"]
    assert main([*args, "--out", str(tmp_path / "ready")]) == 0
    never = Warmup()
    never.started, never.scheduled = 0.0, set(ORDER)
    never.start = lambda *a, **k: None  # kernels never ready: numpy throughout
    monkeypatch.setattr("shoal.app.warmup.WARMUP", never)
    assert main([*args, "--out", str(tmp_path / "numpy")]) == 0
    for name in ("trajectories.csv", "metrics.csv"):
        digest = [hashlib.sha256((tmp_path / d / name).read_bytes()).hexdigest() for d in ("ready", "numpy")]
        assert digest[0] == digest[1], name


def test_shoal_warmup_compiles_every_group_and_says_where():
    done = subprocess.run([sys.executable, "-m", "shoal", "warmup"], capture_output=True, text=True, timeout=900)
    assert done.returncode == 0, done.stderr[-3000:]
    lines = done.stdout.splitlines()
    assert lines[0].startswith("compiling Shoal's kernels (cache: ")
    assert [line.split(":")[0].strip() for line in lines[1:5]] == ["swarm", "fleet", "sonar", "slo"]
    assert lines[-1].startswith("done in ")


def test_a_failed_warmup_is_said_and_scenes_compile_on_first_use(monkeypatch, capsys):
    w = Warmup()

    def broken(*a, **k):
        raise RuntimeError("no compiler today")

    monkeypatch.setattr("shoal.app.warmup.build", broken)
    w.run()
    assert "no compiler today" in capsys.readouterr().err and w.error is not None
    assert all(e.is_set() for e in w.ready.values())  # nobody waits for ever


def test_only_the_groups_a_warmup_compiles_wait_or_run_on_numpy():
    """``shoal run`` compiles its own group only: scenes of other groups compile on first use, as
    before (a test process that ran ``shoal run`` in-process must not leave SLO scenes waiting)."""
    w = Warmup()
    w.started, w.scheduled = 0.0, {"fleet"}
    sim = build(load("default"))
    w.use(sim, load("default"))
    assert sim.compiled and not w.interprets(load("slo-walk")) and w.status(load("slo-walk")) is None
    fleet = build(load("course-dvc"))
    w.use(fleet, load("course-dvc"))
    assert not fleet.compiled and w.status(load("course-dvc")) is not None


def test_a_process_without_a_warmup_compiles_as_before():
    w = Warmup()
    sim = build(load("default"))
    w.use(sim, load("default"))
    assert sim.compiled and not w.interprets(load("slo-walk")) and w.status(load("course-dvc")) is None


def test_the_status_line_says_a_scene_is_being_built(cold, server):
    from app_helpers import hand_tab, shown

    def status_while_built(tab, preset: str) -> str:
        seen, services = [], tab.panels.services
        real = services.replace

        def replace(scenario, **kw):
            seen.append(tab.panels.status.content)
            return real(scenario, **kw)

        object.__setattr__(services, "replace", replace)  # (a frozen dataclass: the tab's own swap, wrapped)
        tab.panels.load_preset(preset)
        return seen[0]

    with hand_tab(server) as tab:
        assert shown(status_while_built(tab, "course-dvc")) == "**course-dvc** · building the scene …"
        said = status_while_built(tab, "slo-walk")  # (its kernels not compiled: it is built all the same)
        assert shown(said) == "**slo-walk** · building the scene …", said


ENTRY_WHILE_COMPILING = """
import threading, time
from shoal.app import cli
from shoal.app.warmup import WARMUP
WARMUP._thread = threading.Thread(target=time.sleep, args=(600,), daemon=True)  # a warm-up still at work
WARMUP._thread.start()
import sys
sys.argv = ["shoal", "presets", "list"]
cli.entry()
"""


def test_the_command_exits_with_its_code_without_waiting_for_a_warmup_still_compiling():
    """``shoal`` (cli.entry) leaves at once with the command's code and its output flushed,
    neither waiting for nor tearing the interpreter down under a compiling warm-up thread."""
    done = subprocess.run([sys.executable, "-c", ENTRY_WHILE_COMPILING], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert "default" in done.stdout and "smooth-tanh" in done.stdout
    bad = subprocess.run([sys.executable, "-c", ENTRY_WHILE_COMPILING.replace('"list"', '"show", "nope"')],
                         capture_output=True, text=True, timeout=120)
    assert bad.returncode != 0 and "nope" in bad.stderr


def test_a_warmup_elsewhere_compiles_in_a_child_into_the_disk_cache_and_counts_its_progress(tmp_path, monkeypatch):
    """``shoal serve``'s warm-up compiles in a child process (the server's own thread held the
    interpreter's lock for most of a minute): the child writes the kernels into the cache this
    process reads, each preset counted as it is done; a stopped warm-up compiles nothing more."""
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path))
    w = Warmup()
    assert w._compile_elsewhere(["slo-walk"])
    assert w.done == 1 and w.revision == 1 and w._child is None
    assert any(tmp_path.rglob("*.nbi")) and any(tmp_path.rglob("*.nbc"))  # numba's index and machine code
    w.stop()
    w.run(only="slo", elsewhere=True)
    assert not w.ready["slo"].is_set() and w.done == 1  # (stopped: nothing more)
