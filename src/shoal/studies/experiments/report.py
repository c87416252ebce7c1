"""``shoal reproduce --all``: every target into one folder, and ``REPRODUCTION.md`` beside them.

Each target writes its own folder (``summary.json`` with the checks, ``README.md``, CSVs and
PNGs). The report is assembled from those folders only, so it can be rebuilt at any time
(``shoal reproduce --report DIR``), e.g. after rerunning one target or after running the
targets on a cluster. A target that fails is named in the report with its error; the others
still run.
"""

from __future__ import annotations

import json
import re
import time
import traceback
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Iterable, Sequence

from shoal import __version__
from shoal.engine.core.atomic import OutputDirError, atomic_write_text

from .output import cell, information_table
from .registry import TARGETS, reproduce

REPORT = "REPRODUCTION.md"
TITLE = "# Shoal reproduction report"  # the first line of every report (one that lacks it is not ours)
FAILED = "failed.json"  # written into a target's folder slot when the target raised

# Thesis figure/table each target stands for, in the order of the theses.
SOURCES: dict[str, str] = {
    "fig3-4": "Rossides, Fig. 3-4", "fig3-5": "Rossides, Fig. 3-5", "fig4-6": "Rossides, Figs. 4-6 and 4-7",
    "fig5-4": "Rossides, Fig. 5-4", "fig5-5": "Rossides, Fig. 5-5", "fig7-2": "Rossides, Fig. 7-2",
    "fig7-3": "Rossides, Fig. 7-3",
    "fig7-4": "Rossides, Fig. 7-4", "fig7-5": "Rossides, Fig. 7-5", "fig8-2": "Rossides, Fig. 8-2",
    "fig8-4": "Rossides, Fig. 8-4", "fig8-5": "Rossides, Fig. 8-5", "slo-errors": "Mai, Figs. 4.1-4.3",
    "slo-mitigation": "Mai, Figs. 4.4-4.6", "slo-neighbourhood": "Mai, Figs. 4.7-4.8",
    "slo-weight": "Mai, Figs. 4.9-4.10", "slo-pso": "Mai, Table 4.4 and Figs. 4.11-4.13",
}


