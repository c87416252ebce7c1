"""Pydantic models of a Shoal scenario (one preset file = one ``Scenario``).

Every field has a range; unknown fields are refused; error locations are dotted paths
such as ``controller.omega`` so the CLI and the UI can name the bad field. The choices of
variants (laws, strategies, selections) and their rules come from the engine's registries.
"""

# (no ``from __future__ import annotations`` here: pydantic reads the fields' annotations as objects
# instead of evaluating a string for each, about 12 ms of the 80 that building these models took)

from dataclasses import dataclass
from typing import TYPE_CHECKING, Annotated, Any, ClassVar, Literal, TypeAlias, TypeVar

from pydantic import (
    AfterValidator,
    BaseModel,
    ConfigDict,
    Field,
    SerializerFunctionWrapHandler,
    field_validator,
    model_serializer,
    model_validator,
)

from shoal.engine.core.objectives import OBJECTIVES
from shoal.engine.core.registry import Registry
from shoal.engine.pso.laws import LAWS

from .kinds import check_plugin_sections, check_scene, resolve

# The registries of the later chapters' variants, by name: imported when a preset names one of
# their entries (a Chapter 3 scene loads no fleet, sonar or SLO code to be validated).
ROBOT_LAWS_REF = "shoal.engine.robots.laws:ROBOT_LAWS"
STRATEGIES_REF = "shoal.engine.acoustics.strategies:STRATEGIES"
SELECTIONS_REF = "shoal.engine.slo.selection:SELECTIONS"


def robot_laws() -> Registry[Any]:
    """The fleet's robot laws (``shoal.engine.robots.laws.ROBOT_LAWS``)."""
    return resolve(ROBOT_LAWS_REF)


def dvc_laws() -> tuple[str, ...]:
    """The robot laws with a DVC form."""
    return tuple(name for name, law in robot_laws().items() if law.dvc is not None)


@dataclass(frozen=True)
class Registered:
    """The mark of a field whose value names an entry of ``registries`` (its choices; each a
    registry or the ``"module:NAME"`` of one)."""

    registries: tuple[Registry[Any] | str, ...]

    def names(self) -> tuple[str, ...]:
        return tuple(n for r in self.registries for n in resolve(r))


def registered(*registries: Registry[Any] | str) -> Any:
    """A string field whose value must be a name of one of ``registries`` (looked up when a preset
    is validated, so plug-ins' names count; a name is only ever looked up, never imported). The
    registries are asked in order: one that holds the value spares loading the next."""

    def check(value: str) -> str:
        if any(value in resolve(r) for r in registries):
            return value
        names = [n for r in registries for n in resolve(r)]
        raise ValueError(f"Input should be {', '.join(map(repr, names[:-1]))} or {names[-1]!r}"
                         if len(names) > 1 else f"Input should be {names[0]!r}")

    return Annotated[str, Field(max_length=100), Registered(registries), AfterValidator(check)]


if TYPE_CHECKING:  # (a type checker sees plain strings; pydantic the registries' checks)
    LawName: TypeAlias = str
    ObjectiveKind: TypeAlias = str
    StrategyName: TypeAlias = str
    SelectionName: TypeAlias = str
else:
    LawName = registered(LAWS, ROBOT_LAWS_REF)
    ObjectiveKind = registered(OBJECTIVES)
    StrategyName = registered(STRATEGIES_REF)
    SelectionName = registered(SELECTIONS_REF)

# Where a robot arriving in a neighbourhood starts (shoal.engine.slo.beliefs.EntryPolicy, the same
# names; tests/test_slo_presets.py checks they agree).
EntryPolicy = Literal["geometric_nearest", "stale", "geometric_random", "dead_reckoning"]

Coefficient = Annotated[float, Field(ge=0.0, le=100.0)]
Coordinate = Annotated[float, Field(ge=-1e5, le=1e5)]  # m, a place on a scene
MAX_OBSTACLES = 2000  # circles in world.obstacles (a preset upload is at most 256 KiB)


