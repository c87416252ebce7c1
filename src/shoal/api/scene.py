"""A scene as a Python object: :func:`make` builds one from a preset name, a file, a dict or a
:class:`~shoal.presets.models.Scenario`, with keyword overrides; :class:`Scene` steps it, reads
its state and metrics, retunes it live and collects its metrics as a table.

    scene = shoal.make("course-dvc", runs=4, seed=7, controller={"alpha": 0.8})
    scene.run(200)                       # advance 200 ticks, recording a metric row per run and tick
    scene.retune(controller={"beta": 0.5})
    table = scene.metrics()              # pandas DataFrame (or numpy record array): metrics.csv's rows
"""

from __future__ import annotations

import copy
import dataclasses
from pathlib import Path
from typing import Any, Callable, Mapping, Sequence

import numpy as np

from shoal.engine.core.contract import Engine, Info, State
from shoal.engine.core.objectives import OBJECTIVES, ObjectiveFunction
from shoal.engine.core.recorder import TRAJECTORY_COLUMNS, TRAJECTORY_SCHEMA, metric_table, trajectory_rows
from shoal.engine.core.schema import Schema
from shoal.presets.io import PresetError, apply_overrides, read_raw, set_dotted, to_toml, validate
from shoal.presets.kinds import KINDS, SceneKind, kind_for, plugin_sections
from shoal.presets.models import Scenario

from .snapshot import Snapshot, SnapshotError, snapshot_of, write_atomically
from .tables import as_table

SIM_KEYWORDS = ("runs", "seed", "steps", "robots", "d")  # make(..., runs=4) sets sim.runs


def scenario_of(preset: str | Path | Mapping[str, Any] | Scenario = "default", overrides: Sequence[str] = (),
                **sections: Any) -> Scenario:
    """A validated scenario: ``preset`` (a shipped name, a TOML/JSON file, a raw dict or a
    scenario) with ``overrides`` (``"dotted.key=value"`` strings, as ``--set``) and keyword
    overrides: ``runs``, ``seed``, ``steps``, ``robots`` and ``d`` set ``sim``'s fields, any other
    keyword is a section, given as a dict of fields (``controller={"alpha": 0.8}``) or, for
    ``objective``, a name or a vectorised function (registered under its ``__name__``)."""
    if isinstance(preset, Scenario):
        raw = preset.model_dump(mode="json")
    elif isinstance(preset, Mapping):
        raw = copy.deepcopy(dict(preset))
    else:
        raw = read_raw(preset)
    raw = apply_overrides(raw, list(overrides))
    for key, value in sections.items():
        if key in SIM_KEYWORDS:
            set_dotted(raw, f"sim.{key}", value)
        elif key == "objective" and (callable(value) or isinstance(value, str)):
            set_dotted(raw, "objective.kind", _objective_name(value))
        elif isinstance(value, Mapping):
            for field, v in value.items():
                set_dotted(raw, f"{key}.{field}", _objective_name(v) if (key, field) == ("objective", "kind") else v)
        else:
            raise PresetError([f"{key}: give a section as a dict of its fields (e.g. {key}={{...}}), got "
                               f"{type(value).__name__}"])
    return validate(raw)


def _objective_name(value: Any) -> Any:
    """A function given as an objective: its registered name. A function met for the first time is
    registered under its ``__name__`` or, where another objective holds that (a built-in
    ``rastrigin``, another module's function), under ``module.qualname``; a function with the
    module and qualname of one registered so (a notebook cell run again) replaces it, so scenes
    made from then on, and those already made from their next tick, use the new definition."""
    if not callable(value):
        return value
    for name, entry in OBJECTIVES.items():
        if entry.f is value:
            return name
    bare = getattr(value, "__name__", "")
    if not bare or bare == "<lambda>":
        raise PresetError(["objective: register a lambda first (shoal.register_objective(name, f)) or pass a "
                           "named function"])
    origin = _origin(value)
    names = (bare, ".".join(p for p in origin if p))
    for name in names:
        found = OBJECTIVES.get(name)
        if found is None:
            OBJECTIVES.register(ObjectiveFunction(name, name, value))
            return name
        if _origin(found.f) == origin:  # the same function, defined again
            OBJECTIVES.register(dataclasses.replace(found, f=value), replace=True)
            return name
    raise ValueError(f"objective: {names[0]!r} and {names[1]!r} name other objectives already; register yours under "
                     "a name of its own (shoal.register_objective(name, f)) and give that name")


