"""The first ``shoal run default --steps 10`` against a plain numpy script of the same 10 steps,
for this tree and (``--base REV``) an earlier commit, in one run (issue 35, item 4: import only
the kind you run).

Run: nice -n 10 python benchmarks/bench_first_run.py [--base main] [--repeats 15]

Each round starts, in turn, a new interpreter for: the numpy script (:data:`NUMPY_SCRIPT`: the
Adapted PSO (sgn) swarm of the default preset, 20 robots in 2-D tuned from U = 6 m/s,
A+ = 30 m/s², Δt = 0.1 s, 10 steps, writing its trajectories and metrics as CSV and a JSON
header, as ``shoal run`` does), then ``python -m shoal run default --steps 10`` of each tree
(its own ``PYTHONPATH``; the base exported with ``git archive``, ``page_server.tree_of``).
The numba cache is the user's, as after any first use (one round is run and dropped first).
Bytecode is cached as on any machine after a first use (``pip install`` compiles it; Python
writes it at a first import): every child, the numpy script's too, writes and reads it under a
``PYTHONPYCACHEPREFIX`` of its own in the temporary folder, filled by the dropped round, whatever
``PYTHONDONTWRITEBYTECODE`` the shell has. Plug-ins load as a user's do (``SHOAL_PLUGINS`` as the
shell has it: on by default), so the entry-point scan is counted. ``--no-bytecode`` measures with none cached instead
(every module of each tree compiled at each start; site-packages keep the bytecode pip wrote).
It prints the median and range of each wall time, the medians' difference to the numpy script,
and, from ``python -X importtime``, how each tree's import time splits between packages. Nothing
is asserted; the machine may be shared, so read the trees side by side.
"""

from __future__ import annotations

import argparse
import os
import re
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
from page_server import tree_of  # noqa: E402

NUMPY_SCRIPT = r"""
import json, sys
from pathlib import Path
import numpy as np

out = Path(sys.argv[1]); out.mkdir(parents=True, exist_ok=True)
N, d, steps, dt, U, A = 20, 2, 10, 0.1, 6.0, 30.0
beta = A * dt / U                       # [3.35]: omega = 1 - beta, c_hat = beta U / sqrt(d) [3.32]-[3.34]
omega, c_hat = 1.0 - beta, beta * U / np.sqrt(d)
c1 = c2 = 0.5 * c_hat
rng = np.random.default_rng(np.random.SeedSequence(1).spawn(1)[0])
source = np.array([12.0, 4.0])
x = np.array([-12.0, -4.0]) + 4.0 * (rng.random((N, d)) - 0.5)
u = np.zeros((N, d))
f = np.linalg.norm(x - source, axis=1)
y, fy = x.copy(), f.copy()
(out / "run.json").write_text(json.dumps({"preset": "default", "seed": 1, "steps": steps}))
traj, metrics = [], []
for k in range(steps + 1):
    if k:
        better = f < fy
        y[better], fy[better] = x[better], f[better]
        g = y[np.argmin(fy)]
        r1, r2 = rng.random((N, d)), rng.random((N, d))
        u = omega * u + c1 * r1 * np.sign(y - x) + c2 * r2 * np.sign(g - x)   # [3.11]
        x = x + dt * u                                                        # [3.10]
        f = np.linalg.norm(x - source, axis=1)
    speed = np.linalg.norm(u, axis=1)
    traj += [f"0,{k},{k * dt:.6f},{i},{x[i, 0]:.9g},{x[i, 1]:.9g},{u[i, 0]:.9g},{u[i, 1]:.9g}" for i in range(N)]
    metrics.append(f"0,{k},{k * dt:.6f},{min(fy.min(), f.min()):.9g},{speed.max():.9g},{speed.mean():.9g}")
(out / "trajectories.csv").write_text("run,step,t,robot,x,y,vx,vy\n" + "\n".join(traj) + "\n")
(out / "metrics.csv").write_text("run,step,t,best_fitness,max_speed,mean_speed\n" + "\n".join(metrics) + "\n")
"""

GROUPS = ("numba", "llvmlite", "scipy", "pymunk", "pydantic", "numpy", "tqdm", "shoal")


