"""Figs. 4-6 and 4-7: the seven Chapter 4 cases on the obstacle course (Section 4.4, p. 102).

Six omnidirectional robots start in the square on the left and seek the source on the
right through layers of circular obstacles (our course in the spirit of Fig. 4-1, which
gives no dimensions). Cases (Table 4.1, ω = 0.1): Original RPSO [4.2] and Adapted RPSO [4.5]
with constant coefficients at c3/(c1 + c2) = 2, 1, 0.5 (``-c3-high/-equal/-low``), and
Adapted RPSO with DVC (Algorithm 1). Two motion modes: ``kinematic`` (ideal particles, the
thesis' MATLAB runs) and ``physics`` (pymunk bodies with inertia and mecanum wheels, in the
role of the thesis' Gazebo runs). A robot that touches anything is disabled where it stops.

Fig. 4-6: median CoM fitness [4.17] over time. Fig. 4-7: collided vs operational robots at
the end of the median run (the run whose final CoM fitness is the median).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Sequence

import numpy as np

from . import chapter45 as ch
from . import verdict as vd
from .output import check, checks_table, info, information_table, new_figure, r3, save, write_csv
from .runner import run_jobs
from .verdict import Estimate

DEFAULT_RUNS = 100  # kinematic runs, as the thesis' 100 MATLAB repeats
DURATION = 600.0  # s; long enough for DVC's CoM to pass the 5th of 6 layers on our course
MODES = ("kinematic", "physics")
EARLY = 20.0  # s; "at first" in the claim that Original RPSO starts fastest
CASE_NAMES = tuple(c.name for c in ch.CH4_CASES)
CONSTANT = tuple(n for n in CASE_NAMES if n != "adapted-dvc")
ADAPTED_CONST = ("adapted-c3-low", "adapted-c3-equal", "adapted-c3-high")  # c3/(c1 + c2) rising
RPSO = ("rpso-c3-high", "rpso-c3-equal", "rpso-c3-low")


def physics_runs_for(runs: int) -> int:
    """Physics is several times slower per run than kinematic: half the runs."""
    return max(1, runs // 2)


def run(
    out_dir: Path,
    runs: int = DEFAULT_RUNS,
    workers: int = 1,
    progress: bool = True,
    *,
    modes: Sequence[str] = MODES,
    duration: float = DURATION,
    physics_runs: int | None = None,
) -> dict[str, Any]:
    """Simulate every case in every mode; write runs.csv, series.csv, fig4-6.png, fig4-7.png
    and README.md into ``out_dir``; return the summary fields (checks and statistics)."""
    modes = tuple(m for m in MODES if m in modes)
    if not modes:
        raise ValueError(f"modes: choose from {MODES}")
    n_runs = {"kinematic": runs, "physics": physics_runs or physics_runs_for(runs)}
    # physics chunks first: they are the slowest, so the process pool stays balanced
    jobs = [ch.fleet_job(c, m, n_runs[m], duration) for m in sorted(modes, key=lambda m: m != "physics")
            for c in ch.CH4_CASES]
    res = run_jobs(jobs, workers=workers, progress=progress, desc="fig4-6", simulate=ch.simulate_fleet,
                   merge=ch.merge)

    runs_rows, series_rows = [], []
    for m in modes:
        for name in CASE_NAMES:
            runs_rows += ch.runs_rows(name, m, res[(name, m)])
            series_rows += ch.series_rows(name, m, res[(name, m)])
    write_csv(out_dir / "runs.csv", ch.RUNS_COLUMNS, runs_rows)
    write_csv(out_dir / "series.csv", ch.SERIES_COLUMNS, series_rows)
    out = {m: {n: ch.outcome(res[(n, m)]) for n in CASE_NAMES} for m in modes}
    layer_x = res[(CASE_NAMES[0], modes[0])].layer_x
    _fig4_6(out_dir / "fig4-6.png", res, modes, layer_x, n_runs)
    _fig4_7(out_dir / "fig4-7.png", out, modes)

    checks, information = [], []
    for m in modes:
        c, i = _checks(m, res, out[m], layer_x)
        checks += c
        information += i
    if "kinematic" in modes and "physics" in modes:
        c, i = _physics_vs_kinematic(res, out, n_runs["physics"])
        checks += c
        information += i

    summary = {
        "checks": checks,
        "information": information,
        "contacts": ch.CONTACTS,
        "runs_per_mode": {m: n_runs[m] for m in modes},
        "duration_s": duration,
        "seed": res[(CASE_NAMES[0], modes[0])].seed,
        "seed_rule": "run i of every case and mode uses child i of SeedSequence(seed), seed = the preset seed; "
                     "run i therefore starts from the same robot positions in every case and mode",
        "median_run": "the run whose final CoM fitness is the median (lower middle one for an even number of runs)",
        "layer_x_m": [r3(v) for v in layer_x],
        "cases": {c.name: {m: ch.fleet_job(c, m, 1, duration).overrides for m in modes} for c in ch.CH4_CASES},
        "commands": {c.name: {m: c.command(ch.MODE_OVERRIDES[m]) + f" --steps {int(duration)}" for m in modes}
                     for c in ch.CH4_CASES},
        "nonomni_dvc": "the non-omnidirectional DVC controller is compared on this course in target fig5-5",
        "outcomes": {m: {n: o.as_dict() for n, o in out[m].items()} for m in modes},
    }
    return summary


def readme(summary: dict[str, Any]) -> str:
    """README.md from the summary alone (``shoal reproduce --report`` renders it again)."""
    return _readme(summary, summary["runs_per_mode"], summary["duration_s"])


# ---------------------------------------------------------------------- checks
def _fmt(d: dict[str, float], unit: str = "") -> str:
    return ", ".join(f"{k} {v:g}{unit}" for k, v in d.items())


def _checks(mode: str, res: dict, out: dict[str, ch.Outcome],
            layer_x: np.ndarray) -> tuple[list[dict[str, Any]], list[dict[str, Any]]]:
    """The checks of one mode, judged as the thesis does on the median run (Fig. 4-7 shows
    "the end of the median simulation"), and the stricter measures over every run."""
    tag = f"[{mode}]"
    sim = "Gazebo" if mode == "physics" else "MATLAB"
    fig = "4-6b/4-7b" if mode == "physics" else "4-6a/4-7a"
    dvc = out["adapted-dvc"]
    com = {n: r3(o.com_median) for n, o in out.items()}
    layers = {n: o.layers_median for n, o in out.items()}
    coll_med = {n: o.collided_median_run for n, o in out.items()}
    coll_mean = {n: r3(o.collided_mean) for n, o in out.items()}
    best_const = max(CONSTANT, key=lambda n: com[n])
    batch = {n: res[(n, mode)] for n in CASE_NAMES}
    com_e = {n: Estimate.median(b.com[-1]) for n, b in batch.items()}
    layers_e = {n: Estimate.median(b.layers[-1]) for n, b in batch.items()}
    runs = batch["adapted-dvc"].runs

    def at_median_runs(n: str) -> np.ndarray:
        """Collided robots at the end of every run that could be the median run of case n."""
        return batch[n].collided[-1][vd.median_runs(batch[n].com[-1])]

    def free(n: str) -> vd.Verdict:
        return vd.over_choices(lambda c: c == 0, at_median_runs(n), runs=runs)

    checks: list[dict[str, Any]] = []
    information: list[dict[str, Any]] = []
    checks.append(check(
        f"{tag} adapted-dvc: no robot collided at the end of the median run (Fig. {fig})",
        f"{sim}: Adapted RPSO + DVC is collision-free",
        f"{dvc.collided_median_run} collided ({dvc.stalled_median_run} stalled)", dvc.collided_median_run == 0,
        free("adapted-dvc")))
    information.append(info(
        f"{tag} adapted-dvc: no robot collided in any run (stricter than the thesis figure, which shows the "
        "median run)", "collision-free", f"{dvc.collided_total} robots collided, in {dvc.runs_with_collision} "
        f"of {dvc.runs} runs", dvc.collided_total == 0))
    checks.append(check(
        f"{tag} adapted-dvc has the highest median final CoM fitness of all cases",
        "DVC has the highest fitness" + (" (Gazebo final average 47 on the thesis course)" if mode == "physics"
                                         else ""),
        f"adapted-dvc {com['adapted-dvc']} m (mean {r3(np.mean(res[('adapted-dvc', mode)].com[-1]))} m); "
        f"best constant case {best_const} {com[best_const]} m",
        all(com["adapted-dvc"] > com[n] for n in CONSTANT),
        vd.all_of(vd.less(com_e[n], com_e["adapted-dvc"]) for n in CONSTANT)))
    checks.append(check(
        f"{tag} adapted-dvc: median CoM passes the 5th layer by the end (median layers passed >= 5; "
        f"layer 5 at x = {layer_x[4]:.2f} m)" if len(layer_x) >= 5 else f"{tag} adapted-dvc passes the 5th layer",
        "the DVC CoM passes the 5th obstacle layer before the end",
        f"{layers['adapted-dvc']:g} layers (median CoM {com['adapted-dvc']} m)", layers["adapted-dvc"] >= 5,
        vd.at_least(layers_e["adapted-dvc"], 5)))
    worst = max(CONSTANT, key=lambda n: layers[n])
    checks.append(check(
        f"{tag} every constant-coefficient case stays short of the 3rd layer (median layers passed <= 2)",
        "every other case stays short of the 3rd layer", _fmt({n: layers[n] for n in CONSTANT}),
        layers[worst] <= 2, vd.all_of(vd.at_most(layers_e[n], 2) for n in CONSTANT)))
    checks.append(check(
        f"{tag} adapted-dvc passes at least two more layers than any constant case (median layers passed)",
        "DVC passes the 5th layer, the others stay short of the 3rd",
        f"adapted-dvc {layers['adapted-dvc']:g} vs {worst} {layers[worst]:g}",
        layers["adapted-dvc"] >= layers[worst] + 2,
        vd.all_of(vd.at_most_of(layers_e[n].shifted(2), layers_e["adapted-dvc"]) for n in CONSTANT)))
    low, equal, high = (coll_med[n] for n in ADAPTED_CONST)
    checks.append(check(
        f"{tag} Adapted RPSO collisions fall as c3/(c1 + c2) rises, end of the median run: "
        "c3-low >= c3-equal >= c3-high", "collisions fall as c3/(c1 + c2) rises",
        f"{low} >= {equal} >= {high} collided (mean over runs {coll_mean['adapted-c3-low']}, "
        f"{coll_mean['adapted-c3-equal']}, {coll_mean['adapted-c3-high']})", low >= equal >= high,
        vd.over_choices(lambda a, b, c: a >= b >= c, *(at_median_runs(n) for n in ADAPTED_CONST), runs=runs)))
    ml, me, mh = (coll_mean[n] for n in ADAPTED_CONST)
    information.append(info(
        f"{tag} the same, mean collided robots over all runs strictly falling (ours, less noisy than one run)",
        "collisions fall as c3/(c1 + c2) rises", f"{ml} > {me} > {mh}", ml > me > mh))
    checks.append(check(
        f"{tag} adapted-c3-low: all 6 robots collided at the end of the median run",
        "all robots collide", f"{low} of 6 (mean over runs {ml})", low == 6,
        vd.over_choices(lambda c: c == 6, at_median_runs("adapted-c3-low"), runs=runs)))
    checks.append(check(
        f"{tag} adapted-c3-high: no robot collided at the end of the median run",
        "no collisions", f"{high} (mean over runs {mh}, runs with a collision: "
        f"{out['adapted-c3-high'].runs_with_collision} of {out['adapted-c3-high'].runs})", high == 0,
        free("adapted-c3-high")))
    op = {n: out[n].operational_median for n in RPSO}
    checks.append(check(
        f"{tag} Original RPSO survives poorly in every case: median operational robots at the end <= 3 of 6",
        "very low survival in every Original RPSO case",
        _fmt(op) + " operational (median over runs); median run: "
        + _fmt({n: out[n].operational_median_run for n in RPSO}), all(v <= 3 for v in op.values()),
        vd.all_of(vd.at_most(Estimate.median(batch[n].robots - batch[n].collided[-1]), 3) for n in RPSO)))
    free_cases = sorted(n for n in CASE_NAMES if coll_med[n] == 0)
    checks.append(check(
        f"{tag} the only collision-free cases (end of the median run) are adapted-c3-high and adapted-dvc",
        "only Adapted c3-high and Adapted + DVC are collision-free", ", ".join(free_cases) or "none",
        set(free_cases) == {"adapted-c3-high", "adapted-dvc"},
        vd.all_of(free(n) if n in ("adapted-c3-high", "adapted-dvc") else vd.negate(free(n)) for n in CASE_NAMES)))
    k = ch.at_time(res[("adapted-dvc", mode)], EARLY)
    early = {n: r3(np.median(res[(n, mode)].com[k])) for n in CASE_NAMES}
    best_rpso = max(RPSO, key=lambda n: early[n])
    best_adapted = max((n for n in CASE_NAMES if n not in RPSO), key=lambda n: early[n])
    checks.append(check(
        f"{tag} Original RPSO moves fastest at first: at t = {EARLY:g} s the best Original RPSO median CoM "
        "is above every Adapted case", "Original RPSO moves fastest at first (it runs at the speed limit)",
        f"{best_rpso} {early[best_rpso]} m vs {best_adapted} {early[best_adapted]} m",
        early[best_rpso] > early[best_adapted],
        vd.all_of(vd.less(Estimate.median(batch[n].com[k]), Estimate.median(batch[best_rpso].com[k]))
                  for n in CASE_NAMES if n not in RPSO)))
    lowest = min(CASE_NAMES, key=lambda n: com[n])
    checks.append(check(
        f"{tag} adapted-c3-high has the lowest median final CoM fitness of all cases",
        "Adapted RPSO with large c3 has the lowest fitness", f"lowest {lowest} {com[lowest]} m; "
        f"adapted-c3-high {com['adapted-c3-high']} m", lowest == "adapted-c3-high",
        vd.all_of(vd.less(com_e["adapted-c3-high"], com_e[n]) for n in CASE_NAMES if n != "adapted-c3-high")))
    return checks, information


def _physics_vs_kinematic(res: dict, out: dict, n_phys: int) -> tuple[list[dict[str, Any]], list[dict[str, Any]]]:
    """Physics against the kinematic runs with the same run indices (same start positions):
    the check on the median run (the thesis compares Figs. 4-7a and b), the mean over runs
    as information."""
    same = {n: res[(n, "kinematic")].head(n_phys) for n in CASE_NAMES}
    phys = {n: res[(n, "physics")] for n in CASE_NAMES}

    def at_median(b: ch.FleetBatch) -> np.ndarray:
        return b.collided[-1][vd.median_runs(b.com[-1])]

    kin = {n: r3(np.median(b.com[-1])) for n, b in same.items()}
    phy = {n: r3(out["physics"][n].com_median) for n in CASE_NAMES}
    adapted = [n for n in CASE_NAMES if n.startswith("adapted")]
    km = {n: ch.outcome(b).collided_median_run for n, b in same.items()}
    pm = {n: out["physics"][n].collided_median_run for n in CASE_NAMES}
    worst_m = max(CASE_NAMES, key=lambda n: abs(pm[n] - km[n]))
    kc = {n: r3(b.collided[-1].mean()) for n, b in same.items()}
    pc = {n: r3(out["physics"][n].collided_mean) for n in CASE_NAMES}
    diff = {n: r3(abs(pc[n] - kc[n])) for n in CASE_NAMES}
    worst = max(CASE_NAMES, key=lambda n: diff[n])
    checks = [
        check(
            f"physics vs kinematic (runs 0-{n_phys - 1} of both): the Adapted cases do no better with physics "
            "(median final CoM fitness, physics <= kinematic)",
            "Adapted cases do slightly worse in Gazebo (direction-dependent mecanum top speed)",
            "; ".join(f"{n} {phy[n]} vs {kin[n]} m" for n in adapted), all(phy[n] <= kin[n] for n in adapted),
            vd.all_of(vd.at_most_of(Estimate.median(phys[n].com[-1]), Estimate.median(same[n].com[-1]))
                      for n in adapted)),
        check(
            f"physics vs kinematic (runs 0-{n_phys - 1}): collision counts almost the same at the end of the median "
            "run (differ by <= 1 robot in every case; threshold ours)",
            "Gazebo collision counts almost the same as MATLAB (Figs. 4-7a, b)",
            f"largest difference {worst_m}: {pm[worst_m]} vs {km[worst_m]}; all: "
            + "; ".join(f"{n} {pm[n]} vs {km[n]}" for n in CASE_NAMES), abs(pm[worst_m] - km[worst_m]) <= 1,
            vd.all_of(vd.over_choices(lambda a, b: abs(a - b) <= 1, at_median(phys[n]), at_median(same[n]),
                                      runs=n_phys) for n in CASE_NAMES)),
    ]
    information = [info(
        f"physics vs kinematic (runs 0-{n_phys - 1}): mean collided robots per run differ by <= 1 in every case",
        "Gazebo collision counts almost the same as MATLAB",
        f"largest difference {worst}: {pc[worst]} vs {kc[worst]}; all: "
        + "; ".join(f"{n} {pc[n]} vs {kc[n]}" for n in CASE_NAMES), diff[worst] <= 1.0)]
    return checks, information


# ---------------------------------------------------------------------- figures
STYLE = {
    "rpso-c3-high": ("#7f0000", "--"), "rpso-c3-equal": ("#d7301f", "--"), "rpso-c3-low": ("#fc8d59", "--"),
    "adapted-c3-high": ("#08306b", "-"), "adapted-c3-equal": ("#2171b5", "-"), "adapted-c3-low": ("#6baed6", "-"),
    "adapted-dvc": ("#238b45", "-"),
}
MODE_TITLE = {"kinematic": "kinematic (MATLAB-like)", "physics": "physics, mecanum (Gazebo-like)"}


def _fig4_6(path: Path, res: dict, modes: Sequence[str], layer_x: np.ndarray, n_runs: dict[str, int]) -> None:
    fig, axes = new_figure(1, len(modes), 5.6, 4.4)
    top = max(float(np.median(res[(n, m)].com, axis=1).max()) for n in CASE_NAMES for m in modes)
    for ax, m in zip(axes, modes):
        for n in CASE_NAMES:
            b = res[(n, m)]
            colour, ls = STYLE[n]
            ax.plot(b.t, np.median(b.com, axis=1), color=colour, ls=ls, lw=2.2 if n == "adapted-dvc" else 1.4,
                    label=n)
        ax.set_title(f"{MODE_TITLE[m]}, median of {n_runs[m]} runs", fontsize=10)
        ax.set_xlim(0, b.t[-1])
        ax.set_ylim(0, max(top, float(layer_x[-1]) if len(layer_x) else 0.0) + 3.0)
        ax.set_xlabel("time (s)")
        ax.set_ylabel("CoM fitness: mean x of all robots (m)")
        ax.grid(alpha=0.25, lw=0.5)
        ch.draw_layers(ax, layer_x)
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside lower center", ncols=4, fontsize=8, frameon=False)
    fig.suptitle("Fig. 4-6 reproduction: CoM fitness over time (dotted: obstacle layers)", fontsize=11)
    save(fig, path)


def _fig4_7(path: Path, out: dict, modes: Sequence[str]) -> None:
    fig, axes = new_figure(1, len(modes), 5.6, 4.0)
    x = np.arange(len(CASE_NAMES))
    for ax, m in zip(axes, modes):
        coll = np.array([out[m][n].collided_median_run for n in CASE_NAMES])
        oper = np.array([out[m][n].operational_median_run for n in CASE_NAMES])
        ax.bar(x, coll, color="#d7301f", label="collided")
        ax.bar(x, oper, bottom=coll, color="#41ab5d", label="operational")
        for i, (c, o) in enumerate(zip(coll, oper)):
            if c:
                ax.text(i, c / 2, str(c), ha="center", va="center", fontsize=8, color="white")
            if o:
                ax.text(i, c + o / 2, str(o), ha="center", va="center", fontsize=8, color="white")
        ax.set_xticks(x, CASE_NAMES, rotation=35, ha="right", fontsize=8)
        ax.set_ylim(0, int((coll + oper).max()) + 0.5)
        ax.set_ylabel("robots at the end of the median run")
        ax.set_title(MODE_TITLE[m], fontsize=10)
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside lower center", ncols=2, fontsize=8, frameon=False)
    fig.suptitle("Fig. 4-7 reproduction: collided vs operational robots (median run)", fontsize=11)
    save(fig, path)


# ---------------------------------------------------------------------- README
def _readme(summary: dict[str, Any], n_runs: dict[str, int], duration: float) -> str:
    modes = ", ".join(f"{m}: {n} runs" for m, n in n_runs.items() if m in summary["runs_per_mode"])
    cmds = "\n".join(f"- `{n}`: `{summary['commands'][n][next(iter(summary['commands'][n]))]}`" for n in CASE_NAMES)
    return f"""# Figs. 4-6 and 4-7 reproduction: seven Chapter 4 cases on the obstacle course

