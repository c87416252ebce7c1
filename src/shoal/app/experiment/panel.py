"""The Sweep tab: pick one or two fields of the scene, their values, the runs per cell and
the outcome; run the sweep on the server; watch the medians come in; open a cell in the arena;
download the tidy CSV and the figure. A grid some of whose cells the model refuses (two
fields whose values do not go together) is refused with an offer: *Run the other cells*
runs the rest and marks those "invalid".

Self-contained: it takes a viser GUI handle, the server's :class:`ExperimentService`, the tab
(``owner``) and four callbacks (the scene's scenario now, open a scenario in the arena,
notify, send a file). The experiment lives in the service, not here: a panel built again (a
scene of another kind) shows the tab's experiment as it stands.

Viser runs a callback of a value set from Python inline, in the setting thread; a thread-local
flag tells those apart from the user's changes. The service calls :meth:`changed` from its own
thread; the arena is opened, and notifications sent, without holding the panel's lock.
"""

from __future__ import annotations

import contextlib
import threading
import time
from typing import Any, Callable, Hashable, Iterator

import numpy as np

from shoal.presets.io import PresetError, file_stem, to_toml
from shoal.presets.models import Scenario
from shoal.studies.sweep import catalogue
from shoal.studies.sweep.catalogue import Field, Outcome
from shoal.studies.sweep.grid import label

from ..markdown import escape
from . import figure
from .request import AxisRequest, ExperimentRequest, Refused
from .service import RUNNING, Experiment, ExperimentService

NONE = "none"
AS_LIST, AS_RANGE = "list", "range and count"
PLOT_PERIOD = 0.25  # s at least between plot redraws while cells come in
INTRO = ("Vary one or two fields and compare an outcome over seeded runs: every cell runs the same runs "
         "(as `shoal sweep`), so cells differ only by the fields' values.")


def _short(key: str) -> str:
    return key.rsplit(".", 1)[-1]


class _AxisGui:
    """The handles of one axis: the field, and its values as a list or a range and count."""

    def __init__(self, gui: Any, n: int, optional: bool) -> None:
        self.optional = optional
        with gui.add_folder(f"Field {n}" + (" (optional: a heat map)" if optional else "")) as self.folder:
            self.field = gui.add_dropdown(f"field {n}", (NONE,) if optional else ("",),
                                          hint="a field of the current preset (dotted path, as shoal sweep --grid)")
            self.info = gui.add_markdown("")
            self.given = gui.add_dropdown(f"values {n} as", (AS_LIST, AS_RANGE), initial_value=AS_LIST)
            self.values = gui.add_text(f"values {n}", "", hint="comma-separated, e.g. 2, 4, 8 or kinematic, physics")
            self.start = gui.add_number(f"from {n}", 0.0, hint="first value of the range")
            self.stop = gui.add_number(f"to {n}", 1.0, hint="last value of the range")
            self.count = gui.add_number(f"count {n}", 5.0, min=2, step=1, hint="how many evenly spaced values")

    @property
    def chosen(self) -> bool:
        return self.field.value not in (NONE, "")

    def request(self) -> AxisRequest:
        if self.given.value == AS_RANGE:
            return AxisRequest(self.field.value, start=self.start.value, stop=self.stop.value, count=self.count.value)
        if self.given.value == AS_LIST:
            return AxisRequest(self.field.value, values=self.values.value)
        return AxisRequest(self.field.value)  # neither: the service refuses it (no values)

    def show(self, field: Field | None) -> None:
        """Visibility and the field's description, range and value now."""
        chosen = field is not None
        numeric = field is not None and field.numeric
        ranged = numeric and self.given.value == AS_RANGE
        self.given.visible = numeric
        self.values.visible = chosen and not ranged
        for h in (self.start, self.stop, self.count):
            h.visible = ranged
        now = "unset" if field is None or field.value is None else label(field.value)
        self.info.content = (f"{escape(field.description)} · {escape(field.range_text())} · now {escape(now)}"
                             if field is not None else "")

    def suggest(self, field: Field) -> None:
        """Fill the values with a first guess for ``field``."""
        self.values.value = ", ".join(label(v) for v in field.suggest())
        if field.numeric:
            lo, hi = catalogue.span(field)
            self.start.value, self.stop.value, self.count.value = float(lo), float(hi), 5.0
        else:
            self.given.value = AS_LIST


