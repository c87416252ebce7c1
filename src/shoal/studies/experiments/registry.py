"""Reproduction targets (one thesis figure or table each) and ``reproduce``."""

from __future__ import annotations

import json
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

from shoal.engine.core.atomic import output_dir

from .schedulers import Scheduler, current, using
from .verdict import LEVEL, OUTCOMES


@dataclass(frozen=True)
class Target:
    """A figure or table that ``shoal reproduce NAME`` regenerates.

    ``run(out_dir, runs, workers, progress, **options)`` writes the target's files into
    ``out_dir`` and returns the summary fields (at least ``checks``). ``quick`` is the
    classroom size: its ``runs`` and any options that make the target cheap while every
    check can still be computed (``shoal reproduce --quick``).
    """

    name: str
    description: str
    default_runs: int
    _run: Callable[..., dict[str, Any]]
    quick: dict[str, Any] = field(default_factory=dict)
    module: str = ""  # the module of ``readme(summary)``, e.g. "fig3_4"

    def readme(self, summary: dict[str, Any]) -> str:
        """The target's README.md, rendered from its ``summary.json`` alone (so it never
        describes another run than the one beside it)."""
        return self._template().readme(summary)

    def why(self, summary: dict[str, Any]) -> str:
        """Why Shoal and the thesis differ, written from the measured numbers ("" if none)."""
        from .why import why

        return why(self.name, summary)

    def _template(self) -> Any:
        from importlib import import_module

        return import_module(f".{self.module}", __package__)

    @property
    def quick_runs(self) -> int:
        return int(self.quick.get("runs", self.default_runs))

    @property
    def quick_options(self) -> dict[str, Any]:
        return {k: v for k, v in self.quick.items() if k != "runs"}

    def run(self, out_dir: Path, runs: int, workers: int = 1, progress: bool = True, **options: Any) -> dict[str, Any]:
        return self._run(Path(out_dir), runs, workers, progress, **options)


def _fig3_4(out_dir: Path, runs: int, workers: int, progress: bool, **options: Any) -> dict[str, Any]:
    from . import fig3_4

    return fig3_4.run(out_dir, runs, workers, progress, **options)


def _fig3_5(out_dir: Path, runs: int, workers: int, progress: bool, **options: Any) -> dict[str, Any]:
    from . import fig3_5

    return fig3_5.run(out_dir, runs, workers, progress, **options)


def _fig4_6(out_dir: Path, runs: int, workers: int, progress: bool, **options: Any) -> dict[str, Any]:
    from . import fig4_6

    return fig4_6.run(out_dir, runs, workers, progress, **options)


def _fig5_4(out_dir: Path, runs: int, workers: int, progress: bool, **options: Any) -> dict[str, Any]:
    from . import fig5_4

    return fig5_4.run(out_dir, runs, workers, progress, **options)


def _fig5_5(out_dir: Path, runs: int, workers: int, progress: bool, **options: Any) -> dict[str, Any]:
    from . import fig5_5

    return fig5_5.run(out_dir, runs, workers, progress, **options)


def _fig7_2(out_dir: Path, runs: int, workers: int, progress: bool, **options: Any) -> dict[str, Any]:
    from . import fig7_2

    return fig7_2.run(out_dir, runs, workers, progress, **options)


def _fig7_3(out_dir: Path, runs: int, workers: int, progress: bool, **options: Any) -> dict[str, Any]:
    from . import fig7_3

    return fig7_3.run(out_dir, runs, workers, progress, **options)


def _fig7_4(out_dir: Path, runs: int, workers: int, progress: bool, **options: Any) -> dict[str, Any]:
    from . import fig7_4

    return fig7_4.run(out_dir, runs, workers, progress, **options)


def _fig7_5(out_dir: Path, runs: int, workers: int, progress: bool, **options: Any) -> dict[str, Any]:
    from . import fig7_5

    return fig7_5.run(out_dir, runs, workers, progress, **options)


def _fig8_2(out_dir: Path, runs: int, workers: int, progress: bool, **options: Any) -> dict[str, Any]:
    from . import fig8_2

    return fig8_2.run(out_dir, runs, workers, progress, **options)


def _fig8_4(out_dir: Path, runs: int, workers: int, progress: bool, **options: Any) -> dict[str, Any]:
    from . import fig8_4

    return fig8_4.run(out_dir, runs, workers, progress, **options)


def _fig8_5(out_dir: Path, runs: int, workers: int, progress: bool, **options: Any) -> dict[str, Any]:
    from . import fig8_5

    return fig8_5.run(out_dir, runs, workers, progress, **options)


