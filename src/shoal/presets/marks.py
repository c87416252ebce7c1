"""Where each value of a preset comes from (docs/readings.md).

Every value that shapes a run is marked:

- **stated**: the thesis gives it (the source names the table, section or equation);
- **read**: our interpretation of stated text (the source names the section of
  docs/readings.md that quotes it and argues the reading);
- **fitted**: chosen by matching the thesis' outcomes (the evidence names the table that
  decided it);
- **ours**: a free choice where the thesis is silent and nothing was fitted (a test
  scene's size, a seed, an extension of ours).

A mark belongs to a field *and a value*: ``acoustics.c1_share = 0.25`` is fitted in the
Chapter 7 presets, ``0.5`` under the non-omnidirectional controller is stated (Algorithm 2).
:func:`provenance` gives the marks of a scenario's fields that shape its kind of run;
a field whose value no rule covers is left unmarked (``None``), and ``tests/test_marks.py``
requires that no shipped thesis preset has one.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable, Literal

from .kinds import kind_for

Kind = Literal["stated", "read", "fitted", "ours"]
KINDS: tuple[Kind, ...] = ("stated", "read", "fitted", "ours")
ANY = object()  # a rule for every value of its field
READINGS = "docs/readings.md"


@dataclass(frozen=True)
class Mark:
    """The provenance of one value."""

    kind: Kind
    source: str  # thesis table/section/equation, or the docs/readings.md heading of a reading
    evidence: str = ""  # fitted: where the evidence table is

    def text(self) -> str:
        return f"{self.kind}: {self.source}" + (f" (evidence: {self.evidence})" if self.evidence else "")


@dataclass(frozen=True)
class Rule:
    path: str
    value: Any
    mark: Mark
    when: Callable[[dict[str, Any]], bool] | None = None  # a condition on the scenario (dumped)


def _r(heading: str) -> str:
    return f'{READINGS}, "{heading}"'


def stated(path: str, value: Any, source: str, when: Callable[[dict[str, Any]], bool] | None = None) -> Rule:
    return Rule(path, value, Mark("stated", source), when)


def read(path: str, value: Any, heading: str, when: Callable[[dict[str, Any]], bool] | None = None) -> Rule:
    return Rule(path, value, Mark("read", _r(heading)), when)


def fitted(path: str, value: Any, heading: str, evidence: str,
           when: Callable[[dict[str, Any]], bool] | None = None) -> Rule:
    return Rule(path, value, Mark("fitted", _r(heading), evidence), when)


def ours(path: str, value: Any, why: str, when: Callable[[dict[str, Any]], bool] | None = None) -> Rule:
    return Rule(path, value, Mark("ours", why), when)


def _get(d: dict[str, Any], path: str) -> Any:
    for part in path.split("."):
        if not isinstance(d, dict) or part not in d:
            return None
        d = d[part]
    return d


def _is(path: str, *values: Any) -> Callable[[dict[str, Any]], bool]:
    return lambda d: _get(d, path) in values


NONOMNI = _is("acoustics.controller", "nonomni")
ADAPTED = _is("acoustics.controller", "adapted")
TWO_HYDROPHONES = _is("acoustics.algorithm", "x-pso", "b-pso", "xb-pso")
ESCORT = lambda d: (_get(d, "acoustics.r") or 0) > 0  # noqa: E731
CH3 = "Rossides §3.5 (p. 74)"
CH4 = "Rossides Table 4.1 (p. 95)"
CH5 = "Rossides Table 5.1, §5.3 (p. 121)"
T71 = "Rossides Table 7.1 (p. 160)"
T81 = "Rossides Table 8.1 (p. 180)"
MAI = "Mai Tab. 4.1 (p. 37)"
FIG35 = "Step changes in Figures 3-5b and 3-5c"

RULES: tuple[Rule, ...] = (
    # ------------------------------------------------------------------ Chapter 3 swarms
    stated("sim.robots", 1000, f"{CH3}: swarms of 10, 100 and 1000 particles (the reproduction runs all three)",
           _is("sim.d", 1)),
    stated("sim.d", 1, f"{CH3}: a 1D environment"),
    stated("sim.steps", 100, f"{CH3}: 100 s at Δt = 1 s", _is("controller.dt", 1.0)),
    stated("sim.steps", 500, f"{CH3}: 100 s at Δt = 0.2 s (Fig. 3-4c, d)", _is("controller.dt", 0.2)),
    read("init.center", ANY, "Unstated settings of Section 3.5", _is("sim.d", 1)),
    read("init.spread", ANY, "Unstated settings of Section 3.5", _is("sim.d", 1)),
    read("init.speed", ANY, "Unstated settings of Section 3.5", _is("sim.d", 1)),
    stated("controller.law", "adapted-sgn", "Rossides [3.10]–[3.11]: Adapted PSO"),
    stated("controller.mode", "physical", "Rossides §3.4 (p. 73): set by U, A+ and Δt [3.32]–[3.35]"),
    stated("controller.dt", 1.0, f"{CH3}, Fig. 3-4a, b and Fig. 3-5", _is("sim.d", 1)),
    stated("controller.dt", 0.2, f"{CH3}: Fig. 3-4c, d have a five times smaller Δt", _is("sim.d", 1)),
    stated("controller.U", 20.0, f"{CH3}: U = 20 m/s", _is("sim.d", 1)),
    stated("controller.A_plus", 20.0, f"{CH3}: A+·Δt = U, β = 1 (Fig. 3-4a)", _is("controller.dt", 1.0)),
    stated("controller.A_plus", 4.0, f"{CH3}: A+ five times smaller, β = 0.2 (Fig. 3-4b; Fig. 3-5a: 4 m/s²)",
           _is("controller.dt", 1.0)),
    stated("controller.A_plus", 20.0, f"{CH3}: Δt five times smaller, β = 0.2 (Fig. 3-4c)",
           _is("controller.dt", 0.2)),
    stated("controller.A_plus", 100.0, f"{CH3}: A+ five times larger at Δt = 0.2 s, β = 1 (Fig. 3-4d)",
           _is("controller.dt", 0.2)),
    read("controller.c1_share", 0.5, "Unstated settings of Section 3.5", _is("sim.d", 1)),
    stated("controller.schedule", [], f"{CH3}: constant U, A+ and Δt (Fig. 3-4)"),
    read("controller.schedule", ANY, FIG35),
    read("bests.pbest_order", "before_velocity", "Unstated settings of Section 3.5"),
    read("bests.attractors", "ahead", 'Attractors in Figure 3-4 ("ahead" and "literal")'),
    read("bests.attractors", "literal", 'Attractors in Figure 3-4 ("ahead" and "literal")'),
    stated("objective.kind", "linear", f"{CH3}: f(x) = x1"),
    # ------------------------------------------------------------------ Chapters 4-5 fleets
    stated("sim.robots", 6, "Rossides §4.3 (p. 92): six robots", _is("world.kind", "obstacle-course")),
    ours("sim.robots", 20, "Fig. 5-4 shows a swarm without giving its size; 20 as drawn", _is("world.kind", "empty")),
    ours("sim.steps", ANY, "the run length of the preset; the thesis gives none (figs. 4-6 and 5-5 run 600 s, "
                           "fig5-4 300 s: docs/readings.md, \"The obstacle course of Figure 4-1\")",
         lambda d: d.get("world") is not None),
    stated("controller.law", "adapted-rpso", "Rossides Algorithm 1 (§4.2.2, p. 90)"),
    stated("controller.law", "nonomni", "Rossides Algorithm 2 (§5.2.2, p. 119)"),
    stated("controller.mode", "dvc", "Rossides Algorithms 1 and 2: DVC"),
    stated("controller.mode", "raw", f"{CH4}: the constant-coefficient cases", lambda d: d.get("world") is not None),
    stated("controller.law", "rpso", "Rossides [4.2]–[4.4]: Original RPSO"),
    stated("controller.dt", 1.0, f"{CH4}; {CH5}", lambda d: d.get("world") is not None),
    stated("controller.alpha", 0.9, f"{CH4}; {CH5}"),
    stated("controller.beta", 0.9, f"{CH4}; {CH5}"),
    stated("controller.gamma", 1.0, CH4),
    stated("controller.c1_share", 0.5, "Rossides Algorithm 1 step 5 and Algorithm 2 line 13: c1 = c2 = ĉ/2",
           lambda d: d.get("world") is not None),
    stated("controller.update", "sequential", "Rossides Algorithms 1–2 loop over the robots"),
    ours("controller.guard", True, "The DVC guard (ours)"),
    stated("controller.guard", False, "Rossides Algorithms 1–2 as written (no guard)"),
    read("controller.rotational_energy", "pi", "Rotational energy [5.12]"),
    stated("controller.r_min", 0.0, "Rossides §5.4: no minimum turning radius in the simulations"),
    stated("controller.s_min", 0.0, "Rossides §5.4: no clearance in the simulations"),
    read("world.kind", "obstacle-course", "The obstacle course of Figure 4-1"),
    ours("world.kind", "empty", "Fig. 5-4: an open arena; its walls and size are ours"),
    ours("world.kind", "forest", "a sandbox world of ours"),
    ours("world.seed", ANY, "The obstacle course of Figure 4-1: a seeded course in its spirit"),
    stated("world.layers", 6, "Rossides Fig. 4-1 (p. 96): six obstacle layers"),
    ours("world.length", ANY, "The obstacle course of Figure 4-1: no dimensions are given"),
    ours("world.width", ANY, "The obstacle course of Figure 4-1: no dimensions are given"),
    ours("world.start_size", ANY, "The obstacle course of Figure 4-1: no dimensions are given"),
    stated("robot.radius", 0.5, "Rossides §4.3 (p. 92): robots of 1 m diameter"),
    stated("robot.v_max", 3.0, "Rossides §4.3 (p. 92): 3 m/s top speed"),
    ours("robot.a_max", ANY, "physics mode only: the actuators' acceleration (Gazebo's is not given)"),
    stated("robot.motion", "kinematic", "Rossides §4.4 (p. 102): MATLAB runs of ideal particles"),
    ours("robot.motion", "physics", "pymunk in the role of the thesis' Gazebo runs (§4.4, p. 103)"),
    stated("robot.drive", "mecanum", "Rossides [4.18]–[4.19] (§4.3.3): mecanum wheels in Gazebo"),
    stated("robot.drive", "holonomic", "Rossides §4.3: omnidirectional robots"),
    stated("robot.drive", "differential", "Rossides §5.1 (p. 111): differential-drive robots"),
    ours("robot.spawn_gap", ANY, "Initial state and partners: robots start apart, by how much is ours"),
    read("robot.contact_tolerance", 1e-9, "What counts as a collision, and stalls"),
    stated("sensing.range", 3.0, "Rossides §4.3 and §5.3: LiDAR range 3 m"),
    # ------------------------------------------------------------------ Chapters 7-8 acoustics
    stated("sim.robots", 10, f"{T71}; {T81}", lambda d: d.get("acoustics") is not None),
    stated("sim.robots", 40, "Rossides Figs. 8-3 to 8-5: 40 robots", ESCORT),
    stated("sim.steps", 6000, "Rossides §7.4 (p. 162): 6000 timesteps", lambda d: d.get("acoustics") is not None),
    stated("sim.steps", 2000, "Rossides §8.1.1 (p. 181): 2000 timesteps", lambda d: d.get("acoustics") is not None
           and not ESCORT(d)),
    read("sim.steps", 2000, "Unstated settings of Chapter 8", ESCORT),
    stated("acoustics.algorithm", ANY, "Rossides Chapters 7–8: A-, X-, B-, XB-PSO (Algorithms 3–6), GT-PSO (Alg. 7)"),
    stated("acoustics.controller", "adapted", "Rossides §7.3.1 (p. 159): Adapted PSO [3.11]"),
    stated("acoustics.controller", "nonomni", "Rossides §8.1.1: the non-omnidirectional controller [8.7]"),
    read("acoustics.mode", "waveform", "Synthesised hydrophone signals"),
    stated("acoustics.snr0_db", ANY, "Rossides §7.4 and Fig. 8-2: the SNR0 of each figure (for the unlisted ones: "
                                     "docs/readings.md, \"Unstated settings of Chapter 8\")"),
    stated("acoustics.psd_s", 120.0, f"{T71}; {T81}"),
    read("acoustics.psd_s", 130.0, "Panels of Figure 8-5"),
    stated("acoustics.psd_n", 60.0, f"{T71}; {T81}"),
    stated("acoustics.f_c", 1000.0, f"{T71}; {T81}"),
    stated("acoustics.Q", 1.5, "Rossides §7.4 (p. 162): Q = 1.5"),
    ours("acoustics.Q", 10.0, "a narrowband example for X-PSO (Figs. 7-4, 7-5 sweep Q)"),
    stated("acoustics.tbp", 100.0, "Rossides §7.3.2: TBP = 100"),
    stated("acoustics.d_over_lambda", 0.5, f"Rossides §7.4 and {T81}: D = λ_c/2 = 0.75 m"),
    ours("acoustics.d_over_lambda", 2.0, "a phase-wrap example for X-PSO (Fig. 7-4 sweeps D)"),
    stated("acoustics.c", 1500.0, f"{T71}; {T81}"),
    fitted("acoustics.fs", 4000.0, "The lag estimate and the sample rate (Chapter 7)",
           "fig7-2 and the sample-rate table in docs/readings.md", TWO_HYDROPHONES),
    fitted("acoustics.lag_peak", "sample", "The lag estimate and the sample rate (Chapter 7)",
           "fig7-2 and the sample-rate table in docs/readings.md", TWO_HYDROPHONES),
    read("acoustics.full_lag", False, "Clipping the arccos and the lag search"),
    stated("acoustics.a", 1.0, f"{T71}; {T81}"),
    stated("acoustics.d_0", 50.0, f"{T71}; {T81}"),
    stated("acoustics.d_c", 50.0, f"{T71}; {T81}"),
    stated("acoustics.U", 2.0, f"{T71}; {T81}"),
    ours("acoustics.U", 4.0, "an example speed (Fig. 7-5 sweeps U)"),
    stated("acoustics.dt", 1.0, f"{T71}; {T81}"),
    read("acoustics.beta", 0.9, "β in Chapter 7", ADAPTED),
    stated("acoustics.beta", 0.9, T81, NONOMNI),
    fitted("acoustics.c1_share", 0.25, "Split of ĉ into c1 and c2 in Chapter 7",
           "fig7-2 (both splits run; summary.json → c1_share_evidence) and docs/readings.md", ADAPTED),
    stated("acoustics.c1_share", 0.5, "Rossides Algorithm 2, line 13: c1/c2 = 1 (the controller of Ch. 8)", NONOMNI),
    stated("acoustics.alpha_dvc", 0.9, T81, NONOMNI),
    read("acoustics.sensing_range", 10.0, "Unstated settings of Chapter 8", NONOMNI),
    read("acoustics.robot_radius", 1.0, "Unstated settings of Chapter 8", NONOMNI),
    stated("acoustics.guard", False, "Rossides Algorithm 2 and [8.7] as written (no guard)"),
    stated("acoustics.r", 0.0, "Rossides Chapter 7 and §8.1: no escorting", lambda d: not ESCORT(d)),
    stated("acoustics.r", 50.0, "Rossides Figs. 8-4, 8-5: r = 25, 50, 75 m", ESCORT),
    stated("acoustics.v_n", 0.0, "Rossides §7.3 and Fig. 8-4: a stationary source"),
    stated("acoustics.v_n", 0.1, "Rossides Fig. 8-5a, c, e: v_n = 0.1 [8.8]"),
    stated("acoustics.v_n", 0.25, "Rossides Fig. 8-3b, 8-5b, d, f: v_n = 0.25 [8.8]"),
    read("acoustics.source_heading_deg", ANY, "Panels of Figure 8-5"),
    read("acoustics.source_bearing_deg", None, "Initial state and partners"),
    read("acoustics.start", "origin", "Initial state and partners"),
    read("acoustics.start", "source", "Unstated settings of Chapter 8"),
    # ------------------------------------------------------------------ Mai: SLO
    read("sim.robots", 20, "Swarm size", lambda d: d.get("slo") is not None),
    stated("sim.steps", 100, "Mai Figs. 4.1–4.10: 100 generations of random walk", _is("slo.motion", "random_walk")),
    read("sim.steps", 1000, "Number of PSO generations", _is("slo.motion", "pso")),
    stated("slo.motion", ANY, "Mai §4.5 (random walk) and §4.6 (PSO)"),
    stated("slo.objective", ANY, "Mai §4.6: the DEAP benchmarks of Tab. 4.4", _is("slo.motion", "pso")),
    read("slo.selection", "css", "Default selection"),
    stated("slo.errors", ANY, "Mai Tab. 4.3 (p. 40): the None, Low and High sets"),
    stated("slo.prediction_weight", 0.5, f"{MAI}; §4.5.4: 0.5 for the other experiments"),
    stated("slo.delta_cos", 0.03, MAI),
    stated("slo.delta_v", 0.03, MAI),
    read("slo.literal_eq_3_1", False, "The denominator of [3.1]"),
    read("slo.entry_policy", "geometric_nearest", "Estimates of robots outside the neighbourhood (SLO)"),
    ours("slo.entry_policy", "dead_reckoning", "an extension: every robot hears every robot's odometry "
                                              "(docs/readings.md, \"Estimates of robots outside the neighbourhood\")"),
    stated("slo.neighbourhood", "knn", f"{MAI}: knn"),
    stated("slo.neighbourhood_param", 5.0, f"{MAI}: k = 5", _is("slo.neighbourhood", "knn")),
    stated("slo.walk_speed", 5.0, "Mai §4.5: |v| = U(0, 5)", _is("slo.motion", "random_walk")),
    read("slo.radial", "uniform_radius", "The point in the hypersphere (SPSO 2011)", _is("slo.motion", "pso")),
    read("slo.quality_threshold", None, "Quality thresholds"),
    read("slo.ranging", None, "Estimates of robots outside the neighbourhood (SLO)"),  # unset: every pair
    read("slo.ranging", "all", "Estimates of robots outside the neighbourhood (SLO)"),
    ours("slo.ranging", "neighbours", "Ranging only the neighbours (ours)"),
    ours("slo.neighbourhood", "full", "a host scene of ours: every robot localises every robot",
         lambda d: not _mai(d)),
    ours("slo.neighbourhood_param", None, "not used by the full neighbourhood", _is("slo.neighbourhood", "full")),
)

# Presets whose values follow the thesis (a thesis figure, or a thesis setting shown in the
# app): no value of theirs may be unmarked. Every other shipped preset is a sandbox scene,
# whose values no rule covers are ours.
THESIS_PRESETS = (
    "fig3-4a", "fig3-4b", "fig3-4c", "fig3-4d", "fig3-5a", "fig3-5b", "fig3-5c", "course-dvc", "course-nonomni",
    "course-rpso", "course-adapted-c3-equal", "course-physics", "open-nonomni", "sonar-xb-pso", "sonar-x-pso",
    "sonar-gt-pso", "sonar-xb-pso-nonomni", "escort-stationary", "escort-moving", "escort-xb-pso", "slo-walk",
    "slo-pso-sphere",
)
SANDBOX = Mark("ours", "a sandbox value of this preset, not a thesis setting")

# The fields that shape a run, per kind of scene (bookkeeping such as seeds, run counts and
# drawing choices is not a value of the thesis).
FIELDS: dict[str, tuple[str, ...]] = {
    "swarm": ("sim.robots", "sim.d", "sim.steps", "init.center", "init.spread", "init.speed", "controller.law",
              "controller.mode", "controller.dt", "controller.U", "controller.A_plus", "controller.c1_share",
              "controller.schedule", "bests.pbest_order", "bests.attractors", "objective.kind"),
    "fleet": ("sim.robots", "sim.steps", "controller.law", "controller.mode", "controller.dt", "controller.alpha",
              "controller.beta", "controller.c1_share", "controller.update", "controller.guard", "world.kind",
              "world.seed", "world.width", "world.start_size", "robot.radius", "robot.v_max", "robot.motion",
              "robot.drive", "robot.spawn_gap", "robot.contact_tolerance", "sensing.range"),
    "sonar": ("sim.robots", "sim.steps", "acoustics.algorithm", "acoustics.controller", "acoustics.mode",
              "acoustics.snr0_db", "acoustics.psd_s", "acoustics.psd_n", "acoustics.f_c", "acoustics.Q",
              "acoustics.tbp", "acoustics.c", "acoustics.a", "acoustics.d_0", "acoustics.d_c", "acoustics.U",
              "acoustics.dt", "acoustics.beta", "acoustics.c1_share", "acoustics.r", "acoustics.v_n",
              "acoustics.source_bearing_deg", "acoustics.start"),
    "slo": ("sim.robots", "sim.steps", "slo.motion", "slo.selection", "slo.errors", "slo.prediction_weight",
            "slo.delta_cos", "slo.delta_v", "slo.literal_eq_3_1", "slo.entry_policy", "slo.neighbourhood",
            "slo.neighbourhood_param", "slo.quality_threshold", "slo.ranging"),
}
EXTRA: dict[str, Callable[[dict[str, Any]], tuple[str, ...]]] = {
    "fleet": lambda d: (
        (("controller.gamma",) if _get(d, "controller.law") in ("rpso", "adapted-rpso") else ())
        + (("controller.rotational_energy", "controller.r_min", "controller.s_min")
           if _get(d, "controller.law") == "nonomni" else ())
        + (("world.layers", "world.length") if _get(d, "world.kind") == "obstacle-course" else ())
        + (("robot.a_max",) if _get(d, "robot.motion") == "physics" else ())),
    "sonar": lambda d: (
        (("acoustics.d_over_lambda", "acoustics.fs", "acoustics.lag_peak", "acoustics.full_lag")
         if TWO_HYDROPHONES(d) else ())
        + (("acoustics.alpha_dvc", "acoustics.sensing_range", "acoustics.robot_radius", "acoustics.guard")
           if NONOMNI(d) else ())
        + (("acoustics.source_heading_deg",) if (_get(d, "acoustics.v_n") or 0) > 0 else ())),
    "slo": lambda d: ("slo.objective", "slo.radial") if _get(d, "slo.motion") == "pso" else ("slo.walk_speed",),
}


def _mai(d: dict[str, Any]) -> bool:
    """Mai's own SLO swarm (not a host scene on SLO positions)."""
    return d.get("slo") is not None and d["slo"].get("swarm") == "slo"


