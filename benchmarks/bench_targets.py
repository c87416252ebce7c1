"""Robot-steps per second of every reproduction target (``shoal reproduce --list``).

Run: python benchmarks/bench_targets.py [--quick] [--only fig4-6 slo-pso ...]

Each target runs once through ``reproduce`` (one worker, in this process) with few runs and
a shortened horizon (the options in ``SMALL``), into a temporary folder. The engine ticks
(``Simulation``, ``Fleet``, ``AcousticSwarm``, ``SLOSwarm``) are wrapped to count the robot-steps
they advance (runs still running × robots, per tick) and the wall time spent inside them,
by engine kind: a target with kinematic and physics fleets (fig4-6) gets one row each.

Times are CPU times of this process (robust while other jobs share the machine; the wall
time is shown too). "engine" rates are robot-steps over the CPU time inside the ticks; "end to
end" divides all the target's robot-steps by its whole CPU time, which also covers building
the scenes, the statistics and writing the CSV/PNG/README files (a large share for these
short runs; the full-size runs spend almost all their time in the ticks). A target with two
engine kinds shows its whole-target columns on both rows.
"""

from __future__ import annotations

import argparse
import functools
import sys
import tempfile
import time
from collections import defaultdict
from pathlib import Path
from typing import Any, Callable

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_common import fmt, load_note, rate, table  # noqa: E402

# target -> (runs, options) of the measured run: several runs per case (the engines batch the
# runs of a case into one tick), short horizons. --quick: one run and half the horizon.
SMALL: dict[str, tuple[int, dict[str, Any]]] = {
    "fig3-4": (5, {}),
    "fig3-5": (5, {}),
    "fig4-6": (10, {"duration": 60.0}),
    "fig5-4": (5, {"duration": 60.0}),
    "fig5-5": (10, {"duration": 60.0}),
    "fig7-2": (20, {"steps": 100}),
    "fig7-4": (5, {"steps": 100}),
    "fig7-5": (5, {"steps": 100}),
    "fig8-2": (20, {"steps": 100}),
    "fig8-4": (5, {"steps": 200}),
    "fig8-5": (5, {"steps": 200}),
    "slo-errors": (5, {"generations": 60}),  # its checks read generation 25
    "slo-mitigation": (2, {"generations": 60}),
    "slo-neighbourhood": (5, {"generations": 60}),
    "slo-weight": (5, {"generations": 60}),
    "slo-pso": (3, {"short": 50, "functions": ("rastrigin", "ackley")}),
}
HORIZONS = ("duration", "steps", "generations", "short")


class TickMeter:
    """Robot-steps and CPU seconds inside the engine ticks, by engine kind."""

    def __init__(self) -> None:
        self.steps: dict[str, int] = defaultdict(int)
        self.seconds: dict[str, float] = defaultdict(float)
        self._undo: list[Callable[[], None]] = []

    def wrap(self, cls: type, kind: Callable[[Any], str], robot_steps: Callable[[Any], int]) -> None:
        original = cls.__dict__["step"]

        @functools.wraps(original)
        def step(engine: Any, *args: Any, **kwargs: Any) -> Any:
            n, k = robot_steps(engine), kind(engine)
            t0 = time.thread_time()
            try:
                return original(engine, *args, **kwargs)
            finally:
                self.seconds[k] += time.thread_time() - t0
                self.steps[k] += n

        cls.step = step
        self._undo.append(lambda: setattr(cls, "step", original))

    def install(self) -> "TickMeter":
        from shoal.engine.kinds.fleet import Fleet
        from shoal.engine.kinds.slo_swarm import SLOSwarm
        from shoal.engine.kinds.sonar import AcousticSwarm
        from shoal.engine.kinds.swarm import Simulation

        self.wrap(Simulation, lambda e: "Ch. 3 swarm" + (" (SLO positions)" if type(e) is not Simulation else ""),
                  lambda e: e.runs * e.robots)
        self.wrap(Fleet, lambda e: f"fleet, {e.params.motion}", lambda e: e.runs * e.robots)
        self.wrap(AcousticSwarm, lambda e: f"acoustic swarm, {e.params.mode}",
                  lambda e: int(e.state.running.sum()) * e.robots)
        self.wrap(SLOSwarm, lambda e: "SLO swarm", lambda e: e.runs * e.config.particles)
        return self

    def remove(self) -> None:
        for undo in reversed(self._undo):
            undo()
        self._undo.clear()

    def take(self) -> dict[str, tuple[int, float]]:
        out = {k: (self.steps[k], self.seconds[k]) for k in self.steps}
        self.steps.clear()
        self.seconds.clear()
        return out


def quick(runs: int, options: dict[str, Any]) -> tuple[int, dict[str, Any]]:
    """One run and half the horizon."""
    small = dict(options)
    for key in HORIZONS:
        if key in small:
            small[key] = type(small[key])(small[key] / 2)
    return 1, small


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="one run and half the horizon per target")
    ap.add_argument("--only", nargs="*", help="these targets only")
    args = ap.parse_args()
    from shoal.studies.experiments.registry import TARGETS, reproduce

    missing = sorted(set(TARGETS) - set(SMALL))
    if missing:
        print(f"note: no small configuration for {', '.join(missing)}; running them at runs=1", file=sys.stderr)
    names = args.only or list(TARGETS)
    meter = TickMeter().install()
    rows = []
    try:
        for name in names:
            runs, options = SMALL.get(name, (1, {}))
            if args.quick:
                runs, options = quick(runs, options)
            with tempfile.TemporaryDirectory() as tmp:
                t0, c0 = time.perf_counter(), time.process_time()
                try:
                    reproduce(name, Path(tmp) / name, runs=runs, workers=1, progress=False, **options)
                except Exception as err:  # a target that refuses the short run: say so, go on
                    meter.take()
                    rows.append([name, f"failed: {err!r}"[:80], str(runs), "", "", "", "", "", "", ""])
                    continue
                wall, cpu = time.perf_counter() - t0, time.process_time() - c0
            ticks = meter.take()
            total = sum(n for n, _ in ticks.values())
            shown = ", ".join(f"{k}={v}" for k, v in options.items()) or "defaults"
            for kind, (n, secs) in sorted(ticks.items()):
                rows.append([name, kind, str(runs), shown, f"{n / 1e6:.3g} M", fmt(secs), rate(n / secs),
                             fmt(cpu), fmt(wall), rate(total / cpu)])
            print(f"  {name}: {total} robot-steps, {wall:.1f} s", file=sys.stderr)
    finally:
        meter.remove()
    print(f"{load_note()}\n")
    print(table(["target", "engine", "runs", "options", "robot-steps", "CPU s in ticks", "engine robot-steps/s",
                 "target CPU s", "target wall s", "end-to-end robot-steps/s (CPU)"], rows))


if __name__ == "__main__":
    main()