def _origin(f: Any) -> tuple[str, str]:
    """Where a function was defined: its module and qualified name (a numba dispatcher's, its Python function's)."""
    f = getattr(f, "py_func", f)
    qualname = getattr(f, "__qualname__", None) or getattr(f, "__name__", "")
    return str(getattr(f, "__module__", None) or ""), str(qualname)


def make(preset: str | Path | Mapping[str, Any] | Scenario = "default", overrides: Sequence[str] = (), *,
         snapshot: Snapshot | bytes | str | Path | None = None, trajectories: bool = False, **sections: Any) -> Scene:
    """A :class:`Scene` of ``preset`` with overrides (see :func:`scenario_of`), at step 0; or, with
    ``snapshot`` (a :class:`~shoal.api.snapshot.Snapshot`, its bytes or a saved file's path), the
    scene it was taken of, at its step, going on with the same bits.

    >>> scene = make("default", runs=2, seed=7, controller={"mode": "raw", "omega": 0.6})
    >>> scene.step().t
    0.1
    """
    if snapshot is not None:
        if preset != "default" or overrides or sections:
            raise ValueError("make: give a snapshot or a preset with overrides, not both (a snapshot holds its "
                             "scenario; retune the scene it gives)")
        return Scene.from_snapshot(snapshot, trajectories=trajectories or None)
    return Scene(scenario_of(preset, overrides, **sections), trajectories=trajectories)


