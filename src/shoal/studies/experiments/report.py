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

from .output import cell, information_table, verdict_cell, verdict_of
from .registry import TARGETS, reproduce
from .verdict import FAILS, HOLDS, UNDECIDED

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


VERDICTS = ("**How checks are judged.** Each check's statistic (mostly a median over seeded runs) carries its "
            "95 % confidence interval, the distribution-free interval of a median from order statistics that the "
            "Sweep tab draws. A check **holds** when the whole interval lies on the passing side of its threshold, "
            "**fails** when it lies wholly on the other side, and is **undecided** at its run count when the "
            "interval straddles the threshold or the runs are too few for one (fewer than 6); two statistics are "
            "compared interval against interval. Claims about every sample (a proven bound, an identity of two "
            "seeded cases) are exact. The runs column of each check says how many runs decided it.")


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

    def count(self, outcome: str) -> int:
        """Checks with this verdict (:mod:`.verdict`)."""
        return sum(verdict_of(c) == outcome for c in self.checks)

    @property
    def held(self) -> int:
        return self.count(HOLDS)

    @property
    def failed(self) -> int:
        return self.count(FAILS)

    @property
    def undecided(self) -> int:
        return self.count(UNDECIDED)


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
        got = Outcome(name, summary=summary)
        log(f"  {got.held} of {len(got.checks)} checks hold, {got.failed} fail, {got.undecided} undecided "
            f"({time.perf_counter() - start:.0f} s, {summary.get('cpu_s', 0):.0f} CPU s)")
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


def refresh_readmes(out_dir: Path, names: Iterable[str] | None = None) -> None:
    """Render every target folder's ``README.md`` from its ``summary.json`` (a file the
    reproduction wrote; a folder without a summary, or with one an older version wrote that
    lacks a field the template needs, keeps its README)."""
    for name in (list(TARGETS) if names is None else names):
        folder = Path(out_dir) / name
        if name in TARGETS and (folder / "summary.json").is_file():
            summary = json.loads((folder / "summary.json").read_text(encoding="utf-8"))
            try:
                text = TARGETS[name].readme(summary)
            except (KeyError, TypeError, ValueError):
                continue
            atomic_write_text(folder / "README.md", text)


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
                  "ran with `--quick`: few runs per case (marked \"quick\" below), the same checks. A check that so "
                  "few runs cannot settle is reported undecided, never turned over; `shoal reproduce --all` "
                  "regenerates the full report.", ""]
    lines += ["| target | thesis | runs | checks | hold | fail | undecided | time (s) | CPU (s) | workers |",
              "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for o in outcomes:
        if o.error is not None:
            lines.append(f"| [{o.name}](#{o.name}) | {SOURCES.get(o.name, '')} | | failed to run | | | | | | |")
        else:
            s = o.summary or {}
            runs = f"{s.get('runs', '')}{' (quick)' if s.get('quick') else ''}"
            lines.append(f"| [{o.name}](#{o.name}) | {SOURCES.get(o.name, '')} | {runs} | {len(o.checks)} | "
                         f"{o.held} | {o.failed} | {o.undecided} | {s.get('elapsed_s', '')} | {s.get('cpu_s', '')} | "
                         f"{s.get('workers', '')} |")
    ran = [o.summary or {} for o in outcomes if o.error is None]
    if ran:
        wall = sum(s.get("elapsed_s", 0.0) for s in ran)
        timed = [s["cpu_s"] for s in ran if "cpu_s" in s]  # (reports older than the CPU column have none)
        cpu = f"{sum(timed):.0f}{'' if len(timed) == len(ran) else ' (of the targets timed)'}" if timed else ""
        total = sum(len(o.checks) for o in outcomes)
        lines.append(f"| all | | | {total} | {sum(o.held for o in outcomes)} | {sum(o.failed for o in outcomes)} | "
                     f"{sum(o.undecided for o in outcomes)} | {wall:.0f} | {cpu} | |")
    total = sum(len(o.checks) for o in outcomes)
    lines += ["", f"In all, over {sum(o.error is None for o in outcomes)} targets: of {total} checks "
              f"{sum(o.held for o in outcomes)} hold, {sum(o.failed for o in outcomes)} fail and "
              f"{sum(o.undecided for o in outcomes)} are undecided at their run counts.", "", VERDICTS, ""]
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
                  f"{verdict_cell(c)} |" for c in o.checks]
        lines.append("")
        if s.get("information"):
            lines += [information_table(s["information"]), ""]
        discussion = {k: v for k, v in sections.items() if k not in ("Files", "Checks")}
        failed = [c for c in o.checks if verdict_of(c) == FAILS]
        open_ = [c for c in o.checks if verdict_of(c) == UNDECIDED]
        lines += ["### Where and why they differ", ""]
        if failed:
            lines += [f"{len(failed)} of {len(o.checks)} checks fail: "
                      + "; ".join(f"*{cell(c['name'])}* (thesis: {cell(c.get('thesis', ''))}; "
                                  f"Shoal: {cell(c.get('measured', ''))})" for c in failed) + ".", ""]
        if open_:
            lines += [f"{len(open_)} of {len(o.checks)} checks are undecided at {s.get('runs')} runs (the 95 % "
                      "interval of the statistic straddles the threshold): "
                      + "; ".join(f"*{cell(c['name'])}* (Shoal: {cell(c.get('measured', ''))}; the point estimate "
                                  f"{'passes' if c.get('pass') else 'fails'})" for c in open_) + ".", ""]
        if not failed and not open_:
            lines += ["Every check holds.", ""]
        for title, body in discussion.items():
            lines += [f"#### {title}", "", _demote(body), ""]
        why = TARGETS[o.name].why(s) if o.name in TARGETS else ""
        if why:
            lines += ["#### Why", "", why, ""]
    return "\n".join(lines).rstrip() + "\n"


