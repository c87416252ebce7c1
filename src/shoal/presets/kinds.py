"""The scene kinds, one registry entry each: everything Shoal needs to know about a kind, said
once, at the bottom of :mod:`shoal.presets` (this module imports no other module of it but
:mod:`.errors`, and no engine kind).

A :class:`SceneKind` names its engine class and its build function by string
(``"shoal.engine.kinds.fleet:Fleet"``), resolved on first use, so that running one kind imports
no other; a plug-in may give the objects themselves. The entry says what the rest of Shoal
would otherwise hard-code: the preset section that asks for it, whether it optimises, its
headline columns and their labels, the scene parts a replay stores, which fields retune a
running engine (:class:`Live`, the one rule of :meth:`SceneKind.live_keywords` that
``Scene.retune`` and the app's sessions both follow), its robot caps in a browser tab, the
app module that shows it and the preset that shows it best. :func:`kind_for` (which kind a
scenario is), the ``Scenario`` cross-section rules, the app's limits, the recorder's and the
sweeps' columns, :mod:`shoal.testing` and the tests that run every kind derive from it; a
plug-in adds a kind with ``KINDS.register(SceneKind(...))`` and a section model of its own.

A string in an entry is code the machine's owner installed (a built-in entry or a plug-in's
registration); no preset, upload or browser value is ever resolved as one.
"""

from __future__ import annotations

import functools
import importlib
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Callable, Protocol

from pydantic import BaseModel, ValidationError

from shoal.engine.core.registry import Registry
from shoal.engine.core.schema import Schema, common_columns, integer_names

from .errors import fields_in, format_errors

if TYPE_CHECKING:
    from shoal.engine.core.contract import Engine

Scenario = Any  # a shoal.presets.models.Scenario (the models build on this module, not it on them)
Ref = Any  # an object, or the string "package.module:name" naming it (resolved on first use)


def resolve(ref: Ref) -> Any:
    """The object ``ref`` names: ``ref`` itself, or for ``"package.module:name.attr"`` that
    attribute of the imported module. Only ever given strings from registry entries (code)."""
    return _resolve(ref) if isinstance(ref, str) else ref


@functools.cache
def _resolve(ref: str) -> Any:
    module, sep, name = ref.partition(":")
    if not sep or not module or not name:
        raise ValueError(f"{ref!r}: a reference is 'package.module:name'")
    obj: Any = importlib.import_module(module)
    for part in name.split("."):
        obj = getattr(obj, part)
    return obj


class Builder(Protocol):
    def __call__(self, scenario: Scenario, *, runs: int | None = None, seed: int | None = None,
                 first_run: int = 0) -> Engine: ...


@dataclass(frozen=True)
class Cap:
    """At most ``robots`` robots in one browser tab (the model's range is for headless runs),
    for the scenarios ``when`` holds for (all if None); ``label`` names the kind of scene."""

    label: str
    robots: int
    when: Callable[[Scenario], bool] | None = None


def on_slo(scenario: Scenario) -> bool:
    """Anything with an ``[slo]`` section localises every pair of robots each tick."""
    return scenario.slo is not None


SLO_CAP = Cap("SLO swarm", 100, on_slo)  # pairwise ranging grows as N²

NEVER_READ = ("view", "name", "description", "sim.steps")  # no engine reads these: changing them needs nothing


@dataclass(frozen=True)
class Live:
    """Which preset fields a running engine of the kind takes without being built again.

    ``fields`` are sections (``"controller"``) or dotted fields (``"sim.robots"``) that retune it
    live, except those in ``fixed``; ``keywords(old, new)`` gives the engine's ``retune``
    keywords (names of its ``LIVE`` set) for a change within them. ``ignores`` are fields its
    engine never reads (nor do :data:`NEVER_READ`): a change there needs nothing. Any other
    change needs a new engine. ``slo``: a host swarm, whose ``[slo]`` settings retune its
    position source (``retune(slo={...})``; the switch between true and SLO positions or another
    length unit needs a new engine)."""

    fields: tuple[str, ...]
    keywords: Ref  # (old, new scenario) -> dict of retune keywords, or "module:function"
    fixed: tuple[str, ...] = ()
    ignores: tuple[str, ...] = ()
    slo: bool = False


