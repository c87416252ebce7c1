"""The scene-kind conformance kit (``shoal.testing``) on every registered kind, what it catches in
a kind that breaks a rule, and what every kind must bring: a preset, notes and a first-minute
promise. The example plug-in's own tests call the same kit (``examples/plugin/tests``, run by
``tests/test_plugins.py``)."""

from __future__ import annotations

from dataclasses import dataclass
from importlib import resources
from typing import Any, ClassVar

import numpy as np
import pytest
from pydantic import BaseModel, ConfigDict

from shoal import testing
from shoal.app.kinds.registry import app_kinds
from shoal.engine.core.contract import check_live
from shoal.engine.core.rng import run_generators
from shoal.engine.core.schema import Column
from shoal.presets.io import list_presets, load, set_dotted, validate
from shoal.presets.kinds import KINDS, Live, SceneKind, kind_for
from shoal.testing import KindCheckError, check_kind, parametrize_with_kinds

from test_first_minute import POINTS


@parametrize_with_kinds()
def test_every_registered_kind_keeps_the_rules(kind, check):
    check(kind)


def one_preset_per_kind_and_positions() -> list[str]:
    """The first preset of each kind on true and on SLO positions (a host swarm's)."""
    out: dict[tuple[str, bool], str] = {}
    for name in list_presets():
        sc = load(name)
        out.setdefault((kind_for(sc).name, sc.slo is not None), name)
    return sorted(out.values())


@pytest.mark.parametrize("preset", [p for p in one_preset_per_kind_and_positions()
                                    if load(p).slo is not None and kind_for(load(p)).name != "slo_swarm"])
def test_host_swarms_on_slo_positions_keep_the_contract(preset):
    sc = load(preset)
    kind = kind_for(sc)
    assert check_kind(kind, sc, skip=("check_app",))  # (the app runs them in test_app_positions.py)


# ---------------------------------------------------------------------------- what it catches
class WalkSection(BaseModel):
    model_config = ConfigDict(extra="forbid")
    speed: float = 1.0


@dataclass
class WalkState:
    x: np.ndarray
    u: np.ndarray
    heading: np.ndarray
    status: np.ndarray
    k: int = 0


@dataclass
class WalkInfo:
    t: float
    spread: np.ndarray

    def columns(self) -> dict[str, np.ndarray]:
        return {"spread": self.spread}


class Walk:
    """A random walk that keeps every rule; its subclasses below break one each."""

    LIVE: ClassVar[frozenset[str]] = frozenset({"speed"})
    COLUMNS: ClassVar[tuple[Column, ...]] = (Column("spread", "m", "float", "spread of the robots"),)
    dt = 0.1

    def __init__(self, speed: float, *, robots: int, runs: int = 1, seed: int = 0, first_run: int = 0) -> None:
        self.speed, self._robots, self.runs, self.first_run = speed, robots, runs, first_run
        self.reset(seed)

    @property
    def t(self) -> float:
        return self.state.k * self.dt

    @property
    def robots(self) -> int:
        return self.state.x.shape[1]

    def reset(self, seed: int | None = None) -> None:
        self.seed = self.seed if seed is None else int(seed)
        self.rngs = run_generators(self.seed, self.first_run, self.runs)
        x = np.stack([g.random((self._robots, 2)) for g in self.rngs])
        self.state = WalkState(x, np.zeros_like(x), np.zeros(x.shape[:2]), np.zeros(x.shape[:2], np.int8))

    def draws(self) -> np.ndarray:
        return np.stack([g.standard_normal((self._robots, 2)) for g in self.rngs])

    def step(self) -> WalkInfo:
        s = self.state
        s.u = self.speed * self.draws()
        s.x = s.x + self.dt * s.u
        s.k += 1
        return self.info()

    def info(self) -> WalkInfo:
        return WalkInfo(self.t, self.state.x.std(axis=(1, 2)))

    def retune(self, **changes: Any) -> list[str]:
        check_live(self.LIVE, changes)
        changed = [k for k, v in changes.items() if v != getattr(self, k)]
        self.speed = changes.get("speed", self.speed)
        return changed


class SharedDraws(Walk):
    """Draws from one generator for the whole batch: run i alone is another run."""

    def draws(self) -> np.ndarray:
        return self.rngs[0].standard_normal((self.runs, self._robots, 2))


class Unseeded(Walk):
    def draws(self) -> np.ndarray:
        return np.random.default_rng().standard_normal((self.runs, self._robots, 2))


class TakesAnything(Walk):
    def retune(self, **changes: Any) -> list[str]:
        self.speed = changes.get("speed", self.speed)
        return list(changes)


class NoInfoAtStart(Walk):
    def info(self) -> WalkInfo:
        if self.state.k == 0:
            raise RuntimeError("no metrics before the first tick")
        return super().info()