class _Model(BaseModel):
    model_config = ConfigDict(extra="forbid", validate_assignment=True, allow_inf_nan=False)  # no NaN/inf anywhere
    # fields a dump leaves out while unset (hand edits: a preset without them dumps as before)
    omit_unset: ClassVar[tuple[str, ...]] = ()
    omit_unset_optional: ClassVar[bool] = False  # also every field whose default is None, while it is None

    @model_serializer(mode="wrap")
    def _omit_unset(self, handler: SerializerFunctionWrapHandler) -> Any:
        data = handler(self)
        names = list(self.omit_unset)
        if self.omit_unset_optional:
            names += [n for n, f in type(self).model_fields.items() if f.default is None]
        for name in names:
            if data.get(name, 0) is None:
                del data[name]
        return data


class Sim(_Model):
    """Size, length and seed of a run."""

    robots: Annotated[int, Field(ge=1, le=100_000, description="number of particles / robots")] = 20
    d: Annotated[int, Field(ge=1, le=1000, description="spatial dimensions (the Chapter 3 swarm: 1–1000; the "
                                                      "others: 2)")] = 2
    steps: Annotated[int, Field(ge=1, le=10_000_000, description="control ticks per run")] = 600
    runs: Annotated[int, Field(ge=1, le=100_000, description="Monte-Carlo runs")] = 1
    seed: Annotated[int, Field(ge=0, le=2**63 - 1)] = 0


class Init(_Model):
    """Where the swarm starts: uniform in a square of side ``spread`` around ``center``."""

    center: tuple[float, float] = (-15.0, -5.0)
    spread: Annotated[float, Field(ge=0.0, le=1e4)] = 4.0
    speed: Annotated[float, Field(ge=0.0, le=1e3, description="initial |u_j| drawn from U(−speed, speed)")] = 0.0


class StepChange(_Model):
    """From ``t_start`` seconds on, the limits become ``U`` and ``A_plus`` (Fig. 3-5)."""

    t_start: Annotated[float, Field(gt=0.0, le=1e7)]
    U: Annotated[float, Field(gt=0.0, le=1e3)]
    A_plus: Annotated[float, Field(gt=0.0, le=1e5)]


