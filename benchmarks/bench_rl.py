"""Speed of the vector environment (shoal.rl) against VMAS on the CPU, and the env layer's overhead
over plain ``Scene.step``, in one run.

Run: python benchmarks/bench_rl.py [--envs 32] [--robots 20] [--steps 100] [--repeats 5]
                                   [--vmas-python PATH] [--quick]

* Shoal: ``ShoalVectorEnv`` of ``course-dvc`` (the Chapter 4 fleet: bodies, obstacle layers,
  six-sector sensing, collisions; kinematic, compiled) with ``--envs`` runs of ``--robots`` robots,
  its start square grown as 2√N m so the density is the preset's (as bench_scaling.py does).
  Actions are the law's own commands, recorded beforehand from a plain scene of the same seed, so
  the environment moves every robot exactly as ``Scene.step`` does (the script checks the positions
  agree to the bit): the two sides do the same engine work, and the difference is the env layer
  (the steering, the observation with each robot's six-sector reading, reward, end rule, info).
* VMAS 1.5 ``flocking`` (agents with a LiDAR, obstacles, collisions; its physics engine; or
  ``--vmas-scenario navigation``: a LiDAR, no obstacles) on the CPU, the same number of envs and
  agents, random actions; run by ``--vmas-python``, the interpreter of
  a separate venv with ``torch`` and ``vmas`` (never this project's: ``pip install torch==2.13.0
  vmas==1.5.2`` there). Without it the VMAS row is left out.

Each repeat times all sides one after another (so the machine's load hits them alike); the
median over repeats is reported. Times are CPU seconds of the process doing the work; both sides
run on one core (torch with one thread). Env steps/s = robots × envs × steps per second.
"""

from __future__ import annotations

import argparse
import json
import math
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_common import load_note, one_core, table  # noqa: E402

PRESET = "course-dvc"

VMAS_CHILD = r"""
import json, sys, time
import torch
torch.set_num_threads(1)
import vmas
envs, agents, steps, seed = (int(a) for a in sys.argv[1:5])
scenario = sys.argv[5]
env = vmas.make_env(scenario=scenario, num_envs=envs, device="cpu", continuous_actions=True, seed=seed,
                    n_agents=agents)
env.reset()
g = torch.Generator().manual_seed(seed)
def actions():
    return [2 * torch.rand((envs, env.get_agent_action_size(a)), generator=g) - 1 for a in env.agents]
for _ in range(5):
    env.step(actions())
acts = [actions() for _ in range(steps)]
c0, t0 = time.process_time(), time.perf_counter()
for a in acts:
    env.step(a)
print(json.dumps({"cpu": time.process_time() - c0, "wall": time.perf_counter() - t0,
                  "version": vmas.__version__, "torch": torch.__version__}))
"""


def world(robots: int) -> dict[str, float]:
    """The course around a start square of 2√N m: the preset's density at any size."""
    side = round(2.0 * math.sqrt(robots), 1)
    return {"start_size": side, "width": side + 10, "length": max(60.0, 2 * side + 30)}


def law_commands(envs: int, robots: int, steps: int, seed: int) -> tuple[list[np.ndarray], np.ndarray]:
    """The commands the law gives each robot, tick by tick, and where the robots end."""
    import shoal
    from shoal.rl.kinds.fleet import SPEC

    scene = shoal.make(PRESET, runs=envs, seed=seed, robots=robots, world=world(robots))
    scene.record = False
    out = []
    for _ in range(steps):
        scene.engine.step()
        out.append(SPEC.commanded(scene))
    return out, scene.state.x.copy()


def time_scene(envs: int, robots: int, steps: int, seed: int) -> float:
    import shoal

    scene = shoal.make(PRESET, runs=envs, seed=seed, robots=robots, world=world(robots))
    scene.record = False  # (a metric row a step would be the scene's own overhead)
    c0 = time.process_time()
    for _ in range(steps):
        scene.step()
    return time.process_time() - c0


