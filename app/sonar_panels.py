"""The Chapter 6–8 control panel: the selected robot's hearing, the signal (SNR_0, Q, D/λ_c,
TBP), the algorithm and forgetting, the swarm and the source, live plots, on top of the
shared header, Export and Notes.

Every change goes through the scenario model (``PanelsBase.apply``). Signal, forgetting,
speed, escort and source-motion changes reach the running swarm at its next step; the
algorithm, the swarm size and SNR_0 rebuild it, and the panel says so.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from shoal.engine.acoustics.strategies import STRATEGIES
from shoal.presets.models import Scenario

from . import sonar_plots
from .panel_base import TRAIL, PanelsBase, SliderSpec, fmt
from .positions_panel import PositionsGui
from .sonar_session import SonarSession, SonarSnapshot

ALGORITHMS = STRATEGIES.labels()
LABELS = {v: k for k, v in ALGORITHMS.items()}

SLIDERS = (
    SliderSpec("acoustics.snr0_db", "SNR₀ [dB]", -10.0, 30.0, 0.5,
               "SNR at the start; places the source at d_s = R_ref·10^(−SNR₀/20) (rebuilds)",
               marks=((-5.0, "−5"), (0.0, "0"), (4.0, "4"), (10.0, "10"))),
    SliderSpec("acoustics.Q", "Q = f_c/B", 0.5, 20.0, 0.1, "quality factor: high Q = narrow band, side peaks",
               marks=((1.0, "1"), (1.5, "1.5"), (10.0, "10"))),
    SliderSpec("acoustics.d_over_lambda", "D/λ_c", 0.1, 4.0, 0.05,
               "hydrophone separation in wavelengths; above ½ the phase wraps",
               marks=((0.5, "½"), (1.0, "1"), (2.0, "2"))),
    SliderSpec("acoustics.tbp", "TBP = B·T", 10.0, 1000.0, 10.0, "time-bandwidth product of one listening window"),
    SliderSpec("acoustics.a", "forgetting a", 0.0, 5.0, 0.05, "memory × e^(−a) each step [7.2]; 0 = never forget"),
    SliderSpec("sim.robots", "swarm size", 2, 60, 1, "number of robots (rebuilds the swarm)", True),
    SliderSpec("acoustics.U", "U [m/s]", 0.2, 10.0, 0.1, "top speed"),
    SliderSpec("acoustics.r", "escort radius r [m]", 0.0, 200.0, 1.0,
               "keep this distance from the global best (needs the non-omni controller, Ch. 8.2)"),
    SliderSpec("acoustics.v_n", "source speed v_n", 0.0, 1.0, 0.01, "source speed as a share of U [8.8]"),
    SliderSpec("acoustics.source_heading_deg", "source heading [°]", -180.0, 180.0, 5.0,
               "direction the source moves (0 = +x)"),
    TRAIL,
)
SPECS = {spec.path: spec for spec in SLIDERS}
REBUILD_NOTE = "*SNR₀, the algorithm and the swarm size rebuild the swarm; the rest applies at the next step.*"


class SonarPanels(PanelsBase):
    """The panel of a tab running an acoustic swarm (:class:`SonarSession`)."""

    PLOT_HISTORY = 2000
    SLIDERS = SLIDERS
    EXPORT_NOTE = " The JSON export also lists the source where it is now (it may have been dragged)."
    session: SonarSession

    # ------------------------------------------------------------------ building
    def _build_above_tabs(self) -> None:
        gui = self.gui
        with gui.add_folder("Selected robot") as folder:
            self.robot = gui.add_number("robot", initial_value=0, min=0, max=self.session.sim.robots - 1, step=1,
                                        hint="whose rays are drawn thick and whose R(τ) is plotted; or click a robot")
            self.hearing = gui.add_markdown("")
        self.top.append(folder)
        self.positions_gui = PositionsGui(self)

    def _build_tabs(self) -> None:
        gui, sc = self.gui, self.session.scenario
        with self.tabs.add_tab("Acoustics"):
            self.algorithm = gui.add_dropdown(
                "algorithm", tuple(ALGORITHMS), initial_value=LABELS[sc.acoustics.algorithm],
                hint="A: amplitude · X: correlation peak · B: ray intersections · XB: both · GT: triangulation")
            for path in ("acoustics.snr0_db", "acoustics.Q", "acoustics.d_over_lambda", "acoustics.tbp",
                         "acoustics.a"):
                self._slider(SPECS[path])
            self.readout = gui.add_markdown("")
            gui.add_markdown(REBUILD_NOTE)
        with self.tabs.add_tab("Swarm"):
            for path in ("sim.robots", "acoustics.U", "acoustics.r", "acoustics.v_n", "acoustics.source_heading_deg",
                         "view.trail_seconds"):
                self._slider(SPECS[path])
            gui.add_markdown("Drag the green source in the arena to move it; click a robot to select it. "
                             "Green ray: the one of the pair nearer the true source; orange: its mirror. "
                             "Purple dots: ray intersections ahead of both rays (grey: dropped by the ρ test "
                             "[7.12]); pink diamonds: each robot's chosen intersection. Gold diamond: the "
                             "global best; green circle: d_c round the source; gold rings: the escort ring.")
        with self.tabs.add_tab("Plots"):
            self.corr_plot = gui.add_uplot(
                data=sonar_plots.corr_data(np.zeros(0), np.zeros(0), 0.0, 0.0), series=sonar_plots.corr_series(),
                scales={"x": {"time": False}}, title="selected robot: R(τ) vs τ [ms] · red: τ_lag", aspect=1.8,
                axes=({}, {"size": 50}))
            self.dist_plot = gui.add_uplot(
                data=sonar_plots.dist_data(np.zeros(0), np.zeros(0), sc.acoustics.d_c),
                series=sonar_plots.dist_series(), scales=sonar_plots.dist_scales(np.zeros(2)),
                title="|CoM − source| [m] vs time [s]", aspect=1.8, axes=({}, {"size": 50}))
            snr = self.session.sim.state.snr_db[0]
            self.snr_plot = gui.add_uplot(
                data=sonar_plots.snr_data(snr), series=sonar_plots.snr_series(), scales=sonar_plots.snr_scales(snr),
                title="SNR [dB] at each robot", aspect=2.0, axes=({}, {"size": 40}), legend={"show": False})
        self._wire()

    def _wire(self) -> None:
        @self.robot.on_update
        def _(event: Any) -> None:
            if not self._syncing:
                self.select_robot(int(self.robot.value))

        @self.algorithm.on_update
        def _(event: Any) -> None:
            if self._syncing:
                return
            algo = ALGORITHMS.get(self.algorithm.value)
            if algo is not None and algo != self.session.scenario.acoustics.algorithm:
                self.apply({"acoustics.algorithm": algo}, f"algorithm = {self.algorithm.value}")

    # ------------------------------------------------------------------ sync
    def _sync_body(self, sc: Scenario) -> None:
        self._set(self.algorithm, LABELS[sc.acoustics.algorithm])
        n = self.session.sim.robots
        if self.robot.max != n - 1:
            self.robot.max = n - 1
        self._set(self.robot, min(self.session.selected_robot, n - 1))
        self.positions_gui.sync(sc)

    def _visibility(self) -> None:
        ac = self.session.scenario.acoustics
        self.sliders["acoustics.r"].visible = ac.controller == "nonomni"
        self.sliders["acoustics.d_over_lambda"].visible = ac.algorithm in ("x-pso", "b-pso", "xb-pso")

    # ------------------------------------------------------------------ changes
    def apply(self, changes: dict[str, Any], what: str) -> bool:
        before = self.session.scene_revision
        ok = super().apply(changes, what)
        if ok and self.session.scene_revision != before:
            self.notify("Swarm rebuilt", f"{what}: the robots start again", "blue")
        return ok

    def select_robot(self, robot: int) -> None:
        self.session.select(robot)
        with self._sync():
            self._set(self.robot, self.session.selected_robot)
        self.refresh_plots()

    def handle_click(self, x: float, y: float, modifier: str | None) -> str:
        """A click in the arena: near a robot selects it; shift-click puts the source there."""
        if modifier == "shift":
            self.session.move_source(x, y)
            return "source"
        robot = self.session.robot_near(x, y)
        if robot is not None:
            self.select_robot(robot)
            return "selected"
        return "none"

    def drag_source(self, x: float, y: float, phase: str) -> None:
        """The source dragged to (x, y) m: the swarm tracks it from the next step."""
        if phase == "start":
            return
        self.session.move_source(x, y)

    # ------------------------------------------------------------------ readouts
    def on_snapshot(self, snap: SonarSnapshot) -> None:
        i = snap.selected
        if self.robot.value != i:
            with self._sync():
                self._set(self.robot, i)
        text = f"robot {i}: SNR {snap.snr[i]:.1f} dB, {np.hypot(*(snap.x[i] - snap.source)):.0f} m from the source"
        corr = self.session.correlation(i)
        if corr is not None:
            _, _, tau, rho = corr
            text += f" · τ_lag = {tau * 1e3:.3f} ms · ρ = {rho:.3g}"
        if snap.true_ray is not None:
            text += " · true ray: " + ("r₊" if snap.true_ray[i] == 0 else "r₋")
        self.hearing.content = text
        self.positions_gui.refresh(snap.ghosts, snap.live)

    def refresh_readout(self) -> None:
        r = self.session.readout()
        ac = self.session.scenario.acoustics
        self.readout.content = (
            f"R_ref = {fmt(r['r_ref'], 'm')} (SNR 0 dB) · source starts at d_s = {fmt(r['d_s'], 'm')} · "
            f"λ_c = {fmt(r['lambda'], 'm')} · D = {fmt(r['D'], 'm')} · window ±D/c = "
            f"{r['D'] / ac.c * 1e3:.3g} ms · controller {ac.controller}")

    def refresh_status(self) -> None:
        r = self.session.readout()
        sc = self.session.scenario
        state = "▶ playing" if self.session.playing else ("■ finished" if self.session.finished else "paused")
        conv = f" · reached d_c at step {int(r['converged_at'])}" if r["converged_at"] >= 0 else ""
        ring = f" · {100 * r['inside']:.0f}% inside r" if sc.acoustics.r > 0 else ""
        self.status.content = (
            f"**{sc.name}** · {LABELS[sc.acoustics.algorithm]} · {state} · t = {r['t']:.0f} s · "
            f"step {int(r['k'])}/{sc.sim.steps} · |CoM − source| = {r['com_dist']:.0f} m{conv}{ring}")

    def compare_choices(self) -> dict[str, dict[str, Any]]:
        """B with another localisation algorithm, or on the other positions (oracle vs SLO)."""
        sc = self.session.scenario
        here = sc.acoustics.algorithm
        return {**{f"algorithm: {label}": {"acoustics.algorithm": alg} for label, alg in ALGORITHMS.items()
                   if alg != here}, **self.positions_gui.compare_choices(sc)}

    def corr_plot_data(self) -> tuple[np.ndarray, ...]:
        c = self.session.correlation()
        if c is None:
            return sonar_plots.corr_data(np.zeros(0), np.zeros(0), 0.0, 0.0)
        return sonar_plots.corr_data(*c)

    def refresh_plots(self) -> None:
        if self.removed:
            return
        s = self.session
        data = self.corr_plot_data()
        self.corr_plot.data = data
        self.corr_plot.scales = sonar_plots.corr_scales(data)
        m, span = self.shown_metrics(self.PLOT_HISTORY)
        data = sonar_plots.dist_data(m["t"], m["com_dist"], s.scenario.acoustics.d_c)
        self.push_uplot(self.dist_plot, data, sonar_plots.dist_series(), sonar_plots.dist_scales(span),
                        twin=("com_dist", "|CoM − source|"))
        with s.lock:
            snr = s.sim.state.snr_db[0].copy()
        self.snr_plot.data = sonar_plots.snr_data(snr)
        self.snr_plot.scales = sonar_plots.snr_scales(snr)
