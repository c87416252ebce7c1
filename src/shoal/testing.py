"""The scene-kind conformance kit: does a kind keep the rules every Shoal kind keeps?

Modelled on Gymnasium's ``check_env`` and scikit-learn's ``parametrize_with_checks``: small
named checks, each testing one rule and failing with a message that says what to fix, chosen by
what the kind's registry entry declares (``best_fitness`` only where it optimises, the live rule
only where it has one, the snapshot where its engine takes one, the app where it names a module).

    from shoal.testing import check_kind, parametrize_with_kinds

    check_kind("gather")                    # every check that applies; KindCheckError lists what fails

    @parametrize_with_kinds(["gather"])     # pytest: one test per (kind, check)
    def test_gather_is_a_shoal_kind(kind, check):
        check(kind)

The checks build the kind's engine from its example preset (``SceneKind.example``, else its first
preset), two seeded runs, and drive it through the engine contract
(:mod:`shoal.engine.core.contract`) as the recorder, the API and the app do. Shoal's own suite
runs them on every built-in kind and on the example plug-in.
"""

from __future__ import annotations

import functools
import importlib
from dataclasses import dataclass
from typing import Any, Callable, Iterable, NoReturn

import numpy as np
from pydantic import BaseModel

from shoal.api.scene import Scene
from shoal.api.scene import scenario_of as api_scenario
from shoal.engine.core.contract import Engine, Info, State
from shoal.engine.core.recorder import metric_table
from shoal.engine.core.schema import Column
from shoal.presets.io import PresetError, list_presets, load, validate
from shoal.presets.kinds import KINDS, SceneKind, kind_for, resolve
from shoal.presets.models import Scenario

RUNS, SEED, STEPS = 2, 3, 4  # the engines the checks build: runs of a seed, ticks stepped


class KindCheckError(AssertionError):
    """A kind breaks a rule; the message names the check and says what to change."""


@dataclass(frozen=True)
class KindCheck:
    """One named rule: ``applies`` (from the kind's declared facts) and ``run`` (raises
    :class:`KindCheckError`)."""

    name: str
    applies: Callable[[SceneKind], bool]
    run: Callable[[SceneKind, Scenario], None]
    doc: str

    def __call__(self, kind: SceneKind | str, scenario: Scenario | None = None) -> None:
        """Check ``kind`` on ``scenario`` (default: its example preset)."""
        entry = _entry(kind)
        try:
            self.run(entry, scenario_of(entry) if scenario is None else scenario)
        except KindCheckError as err:
            raise KindCheckError(f"{entry.name}: {self.name}: {err}") from None
        except Exception as err:  # the kind's own code failed: the check's name, the error, its traceback
            raise KindCheckError(f"{entry.name}: {self.name}: raised {type(err).__name__}: {err}. Fix: see the "
                                 f"traceback above ({self.doc})") from err

    def __repr__(self) -> str:
        return self.name


CHECKS: list[KindCheck] = []


def check(applies: Callable[[SceneKind], bool] = lambda kind: True) -> Callable[[Callable], KindCheck]:
    """Register the decorated function (kind, scenario) as a check (its name and first docstring
    line say what it holds)."""

    def add(fn: Callable[[SceneKind, Scenario], None]) -> KindCheck:
        made = KindCheck(fn.__name__, applies, fn, (fn.__doc__ or "").strip().split("\n")[0])
        CHECKS.append(made)
        return made

    return add


def fail(why: str, fix: str) -> NoReturn:
    raise KindCheckError(f"{why}. Fix: {fix}")


def expect(ok: Any, why: str, fix: str) -> None:
    if not ok:
        fail(why, fix)


# ---------------------------------------------------------------------------- what a check builds
def _entry(kind: SceneKind | str) -> SceneKind:
    if isinstance(kind, SceneKind):
        return kind
    try:
        return KINDS[kind]
    except KeyError:
        raise KindCheckError(f"{kind!r}: no registered scene kind of that name (registered: {', '.join(KINDS)}); "
                             "register it first (KINDS.register(SceneKind(...)), or a shoal.plugins entry "
                             "point)") from None


def presets_of(kind: SceneKind | str) -> list[str]:
    """The presets (shipped and the plug-ins') whose scenario is this kind, in name order."""
    name = _entry(kind).name
    return [p for p in list_presets() if kind_for(load(p)).name == name]