# Why Shoal and the thesis differ, per target: what the thesis leaves open and what our own
# investigations found. Rendered under "Where and why they differ", after the target's own notes.
WHY: dict[str, str] = {
    "fig3-4": "The peaks at β = 0.2 (cases b, c) sit above the thesis' 12.4 and 13.4 m/s under every reading of the "
              "attractors we tried (docs/readings.md, Attractors in Figure 3-4); the qualitative claims (never "
              "above U, a lower peak for smaller β) hold under all of them.",
    "fig3-5": "The thesis does not give the swarm size or seeds of Fig. 3-5; the response times are measured on "
              "100 seeded runs. Right after U drops, ω·u still carries the old speed, so the speed bound is "
              "checked against the worst-case envelope ω·B + ĉ√d rather than the new U.",
    "fig4-6": "The thesis gives no dimensions for its obstacle course, so ours is a seeded course in its spirit; "
              "absolute CoM values belong to each course. Collision claims are judged as the thesis shows them, at "
              "the end of the median run (Fig. 4-7), with a collision counted only for an overlap deeper than 1 mm "
              "(docs/readings.md). Over every run, as information: no kinematic Adapted RPSO + DVC robot collides "
              "in 30 runs; with physics two robots do, in 1 run of 15. The one collision check that fails on the "
              "thesis' metric compares single median runs of small counts (rpso-c3-high: 5 collided with physics, 3 "
              "kinematic); the means over runs differ by less than 0.5 robot.",
    "fig5-4": "DVC bounds the newly added velocity but not the carried-over ω·u, so without our guard robots do "
              "collide (Algorithm 2 as written: 17 robots per run, median). With the guard, robots that meet nose "
              "to nose close the gap geometrically and stop; the 11 'collisions' we used to count in 20 runs were "
              "such touches at gaps of ~1e-16 m and are now stalls (a touch shallower than 1 mm stops a robot "
              "without disabling it): no robot-robot collision in any run. The robots still do not roam as the "
              "thesis describes: a typical run's median speed is 0.24 m/s against our 0.5 m/s threshold, and robots "
              "stand still for seconds at a time.",
    "fig5-5": "With our guard the non-omni controller is ahead of omni DVC, as the thesis reports; as written (no "
              "guard) it collides on the course (DVC does not bound the carried-over ω·u), so its curves fall "
              "behind. With the 1 mm contact tolerance neither DVC controller loses a robot in any of 30 runs.",
    "fig7-2": "Chapter 7 states neither the split of ĉ into c1 and c2 nor the sample rate. Both splits run as "
              "cases: with 1:3 (the preset's) A-PSO and X-PSO converge at 10 dB near the thesis' 4500 and 3400 "
              "steps; with 1:1 they gather into a cluster whose intensity gradient is buried in the noise and never "
              "converge (docs/readings.md). B-PSO and XB-PSO used to converge 2.5-3 times faster than the thesis; "
              "the thesis' Algorithm 5 reads the correlation peak at a whole sample, and with that reading at fs = "
              "4 kHz the bearings take a few values whatever the SNR, so the swarm moves at a nearly constant "
              "0.35-0.5 m/s (thesis 0.22 m/s) and every median time is within ×2 of the thesis. The one check that "
              "fails asks XB-PSO to be 2.5-6 times faster than A-PSO: it is 7.3 times.",
    "fig7-3": "The routes come from the fig7-2 runs, whose sources lie on random bearings; we turn each route so "
              "that its source is on +x. B-PSO and XB-PSO run straighter, as the thesis says (progress over path "
              "length about 0.9 against 0.35 for A-PSO and X-PSO), but the per-component sgn law [3.12] moves a "
              "robot diagonally until one coordinate matches its attractor and then along the other axis, so with "
              "random bearings their routes dog-leg on either side of the source line and no 20 m cell is passed by "
              "more than half of them; A-PSO and X-PSO, pulled by the intensity gradient from positions near the "
              "swarm, creep along the line itself with small zig-zags. The thesis' picture of B/XB-PSO in a narrow "
              "band and A/X-PSO spread out is therefore not reproduced; it would need a source on a fixed bearing, "
              "which the thesis does not state.",
    "fig7-4": "With the Chapter 7 receiver (the sample lag at 4 kHz, docs/readings.md) the bearing resolution grows "
              "with the hydrophone separation: at D = λ_c/2 the lag spans ±2 samples, at 10 λ_c ±40. At low Q B-PSO "
              "and XB-PSO therefore converge faster as D grows (926 to 469 steps for B-PSO), against the thesis' "
              "'no effect', and the slowdown of B-PSO at D = λ for Q = 50 disappears in the noise of 6 runs per "
              "point; with a refined lag at 48 kHz every one of these checks held (the earlier 20-run report, c1:c2 "
              "= 1:1). A-PSO and X-PSO now converge (c1:c2 = 1:3), and neither Q nor D affects them, as the thesis "
              "says.",
    "fig7-5": "With c1:c2 = 1:3 A-PSO and X-PSO converge at every U, but their times fall much faster than 1/U (24 "
              "and 19 times from 2 to 12 m/s, where 1/U predicts 6): at 2 m/s the cluster creeps along a gradient "
              "buried in the noise, faster robots overshoot and sample more of the field. With the sample lag "
              "X-PSO's correlation peak is noisier, and it is not faster than A-PSO above 2 m/s. B-PSO at Q = 50 "
              "converges at every U, against the thesis' 'unable to converge however much U increases'; XB-PSO "
              "keeps improving with U, as reported. 6 runs per point.",
    "fig8-2": "Every check holds.",
    "fig8-4": "Every check holds. Collisions are not enforced in the escort runs (robots may overlap); "
              "the occupancy maps count the fraction of robot-steps per 5 m cell over "
              "steps 1000-2000 of every run.",
    "fig8-5": "Every check holds; collisions are not enforced in the escort runs, as in fig8-4.",
    "slo-errors": "Every ordering the thesis states holds except one threshold of ours: 30 % odometry failures "
                  "leave a median relative error near 0.18, above the 0.1 we fixed before the runs for 'acceptably "
                  "small'. A failed odometry reading is zero, so the triangle of that step is wrong and CSS carries "
                  "the error into its prediction. Carrying estimates of non-neighbours by dead reckoning "
                  "(docs/readings.md) lowers most errors by a few per cent without changing an ordering.",
    "slo-mitigation": "The δ grid of the thesis is not given; we sweep 0, 0.03 and 0.1. With estimates of "
                      "non-neighbours carried by dead reckoning (docs/readings.md) an error-free random topology "
                      "localises exactly (4e-11 after 100 generations), so any mitigation that withholds the exact "
                      "geometric candidates makes it worse by orders of magnitude (4e-4 at 0.03, 33 at 0.1), as "
                      "Fig. 4.6 shows; with the frozen estimates of the old default the error-free run stayed near "
                      "1.8 and 0.03 cost less than a factor of two.",
    "slo-neighbourhood": "The thesis credits an entry rule for new neighbours that it does not describe. None of "
                         "the three readings we run (dead reckoning, our default; frozen; a random mirror "
                         "candidate) gives p = 0.3 and 0.5 the early lead; the random start of every estimate "
                         "dominates the first generations, longest for the rarest links. With dead reckoning RTS "
                         "beats CSS at every p, as the thesis reports, but its error still falls as p rises (16.4, "
                         "12.8, 10.6).",
    "slo-weight": "Fig. 4.9 is not discussed in the thesis; we read its neighbourhood as knn 5.",
    "slo-pso": "The thesis does not give the swarm size, start area, quality thresholds or the number of runs "
               "behind Table 4.4 (medians such as 117.5 cannot come from 31 whole numbers); we use 20 particles, a "
               "[-50, 50]² start area, our own quality thresholds and 31 runs per case, as in the thesis' other "
               "experiments. Error-free Akcan and RTS do not get stuck on Ackley in our runs: both recover from "
               "wrong mirror estimates once the ranges are exact. Line (x0²) needs no "
               "contraction along x1, so the swarm stays spread out, localisation stays good and even runs with "
               "errors reach very small values, unlike the thesis' Low/High columns. With High errors the relative "
               "error rises after generation 4, but by less than the factor of two our check asks for.",
}