HOST_SLO_RETUNE = "shoal.presets.builders.slo:host_slo_retune"  # a host swarm's slo=... keywords (or None)


def leaves(data: Any, prefix: str = "") -> dict[str, Any]:
    """A dumped scenario as dotted path → value (tables opened, lists kept whole)."""
    if not isinstance(data, dict):
        return {prefix: data}
    out: dict[str, Any] = {}
    for key, value in data.items():
        out.update(leaves(value, f"{prefix}{key}.") if isinstance(value, dict) and value else
                   {f"{prefix}{key}": value})
    return {k.removesuffix("."): v for k, v in out.items()}


def changed_fields(old: Scenario, new: Scenario) -> list[str]:
    """The dotted fields whose values differ between two scenarios (a section set in one only:
    each of its fields)."""
    a, b = leaves(old.model_dump(mode="json")), leaves(new.model_dump(mode="json"))
    missing = object()
    return sorted(p for p in a.keys() | b.keys() if a.get(p, missing) != b.get(p, missing))


def _under(path: str, paths: tuple[str, ...]) -> bool:
    return any(path == p or path.startswith(p + ".") for p in paths)


@dataclass(frozen=True)
class SceneKind:
    """One kind of scene, as Shoal's code and a plug-in author declare it.

    ``engine``, ``builder``, ``model`` and ``laws`` are objects or ``"module:name"`` strings,
    resolved on first use (:attr:`engine_class`, :meth:`build`, :attr:`section_model`,
    :attr:`law_registry`).

    - ``name``: the engine kind (:func:`kind_of`), e.g. ``"fleet"``; ``label`` in words, for
      messages ("Chapter 4–5 fleet").
    - ``engine``: its Engine class (:mod:`shoal.engine.core.contract`); its ``COLUMNS`` are the
      kind's own metric columns and its ``LIVE`` set the keywords it retunes.
    - ``builder``: scenario → engine, for runs ``first_run …`` of a seed (:class:`Builder`).
    - ``section``: the preset section that asks for it (None: the default scene, no section);
      ``detect``: is a scenario this kind (default: its section is set), ``asks``: the field a
      refusal names when ``detect`` says more than that; ``model``: a plug-in kind's section
      model (the built-in sections are ``Scenario`` fields).
    - ``optimises``: its state has ``best_fitness`` and its metric table the column.
    - ``headline``: its columns that say how a run is doing, the first the one a sweep shows
      first (default: ``best_fitness`` where it optimises); ``labels``: column → (label, unit) as
      a sweep's outcomes name them (else the column's description); ``hidden``: columns a sweep
      does not offer as outcomes.
    - ``scene_parts``: the parts of the scene that may change while a run goes on (a fleet's
      obstacles, a moving source), name → numbers in one row of it; a replay stores each as its
      changes (``shoal.app.replay``), and the app driver's ``scene()`` draws them.
    - ``live``: which fields retune a running engine (:class:`Live`; None: none do).
    - ``dims``: the ``sim.d`` it runs in, lowest and highest; ``laws``: the registry
      ``controller.law`` names, if the kind reads ``[controller]``.
    - ``caps``: robots in a browser tab on a shared server, the first that applies
      (``default_cap`` otherwise); ``app``: the module whose ``KIND`` shows it in the app (None:
      headless only).
    - ``example``: the preset that shows it best (the tests and :mod:`shoal.testing` run it;
      default: the first preset of the kind).
    - ``reads``: section → the fields its build reads (None: all), in the order a sweep offers
      them; default: its own section and ``sim.robots``, ``sim.steps``.
    - ``cost``: CPU s per run and tick, per robot and tick: a rough price for sizing batches of
      runs (``studies/cost.py`` prices the built-in kinds itself).
    """

    name: str
    label: str
    engine: Ref
    builder: Ref
    section: str | None
    detect: Callable[[Scenario], bool] | None = None
    asks: str | None = None
    model: Ref | None = None
    optimises: bool = True
    headline: tuple[str, ...] = ()
    labels: Mapping[str, tuple[str, str]] = field(default_factory=dict)
    hidden: tuple[str, ...] = ()
    scene_parts: Mapping[str, int] = field(default_factory=dict)
    live: Live | None = None
    dims: tuple[int, int] = (2, 2)
    laws: Ref | None = None
    caps: tuple[Cap, ...] = ()
    app: str | None = None
    default_cap: int = 100
    example: str | None = None
    reads: dict[str, tuple[str, ...] | None] | None = None
    cost: tuple[float, float] = (30e-6, 3e-6)

    # ------------------------------------------------------------------ resolved on first use
    @property
    def engine_class(self) -> type[Any]:
        """The Engine class (imported now if the entry names it by string)."""
        return resolve(self.engine)

    def build(self, scenario: Scenario, *, runs: int | None = None, seed: int | None = None,
              first_run: int = 0) -> Engine:
        """The engine of ``scenario``, for runs ``first_run … first_run + runs − 1`` of the seed."""
        builder: Builder = resolve(self.builder)
        return builder(scenario, runs=runs, seed=seed, first_run=first_run)

    @property
    def section_model(self) -> type[BaseModel] | None:
        """A plug-in kind's section model (None for the built-in kinds, whose sections are fields)."""
        return resolve(self.model) if self.model is not None else None

    @property
    def law_registry(self) -> Registry[Any] | None:
        """The registry ``controller.law`` names for this kind (None: it reads no ``[controller]``)."""
        return resolve(self.laws) if self.laws is not None else None

    # ------------------------------------------------------------------ what it declares
    @property
    def columns(self) -> Schema:
        """Every metric column, in the order ``metrics.csv`` has them: the common ones, then its own."""
        return common_columns(self.optimises) + tuple(self.engine_class.COLUMNS)

    @property
    def headlines(self) -> tuple[str, ...]:
        """Its headline columns (``best_fitness`` where it optimises and declares none)."""
        return self.headline or (("best_fitness",) if self.optimises else ())

    def live_keywords(self, old: Scenario, new: Scenario) -> dict[str, Any] | None:
        """The ``retune`` keywords that take a running engine of ``old`` to ``new``, or None when
        the change needs a new engine (:class:`Live`: the one rule of ``Scene.retune`` and the
        app's sessions)."""
        rule = self.live
        changed = changed_fields(old, new)
        if rule is None:
            return {} if all(_under(p, NEVER_READ) for p in changed) else None
        for path in changed:
            if _under(path, NEVER_READ + rule.ignores) or (rule.slo and _under(path, ("slo",))):
                continue
            if not _under(path, rule.fields) or _under(path, rule.fixed):
                return None
        out = dict(resolve(rule.keywords)(old, new))
        if rule.slo and (old.slo is not None or new.slo is not None):
            slo = resolve(HOST_SLO_RETUNE)(old, new)
            if slo is None:
                return None
            if slo:
                out["slo"] = slo
        return out

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


