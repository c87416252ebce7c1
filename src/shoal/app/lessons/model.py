"""What a lesson is: an ordered list of steps, each with a few sentences, an optional scene to
set up, an instruction, and a question whose answer the student reveals on demand.

A step's scene is a shipped preset plus field values by dotted path (``controller.omega``).
A step that names no preset builds on the scene of the step before: the nearest earlier
step that names a preset, with the values of every step from there on, later ones winning.
*Set up* always loads that scene afresh (the preset's seed, step 0), whatever the student
did in between. An optional ``check`` states what a headless run of that scene must show
(:mod:`.verify`), so the text stays true for what the student sees.
"""

from __future__ import annotations

import math
from typing import Annotated, Any, Union

from pydantic import BaseModel, ConfigDict, Field, StrictBool, StrictFloat, StrictInt, StrictStr, model_validator

Text = Annotated[str, Field(min_length=1)]
Bounds = tuple[float, float]  # closed range [lo, hi]; TOML's inf and -inf leave a side open
FieldValue = Union[StrictBool, StrictInt, StrictFloat, StrictStr, list[Any]]
FIELD_PATH = r"^[a-z_]+(\.[A-Za-z0-9_]+)+$"  # a dotted preset path: section.field[.more]
PRESET_NAME = r"^[a-z0-9][a-z0-9-]*$"  # a shipped preset (never a file path)


class _Model(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=True)


AGGREGATES = ("final", "max", "min", "mean")


class Check(_Model):
    """After ``steps`` steps of ``runs`` seeded runs (run 0 is what the app shows), every
    named metric lies in its bounds: ``final`` at the last step; ``max``, ``min`` and
    ``mean`` over steps ``after``..``steps``. ``quote``: the words of the step's answer that
    quote a reading (``"mean.e_abs_mean" = "about 4 units"``), which must agree with it
    (:mod:`.quotes`)."""

    steps: Annotated[int, Field(ge=1, le=20_000)]
    runs: Annotated[int, Field(ge=1, le=20)] = 1
    after: Annotated[int, Field(ge=1, le=20_000)] = 1
    final: dict[str, Bounds] = Field(default_factory=dict)
    max: dict[str, Bounds] = Field(default_factory=dict)
    min: dict[str, Bounds] = Field(default_factory=dict)
    mean: dict[str, Bounds] = Field(default_factory=dict)
    quote: dict[str, Annotated[str, Field(min_length=1, max_length=80)]] = Field(default_factory=dict)

    @model_validator(mode="after")
    def _bounds(self) -> "Check":
        if self.after > self.steps:
            raise ValueError(f"after = {self.after} is beyond steps = {self.steps}")
        named = False
        for kind in AGGREGATES:
            for metric, (lo, hi) in getattr(self, kind).items():
                named = True
                if not lo <= hi:
                    raise ValueError(f"{kind}.{metric}: bounds [{lo:g}, {hi:g}] are empty")
        if not named:
            raise ValueError("names no metric: add e.g. final.max_speed = [0, 10]")
        for key in self.quote:
            kind, _, metric = key.partition(".")
            if kind not in AGGREGATES or metric not in getattr(self, kind):
                raise ValueError(f"quote.{key!r}: quotes no reading of this check (kind.metric of one it names)")
        return self


class Setup(_Model):
    """The scene a step's *Set up* button loads."""

    preset: Annotated[str, Field(pattern=PRESET_NAME, max_length=60)] | None = None
    values: dict[Annotated[str, Field(pattern=FIELD_PATH, max_length=80)], FieldValue] = Field(default_factory=dict)
    check: Check | None = None


class RoundSpec(_Model):
    """How a step's question is asked of a class (``shoal serve --lecture``): multiple ``choices``
    or a number in ``unit``, and the right ``answer`` if there is one; ``question`` words it for
    a round when the step's own question is long or asks two things."""

    question: Annotated[str, Field(min_length=1, max_length=600)] | None = None
    choices: Annotated[list[Annotated[str, Field(min_length=1, max_length=120)]], Field(min_length=2,
                                                                                       max_length=6)] | None = None
    unit: Annotated[str, Field(max_length=24)] | None = None
    answer: StrictStr | StrictInt | StrictFloat | None = None

    @model_validator(mode="after")
    def _one_kind(self) -> "RoundSpec":
        if (self.choices is None) == (self.unit is None):
            raise ValueError("give choices (multiple choice) or a unit (a number), not both")
        if self.choices is not None:
            if len(set(self.choices)) != len(self.choices):
                raise ValueError("two choices are the same")
            if self.answer is not None and self.answer not in self.choices:
                raise ValueError(f"answer {self.answer!r} is not one of the choices")
        elif self.answer is not None and (isinstance(self.answer, str) or not math.isfinite(self.answer)):
            raise ValueError(f"answer {self.answer!r}: a number round's answer is a finite number")
        return self


class Step(_Model):
    title: Annotated[str, Field(min_length=1, max_length=80)]
    text: Annotated[str, Field(min_length=1, max_length=1500)]
    setup: Setup | None = None
    instruction: Annotated[str, Field(min_length=1, max_length=600)]
    question: Annotated[str, Field(min_length=1, max_length=600)]
    answer: Annotated[str, Field(min_length=1, max_length=1500)]
    round: RoundSpec | None = None  # the question as a class's round (a ```round block)


class Lesson(_Model):
    id: Annotated[str, Field(pattern=PRESET_NAME, max_length=60)]
    title: Annotated[str, Field(min_length=1, max_length=80)]
    chapter: Annotated[str, Field(min_length=1, max_length=12)]
    summary: Annotated[str, Field(min_length=1, max_length=400)]
    intro: str = ""
    steps: Annotated[list[Step], Field(min_length=1, max_length=12)]
    try_it: Annotated[list[Text], Field(min_length=1, max_length=10)]

    @model_validator(mode="after")
    def _every_setup_has_a_preset(self) -> "Lesson":
        preset = None
        for i, step in enumerate(self.steps):
            if step.setup is not None:
                preset = step.setup.preset or preset
                if preset is None:
                    raise ValueError(f"step {i + 1} '{step.title}': setup names no preset, and no earlier step "
                                     "does (add preset = \"...\")")
        return self

    def scene(self, index: int) -> tuple[str, dict[str, Any]] | None:
        """The (preset, field values) step ``index`` sets up, or None when it sets up nothing."""
        if self.steps[index].setup is None:
            return None
        setups = [s.setup for s in self.steps[: index + 1] if s.setup is not None]
        start = max(i for i, s in enumerate(setups) if s.preset is not None)
        values: dict[str, Any] = {}
        for s in setups[start:]:
            values.update(s.values)
        return str(setups[start].preset), values

    @property
    def label(self) -> str:
        """How the lesson is listed: chapter and title."""
        ch = self.chapter if not self.chapter[0].isdigit() else f"Ch. {self.chapter}"
        return f"{ch} · {self.title}"