class Controller(_Model):
    """Velocity law and its coefficients, raw (ω, c1, c2) or physical (U, A+, Δt)."""

    law: LawName = "adapted-sgn"
    mode: Literal["raw", "physical", "dvc"] = "physical"
    dt: Annotated[float, Field(ge=1e-6, le=10.0, description="controller period Δt [s]")] = 0.1
    omega: Annotated[float, Field(ge=-1.0, le=1.2, description="inertia weight ω (raw mode)")] = 0.5
    c1: Annotated[Coefficient, Field(description="cognitive coefficient (raw mode)")] = 0.5
    c2: Annotated[Coefficient, Field(description="social coefficient (raw mode)")] = 0.5
    c3: Annotated[Coefficient, Field(description="obstacle coefficient c3 (raw mode, RPSO laws)")] = 0.0
    alpha: Annotated[float, Field(gt=0.0, lt=1.0, description="DVC safety factor α [4.14]")] = 0.9
    beta: Annotated[float, Field(gt=0.0, le=1.0, description="DVC sensitivity β [4.15]")] = 0.9
    gamma: Annotated[float, Field(gt=0.0, le=1e3, description="avoidance sensitivity γ [4.4]")] = 1.0
    r_min: Annotated[float, Field(ge=0.0, le=100.0, description="minimum turning radius [m] (0 = off, §5.4)")] = 0.0
    s_min: Annotated[float, Field(ge=0.0, le=100.0, description="minimum obstacle clearance [m] (§5.4)")] = 0.0
    update: Literal["sequential", "simultaneous"] = Field(
        "sequential", description="robots sense and move one after another (Algorithms 1–2) or all at once"
    )
    guard: bool = Field(False, description="DVC inertia guard (ours): a step never closes more than α·s on a body")
    rotational_energy: Literal["pi", "disc"] = Field(
        "pi", description="[5.12] as printed (π w²/4) or a disc of the robot's radius (R_b² w²/4)"
    )
    U: Annotated[float, Field(gt=0.0, le=1e3, description="top speed U [m/s] (physical mode)")] = 3.0
    A_plus: Annotated[float, Field(gt=0.0, le=1e5, description="top acceleration A+ [m/s²] (physical mode)")] = 15.0
    c1_share: Annotated[float, Field(ge=0.0, le=1.0, description="c1/(c1+c2) split of ĉ (physical mode)")] = 0.5
    smooth_width: Annotated[float, Field(gt=0.0, le=100.0, description="width of tanh/logistic [m]")] = 1.0
    schedule: list[StepChange] = Field(default_factory=list, description="step changes of U, A+ in time")

    @model_validator(mode="after")
    def _consistent(self) -> "Controller":
        robot_law = self.law not in LAWS  # (a registered name: a robot law if it is not a Chapter 3 law)
        if robot_law and self.mode == "physical":
            raise ValueError(f"law {self.law!r} takes mode 'raw' (constant c1..c3, omega) or 'dvc'")
        if self.mode == "dvc" and self.law not in dvc_laws():
            raise ValueError(f"mode 'dvc' needs law {' or '.join(map(repr, dvc_laws()))}")
        if robot_law:
            return self
        law = LAWS[self.law]
        why = law.check(self.omega, (self.c1, self.c2)) if self.mode == "raw" else None
        if why:
            raise ValueError(why)
        if self.mode == "physical":
            if not law.adapted:
                raise ValueError(f"mode 'physical' needs an Adapted law ({law.label} has no speed limit to tune)")
            for where, U, A in [("A_plus", self.U, self.A_plus)] + [
                (f"schedule.{i}.A_plus", s.U, s.A_plus) for i, s in enumerate(self.schedule)
            ]:
                beta = A * self.dt / U
                if beta > 1.0 + 1e-12:
                    raise ValueError(
                        f"{where}: beta = A_plus*dt/U = {beta:.3g} > 1; the controller must be faster "
                        f"(dt <= {U / A:.3g} s) or A_plus <= {U / self.dt:.3g} [3.35]"
                    )
        times = [s.t_start for s in self.schedule]
        if times != sorted(times):
            raise ValueError("schedule: t_start values must increase")
        return self


class WorldModel(_Model):
    """The obstacle world of Chapters 4–5 (pymunk hosts it)."""

    omit_unset = ("obstacles",)

    kind: Literal["obstacle-course", "empty", "forest"] = "obstacle-course"
    seed: Annotated[int, Field(ge=0, le=2**31 - 1)] = 0
    layers: Annotated[int, Field(ge=1, le=30, description="obstacle layers (course)")] = 6
    length: Annotated[float, Field(gt=5.0, le=1000.0, description="course length along x [m]")] = 60.0
    width: Annotated[float, Field(gt=5.0, le=1000.0, description="course/arena width [m]")] = 30.0
    density: Annotated[float, Field(gt=0.0, le=0.5, description="forest area fraction")] = 0.05
    start_size: Annotated[float, Field(gt=1.0, le=100.0, description="side of the start square [m]")] = 6.0
    obstacles: Annotated[list[tuple[Coordinate, Coordinate, Annotated[float, Field(gt=0.0, le=100.0)]]] | None, Field(
        max_length=MAX_OBSTACLES,
        description="circles [x, y, r] in m that replace the generated obstacles (what a user built in the app); "
                    "unset = the generator's")] = None


class Robot(_Model):
    """Body, drive and motion model of every robot."""

    radius: Annotated[float, Field(ge=1e-3, le=10.0, description="robot radius [m] (1 m diameter default)")] = 0.5
    v_max: Annotated[float, Field(gt=0.0, le=100.0, description="top speed [m/s]")] = 3.0
    a_max: Annotated[float, Field(gt=0.0, le=1e3, description="actuator acceleration (physics) [m/s²]")] = 10.0
    motion: Literal["kinematic", "physics"] = "kinematic"
    drive: Literal["holonomic", "mecanum", "differential"] = "holonomic"
    spawn_gap: Annotated[float, Field(ge=0.0, le=10.0, description="free space between robots at the start [m]")] = 0.3
    contact_tolerance: Annotated[float, Field(ge=0.0, le=1e-6, description=(
        "float-noise allowance [m]: a collision is an overlap deeper than this, a shallower touch only stops the "
        "robot (at most a micrometre, so it never hides a real contact; docs/readings.md)"))] = 1e-9


