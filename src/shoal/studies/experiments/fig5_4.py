"""Fig. 5-4: twenty non-omnidirectional robots in open space (Section 5.3, p. 123).

Differential-drive robots run the non-omni controller [5.13] with its DVC (Algorithm 2,
read through [5.14]–[5.16]) in an empty walled arena (preset ``open-nonomni``). The thesis
reports that they roam for ever without settling, even after reaching the source, and that
no two robots collide; its figure draws each robot's path over the last 15 s.

Two cases: ``nonomni-dvc`` with the DVC inertia guard (ours, the preset's default) and
``nonomni-dvc-noguard``, Algorithm 2 exactly as written. DVC bounds the forward push c5 by
the frontal clearance, but not the carried-over ω·v (docs/readings.md, "The DVC guard"), so without the
guard a robot that has just turned toward a close body can still reach it in one step.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from shoal.presets.builders.world import world_for

from . import chapter45 as ch
from . import verdict as vd
from .output import check, checks_table, info, information_table, new_figure, num, r3, save, write_csv
from .runner import run_jobs
from .verdict import Estimate

DEFAULT_RUNS = 20
DURATION = 300.0  # s
PRESET = "open-nonomni"
CASES = (
    ch.Case("nonomni-dvc", PRESET),  # guard on (the preset's choice)
    ch.Case("nonomni-dvc-noguard", PRESET, ("controller.guard=false",)),
)
SPEED_WINDOW = 100.0  # s: "they keep moving" is judged on the last 100 s
TRAIL = 15.0  # s: trails of the thesis figure, and the "never settles" window
MIN_SPEED = 0.5  # m/s: median speed over the last 100 s must be at least this (top speed 3 m/s)
MIN_PATH = 3.0  # m: every robot covers at least this much in the last 15 s (0.2 m/s on average)
STALL_GAP = 1e-3  # m: a robot-robot contact from closer than this for two ticks follows a stall
RUNS_COLUMNS = ("case", "run", "seed", "collided", "robot_robot_collided", "wall_collided", "operational",
                "median_speed_last_100s", "min_path_last_15s", "stalled")


def _segment_gap(p: np.ndarray, walls: np.ndarray) -> np.ndarray:
    """Distance from points p (M, 2) to the nearest wall segment (W, 2, 2), (M,)."""
    if walls.size == 0:
        return np.full(len(p), np.inf)
    a, b = walls[:, 0], walls[:, 1]
    ab = b - a
    rel = p[:, None, :] - a[None]
    t = np.clip(np.einsum("mwd,wd->mw", rel, ab) / np.maximum(np.einsum("wd,wd->w", ab, ab), 1e-300), 0.0, 1.0)
    return np.linalg.norm(rel - t[..., None] * ab[None], axis=-1).min(axis=1)


def classify_collisions(b: ch.FleetBatch, world: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per run: robots disabled by touching another robot, by touching a wall or an
    obstacle, and robot-robot ones that follow a stall (the two were already closer than
    ``STALL_GAP`` during the two ticks before; a robot that is run into is not "stalled"). At the
    step a robot is disabled, whichever kind of body is closer to its surface is the one it touched."""
    assert b.x is not None and b.status is not None
    r = b.robot_radius
    robot_hits = np.zeros(b.runs, dtype=np.int64)
    other_hits = np.zeros(b.runs, dtype=np.int64)
    stalled = np.zeros(b.runs, dtype=np.int64)
    new = (b.status[1:] != 0) & (b.status[:-1] == 0)  # (K, R, N) disabled during tick k
    for k, run, i in zip(*np.nonzero(new)):
        x = b.x[k + 1, run]
        d = np.linalg.norm(x - x[i], axis=1) - 2 * r
        d[i] = np.inf
        robot_gap = d.min()
        obstacle_gap = _segment_gap(x[i : i + 1], np.asarray(world.walls))[0] - world.wall_radius - r
        if len(world.circles):
            c = np.asarray(world.circles)
            obstacle_gap = min(obstacle_gap, float((np.hypot(*(c[:, :2] - x[i]).T) - c[:, 2]).min() - r))
        if robot_gap <= obstacle_gap:
            robot_hits[run] += 1
            j = int(np.argmin(d))
            before = [np.linalg.norm(b.x[q, run, j] - b.x[q, run, i]) - 2 * r for q in (k, k - 1) if q >= 0]
            stalled[run] += len(before) == 2 and max(before) < STALL_GAP
        else:
            other_hits[run] += 1
    return robot_hits, other_hits, stalled


def motion_stats(b: ch.FleetBatch) -> tuple[np.ndarray, np.ndarray]:
    """Per run: median speed over the operational robots and the ticks of the last
    ``SPEED_WINDOW`` s, and the shortest path an operational robot covered in the last
    ``TRAIL`` s (straight steps between ticks). Collided robots are disabled, not settled:
    they are left out (nan when none is operational)."""
    assert b.x is not None and b.status is not None
    step = np.linalg.norm(np.diff(b.x, axis=0), axis=-1)  # (K, R, N) distance per tick
    n_speed = min(len(step), int(round(SPEED_WINDOW / b.dt)))
    n_trail = min(len(step), int(round(TRAIL / b.dt)))
    alive = b.status[-1] == 0  # (R, N) operational at the end, hence during the whole window
    speed = np.full(b.runs, np.nan)
    path = np.full(b.runs, np.nan)
    for r in range(b.runs):
        if alive[r].any():
            speed[r] = np.median(step[-n_speed:, r, alive[r]]) / b.dt
            path[r] = step[-n_trail:, r, alive[r]].sum(axis=0).min()
    return speed, path