def example_of(kind: SceneKind | str) -> str:
    """The preset that shows ``kind``: its entry's ``example``, else its first preset."""
    entry = _entry(kind)
    if entry.example is not None:
        return entry.example
    found = presets_of(entry)
    if not found:
        fail(f"no preset is a {entry.label}", "ship one (a plug-in: add_presets(folder) in its register()) and "
             "name it in the entry's example=")
    return found[0]


def example_presets() -> dict[str, str]:
    """Kind name → the preset that shows it, for every registered kind (the tests that run every kind)."""
    return {k.name: example_of(k) for k in KINDS.values()}


def variant_presets() -> dict[str, str]:
    """One preset for each robot cap of each registered kind (the kinds of scene a browser tab
    tells apart: a fleet in pymunk physics, a swarm on SLO positions, …), preset → the cap's
    label; each kind's example first."""
    out: dict[str, str] = {}
    for kind in KINDS.values():
        seen: set[str] = set()
        for name in dict.fromkeys([example_of(kind), *presets_of(kind)]):
            label = kind.cap(load(name)).label
            if label not in seen:
                seen.add(label)
                out[name] = label
    return out


@functools.lru_cache(maxsize=32)
def _scenario(kind_name: str, preset: str) -> Scenario:
    return load(preset)


def scenario_of(kind: SceneKind | str) -> Scenario:
    """The example preset of ``kind``, validated."""
    entry = _entry(kind)
    name = example_of(entry)
    try:
        return _scenario(entry.name, name)
    except PresetError as err:
        fail(f"its example preset {name!r} does not load ({err})",
             "ship the preset (a plug-in: add_presets(folder) in its register()) and name it in example=")


def engine_of(kind: SceneKind | str, scenario: Scenario | None = None, *, runs: int = RUNS, seed: int = SEED,
              first_run: int = 0) -> Engine:
    """A new engine of ``scenario`` (default: ``kind``'s example preset)."""
    sc = scenario if scenario is not None else scenario_of(kind)
    return _entry(kind).build(sc, runs=runs, seed=seed, first_run=first_run)


def _stepped(engine: Engine, steps: int = STEPS) -> list[dict[str, np.ndarray]]:
    """The metric rows of ``steps`` ticks (step 0 first)."""
    rows = [metric_table(engine.state, engine.info(), engine.t)]
    for _ in range(steps):
        rows.append(metric_table(engine.state, engine.step(), engine.t))
    return rows


def _same(a: Any, b: Any) -> bool:
    return np.array_equal(np.asarray(a), np.asarray(b), equal_nan=True)


def _same_runs(a: Engine, b: Engine, rows_a: list, rows_b: list) -> str | None:
    """None if two engines are at the same state with the same rows, else what differs."""
    for name in ("x", "u", "status"):
        if not _same(getattr(a.state, name), getattr(b.state, name)):
            return f"state.{name}"
    for i, (ra, rb) in enumerate(zip(rows_a, rows_b)):
        for col in ra:
            if col not in rb or not _same(ra[col], rb[col]):
                return f"the metric {col!r} at step {i}"
    return None


def live_change(kind: SceneKind | str, scenario: Scenario | None = None) -> dict[str, Any] | None:
    """A change of one of the kind's live fields (dotted path → value) that its running engine takes
    without a rebuild: a number a tenth away from its value, inside the model's range; None if no
    live field has a number that can move."""
    entry = _entry(kind)
    sc = scenario if scenario is not None else scenario_of(entry)
    if entry.live is None:
        return None
    data = sc.model_dump(mode="json")
    for path, value in _numbers(data):
        if not any(path == f or path.startswith(f + ".") for f in entry.live.fields) or \
                any(path == f or path.startswith(f + ".") for f in entry.live.fixed):
            continue
        for new in (value * 0.9, value * 1.1, value + 0.1, value - 0.1):
            new = type(value)(round(new)) if isinstance(value, int) else new
            if new == value:
                continue
            try:
                changed = validate(_with(data, path, new))
            except PresetError:
                continue
            if entry.live_keywords(sc, changed) is not None:
                return {path: new}
    return None


def _numbers(data: dict[str, Any], prefix: str = "") -> Iterable[tuple[str, float]]:
    for key, value in data.items():
        if isinstance(value, dict):
            yield from _numbers(value, f"{prefix}{key}.")
        elif isinstance(value, (int, float)) and not isinstance(value, bool):
            yield f"{prefix}{key}", value


