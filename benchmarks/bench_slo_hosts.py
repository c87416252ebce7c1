"""The fleet (Ch. 4–5) and the acoustic swarm (Ch. 7–8) on SLO-estimated positions: what a
tick costs against true positions, and what the localisation error does to the outcome.

Run: python benchmarks/bench_slo_hosts.py [--runs 20]
Prints two markdown tables: CPU ms per tick (oracle vs SLO Low), and, over the same seeds,
the DVC course after 300 steps and XB-PSO's convergence within 1500 steps for true
positions and the None, Low and High error sets (full neighbourhood, CSS).
"""

from __future__ import annotations

import argparse
import statistics

from bench_common import load_note, one_core, timed_cpu

PINNED = one_core()

import numpy as np  # noqa: E402

from shoal.presets.build import build  # noqa: E402
from shoal.presets.io import load  # noqa: E402

SEED = 11
POSITIONS = ("oracle", "none", "low", "high")


def scenario(name: str, positions: str, *more: str):
    over = ["slo.swarm=host", "slo.neighbourhood=full", "slo.selection=css", *more]
    over += ["slo.positions=oracle"] if positions == "oracle" else ["slo.positions=slo", f"slo.errors={positions}"]
    return load(name, over)


def tick_cost(name: str, positions: str, runs: int, steps: int = 30) -> float:
    sim = build(scenario(name, positions), runs=runs, seed=SEED)
    _, cpu = timed_cpu(sim.step, steps, warmup=3)
    return statistics.median(cpu)


def course(positions: str, runs: int) -> str:
    fleet = build(scenario("course-dvc", positions), runs=runs, seed=SEED)
    for _ in range(300):
        info = fleet.step()
    com, layers = info.com_fitness, info.layers_passed
    return (f"| course-dvc, 300 steps | {positions} | CoM x median {np.median(com):.1f} m (min {com.min():.1f}) · "
            f"layers passed median {np.median(layers):.0f}/6 · collided {int(info.collided.sum())} |")


def sonar(positions: str, runs: int) -> str:
    sw = build(scenario("sonar-xb-pso", positions, "acoustics.stop_on_converge=true"), runs=runs, seed=SEED)
    for _ in range(1500):
        info = sw.step()
        if not info.running.any():
            break
    k = info.steps_to_converge
    ok = k >= 0
    steps = f"median {np.median(k[ok]):.0f} steps" if ok.any() else "—"
    return f"| sonar-xb-pso, ≤ 1500 steps | {positions} | converged {ok.sum()}/{runs} · {steps} |"


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--runs", type=int, default=20)
    runs = ap.parse_args().runs
    print(f"{PINNED}; {load_note()}\n")
    print("| scene | runs | oracle ms/tick | SLO (Low) ms/tick |\n|---|---:|---:|---:|")
    for name in ("course-dvc", "sonar-xb-pso"):
        for r in (1, runs):
            print(f"| {name} | {r} | {tick_cost(name, 'oracle', r):.2f} | {tick_cost(name, 'low', r):.2f} |",
                  flush=True)
    print(f"\n| what ({runs} runs, seed {SEED}) | positions | outcome |\n|---|---|---|")
    for positions in POSITIONS:
        print(course(positions, runs), flush=True)
    for positions in POSITIONS:
        print(sonar(positions, runs), flush=True)


if __name__ == "__main__":
    main()
