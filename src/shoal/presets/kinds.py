"""The scene kinds, one registry entry each: everything Shoal needs to know about a kind, said
once.

A :class:`SceneKind` names its engine class (whose ``COLUMNS`` schema gives its metric
columns), its build function, the preset section that asks for it, whether it optimises
something (then its metric table has ``best_fitness``), the dimensions it runs in, which law
registry its ``[controller]`` reads, its robot caps for a browser tab on a shared server and
the app module that shows it. :func:`kind_for` (which kind a scenario is), the
``Scenario`` cross-section rules, the app's limits, the recorder's and the sweeps' column
formats and the tests that run every kind derive from it; a plug-in adds a kind with
``KINDS.register(SceneKind(...))`` and a section model of its own.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Callable

from pydantic import BaseModel, ValidationError

from shoal.engine.core.registry import Registry, shape
from shoal.engine.core.schema import Schema, common_columns, integer_names
from shoal.engine.kinds.fleet import Fleet
from shoal.engine.kinds.slo_swarm import SLOSwarm
from shoal.engine.kinds.sonar import AcousticSwarm
from shoal.engine.kinds.swarm import Simulation
from shoal.engine.pso.laws import LAWS
from shoal.engine.robots.laws import ROBOT_LAWS

from .build import (
    Builder,
    build_fleet,
    build_simulation,
    build_slo_swarm,
    build_sonar,
    fleet_live,
    slo_live_changes,
    sonar_live,
    swarm_live,
)

if TYPE_CHECKING:
    from .models import Scenario


@dataclass(frozen=True)
class Cap:
    """At most ``robots`` robots in one browser tab (the model's range is for headless runs),
    and at most ``d`` dimensions (None: the kind's own range), for the scenarios ``when`` holds
    for (all if None); ``label`` names the kind of scene."""

    label: str
    robots: int
    when: Callable[[Scenario], bool] | None = None
    d: int | None = None


def on_slo(scenario: Scenario) -> bool:
    """Anything with an ``[slo]`` section localises every pair of robots each tick."""
    return scenario.slo is not None


SLO_CAP = Cap("SLO swarm", 100, on_slo)  # pairwise ranging grows as N²
BROWSER_DIMS = 10  # sim.d of a Chapter 3 swarm in a tab: its tick, and each frame its history keeps, grow with N·d


@dataclass(frozen=True)
class SceneKind:
    """One kind of scene."""

    name: str  # the engine kind (``kind_of``), e.g. "fleet"
    label: str  # in words, for messages: "Chapter 4–5 fleet"
    engine: type[Any]  # its Engine class (:mod:`shoal.engine.core.contract`); its ``COLUMNS`` are the kind's own
    build: Builder  # scenario → engine
    section: str | None  # the preset section that asks for it; None: the default scene (no section)
    detect: Callable[[Scenario], bool] | None = None  # is a scenario this kind? (default: its section is set)
    asks: str | None = None  # the field a refusal names when detect says more than "the section is set"
    model: type[BaseModel] | None = None  # a plug-in kind's section model (the built-in ones are Scenario fields)
    optimises: bool = True  # its state has best_fitness and its metric table the column
    dims: tuple[int, int] = (2, 2)  # the sim.d it runs in, lowest and highest
    laws: Registry[Any] | None = None  # the registry ``controller.law`` names, if the kind reads [controller]
    caps: tuple[Cap, ...] = ()  # robots in a browser tab on a shared server: the first that applies
    app: str | None = None  # the module whose ``KIND`` shows it in the app (None: headless only)
    live: Callable[[Scenario, Scenario], dict[str, Any] | None] | None = None  # old, new scenario → the
    # engine's retune keywords, None when the change needs a new engine (no function: never live)
    default_cap: int = 100
    reads: dict[str, tuple[str, ...] | None] | None = None  # section → the fields its build reads (None:
    # all), in the order a sweep offers them; default: its own section and sim.robots, sim.steps
    cost: tuple[float, float] = (30e-6, 3e-6)  # CPU s per run and tick, per robot and tick: a rough price
    # for sizing batches of runs (studies/cost.py prices the built-in kinds itself)

    @property
    def columns(self) -> Schema:
        """Every metric column, in the order ``metrics.csv`` has them: the common ones, then its own."""
        return common_columns(self.optimises) + tuple(self.engine.COLUMNS)

    def read_fields(self) -> dict[str, tuple[str, ...] | None]:
        """The fields its build reads, by section (the axes a sweep offers)."""
        if self.reads is not None:
            return self.reads
        return {**({self.section: None} if self.section else {}), "sim": ("robots", "steps")}

    def detects(self, scenario: Scenario) -> bool:
        if self.detect is not None:
            return self.detect(scenario)
        return self.section is not None and section_of(scenario, self.section) is not None

    def cap(self, scenario: Scenario) -> Cap:
        """The robot cap of a browser tab showing ``scenario``."""
        return next((c for c in self.caps if c.when is None or c.when(scenario)), Cap(self.label, self.default_cap))


_SHAPE = shape("build", "detects", "cap", engine=type, section=(str, type(None)), app=(str, type(None)),
               caps=tuple, dims=tuple, cost=tuple, optimises=bool)


def check_kind(kind: Any) -> str | None:
    """Why ``kind`` is not a well-formed :class:`SceneKind` (None: it is), said when it registers."""
    why = _SHAPE(kind)
    if why is not None:
        return why
    if not all(isinstance(c, Cap) for c in kind.caps):
        return "caps must be a tuple of Cap"
    if kind.live is not None and not callable(kind.live):
        return "live must be callable or None"
    cost = kind.cost
    if len(cost) < 2 or not all(isinstance(v, (int, float)) and not isinstance(v, bool) and 0 <= v < 1e3
                                for v in cost):
        return f"cost must be CPU seconds per run and per robot (finite, >= 0), got {cost!r}"
    return None


def section_of(scenario: Scenario, name: str) -> Any:
    """The section ``name`` of ``scenario`` (a field, or a plug-in kind's section), None if unset."""
    if name in type(scenario).model_fields:
        return getattr(scenario, name)
    return (scenario.model_extra or {}).get(name)


KINDS: Registry[SceneKind] = Registry(  # (the order the app lists them in; a scene matches one kind at most)
    "scene kind",
    SceneKind("swarm", "Chapter 3 swarm", Simulation, build_simulation, None, dims=(1, 1000), laws=LAWS,
              caps=(SLO_CAP, Cap("free-space swarm", 2000, d=BROWSER_DIMS)), app="shoal.app.kinds.swarm",
              live=swarm_live,
              reads={"controller": ("U", "A_plus", "omega", "c1", "c2", "c1_share", "dt", "law", "mode",
                                    "smooth_width"),
                     "objective": None, "bests": None, "init": None, "sim": ("robots", "d", "steps")}),
    SceneKind("fleet", "Chapter 4–5 fleet", Fleet, build_fleet, "world", laws=ROBOT_LAWS,
              caps=(SLO_CAP, Cap("fleet, pymunk physics", 200, lambda sc: sc.robot.motion == "physics"),
                    Cap("fleet", 1000)),
              app="shoal.app.kinds.fleet", live=fleet_live,
              reads={"controller": ("beta", "alpha", "omega", "c1", "c2", "c3", "gamma", "c1_share", "dt", "law",
                                    "mode", "r_min", "s_min", "update", "guard", "rotational_energy"),
                     "robot": None, "sensing": None,
                     "world": ("kind", "layers", "length", "width", "density", "start_size"),
                     "sim": ("robots", "steps")}),
    SceneKind("sonar", "Chapter 7–8 acoustic swarm", AcousticSwarm, build_sonar, "acoustics",
              caps=(SLO_CAP, Cap("acoustic swarm", 100)), app="shoal.app.kinds.sonar", live=sonar_live),
    SceneKind("slo_swarm", "Mai's SLO swarm", SLOSwarm, build_slo_swarm, "slo",
              detect=lambda sc: sc.slo is not None and sc.slo.swarm == "slo", asks="slo.swarm", caps=(SLO_CAP,),
              app="shoal.app.kinds.mai", live=slo_live_changes,
              reads={"slo": ("errors", "error_values", "selection", "neighbourhood", "neighbourhood_param", "motion",
                             "objective", "prediction_weight", "delta_cos", "delta_v", "literal_eq_3_1",
                             "entry_policy", "walk_speed", "quality_threshold"),
                     "sim": ("robots", "steps")}),
    check=check_kind,
)
# Robots per kind in a tab, where one step still costs a few tens of ms at most: the compiled
# kinematic fleet tick takes 1000 robots in a few ms, pymunk physics 200 in about 20 ms; the
# SLO and acoustic swarms grow faster than linearly with the robots (about 2× the slider's top).


def sections() -> tuple[str, ...]:
    """The preset sections that ask for a kind, in registry order (built-in and plug-in)."""
    return tuple(k.section for k in KINDS.values() if k.section is not None)


def plugin_sections() -> dict[str, type[BaseModel]]:
    """Section name → model of the plug-in kinds' sections."""
    return {k.section: k.model for k in KINDS.values() if k.section is not None and k.model is not None}


def matching(scenario: Scenario) -> list[SceneKind]:
    """Every kind with a section whose section asks for ``scenario`` (one, for a valid scenario)."""
    return [k for k in KINDS.values() if k.section is not None and k.detects(scenario)]


def default_kind() -> SceneKind:
    return next(k for k in KINDS.values() if k.section is None)


def kind_for(scenario: Scenario) -> SceneKind:
    """The kind ``scenario`` describes: the kind whose section it sets (Mai's SLO swarm is
    ``[slo] swarm = "slo"``), else the Chapter 3 swarm; the fleet, the acoustic swarm and the
    Chapter 3 swarm on SLO or true positions as ``[slo]`` says."""
    found = matching(scenario)
    return found[0] if found else default_kind()


def check_scene(scenario: Scenario) -> None:
    """The rules across sections that come from the kinds (a ``ValueError`` naming the fields):
    one kind per scene, a dimension the kind runs in, a ``controller.law`` of the registry the
    kind reads."""
    found = matching(scenario)
    if len(found) > 1:
        a, b = found[0], found[1]
        hint = " (slo.swarm = 'host' puts a scene's own swarm on SLO positions)" if "slo" in (a.section, b.section) \
            else ""
        field = next((k.asks for k in (a, b) if k.asks), b.section)
        raise ValueError(f"{field}: [{a.section}] and [{b.section}] describe two kinds of scene ({a.label}, "
                         f"{b.label}); remove one{hint}")
    kind = found[0] if found else default_kind()
    lo, hi = kind.dims
    d = scenario.sim.d
    if not lo <= d <= hi:
        where = f"[{kind.section}]" if kind.section else f"the {kind.label}"
        raise ValueError(f"sim.d must be {lo} with {where}" if lo == hi else
                         f"sim.d = {d}: the {kind.label} runs in {lo} to {hi} dimensions")
    law = scenario.controller.law
    if kind.laws is not None and law not in kind.laws:
        other = next((k for k in KINDS.values() if k.laws is not None and law in k.laws), None)
        need = f"a [{other.section}] section" if other is not None and other.section else f"the {other.label}" \
            if other is not None else "another scene"
        raise ValueError(f"controller.law {law!r}: a {kind.label} takes a {kind.laws.what} of "
                         f"{', '.join(kind.laws)}; {law!r} needs {need}")


def check_plugin_sections(extra: dict[str, Any]) -> dict[str, Any]:
    """Validate a scenario's sections beyond its fields: each must be a plug-in kind's, by its
    model; anything else is refused as an unknown field (nothing is imported for a name)."""
    models = plugin_sections()
    out: dict[str, Any] = {}
    for name, value in extra.items():
        model = models.get(name)
        if model is None:
            raise ValueError(f"{name}: Extra inputs are not permitted (no scene kind has a [{name}] section)")
        if isinstance(value, model):
            out[name] = value
            continue
        try:
            out[name] = model.model_validate(value)
        except Exception as err:  # a pydantic ValidationError: one line per field
            from .io import format_errors  # (io imports the models)

            lines = format_errors(err) if isinstance(err, ValidationError) else [str(err)]
            raise ValueError("; ".join(f"{name}.{line}" for line in lines)) from None
    return out


def metric_columns() -> Schema:
    """Every kind's metric columns (the union, common first; a name twice is kept once)."""
    seen: dict[str, Any] = {}
    for k in KINDS.values():
        for c in k.columns:
            seen.setdefault(c.name, c)
    return tuple(seen.values())


def integer_columns() -> frozenset[str]:
    """Names of the whole-number metric columns of every kind (worked out again when a kind is
    registered or replaced: a sweep asks for every value it writes)."""
    return _integer_columns(KINDS.version)


@functools.lru_cache(maxsize=4)
def _integer_columns(version: int) -> frozenset[str]:
    return integer_names(metric_columns())

