"""A 2 x 2 ``shoal sweep`` in this process, on a 2-process local pool and on a local Dask
cluster of 2 worker processes: wall time, CPU time (this process, its children and the Dask
workers) and whether the three ``results.csv`` files are identical.

    python benchmarks/bench_sweep.py --reps 2 [--runs 4 --steps 1000]

The sweep is Q x D/lambda_c (1.5, 10 x 0.5, 1) of ``sonar-xb-pso`` at the waveform level.
On a shared machine the wall times follow the load; the CPU times are the cost of each
scheduler (worker start-up, imports, smaller chunks, Dask's event loops)."""

from __future__ import annotations

import argparse
import os
import resource
import shutil
import tempfile
import time
from pathlib import Path

from bench_common import load_note

GRID = ["acoustics.Q=1.5,10", "acoustics.d_over_lambda=0.5,1"]


def _cpu_here() -> float:
    a, b = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return a.ru_utime + a.ru_stime + b.ru_utime + b.ru_stime


def _worker_cpu(client) -> float:
    def cpu() -> float:
        import psutil

        t = psutil.Process().cpu_times()
        return t.user + t.system

    return sum(client.run(cpu).values())


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--reps", type=int, default=2)
    ap.add_argument("--runs", type=int, default=4)
    ap.add_argument("--steps", type=int, default=1000)
    args = ap.parse_args()
    from distributed import LocalCluster

    from shoal.studies.experiments.schedulers import DaskCluster, LocalPool
    from shoal.studies.sweep import run_sweep

    root = Path(tempfile.mkdtemp(prefix="bench-sweep-"))
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0") as lc:
        dask = DaskCluster(lc.scheduler_address)
        print(f"2x2 sweep of sonar-xb-pso, {args.runs} runs x {args.steps} steps per cell")
        print("| scheduler | wall s | CPU s | load (1 min) |\n|---|---|---|---|")
        for rep in range(args.reps):
            outs = []
            for name, kw in (("in-process", {}), ("local pool, 2 processes", {"scheduler": LocalPool(2)}),
                             ("Dask, 2 worker processes", {"scheduler": dask})):
                out = root / f"{rep}-{len(outs)}"
                load = os.getloadavg()[0]
                w0 = _worker_cpu(dask.client) if "Dask" in name else 0.0
                c0, t0 = _cpu_here(), time.perf_counter()
                run_sweep("sonar-xb-pso", GRID, out, runs=args.runs, steps=args.steps, progress=False, **kw)
                wall = time.perf_counter() - t0
                cpu = _cpu_here() - c0 + ((_worker_cpu(dask.client) - w0) if "Dask" in name else 0.0)
                print(f"| {name} | {wall:.1f} | {cpu:.1f} | {load:.1f} |", flush=True)
                outs.append(out)
            same = all((o / "results.csv").read_bytes() == (outs[0] / "results.csv").read_bytes() for o in outs)
            print(f"rep {rep + 1}: results.csv identical across schedulers: {same}")
        dask.close()
    print(load_note())
    shutil.rmtree(root, ignore_errors=True)


if __name__ == "__main__":
    main()