class Sensing(_Model):
    """Six-sector range sensing (Figs. 4-3, 5-3)."""

    range: Annotated[float, Field(gt=0.0, le=100.0, description="sensing range R [m]")] = 3.0


class Bests(_Model):
    """Personal-best bookkeeping choices the thesis leaves open (docs/readings.md, "Unstated settings of
    Section 3.5", "Attractors in Figure 3-4")."""

    pbest_order: Literal["before_velocity", "after_velocity"] = "before_velocity"
    attractors: Literal["literal", "ahead"] = "literal"


class ObjectiveModel(_Model):
    """What the swarm optimises: the distance to a source, f = x1, or a benchmark."""

    omit_unset = ("bounds", "boundary")

    kind: ObjectiveKind = "source-distance"
    source: tuple[float, float] = (15.0, 5.0)
    # (below 1e-6 m per unit the benchmark functions overflow over the arena: best_fitness = NaN)
    scale: Annotated[float, Field(ge=1e-6, le=1e4, description="benchmark length scale [m per unit]")] = 1.0
    bounds: Annotated[tuple[Coordinate, Coordinate] | None, Field(
        description="search space [lo, hi] of every component, in the objective's units ((x − source)/scale for a "
                    "benchmark); unset = unbounded, as in the theses")] = None
    boundary: Annotated[Literal["clip", "reflect", "absorb", "periodic"] | None, Field(
        description="how the swarm keeps to the bounds: periodic (the default, as pyswarms), clip, reflect or "
                    "absorb (docs/readings.md, \"Search-space bounds\")")] = None

    @model_validator(mode="after")
    def _bounds(self) -> "ObjectiveModel":
        if self.bounds is not None and not self.bounds[0] < self.bounds[1]:
            raise ValueError(f"bounds: need lo < hi, got {list(self.bounds)}")
        if self.boundary is not None and self.bounds is None:
            raise ValueError("boundary: applies to bounds; set objective.bounds = [lo, hi] too")
        return self