class OneValue(Walk):
    def info(self) -> WalkInfo:
        return WalkInfo(self.t, self.state.x.std(axis=(0, 1, 2)))  # one number for all runs


def walk_kind(engine: type[Walk], **entry: Any) -> SceneKind:
    def build(sc: Any, *, runs: int | None = None, seed: int | None = None, first_run: int = 0) -> Walk:
        return engine(sc.section("walk").speed, robots=sc.sim.robots, runs=runs or sc.sim.runs,
                      seed=sc.sim.seed if seed is None else seed, first_run=first_run)

    live = Live(("walk.speed",), lambda old, new: {"speed": new.section("walk").speed})
    return SceneKind("walk", "random walk (test)", engine, build, "walk", model=WalkSection,
                     **{"optimises": False, "live": live, **entry})


def checked(kind: SceneKind) -> str:
    """The message of ``check_kind`` on a scenario of ``kind`` ('' if it passes)."""
    KINDS.register(kind)
    try:
        check_kind(kind, validate({"name": "walk", "walk": {"speed": 1.0}, "sim": {"robots": 5}}))
        return ""
    except KindCheckError as err:
        return str(err)
    finally:
        KINDS.unregister("walk")


def test_a_kind_that_keeps_the_rules_passes():
    assert checked(walk_kind(Walk)) == ""


@pytest.mark.parametrize("engine, entry, check, says", [
    (SharedDraws, {}, "check_run_alone", "run 1 of a batch of 2 is not the run first_run=1 alone"),
    (Unseeded, {}, "check_determinism", "two engines of seed 3 differ in state.x"),
    (TakesAnything, {}, "check_retune_refuses_unknown_keywords", "retune(no_such_setting=...) was accepted"),
    (NoInfoAtStart, {}, "check_info_before_the_first_tick", "no metrics before the first tick"),
    (OneValue, {}, "check_columns", "column 'spread' has shape ()"),
    (Walk, {"optimises": True}, "check_columns", "the metric table is"),
    (Walk, {"headline": ("distance",)}, "check_declared_columns", "headline names ['distance']"),
    (Walk, {"live": Live(("walk.pace",), lambda old, new: {})}, "check_live_rule", "names 'walk.pace'"),
    (Walk, {"live": Live(("walk.speed",), lambda old, new: {})}, "check_live_change", "retune changed nothing"),
])
def test_the_kit_names_the_broken_rule_and_the_fix(engine, entry, check, says):
    message = checked(walk_kind(engine, **entry))
    assert f"walk: {check}: " in message and says in message and "Fix: " in message, message


def test_the_kit_checks_what_the_entry_declares():
    names = {c.name for c in testing.checks_for(walk_kind(Walk))}
    assert "check_no_best_fitness" in names and "check_best_fitness" not in names
    assert "check_snapshot" not in names and "check_app" not in names  # no snapshot(), no app module
    assert {c.name for c in testing.checks_for(KINDS["swarm"])} >= {"check_best_fitness", "check_snapshot",
                                                                     "check_app", "check_live_change"}
    assert "check_live_rule" not in {c.name for c in testing.checks_for(walk_kind(Walk, live=None))}


def test_check_kind_names_an_unknown_kind():
    with pytest.raises(KindCheckError, match="'nosuch': no registered scene kind"):
        check_kind("nosuch")


# ---------------------------------------------------------------------------- what every kind brings
@pytest.mark.parametrize("name", list(KINDS))
def test_every_kind_has_a_preset_notes_and_a_first_minute_promise(name):
    kind = KINDS[name]
    example = testing.example_of(kind)
    assert example in list_presets() and kind_for(load(example)) is kind
    assert testing.presets_of(kind), f"{name}: no shipped preset"
    promised = [p for p in testing.presets_of(kind) if p in POINTS]
    assert example in promised, f"{name}: its example {example!r} has no first-minute promise (test_first_minute.py)"
    app = app_kinds()[name]
    notes = resources.files("shoal.static").joinpath(f"notes/{app.notes}.md")
    assert app.notes and notes.is_file() and len(notes.read_text(encoding="utf-8")) > 200, f"{name}: no teaching notes"


@pytest.mark.parametrize("name", list(KINDS))
def test_a_live_change_is_found_for_every_kind_and_its_rule_takes_it(name):
    kind = KINDS[name]
    change = testing.live_change(kind)
    assert change is not None and kind.live is not None
    (path, value), = change.items()
    sc = testing.scenario_of(kind)
    data = sc.model_dump(mode="json")
    set_dotted(data, path, value)
    assert kind.live_keywords(sc, validate(data)) is not None
    assert any(path == f or path.startswith(f + ".") for f in kind.live.fields)
    set_dotted(data, "sim.seed", sc.sim.seed + 1)
    assert kind.live_keywords(sc, validate(data)) is None  # a new seed: a new engine