@dataclass
class Outcome:
    """What one target left in its folder."""

    name: str
    summary: dict[str, Any] | None = None
    readme: str = ""
    error: str | None = None
    figures: list[str] = field(default_factory=list)

    @property
    def checks(self) -> list[dict[str, Any]]:
        return list((self.summary or {}).get("checks", []))

    @property
    def passed(self) -> int:
        return sum(bool(c.get("pass")) for c in self.checks)


def run_all(
    out_dir: Path,
    *,
    runs: int | None = None,
    workers: int = 1,
    progress: bool = True,
    targets: Sequence[str] | None = None,
    resume: bool = False,
    quick: bool = False,
    log: Callable[[str], None] = print,
    **options: Any,
) -> Path:
    """Reproduce ``targets`` (default: all) into ``out_dir/<target>`` and write the report.

    ``runs`` overrides every target's default run count (``None`` keeps each default);
    ``quick`` runs every target at its classroom size (``Target.quick``). With ``resume``, a
    target folder that already holds a ``summary.json`` of the same run count and size is
    kept. ``options`` go to :func:`reproduce` (e.g. a scheduler)."""
    out_dir = Path(out_dir)
    names = list(TARGETS) if targets is None else list(targets)
    unknown = [n for n in names if n not in TARGETS]
    if unknown:
        raise KeyError(f"unknown target(s) {', '.join(unknown)}; known: {', '.join(TARGETS)}")
    if (out_dir / REPORT).exists() and not _is_report(out_dir / REPORT):  # refused now, not after every target
        raise OutputDirError(f"{out_dir / REPORT}: exists and is not a report Shoal wrote; it is left as it is "
                             "(move it away or choose another --out)")
    out_dir.mkdir(parents=True, exist_ok=True)
    for i, name in enumerate(names, 1):
        folder = out_dir / name
        spec = TARGETS[name]
        wanted = (spec.quick_runs if quick else spec.default_runs) if runs is None else runs
        if resume and _finished(folder, wanted, quick):
            log(f"[{i}/{len(names)}] {name}: kept (finished earlier with {wanted} runs)")
            continue
        log(f"[{i}/{len(names)}] {name} ({wanted} runs{', quick' if quick else ''})")
        (out_dir / f"{name}.{FAILED}").unlink(missing_ok=True)
        start = time.perf_counter()
        try:
            summary = reproduce(name, folder, runs=wanted, workers=workers, progress=progress, quick=quick,
                                **options)
        except KeyboardInterrupt:
            raise
        except Exception as e:  # one broken target must not cost the others
            atomic_write_text(out_dir / f"{name}.{FAILED}", json.dumps(
                {"target": name, "error": f"{type(e).__name__}: {e}", "traceback": traceback.format_exc()}, indent=2))
            log(f"  {name} failed: {type(e).__name__}: {e}")
            continue
        n_pass = sum(bool(c["pass"]) for c in summary["checks"])
        log(f"  {n_pass}/{len(summary['checks'])} checks pass ({time.perf_counter() - start:.0f} s, "
            f"{summary.get('cpu_s', 0):.0f} CPU s)")
    return write_report(out_dir, names)