class Acoustics(_Model):
    """Acoustic source localisation (Chapters 7–8): algorithm, signal, swarm and source.

    The robot count, horizon, runs and seed come from ``[sim]``; the ``[controller]``,
    ``[robot]`` and ``[sensing]`` sections do not apply (their values are here).
    """

    omit_unset = ("source",)

    algorithm: StrategyName = Field(
        "xb-pso", description="best-location strategy: A-/X-/B-/XB-PSO (Ch. 7) or GT-PSO (Ch. 8)")
    controller: Literal["adapted", "nonomni"] = Field(
        "adapted",
        description="Adapted PSO [3.11] in the global frame (Ch. 7) or the non-omni DVC controller [8.7] (Ch. 8)")
    mode: Literal["waveform", "surrogate"] = Field(
        "waveform", description="band spectra and cross-correlation, or the APPROXIMATE statistical surrogate")
    snr0_db: Annotated[float, Field(ge=-30.0, le=40.0,
                                    description="SNR at the origin [dB]; sets d_s = R_ref·10^(−SNR0/20)")] = 10.0
    psd_s: Annotated[float, Field(ge=0.0, le=250.0, description="source PSD at 1 m [dB re 1 µPa²/Hz]")] = 120.0
    psd_n: Annotated[float, Field(ge=0.0, le=200.0, description="noise PSD [dB re 1 µPa²/Hz]")] = 60.0
    f_c: Annotated[float, Field(ge=10.0, le=100_000.0, description="centre frequency f_c [Hz]")] = 1000.0
    Q: Annotated[float, Field(ge=0.1, le=1000.0, description="quality factor Q = f_c/B [7.13]")] = 1.5
    tbp: Annotated[float, Field(ge=2.0, le=5000.0, description="time-bandwidth product B·T of a window")] = 100.0
    d_over_lambda: Annotated[float, Field(gt=0.0, le=50.0,
                                          description="hydrophone separation D/λ_c (two-hydrophone strategies)")] = 0.5
    c: Annotated[float, Field(ge=1000.0, le=2000.0, description="sound speed [m/s]")] = 1500.0
    fs: Annotated[float, Field(ge=1000.0, le=1_000_000.0, description="sample rate of the lag grid [Hz]")] = 48_000.0
    full_lag: bool = Field(False, description="search the lag over the whole window instead of ±D/c (waveform mode)")
    lag_peak: Literal["parabolic", "sample"] = Field(
        "parabolic", description="τ_lag: the correlation peak refined by a parabola, or the sample lag itself as "
        "Alg. 5 takes it (then fs sets how finely bearings are resolved)")
    a: Annotated[float, Field(ge=0.0, le=20.0, description="forgetting scale a [7.2]: memory × e^(−a) per step")] = 1.0
    d_0: Annotated[float, Field(ge=0.0, le=10_000.0, description="deployment radius d_0 [m]")] = 50.0
    d_c: Annotated[float, Field(gt=0.0, le=10_000.0, description="convergence radius d_c [m]")] = 50.0
    U: Annotated[float, Field(gt=0.0, le=50.0, description="top speed U = v_max [m/s]")] = 2.0
    dt: Annotated[float, Field(ge=1e-6, le=10.0, description="controller period Δt [s]")] = 1.0
    beta: Annotated[float, Field(gt=0.0, le=1.0, description="sensitivity β: ω = 1 − β, ĉ = βU/√d")] = 0.9
    c1_share: Annotated[float, Field(ge=0.0, le=1.0, description="c1/(c1 + c2)")] = 0.5
    alpha_dvc: Annotated[float, Field(gt=0.0, lt=1.0, description="DVC safety factor α (nonomni)")] = 0.9
    sensing_range: Annotated[float, Field(gt=0.0, le=1000.0,
                                          description="six-sector sensing range [m] (nonomni)")] = 10.0
    robot_radius: Annotated[float, Field(gt=0.0, le=20.0,
                                         description="robot disc radius [m] (1 m encloses a 2 × 1 m hull)")] = 1.0
    guard: bool = Field(False, description="DVC forward guard (ours, not in the thesis): v ≤ α·s_f/Δt")
    r: Annotated[float, Field(ge=0.0, le=10_000.0,
                              description="escort ring radius r [m] round y_g (0 = no escort; nonomni)")] = 0.0
    v_n: Annotated[float, Field(ge=0.0, le=2.0, description="source speed / U [8.8]")] = 0.0
    source_heading_deg: Annotated[float, Field(ge=-360.0, le=360.0,
                                               description="direction the source moves [°] (0 = +x)")] = 0.0
    source_bearing_deg: Annotated[float | None, Field(
        ge=-360.0, le=360.0, description="source bearing from the origin [°]; unset = random per run")] = None
    source: tuple[Coordinate, Coordinate] | None = Field(
        None, description="where the source starts [m] (placed by hand in the app); unset = d_s from SNR0 on "
                          "source_bearing_deg")
    start: Literal["origin", "source"] = Field(
        "origin", description="deploy the robots round the origin or round the source")
    stop_on_converge: bool = Field(False, description="freeze a run once its CoM is within d_c of the source")

    @model_validator(mode="after")
    def _consistent(self) -> "Acoustics":
        if self.full_lag and self.mode == "surrogate":
            raise ValueError("full_lag = true needs mode 'waveform' (the surrogate has no correlation function)")
        if self.r > 0 and self.controller != "nonomni":
            raise ValueError("r > 0 (escorting) needs controller 'nonomni' (the ring is a sensed obstacle)")
        top = self.f_c * (1.0 + 0.5 / self.Q)  # upper band edge f_c + B/2
        if self.fs <= 2.0 * top:
            raise ValueError(f"fs = {self.fs:g} Hz must exceed twice the upper band edge, {2.0 * top:g} Hz")
        return self


SLOErrorValue = Annotated[float | None, Field(ge=0.0, le=100.0)]