def _with(data: dict[str, Any], path: str, value: Any) -> dict[str, Any]:
    import copy

    out = copy.deepcopy(data)
    node = out
    *parents, last = path.split(".")
    for part in parents:
        node = node[part]
    node[last] = value
    return out


def _is_field(path: str, kind: SceneKind) -> bool:
    """Is ``path`` a section (``"controller"``) or a dotted field (``"sim.robots"``) of a scenario?"""
    section, *names = path.split(".")
    field = Scenario.model_fields.get(section)
    if field is not None:
        model: Any = next((a for a in (field.annotation, *getattr(field.annotation, "__args__", ()))
                           if isinstance(a, type) and issubclass(a, BaseModel)), None)
    elif section == kind.section:
        model = kind.section_model
    else:
        return False
    for name in names:
        if model is None or name not in model.model_fields:
            return False
        annotation = model.model_fields[name].annotation
        model = annotation if isinstance(annotation, type) and issubclass(annotation, BaseModel) else None
    return True


# ---------------------------------------------------------------------------- the checks
@check()
def check_entry(kind: SceneKind, sc: Scenario) -> None:
    """The entry resolves: an Engine class with COLUMNS and LIVE, a builder, a section model where needed."""
    try:
        engine = kind.engine_class
    except (ImportError, AttributeError, ValueError) as err:
        fail(f"engine {kind.engine!r} does not resolve ({err})", "give the class, or 'package.module:Class'")
    expect(isinstance(getattr(engine, "COLUMNS", None), tuple) and all(isinstance(c, Column) for c in engine.COLUMNS),
           f"{engine.__name__}.COLUMNS is not a tuple of Column", "declare COLUMNS = (Column(name, unit, dtype, "
           "description), ...) on the class, one for each of Info.columns()")
    expect(isinstance(getattr(engine, "LIVE", None), frozenset), f"{engine.__name__}.LIVE is not a frozenset",
           "declare LIVE = frozenset({...}): the keywords retune accepts (frozenset() for none)")
    try:
        expect(callable(resolve(kind.builder)), "its builder is not callable", "give a function scenario -> engine")
    except (ImportError, AttributeError, ValueError) as err:
        fail(f"builder {kind.builder!r} does not resolve ({err})", "give the function, or 'package.module:name'")
    if kind.section is not None and kind.section not in Scenario.model_fields:
        expect(kind.section_model is not None, f"[{kind.section}] is no Scenario field and the entry has no model",
               "give model=YourSection (a pydantic model) so that presets can validate the section")


@check()
def check_declared_columns(kind: SceneKind, sc: Scenario) -> None:
    """Its headline, labelled and hidden columns are columns of its metric table."""
    names = {c.name for c in kind.columns}
    for what, declared in (("headline", kind.headlines), ("labels", tuple(kind.labels)), ("hidden", kind.hidden)):
        unknown = sorted(set(declared) - names)
        expect(not unknown, f"{what} names {unknown}, not among its columns {sorted(names)}",
               f"name columns of COLUMNS (or the common ones) in {what}=")
    for part, columns in kind.scene_parts.items():
        expect(isinstance(columns, int) and columns >= 1, f"scene part {part!r} has {columns!r} numbers a row",
               "declare scene_parts={name: numbers in one row, at least 1}")


@check()
def check_scenario_kind(kind: SceneKind, sc: Scenario) -> None:
    """The scenario it is checked on (its example preset) is a scenario of this kind."""
    expect(kind_for(sc).name == kind.name, f"{sc.name!r} is a {kind_for(sc).label}",
           "check it on a preset that sets this kind's section (example=), or fix the entry's detect")


