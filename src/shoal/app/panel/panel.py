"""The control panel of one tab, the same for every scene kind: the header (preset, status,
playback, speed, what happens at the last step, seed), the *Replay and files* and *Compare*
folders (closed at first), the kind's folders and tabs (built from their :mod:`.spec`), the
Lessons tab (with the chapter's notes) and the Sweep tab, and the rule that every change goes
through the scenario model. The tab row holds one line at 1280 px.

A change is validated by ``session.apply``; a refused value shows a red notification and
every handle goes back to the scenario, the running scene untouched. ``sync`` pushes the
scenario into the handles (values, slider ranges, options, visibility, readouts) after a
load, a change or a refusal; a guard tells those Python-side assignments from a user's.
"""

from __future__ import annotations

import contextlib
import math
import threading
from dataclasses import dataclass, field
from importlib import resources
from typing import Any, Callable, Hashable, Iterator, Protocol

import numpy as np

from shoal.presets.io import PresetError
from shoal.presets.models import Scenario

from ..experiment.panel import ExperimentPanel
from ..experiment.service import ExperimentService
from ..lessons.panel import LessonProgress, LessonsPanel
from ..lessons.scenes import load_scene
from ..markdown import escape
from ..preset_menu import PresetMenu
from ..session.lifecycle import AT_END, at_end_choice, at_end_label
from ..session.session import Session
from ..session.snapshot import Snapshot
from ..session.upload import parse_upload
from ..warmup import WARMUP
from .board import WIDTH, Board, plot_height
from .compare import CompareFolder
from .figures import text_scaled
from .keys import PLAYING
from .lesson_run import LessonRun
from .plot_stream import Backlog, PlotStream, Script
from .plots import Chart, Frame, PlotSpec, scale_text
from .replay import ReplayFolder
from .spec import (
    Button,
    Checkbox,
    Control,
    Dropdown,
    Figure,
    Folder,
    KindPanel,
    Number,
    PanelAPI,
    Slider,
    Tab,
    Text,
    get_path,
)
from .view_row import LIGHT_NOTE, Display, ViewRow

PLAYBACK = ("Play", "Pause", "Step", "Reset")
SPEED_SLIDER = Slider("view.steps_per_second", "speed [steps/s]", 1.0, 240.0, 1.0, "playback rate")
TRAIL_SLIDER = Slider("view.trail_seconds", "trail [s]", 0.0, 60.0, 1.0, "length of the drawn trails")

SHOWN_WHEN = (Slider, Dropdown, Checkbox, Number, Text, Folder, PlotSpec, Chart)  # may be hidden (``visible``)
Notify = Callable[[str, str, str], None]
SendFile = Callable[[str, bytes], None]


class PanelKind(Protocol):
    """A scene kind as a panel sees it (the whole plug-in is :class:`shoal.app.kinds.base.AppKind`)."""

    @property
    def name(self) -> str: ...

    @property
    def notes(self) -> str:
        """Teaching notes ``static/notes/<notes>.md``."""
        ...

    def panel(self, api: PanelAPI) -> KindPanel: ...


@dataclass(frozen=True)
class Services:
    """What a panel asks of the tab and the app around it."""

    notify: Notify
    send_file: SendFile
    menu: PresetMenu  # the preset dropdown's choices (the tab keeps it: uploads outlive a swap of panels)
    make_session: Callable[[Scenario], Session]  # a fresh session of any kind (to check a replay)
    replace: Callable[..., Session] | None = None  # load a scene, maybe of another kind (play=False: paused)
    share: Callable[[Session], bytes] | None = None  # the recorded run as one web page
    lessons: LessonProgress = field(default_factory=LessonProgress)  # where the Lessons tab is (the tab keeps it)
    experiments: ExperimentService | None = None  # the server's experiments (None: no Experiment tab)
    owner: Hashable = None  # this browser tab's key among the experiments
    view: Callable[[str], None] | None = None  # the arena's view buttons: "fit", "follow" or "display"
    veil: Callable[[str | None], None] | None = None  # marks the arena as the old scene's while another is built
    display: Display | None = None  # how the tab's arena is drawn (the tab keeps it: it outlives a swap of panels)
    script: Script | None = None  # runs JavaScript in the tab's page (None: no page; plots always sent whole)
    backlog: Backlog | None = None  # messages still on their way to the page
    board: Board | None = None  # the panel beside the arena (the tab keeps it; None: the panel makes its own)
    ask: Callable[..., None] | None = None  # a lesson step's question as a class's round (a lecturer's tab only)


