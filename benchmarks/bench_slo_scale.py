"""Mai's SLO generation against the swarm size, all-pairs ranging (the thesis) against
neighbour-only ranging (``slo.ranging = "neighbours"``; issue 35, item 3).

Run: python benchmarks/bench_slo_scale.py [--base PATH] [--neighbours 1000 2000 5000 10000]
     [--all 200 400 1000] [--runs 1] [--reps 3]

SPSO on Sphere, Low errors, CSS, knn 5 (the thesis' settings), one generation = one
``SLOSwarm.step()``. Each point runs in a fresh process: a small swarm loads the kernels, the
swarm is built and stepped twice (warm-up), then ``--gens`` generations are timed, ``--reps``
times in turn across the sizes and modes (A B A B); the table gives the median wall ms per
generation and its range, the process's peak resident memory (``ru_maxrss``) and that peak
less the resident memory before the swarm was built (what the swarm and its generations add). The
growth exponent is the slope of log(time) on log(N) over the sizes given. ``--base`` also runs
the all-pairs sizes in another tree (a checkout of main), ``PYTHONPATH`` at its ``src``.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import subprocess
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_common import fmt, load_note, table  # noqa: E402

CHILD = r"""
import json, os, resource, sys, time
n, runs, gens, ranging = int(sys.argv[1]), int(sys.argv[2]), int(sys.argv[3]), sys.argv[4]
from shoal.engine.kinds.slo_swarm import SLOSwarm
kw = {} if ranging == "all" else {"ranging": ranging}
make = lambda n, runs: SLOSwarm(runs=runs, seed=1, particles=n, errors="low", neighbourhood="knn", **kw)
small = make(30, 1)
small.step(); small.step(); small.info().e_abs  # the kernels loaded before anything is measured
del small
with open("/proc/self/statm") as fh:
    before = int(fh.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 2**20
sw = make(n, runs)
sw.step(); sw.step()
t0 = time.perf_counter()
for _ in range(gens):
    sw.step()
ms = (time.perf_counter() - t0) / gens * 1e3
peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
print(json.dumps({"ms": ms, "mib": peak - before, "peak_mib": peak}))
"""


def point(n: int, runs: int, gens: int, ranging: str, tree: Path | None = None) -> dict:
    env = dict(os.environ)
    if tree is not None:
        env["PYTHONPATH"] = str(tree / "src")
    done = subprocess.run(["nice", "-n", "10", sys.executable, "-c", CHILD, str(n), str(runs), str(gens), ranging],
                          env=env, capture_output=True, text=True, check=True)
    return json.loads(done.stdout.strip().splitlines()[-1])


def slope(ns: list[int], ms: list[float]) -> float:
    """Least-squares slope of log(ms) on log(n)."""
    x = [math.log(v) for v in ns]
    y = [math.log(v) for v in ms]
    mx, my = sum(x) / len(x), sum(y) / len(y)
    return sum((a - mx) * (b - my) for a, b in zip(x, y)) / sum((a - mx) ** 2 for a in x)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--base", type=Path)
    ap.add_argument("--neighbours", type=int, nargs="*", default=[1000, 2000, 5000, 10_000])
    ap.add_argument("--all", type=int, nargs="*", default=[200, 400, 1000])
    ap.add_argument("--runs", type=int, default=1)
    ap.add_argument("--gens", type=int, default=3)
    ap.add_argument("--reps", type=int, default=3)
    args = ap.parse_args()
    cases = [("neighbours", n, None) for n in args.neighbours] + [("all", n, None) for n in args.all]
    if args.base:
        cases += [("all (base)", n, args.base) for n in args.all]
    print(f"# {load_note()} (before)", flush=True)
    got: dict[tuple[str, int], list[dict]] = {}
    for _ in range(args.reps):
        for mode, n, tree in cases:
            r = point(n, args.runs, args.gens, mode.split()[0], tree)
            got.setdefault((mode, n), []).append(r)
            print(mode, n, r, flush=True)
    rows = []
    for mode, n, _ in cases:
        ms = sorted(r["ms"] for r in got[(mode, n)])
        mib = sorted(r["mib"] for r in got[(mode, n)])
        peak = sorted(r["peak_mib"] for r in got[(mode, n)])
        rows.append([mode, str(n), str(args.runs), f"{fmt(ms[len(ms) // 2])} ({fmt(ms[0])}–{fmt(ms[-1])})",
                     fmt(peak[len(peak) // 2]), fmt(mib[len(mib) // 2]), fmt(1e3 * ms[len(ms) // 2] / (n * args.runs))])
    print(table(["ranging", "particles", "runs", "ms / generation", "peak RSS MiB", "MiB the swarm adds",
                 "µs / particle-gen"], rows))
    for mode in ("neighbours", "all", "all (base)"):
        ns = [n for m, n, _ in cases if m == mode]
        if len(ns) > 1:
            meds = [sorted(r["ms"] for r in got[(mode, n)])[len(got[(mode, n)]) // 2] for n in ns]
            print(f"growth exponent, {mode}, {ns[0]}–{ns[-1]}: {slope(ns, meds):.2f}")
    print(f"# {load_note()} (after)")


if __name__ == "__main__":
    main()