def _is_report(path: Path) -> bool:
    try:
        with open(path, encoding="utf-8") as fh:
            return fh.readline().rstrip("\n") == TITLE
    except (OSError, UnicodeDecodeError):
        return False


def write_report(out_dir: Path, names: Iterable[str] | None = None, *, dest: Path | None = None,
                 image_prefix: str = "") -> Path:
    """Write (atomically) ``REPRODUCTION.md`` for the target folders in ``out_dir``, after
    rendering each target's ``README.md`` again from its ``summary.json`` (the templates of
    this version: a report's words always describe the numbers beside them)."""
    out_dir = Path(out_dir)
    refresh_readmes(out_dir, names)
    outcomes = collect(out_dir, names)
    if not outcomes:
        raise FileNotFoundError(f"{out_dir} holds no reproduced target (no <target>/summary.json)")
    dest = out_dir / REPORT if dest is None else Path(dest)
    if dest.exists() and not _is_report(dest):
        raise OutputDirError(f"{dest}: exists and is not a report Shoal wrote; it is left as it is (move it away)")
    atomic_write_text(dest, render(outcomes, image_prefix=image_prefix))
    return dest


def _paired(a: Path, b: Path) -> tuple[list[tuple[tuple[str, str], tuple[str, str]]], dict, dict]:
    """The checks two reproductions share, as (key in a, key in b) with key = (target, check
    name), and each side's verdicts. A name whose only difference is a count that follows the
    run count ("runs 0-49", "82200 samples") is the same check: paired by the name with its
    numbers blanked, where that is unique."""
    def verdicts(folder: Path) -> dict[tuple[str, str], str]:
        return {(o.name, c["name"]): verdict_of(c) for o in collect(folder) for c in o.checks}

    def by_shape(keys: set) -> dict[tuple[str, str], tuple[str, str]]:
        shapes: dict[tuple[str, str], list[tuple[str, str]]] = {}
        for key in keys:
            shapes.setdefault((key[0], re.sub(r"\d+", "#", key[1])), []).append(key)
        return {shape: ks[0] for shape, ks in shapes.items() if len(ks) == 1}

    va, vb = verdicts(Path(a)), verdicts(Path(b))
    pairs = [(k, k) for k in set(va) & set(vb)]
    sa, sb = by_shape(set(va) - set(vb)), by_shape(set(vb) - set(va))
    pairs += [(sa[shape], sb[shape]) for shape in set(sa) & set(sb)]
    return sorted(pairs), va, vb


@dataclass(frozen=True)
class Agreement:
    """How two reproductions judge the checks they share (:func:`agreement`). Each differing
    check is listed as (target, check as named in a, verdict in a, verdict in b)."""

    same: dict[str, int]  # verdict -> checks both judged so
    one_sided: list[tuple[str, str, str, str]]  # decided in one, undecided in the other
    opposite: list[tuple[str, str, str, str]]  # one holds what the other fails
    only_in_a: int  # checks without a partner in b
    only_in_b: int

    @property
    def decided_in_a_only(self) -> int:
        return sum(y == UNDECIDED for *_, y in self.one_sided)

    @property
    def decided_in_b_only(self) -> int:
        return sum(x == UNDECIDED for *_, x, _ in self.one_sided)

    @property
    def shared(self) -> int:
        return sum(self.same.values()) + len(self.one_sided) + len(self.opposite)

    def text(self, a: str = "A", b: str = "B") -> str:
        """A few lines for a terminal or a note."""
        same = sum(self.same.values())
        lines = [f"{self.shared} checks in both ({self.only_in_a} in {a} only, {self.only_in_b} in {b} only)",
                 f"  same verdict: {same} (" + ", ".join(f"{n} {v}" for v, n in self.same.items()) + ")",
                 f"  decided in {b}, undecided in {a}: {self.decided_in_b_only}",
                 f"  decided in {a}, undecided in {b}: {self.decided_in_a_only}",
                 f"  opposite verdicts: {len(self.opposite)}"]
        lines += [f"    {t}: {name}: {x} in {a}, {y} in {b}" for t, name, x, y in self.opposite]
        return "\n".join(lines)


def agreement(a: Path, b: Path) -> Agreement:
    """Compare two reproductions of the same targets (e.g. ``--quick`` against a full run) check
    by check: the same verdict, decided in one only, or opposite verdicts. A folder without any
    reproduced target is refused (``FileNotFoundError``)."""
    for folder in (a, b):
        if not collect(Path(folder)):
            raise FileNotFoundError(f"{folder} holds no reproduced target (no <target>/summary.json)")
    pairs, va, vb = _paired(a, b)
    same = {v: 0 for v in (HOLDS, FAILS, UNDECIDED)}
    one_sided: list[tuple[str, str, str, str]] = []
    opposite: list[tuple[str, str, str, str]] = []
    for ka, kb in pairs:
        x, y = va[ka], vb[kb]
        if x == y:
            same[x] += 1
        else:
            (one_sided if UNDECIDED in (x, y) else opposite).append((*ka, x, y))
    paired_a, paired_b = {ka for ka, _ in pairs}, {kb for _, kb in pairs}
    return Agreement(same, one_sided, opposite, len(set(va) - paired_a), len(set(vb) - paired_b))
