"""The experiment service of a shared server: the same per-run outcomes as ``shoal sweep``,
Cancel that keeps finished cells, one queue with stated limits, one experiment per tab, a
closed tab that cancels, and refusals that say why."""

from __future__ import annotations

import csv
import io
import threading
import time

import pytest

from shoal.app.experiment import AxisRequest, ExperimentRequest, ExperimentService, Limits, Refused, experiment_pool
from shoal.app.experiment.service import CANCELLED, FINISHED, QUEUED, RUNNING
from shoal.presets.io import load, to_toml
from shoal.studies.experiments.schedulers import InProcess
from shoal.studies.sweep import run_sweep

from browser.browser_helpers import wait_until
from gates import GATES, STARTED, gated, reset


@pytest.fixture
def gates():
    reset()
    yield GATES
    reset()


def _request(*axes, runs=3, steps=20, outcome=None):
    return ExperimentRequest(axes=axes, runs=runs, steps=steps, outcome=outcome)


def _done(exp, timeout=120):
    wait_until(lambda: exp.over, timeout=timeout, what=f"experiment {exp.number} over")
    return exp


def _sweep(tmp_path, exp, **kw):
    """``shoal sweep`` of the experiment's preset file and grid, as its panel spells it."""
    preset = tmp_path / "experiment.toml"
    preset.write_text(to_toml(exp.plan.base), encoding="utf-8")
    grid = [f"{a.key}={','.join(a.labels)}" for a in exp.plan.axes]
    out = tmp_path / "sweep"
    run_sweep(str(preset), grid, out, runs=exp.plan.runs, progress=False, **kw)
    return out


# ------------------------------------------------------------------ same as shoal sweep
@pytest.mark.parametrize("preset, axes, outcome", [
    ("default", (AxisRequest("controller.U", values="2, 4.5"), AxisRequest("controller.A_plus", start=5, stop=15,
                                                                            count=3)), "best_fitness"),
    ("sonar-xb-pso", (AxisRequest("acoustics.algorithm", values="x-pso, xb-pso"),), "steps_to_converge"),
    ("course-dvc", (AxisRequest("robot.motion", values=["kinematic", "physics"]),), "collided"),
])
def test_per_run_outcomes_equal_shoal_sweep_byte_for_byte(tmp_path, preset, axes, outcome):
    service = ExperimentService(experiment_pool(1))  # what shoal serve runs them on
    try:
        exp = _done(service.submit("tab", load(preset), _request(*axes, runs=3, steps=25, outcome=outcome)))
    finally:
        service.stop()
    assert exp.phase == FINISHED and exp.runs_done == exp.cost == len(exp.plan) * 3
    out = _sweep(tmp_path, exp)
    assert exp.table.csv().encode() == (out / "results.csv").read_bytes()
    with open(out / "medians.csv", newline="", encoding="utf-8") as fh:
        medians = list(csv.DictReader(fh))
    med, lo, hi = exp.table.summary(outcome)
    assert [r[outcome] for r in medians] == [f"{v:.12g}" if v == v else "" for v in med.ravel()]
    assert exp.plan.base.sim.seed == load(preset).sim.seed  # the scene's seed: run i is child i of it


def test_a_range_and_count_are_the_values_a_sweep_would_be_given():
    service = ExperimentService(InProcess())
    try:
        exp = _done(service.submit("tab", load("default"), _request(
            AxisRequest("sim.robots", start=3, stop=12, count=4), runs=1, steps=2)))
        assert exp.plan.axes[0].values == (3, 6, 9, 12)
        exp = _done(service.submit("tab", load("default"), _request(
            AxisRequest("controller.U", start=6, stop=7, count=3), runs=1, steps=2)))
        assert exp.plan.axes[0].labels == ("6.0", "6.5", "7.0")
    finally:
        service.stop()