_SLO_TARGETS = {  # target -> (module, function)
    "slo-errors": ("slo_walk", "run_errors"), "slo-mitigation": ("slo_walk", "run_mitigation"),
    "slo-neighbourhood": ("slo_walk", "run_neighbourhood"), "slo-weight": ("slo_walk", "run_weight"),
    "slo-pso": ("slo_pso", "run"),
}


def _slo(name: str) -> Callable[..., dict[str, Any]]:
    def run(out_dir: Path, runs: int, workers: int, progress: bool, **options: Any) -> dict[str, Any]:
        from importlib import import_module

        module, fn = _SLO_TARGETS[name]
        return getattr(import_module(f".{module}", __package__), fn)(out_dir, runs, workers, progress, **options)

    return run


TARGETS: dict[str, Target] = {
    t.name: t
    for t in (
        Target("fig3-4", "Ch. 3 Fig. 3-4: highest speed at constant U, A+, dt (cases a-d, ahead and literal)",
               100, _fig3_4, {"runs": 20}, module="fig3_4"),
        Target("fig3-5", "Ch. 3 Fig. 3-5: response of the highest speed to step changes of U and A+ (a-c)",
               100, _fig3_5, {"runs": 20}, module="fig3_5"),
        Target("fig4-6", "Ch. 4 Figs. 4-6/4-7: seven RPSO/Adapted RPSO/DVC cases on the obstacle course, "
               "kinematic and physics (CoM fitness, collisions)", 100, _fig4_6, {"runs": 8}, module="fig4_6"),
        Target("fig5-4", "Ch. 5 Fig. 5-4: 20 non-omni DVC robots in an empty arena, with and without our guard "
               "(collisions, roaming, trails of the last 15 s)", 20, _fig5_4, {"runs": 6}, module="fig5_4"),
        Target("fig5-5", "Ch. 5 Fig. 5-5: omni vs non-omni DVC on the obstacle course (median CoM fitness, "
               "5th-95th percentile bands)", 100, _fig5_5, {"runs": 10}, module="fig5_5"),
        Target("fig7-2", "Ch. 7 Fig. 7-2: A-/X-/B-/XB-PSO convergence from SNR0 = 10, 4, 0 dB (waveform level, "
               "10 robots, 6000 steps; c1:c2 1:3 and 1:1)", 100, _fig7_2, {"runs": 6}, module="fig7_2"),
        Target("fig7-3", "Ch. 7 Fig. 7-3: CoM routes of the 10 dB swarms of Fig. 7-2 and where they passed "
               "(routes from a fig7-2 run beside it, else the same runs simulated)", 100, _fig7_3, {"runs": 6},
               module="fig7_3"),
        Target("fig7-4", "Ch. 7 Fig. 7-4: median time to convergence over (Q, D/lambda_c) at 10 dB "
               "(20 runs per point by default)", 20, _fig7_4,
               {"runs": 3, "q": (1.0, 1.5, 50.0), "d": (0.5, 1.0, 10.0)}, module="fig7_4"),
        Target("fig7-5", "Ch. 7 Fig. 7-5: median time to convergence over (Q, U) at 10 dB, D = lambda_c/2 "
               "(20 runs per point by default; c1:c2 1:3 and 1:1)", 20, _fig7_5,
               {"runs": 3, "q": (1.5, 50.0), "u": (2.0, 4.0, 12.0)}, module="fig7_5"),
        Target("fig8-2", "Ch. 8 Fig. 8-2: GT-PSO vs XB-PSO with the non-omni DVC controller from SNR0 = 10, 6, 4, 0 dB "
               "(2000 steps)", 100, _fig8_2, {"runs": 10}, module="fig8_2"),
        Target("fig8-4", "Ch. 8 Fig. 8-4: escorting a stationary source, 10 and 40 robots at r = 25, 50, 75 m "
               "(GT-PSO, occupancy maps)", 20, _fig8_4, {"runs": 3}, module="fig8_4"),
        Target("fig8-5", "Ch. 8 Fig. 8-5: escorting a source moving at v_n = 0.1 and 0.25, 40 robots, r = 25/50 m, "
               "louder source", 20, _fig8_5, {"runs": 3}, module="fig8_4"),
        Target("slo-errors", "SLO Figs. 4.1-4.3: localisation error vs single sensor errors, velocity offset per "
               "neighbourhood x selection, failures (random walk)", 31, _slo("slo-errors"), {"runs": 6},
               module="slo_walk"),
        Target("slo-mitigation", "SLO Figs. 4.4-4.6: error at generation 100 over a delta_cos x delta_v grid "
               "(knn None/Low/High, ring Low CSS/RTS, random None)", 31, _slo("slo-mitigation"), {"runs": 6},
               module="slo_walk"),
        Target("slo-neighbourhood", "SLO Figs. 4.7-4.8: ring n sweep (CSS) and random p in {0.3, 0.5, 0.9} "
               "(CSS, RTS), Low error", 31, _slo("slo-neighbourhood"), {"runs": 6}, module="slo_walk"),
        Target("slo-weight", "SLO Figs. 4.9-4.10: prediction weight w in {0, 0.25, 0.5, 0.75}, knn and ring, CSS, "
               "Low error", 31, _slo("slo-weight"), {"runs": 6}, module="slo_walk"),
        Target("slo-pso", "SLO Table 4.4 and Figs. 4.11-4.13: SLO-PSO on seven benchmarks x 3 selections x 3 error "
               "levels, 1000 generations, 31 runs per case as in the thesis", 31, _slo("slo-pso"),
               {"runs": 2, "short": 200}, module="slo_pso"),
    )
}