def _timed(args: list[str], env: dict[str, str]) -> tuple[float, float]:
    """Wall-clock and CPU (user + system) seconds of one child process."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    done = subprocess.run(args, env=env, capture_output=True, text=True, timeout=600)
    took = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if done.returncode != 0:
        raise RuntimeError(f"{' '.join(args)} failed: {done.stderr[-2000:]}")
    return took, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def _shoal(pkg: Path, out: Path) -> list[str]:
    return [sys.executable, "-m", "shoal", "run", "default", "--steps", "10", "--out", str(out)]


def import_split(pkg: Path, tmp: Path, pycache: Path | None) -> tuple[float, dict[str, float], list[str]]:
    """``python -X importtime`` of one ``shoal run``: total seconds, seconds by package (self
    times), and the shoal modules of the later chapters it imported."""
    done = subprocess.run([sys.executable, "-X", "importtime", *_shoal(pkg, tmp / "it")[1:]], env=_env(pkg, pycache),
                          capture_output=True, text=True, timeout=600)
    rows = [m.groups() for m in re.finditer(r"import time:\s+(\d+) \|\s+\d+ \|( *)(\S+)", done.stderr)]
    split = dict.fromkeys(GROUPS + ("other",), 0.0)
    for self_us, _, name in rows:
        top = name.split(".")[0]
        split[top if top in GROUPS else "other"] += int(self_us) / 1e6
    later = sorted(n for _, _, n in rows if re.match(r"shoal\.(engine\.(robots|acoustics|slo)|engine\.kinds\.(fleet|"
                                                      r"sonar|slo_swarm)|presets\.builders\.(fleet|sonar|slo))", n))
    return sum(split.values()), split, later


def _base_env(pycache: Path | None) -> dict[str, str]:
    """The shell's environment with the bytecode choice (``pycache``: the prefix to cache it under,
    None: none written)."""
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONDONTWRITEBYTECODE", "PYTHONPYCACHEPREFIX")}
    if pycache is None:
        env["PYTHONDONTWRITEBYTECODE"] = "1"
    else:
        env["PYTHONPYCACHEPREFIX"] = str(pycache)
    return env


def _env(pkg: Path, pycache: Path | None) -> dict[str, str]:
    return {**_base_env(pycache), "PYTHONPATH": str(pkg)}  # (plug-ins as the shell has them: on by default)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--base", default="main", help="the commit to compare with ('' for none)")
    ap.add_argument("--repeats", type=int, default=15)
    ap.add_argument("--no-bytecode", action="store_true",
                    help="cache no bytecode: each tree's modules compiled at every start")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp_name:
        tmp = Path(tmp_name)
        pycache = None if args.no_bytecode else tmp / "pycache"
        trees = {"this tree": tree_of(None, tmp / "this")}
        if args.base:
            (tmp / "base").mkdir()
            trees[args.base] = tree_of(args.base, tmp / "base")
        script = tmp / "numpy_run.py"
        script.write_text(NUMPY_SCRIPT)
        times: dict[str, list[tuple[float, float]]] = {"numpy script": [], **{name: [] for name in trees}}
        for round_ in range(args.repeats + 1):  # round 0: the caches filled, dropped
            got = {"numpy script": _timed([sys.executable, str(script), str(tmp / "np")], _base_env(pycache))}
            for name, pkg in trees.items():
                got[name] = _timed(_shoal(pkg, tmp / f"out-{round_}-{len(got)}"), _env(pkg, pycache))
            if round_:
                for name, t in got.items():
                    times[name].append(t)
        load = os.getloadavg()
        print(f"{args.repeats} rounds, load average {load[0]:.2f} {load[1]:.2f} {load[2]:.2f} (uptime), "
              f"{os.cpu_count()} cores, bytecode "
              f"{'compiled at every start' if args.no_bytecode else 'cached (written by the dropped round)'}\n")
        for i, what in enumerate(("wall-clock", "CPU (user + system)")):
            base = statistics.median(t[i] for t in times["numpy script"])
            print(f"{what + ' s':<22} {'median':>8} {'min':>7} {'max':>7}  {'median − numpy':>15}")
            for name, ts in times.items():
                vals = [t[i] for t in ts]
                med = statistics.median(vals)
                print(f"  {name:<20} {med:8.3f} {min(vals):7.3f} {max(vals):7.3f}  {med - base:+14.3f}")
            print()
        print("\nimport time by package (python -X importtime, self times, s):")
        print(f"{'':<12}" + "".join(f"{g:>9}" for g in (*GROUPS, "other", "total")))
        for name, pkg in trees.items():
            total, split, later = import_split(pkg, tmp, pycache)
            print(f"{name:<12}" + "".join(f"{split[g]:9.3f}" for g in (*GROUPS, "other")) + f"{total:9.3f}")
            print(f"{'':<12}later chapters' shoal modules imported: {len(later)}"
                  + (f" ({', '.join(later[:4])}, …)" if later else ""))


if __name__ == "__main__":
    main()
