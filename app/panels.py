"""The Chapter 3 control panel: controller sliders (raw ω, c1, c2 or physical U, A+, Δt), the
(ω, ĉ) and phase-plane plots and the speed plot, on top of the shared header, Export and
Notes of :class:`PanelsBase`; in 2-D the *Positions* folder (true or SLO-estimated
positions, :mod:`.positions_panel`).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from shoal.engine.pso import tuning
from shoal.engine.pso.laws import LAWS as VELOCITY_LAWS
from shoal.presets.models import Scenario

from . import plots
from .panel_base import TRAIL, PanelsBase, SliderSpec, field_bounds, fmt, get_path, notes_text, round_sig, slider_range
from .positions_panel import PositionsGui
from .session import Session, Snapshot

__all__ = ["LAWS", "MODES", "Panels", "SLIDERS", "SPECS", "field_bounds", "get_path", "notes_text",
           "slider_range"]

LAWS = VELOCITY_LAWS.names()
MODES = ("raw", "physical")

SLIDERS = (
    SliderSpec("controller.dt", "Δt [s]", 0.01, 2.0, 0.01, "controller period: the real time of one PSO iteration"),
    SliderSpec("sim.robots", "robots", 1, 1000, 1,
               "number of particles; changes at once, new ones spawn at the start", True),
    SliderSpec("controller.omega", "omega ω", -1.0, 1.2, 0.01,
               "inertia weight (raw mode); Adapted laws need 0 ≤ ω < 1"),
    SliderSpec("controller.c1", "c1", 0.0, 5.0, 0.05, "cognitive coefficient: pull towards the personal best"),
    SliderSpec("controller.c2", "c2", 0.0, 5.0, 0.05, "social coefficient: pull towards the global best"),
    SliderSpec("controller.U", "U [m/s]", 0.1, 30.0, 0.1, "top speed (physical mode)"),
    SliderSpec("controller.A_plus", "A+ [m/s²]", 0.1, 200.0, 0.1, "top acceleration (physical mode)"),
    SliderSpec("controller.c1_share", "c1 : c2 split", 0.0, 1.0, 0.05, "c1/(c1+c2): 0 = all social, 1 = all cognitive"),
    SliderSpec("controller.smooth_width", "smooth width [m]", 0.05, 10.0, 0.05,
               "width of tanh / logistic in place of sgn"),
    TRAIL,
)
SPECS = {spec.path: spec for spec in SLIDERS}


class Panels(PanelsBase):
    """The panel of a tab running a Chapter 3 swarm (:class:`Session`)."""

    PLOT_HISTORY = 1500  # speed plot: at most this many points
    SLIDERS = SLIDERS
    session: Session

    def __init__(self, gui: Any, session: Session, *args: Any, **kwargs: Any) -> None:
        self._stability_key: tuple | None = None
        self._phase_key: tuple | None = None
        super().__init__(gui, session, *args, **kwargs)

    # ------------------------------------------------------------------ building
    def _build_above_tabs(self) -> None:
        self.positions_gui = PositionsGui(self, observer=" The robot is the *particle* of the Plots tab.")

    def _build_tabs(self) -> None:
        gui, sc = self.gui, self.session.scenario
        with self.tabs.add_tab("Controller"):
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
        with self.tabs.add_tab("Plots"):
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
        self._wire()

    @staticmethod
    def _dims(sc: Scenario) -> tuple[str, ...]:
        return ("x", "y", "z")[: sc.sim.d]

    def _wire(self) -> None:
        @self.law.on_update
        def _(event: Any) -> None:
            self._choice_changed("controller.law", self.law)

        @self.mode.on_update
        def _(event: Any) -> None:
            if not self._syncing:
                self._mode_changed()

        @self.particle.on_update
        def _(event: Any) -> None:
            if int(self.particle.value) != self.session.selected_robot:
                self.session.select(int(self.particle.value))  # redraws its ghosts (SLO positions)

        @self.dimension.on_update
        def _(event: Any) -> None:
            dims = self._dims(self.session.scenario)
            if self.dimension.value in dims:
                self.session.selected_dim = dims.index(self.dimension.value)

    def _sync_body(self, sc: Scenario) -> None:
        self._set(self.law, sc.controller.law)
        self._set(self.mode, sc.controller.mode)
        self.particle.max = max(sc.sim.robots - 1, 0)
        if self.particle.value > sc.sim.robots - 1:
            self._set(self.particle, sc.sim.robots - 1)
        dims = self._dims(sc)
        if tuple(self.dimension.options) != dims:
            self.dimension.options = dims
        if self.dimension.value not in dims:
            self._set(self.dimension, dims[0])
        self.positions_gui.sync(sc)

    def _visibility(self) -> None:
        c = self.session.scenario.controller
        self.raw_folder.visible = c.mode == "raw"
        self.physical_folder.visible = c.mode == "physical"
        self.sliders["controller.smooth_width"].visible = c.law in ("adapted-tanh", "adapted-logistic")
        self.positions_gui.folder.visible = self.session.scenario.sim.d == 2  # SLO localises in the plane

    def compare_choices(self) -> dict[str, dict[str, Any]]:
        """B with another law: the standard law at the same (ω, c1, c2), or an Adapted one;
        in 2-D also on the other positions (oracle vs SLO)."""
        sc = self.session.scenario
        c = sc.controller
        out: dict[str, dict[str, Any]] = {}
        if c.law != "standard":
            out["standard PSO law (same ω, c1, c2)"] = {"controller.law": "standard", **self._raw_coefficients()}
        for law in LAWS[1:]:
            if law != c.law:
                out[f"{law} law"] = {"controller.law": law}
        if sc.sim.d == 2:
            out.update(self.positions_gui.compare_choices(sc))
        return out

    def on_snapshot(self, snap: Snapshot) -> None:
        self.positions_gui.refresh(snap.ghosts, snap.live)

    def _raw_coefficients(self) -> dict[str, Any]:
        """The controller's current (ω, c1, c2) as raw-mode fields (physical mode derives them)."""
        sim = self.session.sim
        with self.session.lock:
            omega, c = sim.policy.coefficients(sim.t, sim.dt, sim.d)
        c = np.asarray(c, dtype=float).reshape(-1)
        return {"controller.mode": "raw", "controller.omega": round_sig(float(np.mean(omega))),
                "controller.c1": round_sig(float(c[0])), "controller.c2": round_sig(float(c[1:].sum()))}

    # ------------------------------------------------------------------ changes
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
            changes.update({"controller.omega": round_sig(float(np.mean(omega))),
                            "controller.c1": round_sig(float(c[0])), "controller.c2": round_sig(float(c[1:].sum()))})
        else:
            try:
                tun = tuning.from_coefficients(float(np.mean(omega)), c_hat, sc.controller.dt, sc.sim.d)
                changes.update({"controller.U": round_sig(tun.U), "controller.A_plus": round_sig(tun.A_plus),
                                "controller.c1_share": round_sig(float(c[0]) / c_hat)})
            except tuning.TuningError:
                pass  # keep the stored U, A+; the model decides whether that is valid
        self.apply(changes, f"mode = {target}")

    # ------------------------------------------------------------------ readouts and plots
    def refresh_readout(self) -> None:
        r = self.session.readout()
        c = self.session.scenario.controller
        lines = [
            "| ω | ĉ [m/s] | β | U [m/s] | U_j [m/s] | A+ | A− |",
            "|---|---|---|---|---|---|---|",
            f"| {fmt(r['omega'])} | {fmt(r['c_hat'])} | {fmt(r['beta'])} | {fmt(r['U'])} | "
            f"{fmt(r['U_j'])} | {fmt(r['A_plus'])} | {fmt(r['A_minus'])} |",
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
        cut, span = self.shown_metrics(self.PLOT_HISTORY)
        data = plots.speed_data(
            cut["t"], cut["max_speed"], cut["max_component"], cut["omega"], cut["c_hat"], adapted=adapted, d=sc.sim.d)
        # An explicit x range on every update: viser's client keeps a *relative* x range across
        # data pushes, which goes wrong for a chart first mounted in a hidden tab.
        self.push_uplot(self.speed_plot, data, plots.speed_series_config(adapted), plots.speed_scales(span),
                        twin=("max_speed", "max |u|"))