class SLOErrorValues(_Model):
    """Single error parameters of Mai's Tab. 4.3 that replace the value of ``slo.errors``
    (unset = the preset's value). Multiplicative σ are factors, additive σ thesis length
    units (a 100 × 100 area), rotations radians, failures probabilities."""

    range_sigma_m: Annotated[SLOErrorValue, Field(description="range: stochastic multiplicative σ_m [4.2]")] = None
    range_sigma_a: Annotated[SLOErrorValue, Field(description="range: stochastic additive σ_a [4.3]")] = None
    range_perm_sigma_m: Annotated[SLOErrorValue, Field(description="range: permanent multiplicative σ̂_m")] = None
    range_perm_sigma_a: Annotated[SLOErrorValue, Field(description="range: permanent additive σ̂_a")] = None
    range_p_fail: Annotated[float | None, Field(ge=0.0, le=1.0, description="range: failure probability")] = None
    odometry_sigma_m: Annotated[SLOErrorValue, Field(
        description="odometry: stochastic multiplicative σ_m [4.4]")] = None
    odometry_sigma_a: Annotated[SLOErrorValue, Field(description="odometry: stochastic additive σ_a")] = None
    odometry_perm_sigma_m: Annotated[SLOErrorValue, Field(description="odometry: permanent multiplicative σ̂_m")] = None
    odometry_perm_sigma_a: Annotated[SLOErrorValue, Field(
        description="odometry: permanent additive σ̂_a (velocity offset)")] = None
    odometry_p_fail: Annotated[float | None, Field(ge=0.0, le=1.0, description="odometry: failure probability")] = None
    odometry_sigma_r: Annotated[SLOErrorValue, Field(description="odometry: stochastic rotation σ_r [rad]")] = None
    odometry_perm_sigma_r: Annotated[SLOErrorValue, Field(description="odometry: permanent rotation σ̂_r [rad]")] = None

    def values(self) -> dict[str, float]:
        """The fields that are set, as :meth:`ErrorModel.with_values` keywords."""
        return {k: v for k, v in self.model_dump().items() if v is not None}