@check()
def check_contract(kind: SceneKind, sc: Scenario) -> None:
    """The engine offers the contract: runs, seed, first_run, state arrays (R, N, …), dt, t, robots."""
    e = engine_of(kind, sc)
    expect(isinstance(e, Engine), f"{type(e).__name__} lacks part of the Engine protocol",
           "offer runs, seed, first_run, state, dt, t, robots, reset, step, info, retune, LIVE and COLUMNS")
    expect(type(e) is kind.engine_class, f"its builder made a {type(e).__name__}, the entry names "
           f"{kind.engine_class.__name__}", "make the builder return the entry's engine class")
    expect((e.runs, e.seed, e.first_run) == (RUNS, SEED, 0), f"built with runs={RUNS}, seed={SEED}: it says "
           f"runs={e.runs}, seed={e.seed}, first_run={e.first_run}", "take runs, seed and first_run from the builder")
    s = e.state
    expect(isinstance(s, State), "its state lacks k, x, u, heading or status", "give the state those arrays")
    R, N = RUNS, e.robots
    expect(s.x.ndim == 3 and s.x.shape[:2] == (R, N) and s.u.shape == s.x.shape, f"state.x {s.x.shape}, u "
           f"{s.u.shape}: expected (runs, robots, d) = ({R}, {N}, d)", "keep run-major arrays (R, N, d)")
    expect(np.shape(s.heading) == (R, N) and np.shape(s.status) == (R, N), f"heading {np.shape(s.heading)}, "
           f"status {np.shape(s.status)}: expected ({R}, {N})", "one heading and one status per robot and run")
    expect(s.k == 0 and e.t == 0.0 and e.dt > 0, f"a new engine is at k={s.k}, t={e.t}, dt={e.dt}",
           "start at step 0, time 0, with dt > 0")


@check()
def check_info_before_the_first_tick(kind: SceneKind, sc: Scenario) -> None:
    """info() works at step 0 and gives the COLUMNS, one value per run."""
    e = engine_of(kind, sc)
    info = e.info()
    expect(isinstance(info, Info) and info.t == 0.0, "info() before the first tick is no Info at t = 0",
           "give the metrics of the initial state (NaN where a value needs a tick)")
    _columns_match(kind, info)


@check()
def check_columns(kind: SceneKind, sc: Scenario) -> None:
    """After a tick, Info.columns() is COLUMNS in order, each (runs,), and the metric table is the entry's columns."""
    e = engine_of(kind, sc)
    info = e.step()
    expect(e.state.k == 1 and e.t == e.dt and info.t == e.t, f"after one step: k={e.state.k}, t={e.t}, info.t="
           f"{info.t}", "advance k by one and t by dt each step")
    _columns_match(kind, info)
    table = metric_table(e.state, info, e.t)
    expect(list(table) == [c.name for c in kind.columns], f"the metric table is {list(table)}, the entry's columns "
           f"{[c.name for c in kind.columns]}", "keep optimises= true to the state (best_fitness) and COLUMNS to "
           "Info.columns()")


def _columns_match(kind: SceneKind, info: Info) -> None:
    cols = info.columns()
    want = [c.name for c in kind.engine_class.COLUMNS]
    expect(list(cols) == want, f"Info.columns() gives {list(cols)}, COLUMNS declares {want}",
           "list the same columns in the same order")
    for c in kind.engine_class.COLUMNS:
        value = np.asarray(cols[c.name])
        expect(value.shape == (RUNS,), f"column {c.name!r} has shape {value.shape}", f"one value per run: ({RUNS},)")
        if c.dtype == "int":
            whole = np.isfinite(value) & (value == np.round(value))
            expect(whole.all(), f"int column {c.name!r} holds {value}", "give whole numbers, or declare it 'float'")
        expect(bool(c.description) and c.unit is not None, f"column {c.name!r} has no description",
               "describe it (docs/data-dictionary.md is written from it)")


@check(lambda kind: kind.optimises)
def check_best_fitness(kind: SceneKind, sc: Scenario) -> None:
    """A kind that optimises keeps best_fitness (runs,) in its state and its metric table, never NaN."""
    e = engine_of(kind, sc)
    rows = _stepped(e)
    expect("best_fitness" in rows[-1] and np.shape(getattr(e.state, "best_fitness", ())) == (RUNS,),
           "it declares optimises=True but its state has no best_fitness (runs,)",
           "keep state.best_fitness, or declare optimises=False")
    best = np.array([r["best_fitness"] for r in rows], dtype=float)
    expect(not np.isnan(best).any(), f"best_fitness is NaN: {best.tolist()}", "never take NaN as a best")


@check(lambda kind: not kind.optimises)
def check_no_best_fitness(kind: SceneKind, sc: Scenario) -> None:
    """A kind that optimises nothing has no best_fitness, in its state or its metric table."""
    e = engine_of(kind, sc)
    expect(not hasattr(e.state, "best_fitness"), "it declares optimises=False but its state has best_fitness",
           "declare optimises=True, or drop state.best_fitness")


