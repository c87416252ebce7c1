"""The control panel of one tab: preset, playback, controller sliders, plots, export, notes.

Every slider is a preset field (a dotted path into :class:`Scenario`); its limits come
from the pydantic model, narrowed to a range that is useful on screen. A change is
validated by :meth:`Session.apply`; a refused value shows a red notification and the
handle goes back to the previous value, the running swarm untouched.

``gui`` is a viser ``GuiApi`` (``client.gui`` for a browser tab, ``server.gui`` in tests);
``notify(title, body, color)`` and ``send_file(name, bytes)`` reach the tab's client.
"""

from __future__ import annotations

import contextlib
import math
import threading
from dataclasses import dataclass
from importlib import resources
from typing import Any, Callable, Iterator

import annotated_types as at
import numpy as np

from shoal.engine import tuning
from shoal.presets.io import PresetError
from shoal.presets.models import Scenario

from . import plots
from .session import Session, app_presets

Notify = Callable[[str, str, str], None]
SendFile = Callable[[str, bytes], None]

LAWS = ("standard", "adapted-sgn", "adapted-tanh", "adapted-logistic")
MODES = ("raw", "physical")
PLAYBACK = ("Play", "Pause", "Step", "Reset")
NOTES_FALLBACK = (
    "# Teaching notes\n\nThe notes for Chapter 3 (`notes/ch3.md`) are not installed. "
    "Move the sliders on the *Controller* tab and watch the *Plots* tab."
)


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


SLIDERS = (
    SliderSpec("controller.dt", "Δt [s]", 0.01, 2.0, 0.01, "controller period: the real time of one PSO iteration"),
    SliderSpec("sim.robots", "robots", 1, 1000, 1, "number of particles; changes at once, new ones spawn at the start", True),
    SliderSpec("controller.omega", "omega ω", -1.0, 1.2, 0.01, "inertia weight (raw mode); Adapted laws need 0 ≤ ω < 1"),
    SliderSpec("controller.c1", "c1", 0.0, 5.0, 0.05, "cognitive coefficient: pull towards the personal best"),
    SliderSpec("controller.c2", "c2", 0.0, 5.0, 0.05, "social coefficient: pull towards the global best"),
    SliderSpec("controller.U", "U [m/s]", 0.1, 30.0, 0.1, "top speed (physical mode)"),
    SliderSpec("controller.A_plus", "A+ [m/s²]", 0.1, 200.0, 0.1, "top acceleration (physical mode)"),
    SliderSpec("controller.c1_share", "c1 : c2 split", 0.0, 1.0, 0.05, "c1/(c1+c2): 0 = all social, 1 = all cognitive"),
    SliderSpec("controller.smooth_width", "smooth width [m]", 0.05, 10.0, 0.05, "width of tanh / logistic in place of sgn"),
    SliderSpec("view.steps_per_second", "speed [steps/s]", 1.0, 240.0, 1.0, "playback rate"),
    SliderSpec("view.trail_seconds", "trail [s]", 0.0, 60.0, 1.0, "length of the drawn trails"),
)
SPECS = {spec.path: spec for spec in SLIDERS}


def field_bounds(path: str) -> tuple[float, float]:
    """The closed range [lo, hi] the model allows for a numeric field (±inf when open)."""
    section, name = path.split(".")
    model = Scenario.model_fields[section].annotation
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


def slider_range(spec: SliderSpec, value: float) -> tuple[float, float]:
    """The on-screen range, inside the model's range, widened to hold ``value``."""
    lo, hi = field_bounds(spec.path)
    smin, smax = max(spec.lo, lo), min(spec.hi, hi)
    if value > smax:
        smax = min(hi, float(_nice_ceil(1.5 * value)))
    if value < smin:
        smin = max(lo, value)
    return smin, smax


def _nice_ceil(v: float) -> float:
    if v <= 0:
        return 1.0
    mag = 10 ** math.floor(math.log10(v))
    for m in (1, 2, 5, 10):
        if m * mag >= v:
            return m * mag
    return 10 * mag


def get_path(scenario: Scenario, path: str) -> Any:
    section, name = path.split(".")
    return getattr(getattr(scenario, section), name)


def _round(v: float, digits: int = 6) -> float:
    return float(f"{v:.{digits}g}")


