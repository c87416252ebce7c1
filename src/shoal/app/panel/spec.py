"""Panels as data: a scene kind describes its controls as :class:`Tab` s and :class:`Folder` s
of controls, and the shared :class:`~.panel.Panel` builds, wires and syncs them.

A control bound to a preset field (a dotted path, ``key``) reads its value from the scenario
and turns a user's change into ``{path: value}``; the panel sends that through the preset
model (``Session.apply``), so a refused value shows a red notification and the handle goes
back. A control may instead ``read``/``write`` several fields (``write`` returns the changes,
None for nothing to do), or ``act`` on the session without touching the scenario (the
selected robot, the view), in which case ``read`` may say what it shows (or None: the handle
keeps its own value). Readouts are :class:`Text` s whose content the panel computes when the
scenario changes (``compute``) or with every snapshot drawn (``on_snapshot``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Callable, Protocol, Union

import annotated_types as at
from pydantic import BaseModel

from shoal.presets.kinds import plugin_sections
from shoal.presets.models import Scenario

from ..session.session import Session
from ..session.snapshot import Snapshot
from .plots import Chart, PlotSpec

Visible = Callable[[Session], bool]  # shown when true
Read = Callable[[Session], Any]
Write = Callable[[Session, Any], Union[dict[str, Any], None]]  # the scenario changes a value asks for


class PanelAPI(Protocol):
    """What a control's action or a kind's hook may ask of the panel it lives in."""

    session: Session
    handles: dict[str, Any]
    removed: bool

    def apply(self, changes: dict[str, Any], what: str) -> bool: ...

    def notify(self, title: str, body: str, color: str = "blue") -> None: ...

    def select_robot(self, robot: int) -> None: ...

    def set_quietly(self, handle: Any, value: Any) -> None: ...


Act = Callable[[PanelAPI, Any], None]


class Host(PanelAPI, Protocol):
    """What the shared sections (the Replay folder, the Compare folder) ask of the panel."""

    gui: Any
    tabs: Any
    top: list[Any]
    services: Any  # :class:`~.panel.Services`
    controls: int  # the user's control events so far

    @property
    def syncing(self) -> bool: ...

    def quietly(self) -> Any: ...

    def on_user_change(self, handle: Any, act: Callable[[], object]) -> None: ...

    def refuse(self, err: Any, what: str) -> None: ...

    def send_file(self, name: str, content: bytes) -> None: ...

    def stem(self) -> str: ...

    def sync(self) -> None: ...

    def refresh_status(self) -> None: ...

    def compare_choices(self) -> dict[str, dict[str, Any]]: ...


# ---------------------------------------------------------------------------- preset fields
def field_bounds(path: str) -> tuple[float, float]:
    """The closed range [lo, hi] the model allows for a numeric field ``section.name`` (±inf when open)."""
    section, name = path.split(".")
    field = Scenario.model_fields.get(section)
    annotation = field.annotation if field is not None else plugin_sections()[section]  # a plug-in kind's section
    model = next((a for a in getattr(annotation, "__args__", (annotation,)) if hasattr(a, "model_fields")), annotation)
    if not (isinstance(model, type) and issubclass(model, BaseModel)):
        raise ValueError(f"{path}: [{section}] is not a section of a preset")
    lo, hi = -math.inf, math.inf
    for m in model.model_fields[name].metadata:
        if isinstance(m, at.Ge):
            lo = max(lo, _number(m.ge, path))
        elif isinstance(m, at.Gt):
            lo = max(lo, _number(m.gt, path))
        elif isinstance(m, at.Le):
            hi = min(hi, _number(m.le, path))
        elif isinstance(m, at.Lt):
            hi = min(hi, _number(m.lt, path))
    return lo, hi


def _number(bound: object, path: str) -> float:
    """A bound of a numeric field (annotated_types allows any comparable)."""
    if not isinstance(bound, (int, float)):
        raise TypeError(f"{path}: the model's bound {bound!r} is not a number")
    return float(bound)


def get_path(scenario: Scenario, path: str) -> Any:
    """The value of the dotted field ``path`` of ``scenario``."""
    value: Any = scenario
    for part in path.split("."):
        value = getattr(value, part)
    return value


def nice_ceil(v: float) -> float:
    if v <= 0:
        return 1.0
    mag = 10 ** math.floor(math.log10(v))
    for m in (1, 2, 5, 10):
        if m * mag >= v:
            return m * mag
    return 10 * mag


def round_sig(v: float, digits: int = 6) -> float:
    return float(f"{v:.{digits}g}")


def fmt(v: float, unit: str = "") -> str:
    if not math.isfinite(v):
        return "—"
    return f"{v:.4g}{(' ' + unit) if unit else ''}"


# ---------------------------------------------------------------------------- controls
@dataclass(frozen=True)
class Slider:
    """A slider; by default bound to the preset field ``key``, its limits from the model
    narrowed to ``lo, hi`` (the useful on-screen range, widened to hold the value)."""

    key: str
    label: str
    lo: float
    hi: float
    step: float
    hint: str = ""
    integer: bool = False
    marks: tuple[tuple[float, str], ...] | None = None
    read: Read | None = None
    write: Write | None = None
    act: Act | None = None
    visible: Visible | None = None
    label_of: Callable[[Scenario], str] | None = None  # a label that follows the scenario
    widen: bool = False  # (not a field) raise ``hi`` to twice a larger value
    initial: float = 0.0  # the value of a local slider that reads nothing

    @property
    def field(self) -> bool:
        return self.read is None and self.act is None

    def range(self, value: float) -> tuple[float, float]:
        """The on-screen range for ``value``."""
        if not self.field:
            hi = float(min(100.0, 2 * value)) if self.widen and value > self.hi else self.hi
            return self.lo, hi
        lo, hi = field_bounds(self.key)
        smin, smax = max(self.lo, lo), min(self.hi, hi)
        if value > smax:
            smax = min(hi, float(nice_ceil(1.5 * value)))
        if value < smin:
            smin = max(lo, value)
        return smin, smax


@dataclass(frozen=True)
class Dropdown:
    """A choice among ``options`` (labels); by default the preset field ``key``'s value itself."""

    key: str
    label: str
    options: tuple[str, ...] | Callable[[Session], tuple[str, ...]]
    hint: str = ""
    read: Read | None = None
    write: Write | None = None
    act: Act | None = None
    visible: Visible | None = None