@check()
def check_determinism(kind: SceneKind, sc: Scenario) -> None:
    """The same seed gives the same run, bit for bit; another seed another one."""
    a, b, c = engine_of(kind, sc), engine_of(kind, sc), engine_of(kind, sc, seed=SEED + 1)
    ra, rb = _stepped(a), _stepped(b)
    _stepped(c)
    differs = _same_runs(a, b, ra, rb)
    expect(differs is None, f"two engines of seed {SEED} differ in {differs}",
           "draw every random number from the run's generator (shoal.engine.core.rng.run_generators)")
    expect(not _same(a.state.x, c.state.x), f"seeds {SEED} and {SEED + 1} give the same positions",
           "seed the generators from the engine's seed")


@check()
def check_run_alone(kind: SceneKind, sc: Scenario) -> None:
    """Run i of a batch is the run first_run = i alone."""
    batch, alone = engine_of(kind, sc), engine_of(kind, sc, runs=1, first_run=1)
    _stepped(batch), _stepped(alone)
    expect(_same(batch.state.x[1:], alone.state.x), "run 1 of a batch of 2 is not the run first_run=1 alone",
           "give run i child i of SeedSequence(seed) (run_generators(seed, first_run, runs)) and no shared draws")


@check()
def check_reset(kind: SceneKind, sc: Scenario) -> None:
    """reset(seed) is a new engine of that seed, and steps like one."""
    e, fresh = engine_of(kind, sc), engine_of(kind, sc, seed=SEED + 1)
    _stepped(e)
    e.reset(SEED + 1)
    expect(e.state.k == 0 and e.seed == SEED + 1 and e.t == 0.0, f"after reset(seed): k={e.state.k}, seed={e.seed}",
           "reset to step 0 with the new seed")
    differs = _same_runs(e, fresh, _stepped(e), _stepped(fresh))
    expect(differs is None, f"after reset(seed) the run differs from a new engine of that seed in {differs}",
           "reset every array, counter and generator")


@check()
def check_retune_refuses_unknown_keywords(kind: SceneKind, sc: Scenario) -> None:
    """retune refuses a keyword outside LIVE (and runs), naming it, and changes nothing."""
    e, twin = engine_of(kind, sc), engine_of(kind, sc)
    for bad in ({"no_such_setting": 1.0}, {"runs": 5}):
        try:
            e.retune(**bad)
        except ValueError as err:
            expect(next(iter(bad)) in str(err), f"retune({next(iter(bad))}=...) refused without naming it: {err}",
                   "name the keyword (shoal.engine.core.contract.check_live)")
        else:
            fail(f"retune({next(iter(bad))}=...) was accepted", "check the keywords against LIVE first "
                 "(shoal.engine.core.contract.check_live) and raise ValueError")
    differs = _same_runs(e, twin, _stepped(e), _stepped(twin))
    expect(differs is None, f"a refused retune changed the run ({differs})",
           "check everything before changing anything")


@check(lambda kind: kind.live is not None)
def check_live_rule(kind: SceneKind, sc: Scenario) -> None:
    """Its live rule names fields and gives LIVE keywords; an unchanged scenario changes nothing; a new seed
    needs a new engine."""
    assert kind.live is not None
    keywords = kind.live_keywords(sc, sc)
    expect(keywords is not None, "its live rule refuses a scenario changed in nothing", "let a no-change through")
    assert keywords is not None
    e = engine_of(kind, sc)
    outside = sorted(set(keywords) - set(e.LIVE))
    expect(not outside, f"its live rule gives {outside}, not in {type(e).__name__}.LIVE",
           "give only LIVE keywords from Live.keywords")
    expect(e.retune(**keywords) == [], "retune with the scenario's own values reports changes",
           "report only what changed")
    reseeded = sc.model_copy(update={"sim": sc.sim.model_copy(update={"seed": sc.sim.seed + 1})})
    expect(kind.live_keywords(sc, reseeded) is None, "its live rule takes a new sim.seed live",
           "leave sim.seed out of Live.fields (a new seed is a new engine)")
    for path in (*kind.live.fields, *kind.live.fixed, *kind.live.ignores):
        expect(_is_field(path, kind), f"its Live rule names {path!r}, no section or field of a scenario",
               "name sections or dotted fields of the preset model")