# ------------------------------------------------------------------ cancel
def test_cancel_keeps_the_finished_cells_and_skips_the_rest(gates, tmp_path):
    gates[2] = threading.Event()
    events: list[tuple[str, int]] = []
    service = ExperimentService(InProcess(), simulate=gated)
    try:
        exp = service.submit("tab", load("default"), _request(AxisRequest("controller.U", values="3, 4, 5, 6, 7")),
                             listener=lambda e: events.append((e.phase, len(e.table))))
        wait_until(lambda: 2 in STARTED, what="cell 2 started")
        assert service.cancel("tab") is exp and exp.cancelling and "cancelling" in exp.status()
        gates[2].set()
        _done(exp)
    finally:
        service.stop()
    assert exp.phase == CANCELLED and exp.table.finished() == [0, 1, 2]  # the cell in progress finished too
    assert sorted(set(STARTED)) == [0, 1, 2]  # cells 3 and 4 never started
    assert events[-1] == (CANCELLED, 3) and "3 of 5 cells finished and kept" in exp.status()
    full = ExperimentService(InProcess())
    try:
        ask = _request(AxisRequest("controller.U", values="3, 4, 5, 6, 7"))
        whole = _done(full.submit("tab", load("default"), ask))
    finally:
        full.stop()
    kept = exp.table.csv().splitlines()
    assert kept == whole.table.csv().splitlines()[: len(kept)] and len(kept) == 1 + 3 * 3


def test_cancel_on_the_process_pool_stops_after_the_chunks_in_progress():
    service = ExperimentService(experiment_pool(1), chunk=2)
    first = threading.Event()
    try:
        exp = service.submit("tab", load("default"), _request(AxisRequest("sim.robots", start=10, stop=40, count=12),
                                                              runs=4, steps=200),
                             listener=lambda e: first.set() if len(e.table) else None)
        assert first.wait(120)
        service.cancel("tab")
        _done(exp)
    finally:
        service.stop()
    assert exp.phase == CANCELLED and 1 <= len(exp.table) < 12
    rows = list(csv.DictReader(io.StringIO(exp.table.csv())))
    assert len(rows) == 4 * len(exp.table)


# ------------------------------------------------------------------ fairness
def test_one_queue_for_the_server_one_experiment_per_tab_and_a_stated_maximum(gates):
    gates[0] = threading.Event()
    limits = Limits(max_queue_runs=25)
    service = ExperimentService(InProcess(), limits, simulate=gated)
    ask = _request(AxisRequest("controller.U", values="4, 8"), runs=5)  # 10 cells × runs
    started: list[str] = []

    def note(e):
        if e.phase == RUNNING and e.owner not in started:
            started.append(e.owner)

    try:
        a = service.submit("A", load("default"), ask, listener=note)
        wait_until(lambda: a.phase == RUNNING, what="A running")
        b = service.submit("B", load("default"), ask, listener=note)
        assert b.phase == QUEUED and b.place == 1 and "1st in the server's queue" in b.status()
        with pytest.raises(Refused, match="already has an experiment queued or running"):
            service.submit("A", load("default"), ask)
        with pytest.raises(Refused, match="queue holds 20 of its 25 cells × runs and this experiment needs 10"):
            service.submit("C", load("default"), ask)
        c = service.submit("C", load("default"), _request(AxisRequest("controller.U", values="8"), runs=5),
                           listener=note)
        assert service.queued_runs() == 25 and c.place == 2
        gates[0].set()
        for e in (a, b, c):
            _done(e)
        assert [e.phase for e in (a, b, c)] == [FINISHED] * 3
        assert service.queued_runs() == 0
        again = _done(service.submit("A", load("default"), ask))  # over: the tab may ask again
        assert again.phase == FINISHED and service.experiment("A") is again
    finally:
        service.stop()
    assert started == ["A", "B", "C"]  # first come, first served, one at a time


def test_a_closed_tab_cancels_its_experiment_running_or_queued(gates):
    gates[0] = threading.Event()
    service = ExperimentService(InProcess(), simulate=gated)
    ask = _request(AxisRequest("controller.U", values="4, 8"))
    try:
        a = service.submit("A", load("default"), ask)
        b = service.submit("B", load("default"), ask)
        wait_until(lambda: a.phase == RUNNING, what="A running")
        service.close_owner("B")  # queued: dropped at once
        assert b.phase == CANCELLED and service.experiment("B") is None and service.queued_runs() == a.cost
        service.close_owner("A")  # running: stops after the chunk in progress
        gates[0].set()
        _done(a)
        assert a.phase == CANCELLED and service.experiment("A") is None
        assert service.queued_runs() == 0
    finally:
        service.stop()


