"""The ``shoal`` command: serve, hall, run, reproduce, sweep, export-replay, warmup, presets."""

from __future__ import annotations

import argparse
import contextlib
import os
import sys
import time
from pathlib import Path
from typing import Any, Callable, NoReturn

from shoal import __version__

EXIT_FAILED = 1
EXIT_USAGE = 2
DEFAULT_MAX_SESSIONS = 24  # as shoal.app.server.DEFAULT_MAX_SESSIONS (not imported: viser loads slowly)
DEFAULT_MAX_WATCHERS = 500  # as shoal.app.hall.lecture.DEFAULT_MAX_WATCHERS
MAX_PORT = 65535


def whole(lo: int, hi: int | None = None) -> Callable[[str], int]:
    """An argparse type: a whole number from ``lo`` (to ``hi``), refused with the range before anything starts."""
    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected a whole number, got {text!r}") from None
        if value < lo or (hi is not None and value > hi):
            span = f"from {lo} to {hi}" if hi is not None else f"at least {lo}"
            raise argparse.ArgumentTypeError(f"must be {span}, got {value}")
        return value

    parse.__name__ = "whole number"
    return parse


def _err(msg: str, code: int = EXIT_USAGE) -> int:
    print(f"shoal: error: {msg}", file=sys.stderr)
    return code


def _too_big(scenario: Any) -> int:
    return _err(f"not enough memory for {scenario.name} with sim.robots = {scenario.sim.robots} and "
                f"sim.runs = {scenario.sim.runs}; choose fewer", EXIT_FAILED)


def _cannot_write(out: Path, err: OSError) -> int:
    """One line naming the output folder and why it cannot be written (a full disk, say)."""
    return _err(f"cannot write {out}: {err.strerror or err}", EXIT_FAILED)


def _cmd_serve(args: argparse.Namespace) -> int:
    from shoal.presets.io import PresetError, load

    try:
        load(args.preset)
    except PresetError as e:
        return _err("bad preset:\n  " + "\n  ".join(e.messages))
    from shoal.app.origin_guard import check_origin_url
    from shoal.app.server import serve

    if args.scheduler is not None:
        from shoal.studies.experiments.schedulers import SchedulerError, scheduler_address

        try:
            scheduler_address(args.scheduler)  # (reached, with a timeout, when the server starts)
        except SchedulerError as e:
            return _err(str(e))
    try:
        origins = tuple(check_origin_url(url) for url in args.allow_origin or ())
    except ValueError as e:
        return _err(str(e))
    try:
        if args.lecture:
            from shoal.app.hall.command import serve_lecture

            serve_lecture(preset=args.preset, host=args.host, port=args.port, max_sessions=args.max_sessions,
                          max_watchers=args.max_watchers, allow_origins=origins, scheduler=args.scheduler,
                          experiment_workers=args.experiment_workers, projector=args.projector)
        else:
            serve(preset=args.preset, host=args.host, port=args.port, max_sessions=args.max_sessions,
                  allow_origins=origins, scheduler=args.scheduler, experiment_workers=args.experiment_workers,
                  projector=args.projector)
    except OSError as e:
        return _err(str(e))
    return 0


def _cmd_hall(args: argparse.Namespace) -> int:
    from shoal.presets.io import PresetError, load

    try:
        load(args.preset)
    except PresetError as e:
        return _err("bad preset:\n  " + "\n  ".join(e.messages))
    from shoal.app.hall.supervisor import serve_hall
    from shoal.app.origin_guard import check_origin_url

    try:
        origins = tuple(check_origin_url(url) for url in args.allow_origin or ())
    except ValueError as e:
        return _err(str(e))
    serve_hall(args.preset, workers=args.workers, host=args.host, port=args.port, max_sessions=args.max_sessions,
               max_watchers=args.max_watchers, allow_origins=origins)
    return 0


WARM_AFTER = 1.0  # s: a run still going after this long has its kernels compiled beside it (a shorter one never waits)
BAR_FROM = 200  # steps: a shorter run shows no progress bar (and never imports tqdm)


class _NoBar:
    def update(self) -> None:
        pass


def _progress(steps: int, desc: str) -> Any:
    """A progress bar over ``steps`` (tqdm's, shown on a terminal) or one that shows nothing."""
    if steps < BAR_FROM:
        return contextlib.nullcontext(_NoBar())
    from tqdm import tqdm

    return tqdm(total=steps, desc=desc, unit="step", disable=None)