def _finished(folder: Path, runs: int, quick: bool = False) -> bool:
    try:
        summary = json.loads((folder / "summary.json").read_text(encoding="utf-8"))
        return int(summary["runs"]) == runs and bool(summary.get("quick", False)) == quick
    except (OSError, ValueError, KeyError, TypeError):
        return False


def collect(out_dir: Path, names: Iterable[str] | None = None) -> list[Outcome]:
    """The outcome of every target that left a folder (or a failure record) in ``out_dir``."""
    out_dir = Path(out_dir)
    outcomes = []
    for name in (list(TARGETS) if names is None else names):
        folder, failed = out_dir / name, out_dir / f"{name}.{FAILED}"
        if failed.is_file():
            outcomes.append(Outcome(name, error=json.loads(failed.read_text(encoding="utf-8"))["error"]))
        elif (folder / "summary.json").is_file():
            readme = folder / "README.md"
            outcomes.append(Outcome(
                name, summary=json.loads((folder / "summary.json").read_text(encoding="utf-8")),
                readme=readme.read_text(encoding="utf-8") if readme.is_file() else "",
                figures=sorted(p.name for p in folder.glob("*.png")),
            ))
    return outcomes


def _sections(readme: str) -> tuple[str, dict[str, str]]:
    """Split a target README into its lead text and its ``## `` sections."""
    parts = re.split(r"^## +(.+)$", readme, flags=re.M)
    lead = re.sub(r"^# .*\n", "", parts[0], count=1).strip()
    return lead, {parts[i].strip(): parts[i + 1].strip() for i in range(1, len(parts) - 1, 2)}


def _demote(text: str) -> str:
    return re.sub(r"^(#+) ", lambda m: "#" * (len(m.group(1)) + 2) + " ", text, flags=re.M)


