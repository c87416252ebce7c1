"""What ``shoal reproduce --all`` costs at the thesis' run counts, before and after, target by
target, estimated from one run per case.

Run: python benchmarks/bench_reproduce.py --before PYTHON [--runs 1] [--only fig4-6 slo-pso ...]

Each target runs through ``reproduce`` with ``--runs`` runs per case (default 1) and its full
horizon, one worker, in a subprocess of this interpreter ("after") and of PYTHON, an
environment with the previous release installed ("before"); the child reports its process CPU
time and the part of it spent in the engines' ticks. Runs are independent and alike, so a
target's CPU time at its full run count (the registry's default, 31 for every Mai target as the
thesis has it) is estimated as the rest + the ticks × full runs / measured runs (after one tick
of every scene kind, so that loading compiled code is not counted): a slight overestimate,
since the per-call overhead a bigger batch shares is counted once per run. The
estimated wall time of ``--all`` with 2 workers is the sum over 2 (batches sized by cost keep
both workers busy to the end). Only an estimate: measured this way because the shared machine
was too busy for a full ``--all`` at thesis size to mean anything.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_common import fmt, load_note, table  # noqa: E402

THESIS_RUNS = {"slo-pso": 31}  # the thesis' count where the registry's default is smaller


WARM = ("default", "course-dvc", "slo-pso-sphere", "sonar-xb-pso", "course-dvc-slo")


def warm_up() -> None:
    """One tick of every scene kind, so that loading compiled code (and first-call costs of
    either release) is not counted as if every run paid it."""
    from shoal.presets.build import build
    from shoal.presets.io import load

    for preset in WARM:
        build(load(preset, ["sim.robots=6"] if preset != "slo-pso-sphere" else []), runs=2).step()


ENGINES = (("shoal.engine.kinds.swarm:Simulation", "shoal.engine.sim:Simulation"),
           ("shoal.engine.kinds.fleet:Fleet", "shoal.engine.fleet:Fleet"),
           ("shoal.engine.kinds.sonar:AcousticSwarm", "shoal.engine.sonar:AcousticSwarm"),
           ("shoal.engine.kinds.slo_swarm:SLOSwarm", "shoal.engine.slo:SLOSwarm"))


def count_ticks() -> list[float]:
    """Wrap every engine's ``step`` to add its CPU seconds to the returned cell (outermost
    call only, so a subclass calling its parent's step counts once)."""
    from bench_speed import _first

    spent, depth = [0.0], [0]
    for paths in ENGINES:
        cls = _first(*paths)
        original = cls.__dict__["step"]

        def step(engine, *a, _original=original, **k):  # type: ignore[no-untyped-def]
            depth[0] += 1
            t0 = time.process_time()
            try:
                return _original(engine, *a, **k)
            finally:
                depth[0] -= 1
                if depth[0] == 0:
                    spent[0] += time.process_time() - t0

        cls.step = step
    return spent


def child(target: str, runs: int) -> dict[str, float]:
    """Run ``target`` with ``runs`` runs here: CPU seconds in all, in the engines' ticks, and
    the full run count."""
    warm_up()
    try:
        from shoal.studies.experiments.registry import TARGETS, reproduce
    except ImportError:  # the previous release's layout
        from shoal.engine.experiments.registry import TARGETS, reproduce
    ticks = count_ticks()
    with tempfile.TemporaryDirectory() as tmp:
        c0, t0 = time.process_time(), time.perf_counter()
        reproduce(target, Path(tmp) / target, runs=runs, workers=1, progress=False)
        cpu, wall = time.process_time() - c0, time.perf_counter() - t0
    return {"cpu": cpu, "ticks": ticks[0], "wall": wall, "full": THESIS_RUNS.get(target, TARGETS[target].default_runs)}


def measure(python: str, target: str, runs: int) -> dict[str, float]:
    cmd = [python, str(Path(__file__).resolve()), "--child", target, "--runs", str(runs)]
    done = subprocess.run(cmd, capture_output=True, text=True)
    if done.returncode:
        sys.stderr.write(done.stderr[-3000:])
        raise SystemExit(f"{target} failed under {python}")
    return json.loads(done.stdout.strip().splitlines()[-1])


def scaled(m: dict[str, float], runs: int) -> float:
    """CPU seconds at the full run count: the ticks scale with the runs, the rest (building
    scenes, statistics, plots, files) is counted once."""
    return m["cpu"] - m["ticks"] + m["ticks"] * m["full"] / runs


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--before", help="python of an environment with the previous release installed")
    ap.add_argument("--runs", type=int, default=1, help="runs per case measured")
    ap.add_argument("--only", nargs="*", help="these targets only")
    ap.add_argument("--child", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child:
        print(json.dumps(child(args.child, args.runs)))
        return
    from shoal.studies.experiments.registry import TARGETS

    print(f"{load_note()}\n", flush=True)
    rows, total = [], {"before": 0.0, "after": 0.0}
    for name in args.only or list(TARGETS):
        after = measure(sys.executable, name, args.runs)
        before = measure(args.before, name, args.runs) if args.before else None
        est = {"after": scaled(after, args.runs)}
        if before:
            est["before"] = scaled(before, args.runs)
        for side, v in est.items():
            total[side] += v
        ratio = f"{est['before'] / est['after']:.1f}×" if before else "–"
        rows.append([name, str(after["full"]), fmt(est.get("before", float("nan"))), fmt(est["after"]), ratio])
        print(f"  {name}: after {est['after']:.0f} s" + (f", before {est['before']:.0f} s" if before else ""),
              file=sys.stderr, flush=True)
    rows.append(["**all, CPU s**", "", fmt(total["before"]) if args.before else "–", fmt(total["after"]),
                 f"{total['before'] / total['after']:.1f}×" if args.before else "–"])
    rows.append(["**all, estimated wall min with 2 workers**", "",
                 fmt(total["before"] / 120) if args.before else "–", fmt(total["after"] / 120),
                 ""])
    print(table(["target", "runs a case (thesis)", "before CPU s (est.)", "after CPU s (est.)", "ratio"], rows))
    print(f"\nmeasured with {args.runs} run(s) a case, scaled to the full count; after the run: {load_note()}")


if __name__ == "__main__":
    main()