def section_of(scenario: Scenario, name: str) -> Any:
    """The section ``name`` of ``scenario`` (a field, or a plug-in kind's section), None if unset."""
    if name in type(scenario).model_fields:
        return getattr(scenario, name)
    return (scenario.model_extra or {}).get(name)


# [slo] fields an engine can change mid-run (SLOSwarm.retune, a host swarm's retune(slo=...)).
SLO_LIVE = ("selection", "prediction_weight", "delta_cos", "delta_v", "literal_eq_3_1", "entry_policy", "neighbourhood",
            "neighbourhood_param", "errors", "error_values", "objective", "walk_speed", "quality_threshold")
# [acoustics] fields that shape the start (the source, the deployment) or the kind of swarm
# (AcousticSwarm's fixed SonarParams, by their preset names).
SONAR_FIXED = ("algorithm", "controller", "mode", "snr0_db", "d_0", "start", "source_bearing_deg", "source",
               "full_lag", "stop_on_converge")

_B = "shoal.presets.builders"
KINDS: Registry[SceneKind] = Registry(  # (the order the app lists them in; a scene matches one kind at most)
    "scene kind",
    SceneKind(
        "swarm", "Chapter 3 swarm", "shoal.engine.kinds.swarm:Simulation", f"{_B}.swarm:build_simulation", None,
        headline=("best_fitness",),
        labels={"max_component": ("largest velocity component at the end", "m/s"),
                "omega": ("inertia weight ω at the end", ""), "c_hat": ("ĉ = c1 + c2 at the end", "")},
        live=Live(("controller", "bests", "objective", "sim.robots"), f"{_B}.swarm:swarm_retune",
                  ignores=("arena", "robot", "sensing"), slo=True),
        dims=(1, 1000), laws="shoal.engine.pso.laws:LAWS", caps=(SLO_CAP, Cap("free-space swarm", 2000)),
        app="shoal.app.kinds.swarm", example="default",
        reads={"controller": ("U", "A_plus", "omega", "c1", "c2", "c1_share", "dt", "law", "mode", "smooth_width"),
               "objective": None, "bests": None, "init": None, "sim": ("robots", "d", "steps")}),
    SceneKind(
        "fleet", "Chapter 4–5 fleet", "shoal.engine.kinds.fleet:Fleet", f"{_B}.fleet:build_fleet", "world",
        headline=("com_fitness", "operational"),
        labels={"com_fitness": ("CoM fitness (mean x1) at the end", "m"), "collided": ("collided robots", "robots"),
                "stalled": ("stalled robots", "robots"), "operational": ("operational robots", "robots"),
                "layers_passed": ("obstacle layers passed", "layers")},
        scene_parts={"obstacles": 3},  # circles x, y, r [m]: the user adds, moves and removes them
        live=Live(("controller", "sensing"), f"{_B}.fleet:fleet_retune",
                  ignores=("init", "objective", "bests", "arena"), slo=True),
        laws="shoal.engine.robots.laws:ROBOT_LAWS",
        caps=(SLO_CAP, Cap("fleet, pymunk physics", 200, lambda sc: sc.robot.motion == "physics"), Cap("fleet", 1000)),
        app="shoal.app.kinds.fleet", example="course-dvc",
        reads={"controller": ("beta", "alpha", "omega", "c1", "c2", "c3", "gamma", "c1_share", "dt", "law", "mode",
                              "r_min", "s_min", "update", "guard", "rotational_energy"),
               "robot": None, "sensing": None, "world": ("kind", "layers", "length", "width", "density", "start_size"),
               "sim": ("robots", "steps")}),
    SceneKind(
        "sonar", "Chapter 7–8 acoustic swarm", "shoal.engine.kinds.sonar:AcousticSwarm", f"{_B}.sonar:build_sonar",
        "acoustics", headline=("com_dist",),
        labels={"com_dist": ("CoM distance to the source at the end", "m"),
                "converged": ("converged (1) or not (0)", ""), "steps_to_converge": ("steps to converge", "steps"),
                "frac_inside_ring": ("share of robots inside the escort ring", ""),
                "mean_dist_to_source": ("mean robot–source distance", "m"), "contacts": ("robot contacts", "contacts")},
        hidden=("com_x", "com_y", "source_x", "source_y"),  # positions, not outcomes
        scene_parts={"source": 2},  # x, y [m]: it moves [8.8], or the user drags it
        live=Live(("acoustics",), f"{_B}.sonar:sonar_retune", fixed=tuple(f"acoustics.{f}" for f in SONAR_FIXED),
                  ignores=("controller", "robot", "sensing", "init", "objective", "bests", "arena"), slo=True),
        caps=(SLO_CAP, Cap("acoustic swarm", 100)), app="shoal.app.kinds.sonar", example="sonar-xb-pso"),
    SceneKind(
        "slo_swarm", "Mai's SLO swarm", "shoal.engine.kinds.slo_swarm:SLOSwarm", f"{_B}.slo:build_slo_swarm", "slo",
        detect=lambda sc: sc.slo is not None and sc.slo.swarm == "slo", asks="slo.swarm",
        headline=("e_abs_mean", "best_so_far"),
        labels={"generation_best": ("best f of the last generation", ""),
                "quality_met_at": ("first generation with best f ≤ T", "generations"),
                "e_abs_mean": ("absolute localisation error, mean over pairs", "units"),
                "e_abs_median": ("absolute localisation error, median over pairs", "units"),
                "e_rel_mean": ("relative localisation error, mean over pairs", ""),
                "e_rel_median": ("relative localisation error, median over pairs", ""),
                "e_ang_mean": ("angular localisation error, mean over pairs", "rad"),
                "e_ang_median": ("angular localisation error, median over pairs", "rad"),
                "distance_mean": ("distance between particles, mean over pairs", "units"),
                "distance_median": ("distance between particles, median over pairs", "units"),
                "dead_reckoning": ("share of estimates by dead reckoning", ""),
                "round_trip": ("round-trip error", "units")},
        hidden=("best_so_far",),  # the SLO swarm's copy of best_fitness
        live=Live(tuple(f"slo.{f}" for f in SLO_LIVE), f"{_B}.slo:slo_keywords"),
        caps=(SLO_CAP,), app="shoal.app.kinds.mai", example="slo-walk",
        reads={"slo": ("errors", "error_values", "selection", "neighbourhood", "neighbourhood_param", "motion",
                       "objective", "prediction_weight", "delta_cos", "delta_v", "literal_eq_3_1", "entry_policy",
                       "walk_speed", "quality_threshold"),
               "sim": ("robots", "steps")}),
)
# Robots per kind in a tab, where one step still costs a few tens of ms at most: the compiled
# kinematic fleet tick takes 1000 robots in a few ms, pymunk physics 200 in about 20 ms; the
# SLO and acoustic swarms grow faster than linearly with the robots (about 2× the slider's top).


