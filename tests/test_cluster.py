"""Sweeps and reproductions on a real local Dask cluster of two worker processes: the same
files as local runs, and a worker that dies mid-sweep costs only a retry."""

from __future__ import annotations

import functools
import os
import subprocess
import sys
from pathlib import Path

import pytest

distributed = pytest.importorskip("distributed")
cloudpickle = pytest.importorskip("cloudpickle")

from shoal.studies.experiments import reproduce  # noqa: E402
from shoal.studies.experiments.schedulers import DaskCluster  # noqa: E402
from shoal.studies.sweep import run_sweep, simulate_cell  # noqa: E402

GRID = ["controller.U=2,4", "controller.A_plus=5,10"]


@pytest.fixture(scope="module")
def cluster():
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0") as lc:
        client = DaskCluster(lc.scheduler_address)
        try:
            yield client
        finally:
            client.close()


@pytest.fixture(scope="module")
def local_sweep(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("local") / "s"
    run_sweep("default", GRID, out, runs=3, steps=20, progress=False)
    return out


def test_the_cluster_has_two_workers(cluster):
    assert cluster.workers == 2 and "Dask cluster" in cluster.describe()


def test_sweep_on_the_cluster_equals_the_local_sweep(cluster, local_sweep, tmp_path):
    out = tmp_path / "dask"
    report = run_sweep("default", GRID, out, runs=3, steps=20, progress=False, scheduler=cluster)
    assert report.computed == 4
    for name in ("results.csv", "medians.csv"):
        assert (out / name).read_bytes() == (local_sweep / name).read_bytes()


def test_reproduce_on_the_cluster_equals_local(cluster, tmp_path):
    local, dask = tmp_path / "local", tmp_path / "dask"
    reproduce("fig3-5", local, runs=3, progress=False, sizes=(10,))
    summary = reproduce("fig3-5", dask, runs=3, progress=False, sizes=(10,), scheduler=cluster)
    assert "Dask cluster" in summary["scheduler"]
    for name in ("runs.csv", "series.csv"):
        assert (dask / name).read_bytes() == (local / name).read_bytes()


def die_once(marker: str, job, first_run: int, runs: int):
    """Kill this worker process the first time cell 1 is simulated (the marker records it)."""
    if job.key == 1 and not Path(marker).exists():
        Path(marker).write_text(str(os.getpid()))
        os._exit(1)
    return simulate_cell(job, first_run, runs)


def test_a_worker_that_dies_mid_sweep_costs_a_retry_not_the_sweep(cluster, local_sweep, tmp_path):
    marker = tmp_path / "killed"
    out = tmp_path / "dies"
    module = sys.modules[__name__]
    cloudpickle.register_pickle_by_value(module)  # workers cannot import this test module by name
    try:
        report = run_sweep("default", GRID, out, runs=3, steps=20, progress=False, scheduler=cluster,
                           simulate=functools.partial(die_once, str(marker)))
    finally:
        cloudpickle.unregister_pickle_by_value(module)
    assert marker.exists() and int(marker.read_text()) != os.getpid()  # a worker process really died
    assert report.computed == 4 and len(list((out / "cells").iterdir())) == 4
    assert (out / "results.csv").read_bytes() == (local_sweep / "results.csv").read_bytes()


def test_cli_sweep_and_reproduce_take_a_scheduler_address(cluster, tmp_path):
    out = tmp_path / "cli"
    res = subprocess.run([sys.executable, "-m", "shoal", "sweep", "default", "--grid", "controller.U=6,8",
                          "--runs", "2", "--steps", "10", "--out", str(out), "--scheduler", cluster.address],
                         capture_output=True, text=True, timeout=300)
    assert res.returncode == 0, res.stderr
    assert (out / "results.csv").is_file()
    assert "Dask cluster" in (out / "sweep.json").read_text()
    fig = tmp_path / "fig3-5"
    res = subprocess.run([sys.executable, "-m", "shoal", "reproduce", "fig3-5", "--runs", "1", "--out", str(fig),
                          "--scheduler", cluster.address], capture_output=True, text=True, timeout=300)
    assert res.returncode == 0, res.stderr
    assert "Dask cluster" in (fig / "summary.json").read_text()
    reproduce("fig3-5", tmp_path / "local", runs=1, progress=False)
    assert (fig / "runs.csv").read_bytes() == (tmp_path / "local" / "runs.csv").read_bytes()


def test_without_dask_the_scheduler_option_says_what_to_install(tmp_path):
    code = ("import sys; sys.modules['distributed'] = None; from shoal.app.cli import main; "
            f"sys.exit(main(['sweep', 'default', '--grid', 'controller.U=6,8', '--out', {str(tmp_path / 'x')!r}, "
            "'--scheduler', 'tcp://127.0.0.1:8786']))")
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert res.returncode == 2 and "shoal[cluster]" in res.stderr


def test_shoal_serve_with_a_scheduler_runs_experiments_on_the_cluster(cluster):
    """``shoal serve --scheduler``: the Experiment tab's cells go to the cluster, and they are
    those of the local pool, byte for byte."""
    from shoal.app.experiment import AxisRequest, ExperimentRequest, ExperimentService, experiment_pool
    from shoal.app.server import start_server
    from shoal.presets.io import load

    from browser.browser_helpers import wait_until

    ask = ExperimentRequest((AxisRequest("controller.U", values="6, 9"), AxisRequest("controller.A_plus",
                                                                                    values="10, 20")), 3, 20)
    srv = start_server("default", port=0, scheduler=cluster.address)
    try:
        assert "Dask cluster" in srv.experiments.scheduler.describe()
        on_cluster = srv.experiments.submit("tab", load("default"), ask)
        wait_until(lambda: on_cluster.over, timeout=120, what="the experiment on the cluster")
    finally:
        srv.stop()
    local = ExperimentService(experiment_pool(1))
    try:
        here = local.submit("tab", load("default"), ask)
        wait_until(lambda: here.over, timeout=120, what="the experiment on the local pool")
    finally:
        local.stop()
    assert on_cluster.phase == here.phase == "finished"
    assert on_cluster.table.csv() == here.table.csv()
    assert cluster.client.status == "running"  # the fixture's own client: not the server's to close


def test_cancel_interrupts_the_runs_on_the_cluster_within_seconds(cluster):
    """Issue 20, case 3: the tasks in progress see the scheduler's event and stop."""
    import time

    from shoal.app.experiment.request import AxisRequest, ExperimentRequest, Limits
    from shoal.app.experiment.service import CANCELLED, RUNNING, ExperimentService
    from shoal.presets.io import load

    from browser.browser_helpers import wait_until

    service = ExperimentService(cluster, Limits(max_seconds=1e6, max_queue_seconds=1e6))
    try:
        exp = service.submit("a", load("default"), ExperimentRequest(
            axes=(AxisRequest("sim.robots", values="1000, 999"),), runs=100, steps=10_000))
        wait_until(lambda: exp.phase == RUNNING, timeout=60, what="the experiment running")
        time.sleep(3.0)  # tasks on both workers
        start = time.monotonic()
        service.cancel("a")
        wait_until(lambda: exp.over, timeout=30, what="the experiment over")
        assert exp.phase == CANCELLED and time.monotonic() - start < 5.0
        wait_until(lambda: not any(cluster.client.processing().values()), timeout=10, what="idle workers")
    finally:
        service.stop()