class ExperimentPanel:
    """The handles of the Sweep tab, wired to ``service`` for ``owner``."""

    def __init__(self, gui: Any, service: ExperimentService, owner: Hashable, *, scenario: Callable[[], Scenario],
                 open_cell: Callable[[Scenario], Any], notify: Callable[[str, str, str], None],
                 send_file: Callable[[str, bytes], None]) -> None:
        self.gui, self.service, self.owner = gui, service, owner
        self.scenario, self.open_cell, self.notify, self.send_file = scenario, open_cell, notify, send_file
        self.experiment: Experiment | None = None
        self.removed = False
        self._lock = threading.RLock()
        self._local = threading.local()
        self._shown_scenario: Scenario | None = None
        self._fields: dict[str, Field] = {}
        self._outcomes: dict[str, Outcome] = {}  # offered in the dropdown, by title
        self._scene_outcomes: set[str] = set()  # the names the scene records
        self._cells: dict[str, int] = {}  # cell option → index
        self._drawn, self._drawn_cells = 0.0, 0  # when the plot was drawn, with how many cells
        self._timer: threading.Timer | None = None  # a redraw waiting for PLOT_PERIOD to pass
        self._build()
        self._wire()
        with self._sync():
            self.steps.value = float(min(self.scenario().sim.steps, service.limits.max_steps))
        self.sync()
        exp = service.experiment(owner)
        if exp is not None:
            exp.listen(self.changed)
            self.changed(exp)

    # ------------------------------------------------------------------ building
    def _build(self) -> None:
        gui, limits = self.gui, self.service.limits
        self.handles: list[Any] = [gui.add_markdown(INTRO)]
        self.axes = (_AxisGui(gui, 1, False), _AxisGui(gui, 2, True))
        self.handles += [a.folder for a in self.axes]
        # whole numbers held as floats: viser would truncate 2.5 to 2 for an int handle, unseen
        self.runs = gui.add_number("runs per cell", 10.0, min=1, max=limits.max_runs, step=1,
                                   hint="seeded runs in every cell; 6 or more give a 95 % interval")
        self.steps = gui.add_number("steps per run", 100.0, min=1, max=limits.max_steps, step=1,
                                    hint="control ticks of every run (the preset's sim.steps)")
        self.run = gui.add_button("Run experiment", color="green", hint="queue the sweep on this server")
        self.skip = gui.add_button("Run the other cells", color="yellow", visible=False,
                                   hint="run the cells that can run; those the model refuses are left out")
        self.cancel = gui.add_button("Cancel experiment", color="red", disabled=True,
                                     hint="stop it; the cells already finished are kept")
        self.progress = gui.add_progress_bar(0.0)
        self.status = gui.add_markdown(f"Limits of this server: {escape(limits.describe())}.")
        self.outcome = gui.add_dropdown("outcome", ("",), hint="what the plot compares; can change after the run")
        self.plot = gui.add_plotly(figure.empty_figure("the medians appear here as cells finish"), aspect=0.8)
        with gui.add_folder("Cells") as self.cells_folder:
            self.cell = gui.add_dropdown("cell", ("—",), hint="a finished cell of the grid")
            self.cell_info = gui.add_markdown("")
            self.open = gui.add_button("Open in arena", hint="load this cell's preset and seed: the run behind run 0")
            self.download_csv = gui.add_button("Download CSV", hint="one row per cell × run, as shoal sweep's "
                                                                    "results.csv")
            self.download_png = gui.add_button("Download figure", hint="the plot as a PNG")
            self.download_preset = gui.add_button("Download experiment preset",
                                                  hint="the scene the cells vary, with these runs and steps (TOML)")
            self.command = gui.add_markdown("")
        self.handles += [self.runs, self.steps, self.run, self.skip, self.cancel, self.progress, self.status,
                         self.outcome, self.plot, self.cells_folder]

    def _wire(self) -> None:
        for ax in self.axes:
            ax.field.on_update(lambda _e, ax=ax: self._user(self._field_changed, ax))
            ax.given.on_update(lambda _e, ax=ax: self._user(self._show_axis, ax))
        self.run.on_click(lambda _e: self._user(self.start))
        self.skip.on_click(lambda _e: self._user(self.start, True))
        self.cancel.on_click(lambda _e: self._user(self.stop))
        self.outcome.on_update(lambda _e: self._user(self._outcome_changed))
        self.cell.on_update(lambda _e: self._user(self._describe_cell))
        self.open.on_click(lambda _e: self._user(self.open_selected))
        self.download_csv.on_click(lambda _e: self._user(self.send_csv))
        self.download_png.on_click(lambda _e: self._user(self.send_png))
        self.download_preset.on_click(lambda _e: self._user(self.send_preset))

    # ------------------------------------------------------------------ sync guard
    @contextlib.contextmanager
    def _sync(self) -> Iterator[None]:
        self._local.depth = getattr(self._local, "depth", 0) + 1
        try:
            yield
        finally:
            self._local.depth -= 1

    def _user(self, fn: Callable[..., Any], *args: Any) -> None:
        """Run ``fn`` for a change the user made (not one set from Python)."""
        if getattr(self._local, "depth", 0) == 0 and not self.removed:
            fn(*args)

    @staticmethod
    def _set(handle: Any, value: Any) -> None:
        if handle.value != value:
            handle.value = value

    def detach(self) -> None:
        """Stop listening to the experiment (the tab closes); returns once a change being
        shown has been shown."""
        self.removed = True
        with self._lock:
            if self.experiment is not None:
                self.experiment.listen(None)
            if self._timer is not None:
                self._timer.cancel()

    def remove(self) -> None:
        """Take the tab's handles off the page and stop listening to the experiment."""
        self.detach()
        for h in reversed(self.handles):
            with contextlib.suppress(Exception):
                h.remove()

    # ------------------------------------------------------------------ the scene's catalogue
    def sync(self) -> None:
        """Offer the fields of the scene as it is now (called when the scene may have changed)."""
        sc = self.scenario()
        if sc is self._shown_scenario or self.removed:
            return
        with self._lock, self._sync():
            self._shown_scenario = sc
            self._fields = {f.key: f for f in catalogue.fields(sc)}
            keys = tuple(self._fields)
            default = keys[0] if keys else ""
            for ax in self.axes:
                options = ((NONE,) + keys) if ax.optional else (keys or ("",))
                before = ax.field.value
                if tuple(ax.field.options) != options:
                    ax.field.options = options
                keep = before if before in options else (NONE if ax.optional else default)
                ax.field.value = keep
                if keep != before or not ax.values.value:
                    if keep in self._fields:
                        ax.suggest(self._fields[keep])
                ax.show(self._fields.get(ax.field.value))
            outcomes = catalogue.outcomes(sc)
            self._scene_outcomes = {o.name for o in outcomes}
            if self.experiment is None:
                self._offer_outcomes(outcomes)

    def _offer_outcomes(self, outcomes: list[Outcome]) -> None:
        before = self.outcome.value
        self._outcomes = {o.title: o for o in outcomes}
        options = tuple(self._outcomes) or ("",)
        if tuple(self.outcome.options) != options:
            self.outcome.options = options
        first = catalogue.first_outcome(outcomes).title if outcomes else ""
        self.outcome.value = before if before in options else first

    def _field_changed(self, ax: _AxisGui) -> None:
        self.skip.visible = False  # the offer was for the grid asked before
        with self._lock, self._sync():
            field = self._fields.get(ax.field.value)
            if field is not None:
                ax.suggest(field)
            ax.show(field)

    def _show_axis(self, ax: _AxisGui) -> None:
        with self._lock:
            ax.show(self._fields.get(ax.field.value))

    # ------------------------------------------------------------------ run and cancel
    def request(self, skip_invalid: bool = False) -> ExperimentRequest:
        """What the handles ask for (checked by the service, never here). The outcome shown
        goes along if the scene records it (the list may still be a past experiment's)."""
        outcome = self._outcomes.get(self.outcome.value)
        if outcome is None:  # not an option of the dropdown: the service says so
            name = self.outcome.value
        else:
            name = outcome.name if outcome.name in self._scene_outcomes else None
        return ExperimentRequest(axes=tuple(ax.request() for ax in self.axes if ax.chosen), runs=self.runs.value,
                                 steps=self.steps.value, outcome=name, skip_invalid=skip_invalid)

    def start(self, skip_invalid: bool = False) -> Experiment | None:
        """Run experiment (``skip_invalid``: *Run the other cells*): queue the request, or say why
        it is refused, offering to leave out the cells the model refuses when others can run."""
        self.skip.visible = False
        try:
            exp = self.service.submit(self.owner, self.scenario(), self.request(skip_invalid), listener=self.changed)
        except Refused as err:
            self.status.content = "**Refused:** " + "; ".join(escape(m) for m in err.messages[:6])
            if err.runnable:
                self.skip.label = f"Run the other {err.runnable:d} of {err.cells:d} cells"
                self.skip.visible = True
            self.notify("Refused: experiment", "\n".join(err.messages[:6]), "red")
            return None
        return exp

    def stop(self) -> None:
        """Cancel experiment."""
        if self.service.cancel(self.owner) is None:
            self.notify("Nothing to cancel", "this tab has no experiment queued or running", "yellow")

    # ------------------------------------------------------------------ progress and results
    def changed(self, exp: Experiment) -> None:
        """The service's word that ``exp`` moved on (any thread)."""
        if self.removed:
            return
        with self._lock:
            new = exp is not self.experiment
            if new:
                self._adopt(exp)
            self.progress.value = 100.0 * exp.runs_done / max(exp.cost, 1)
            self.progress.animated = exp.phase == RUNNING
            self.status.content = f"**Experiment {exp.number:d}** ({escape(exp.name)}): {exp.status()}"
            if new or exp.over:
                self._redraw()
            elif len(exp.table) != self._drawn_cells:  # a new cell: drawn now, or soon if just drawn
                wait = PLOT_PERIOD - (time.monotonic() - self._drawn)
                if wait <= 0:
                    self._redraw()
                elif self._timer is None:
                    self._timer = threading.Timer(wait, self._deferred)
                    self._timer.daemon = True
                    self._timer.start()
            self.run.disabled = not exp.over  # last: a page that sees Run again sees the final plot
            self.cancel.disabled = exp.over or exp.cancelling

    def _adopt(self, exp: Experiment) -> None:
        if self.experiment is not None and self.experiment is not exp:
            self.experiment.listen(None)
        self.experiment = exp
        with self._sync():
            self._offer_outcomes(catalogue.outcomes(exp.plan.base))
            chosen = next((t for t, o in self._outcomes.items() if o.name == exp.outcome), None)
            if chosen is not None:
                self._set(self.outcome, chosen)
        self._cells = {}
        self.command.content = _command(exp)

    def _deferred(self) -> None:
        with self._lock:
            self._timer = None
            if not self.removed:
                self._redraw()

    def _outcome_changed(self) -> None:
        if self.outcome.value not in self._outcomes:
            self.notify("Refused: outcome", f"{str(self.outcome.value)[:60]}: not an outcome offered here", "red")
            return
        self._redraw()

    def _redraw(self) -> None:
        """The plot and the list of finished cells."""
        with self._lock:
            exp, outcome = self.experiment, self._outcomes.get(self.outcome.value)
            if exp is None or outcome is None:
                return
            self._drawn, self._drawn_cells = time.monotonic(), len(exp.table)
            self.plot.figure = (figure.page_figure(exp, outcome) if len(exp.table)
                                else figure.empty_figure(exp.status()))
            finished = exp.table.finished()
            if len(finished) != len(self._cells):
                self._cells = {f"{i + 1}: " + ", ".join(f"{_short(k)}={v}" for k, v in exp.plan.prefix(i).items()): i
                               for i in finished}
                with self._sync():
                    before = self.cell.value
                    self.cell.options = tuple(self._cells) or ("—",)
                    self._set(self.cell, before if before in self._cells else self.cell.options[0])
            self._describe_cell()

    def _selected(self) -> tuple[Experiment, int, Outcome | None] | None:
        exp, index = self.experiment, self._cells.get(self.cell.value)
        if exp is None or index is None:
            return None
        return exp, index, self._outcomes.get(self.outcome.value)

    def _describe_cell(self) -> None:
        with self._lock:
            picked = self._selected()
            outcome = None if picked is None else picked[2]
            if picked is None or outcome is None:
                self.cell_info.content = ""
                return
            exp, index, _ = picked
            runs = exp.table.runs_of(index, outcome.name)
            where = np.unravel_index(index, exp.plan.shape)
            med, lo, hi = (float(v[where]) for v in exp.table.summary(outcome.name))
            band = f" (95 % interval {_num(lo)} … {_num(hi)})" if lo == lo else " (too few runs for an interval)"
            self.cell_info.content = (f"median {_num(med)}{band} over {exp.plan.runs:d} runs · "
                                      f"run 0: {_num(runs[0])} · seed {exp.plan.scenario(index).sim.seed:d}")

    def open_selected(self) -> bool:
        """Open in arena: the selected cell's scenario (its preset and seed) replaces the scene."""
        with self._lock:
            picked = self._selected()
        if picked is None:
            self.notify("No cell chosen", "run an experiment and pick a finished cell first", "yellow")
            return False
        exp, index, _ = picked
        sc = exp.plan.scenario(index)  # (a finished cell: never a skipped one)
        try:
            self.open_cell(sc)
        except PresetError as err:
            self.notify("Refused: open cell", "\n".join(err.messages[:6]), "red")
            return False
        where = ", ".join(f"{k} = {v}" for k, v in exp.plan.prefix(index).items())
        self.notify("Cell opened in the arena", f"{where}, seed {sc.sim.seed}: the arena plays run 0 of this cell",
                    "green")
        return True

    def send_csv(self) -> None:
        exp = self.experiment
        if exp is None or not len(exp.table):
            self.notify("Nothing to download yet", "no cell has finished", "yellow")
            return
        self.send_file(f"{file_stem(exp.name)}-experiment.csv", exp.table.csv().encode("utf-8"))

    def send_png(self) -> None:
        exp, outcome = self.experiment, self._outcomes.get(self.outcome.value)
        if exp is None or outcome is None or not len(exp.table):
            self.notify("Nothing to download yet", "no cell has finished", "yellow")
            return
        self.send_file(f"{file_stem(exp.name)}-experiment-{outcome.name}.png", figure.png(exp, outcome))

    def send_preset(self) -> None:
        exp = self.experiment
        if exp is None:
            self.notify("Nothing to download yet", "run an experiment first", "yellow")
            return
        self.send_file(f"{file_stem(exp.name)}-experiment.toml", to_toml(exp.plan.base).encode("utf-8"))


def _num(v: float) -> str:
    return "n.c." if v == float("inf") else ("—" if v != v else f"{v:.4g}")


def _command(exp: Experiment) -> str:
    """The ``shoal sweep`` call that computes the same cells."""
    stem = file_stem(exp.name)
    grid = " ".join(f"--grid {a.key}={','.join(a.labels)}" for a in exp.plan.axes)
    return (f"The same cells from a terminal, with the preset from *Download experiment preset*:  \n"
            f"<code>{escape(f'shoal sweep {stem}-experiment.toml {grid} --runs {exp.plan.runs}', limit=None)}</code>")