Six omnidirectional robots (1 m diameter, 3 m/s, 3 m sensing in six equal sectors) seek the
source through six layers of circular obstacles that get denser toward the source (our
course in the spirit of Fig. 4-1; the thesis gives no dimensions). {duration:g} s of
simulated time with Δt = 1 s; {modes}. Every case is a shipped preset plus `--set`
overrides, e.g.:

{cmds}

(`physics` adds `--set robot.motion=physics --set robot.drive=mecanum`.)

## Files

- `runs.csv`: one row per (case, mode, run): `{','.join(ch.RUNS_COLUMNS)}`. Final CoM
  fitness (mean x of all robots, m), obstacle layers whose x is below the CoM, collided,
  operational and stalled robots at the end.
- `series.csv`: per case, mode and second: median, 5th and 95th percentile over runs of
  the CoM fitness, mean collided robots, median layers passed and mean stalled robots.
- Contacts: {summary['contacts']}
- `fig4-6.png`: median CoM fitness over time per case; dotted lines are the layers.
- `fig4-7.png`: collided (red) and operational (green) robots at the end of the median
  run (the run with the median final CoM fitness).
- `summary.json`: the checks below, per-case outcomes, seeds and the exact overrides.

## Checks

{checks_table(summary['checks'])}

{information_table(summary['information'])}

## Differences from the thesis

- The course is ours: layer positions {summary['layer_x_m']} m, the source beyond the last. The
  thesis' absolute numbers (e.g. the Gazebo DVC fitness of 47) belong to its own course.
- `physics` is pymunk with mecanum wheels, not Gazebo/ROS; it runs fewer repeats than the
  kinematic mode because it is slower (the thesis does not state its Gazebo repeat count).
- A check that fails is reported as failing; see the measured column.
"""