def notes_text() -> str:
    """The Chapter 3 teaching notes shipped in ``shoal.static`` (``notes/ch3.md``), or a fallback."""
    try:
        return resources.files("shoal.static").joinpath("notes/ch3.md").read_text(encoding="utf-8")
    except (FileNotFoundError, ModuleNotFoundError, OSError):
        return NOTES_FALLBACK


def _fmt(v: float, unit: str = "") -> str:
    if not math.isfinite(v):
        return "—"
    return f"{v:.4g}{(' ' + unit) if unit else ''}"


class Panels:
    """All GUI handles of one tab, wired to its :class:`Session`."""

    PLOT_HISTORY = 1500  # speed plot: at most this many points

    def __init__(self, gui: Any, session: Session, notify: Notify, send_file: SendFile) -> None:
        self.gui, self.session, self.notify, self.send_file = gui, session, notify, send_file
        self._local = threading.local()  # per thread: programmatic .value fires callbacks inline
        self.sliders: dict[str, Any] = {}
        self._stability_key: tuple | None = None
        self._phase_key: tuple | None = None
        self._build()
        self.sync_from_scenario()

    # ------------------------------------------------------------------ building
    def _build(self) -> None:
        gui, sc = self.gui, self.session.scenario
        names = tuple(app_presets())
        self.preset = gui.add_dropdown(
            "preset", names, initial_value=sc.name if sc.name in names else names[0],
            hint="shipped scenes; switching replaces the whole scene")
        self.status = gui.add_markdown("")
        self.playback = gui.add_button_group("playback", PLAYBACK)
        self._slider(SPECS["view.steps_per_second"])
        self.seed = gui.add_number("seed", initial_value=int(sc.sim.seed), min=0, step=1,
                                   hint="random seed; changing it restarts the run")
        tabs = gui.add_tab_group()
        with tabs.add_tab("Controller"):
            self.law = gui.add_dropdown("law", LAWS, initial_value=sc.controller.law,
                                        hint="velocity update: standard PSO [2.1] or Adapted PSO [3.11]")
            self.mode = gui.add_dropdown("mode", MODES, initial_value=sc.controller.mode,
                                         hint="raw: set ω, c1, c2; physical: set U, A+, Δt and derive ω, ĉ")
            for path in ("controller.dt", "sim.robots"):
                self._slider(SPECS[path])
            with gui.add_folder("Raw coefficients") as self.raw_folder:
                for path in ("controller.omega", "controller.c1", "controller.c2"):
                    self._slider(SPECS[path])
            with gui.add_folder("Physical limits") as self.physical_folder:
                for path in ("controller.U", "controller.A_plus", "controller.c1_share"):
                    self._slider(SPECS[path])
            self._slider(SPECS["controller.smooth_width"])
            self._slider(SPECS["view.trail_seconds"])
            self.readout = gui.add_markdown("")
        with tabs.add_tab("Plots"):
            # (viser's plotly aspect is height/width; uPlot's below is width/height)
            self.stability_plot = gui.add_plotly(plots.stability_figure(0.5, 1.0, adapted=True), aspect=1.0)
            self.particle = gui.add_number("particle", initial_value=0, min=0, max=max(sc.sim.robots - 1, 0),
                                           step=1, hint="which particle the phase plane shows")
            self.dimension = gui.add_dropdown("dimension", self._dims(sc), initial_value="x")
            self.phase_plot = gui.add_plotly(plots.phase_figure(0.5, 1.0, 0.1), aspect=1.0)
            adapted = sc.controller.law != "standard"
            self.speed_plot = gui.add_uplot(
                data=plots.speed_data(np.zeros(0), np.zeros(0), np.zeros(0), np.zeros(0), np.zeros(0),
                                      adapted=adapted, d=sc.sim.d),
                series=plots.speed_series_config(adapted), scales=plots.speed_scales(np.zeros(2)),
                title="highest speed vs time [m/s]", aspect=2.0, axes=({}, {"size": 76}),
            )
            self._speed_adapted = adapted
        with tabs.add_tab("Export"):
            gui.add_markdown("Trajectories of the current run (the last steps kept in memory), "
                             "the scenario as a preset file, or load your own preset.")
            self.export_csv = gui.add_button("Export CSV", hint="run,step,t,robot,x,y,heading,vx,vy,status")
            self.export_json = gui.add_button("Export JSON", hint="resolved preset, seed, version, trajectories")
            self.download = gui.add_button("Download preset", hint="the current scenario as TOML")
            self.upload = gui.add_upload_button("Upload preset", hint=".toml or .json, at most 256 KiB")
        with tabs.add_tab("Notes"):
            self.notes = gui.add_markdown(notes_text())
        self._wire()

    def _slider(self, spec: SliderSpec) -> None:
        value = get_path(self.session.scenario, spec.path)
        lo, hi = slider_range(spec, value)
        h = self.gui.add_slider(spec.label, min=lo, max=hi, step=spec.step,
                                initial_value=int(value) if spec.integer else float(value), hint=spec.hint)
        self.sliders[spec.path] = h

        @h.on_update
        def _(event: Any) -> None:
            self._field_changed(spec, h)

    @staticmethod
    def _dims(sc: Scenario) -> tuple[str, ...]:
        return ("x", "y", "z")[: sc.sim.d]

    def _wire(self) -> None:
        @self.preset.on_update
        def _(event: Any) -> None:
            if self._syncing:
                return
            self.load_preset(self.preset.value)

        @self.playback.on_click
        def _(event: Any) -> None:
            self.press(event.target.value)

        @self.seed.on_update
        def _(event: Any) -> None:
            if self._syncing:
                return
            self._seed_changed()

        @self.law.on_update
        def _(event: Any) -> None:
            if not self._syncing:
                self._choice_changed("controller.law", self.law)

        @self.mode.on_update
        def _(event: Any) -> None:
            if not self._syncing:
                self._mode_changed()

        @self.particle.on_update
        def _(event: Any) -> None:
            n = self.session.scenario.sim.robots
            self.session.selected_robot = int(min(max(int(self.particle.value), 0), n - 1))

        @self.dimension.on_update
        def _(event: Any) -> None:
            dims = self._dims(self.session.scenario)
            if self.dimension.value in dims:
                self.session.selected_dim = dims.index(self.dimension.value)

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

    def _set(self, handle: Any, value: Any) -> None:
        if handle.value != value:
            handle.value = value

    def sync_from_scenario(self) -> None:
        """Push the session's scenario into every handle (after a preset switch, upload or mode change)."""
        sc = self.session.scenario
        with self._sync():
            for spec in SLIDERS:
                h, value = self.sliders[spec.path], get_path(sc, spec.path)
                lo, hi = slider_range(spec, value)
                if (h.min, h.max) != (lo, hi):
                    h.min, h.max = lo, hi
                self._set(h, int(value) if spec.integer else float(value))
            self._set(self.law, sc.controller.law)
            self._set(self.mode, sc.controller.mode)
            self._set(self.seed, int(sc.sim.seed))
            if sc.name in self.preset.options:
                self._set(self.preset, sc.name)
            self.particle.max = max(sc.sim.robots - 1, 0)
            if self.particle.value > sc.sim.robots - 1:
                self._set(self.particle, sc.sim.robots - 1)
            dims = self._dims(sc)
            if tuple(self.dimension.options) != dims:
                self.dimension.options = dims
            if self.dimension.value not in dims:
                self._set(self.dimension, dims[0])
        self._visibility()
        self.refresh_readout()

    def _visibility(self) -> None:
        c = self.session.scenario.controller
        self.raw_folder.visible = c.mode == "raw"
        self.physical_folder.visible = c.mode == "physical"
        self.sliders["controller.smooth_width"].visible = c.law in ("adapted-tanh", "adapted-logistic")

    # ------------------------------------------------------------------ changes
    def _refuse(self, err: PresetError, what: str) -> None:
        body = "\n".join(err.messages[:6])
        self.notify(f"Refused: {what}", body, "red")

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
        value = handle.value
        if value == get_path(self.session.scenario, path):
            return
        self.apply({path: value}, f"{path.split('.')[-1]} = {value}")

    def _mode_changed(self) -> None:
        """Switch raw ↔ physical keeping the controller's behaviour: carry (ω, c1, c2) ↔ (U, A+, split)."""
        target = self.mode.value
        sc = self.session.scenario
        if target == sc.controller.mode:
            return
        omega, c = self.session.sim.policy.coefficients(self.session.sim.t, self.session.sim.dt, self.session.sim.d)
        c = np.asarray(c, dtype=float).reshape(-1)
        c_hat = float(c.sum())
        changes: dict[str, Any] = {"controller.mode": target}
        if target == "raw":
            changes.update({"controller.omega": _round(float(np.mean(omega))),
                            "controller.c1": _round(float(c[0])), "controller.c2": _round(float(c[1:].sum()))})
        else:
            try:
                tun = tuning.from_coefficients(float(np.mean(omega)), c_hat, sc.controller.dt, sc.sim.d)
                changes.update({"controller.U": _round(tun.U), "controller.A_plus": _round(tun.A_plus),
                                "controller.c1_share": _round(float(c[0]) / c_hat)})
            except tuning.TuningError:
                pass  # keep the stored U, A+; the model decides whether that is valid
        self.apply(changes, f"mode = {target}")

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

    def load_preset(self, name: str) -> bool:
        try:
            self.session.load_preset(name)
        except PresetError as err:
            self._refuse(err, f"preset {name}")
            self.sync_from_scenario()
            return False
        self.sync_from_scenario()
        self.notify("Preset loaded", self.session.scenario.description or name, "green")
        return True

    def upload_preset(self, filename: str, content: bytes) -> bool:
        """Validate an uploaded preset; a bad one is listed field by field and changes nothing."""
        try:
            sc = self.session.load_upload(filename, content)
        except PresetError as err:
            self._refuse(err, f"uploaded {filename}")
            return False
        self.sync_from_scenario()
        self.notify("Preset uploaded", f"{filename}: scene '{sc.name}' loaded", "green")
        return True

    # ------------------------------------------------------------------ readouts and plots
    def refresh_readout(self) -> None:
        r = self.session.readout()
        c = self.session.scenario.controller
        lines = [
            "| ω | ĉ [m/s] | β | U [m/s] | U_j [m/s] | A+ | A− |",
            "|---|---|---|---|---|---|---|",
            f"| {_fmt(r['omega'])} | {_fmt(r['c_hat'])} | {_fmt(r['beta'])} | {_fmt(r['U'])} | "
            f"{_fmt(r['U_j'])} | {_fmt(r['A_plus'])} | {_fmt(r['A_minus'])} |",
        ]
        if c.law == "standard":
            lines.append("\nStandard PSO: ĉ has no unit and nothing bounds the speed.")
        elif c.mode == "physical":
            lines.append("\nDerived from U, A+ and Δt: β = A+Δt/U, ω = 1 − β, ĉ = A+Δt/√d.")
        self.readout.content = "\n".join(lines)

    def refresh_status(self) -> None:
        r = self.session.readout()
        sc = self.session.scenario
        state = "▶ playing" if self.session.playing else ("■ finished" if self.session.finished else "paused")
        self.status.content = (
            f"**{sc.name}** · {state} · t = {r['t']:.1f} s · step {int(r['k'])}/{sc.sim.steps} · "
            f"best f = {r['best']:.4g}"
            + (f" · {int(r['outside'])} outside the arena" if r["outside"] else "")
        )

    def refresh_plots(self) -> None:
        """Rebuild the three plots from the session (the caller throttles this)."""
        s = self.session
        sc = s.scenario
        adapted = sc.controller.law != "standard"
        omega, c_hat = s.coefficients()
        key = (round(omega, 9), round(c_hat, 9), adapted)
        if key != self._stability_key:  # move the point; building a new figure costs ~50 ms
            self.stability_plot.figure = plots.update_stability_point(
                self.stability_plot.figure, omega, c_hat, adapted=adapted)
            self._stability_key = key
        robot, dim = s.selected_robot, s.selected_dim
        u, a = s.particle_history(robot, dim)
        label = f"particle {robot}, {self._dims(sc)[min(dim, sc.sim.d - 1)]}"
        phase_key = (key, round(s.sim.dt, 12), label)
        fig = self.phase_plot.figure
        if phase_key != self._phase_key or not plots.update_phase_points(fig, u, a):
            fig = plots.phase_figure(omega, c_hat, s.sim.dt, u, a, adapted=adapted, label=label)
            self._phase_key = phase_key
        self.phase_plot.figure = fig
        m = s.metric_arrays()
        n = self.PLOT_HISTORY
        cut = {k: v[-n:] for k, v in m.items()}
        if adapted != self._speed_adapted:
            self.speed_plot.series = plots.speed_series_config(adapted)
            self._speed_adapted = adapted
        data = plots.speed_data(
            cut["t"], cut["max_speed"], cut["max_component"], cut["omega"], cut["c_hat"], adapted=adapted, d=sc.sim.d)
        self.speed_plot.data = data
        # An explicit x range on every update: viser's client keeps a *relative* x range across
        # data pushes, which goes wrong for a chart first mounted in a hidden tab.
        self.speed_plot.scales = plots.speed_scales(data[0])
