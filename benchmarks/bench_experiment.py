"""The Experiment tab's cost: the same grid as ``shoal sweep`` in this process and as an
experiment on the app server's pool (one forkserver worker), wall time and whether the tidy
tables are identical; and how fast a live tab of that server plays while the experiment runs,
against the same tab with no experiment.

    python benchmarks/bench_experiment.py [--runs 10 --steps 600 --reps 2]

The grid is U x A+ (6, 8, 10 x 10, 20, 30) of ``default``. The live tab plays ``default`` at
240 steps/s (the speed slider's top), ticked by the server's own thread; its steps per second
are what a student sees move. On a shared machine wall times follow the load."""

from __future__ import annotations

import argparse
import os
import tempfile
import time
from pathlib import Path

GRID = ["controller.U=6,8,10", "controller.A_plus=10,20,30"]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--reps", type=int, default=2)
    ap.add_argument("--runs", type=int, default=10)
    ap.add_argument("--steps", type=int, default=600)
    args = ap.parse_args()
    from shoal.app.experiment import AxisRequest, ExperimentRequest
    from shoal.app.server import start_server
    from shoal.presets.io import load
    from shoal.studies.sweep import run_sweep

    ask = ExperimentRequest((AxisRequest("controller.U", values="6, 8, 10"),
                             AxisRequest("controller.A_plus", values="10, 20, 30")), args.runs, args.steps)
    srv = start_server("default", port=0)
    tab = srv.open_tab(-1, srv.viser.gui, srv.viser.scene)
    tab.session.apply({"view.steps_per_second": 240.0, "sim.steps": 10_000_000})  # plays on and on
    tab.session.play()

    def steps_per_s(seconds: float) -> float:  # of the live tab
        k0, t0 = tab.session.sim.state.k, time.monotonic()
        time.sleep(seconds)
        return (tab.session.sim.state.k - k0) / (time.monotonic() - t0)

    print(f"3 x 3 grid of default, {args.runs} runs x {args.steps} steps per cell; load {os.getloadavg()[0]:.1f}")
    print("| rep | shoal sweep, in-process: wall s | experiment, server pool: wall s | same results.csv | "
          "live tab steps/s, idle | live tab steps/s, experiment running |\n|---|---|---|---|---|---|")
    try:
        for rep in range(args.reps):
            with tempfile.TemporaryDirectory() as tmp:
                t0 = time.perf_counter()
                run_sweep("default", GRID, Path(tmp) / "s", runs=args.runs, steps=args.steps, progress=False)
                sweep_s = time.perf_counter() - t0
                table = (Path(tmp) / "s" / "results.csv").read_text(encoding="utf-8")
            idle = steps_per_s(5.0)
            ended: list[tuple[float, int]] = []  # (time, live tab's step) when the experiment ended

            def note(e, ended=ended) -> None:
                if e.over:
                    ended.append((time.perf_counter(), tab.session.sim.state.k))

            k0, t0 = tab.session.sim.state.k, time.perf_counter()
            srv.experiments.submit(f"bench-{rep}", load("default"), ask, listener=note)
            while not ended:
                time.sleep(0.01)
            exp_s = ended[0][0] - t0
            busy = (ended[0][1] - k0) / exp_s
            exp = srv.experiments.experiment(f"bench-{rep}")
            print(f"| {rep + 1} | {sweep_s:.1f} | {exp_s:.1f} | {exp.table.csv() == table} | {idle:.0f} | {busy:.0f} |")
    finally:
        srv.stop()


if __name__ == "__main__":
    main()