def _cmd_run(args: argparse.Namespace) -> int:
    from shoal.app.warmup import NUMPY_TICK, WARMUP, group_of
    from shoal.engine.core.atomic import OutputDirError, check_output_dir
    from shoal.engine.core.runs import RUN_FILES, run_to_dir
    from shoal.presets.build import build
    from shoal.presets.io import PresetError, file_stem, load

    overrides = list(args.set or [])
    for flag, key in ((args.runs, "sim.runs"), (args.seed, "sim.seed"), (args.steps, "sim.steps")):
        if flag is not None:
            overrides.append(f"{key}={flag}")
    try:
        scenario = load(args.preset, overrides)
        out = Path(args.out or f"out/{file_stem(scenario.name)}-seed{scenario.sim.seed}")  # a name is no path
        check_output_dir(out, RUN_FILES.__contains__, "shoal run")  # before any work
        sim = build(scenario)  # (a world that cannot be laid out is refused here, by field)
    except PresetError as e:
        return _err("bad preset:\n  " + "\n  ".join(e.messages))
    except OutputDirError as e:
        return _err(str(e))
    except MemoryError:
        return _too_big(scenario)
    meta = {
        "shoal_version": __version__,
        "preset": scenario.model_dump(mode="json"),
        "seed": scenario.sim.seed,
        "runs": scenario.sim.runs,
        "steps": scenario.sim.steps,
    }
    steps = scenario.sim.steps
    # A kind with a numpy tick starts on it (the compiled tick's numbers, bit for bit), so a short run
    # never loads numba; one that runs longer than WARM_AFTER has its kernels compiled beside it and
    # changes over once they are ready.
    numpy_first = group_of(scenario) in NUMPY_TICK and hasattr(sim, "compiled")
    if numpy_first:
        sim.compiled = False  # type: ignore[attr-defined]  # (the kinds with a numpy tick have it)
    started = time.monotonic()

    def ticked(_k: int) -> None:
        bar.update()
        if numpy_first:
            if not WARMUP.active and time.monotonic() - started > WARM_AFTER:
                WARMUP.start(scenario, only=True)
            if WARMUP.active:
                WARMUP.use(sim, scenario)

    try:
        with _progress(steps, f"run {scenario.name}") as bar:
            run_to_dir(sim, steps, out, meta, on_step=ticked)
    except OutputDirError as e:  # (a file appeared in --out meanwhile)
        return _err(str(e))
    except OSError as e:
        return _cannot_write(out, e)
    except MemoryError:  # (its partial folder is gone already)
        return _too_big(scenario)
    print(f"wrote {out}/run.json, trajectories.csv, metrics.csv")
    return 0


def _cmd_reproduce(args: argparse.Namespace) -> int:
    from shoal.studies.experiments import TARGETS, OutputDirError, reproduce

    if args.report:
        return _report(args.report)
    if args.compare:
        return _compare(*args.compare)
    if args.all:
        return _reproduce_all(args)
    if args.list or not args.target:
        for name, target in TARGETS.items():
            print(f"{name:12s} {target.description}")
        return 0 if args.list else _err("name a TARGET (see --list)")
    if args.target not in TARGETS:
        return _err(f"unknown target {args.target!r}; known: {', '.join(TARGETS)}")
    out = Path(args.out or f"out/{args.target}")
    try:
        summary = reproduce(args.target, out, runs=args.runs, workers=args.workers, progress=True, quick=args.quick)
    except OutputDirError as e:
        return _err(str(e))
    except OSError as e:
        return _cannot_write(out, e)
    from shoal.studies.experiments.output import verdict_of

    verdicts = [(verdict_of(c), c["name"]) for c in summary["checks"]]
    counts = {v: sum(got == v for got, _ in verdicts) for v in ("holds", "fails", "undecided")}
    print(f"wrote {out}/summary.json ({len(verdicts)} checks: {counts['holds']} hold, {counts['fails']} fail, "
          f"{counts['undecided']} undecided at {summary['runs']} runs)")
    for verdict, name in verdicts:
        if verdict != "holds":
            print(f"  {'fails' if verdict == 'fails' else 'undecided'}: {name}")
    return 0