def notes_text(name: str = "ch3") -> str:
    """Teaching notes ``notes/<name>.md`` shipped in ``shoal.static``, or a short fallback."""
    try:
        return resources.files("shoal.static").joinpath(f"notes/{name}.md").read_text(encoding="utf-8")
    except (FileNotFoundError, ModuleNotFoundError, OSError):
        return (f"# Teaching notes\n\nThe notes `notes/{name}.md` are not installed. "
                "Move the sliders and watch the arena and the *Plots* tab.")


def marks_text(scenario: Scenario) -> str:
    """The scene's values that shape a run, one line each (a table would not fit the narrow
    panel), each marked stated, read (our reading of stated text), fitted (chosen to match
    the thesis' outcomes) or ours, with its source."""
    from shoal.presets.marks import provenance, shown_value, values

    vals, rows = values(scenario), []
    for path, m in provenance(scenario).items():
        source = (f", {escape(m.source)}" + (f"; evidence: {escape(m.evidence)}" if m.evidence else "")) if m else ""
        rows.append(f"- {escape(path)} = {escape(shown_value(vals[path]))}: "
                    f"**{escape(m.kind) if m else 'unmarked'}**{source}")
    return ("Each value is **stated** by the thesis, **read** from its text, **fitted** to its outcomes, or **ours**; "
            "the sources name the thesis' tables and the sections of docs/readings.md.\n\n" + "\n".join(rows))


SEED_MAX = 2**63 - 1  # sim.seed's largest value (the seed box's own range)


def _coerce(control: Any, value: Any) -> Any:
    """A control's value as its item reads it; never an integer no message can carry (a
    number box holding 1e308 stays a float: ``int(1e308)`` has 309 digits)."""
    if isinstance(control, Slider):
        return int(round(value)) if control.integer else float(value)
    if isinstance(control, Number):
        try:
            v = float(value)
        except (TypeError, ValueError):
            return -1
        whole = control.step == 1 and math.isfinite(v) and v.is_integer() and abs(v) <= SEED_MAX
        return int(v) if whole else v
    if isinstance(control, Checkbox):
        return bool(value)
    return value