def sections() -> tuple[str, ...]:
    """The preset sections that ask for a kind, in registry order (built-in and plug-in)."""
    return tuple(k.section for k in KINDS.values() if k.section is not None)


def plugin_sections() -> dict[str, type[BaseModel]]:
    """Section name → model of the plug-in kinds' sections."""
    out: dict[str, type[BaseModel]] = {}
    for k in KINDS.values():
        model = k.section_model
        if k.section is not None and model is not None:
            out[k.section] = model
    return out


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


def kind_of(scenario: Scenario) -> str:
    """The name of the kind a scenario describes (:func:`kind_for`): Mai's SLO swarm (``[slo]
    swarm = "slo"``), an acoustic swarm (``[acoustics]``, Ch. 7–8), a fleet in a world
    (``[world]``, Ch. 4–5), a plug-in kind (its own section) or the free-space swarm (Ch. 3)."""
    return kind_for(scenario).name


def check_scene(scenario: Scenario) -> None:
    """The rules across sections that come from the kinds (a ``ValueError`` naming the fields):
    one kind per scene, a dimension the kind runs in, a ``controller.law`` of the registry the
    kind reads."""
    found = matching(scenario)
    if len(found) > 1:
        a, b = found[0], found[1]
        hint = " (slo.swarm = 'host' puts a scene's own swarm on SLO positions)" if "slo" in (a.section, b.section) \
            else ""
        where = next((k.asks for k in (a, b) if k.asks), b.section)
        raise ValueError(f"{where}: [{a.section}] and [{b.section}] describe two kinds of scene ({a.label}, "
                         f"{b.label}); remove one{hint}")
    kind = found[0] if found else default_kind()
    lo, hi = kind.dims
    d = scenario.sim.d
    if not lo <= d <= hi:
        at = f"[{kind.section}]" if kind.section else f"the {kind.label}"
        raise ValueError(f"sim.d must be {lo} with {at}" if lo == hi else
                         f"sim.d = {d}: the {kind.label} runs in {lo} to {hi} dimensions")
    law, laws = scenario.controller.law, kind.law_registry
    if laws is not None and law not in laws:
        other = next((k for k in KINDS.values() if k.laws is not None and law in k.law_registry), None)  # type: ignore[operator]
        need = f"a [{other.section}] section" if other is not None and other.section else f"the {other.label}" \
            if other is not None else "another scene"
        raise ValueError(f"controller.law {law!r}: a {kind.label} takes a {laws.what} of "
                         f"{', '.join(laws)}; {law!r} needs {need}")


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
            lines = format_errors(err, functools.partial(fields_in, model)) if isinstance(err, ValidationError) \
                else [str(err)]
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


def scene_parts() -> dict[str, int]:
    """Every registered kind's scene parts (name → numbers in a row): what a replay may store."""
    out: dict[str, int] = {}
    for k in KINDS.values():
        for part, columns in k.scene_parts.items():
            if out.setdefault(part, columns) != columns:
                raise ValueError(f"scene part {part!r}: {k.name} gives it {columns} columns, another kind "
                                 f"{out[part]}")
    return out