class SLO(_Model):
    """Simultaneous Localisation and Optimisation (Mai): robots act on positions they estimate
    from noisy ranges and odometry.

    ``swarm = "slo"`` runs Mai's SLO swarm (PSO or random-walk motion; ``sim.robots`` particles,
    ``sim.steps`` generations). ``swarm = "host"`` runs the scene's own swarm (the Chapter 3
    swarm of ``[controller]``/``[objective]``, the fleet of a ``[world]``, the acoustic swarm
    of ``[acoustics]``) on SLO-estimated (``positions = "slo"``) or true
    (``positions = "oracle"``) positions, same seed either way. ``"chapter3"`` is read as
    ``"host"``. Lengths are in thesis units on a 100-wide area, rescaled to the scene
    (docs/readings.md, "Thesis units on a scene (ours)").
    """

    omit_unset = ("ranging",)  # added later: a scene that leaves it unset dumps as before

    swarm: Literal["slo", "host"] = Field(
        "slo",
        description="Mai's SLO swarm, or the scene's own swarm (Ch. 3, [world] fleet, [acoustics]) on SLO positions")
    positions: Literal["slo", "oracle"] = Field("slo", description="host swarm: estimated or true positions")
    motion: Literal["pso", "random_walk"] = Field(
        "pso", description="SLO swarm: SPSO 2011 in each robot's frame or a random walk")
    objective: Literal["ackley", "griewank", "line", "plane", "rastrigin", "rosenbrock", "sphere"] = Field(
        "sphere", description="SLO swarm: 2-D benchmark, minimised (DEAP forms)")
    selection: SelectionName = Field("css", description="candidate selection [3.7]-[3.9]")
    errors: Literal["none", "low", "high"] = Field("low", description="sensor error set of Tab. 4.3")
    error_values: SLOErrorValues = Field(default_factory=SLOErrorValues,
                                         description="single error parameters replacing the set's")
    prediction_weight: Annotated[float, Field(ge=0.0, le=1.0, description="prediction weight w of [3.7]")] = 0.5
    delta_cos: Annotated[float, Field(ge=0.0, le=1.0, description="mitigation threshold δ_cos [3.5]")] = 0.03
    delta_v: Annotated[float, Field(ge=0.0, le=10.0, description="mitigation threshold δ_v [3.6]")] = 0.03
    literal_eq_3_1: bool = Field(
        False, description="use [3.1] as printed (known slip) instead of the corrected law of cosines")
    entry_policy: EntryPolicy = Field(
        "geometric_nearest", description="estimates of robots outside the neighbourhood and where an arriving "
        "neighbour starts: frozen, then the geometric candidate nearest the old estimate (our reading of Mai §4.5, "
        "§4.5.4); frozen and blended; frozen, then a random mirror candidate; or carried by odometry (an extension "
        "that assumes every robot's odometry is heard)")
    neighbourhood: Literal["knn", "radius", "full", "random", "ring"] = Field("knn", description="who localises whom")
    neighbourhood_param: Annotated[float | None, Field(
        ge=0.0, le=1e4, description="k (knn), r (radius), n (ring), p (random); unset = 5, 25, 2, 0.5")] = None
    walk_speed: Annotated[float, Field(gt=0.0, le=100.0,
                                       description="random walk: top step length (thesis units)")] = 5.0
    radial: Literal["uniform_radius", "uniform_area"] = Field(
        "uniform_radius", description="SLO swarm, SPSO 2011 [3.11]: the point in the hypersphere H(G, r) is r·ρ·g/|g| "
        "with ρ ~ U(0, 1), as the SPSO 2011 reference code draws it (denser near G; Mai does not say), or √ρ, uniform "
        "over the disc")
    unit: Annotated[float | None, Field(
        gt=0.0, le=1e4, description="host swarm: metres per thesis length unit (the thesis area is 100 wide); "
                                    "unset = the scene's size / 100")] = None
    quality_threshold: Annotated[float | None, Field(
        ge=-1e12, le=1e12,
        description="fitness T of 'first generation with best <= T'; unset = the benchmark's")] = None
    ranging: Literal["all", "neighbours"] | None = Field(
        None, description="SLO swarm: every robot ranges and localises every other ('all', the thesis, O(N²); "
        "unset means 'all'), or only "
        "the robots of its neighbourhood (ours, O(N·k): knn, radius or ring, CSS; a robot remembers the last few that "
        "left, frozen, and starts any other arriving neighbour from its initial estimate)")

    @field_validator("swarm", mode="before")
    @classmethod
    def _chapter3_is_host(cls, value: object) -> object:
        return "host" if value == "chapter3" else value  # the name before fleets and sonar took SLO

    @model_validator(mode="after")
    def _consistent(self) -> "SLO":
        p = self.neighbourhood_param
        if p is not None:
            if self.neighbourhood == "random" and not 0.0 < p <= 1.0:
                raise ValueError(f"neighbourhood_param = {p:g}: a random neighbourhood takes a probability in (0, 1]")
            if self.neighbourhood in ("knn", "ring") and (p < 1 or p != int(p)):
                raise ValueError(f"neighbourhood_param = {p:g}: {self.neighbourhood} takes a whole number >= 1")
        if self.positions == "oracle" and self.swarm != "host":
            raise ValueError("positions = 'oracle' needs swarm = 'host' (the SLO swarm always localises)")
        if self.ranging == "neighbours":
            if self.swarm != "slo":
                raise ValueError("ranging = 'neighbours' is the SLO swarm's (swarm = 'slo'); a host swarm ranges all")
            from shoal.engine.slo.ranging_modes import refusal  # (plain Python: no SLO kernels to check a preset)

            why = refusal(selection=self.selection, entry_policy=self.entry_policy, neighbourhood=self.neighbourhood,
                          motion=self.motion, ar_gain=0.0)
            if why:
                raise ValueError(f"ranging = 'neighbours': {why}")
        return self


class Arena(_Model):
    """The square drawn in the app, ``[-half_size, half_size]²``."""

    half_size: Annotated[float, Field(gt=0.0, le=1e5)] = 20.0


