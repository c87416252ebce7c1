"""What every tab's control panel shares: the header (preset, status, playback, speed, seed),
the Export, Notes and Lessons tabs, and the rule that every change goes through the scenario
model.

A slider is a preset field (a dotted path into :class:`Scenario`); its limits come from the
pydantic model, narrowed to a range that is useful on screen. A change is validated by
``session.apply``; a refused value shows a red notification and the handle goes back to the
previous value, the running scene untouched.

Subclasses (``panels.Panels`` for Chapter 3, ``fleet_panels.FleetPanels`` for Chapters 4–5)
add their own tabs in ``_build_tabs``, sync them in ``_sync_body`` and redraw their readouts
and plots in ``refresh_*``. ``replace(scenario)`` comes from the tab: it loads a scenario
that may need another kind of session (and so other panels).
"""

from __future__ import annotations

import contextlib
import math
import threading
from dataclasses import dataclass
from importlib import resources
from typing import Any, Callable, ClassVar, Iterator

import annotated_types as at
import numpy as np

from shoal.presets.io import PresetError
from shoal.presets.models import Scenario

from .base_session import BaseSession, parse_upload
from .compare_panel import CompareGui
from .lessons.panel import LessonProgress, LessonsPanel
from .lessons.scenes import load_scene
from .preset_menu import PresetMenu
from .replay_panel import ReplayGui
from .twin_view import twin_series

Notify = Callable[[str, str, str], None]
SendFile = Callable[[str, bytes], None]
Replace = Callable[[Scenario], Any]  # loads a scene (maybe of another kind); returns the session shown

PLAYBACK = ("Play", "Pause", "Step", "Reset")


@dataclass(frozen=True)
class SliderSpec:
    """A slider bound to a preset field; ``lo, hi`` is the useful on-screen range."""

    path: str
    label: str
    lo: float
    hi: float
    step: float
    hint: str
    integer: bool = False
    marks: tuple[tuple[float, str], ...] | None = None


SPEED = SliderSpec("view.steps_per_second", "speed [steps/s]", 1.0, 240.0, 1.0, "playback rate")
TRAIL = SliderSpec("view.trail_seconds", "trail [s]", 0.0, 60.0, 1.0, "length of the drawn trails")


def field_bounds(path: str) -> tuple[float, float]:
    """The closed range [lo, hi] the model allows for a numeric field (±inf when open)."""
    section, name = path.split(".")
    model = Scenario.model_fields[section].annotation
    model = next((a for a in getattr(model, "__args__", (model,)) if hasattr(a, "model_fields")), model)
    lo, hi = -math.inf, math.inf
    for m in model.model_fields[name].metadata:  # type: ignore[union-attr]
        if isinstance(m, at.Ge):
            lo = max(lo, float(m.ge))
        elif isinstance(m, at.Gt):
            lo = max(lo, float(m.gt))
        elif isinstance(m, at.Le):
            hi = min(hi, float(m.le))
        elif isinstance(m, at.Lt):
            hi = min(hi, float(m.lt))
    return lo, hi


def _nice_ceil(v: float) -> float:
    if v <= 0:
        return 1.0
    mag = 10 ** math.floor(math.log10(v))
    for m in (1, 2, 5, 10):
        if m * mag >= v:
            return m * mag
    return 10 * mag


def slider_range(spec: SliderSpec, value: float) -> tuple[float, float]:
    """The on-screen range, inside the model's range, widened to hold ``value``."""
    lo, hi = field_bounds(spec.path)
    smin, smax = max(spec.lo, lo), min(spec.hi, hi)
    if value > smax:
        smax = min(hi, float(_nice_ceil(1.5 * value)))
    if value < smin:
        smin = max(lo, value)
    return smin, smax


def get_path(scenario: Scenario, path: str) -> Any:
    section, name = path.split(".")
    return getattr(getattr(scenario, section), name)


def round_sig(v: float, digits: int = 6) -> float:
    return float(f"{v:.{digits}g}")


def notes_text(name: str = "ch3") -> str:
    """Teaching notes ``notes/<name>.md`` shipped in ``shoal.static``, or a short fallback."""
    try:
        return resources.files("shoal.static").joinpath(f"notes/{name}.md").read_text(encoding="utf-8")
    except (FileNotFoundError, ModuleNotFoundError, OSError):
        return (f"# Teaching notes\n\nThe notes `notes/{name}.md` are not installed. "
                "Move the sliders and watch the arena and the *Plots* tab.")