class Panel:
    """The GUI handles of one tab (``handles``: key → viser handle), wired to its session.
    ``gui`` is a viser ``GuiApi`` (``client.gui`` for a browser tab, ``server.gui`` in tests)."""

    def __init__(self, gui: Any, session: Session, kind: PanelKind, services: Services) -> None:
        self.gui, self.session, self.services = gui, session, services
        self.name = kind.name  # the scene kind it shows
        self.handles: dict[str, Any] = {}
        self.top: list[Any] = []  # top-level handles: removing them removes the whole panel
        self.removed = False
        self._local = threading.local()  # per thread: programmatic .value fires callbacks inline
        self._taken: dict[int, float] = {}  # id(watched handle) → update time of the value last taken or set
        self._controls: list[tuple[Any, Any]] = []  # (spec, handle) in build order
        # the controls each per-draw refresh visits, sorted out once as they are built (not every draw)
        self._followers: list[tuple[Number, Any]] = []  # numbers that follow the selected robot
        self._drawn_texts: list[tuple[Text, Any]] = []  # readouts of what was drawn (Text.on_snapshot)
        self._computed_texts: list[tuple[Text, Any]] = []  # readouts of the scenario (Text.compute)
        self._plots: list[tuple[Any, Any]] = []  # PlotSpec, Chart and Figure
        self._scaled: dict[int, tuple[Any, float]] = {}  # id(figure handle) → (its figure, text scale) checked
        self._sent: dict[int, tuple] = {}  # uPlot (series, axes) last sent, by handle (see push_uplot)
        self.controls = 0  # a count of the user's control events (the tab holds the scene a moment after one)
        self.text_scale = services.display.text_scale if services.display is not None else 1.0  # plots' text
        self.plot_stream = PlotStream(gui, services.script, services.backlog)  # the new rows, where the page takes them
        if self.plot_stream.sync is not None:
            self.top.append(self.plot_stream.sync)
        self.part = kind.panel(self)
        self._skip: Any = None  # the main plot: built on the board, not in its tab
        self.main_key = self.wanted_main()
        self.board, self.board_plot = self._build_board()
        self._build_header()  # (with the view row: the projector switch on the first screen in both modes)
        badge = gui.add_markdown("", visible=False)  # names a loaded replay
        live = gui.add_button("Run live (leave the replay)", visible=False,
                              hint="a live run of the replay's preset and seed, from step 0")
        with gui.add_folder("Replay and files", expand_by_default=False) as files:  # closed: the controls fit
            self.replay_gui = ReplayFolder(self, badge, live)
            self._build_files()
        self.compare_gui = CompareFolder(self)
        self.top += [badge, live, files, self.compare_gui.folder]
        for folder in self.part.folders:
            self.top.append(self._build(folder))
        self.tabs = gui.add_tab_group()  # one row at 1280 px: the kind's tabs, Lessons and Sweep
        self.top.append(self.tabs)
        focus = services.lessons.focus  # a lesson's Set up rebuilt this panel: keep its tab in view
        if focus:
            self._build_lessons(kind.notes)
        for tab in self.part.tabs:
            self._build_tab(tab)
        if not focus:
            self._build_lessons(kind.notes)
        self.experiment = self._build_experiment()
        self.sync()

    def notify(self, title: str, body: str, color: str = "blue") -> None:
        """A message for the tab's user (the tab shows it)."""
        self.services.notify(title, body, color)

    # ------------------------------------------------------------------ building
    def _build_header(self) -> None:
        gui, sc, menu = self.gui, self.session.scenario, self.services.menu
        names = menu.options()
        self.preset = gui.add_dropdown(
            "preset", names, initial_value=menu.label_for(sc) or names[0],
            hint="shipped scenes and the presets uploaded in this tab; switching replaces the whole scene")
        self.status = gui.add_markdown("")
        self.light = False  # the light drawing: said on a line under the status line
        self.playback = gui.add_button_group("playback", PLAYBACK)
        self.top += [self.preset, self.status, self.playback, self._build(SPEED_SLIDER)]
        self.view_gui = ViewRow(self, legend=self.board_legend)
        self.at_end = gui.add_dropdown(
            "at the end", self._at_end_options(), initial_value=at_end_label(self.session.at_end, sc.sim.steps),
            hint="at the preset's last step the run stops (Play, Step or a changed control start it again), "
                 "starts again from step 0, or runs on")
        self.seed = gui.add_number("seed", initial_value=int(sc.sim.seed), min=0, max=SEED_MAX, step=1,
                                   hint="random seed; changing it restarts the run")
        self.top += [self.at_end, self.seed]

        self.on_user_change(self.preset, lambda: self.load_preset(self.preset.value))
        self.on_user_change(self.seed, self._seed_changed)
        self.on_user_change(self.at_end, lambda: self.choose_at_end(self.at_end.value))

        @self.playback.on_click
        def _(event: Any) -> None:
            self.press(event.target.value)

    # ------------------------------------------------------------------ the board
    def wanted_main(self) -> str | None:
        """The key of the plot the scene is about now (None: the kind names none)."""
        main = self.part.main
        return main(self.session) if main is not None else None

    def _find(self, key: str | None) -> Any:
        """The plot spec of the kind's tabs and folders with ``key`` (None if there is none)."""
        def walk(items: Any) -> Any:
            for item in items:
                if isinstance(item, Folder):
                    found = walk(item.items)
                    if found is not None:
                        return found
                elif isinstance(item, (PlotSpec, Chart, Figure)) and item.key == key:
                    return item
            return None
        return walk([*self.part.folders, *(i for tab in self.part.tabs for i in tab.items)]) if key else None

    def _build_board(self) -> tuple[Board | None, Any]:
        """The main plot and the legend on the board beside the arena (the tab's, else one of
        this panel's own); None where the GUI has no panels."""
        self.board_legend: Any = None
        item = self._find(self.main_key)
        board = self.services.board
        if board is None:
            try:
                board = Board(self.gui)
            except AttributeError:  # a GUI without panels: the legend stays under the view row
                return None, None
            self.top.append(board)
        with board:
            plot = self._build(item) if item is not None else None
            self.board_legend = self.gui.add_markdown("")
        self.top += [h for h in (plot, self.board_legend) if h is not None]
        self._skip = item
        return board, plot

    def place(self, projector: bool, window_height: float | None = None, panel_width: float | None = None) -> None:
        """Dock the board for the mode and shape its plot for the room it has there (the window's
        height and the control panel's width, px, where known)."""
        if self.board is None:
            return
        self.board.place(projector)
        h = self.board_plot
        if h is not None:
            width = (panel_width or 768.0) - 40 if projector else WIDTH - 24
            time_plot = isinstance(self.control_of(h), (PlotSpec, Chart))
            tall = plot_height(projector, window_height, width, "time" if time_plot else "figure")
            aspect = 1.0 / tall if time_plot else tall  # (uPlot's aspect is width / height, plotly's the inverse)
            if abs(float(h.aspect) - aspect) > 1e-3:
                h.aspect = aspect

    def control_of(self, handle: Any) -> Any:
        return next(item for item, h in self._controls if h is handle)

    def _at_end_options(self) -> tuple[str, ...]:
        steps = self.session.scenario.sim.steps
        return tuple(at_end_label(c, steps) for c in AT_END)

    def choose_at_end(self, label: str) -> bool:
        """The header's *at the end* choice (a label of the dropdown); anything else is refused."""
        choice = at_end_choice(str(label), self.session.scenario.sim.steps)
        if choice is None:
            self.notify("Refused: at the end", f"{label!r} is not one of: {', '.join(self._at_end_options())}",
                        "red")
            self.sync()
            return False
        self.session.choose_at_end(choice)
        self.refresh_status()
        return True

    def _build_tab(self, tab: Tab) -> None:
        with self.tabs.add_tab(tab.label):
            for item in tab.items:
                self._build(item)

    def _build_files(self) -> None:
        """Trajectories and the scenario as files, and a preset of one's own (in the current folder)."""
        gui = self.gui
        gui.add_markdown("Trajectories of the current run (the last steps kept in memory), the scenario "
                         "as a preset file, or load your own preset." + self.part.export_note)
        self.export_csv = gui.add_button("Export CSV", hint="run,step,t,robot,x,y,heading,vx,vy,status")
        self.export_json = gui.add_button("Export JSON",
                                          hint="the preset as edited (as Download preset), seed, version, trajectories")
        self.download = gui.add_button("Download preset", hint="the current scenario as TOML")
        self.upload = gui.add_upload_button("Upload preset", hint=".toml or .json, at most 256 KiB")

        @self.export_csv.on_click
        def _(event: Any) -> None:
            self.send_file(f"{self.stem()}-trajectories.csv", self.session.export_csv())

        @self.export_json.on_click
        def _(event: Any) -> None:
            try:
                content = self.session.export_json()
            except PresetError as err:  # hand edits the preset cannot hold (as Download preset says)
                self.refuse(err, "export JSON")
                return
            self.send_file(f"{self.stem()}-run.json", content)

        @self.download.on_click
        def _(event: Any) -> None:
            try:
                content = self.session.preset_toml()
            except PresetError as err:
                self.refuse(err, "download preset")
                return
            self.send_file(f"{self.stem()}.toml", content)

        @self.upload.on_upload
        def _(event: Any) -> None:
            f = event.target.value
            self.upload_preset(f.name, f.content)

    def _build_experiment(self) -> ExperimentPanel | None:
        sv = self.services
        if sv.experiments is None:
            return None
        replace = sv.replace

        def open_cell(scenario: Scenario) -> Session:
            if replace is None:
                raise PresetError(["this app cannot open a cell in the arena"])
            return replace(scenario)

        with self.tabs.add_tab("Sweep"):
            return ExperimentPanel(self.gui, sv.experiments, sv.owner, scenario=lambda: self.session.scenario,
                                   open_cell=open_cell, notify=self.notify, send_file=self.send_file)

    def _build_lessons(self, notes: str) -> None:
        """The Lessons tab, the chapter's teaching notes below the lessons."""
        with self.tabs.add_tab("Lessons"):
            self.lessons = LessonsPanel(self.gui, self.set_up_lesson, self.notify, self.services.lessons,
                                        measure=LessonRun(self.session), ask=self.services.ask)
            with self.gui.add_folder("Notes on this chapter", expand_by_default=False):
                self.notes = self.gui.add_markdown(notes_text(notes))
            with self.gui.add_folder("Where this scene's values come from", expand_by_default=False):
                self.marks = self.gui.add_markdown(marks_text(self.session.scenario))

    def _build(self, item: Control) -> Any:
        """A handle for ``item`` (a folder with its items), kept as ``handles[key]`` and wired."""
        gui, s = self.gui, self.session
        if item is self._skip:  # (on the board)
            return None
        if isinstance(item, Folder):
            expand = item.expand(s) if callable(item.expand) else item.expand
            with gui.add_folder(item.label, expand_by_default=expand) as h:
                for child in item.items:
                    self._build(child)
        elif isinstance(item, Slider):
            value = self._read(item)
            value = item.initial if value is None else value
            lo, hi = item.range(value)
            h = gui.add_slider(item.label, min=lo, max=hi, step=item.step, marks=item.marks, hint=item.hint,
                               initial_value=int(value) if item.integer else float(value))
        elif isinstance(item, Dropdown):
            options = self._options(item)
            value = self._read(item)
            h = gui.add_dropdown(item.label, options, initial_value=value if value in options else options[0],
                                 hint=item.hint)
        elif isinstance(item, Checkbox):
            h = gui.add_checkbox(item.label, bool(self._read(item)), hint=item.hint)
        elif isinstance(item, Number):
            value = item.read(s) if item.read is not None else None
            value = item.low if value is None else value
            h = gui.add_number(item.label, initial_value=value, min=item.low, step=item.step, hint=item.hint,
                               max=item.high(s) if item.high is not None else None)
        elif isinstance(item, Button):
            h = gui.add_button(item.label, hint=item.hint)
        elif isinstance(item, Text):
            h = gui.add_markdown(item.text)
        elif isinstance(item, Figure):
            h = gui.add_plotly(text_scaled(item.make(s), self.text_scale), aspect=item.aspect)  # (height/width)
        elif isinstance(item, (PlotSpec, Chart)):
            f = self._frame(item)
            h = gui.add_uplot(data=f.data, series=f.series, scales=f.scales, axes=f.axes, title=item.title,
                              aspect=item.aspect, legend=item.legend, padding=f.padding,
                              visible=item.visible is None or bool(item.visible(s)))
            self._sent[id(h)] = (f.series, f.axes)
        else:
            raise TypeError(f"not a control: {item!r}")
        if item.key:
            self.handles[item.key] = h
        self._controls.append((item, h))
        if isinstance(item, Number) and item.follow and item.read is not None:
            self._followers.append((item, h))
        if isinstance(item, Text) and item.on_snapshot is not None:
            self._drawn_texts.append((item, h))
        if isinstance(item, Text) and item.compute is not None:
            self._computed_texts.append((item, h))
        if isinstance(item, (PlotSpec, Chart, Figure)):
            self._plots.append((item, h))
        self._wire(item, h)
        return h

    def control(self, key: str) -> Any:
        """The spec of the control ``handles[key]`` shows."""
        h = self.handles[key]
        return next(item for item, handle in self._controls if handle is h)

    def _wire(self, item: Any, h: Any) -> None:
        if isinstance(item, Button):
            @h.on_click
            def _(event: Any) -> None:
                item.act(self)
        elif isinstance(item, (Slider, Dropdown, Checkbox, Number)):
            self.on_user_change(h, lambda: self._changed(item, _coerce(item, h.value)))

    # ------------------------------------------------------------------ values
    def _read(self, item: Any) -> Any:
        """What ``item`` shows now (None: a local control that keeps its own value)."""
        if item.read is not None:
            return item.read(self.session)
        if item.act is not None:
            return None
        return get_path(self.session.scenario, item.key)

    def _options(self, item: Dropdown) -> tuple[str, ...]:
        return tuple(item.options(self.session) if callable(item.options) else item.options)

    def _changed(self, item: Any, value: Any) -> None:
        """A user's change of a control's value."""
        self.controls += 1
        if item.act is not None:
            item.act(self, value)
            return
        if item.write is not None:
            changes = item.write(self.session, value)
        else:
            changes = None if value == get_path(self.session.scenario, item.key) else {item.key: value}
        if changes is not None:
            shown = f"{value:g}" if isinstance(item, Slider) else f"{value}"
            self.apply(changes, f"{item.label} = {shown}")

    # ------------------------------------------------------------------ sync guard
    @property
    def syncing(self) -> bool:
        return getattr(self._local, "depth", 0) > 0

    @contextlib.contextmanager
    def quietly(self) -> Iterator[None]:
        """Set handle values from Python without treating them as user changes. Viser runs the
        callbacks of a Python-side assignment in the assigning thread, so a thread-local flag
        tells them apart from a user's change arriving at the same time on another thread."""
        self._local.depth = getattr(self._local, "depth", 0) + 1
        try:
            yield
        finally:
            self._local.depth -= 1

    def set_quietly(self, handle: Any, value: Any) -> None:
        """Show ``value`` on ``handle``, unless a user's newer value waits there for its callback."""
        if self.pending(handle):
            return
        with self.quietly():
            if handle.value != value:
                handle.value = value
        self.taken(handle)

    def on_user_change(self, handle: Any, act: Callable[[], object]) -> None:
        """Call ``act`` when a user changes ``handle`` (not when the app sets it, :meth:`quietly`).
        Until then a sync leaves the user's value on it (:meth:`pending`)."""
        self._taken[id(handle)] = handle.update_timestamp

        @handle.on_update
        def _(event: Any) -> None:
            if not self.syncing:
                self.taken(handle)
                act()

    def taken(self, handle: Any) -> None:
        """Note that the value of an :meth:`on_user_change` ``handle`` as it stands now is handled
        (a user's change taken, or the app's own)."""
        if id(handle) in self._taken:
            self._taken[id(handle)] = handle.update_timestamp

    def pending(self, handle: Any) -> bool:
        """A user's value arrived on ``handle`` after the last one taken: viser has stored it and queued
        its callback on another thread, which will take it. A sync meanwhile (after a change of
        another control) must not put the scenario's older value over it, or the change is lost."""
        last = self._taken.get(id(handle))
        return last is not None and handle.update_timestamp > last

    def sync(self) -> None:
        """Push the session's scenario into every handle (after a load, a refusal or a change)."""
        if self.removed:
            return
        s = self.session
        sc = s.scenario
        with self.quietly():
            for item, h in self._controls:
                self._sync_one(item, h, s, sc)
            self.set_quietly(self.seed, int(sc.sim.seed))
            if tuple(self.at_end.options) != self._at_end_options():
                self.at_end.options = self._at_end_options()
            self.set_quietly(self.at_end, at_end_label(s.at_end, sc.sim.steps))
            menu = self.services.menu
            if tuple(self.preset.options) != menu.options():
                self.preset.options = menu.options()
            if (choice := menu.label_for(sc)) is not None:
                self.set_quietly(self.preset, choice)
        self.compare_gui.sync()
        if (marks := getattr(self, "marks", None)) is not None and marks.content != (
                text := marks_text(sc)):
            marks.content = text
        self.refresh_readout()

    def _sync_one(self, item: Any, h: Any, s: Session, sc: Scenario) -> None:
        if isinstance(item, SHOWN_WHEN) and item.visible is not None:
            h.visible = bool(item.visible(s))
        if isinstance(item, Slider):
            if item.label_of is not None:
                h.label = item.label_of(sc)
            value = self._read(item)
            if value is None:
                return
            lo, hi = item.range(value)
            if (h.min, h.max) != (lo, hi):
                h.min, h.max = lo, hi
            self.set_quietly(h, int(value) if item.integer else float(value))
        elif isinstance(item, Dropdown):
            options = self._options(item)
            if tuple(h.options) != options:
                h.options = options
            value = self._read(item)
            if value in options:
                self.set_quietly(h, value)
        elif isinstance(item, Checkbox):
            value = self._read(item)
            if value is not None:
                self.set_quietly(h, bool(value))
        elif isinstance(item, Number):
            if item.high is not None and h.max != item.high(s):
                h.max = item.high(s)
            value = item.read(s) if item.read is not None else None
            if value is not None:
                self.set_quietly(h, value)

    # ------------------------------------------------------------------ changes
    def refuse(self, err: Any, what: str) -> None:
        """A red notification listing why ``what`` was refused (``err.messages``)."""
        self.notify(f"Refused: {what}", "\n".join(err.messages[:6]), "red")

    def apply(self, changes: dict[str, Any], what: str) -> bool:
        """Validate and apply; on refusal notify and put every handle back. Returns True if applied."""
        s = self.session
        before = s.scene_revision
        try:
            s.apply(changes)
        except PresetError as err:
            self.refuse(err, what)
            self.sync()  # restores the refused handle to the previous value
            return False
        self.sync()
        if s.scene_revision != before:
            note = self.part.rebuilt(s, what, changes)
            if note is not None:
                self.notify(*note, "blue")
        return True

    def select_robot(self, robot: int) -> None:
        """Single out ``robot`` and show it in the handles that follow it."""
        self.session.select(robot)
        self._follow()

    def _follow(self) -> None:
        with self.quietly():
            for item, h in self._followers:
                self.set_quietly(h, item.read(self.session))  # type: ignore[misc]

    def _seed_changed(self) -> None:
        try:
            seed = int(self.seed.value)
        except (TypeError, ValueError):
            seed = -1
        try:
            self.session.reset(seed)
        except PresetError as err:
            self.refuse(err, f"seed = {self.seed.value}")
        self.sync()

    def press(self, what: str) -> None:
        """A playback button: Play, Pause, Step or Reset."""
        s = self.session
        self.controls += 1
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

    # ------------------------------------------------------------------ loading
    def _load(self, scenario: Scenario) -> None:
        """Load ``scenario``; until it is built the arena is veiled, the legend and the kind's tabs
        cleared: nothing of the old scene passes for the new one."""
        self.status.content = f"**{escape(scenario.name)}** · building the scene …"
        self._building(f"Building {scenario.name} …")
        try:
            if self.services.replace is not None:
                self.services.replace(scenario)  # the tab syncs whichever panel is current afterwards
            else:
                self.session.load_scenario(scenario)
                self.sync()
        finally:
            self._building(None)

    def _building(self, text: str | None) -> None:
        """Say that another scene is being built (``text``), or that this one is shown again (None).
        The board's plot goes at once too: taken off the page in the same batch as the new one
        arrives, plotly re-laid it out as it went (an error in the page)."""
        if self.services.veil is not None:
            self.services.veil(text)
        if self.removed:
            return
        self.tabs.visible = text is None
        for h in (self.board_plot, self.board_legend):
            if h is not None:
                h.visible = text is None
        if text is not None:
            self.view_gui.show_legend(())

    def load_preset(self, choice: str) -> bool:
        """Load a choice of the preset dropdown: a shipped preset or one uploaded in this tab
        (never a file: anything else is refused)."""
        menu, previous = self.services.menu, self.services.menu.current
        try:
            scenario = menu.scenario(choice)
            menu.current = choice
            self._load(scenario)
        except PresetError as err:
            menu.current = previous
            self.refuse(err, "preset")
            self.sync()
            return False
        self.notify("Preset loaded", scenario.description or choice, "green")
        return True

    def set_up_lesson(self, preset: str, values: dict[str, Any]) -> list[str]:
        """A lesson step's scene: the preset with the step's field values, validated as an upload
        would be, loaded paused at step 0. Returns the refusal's messages (empty: loaded)."""
        try:
            scenario = load_scene(preset, values)
            self._building(f"Setting up {scenario.name} …")
            if self.services.replace is not None:  # (never a step before it is paused)
                self.services.replace(scenario, play=False)  # may rebuild the panel (another kind of scene)
            else:
                self.session.load_scenario(scenario, play=False)
                self.sync()
        except PresetError as err:
            return list(err.messages)
        finally:
            self._building(None)
        return []

    def upload_preset(self, filename: str, content: bytes) -> bool:
        """Validate an uploaded preset and load it; it stays a choice of the preset dropdown
        (in memory, this tab only). A bad one is listed field by field and changes nothing."""
        menu, previous = self.services.menu, self.services.menu.current
        label = None
        try:
            sc = parse_upload(filename, content)
            label = menu.current = menu.add_upload(sc)
            self._load(sc)
        except PresetError as err:
            if label is not None:
                menu.forget(label)
            menu.current = previous
            self.refuse(err, f"uploaded {filename}")
            return False
        self.notify("Preset uploaded", f"{filename}: scene '{sc.name}' loaded (also in the preset list)", "green")
        return True

    def send_file(self, name: str, content: bytes) -> None:
        self.services.send_file(name, content)

    def stem(self) -> str:
        """The scene's name as a file name."""
        name = self.session.scenario.name
        return "".join(c if c.isalnum() or c in "-_" else "_" for c in name) or "shoal"

    def retire(self) -> None:
        """Hide every handle of this panel and stop updating them (the tab swaps in another kind
        and removes them a moment later: see :meth:`shoal.app.tab.TabApp.replace`)."""
        if self.removed:
            return
        self.removed = True
        self.lessons.close()
        if self.experiment is not None:
            self.experiment.detach()
        for h in self.top:
            h.visible = False

    def remove(self) -> None:
        """Take every handle of this panel off the page."""
        self.retire()
        if self.experiment is not None:
            self.experiment.remove()
        for h in reversed(self.top):
            h.remove()
        self.top.clear()

    def detach(self) -> None:
        """The browser tab went away: stop following its experiment (which the server cancels)."""
        if self.experiment is not None:
            self.experiment.detach()

    # ------------------------------------------------------------------ readouts and plots
    def refresh_experiment(self) -> None:
        """The Experiment tab offers the fields of the scene as it is now."""
        if self.experiment is not None:
            self.experiment.sync()

    def compare_choices(self) -> dict[str, dict[str, Any]]:
        """Quick choices of how swarm B differs from A: label → overrides."""
        return self.part.compare(self.session)

    def refresh_status(self) -> None:
        """The status line: the kind's numbers of the live run, or (scrubbing, replaying) the
        recorded step shown, whose numbers are not recorded."""
        s = self.session
        state = PLAYING if s.playing else ("■ finished: Play runs it again" if s.finished else "paused")
        shown = s.shown_step()
        if shown is None:
            compiling = WARMUP.status(s.scenario)  # kernels compiling: what the scene does meanwhile
            short = s.history.shortened  # the tab's memory budget holds fewer steps than usual
            self._status(self.part.status(s, s.readout(), state) + (f" · {compiling}" if compiling else "")
                         + (f" · {escape(short)}" if short else ""))
            return
        k, t, last = shown
        what = "replay" if s.replaying is not None else "recorded history"
        self._status(f"**{escape(s.scenario.name)}** · {state} · {what} · step {k:d} of {last:d} · t = {t:.4g} s"
                     " · the live run's numbers are not recorded")

    def _status(self, text: str) -> None:
        """Show the status line, with the drawing's note (if any) on a line of its own below it."""
        self.status.content = f"{text}<br>{LIGHT_NOTE}" if self.light else text

    def show_light(self, light: bool) -> None:
        """Say (or stop saying) under the status line that the arena is drawn lightly."""
        if light != self.light:
            self.light = light
            self.refresh_status()

    def refresh_readout(self) -> None:
        """Readouts that follow the scenario (derived numbers beside the controls)."""
        for item, h in self._computed_texts:
            h.content = item.compute(self.session)  # type: ignore[misc]

    def on_snapshot(self, snap: Snapshot) -> None:
        """After each scene redraw: the handles that follow the selected robot and the readouts of
        what was drawn."""
        if self.removed:
            return
        self._follow()
        for item, h in self._drawn_texts:
            text = item.on_snapshot(self.session, snap)  # type: ignore[misc]
            if h.content != text:
                h.content = text

    def refresh_plots(self) -> None:
        """Redraw the live plots (the caller throttles this)."""
        if self.removed:
            return
        for item, h in self._plots:
            if isinstance(item, (PlotSpec, Chart)):
                if item.visible is not None and not h.visible:
                    continue
                self.push_uplot(h, self._frame(item))
            elif isinstance(item, Figure):
                item.refresh(self, h)
                checked = self._scaled.get(id(h))  # (plotly's attributes are slow to read: once a figure and scale)
                if checked is None or checked[0] is not h.figure or checked[1] != self.text_scale:
                    if (fig := text_scaled(h.figure, self.text_scale)) is not h.figure:
                        h.figure = fig
                    self._scaled[id(h)] = (h.figure, self.text_scale)

    def _frame(self, item: PlotSpec | Chart) -> Frame:
        """What ``item`` shows now: the metrics up to the step shown (with swarm B's curve) or the chart."""
        s = self.session
        if isinstance(item, Chart):
            return scale_text(item.render(s), self.text_scale)
        m, span = s.shown_metrics(item.history)
        if not len(m.get("t", ())):
            m = {name: np.zeros(0) for name in s.history.names}
        twin = s.twin_metric(item.twin, np.asarray(m["t"], float)) if item.twin is not None else None
        if twin is not None and len(m["t"]) < 2:
            twin = None
        return scale_text(item.render(m, span, s, twin), self.text_scale)

    def refresh_lessons(self) -> None:
        """The numbers of the lesson step shown, as the run on screen reads them (the caller throttles this)."""
        if not self.removed:
            self.lessons.refresh()

    def refresh_timeline(self) -> None:
        """The Replay folder: timeline and badge (the caller throttles this)."""
        self.replay_gui.refresh()

    def push_uplot(self, handle: Any, f: Frame) -> None:
        """Send a chart's frame: data and scales always (as the rows that are new where the page
        takes them, :mod:`.plot_stream`), series and axes only when they change
        (the client rebuilds the chart for those). An explicit x range goes with every update:
        viser's client keeps a *relative* x range across data pushes, which goes wrong for a
        chart first mounted in a hidden tab."""
        series, axes = self._sent.get(id(handle), (None, None))
        if series != f.series:
            handle.series = f.series
        if axes != f.axes:
            handle.axes = f.axes
        self._sent[id(handle)] = (f.series, f.axes)
        if tuple(handle.padding or ()) != f.padding:
            handle.padding = f.padding
        self.plot_stream.push(handle, f.data, f.scales)  # (the rows that are new, where the page takes them)
