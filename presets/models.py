"""Pydantic models of a Shoal scenario (one preset file = one ``Scenario``).

Every field has a range; unknown fields are refused; error locations are dotted paths
such as ``controller.omega`` so the CLI and the UI can name the bad field.
"""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import BaseModel, ConfigDict, Field, model_validator

from shoal.engine.laws import LawName
from shoal.engine.objectives import ObjectiveName

Coefficient = Annotated[float, Field(ge=0.0, le=100.0)]


class _Model(BaseModel):
    model_config = ConfigDict(extra="forbid", validate_assignment=True)


class Sim(_Model):
    """Size, length and seed of a run."""

    robots: Annotated[int, Field(ge=1, le=100_000, description="number of particles / robots")] = 20
    d: Annotated[int, Field(ge=1, le=3, description="spatial dimensions")] = 2
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
    mode: Literal["raw", "physical"] = "physical"
    dt: Annotated[float, Field(gt=0.0, le=10.0, description="controller period Δt [s]")] = 0.1
    omega: Annotated[float, Field(ge=-1.0, le=1.2, description="inertia weight ω (raw mode)")] = 0.5
    c1: Annotated[Coefficient, Field(description="cognitive coefficient (raw mode)")] = 0.5
    c2: Annotated[Coefficient, Field(description="social coefficient (raw mode)")] = 0.5
    U: Annotated[float, Field(gt=0.0, le=1e3, description="top speed U [m/s] (physical mode)")] = 3.0
    A_plus: Annotated[float, Field(gt=0.0, le=1e5, description="top acceleration A+ [m/s²] (physical mode)")] = 15.0
    c1_share: Annotated[float, Field(ge=0.0, le=1.0, description="c1/(c1+c2) split of ĉ (physical mode)")] = 0.5
    smooth_width: Annotated[float, Field(gt=0.0, le=100.0, description="width of tanh/logistic [m]")] = 1.0
    schedule: list[StepChange] = Field(default_factory=list, description="step changes of U, A+ in time")

    @model_validator(mode="after")
    def _consistent(self) -> "Controller":
        adapted = self.law != "standard"
        if self.mode == "raw" and adapted and not (0.0 <= self.omega < 1.0):
            raise ValueError(f"omega = {self.omega:g}: an Adapted law needs 0 <= omega < 1 [3.14]")
        if self.mode == "physical":
            if not adapted:
                raise ValueError("mode 'physical' needs an Adapted law (standard PSO has no speed limit)")
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


class Bests(_Model):
    """Personal-best bookkeeping choices the thesis leaves open (spec §20 item 12, §22)."""

    pbest_order: Literal["before_velocity", "after_velocity"] = "before_velocity"
    attractors: Literal["literal", "ahead"] = "literal"


class ObjectiveModel(_Model):
    """What the swarm optimises: the distance to a source, f = x1, or a benchmark."""

    kind: ObjectiveName = "source-distance"
    source: tuple[float, float] = (15.0, 5.0)
    scale: Annotated[float, Field(gt=0.0, le=1e4, description="benchmark length scale [m per unit]")] = 1.0


class Arena(_Model):
    """The square drawn in the app, ``[-half_size, half_size]²``."""

    half_size: Annotated[float, Field(gt=0.0, le=1e5)] = 20.0


class View(_Model):
    """Drawing choices of the browser app."""

    trail_seconds: Annotated[float, Field(ge=0.0, le=600.0)] = 15.0
    steps_per_second: Annotated[float, Field(gt=0.0, le=240.0, description="playback rate")] = 20.0


class Scenario(_Model):
    """A complete, validated scenario: a preset file plus overrides."""

    schema_version: Literal[1] = 1
    name: Annotated[str, Field(min_length=1, max_length=80)] = "custom"
    description: Annotated[str, Field(max_length=2000)] = ""
    sim: Sim = Field(default_factory=Sim)
    init: Init = Field(default_factory=Init)
    controller: Controller = Field(default_factory=Controller)
    bests: Bests = Field(default_factory=Bests)
    objective: ObjectiveModel = Field(default_factory=ObjectiveModel)
    arena: Arena = Field(default_factory=Arena)
    view: View = Field(default_factory=View)