def run(
    out_dir: Path, runs: int = DEFAULT_RUNS, workers: int = 1, progress: bool = True, *,
    duration: float = DURATION,
) -> dict[str, Any]:
    jobs = [ch.fleet_job(c, "", runs, duration, positions=True) for c in CASES]
    res = run_jobs(jobs, workers=workers, progress=progress, desc="fig5-4", simulate=ch.simulate_fleet,
                   merge=ch.merge)
    world_model = CASES[0].scenario().world
    assert world_model is not None  # (a fleet's case)
    world = world_for(world_model)
    rows, stats = [], {}
    for c in CASES:
        b = res[(c.name, "")]
        rr, other, stalled = classify_collisions(b, world)
        speed, path = motion_stats(b)
        coll = b.collided[-1]
        stats[c.name] = {"robot_robot": rr, "other": other, "after_stall": stalled, "speed": speed, "path": path,
                         "collided": coll, "stalled": b.stalled[-1]}
        rows += [[c.name, str(i), str(b.seed), str(int(coll[j])), str(int(rr[j])), str(int(other[j])),
                  str(int(b.robots - coll[j])), num(speed[j]), num(path[j]), str(int(b.stalled[-1, j]))]
                 for j, i in enumerate(b.run_index)]
    write_csv(out_dir / "runs.csv", RUNS_COLUMNS, rows)
    _figure(out_dir / "fig5-4.png", res, world, duration)

    checks, information = [], []
    for c in CASES:
        s, b = stats[c.name], res[(c.name, "")]
        label = "with the DVC guard (ours)" if c.name == "nonomni-dvc" else "Algorithm 2 as written (guard off)"
        rr = s["robot_robot"]
        checks.append(check(
            f"{c.name}: no robot-robot collision in a typical run (median over runs of the robots disabled by "
            f"touching another), {label}", "no robot-robot collisions (the example run of Fig. 5-4)",
            f"median {np.median(rr):g} (mean {r3(rr.mean())}); stalled robots at the end of "
            f"{s['stalled'][s['stalled'] > 0].size} of {b.runs} runs (median {np.median(s['stalled']):g})",
            np.median(rr) == 0,
            vd.at_most(Estimate.median(rr), 0)))
        information.append(info(
            f"{c.name}: no robot-robot collision in any run, {label}", "no robot-robot collisions",
            f"{int(rr.sum())} robots disabled by touching another robot, in {int((rr > 0).sum())} of {b.runs} runs "
            f"({int(s['after_stall'].sum())} of them after a stall: closer than {STALL_GAP * 1e3:g} mm during the "
            f"two ticks before); {int(s['other'].sum())} by touching a wall", rr.sum() == 0))
        checks.append(check(
            f"{c.name}: the robots keep moving in a typical run: median over runs of the median speed of the "
            f"operational robots over the last {SPEED_WINDOW:g} s >= {MIN_SPEED:g} m/s (threshold ours)",
            "the robots roam constantly", f"median over runs {r3(np.nanmedian(s['speed']))} m/s",
            bool(np.nanmedian(s["speed"]) >= MIN_SPEED), vd.at_least(Estimate.median(s["speed"]), MIN_SPEED)))
        information.append(info(
            f"{c.name}: the same in every run", "the robots roam constantly",
            f"lowest run median {r3(np.nanmin(s['speed']))} m/s", bool(np.all(s["speed"] >= MIN_SPEED))))
        checks.append(check(
            f"{c.name}: none settles in a typical run: median over runs of the shortest path an operational robot "
            f"covers in the last {TRAIL:g} s >= {MIN_PATH:g} m (threshold ours)",
            "they never settle, even after reaching the source",
            f"median over runs of the shortest {r3(np.nanmedian(s['path']))} m",
            bool(np.nanmedian(s["path"]) >= MIN_PATH), vd.at_least(Estimate.median(s["path"]), MIN_PATH)))
        information.append(info(
            f"{c.name}: the same in every run", "they never settle, even after reaching the source",
            f"shortest path {r3(np.nanmin(s['path']))} m", bool(np.all(s["path"] >= MIN_PATH))))
    summary = {
        "checks": checks,
        "information": information,
        "contacts": ch.CONTACTS,
        "duration_s": duration,
        "robots": res[(CASES[0].name, "")].robots,
        "seed": res[(CASES[0].name, "")].seed,
        "seed_rule": "run i of both cases uses child i of SeedSequence(seed), seed = the preset seed",
        "cases": {c.name: c.command() + f" --steps {int(duration)}" for c in CASES},
        "why_guard": "DVC sets the forward push c5 = beta*alpha*sf_1/dt from the nearest frontal gap, but the "
                     "carried-over omega*v is not bounded by it (docs/readings.md, 'The DVC guard'): a robot that "
                     "was fast and "
                     "then turns toward a close body, or sees one appear in front, can close more than the gap in "
                     "one step. The guard (ours) caps v at alpha*sf_1/dt after the update, which makes the "
                     "one-step clearance toward the frontal bodies exact in exact arithmetic; the thesis reports no "
                     "collisions without it.",
        "collision_classes": "a disabled robot is counted as robot-robot when, at the tick it was disabled, "
                             "another robot's surface is closer than any wall. Both robots of a contact are "
                             "disabled at once (both have touched something)",
        "stall": f"with the guard, two robots that meet nose to nose each close at most alpha = 0.9 of the gap "
                 f"per tick, so the gap shrinks geometrically and both stop (v -> 0) while still turning. The gap "
                 f"soon sits far below the contact tolerance, so a touch there stops a robot without disabling it; "
                 f"such a robot counts as stalled (`stalled` in runs.csv). A collision from a gap below "
                 f"{STALL_GAP * 1e3:g} mm during the two ticks before is counted as after a stall.",
    }
    return summary