class Scene:
    """One scenario's engine: ``runs`` seeded runs of its scene kind, stepped together.

    Every step records one metric row per run (the columns of ``metrics.csv``); :meth:`metrics`
    gives them as a table. ``record=False`` keeps none (for long runs where only the end matters).
    """

    def __init__(self, scenario: Scenario, *, record: bool = True, trajectories: bool = False) -> None:
        self.scenario = scenario
        self.kind: SceneKind = kind_for(scenario)
        self.engine: Engine = self.kind.build(scenario)
        self.record = record
        self.keep_trajectories = trajectories
        self._rows: list[dict[str, np.ndarray]] = []
        self._paths: list[np.ndarray] = []  # trajectory rows of each step, (runs × robots, columns)
        self._detached: set[str] = set()  # engine keywords retuned that the scenario does not hold
        self._note(self.engine.info())

    # ------------------------------------------------------------------ keeping
    def snapshot(self, *, metrics: bool = True) -> Snapshot:
        """This scene now, to go on from later or elsewhere (``shoal.make(snapshot=...)``) with the
        same bits: the scenario, the engine's whole state (every generator included) and, with
        ``metrics``, the rows recorded so far. ``snapshot().to_bytes()`` is an ``.npz`` archive, no
        pickle. The scene is not changed."""
        take = getattr(self.engine, "snapshot", None)
        if take is None:
            raise SnapshotError(f"the {self.kind.label} engine ({type(self.engine).__name__}) offers no snapshot()")
        if self._detached:
            raise SnapshotError(f"snapshot: {', '.join(sorted(self._detached))} were retuned as engine keywords, which "
                                "the scenario does not hold; retune them as preset sections "
                                "(e.g. controller={...}) to keep this scene")
        rows = paths = None
        if metrics and self.record and self._rows:
            rows = {n: np.stack([np.asarray(r[n]) for r in self._rows]) for n in self._rows[-1]}
        if metrics and self.keep_trajectories and self._paths:
            paths = np.stack(self._paths)
        return Snapshot(self.scenario, self.kind.name, self.k, take(), rows, trajectories=paths)

    @classmethod
    def from_snapshot(cls, snapshot: Snapshot | bytes | str | Path, *, record: bool = True,
                      trajectories: bool | None = None) -> Scene:
        """The scene ``snapshot`` was taken of, at its step (see :meth:`snapshot`); it keeps
        trajectories if the snapshot holds some (or as ``trajectories`` says)."""
        snap = snapshot_of(snapshot)
        keep = snap.trajectories is not None if trajectories is None else trajectories
        scene = cls(snap.scenario, record=record, trajectories=keep)
        if scene.kind.name != snap.kind:
            raise SnapshotError(f"snapshot: of a {snap.kind!r} scene, but its scenario builds a "
                                f"{scene.kind.name!r} one")
        restore = getattr(scene.engine, "restore", None)
        if restore is None:
            raise SnapshotError(f"the {scene.kind.label} engine ({type(scene.engine).__name__}) offers no restore()")
        restore(snap.engine)
        if scene.k != snap.k:
            raise SnapshotError(f"snapshot: its engine is at step {scene.k}, its header says {snap.k}")
        scene._rows = []
        if record and snap.rows is not None:
            names = list(snap.rows)
            steps = snap.rows[names[0]].shape[0] if names else 0
            scene._rows = [{n: snap.rows[n][i].copy() for n in names} for i in range(steps)]
        scene._paths = list(snap.trajectories) if keep and snap.trajectories is not None else []
        if record and not scene._rows:  # a snapshot taken without its history: this step's rows
            scene._rows = [{k: np.array(v, copy=True) for k, v in scene.row().items()}]
        if keep and not scene._paths:
            scene._paths = [trajectory_rows(scene.engine.state, scene.engine.t)]
        return scene

    # ------------------------------------------------------------------ reading
    @property
    def state(self) -> State:
        """The engine's state: ``x``, ``u`` (runs, robots, d), ``heading``, ``status`` (runs, robots), ``k``."""
        return self.engine.state

    @property
    def t(self) -> float:
        return self.engine.t

    @property
    def k(self) -> int:
        return self.engine.state.k

    @property
    def columns(self) -> Schema:
        """The metric columns (name, unit, dtype, description), in order."""
        return self.kind.columns

    def info(self) -> Info:
        """The engine's metrics of the current step."""
        return self.engine.info()

    def row(self) -> dict[str, np.ndarray]:
        """The current step's metrics, one value per run in each column."""
        return metric_table(self.engine.state, self.engine.info(), self.engine.t)

    def metrics(self, *, pandas: bool | None = None) -> Any:
        """Every recorded step's metrics, one row per run and step (step 0 first): a pandas
        DataFrame when pandas is installed, else a numpy record array (``pandas`` forces either)."""
        rows = self._rows or [self.row()]
        names = list(rows[-1])
        return as_table({n: np.concatenate([np.asarray(r[n]) for r in rows]) for n in names}, pandas=pandas)

    # ------------------------------------------------------------------ stepping
    def step(self, n: int = 1) -> Info:
        """Advance every run by ``n`` control ticks; the last tick's :class:`Info`."""
        if n < 1:
            raise ValueError(f"n: must be >= 1, got {n}")
        info = self.engine.info()
        for _ in range(n):
            info = self.engine.step()
            self._note(info)
        return info

    def run(self, steps: int | None = None, *, until: Callable[[Scene], bool] | None = None) -> Any:
        """Advance ``steps`` ticks (default: the preset's ``sim.steps`` less those done), stopping
        early once ``until(scene)`` is true; the recorded metrics as a table."""
        left = max(self.scenario.sim.steps - self.k, 0) if steps is None else steps
        for _ in range(left):
            self._note(self.engine.step())
            if until is not None and until(self):
                break
        return self.metrics()

    def reset(self, seed: int | None = None) -> None:
        """Back to step 0 (with ``seed``, or the current one); the recorded metrics start again."""
        self.engine.reset(seed)
        self._rows, self._paths = [], []
        self._note(self.engine.info())

    def _note(self, info: Info) -> None:
        if self.record:
            self._rows.append({k: np.array(v, copy=True) for k, v in
                               metric_table(self.engine.state, info, self.engine.t).items()})
        if self.keep_trajectories:
            self._paths.append(trajectory_rows(self.engine.state, self.engine.t))

    def trajectories(self, *, pandas: bool | None = None) -> Any:
        """Every robot at every recorded step, one row per run, step and robot (step 0 first): the
        columns ``shoal run`` writes to ``trajectories.csv`` (``run, step, t, robot, x, y, heading,
        vx, vy, status``, and ``z, vz`` in three or more dimensions), as a table. The scene keeps
        them when made with ``trajectories=True`` (``shoal.make(..., trajectories=True)``)."""
        if not self.keep_trajectories:
            raise ValueError("trajectories: this scene keeps none; make it with shoal.make(..., trajectories=True)")
        rows = np.concatenate(self._paths or [trajectory_rows(self.engine.state, self.engine.t)])
        names = [*TRAJECTORY_COLUMNS, *(("z", "vz") if rows.shape[1] > len(TRAJECTORY_COLUMNS) else ())]
        whole = {c.name for c in TRAJECTORY_SCHEMA if c.dtype == "int"}
        return as_table({n: rows[:, i].astype(np.int64) if n in whole else rows[:, i] for i, n in enumerate(names)},
                        pandas=pandas)

    # ------------------------------------------------------------------ pickle
    def __getstate__(self) -> dict[str, Any]:
        """A scene pickles with its kind by name (the registry entry stays in the registry)."""
        state = dict(self.__dict__)
        state["kind"] = self.kind.name
        return state

    def __setstate__(self, state: dict[str, Any]) -> None:
        name = state["kind"]
        if name not in KINDS:
            raise ValueError(f"scene kind {name!r} is not registered here (install or register its plug-in)")
        self.__dict__.update(state, kind=KINDS[name])

    def save_preset(self, path: str | Path, *, overwrite: bool = False) -> Path:
        """Write :attr:`scenario` as a TOML preset that loads back to an equal scenario
        (``shoal.make(path)``), completely or not at all; an existing file is kept unless
        ``overwrite``. Engine-keyword retunes are not in the scenario (see :meth:`snapshot`)."""
        path = Path(path)
        if path.exists() and not overwrite:
            raise FileExistsError(f"{path}: exists already (pass overwrite=True to replace it)")
        write_atomically(path, to_toml(self.scenario).encode("utf-8"))
        return path

    # ------------------------------------------------------------------ changing
    def retune(self, **changes: Any) -> list[str]:
        """Change the running scene from the next tick on; the names that changed.

        Preset sections as dicts of their fields (``controller={"alpha": 0.5}``, ``slo={"errors":
        "high"}``): validated like a preset, taken by the running engine where the kind's live
        rule allows it (:meth:`~shoal.presets.kinds.SceneKind.live_keywords`, the rule the app
        follows), and :attr:`scenario` follows. Or the engine's own keywords (its ``LIVE`` set,
        e.g. ``alpha=0.5`` for a fleet), passed as they are: :attr:`scenario` then still says
        what the scene was made from. A change the running engine cannot take (another world, a
        dimension, …) or an unknown keyword is refused with a ``ValueError`` and nothing changes:
        make a new scene for it."""
        section_names = {*type(self.scenario).model_fields, *plugin_sections()}
        sections = {k: v for k, v in changes.items() if isinstance(v, Mapping) and k in section_names}
        engine_keywords = {k: v for k, v in changes.items() if k not in sections}
        if sections and engine_keywords:
            raise ValueError("retune: give preset sections or engine keywords, not both in one call")
        if engine_keywords:
            changed = self.engine.retune(**engine_keywords)
            self._detached.update(changed)
            return changed
        new = scenario_of(self.scenario, (), **sections)
        live = self.kind.live_keywords(self.scenario, new) if kind_for(new) is self.kind else None
        if live is None:
            raise ValueError(f"{', '.join(sections)}: this change needs a new engine (cannot change mid-run); "
                             "make a new scene with shoal.make")
        changed = self.engine.retune(**live)
        self.scenario = new
        return changed

    def __repr__(self) -> str:
        return (f"<Scene {self.scenario.name!r}: {self.kind.label}, {self.engine.runs} run(s) of "
                f"{self.engine.robots} robots, step {self.k}>")