def time_env(envs, commands: list[np.ndarray], seed: int, end: np.ndarray) -> float:
    envs.reset(seed=seed)
    c0 = time.process_time()
    for a in commands:
        envs.step(a)
    cpu = time.process_time() - c0
    assert np.array_equal(envs.scene.state.x, end), "the env moved the robots as Scene.step does"
    return cpu


def time_vmas(python: str, envs: int, robots: int, steps: int, seed: int, scenario: str) -> dict:
    done = subprocess.run([python, "-c", VMAS_CHILD, str(envs), str(robots), str(steps), str(seed), scenario],
                          capture_output=True, text=True, timeout=3600)
    if done.returncode != 0:
        raise SystemExit(f"VMAS failed:\n{done.stderr[-3000:]}")
    return json.loads(done.stdout.strip().splitlines()[-1])


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--envs", type=int, default=32)
    ap.add_argument("--robots", type=int, default=20)
    ap.add_argument("--steps", type=int, default=100)
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--vmas-python", help="python of a venv with torch and vmas (VMAS row left out without it)")
    ap.add_argument("--vmas-scenario", default="flocking", help="flocking (obstacles, LiDAR) or navigation (LiDAR)")
    ap.add_argument("--quick", action="store_true", help="4 envs × 5 robots, 20 steps, 2 repeats")
    args = ap.parse_args(argv)
    if args.quick:
        args.envs, args.robots, args.steps, args.repeats = 4, 5, 20, 2
    pinned = one_core()
    import gymnasium as gym

    import shoal.rl  # noqa: F401  (registers the envs)

    E, N, T = args.envs, args.robots, args.steps
    envs = gym.make_vec(f"shoal/{PRESET}-v0", num_envs=E, vectorization_mode="vector_entry_point", robots=N,
                        steps=T + 1, world=world(N))
    commands, end = law_commands(E, N, T, args.seed)
    time_env(envs, commands, args.seed, end)  # compile and warm up
    time_scene(E, N, T, args.seed)
    results: dict[str, list[float]] = {"scene": [], "env": [], "vmas": []}
    vmas_meta: dict = {}
    for _ in range(args.repeats):
        results["scene"].append(time_scene(E, N, T, args.seed))
        results["env"].append(time_env(envs, commands, args.seed, end))
        if args.vmas_python:
            got = time_vmas(args.vmas_python, E, N, T, args.seed, args.vmas_scenario)
            vmas_meta = got
            results["vmas"].append(got["cpu"])
    med = {k: float(np.median(v)) for k, v in results.items() if v}
    rate = {k: N * E * T / v for k, v in med.items()}
    rows = [["plain Scene.step (course-dvc, law)", f"{E} × {N}", f"{med['scene'] / T * 1e3:.3f}",
             f"{rate['scene'] / 1e3:.1f} k", "–"],
            ["ShoalVectorEnv.step (course-dvc, velocity)", f"{E} × {N}", f"{med['env'] / T * 1e3:.3f}",
             f"{rate['env'] / 1e3:.1f} k", "–"]]
    if "vmas" in med:
        what = f"VMAS {vmas_meta['version']} {args.vmas_scenario} (torch {vmas_meta['torch']}, CPU)"
        rows.append([what, f"{E} × {N}",
                     f"{med['vmas'] / T * 1e3:.3f}", f"{rate['vmas'] / 1e3:.1f} k",
                     f"{rate['env'] / rate['vmas']:.1f}×"])
    print(f"# shoal.rl vector env: {E} envs × {N} robots, {T} steps, median of {args.repeats} ({pinned}; "
          f"{load_note()})\n")
    print(table(["what", "envs × robots", "ms/step", "env steps/s", "Shoal env ÷ this"], rows))
    print(f"\nenv layer's overhead over plain Scene.step: {med['env'] / med['scene'] - 1:+.1%} "
          f"(target ≤ +20 %)")
    if "vmas" in med:
        print(f"Shoal's vector env ÷ VMAS: {rate['env'] / rate['vmas']:.1f}× (target ≥ 8×)")


if __name__ == "__main__":
    main()