def _ours(out_dir: Path) -> Callable[[str], bool]:
    """The entries of ``out_dir`` an earlier reproduction wrote (its ``summary.json`` lists them)."""
    try:
        files = json.loads((out_dir / "summary.json").read_text(encoding="utf-8")).get("files")
    except (OSError, ValueError):
        files = None
    if not isinstance(files, list):
        return lambda name: False  # no reproduction, or one too old to list its files: nothing is ours
    names = {str(f) for f in files} | {"summary.json"}
    return names.__contains__


def _cpu_seconds() -> float:
    """CPU seconds of this process and of its worker processes that have ended (a local pool's
    workers end with each batch of jobs; a Dask cluster's are not counted; without the
    ``resource`` module, as on Windows, this process only)."""
    try:
        import resource
    except ImportError:
        return time.process_time()
    me, children = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return me.ru_utime + me.ru_stime + children.ru_utime + children.ru_stime


def reproduce(
    target: str,
    out_dir: Path,
    runs: int | None = None,
    workers: int = 1,
    progress: bool = True,
    scheduler: Scheduler | None = None,
    quick: bool = False,
    **options: Any,
) -> dict[str, Any]:
    """Regenerate ``target`` into ``out_dir`` and return its summary.

    ``quick`` runs the target at its classroom size (:attr:`Target.quick`, marked
    ``"quick": true`` in the summary); ``runs`` and ``options`` still override it.

    The target's chunks of runs go to ``scheduler`` (e.g. a
    :class:`~.schedulers.DaskCluster`) when given, else to ``workers`` local processes;
    the files are the same either way.

    Everything is written into a temporary sibling folder which replaces ``out_dir`` only
    when the target has finished: an interrupted or failed run leaves ``out_dir`` as it was
    (absent, or the previous reproduction). An ``out_dir`` holding anything an earlier
    reproduction did not write (its ``summary.json`` lists its ``files``) is refused
    (:class:`OutputDirError`) before the target runs. ``options`` go to the target (e.g.
    ``sizes=(10, 100)`` for a quick check).
    """
    if target not in TARGETS:
        raise KeyError(f"unknown target {target!r}; known: {', '.join(TARGETS)}")
    spec = TARGETS[target]
    if quick:
        options = {**spec.quick_options, **options}
    runs = (spec.quick_runs if quick else spec.default_runs) if runs is None else int(runs)
    if runs < 1:
        raise ValueError(f"runs must be >= 1, got {runs}")
    if workers < 1:
        raise ValueError(f"workers must be >= 1, got {workers}")
    out_dir = Path(out_dir)
    start, cpu = time.perf_counter(), _cpu_seconds()
    with output_dir(out_dir, _ours(out_dir), f"shoal reproduce {target}") as tmp:
        with using(scheduler):
            fields = spec.run(tmp, runs, workers, progress, **options)
        summary = {"target": target, "runs": runs, "elapsed_s": round(time.perf_counter() - start, 3),
                   "cpu_s": round(_cpu_seconds() - cpu, 3), **fields}
        summary["workers"] = workers
        summary["quick"] = quick
        verdicts = [c.get("verdict") for c in summary.get("checks", [])]
        # how the checks came out, each judged by the interval of its statistic at this level
        summary["judged"] = {"checks": len(verdicts), **{v: verdicts.count(v) for v in OUTCOMES}, "level": LEVEL}
        if (used := scheduler or current()) is not None:
            summary["scheduler"] = used.describe()
        # what a rerun into out_dir may replace: the target's files, this summary and its README
        summary["files"] = sorted({p.name for p in tmp.iterdir()} | {"summary.json", "README.md"})
        (tmp / "summary.json").write_text(json.dumps(summary, indent=2, ensure_ascii=False) + "\n", encoding="utf-8")
        (tmp / "README.md").write_text(spec.readme(json.loads(json.dumps(summary))), encoding="utf-8")
    return summary