def _matches(rule: Rule, value: Any, d: dict[str, Any]) -> bool:
    if rule.value is not ANY and not _equal(rule.value, value):
        return False
    return rule.when is None or bool(rule.when(d))


def _equal(a: Any, b: Any) -> bool:
    if isinstance(a, float) or isinstance(b, float):
        return isinstance(a, (int, float)) and isinstance(b, (int, float)) and float(a) == float(b)
    return a == b


def provenance(scenario: Any) -> dict[str, Mark | None]:
    """Every field that shapes a run of this scenario's kind, with its mark (None: no rule
    covers its value). ``scenario`` is a :class:`~shoal.presets.models.Scenario`."""
    d = scenario.model_dump(mode="json")
    kind = {"slo_swarm": "slo"}.get(kind_for(scenario).name, kind_for(scenario).name)
    if kind not in FIELDS:  # a plug-in kind: no thesis values
        return {}
    paths = FIELDS[kind] + EXTRA.get(kind, lambda _d: ())(d)
    if kind != "slo" and d.get("slo") is not None:  # a host swarm on SLO positions
        paths += tuple(p for p in FIELDS["slo"] if p not in ("sim.robots", "sim.steps", "slo.motion",
                                                              "slo.objective", "slo.walk_speed", "slo.radial",
                                                              "slo.quality_threshold"))
    out: dict[str, Mark | None] = {}
    fallback = None if d.get("name") in THESIS_PRESETS or d.get("name") == "custom" else SANDBOX
    for path in paths:
        value = _get(d, path)
        out[path] = next((r.mark for r in RULES if r.path == path and _matches(r, value, d)), fallback)
    return out


def values(scenario: Any) -> dict[str, Any]:
    """The values of :func:`provenance`'s fields."""
    d = scenario.model_dump(mode="json")
    return {p: _get(d, p) for p in provenance(scenario)}


def text(scenario: Any) -> str:
    """The marks as comment lines for ``shoal presets show`` (a TOML comment block)."""
    vals = values(scenario)
    width = max((len(p) for p in vals), default=0)
    lines = ["# Where the values come from (stated / read / fitted / ours; docs/readings.md):"]
    for p, m in provenance(scenario).items():
        lines.append(f"#   {p:<{width}} = {shown_value(vals[p])}  -> {m.text() if m else 'UNMARKED'}")
    return "\n".join(lines) + "\n"


def shown_value(v: Any) -> str:
    """A field's value as the marks list it (a list of tables: one group of pairs per table)."""
    if isinstance(v, list) and v and isinstance(v[0], dict):
        return "; ".join(", ".join(f"{k} {x:g}" if isinstance(x, float) else f"{k} {x}" for k, x in s.items())
                         for s in v)
    return "unset" if v is None else str(v)