def _cmd_reproduce_on(args: argparse.Namespace) -> int:
    """``reproduce`` with ``--scheduler``: every target's chunks of runs go to the Dask cluster."""
    if args.scheduler is None or args.list or args.report or args.compare:
        return _cmd_reproduce(args)
    from shoal.studies.experiments.schedulers import SchedulerError, connect, using

    try:
        with connect(args.scheduler) as cluster, using(cluster):
            return _cmd_reproduce(args)
    except SchedulerError as e:
        return _err(str(e))


def _cmd_sweep(args: argparse.Namespace) -> int:
    from shoal.studies.experiments.schedulers import SchedulerError, connect
    from shoal.studies.sweep import SweepError, run_sweep

    out = Path(args.out or f"out/sweep-{Path(args.preset).stem}")
    try:
        with connect(args.scheduler, args.workers) as scheduler:
            report = run_sweep(args.preset, args.grid, out, runs=args.runs, seed=args.seed, steps=args.steps,
                               sets=args.set or (), workers=args.workers, scheduler=scheduler)
    except SweepError as e:
        return _err("bad sweep:\n  " + "\n  ".join(e.messages))
    except SchedulerError as e:
        return _err(str(e))
    except OSError as e:
        return _cannot_write(out, e)
    except KeyboardInterrupt:
        print(f"interrupted: finished cells are kept in {out}/cells; rerun the same command to resume",
              file=sys.stderr)
        return 130
    print(f"wrote {out}/results.csv ({report.cells} cells x {report.runs} runs; {report.computed} cells computed, "
          f"{report.cells - report.computed} already done), medians.csv, sweep.json and {len(report.plots)} plots")
    return 0


def _cmd_export_replay(args: argparse.Namespace) -> int:
    from shoal.app.share.command import ExportError, export_replay

    try:
        print(export_replay(args.preset, args.out, seed=args.seed, steps=args.steps, sets=args.set or ()))
    except ExportError as e:
        return _err(str(e))
    return 0


def _reproduce_all(args: argparse.Namespace) -> int:
    from shoal.studies.experiments import OutputDirError
    from shoal.studies.experiments.report import run_all

    if args.target:
        return _err("--all takes no TARGET")
    out = Path(args.out or "out/reproduction")
    try:
        report = run_all(out, runs=args.runs, workers=args.workers, resume=args.resume, quick=args.quick)
    except OutputDirError as e:
        return _err(str(e))
    except OSError as e:
        return _cannot_write(out, e)
    print(f"wrote {report}")
    return 0


def _report(folder: str) -> int:
    from shoal.studies.experiments import OutputDirError
    from shoal.studies.experiments.report import write_report

    try:
        print(f"wrote {write_report(Path(folder))}")
    except (FileNotFoundError, OutputDirError) as e:
        return _err(str(e))
    return 0


def _compare(a: str, b: str) -> int:
    """``--compare A B``: how two reproductions judge their shared checks; 1 if one holds a
    check the other fails."""
    from shoal.studies.experiments.report import agreement

    try:
        got = agreement(Path(a), Path(b))
    except FileNotFoundError as e:
        return _err(str(e))
    print(got.text(a, b))
    return 1 if got.opposite else 0


def _cmd_warmup(args: argparse.Namespace) -> int:
    from shoal.app.warmup import WARMUP
    from shoal.engine.core import compiled

    print(f"compiling Shoal's kernels (cache: {compiled.cache_dir()})", flush=True)
    seconds = WARMUP.run(say=lambda line: print(f"  {line}", flush=True))
    if WARMUP.error is not None:
        return _err(f"compiling failed: {WARMUP.error}", EXIT_FAILED)
    if compiled.uncached:
        print("no cache folder could be written (a read-only install and home?): every process compiles again; "
              "set NUMBA_CACHE_DIR to a writable folder to keep them")
    print(f"done in {seconds:.0f} s; scenes and runs now start at full speed")
    return 0