class View(_Model):
    """Drawing choices of the browser app."""

    trail_seconds: Annotated[float, Field(ge=0.0, le=600.0)] = 15.0
    steps_per_second: Annotated[float, Field(gt=0.0, le=240.0, description="playback rate")] = 20.0


class Scenario(_Model):
    """A complete, validated scenario: a preset file plus overrides. Beyond its fields it takes
    the sections of the plug-in scene kinds (:mod:`shoal.presets.kinds`), each validated by its
    kind's model; any other name is refused."""

    model_config = ConfigDict(extra="allow")
    # An unset section (world, acoustics, slo, a new kind's) is left out of a dump, so that a
    # scenario written down (run.json, a replay, a preset file) reads the same whichever kinds
    # Shoal has: adding a kind changes no file of another kind's run.
    omit_unset_optional = True

    schema_version: Literal[1] = 1
    name: Annotated[str, Field(min_length=1, max_length=80)] = "custom"
    description: Annotated[str, Field(max_length=2000)] = ""
    sim: Sim = Field(default_factory=Sim)
    init: Init = Field(default_factory=Init)
    controller: Controller = Field(default_factory=Controller)  # type: ignore[arg-type]  # (mypy misreads Field("…") defaults)
    bests: Bests = Field(default_factory=Bests)
    objective: ObjectiveModel = Field(default_factory=ObjectiveModel)
    arena: Arena = Field(default_factory=Arena)
    world: WorldModel | None = None
    acoustics: Acoustics | None = None
    slo: SLO | None = None
    robot: Robot = Field(default_factory=Robot)
    sensing: Sensing = Field(default_factory=Sensing)
    view: View = Field(default_factory=View)

    def marks(self) -> dict[str, Any]:
        """Where each value that shapes this scene's runs comes from: stated, read, fitted or
        ours, with its source (:func:`shoal.presets.marks.provenance`; None: unmarked)."""
        from .marks import provenance  # (a run reads no marks)

        return provenance(self)

    @model_validator(mode="after")
    def _across_sections(self) -> "Scenario":
        if self.model_extra:
            self.__pydantic_extra__ = check_plugin_sections(self.model_extra)
        check_scene(self)  # one kind, its dimensions, a law of the registry it reads
        if self.world is not None and 2.0 * self.robot.radius >= self.world.start_size:
            raise ValueError(f"robot.radius = {self.robot.radius:g}: a robot must fit the start square "
                             f"(world.start_size = {self.world.start_size:g})")
        law = None if self.controller.law in LAWS else robot_laws().get(self.controller.law)
        if law is not None and law.body_frame and self.robot.drive != "differential":
            raise ValueError(f"controller.law {self.controller.law!r} needs robot.drive = 'differential'")
        if self.acoustics is not None:
            a = self.acoustics
            need = resolve(STRATEGIES_REF)[a.algorithm].min_robots
            if self.sim.robots < need:
                raise ValueError(f"sim.robots = {self.sim.robots}: acoustics.algorithm {a.algorithm!r} "
                                 f"needs at least {need}")
        if self.slo is not None:
            if self.sim.d != 2:
                raise ValueError("sim.d must be 2 with [slo]")
            if self.sim.robots < 2:
                raise ValueError(f"sim.robots = {self.sim.robots}: [slo] needs at least 2 robots")
        return self

    def section(self, name: str) -> Any:
        """The section ``name`` (a field such as ``world``, or a plug-in kind's), None if unset."""
        if name in type(self).model_fields:
            return getattr(self, name)
        return (self.model_extra or {}).get(name)


def on_slo_positions(scenario: Scenario) -> bool:
    """Does the scene's own swarm act on SLO-estimated positions (``[slo] swarm = "host"``,
    ``positions = "slo"``)?"""
    slo = scenario.slo
    return slo is not None and slo.swarm == "host" and slo.positions == "slo"


_Section = TypeVar("_Section")


def required(section: _Section | None, name: str) -> _Section:
    """An optional section a caller cannot do without (``required(sc.acoustics, "acoustics")``):
    the section, or a ``ValueError`` saying the scenario has no ``[name]``."""
    if section is None:
        raise ValueError(f"this scenario has no [{name}] section")
    return section