@check(lambda kind: kind.live is not None)
def check_live_change(kind: SceneKind, sc: Scenario) -> None:
    """A change of a live field reaches the running engine (retune reports it) without a new engine."""
    change = live_change(kind, sc)
    expect(change is not None, "no number among its Live.fields can change live",
           "list fields whose change retune takes, or declare live=None")
    assert change is not None
    new = validate(_with(sc.model_dump(mode="json"), *next(iter(change.items()))))
    keywords = kind.live_keywords(sc, new)
    assert keywords is not None
    e = engine_of(kind, sc)
    e.step()
    expect(e.retune(**keywords) != [], f"{change} passed the live rule, but retune changed nothing",
           "map that field to its retune keyword in Live.keywords, or list it in Live.fixed")


@check(lambda kind: callable(getattr(kind.engine_class, "snapshot", None)))
def check_snapshot(kind: SceneKind, sc: Scenario) -> None:
    """A snapshot taken at a step and restored (through its bytes) goes on with the same bits."""
    sc = api_scenario(sc, runs=RUNS, seed=SEED)
    a = Scene(sc)
    a.step(2)
    b = Scene.from_snapshot(a.snapshot().to_bytes())
    a.step(STEPS), b.step(STEPS)
    differs = _same_runs(a.engine, b.engine, [a.row()], [b.row()])
    expect(differs is None, f"restored from its snapshot, the run differs in {differs}",
           "put every array, counter and generator state in snapshot() and back in restore()")


@check(lambda kind: kind.app is not None)
def check_app(kind: SceneKind, sc: Scenario) -> None:
    """Its app module's KIND shows it: a session builds, steps, draws and records its scene parts."""
    from shoal.app.kinds.base import AppKind

    assert kind.app is not None
    try:
        app = getattr(importlib.import_module(kind.app), "KIND", None)
    except ImportError as err:
        fail(f"its app module {kind.app!r} does not import ({err})", "install it, or set app=None (headless only)")
    if not isinstance(app, AppKind) or app.engine != kind.name:
        fail(f"{kind.app}.KIND is not an AppKind of engine {kind.name!r}",
             f"define KIND = AppKind(..., engine={kind.name!r}, ...) there")
    session = app.session(sc)
    session.step(3)
    snap = session.snapshot()
    expect(snap.x.shape[0] == session.sim.robots, "the session's snapshot has another number of robots",
           "draw the engine's robots")
    parts = session.driver.frame(session.clock()).scene
    unknown = sorted(set(parts) - set(kind.scene_parts))
    expect(not unknown, f"its driver's frames hold scene parts {unknown} the entry does not declare",
           "declare them in scene_parts={name: numbers a row} (a replay stores them)")
    for part, rows in parts.items():
        expect(np.ndim(rows) == 2 and np.shape(rows)[1] == kind.scene_parts[part],
               f"scene part {part!r} is {np.shape(rows)}, declared {kind.scene_parts[part]} a row",
               "give one row of the declared numbers per item")


# ---------------------------------------------------------------------------- the entry points
def checks_for(kind: SceneKind | str) -> list[KindCheck]:
    """The checks that apply to ``kind``, by what its entry declares."""
    entry = _entry(kind)
    return [c for c in CHECKS if c.applies(entry)]


def check_kind(kind: SceneKind | str, scenario: Scenario | None = None, *, skip: Iterable[str] = ()) -> list[str]:
    """Run every check that applies to ``kind`` on ``scenario`` (default: its example preset), but
    those named in ``skip``; the names of those run. Raises :class:`KindCheckError` listing every
    check that fails, each with what to fix."""
    entry = _entry(kind)
    skipped = set(skip)
    failures, ran = [], []
    for c in checks_for(entry):
        if c.name in skipped:
            continue
        ran.append(c.name)
        try:
            c(entry, scenario)
        except KindCheckError as err:
            failures.append(str(err))
    if failures:
        raise KindCheckError(f"{len(failures)} of {len(ran)} checks fail:\n" + "\n".join(failures))
    return ran


def parametrize_with_kinds(kinds: Iterable[SceneKind | str] | None = None) -> Any:
    """A ``pytest.mark.parametrize("kind, check", ...)`` over every check that applies to each of
    ``kinds`` (default: every registered kind), with ids ``<kind>-<check>``: the test body is
    ``check(kind)``."""
    import pytest

    entries = [_entry(k) for k in (KINDS.values() if kinds is None else kinds)]
    pairs = [(k, c) for k in entries for c in checks_for(k)]
    return pytest.mark.parametrize("kind, check", pairs, ids=[f"{k.name}-{c.name}" for k, c in pairs])