def _cmd_presets(args: argparse.Namespace) -> int:
    from shoal.presets.build import check_buildable
    from shoal.presets.io import PresetError, list_presets, load, to_toml

    if args.action == "list":
        for name, desc in list_presets().items():
            print(f"{name:14s} {desc}")
        return 0
    if not args.name:
        return _err(f"presets {args.action} needs a NAME or FILE")
    try:
        scenario = load(args.name)
        if args.action == "validate":
            check_buildable(scenario)  # the rules `shoal run` applies when it builds the scene, not only the model's
    except PresetError as e:
        print("\n".join(e.messages), file=sys.stderr)
        return 1 if args.action == "validate" else EXIT_USAGE
    if args.action == "show":
        from shoal.presets.marks import text

        print(to_toml(scenario), end="")
        print("\n" + text(scenario), end="")
    else:
        print(f"{args.name}: valid ({scenario.name})")
    return 0


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="shoal", description="PSO control of robot swarms: sandbox and research tool")
    p.add_argument("--version", action="version", version=f"shoal {__version__}")
    sub = p.add_subparsers(dest="command", required=True)

    s = sub.add_parser("serve", help="start the browser app")
    s.add_argument("--host", default="127.0.0.1", help="bind address (default loopback)")
    s.add_argument("--port", type=whole(0, MAX_PORT), default=8080, help="0 picks a free one")
    s.add_argument("--preset", default="default", help="preset name or TOML/JSON file")
    s.add_argument("--max-sessions", type=whole(1), default=DEFAULT_MAX_SESSIONS, metavar="N",
                   help=f"browser tabs with a simulation at once; more are told the server is full "
                        f"(default {DEFAULT_MAX_SESSIONS})")
    s.add_argument("--allow-origin", action="append", metavar="URL",
                   help="also accept pages of this origin, e.g. http://192.168.1.10:8080 or a proxy's "
                        "https://shoal.example.org (repeatable; by default only this server's own pages)")
    s.add_argument("--scheduler", help="run the Sweep tab's sweeps on this Dask scheduler (tcp://HOST:PORT)")
    s.add_argument("--experiment-workers", type=whole(1), default=1, metavar="W",
                   help="without --scheduler: local worker processes for the Sweep tab (default 1)")
    s.add_argument("--projector", action="store_true",
                   help="every tab opens in projector mode (text twice its size; a browser's own choice wins; "
                        "with --lecture: the lecturer's tab, a class tab stays normal)")
    s.add_argument("--lecture", action="store_true",
                   help="teach a class: prints the lecturer's address (with a secret key: it drives one run) and "
                        "the class's (every tab there watches that run, and may take it over or answer a round)")
    s.add_argument("--max-watchers", type=whole(1), default=DEFAULT_MAX_WATCHERS, metavar="N",
                   help=f"with --lecture: class tabs at once (default {DEFAULT_MAX_WATCHERS})")
    s.set_defaults(func=_cmd_serve)

    h = sub.add_parser("hall", help="teach a class across processes: the lecture, N workers for the private "
                                    "sessions, and nginx in front, started and stopped together")
    h.add_argument("--workers", type=whole(1), default=2, metavar="N",
                   help="worker processes for private sessions (take-overs, /solo); default 2")
    h.add_argument("--host", default="127.0.0.1", help="nginx's bind address (default loopback; 0.0.0.0: the class's "
                                                       "machines)")
    h.add_argument("--port", type=whole(1, MAX_PORT), default=8080, help="nginx's port (default 8080)")
    h.add_argument("--preset", default="default", help="the lecture's preset name or TOML/JSON file")
    h.add_argument("--max-sessions", type=whole(1), default=DEFAULT_MAX_SESSIONS, metavar="N",
                   help=f"private sessions a worker runs at once (default {DEFAULT_MAX_SESSIONS})")
    h.add_argument("--max-watchers", type=whole(1), default=DEFAULT_MAX_WATCHERS, metavar="N",
                   help=f"class tabs at once (default {DEFAULT_MAX_WATCHERS})")
    h.add_argument("--allow-origin", action="append", metavar="URL",
                   help="also accept pages of this origin (a name the class reaches the hall by, e.g. "
                        "http://lecturehall.example:8080)")
    h.set_defaults(func=_cmd_hall)

    r = sub.add_parser("run", help="headless seeded runs")
    r.add_argument("preset", help="preset name or TOML/JSON file")
    r.add_argument("--set", action="append", metavar="KEY=VALUE", help="override a field by dotted path")
    r.add_argument("--runs", type=whole(1))
    r.add_argument("--seed", type=whole(0))
    r.add_argument("--steps", type=whole(0))
    r.add_argument("--out", help="output folder")
    r.set_defaults(func=_cmd_run)

    q = sub.add_parser("reproduce", help="regenerate a thesis figure or table")
    q.add_argument("target", nargs="?")
    q.add_argument("--list", action="store_true", help="list the targets")
    q.add_argument("--runs", type=whole(1))
    q.add_argument("--out")
    q.add_argument("--workers", type=whole(1), default=1)
    q.add_argument("--scheduler", help="Dask scheduler address (tcp://HOST:PORT)")
    q.add_argument("--all", action="store_true", help="every target into --out, plus REPRODUCTION.md")
    q.add_argument("--resume", action="store_true", help="with --all: keep targets already finished in --out")
    q.add_argument("--quick", action="store_true",
                   help="classroom size: few runs per case, the same checks (every target in minutes)")
    q.add_argument("--report", metavar="DIR", help="rebuild DIR/REPRODUCTION.md from its target folders")
    q.add_argument("--compare", nargs=2, metavar=("A", "B"),
                   help="compare two reproductions check by check (e.g. a --quick one and a full one); "
                        "exit status 1 if one holds a check the other fails")
    q.set_defaults(func=_cmd_reproduce_on)

    w = sub.add_parser("sweep", help="seeded runs of a preset over a grid of field values (resumable)")
    w.add_argument("preset", help="preset name or TOML/JSON file")
    w.add_argument("--grid", action="append", required=True, metavar="KEY=V1,V2,...",
                   help="a dotted preset field and its values (TOML literals); repeat for more axes")
    w.add_argument("--set", action="append", metavar="KEY=VALUE", help="override a field in every cell")
    w.add_argument("--runs", type=whole(1), help="seeded runs per cell (default: the preset's sim.runs)")
    w.add_argument("--seed", type=whole(0))
    w.add_argument("--steps", type=whole(0))
    w.add_argument("--out", help="output folder (a rerun into it resumes)")
    w.add_argument("--workers", type=whole(1), default=1)
    w.add_argument("--scheduler", help="Dask scheduler address (tcp://HOST:PORT)")
    w.set_defaults(func=_cmd_sweep)

    e = sub.add_parser("export-replay", help="a seeded run as one HTML page that plays in any browser")
    e.add_argument("preset", help="preset name or TOML/JSON file")
    e.add_argument("--seed", type=whole(0))
    e.add_argument("--steps", type=whole(0))
    e.add_argument("--out", required=True, help="the page to write (.html)")
    e.add_argument("--set", action="append", metavar="KEY=VALUE", help="override a field by dotted path")
    e.set_defaults(func=_cmd_export_replay)

    c = sub.add_parser("warmup", help="compile the kernels now, so that the first scenes and runs start at full "
                                      "speed (otherwise they run on numpy until the kernels are ready)")
    c.set_defaults(func=_cmd_warmup)

    ps = sub.add_parser("presets", help="list, show or validate presets")
    ps.add_argument("action", choices=["list", "show", "validate"])
    ps.add_argument("name", nargs="?")
    ps.set_defaults(func=_cmd_presets)
    return p