def render(outcomes: Sequence[Outcome], *, image_prefix: str = "") -> str:
    """The text of ``REPRODUCTION.md``; figures are linked as ``<image_prefix><target>/<png>``."""
    lines = [
        TITLE, "",
        f"Every thesis figure and table that Shoal reproduces, regenerated by `shoal reproduce --all` "
        f"(Shoal {__version__}). For each target: the thesis' figure or table it stands for, Shoal's own "
        "figures, each check with the thesis' claim beside Shoal's measured value, and where and why the two "
        "differ. A check that does not hold is reported as not passed, never hidden. Each target folder also "
        "holds `runs.csv` and `summary.json`; a fresh run also writes the series behind the figures. Times are "
        "wall-clock seconds with the workers given in the table; CPU seconds add up the process and its "
        "local workers (they depend far less on what else the machine is doing).", "",
    ]
    quick = [o.name for o in outcomes if (o.summary or {}).get("quick")]
    if quick:
        lines += [f"**Quick (classroom) size:** {'every target' if len(quick) == len(outcomes) else ', '.join(quick)} "
                  "ran with `--quick`: few runs per case (marked \"quick\" below), the same checks. The numbers are "
                  "noisier than at full size; `shoal reproduce --all` regenerates the full report.", ""]
    lines += ["| target | thesis | runs | checks passed | time (s) | CPU (s) | workers |",
              "|---|---|---:|---:|---:|---:|---:|"]
    for o in outcomes:
        if o.error is not None:
            lines.append(f"| [{o.name}](#{o.name}) | {SOURCES.get(o.name, '')} | | failed to run | | | |")
        else:
            s = o.summary or {}
            runs = f"{s.get('runs', '')}{' (quick)' if s.get('quick') else ''}"
            lines.append(f"| [{o.name}](#{o.name}) | {SOURCES.get(o.name, '')} | {runs} | "
                         f"{o.passed}/{len(o.checks)} | {s.get('elapsed_s', '')} | {s.get('cpu_s', '')} | "
                         f"{s.get('workers', '')} |")
    ran = [o.summary or {} for o in outcomes if o.error is None]
    if ran:
        wall = sum(s.get("elapsed_s", 0.0) for s in ran)
        timed = [s["cpu_s"] for s in ran if "cpu_s" in s]  # (reports older than the CPU column have none)
        cpu = f"{sum(timed):.0f}{'' if len(timed) == len(ran) else ' (of the targets timed)'}" if timed else ""
        lines.append(f"| all | | | | {wall:.0f} | {cpu} | |")
    total = sum(len(o.checks) for o in outcomes)
    lines += ["", f"In all: {sum(o.passed for o in outcomes)} of {total} checks pass over "
              f"{sum(o.error is None for o in outcomes)} targets.", ""]
    for o in outcomes:
        lines += [f'<a id="{o.name}"></a>', "", f"## {o.name}: {SOURCES.get(o.name, '')}", ""]
        if o.error is not None:
            lines += [f"This target failed to run: `{cell(o.error)}`. Rerun it alone with "
                      f"`shoal reproduce {o.name}` to see the whole error.", ""]
            continue
        s = o.summary or {}
        lead, sections = _sections(o.readme)
        lines += [TARGETS[o.name].description if o.name in TARGETS else "", ""]
        flag = " --quick" if s.get("quick") else ""
        lines += [f"Regenerate: `shoal reproduce {o.name}{flag} --runs {s.get('runs')}` "
                  f"({s.get('elapsed_s')} s with {s.get('workers', 1)} worker(s){', quick size' if flag else ''}).", ""]
        if lead:
            lines += ["### Setup", "", _demote(lead), ""]
        if o.figures:
            lines += ["### Shoal's figures", ""]
            lines += [f"![{o.name} {png}]({image_prefix}{o.name}/{png})" for png in o.figures]
            lines.append("")
        lines += ["### Thesis beside Shoal", "", "| check | thesis | Shoal | holds |", "|---|---|---|---|"]
        lines += [f"| {cell(c['name'])} | {cell(c.get('thesis', ''))} | {cell(c.get('measured', ''))} | "
                  f"{'yes' if c.get('pass') else '**no**'} |" for c in o.checks]
        lines.append("")
        if s.get("information"):
            lines += [information_table(s["information"]), ""]
        discussion = {k: v for k, v in sections.items() if k not in ("Files", "Checks")}
        failed = [c for c in o.checks if not c.get("pass")]
        lines += ["### Where and why they differ", ""]
        if failed:
            lines += [f"{len(failed)} of {len(o.checks)} checks do not hold: "
                      + "; ".join(f"*{cell(c['name'])}* (thesis: {cell(c.get('thesis', ''))}; "
                                  f"Shoal: {cell(c.get('measured', ''))})" for c in failed) + ".", ""]
        else:
            lines += ["Every check holds.", ""]
        for title, body in discussion.items():
            lines += [f"#### {title}", "", _demote(body), ""]
        if o.name in WHY:
            lines += ["#### Why", "", WHY[o.name], ""]
    return "\n".join(lines).rstrip() + "\n"


def _is_report(path: Path) -> bool:
    try:
        with open(path, encoding="utf-8") as fh:
            return fh.readline().rstrip("\n") == TITLE
    except (OSError, UnicodeDecodeError):
        return False


def write_report(out_dir: Path, names: Iterable[str] | None = None, *, dest: Path | None = None,
                 image_prefix: str = "") -> Path:
    """Write (atomically) ``REPRODUCTION.md`` for the target folders in ``out_dir``."""
    out_dir = Path(out_dir)
    outcomes = collect(out_dir, names)
    if not outcomes:
        raise FileNotFoundError(f"{out_dir} holds no reproduced target (no <target>/summary.json)")
    dest = out_dir / REPORT if dest is None else Path(dest)
    if dest.exists() and not _is_report(dest):
        raise OutputDirError(f"{dest}: exists and is not a report Shoal wrote; it is left as it is (move it away)")
    atomic_write_text(dest, render(outcomes, image_prefix=image_prefix))
    return dest