@dataclass(frozen=True)
class Checkbox:
    key: str
    label: str
    hint: str = ""
    read: Read | None = None
    write: Write | None = None
    act: Act | None = None
    visible: Visible | None = None


@dataclass(frozen=True)
class Number:
    """A number box (integers when ``step`` is 1); ``high`` bounds it by the session (robots)."""

    key: str
    label: str
    read: Read | None
    write: Write | None = None
    act: Act | None = None
    low: float = 0.0
    high: Callable[[Session], float] | None = None
    step: float = 1.0
    hint: str = ""
    visible: Visible | None = None
    follow: bool = False  # read again with every snapshot drawn (a robot picked in the arena)


@dataclass(frozen=True)
class Button:
    key: str
    label: str
    act: Callable[[PanelAPI], None]
    hint: str = ""


@dataclass(frozen=True)
class Text:
    """Markdown: fixed ``text``, or a readout (``compute`` when the scenario changes,
    ``on_snapshot`` with every snapshot drawn)."""

    key: str = ""
    text: str = ""
    compute: Callable[[Session], str] | None = None
    on_snapshot: Callable[[Session, Snapshot], str] | None = None
    visible: Visible | None = None


@dataclass(frozen=True)
class Figure:
    """A plotly figure the kind draws (``make``) and updates (``refresh``, with the plots)."""

    key: str
    make: Callable[[Session], Any]
    refresh: Callable[[PanelAPI, Any], None]
    aspect: float = 1.0
    title: str = ""  # what the board calls it when it is the scene's main plot


Control = Union[Slider, Dropdown, Checkbox, Number, Button, Text, Figure, PlotSpec, Chart, "Folder"]


@dataclass(frozen=True)
class Folder:
    label: str
    items: tuple[Control, ...]
    key: str = ""
    expand: bool | Callable[[Session], bool] = True
    visible: Visible | None = None


@dataclass(frozen=True)
class Tab:
    label: str
    items: tuple[Control, ...]


# ---------------------------------------------------------------------------- what a kind brings
Status = Callable[[Session, dict[str, float], str], str]  # (session, readout, "▶ playing"…) → the status line
Click = Callable[[PanelAPI, float, float, Union[str, None]], str]  # a click in the arena at world (x, y)


@dataclass(frozen=True)
class KindPanel:
    """A scene kind's part of the panel: its tabs, the folders above them, its status line, how
    swarm B may differ (Compare), what a rebuild says, what a click in the arena does, and what
    a drag on its draggable layer does (``drag``, given to the kind's view)."""

    tabs: tuple[Tab, ...]
    status: Status
    folders: tuple[Folder, ...] = ()
    compare: Callable[[Session], dict[str, dict[str, Any]]] = field(default=lambda session: {})
    rebuilt: Callable[[Session, str, dict[str, Any]], Union[tuple[str, str], None]] = field(
        default=lambda session, what, changes: None)
    click: Click | None = None
    drag: Callable[..., None] | None = None
    export_note: str = ""
    state: Any = None  # the kind's own state of this panel (the fleet's world editor)
    main: Callable[[Session], Union[str, None]] | None = None  # the key of the plot the scene is about (the board's)