def main(argv: list[str] | None = None) -> int:
    from shoal.app.terminate import EXIT_TERMINATED, Terminated, terminate_as_interrupt

    with terminate_as_interrupt():  # SIGTERM cleans up as Ctrl-C does (serve: tabs told, run: no partial folder)
        try:
            args = build_parser().parse_args(argv)  # (--help prints too)
            code = args.func(args)
            sys.stdout.flush()  # (a closed pipe is found here, not at exit)
            return code
        except BrokenPipeError:
            return _closed_pipe()
        except Terminated:
            print("terminated", file=sys.stderr)
            return EXIT_TERMINATED
        except KeyboardInterrupt:
            print("interrupted", file=sys.stderr)
            return 130


EXIT_PIPE = 128 + 13  # as a process that SIGPIPE ended


def _closed_pipe() -> int:
    """The reader of standard output went away (``shoal presets show default | head``): stop
    quietly, as a command killed by SIGPIPE does, with nothing more written to the pipe."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())  # (Python's own flush at exit then has nowhere to fail)
    except (OSError, ValueError):
        pass
    return EXIT_PIPE


def entry() -> NoReturn:
    """The ``shoal`` command: :func:`main`, then the exit. A warm-up thread still compiling
    (``shoal run`` starts one) is not waited for, and the interpreter is not torn down under it:
    a daemon thread inside LLVM while Python finalises can abort the process after its work is
    written. Every file a command writes is closed (and renamed into place) before it returns."""
    code = main()
    from shoal.app.warmup import WARMUP

    if WARMUP.compiling():
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(code)
    raise SystemExit(code)