def readme(summary: dict[str, Any]) -> str:
    """README.md from the summary alone (``shoal reproduce --report`` renders it again)."""
    return _readme(summary, summary["runs"])


def _figure(path: Path, res: dict, world: Any, duration: float) -> None:
    import matplotlib

    fig, axes = new_figure(1, len(CASES), 5.0, 5.2)
    n_trail = int(round(TRAIL / res[(CASES[0].name, "")].dt))
    for ax, c in zip(axes, CASES):
        b = res[(c.name, "")]
        x, status = b.x[-n_trail - 1 :, 0], b.status[-1, 0]  # run 0, last 15 s
        colours = matplotlib.colormaps["tab20"](np.linspace(0, 1, b.robots, endpoint=False))
        for wall in np.asarray(world.walls):
            ax.plot(wall[:, 0], wall[:, 1], color="0.3", lw=1.5)
        for i in range(b.robots):
            ax.plot(x[:, i, 0], x[:, i, 1], color=colours[i], lw=1.2)
            end = x[-1, i]
            ax.add_patch(matplotlib.patches.Circle(end, b.robot_radius, fc=colours[i], ec="k", lw=0.5,
                                                   alpha=0.9))
            if status[i]:
                ax.plot(*end, marker="x", color="red", ms=9, mew=2)
        ax.plot(*world.source, marker="*", color="red", ms=12, mec="k", label="source")
        ax.set_aspect("equal")
        lo, hi = x.reshape(-1, 2).min(axis=0), x.reshape(-1, 2).max(axis=0)
        centre, half = (lo + hi) / 2, max(hi - lo) / 2 + 2.0  # zoom on the trails (square view)
        xmin, ymin, xmax, ymax = world.bounds
        ax.set_xlim(max(xmin - 0.5, centre[0] - half), min(xmax + 0.5, centre[0] + half))
        ax.set_ylim(max(ymin - 0.5, centre[1] - half), min(ymax + 0.5, centre[1] + half))
        title = "with the DVC guard (ours)" if c.name == "nonomni-dvc" else "Algorithm 2 as written (no guard)"
        ax.set_title(title, fontsize=10)
        ax.grid(alpha=0.2, lw=0.5)
        ax.set_xlabel("x (m)")
        ax.set_ylabel("y (m)")
    b = res[(CASES[0].name, "")]
    fig.suptitle(f"Fig. 5-4 reproduction: {b.robots} non-omni robots, run 0, paths over t = {duration - TRAIL:g}-"
                 f"{duration:g} s (star: source, red x: collided)", fontsize=11)
    save(fig, path)


def _readme(summary: dict[str, Any], runs: int) -> str:
    cmds = "\n".join(f"- `{k}`: `{v}`" for k, v in summary["cases"].items())
    return f"""# Fig. 5-4 reproduction: twenty non-omni robots in open space

{summary['robots']} differential-drive robots with the non-omnidirectional DVC controller in
an empty square walled arena (preset `open-nonomni`), {summary['duration_s']:g} s, {runs} seeded runs per case:

{cmds}

## Files

- `runs.csv`: one row per (case, run): `{','.join(RUNS_COLUMNS)}`. Collided robots are
  split into robot-robot and wall contacts; the median speed is over the operational robots
  and the ticks of the last {SPEED_WINDOW:g} s; the shortest path is the least distance an
  operational robot covered in the last {TRAIL:g} s (straight steps between ticks).
- Collision classes: {summary['collision_classes']}.
- Contacts: {summary['contacts']} `stalled` counts the stalled robots at the end of a run.
- `fig5-4.png`: run 0 of each case, every robot's path over the last {TRAIL:g} s and its
  final position.
- `summary.json`: the checks below.

## Checks

{checks_table(summary['checks'])}

{information_table(summary['information'])}

## Why a guard

{summary['why_guard']}

## Stalls with the guard

{summary['stall'][0].upper() + summary['stall'][1:]}
"""