def fmt(v: float, unit: str = "") -> str:
    if not math.isfinite(v):
        return "—"
    return f"{v:.4g}{(' ' + unit) if unit else ''}"


class PanelsBase:
    """The GUI handles of one tab, wired to its session. ``gui`` is a viser ``GuiApi``
    (``client.gui`` for a browser tab, ``server.gui`` in tests)."""

    SLIDERS: ClassVar[tuple[SliderSpec, ...]] = ()
    EXPORT_NOTE: ClassVar[str] = ""  # more words for the Export tab

    def __init__(self, gui: Any, session: BaseSession, notify: Notify, send_file: SendFile,
                 replace: Replace | None = None, lessons: LessonProgress | None = None,
                 menu: PresetMenu | None = None) -> None:
        self.gui, self.session, self.notify, self.send_file = gui, session, notify, send_file
        self.replace = replace
        self.lesson_progress = lessons if lessons is not None else LessonProgress()  # the tab keeps it
        self.menu = menu or PresetMenu()  # the tab's, so that uploads outlive a swap of panels
        self._local = threading.local()  # per thread: programmatic .value fires callbacks inline
        self.sliders: dict[str, Any] = {}
        self.top: list[Any] = []  # top-level handles: removing them removes the whole panel
        self.removed = False
        self._series: dict[int, tuple] = {}  # uPlot series last sent, by handle (see push_uplot)
        self._build_header()
        self.replay_gui = ReplayGui(self)
        self._build_above_tabs()
        self.tabs = gui.add_tab_group()
        self.top.append(self.tabs)
        focus = self.lesson_progress.focus  # a lesson's Set up rebuilt this panel: keep its tab in view
        if focus:
            self._build_lessons()
        self._build_tabs()
        self.compare_gui = CompareGui(self)
        self._build_export_notes()
        if not focus:
            self._build_lessons()
        self._wire_common()
        self.sync_from_scenario()

    # ------------------------------------------------------------------ building
    def _build_header(self) -> None:
        gui, sc = self.gui, self.session.scenario
        names = self.menu.options()
        self.preset = gui.add_dropdown(
            "preset", names, initial_value=self.menu.label_for(sc) or names[0],
            hint="shipped scenes and the presets uploaded in this tab; switching replaces the whole scene")
        self.status = gui.add_markdown("")
        self.playback = gui.add_button_group("playback", PLAYBACK)
        self.top += [self.preset, self.status, self.playback]
        self.top.append(self._slider(SPEED))
        self.seed = gui.add_number("seed", initial_value=int(sc.sim.seed), min=0, step=1,
                                   hint="random seed; changing it restarts the run")
        self.top.append(self.seed)

    def _build_above_tabs(self) -> None:
        """Handles between the header and the tabs (none by default)."""

    def _build_tabs(self) -> None:
        raise NotImplementedError

    def _build_export_notes(self) -> None:
        gui = self.gui
        with self.tabs.add_tab("Export"):
            gui.add_markdown("Trajectories of the current run (the last steps kept in memory), "
                             "the scenario as a preset file, or load your own preset." + self.EXPORT_NOTE)
            self.export_csv = gui.add_button("Export CSV", hint="run,step,t,robot,x,y,heading,vx,vy,status")
            self.export_json = gui.add_button("Export JSON", hint="resolved preset, seed, version, trajectories")
            self.download = gui.add_button("Download preset", hint="the current scenario as TOML")
            self.upload = gui.add_upload_button("Upload preset", hint=".toml or .json, at most 256 KiB")
        with self.tabs.add_tab("Notes"):
            self.notes = gui.add_markdown(notes_text(self.session.NOTES))

    def _build_lessons(self) -> None:
        with self.tabs.add_tab("Lessons"):
            self.lessons = LessonsPanel(self.gui, self.set_up_lesson, self.notify, self.lesson_progress)

    def _slider(self, spec: SliderSpec) -> Any:
        value = get_path(self.session.scenario, spec.path)
        lo, hi = slider_range(spec, value)
        h = self.gui.add_slider(spec.label, min=lo, max=hi, step=spec.step, marks=spec.marks,
                                initial_value=int(value) if spec.integer else float(value), hint=spec.hint)
        self.sliders[spec.path] = h

        @h.on_update
        def _(event: Any) -> None:
            self._field_changed(spec, h)

        return h

    def _wire_common(self) -> None:
        @self.preset.on_update
        def _(event: Any) -> None:
            if not self._syncing:
                self.load_preset(self.preset.value)

        @self.playback.on_click
        def _(event: Any) -> None:
            self.press(event.target.value)

        @self.seed.on_update
        def _(event: Any) -> None:
            if not self._syncing:
                self._seed_changed()

        @self.export_csv.on_click
        def _(event: Any) -> None:
            self.send_file(f"{self._stem()}-trajectories.csv", self.session.export_csv())

        @self.export_json.on_click
        def _(event: Any) -> None:
            self.send_file(f"{self._stem()}-run.json", self.session.export_json())

        @self.download.on_click
        def _(event: Any) -> None:
            self.send_file(f"{self._stem()}.toml", self.session.preset_toml())

        @self.upload.on_upload
        def _(event: Any) -> None:
            f = event.target.value
            self.upload_preset(f.name, f.content)

    def _stem(self) -> str:
        name = self.session.scenario.name
        return "".join(c if c.isalnum() or c in "-_" else "_" for c in name) or "shoal"

    def remove(self) -> None:
        """Take every handle of this panel off the page (the tab swaps in another kind)."""
        self.removed = True
        self.lessons.close()
        for h in reversed(self.top):
            h.remove()
        self.top.clear()

    # ------------------------------------------------------------------ sync guard
    @property
    def _syncing(self) -> bool:
        return getattr(self._local, "depth", 0) > 0

    @contextlib.contextmanager
    def _sync(self) -> Iterator[None]:
        """Set handle values from Python without treating them as user changes. Viser runs the
        callbacks of a Python-side assignment in the assigning thread, so a thread-local flag
        tells them apart from a user's change arriving at the same time on another thread."""
        self._local.depth = getattr(self._local, "depth", 0) + 1
        try:
            yield
        finally:
            self._local.depth -= 1

    @staticmethod
    def _set(handle: Any, value: Any) -> None:
        if handle.value != value:
            handle.value = value

    def sync_from_scenario(self) -> None:
        """Push the session's scenario into every handle (after a load, a refusal or a change)."""
        if self.removed:
            return
        sc = self.session.scenario
        with self._sync():
            for spec in self.SLIDERS + (SPEED,):
                h, value = self.sliders[spec.path], get_path(sc, spec.path)
                lo, hi = slider_range(spec, value)
                if (h.min, h.max) != (lo, hi):
                    h.min, h.max = lo, hi
                self._set(h, int(value) if spec.integer else float(value))
            self._set(self.seed, int(sc.sim.seed))
            if self.preset.options != self.menu.options():
                self.preset.options = self.menu.options()
            if (choice := self.menu.label_for(sc)) is not None:
                self._set(self.preset, choice)
            self._sync_body(sc)
        self.compare_gui.sync()
        self._visibility()
        self.refresh_readout()

    def _sync_body(self, sc: Scenario) -> None:
        """Push the scenario into the subclass's own handles (inside the sync guard)."""

    def _visibility(self) -> None:
        """Show the handles that matter for the current scenario."""

    # ------------------------------------------------------------------ changes
    def _refuse(self, err: PresetError, what: str) -> None:
        self.notify(f"Refused: {what}", "\n".join(err.messages[:6]), "red")

    def apply(self, changes: dict[str, Any], what: str) -> bool:
        """Validate and apply; on refusal notify and put every handle back. Returns True if applied."""
        try:
            self.session.apply(changes)
        except PresetError as err:
            self._refuse(err, what)
            self.sync_from_scenario()  # restores the refused handle to the previous value
            return False
        self.sync_from_scenario()
        return True

    def _field_changed(self, spec: SliderSpec, handle: Any) -> None:
        if self._syncing:
            return
        value = int(round(handle.value)) if spec.integer else float(handle.value)
        if value == get_path(self.session.scenario, spec.path):
            return
        self.apply({spec.path: value}, f"{spec.label} = {value:g}")

    def _choice_changed(self, path: str, handle: Any) -> None:
        if self._syncing:
            return
        value = handle.value
        if value == get_path(self.session.scenario, path):
            return
        self.apply({path: value}, f"{path.split('.')[-1]} = {value}")

    def _seed_changed(self) -> None:
        try:
            seed = int(self.seed.value)
        except (TypeError, ValueError):
            seed = -1
        try:
            self.session.reset(seed)
        except PresetError as err:
            self._refuse(err, f"seed = {self.seed.value}")
        self.sync_from_scenario()

    def press(self, what: str) -> None:
        """A playback button: Play, Pause, Step or Reset."""
        s = self.session
        if what == "Play":
            s.play()
        elif what == "Pause":
            s.pause()
        elif what == "Step":
            s.pause()
            s.step(1)
        elif what == "Reset":
            s.reset()
        self.refresh_status()

    def _load(self, scenario: Scenario) -> None:
        if self.replace is not None:
            self.replace(scenario)  # the tab syncs whichever panels are current afterwards
        else:
            self.session.load_scenario(scenario)
            self.sync_from_scenario()

    def load_preset(self, choice: str) -> bool:
        """Load a choice of the preset dropdown: a shipped preset or one uploaded in this tab
        (never a file: anything else is refused)."""
        menu, previous = self.menu, self.menu.current
        try:
            scenario = menu.scenario(choice)
            menu.current = choice
            self._load(scenario)
        except PresetError as err:
            menu.current = previous
            self._refuse(err, "preset")
            self.sync_from_scenario()
            return False
        self.notify("Preset loaded", scenario.description or choice, "green")
        return True

    def set_up_lesson(self, preset: str, values: dict[str, Any]) -> list[str]:
        """A lesson step's scene: the preset with the step's field values, validated as an upload
        would be, loaded paused at step 0. Returns the refusal's messages (empty: loaded)."""
        try:
            scenario = load_scene(preset, values)
            if self.replace is not None:
                session = self.replace(scenario)  # may rebuild the panels (another kind of scene)
            else:
                self.session.load_scenario(scenario)
                self.sync_from_scenario()
                session = self.session
        except PresetError as err:
            return list(err.messages)
        session.pause()
        return []

    def upload_preset(self, filename: str, content: bytes) -> bool:
        """Validate an uploaded preset and load it; it stays a choice of the preset dropdown
        (in memory, this tab only). A bad one is listed field by field and changes nothing."""
        menu, previous = self.menu, self.menu.current
        label = None
        try:
            sc = parse_upload(filename, content)
            label = menu.current = menu.add_upload(sc)
            self._load(sc)
        except PresetError as err:
            if label is not None:
                menu.forget(label)
            menu.current = previous
            self._refuse(err, f"uploaded {filename}")
            return False
        self.notify("Preset uploaded", f"{filename}: scene '{sc.name}' loaded (also in the preset list)", "green")
        return True

    # ------------------------------------------------------------------ readouts
    def refresh_readout(self) -> None:
        """Derived numbers beside the controls (none by default)."""

    def refresh_status(self) -> None:
        raise NotImplementedError

    def refresh_plots(self) -> None:
        """Redraw the live plots (the caller throttles this)."""

    def refresh_timeline(self) -> None:
        """The Replay folder: timeline and badge (the caller throttles this)."""
        self.replay_gui.refresh()

    # ------------------------------------------------------------------ compare and timeline in plots
    def compare_choices(self) -> dict[str, dict[str, Any]]:
        """Quick choices of how swarm B differs from A: label → overrides (a kind adds its own)."""
        return {}

    def shown_metrics(self, n: int) -> tuple[dict[str, Any], Any]:
        """The last ``n`` metric rows up to the step shown (live or scrubbed), and the (t0, t1)
        span of all of them: plots keep that x range, so a scrubbed curve ends at the cursor."""
        m, span = self.session.shown_metrics(n)
        return m, np.array(span)

    def push_uplot(self, handle: Any, data: tuple, series: tuple, scales: dict[str, Any],
                   twin: tuple[str, str] | None = None) -> None:
        """Set a uPlot's data and scales (its series only when they change). ``twin = (metric,
        label)``: with swarm B on, B's metric at the same times is one more (dashed teal) series."""
        if twin is not None:
            b = self.session.twin_metric(twin[0], data[0])
            if b is not None:
                data = tuple(data) + (np.nan_to_num(b, nan=0.0),)
                series = tuple(series) + (twin_series(twin[1]),)
        if self._series.get(id(handle)) != series:
            handle.series = series
            self._series[id(handle)] = series
        handle.data = data
        handle.scales = scales

    def on_snapshot(self, snap: Any) -> None:
        """Called after each scene redraw with the snapshot drawn (per-step readouts)."""