# ------------------------------------------------------------------ refusals
BAD = [
    ((), 3, None, None, "choose one or two fields"),
    ((AxisRequest("controller.U", values="1"),) * 3, 3, None, None, "choose one or two fields to vary (got 3)"),
    ((AxisRequest("name", values="x"),), 3, None, None, "name: not a field this scene can vary"),
    ((AxisRequest("sim.seed", values="1, 2"),), 3, None, None, "sim.seed: not a field this scene can vary"),
    ((AxisRequest("sim.runs", values="1, 2"),), 3, None, None, "sim.runs: not a field this scene can vary"),
    ((AxisRequest("../../etc/passwd", values="1"),), 3, None, None, "not a field this scene can vary"),
    ((AxisRequest(["controller.U"], values="1"),), 3, None, None, "not a field this scene can vary"),
    ((AxisRequest("controller.U", values="1"), AxisRequest("controller.U", values="8")), 3, None, None,
     "chosen twice"),
    ((AxisRequest("controller.U", values="0, 2"),), 3, None, None, "controller.U: 0 is outside 0 < U ≤ 1000"),
    ((AxisRequest("controller.U", values="2, fast"),), 3, None, None, "controller.U: fast is not a number"),
    ((AxisRequest("controller.U", values="2, 2"),), 3, None, None, "a value is repeated"),
    ((AxisRequest("controller.U", values=",".join(str(i) for i in range(1, 14))),), 3, None, None,
     "13 values; this server takes at most 12 per field"),
    ((AxisRequest("controller.U", values="1" * 2000),), 3, None, None, "longer than 1000 characters"),
    ((AxisRequest("controller.U", values=" "),), 3, None, None, "controller.U: no values; give a list of values"),
    ((AxisRequest("controller.U", start="1", stop=2, count=3),), 3, None, None, "from: 1 is not a finite number"),
    ((AxisRequest("controller.law", start=0, stop=1, count=3),), 3, None, None, "a range needs a numeric field"),
    ((AxisRequest("controller.U", start=1, stop=float("nan"), count=3),), 3, None, None, "not a finite number"),
    ((AxisRequest("controller.U", start=1, stop=2, count=1),), 3, None, None, "count: 1 is outside 2..12"),
    ((AxisRequest("controller.U", start=1, stop=2, count=2.5),), 3, None, None, "count: 2.5 is not a whole number"),
    ((AxisRequest("controller.U", values="1,2,3,4,5,6,7,8,9"), AxisRequest("controller.A_plus", values="10,20,30,40,50,"
                                                                           "60,70,80")), 1, None, None,
     "9 × 8 = 72 cells; this server runs at most 64"),
    ((AxisRequest("controller.U", values="1,2,3"),), 400, None, None, "runs per cell: 400 is outside 1..100"),
    ((AxisRequest("controller.U", values="1,2,3,4,5,6,7,8,9,10,11"),), 100, None, None,
     "11 cells × 100 runs = 1100 runs; this server runs at most 1000"),
    ((AxisRequest("controller.U", values="1"),), "ten", None, None, "runs per cell: ten is not a whole number"),
    ((AxisRequest("controller.U", values="1"),), float("inf"), None, None, "is not a whole number"),
    ((AxisRequest("controller.U", values="1"),), True, None, None, "runs per cell: true is not a whole number"),
    ((AxisRequest("controller.U", values="1"),), 3, 10**9, None, "steps per run: 1000000000 is outside 1..10000"),
    ((AxisRequest("controller.U", values="1"),), 3, None, "__class__", "__class__: not an outcome of this scene"),
    ((AxisRequest("controller.dt", values="0.1, 1"),), 3, None, None,
     "cell controller.dt=1: controller: A_plus: beta = A_plus*dt/U = 5 > 1"),
    ((AxisRequest("sim.robots", values="10, 5000"),), 3, None, None, "the browser app runs at most 2000 robots"),
]


