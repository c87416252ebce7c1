"""What A/B comparison and replays cost in the browser app, per kind of scene.

* step: one session step (engine + history) alone and with swarm B in lock-step;
* frame: what the scene redraw reads per frame (snapshot + B's robots and trails), live and
  at a scrubbed step;
* replay: export (pack + compress), file size, load (checks + unpack) and the determinism
  check (a fresh session re-running the first 20 steps) for the buffered history;
* the largest history the ring buffer keeps (1000 robots × 400 steps) as a replay.

Run: python benchmarks/bench_compare_replay.py
"""

from __future__ import annotations

import time

from shoal.app import replay
from shoal.app.tab import session_for
from shoal.app.timeline import verify_replay
from shoal.presets import io as presets_io

CASES = (("default", 400), ("course-dvc", 200), ("sonar-xb-pso", 200), ("slo-walk", 200))


def per_call(fn, n: int) -> float:
    t0 = time.perf_counter()
    for _ in range(n):
        fn()
    return (time.perf_counter() - t0) / n * 1e3


def step_cost(name: str, steps: int, compare: bool) -> tuple[float, object]:
    s = session_for(presets_io.load(name, [f"sim.steps={10 * steps}"]))
    if compare:
        s.enable_compare({})
    s.step(2)
    return per_call(lambda: s.step(1), steps), s


def main() -> None:
    print(f"{'preset':>13} {'ms/step':>8} {'+B':>8} {'frame':>7} {'scrubbed':>8} {'steps':>6} "
          f"{'KiB':>7} {'export':>7} {'load':>7} {'verify':>7}  (ms)")
    for name, steps in CASES:
        alone, _ = step_cost(name, steps, compare=False)
        both, s = step_cost(name, steps, compare=True)
        live = per_call(lambda s=s: (s.shown_snapshot(), s.twin_view()), 20)
        s.scrub(steps // 2)
        scrubbed = per_call(lambda s=s: (s.shown_snapshot(), s.twin_view()), 20)
        export = per_call(s.export_replay, 3)
        data = s.export_replay()
        load = per_call(lambda data=data: replay.from_bytes(data), 3)
        rec = replay.from_bytes(data)
        t0 = time.perf_counter()
        ok, _ = verify_replay(session_for(presets_io.validate(rec.meta["preset"])), rec)
        verify = (time.perf_counter() - t0) * 1e3
        assert ok
        print(f"{name:>13} {alone:>8.3f} {both:>8.3f} {live:>7.2f} {scrubbed:>8.2f} {rec.frames:>6} "
              f"{len(data) / 1024:>7.0f} {export:>7.1f} {load:>7.1f} {verify:>7.1f}")
    s = session_for(presets_io.load("default", ["sim.robots=1000", "sim.steps=100000"]))
    s.step(s.MAX_ROWS // 1000 + 10)
    data = s.export_replay()
    load = per_call(lambda: replay.from_bytes(data), 2)
    print(f"largest history: {len(s.frames)} steps × 1000 robots → {len(data) / 2**20:.1f} MiB "
          f"(limit {replay.MAX_REPLAY_BYTES // 2**20} MiB), load {load:.0f} ms")


if __name__ == "__main__":
    main()