@pytest.mark.parametrize("axes, runs, steps, outcome, words", BAD)
def test_a_refused_request_says_why_and_queues_nothing(axes, runs, steps, outcome, words):
    service = ExperimentService(InProcess())
    try:
        with pytest.raises(Refused) as err:
            service.submit("tab", load("default"), ExperimentRequest(axes, runs, steps, outcome))
        assert any(words in m for m in err.value.messages), err.value.messages
        assert service.queued_runs() == 0 and service.experiment("tab") is None
        ok = _done(service.submit("tab", load("default"), _request(AxisRequest("controller.U", values="8"), runs=1,
                                                                    steps=2)))
        assert ok.phase == FINISHED  # a refusal leaves the tab free to ask again
    finally:
        service.stop()


def test_a_stopped_service_refuses_and_cancels_what_it_held(gates):
    gates[0] = threading.Event()
    service = ExperimentService(InProcess(), simulate=gated)
    a = service.submit("A", load("default"), _request(AxisRequest("controller.U", values="4, 8")))
    b = service.submit("B", load("default"), _request(AxisRequest("controller.U", values="4, 8")))
    wait_until(lambda: a.phase == RUNNING, what="A running")
    stopper = threading.Thread(target=service.stop)
    stopper.start()
    time.sleep(0.1)
    gates[0].set()
    stopper.join(60)
    # the run in progress is interrupted at its first step, not finished (issue 20: stop in seconds)
    assert not stopper.is_alive() and b.phase == CANCELLED and a.phase == CANCELLED and len(a.table) == 0
    with pytest.raises(Refused, match="stopping"):
        service.submit("C", load("default"), _request(AxisRequest("controller.U", values="8")))


def test_a_grid_with_invalid_cells_is_offered_without_them_and_runs_the_rest():
    """U × A+ where β = A+Δt/U > 1 in one cell: refused as a whole with the count of cells that
    can run; asked again with skip_invalid, the other cells run, seeded as shoal sweep's, and
    the invalid one is named, never run."""
    service = ExperimentService(InProcess())
    axes = (AxisRequest("controller.U", values="2, 6"), AxisRequest("controller.A_plus", values="10, 30"))
    try:
        with pytest.raises(Refused) as err:
            service.submit("tab", load("default"), _request(*axes, runs=2, steps=5))
        assert (err.value.runnable, err.value.cells) == (3, 4)
        assert err.value.messages[0] == "1 of 4 cells cannot run; the other 3 can: run them and leave these out?"
        assert any(m.startswith("cell controller.U=2, controller.A_plus=30: controller:") and "> 1" in m
                   for m in err.value.messages[1:]), err.value.messages
        assert service.queued_runs() == 0
        skip = ExperimentRequest(axes=axes, runs=2, steps=5, skip_invalid=True)
        exp = _done(service.submit("tab", load("default"), skip))
        assert exp.phase == FINISHED and exp.cells == 3 and exp.cost == 6 and exp.table.finished() == [0, 2, 3]
        assert list(exp.plan.skipped) == [1] and exp.plan.scenarios[1] is None
        assert exp.status() == "finished: 3 cells × 2 runs (1 invalid left out)"
        med = exp.table.summary("best_fitness")[0]
        assert med.shape == (2, 2) and med[0, 1] != med[0, 1] and all(v == v for v in med.ravel()[[0, 2, 3]])
        with pytest.raises(Refused) as none:  # no cell can run: no offer
            service.submit("tab", load("default"), ExperimentRequest(
                axes=(AxisRequest("controller.U", values="1, 2"), AxisRequest("controller.A_plus", values="30, 40")),
                runs=1, steps=2, skip_invalid=True))
        assert none.value.runnable == 0
        truthy = ExperimentRequest(axes=axes, runs=2, steps=5, skip_invalid="yes")  # only True skips
        with pytest.raises(Refused):
            service.submit("tab", load("default"), truthy)
    finally:
        service.stop()
