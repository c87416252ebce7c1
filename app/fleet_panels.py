"""The Chapter 4–5 control panel: the selected robot's budget, the world and its obstacles,
the controller, the robots, live plots, on top of the shared header, Export and Notes.

Controller and sensing fields change the running fleet at its next step; the world, the
robot model and the robot count rebuild it (the panel says so when it happens).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from shoal.engine.robots.dvc import TABLE_4_1
from shoal.engine.robots.laws import ROBOT_LAWS
from shoal.presets.models import Scenario

from . import fleet_plots
from .budget import budget_markdown
from .fleet_edit import MODES as CLICK_MODES
from .fleet_edit import WorldEditor
from .fleet_session import FleetSession, FleetSnapshot
from .panel_base import TRAIL, PanelsBase, SliderSpec, fmt, round_sig
from .positions_panel import PositionsGui

# label → (controller.law, controller.mode)
CONTROLLERS: dict[str, tuple[str, str]] = {
    "Original RPSO": ("rpso", "raw"),
    "Adapted RPSO (constant)": ("adapted-rpso", "raw"),
    "Adapted RPSO + DVC": ("adapted-rpso", "dvc"),
    "Robot-centred (constant)": ("robot-centred", "raw"),
    "Non-omni + DVC": ("nonomni", "dvc"),
}
BODY_FRAME_LAWS = tuple(name for name, law in ROBOT_LAWS.items() if law.body_frame)
OMNI_DRIVES = ("holonomic", "mecanum")
WORLDS = ("obstacle-course", "forest", "empty")

SLIDERS = (
    SliderSpec("sim.robots", "robots", 1, 40, 1, "number of robots (rebuilds the fleet)", True),
    SliderSpec("world.layers", "layers", 1, 15, 1, "obstacle layers, denser towards the source", True),
    SliderSpec("world.length", "length [m]", 20.0, 150.0, 1.0, "course length along x"),
    SliderSpec("world.width", "width [m]", 13.0, 80.0, 1.0, "course width, or the side of a square arena"),
    SliderSpec("world.density", "tree density", 0.01, 0.2, 0.01, "share of the forest floor covered by trees"),
    SliderSpec("controller.dt", "Δt [s]", 0.1, 2.0, 0.05, "controller period"),
    SliderSpec("controller.alpha", "α safety", 0.05, 0.99, 0.01, "DVC: a step may cover at most α of a gap [4.14]"),
    SliderSpec("controller.beta", "β", 0.05, 1.0, 0.01, "ĉ = βU/√d [4.15]; ω = 1 − β under DVC"),
    SliderSpec("controller.omega", "ω", 0.0, 0.99, 0.01, "inertia weight (constant coefficients)"),
    SliderSpec("controller.gamma", "γ", 0.1, 10.0, 0.1,
               "avoidance sensitivity [4.4]: F = γ/s; only the sign of F_t counts in Adapted RPSO"),
    SliderSpec("controller.c1_share", "c1 : c2 split", 0.0, 1.0, 0.05, "c1/(c1+c2); the thesis uses 0.5"),
    SliderSpec("sensing.range", "sensing range R [m]", 0.5, 10.0, 0.1, "LiDAR range of the six sectors"),
    TRAIL,
)
SPECS = {spec.path: spec for spec in SLIDERS}
RATIO_MARKS = ((0.5, "½"), (1.0, "1"), (2.0, "2"))  # the Table 4.1 cases
VIEWS = {"whole world": "world", "follow the swarm": "swarm", "follow the robot": "robot"}
FOLLOW_ZOOM = 2.5  # zoom a follow view starts with


def controller_changes(label: str, sc: Scenario) -> dict[str, Any]:
    """The preset fields that switch ``sc`` to the controller ``label`` (one of ``CONTROLLERS``)."""
    law, mode = CONTROLLERS[label]
    c = sc.controller
    changes: dict[str, Any] = {"controller.law": law, "controller.mode": mode}
    drive = sc.robot.drive
    if law in BODY_FRAME_LAWS and drive != "differential":
        changes["robot.drive"] = "differential"
    elif law not in BODY_FRAME_LAWS and drive == "differential":
        changes["robot.drive"] = "holonomic"
    if mode == "raw" and (c.c3 == 0.0 or c.mode == "dvc"):
        case = TABLE_4_1["c3-equal"]  # a sensible constant case to start from
        changes.update({f"controller.{k}": v for k, v in case.items()})
    return changes


def controller_label(law: str, mode: str) -> str:
    for label, key in CONTROLLERS.items():
        if key == (law, mode):
            return label
    return f"{law} ({mode})"


class FleetPanels(PanelsBase):
    """The panel of a tab running a fleet (:class:`FleetSession`)."""

    PLOT_HISTORY = 1500
    SLIDERS = SLIDERS
    EXPORT_NOTE = (" Obstacles added, removed or moved by hand are not part of the preset (it names its "
                   "world by generator and seed); the JSON export lists the obstacles as they are.")
    session: FleetSession

    def __init__(self, gui: Any, session: FleetSession, notify: Any, *args: Any, **kwargs: Any) -> None:
        self.editor = WorldEditor(session, notify, self.select_robot)
        super().__init__(gui, session, notify, *args, **kwargs)

    # ------------------------------------------------------------------ building
    def _build_above_tabs(self) -> None:
        gui = self.gui
        with gui.add_folder("Arena view and selected robot") as folder:
            self.view_mode = gui.add_dropdown("view", tuple(VIEWS), initial_value="whole world",
                                              hint="the whole world, or a closer view that follows")
            self.zoom = gui.add_slider("zoom", min=1.0, max=6.0, step=0.5, initial_value=FOLLOW_ZOOM,
                                       visible=False, hint="how close the following view is")
            self.robot = gui.add_number("robot", initial_value=0, min=0, max=self.session.sim.robots - 1, step=1,
                                        hint="whose sectors, force and budget are drawn; or click a robot")
            self.budget = gui.add_markdown("")
        self.top.append(folder)
        self.positions_gui = PositionsGui(self)

    def _build_tabs(self) -> None:
        gui, sc = self.gui, self.session.scenario
        with self.tabs.add_tab("Controller"):
            self.controller = gui.add_dropdown(
                "controller", tuple(CONTROLLERS), initial_value=controller_label(sc.controller.law, sc.controller.mode),
                hint="velocity law and coefficient policy (Chapters 4 and 5)")
            for path in ("controller.dt", "controller.alpha", "controller.beta", "controller.omega"):
                self._slider(SPECS[path])
            self.c_hat = gui.add_slider("ĉ = c1 + c2 + c3", min=0.05, max=5.0, step=0.01, initial_value=1.0,
                                        hint="total budget of the constant coefficients [m/s]")
            self.ratio = gui.add_slider("c3 / (c1 + c2)", min=0.0, max=4.0, step=0.05, initial_value=1.0,
                                        marks=RATIO_MARKS, hint="avoidance against attraction; Table 4.1: ½, 1, 2")
            for path in ("controller.gamma", "controller.c1_share", "sensing.range"):
                self._slider(SPECS[path])
            self.guard = gui.add_checkbox("DVC inertia guard", sc.controller.guard,
                                          hint="ours: cap each step at α of every sensed gap, inertia included")
            self.update_order = gui.add_dropdown(
                "update order", ("sequential", "simultaneous"), initial_value=sc.controller.update,
                hint="robots sense and move one after another (Algorithms 1–2) or all at once")
            self.readout = gui.add_markdown("")
            gui.add_markdown("*Controller changes take effect at the next step, without a restart.*")
        with self.tabs.add_tab("World"):
            gui.add_markdown("*Changes on this tab rebuild the fleet: the robots start again from the start "
                             "box and obstacle edits are dropped.*")
            self.world_kind = gui.add_dropdown("world", WORLDS, initial_value=sc.world.kind)
            for path in ("world.layers", "world.length", "world.width", "world.density", "sim.robots"):
                self._slider(SPECS[path])
            self.world_seed = gui.add_number("world seed", initial_value=int(sc.world.seed), min=0, step=1,
                                             hint="which random course or forest")
            self.motion = gui.add_dropdown("motion", ("kinematic", "physics"), initial_value=sc.robot.motion,
                                           hint="ideal particles (MATLAB) or pymunk bodies with inertia (Gazebo)")
            self.drive = gui.add_dropdown("drive", (sc.robot.drive,), initial_value=sc.robot.drive,
                                          hint="holonomic, mecanum (direction-dependent top speed) or differential")
            with gui.add_folder("Edit obstacles"):
                gui.add_markdown("Click the arena: **add** an obstacle · **shift-** or **ctrl-click** removes "
                                 "the nearest · **drag** an obstacle to move it · click a robot to select it.")
                self.click_mode = gui.add_dropdown("click does", CLICK_MODES, initial_value=CLICK_MODES[0])
                self.obstacle_radius = gui.add_slider("new obstacle radius [m]", min=0.2, max=3.0, step=0.1,
                                                      initial_value=self.session.obstacle_radius)
                self.restore = gui.add_button("Restore world", hint="drop the edits: the generated world again")
            self._slider(SPECS["view.trail_seconds"])
        with self.tabs.add_tab("Plots"):
            layers = np.asarray(self.session.sim.world.layer_x)
            self.com_plot = gui.add_uplot(
                data=fleet_plots.com_data(np.zeros(0), np.zeros(0), layers), series=fleet_plots.com_series(layers),
                scales=fleet_plots.com_scales(np.zeros(2), self.session.sim.world.bounds),
                title="swarm fitness: CoM x [m] vs time [s] · dotted: layers", aspect=1.6,
                axes=({}, {"size": 50}), legend={"show": False})
            self.robots_plot = gui.add_uplot(
                data=fleet_plots.robots_data(np.zeros(0), np.zeros(0), np.zeros(0)),
                series=fleet_plots.robots_series(), scales=fleet_plots.robots_scales(np.zeros(2), sc.sim.robots),
                title="robots vs time [s]", aspect=2.0, axes=({}, {"size": 40}))
        self._wire()

    def _wire(self) -> None:
        @self.view_mode.on_update
        def _(event: Any) -> None:
            self._view_changed()

        @self.zoom.on_update
        def _(event: Any) -> None:
            self._view_changed()

        @self.robot.on_update
        def _(event: Any) -> None:
            if not self._syncing:
                self.session.select(int(self.robot.value))

        @self.controller.on_update
        def _(event: Any) -> None:
            if not self._syncing:
                self._controller_changed()

        @self.c_hat.on_update
        def _(event: Any) -> None:
            if not self._syncing:
                self._budget_changed()

        @self.ratio.on_update
        def _(event: Any) -> None:
            if not self._syncing:
                self._budget_changed()

        @self.guard.on_update
        def _(event: Any) -> None:
            self._choice_changed("controller.guard", self.guard)

        @self.update_order.on_update
        def _(event: Any) -> None:
            self._choice_changed("controller.update", self.update_order)

        @self.world_kind.on_update
        def _(event: Any) -> None:
            self._choice_changed("world.kind", self.world_kind)

        @self.world_seed.on_update
        def _(event: Any) -> None:
            if not self._syncing:
                self._world_seed_changed()

        @self.motion.on_update
        def _(event: Any) -> None:
            self._choice_changed("robot.motion", self.motion)

        @self.drive.on_update
        def _(event: Any) -> None:
            self._choice_changed("robot.drive", self.drive)

        @self.obstacle_radius.on_update
        def _(event: Any) -> None:
            self.session.obstacle_radius = float(min(max(self.obstacle_radius.value, 0.05), 10.0))

        @self.restore.on_click
        def _(event: Any) -> None:
            self.session.restore_world()
            self.notify("World restored", "the generated obstacles are back; the robots carry on", "blue")

    # ------------------------------------------------------------------ sync
    def _sync_body(self, sc: Scenario) -> None:
        c = sc.controller
        label = controller_label(c.law, c.mode)
        options = tuple(CONTROLLERS) + (() if label in CONTROLLERS else (label,))
        if tuple(self.controller.options) != options:
            self.controller.options = options
        self._set(self.controller, label)
        c12, c3 = c.c1 + c.c2, c.c3 if c.law != "robot-centred" else 0.0
        self._set(self.c_hat, round_sig(min(max(c12 + c3, self.c_hat.min), self.c_hat.max), 4))
        self._set(self.ratio, round_sig(min(c3 / c12 if c12 > 0 else self.ratio.max, self.ratio.max), 4))
        self._set(self.guard, bool(c.guard))
        self._set(self.update_order, c.update)
        self._set(self.world_kind, sc.world.kind)
        self._set(self.world_seed, int(sc.world.seed))
        self._set(self.motion, sc.robot.motion)
        drives = ("differential",) if c.law in BODY_FRAME_LAWS else OMNI_DRIVES
        drives = drives if sc.robot.drive in drives else drives + (sc.robot.drive,)
        if tuple(self.drive.options) != drives:
            self.drive.options = drives
        self._set(self.drive, sc.robot.drive)
        n = self.session.sim.robots
        if self.robot.max != n - 1:
            self.robot.max = n - 1
        self._set(self.robot, min(self.session.selected_robot, n - 1))
        self.positions_gui.sync(sc)

    def _visibility(self) -> None:
        sc = self.session.scenario
        c, kind = sc.controller, sc.world.kind
        dvc, omni_rpso = c.mode == "dvc", c.law in ("rpso", "adapted-rpso")
        self.sliders["controller.alpha"].visible = dvc
        self.sliders["controller.beta"].visible = dvc
        self.guard.visible = dvc
        self.sliders["controller.omega"].visible = not dvc
        self.c_hat.visible = not dvc
        self.c_hat.label = "ĉ = c1 + c2 + c3" if omni_rpso else "ĉ = c1 + c2"
        self.ratio.visible = not dvc and omni_rpso
        self.sliders["controller.gamma"].visible = omni_rpso
        self.sliders["world.layers"].visible = kind == "obstacle-course"
        self.sliders["world.length"].visible = kind == "obstacle-course"
        self.sliders["world.density"].visible = kind == "forest"

    # ------------------------------------------------------------------ changes
    def apply(self, changes: dict[str, Any], what: str) -> bool:
        """As :meth:`PanelsBase.apply`, and says so when the change rebuilt the fleet."""
        before, edits = self.session.scene_revision, self.session.edits
        ok = super().apply(changes, what)
        if ok and self.session.scene_revision != before:
            dropped = f"; {edits} obstacle edit{'s' * (edits != 1)} dropped" if edits else ""
            self.notify("Fleet rebuilt", f"{what}: the robots start again from the start box{dropped}", "blue")
        return ok

    def _controller_changed(self) -> None:
        label = self.controller.value
        if label not in CONTROLLERS:
            return
        c = self.session.scenario.controller
        if CONTROLLERS[label] == (c.law, c.mode):
            return
        self.apply(controller_changes(label, self.session.scenario), f"controller = {label}")

    def compare_choices(self) -> dict[str, dict[str, Any]]:
        """B with another controller (law, coefficient policy and the drive it needs), or on
        the other positions (oracle vs SLO)."""
        sc = self.session.scenario
        here = (sc.controller.law, sc.controller.mode)
        return {**{f"controller: {label}": controller_changes(label, sc)
                   for label, key in CONTROLLERS.items() if key != here}, **self.positions_gui.compare_choices(sc)}

    def _budget_changed(self) -> None:
        """ĉ and c3/(c1+c2) → c1, c2, c3 (split by c1 : c2)."""
        c = self.session.scenario.controller
        total, ratio = float(self.c_hat.value), float(self.ratio.value)
        if c.law == "robot-centred":
            c12, c3 = total, c.c3
        else:
            c12, c3 = total / (1.0 + ratio), total * ratio / (1.0 + ratio)
        changes = {"controller.c1": round_sig(c.c1_share * c12), "controller.c2": round_sig((1 - c.c1_share) * c12),
                   "controller.c3": round_sig(c3)}
        self.apply(changes, f"ĉ = {total:g}, c3/(c1+c2) = {ratio:g}")

    def _world_seed_changed(self) -> None:
        try:
            seed = int(self.world_seed.value)
        except (TypeError, ValueError):
            seed = -1
        self.apply({"world.seed": seed}, f"world seed = {self.world_seed.value}")

    def _view_changed(self) -> None:
        follow = VIEWS.get(self.view_mode.value, "world")
        self.zoom.visible = follow != "world"
        self.session.set_view(follow, float(self.zoom.value))

    def select_robot(self, robot: int) -> None:
        self.session.select(robot)
        with self._sync():
            self._set(self.robot, self.session.selected_robot)

    def handle_click(self, x: float, y: float, modifier: str | None) -> str:
        """A click in the arena at world (x, y) (see :class:`WorldEditor`)."""
        return self.editor.click(x, y, modifier, self.click_mode.value)

    def drag_obstacle(self, index: int, x: float, y: float, phase: str) -> None:
        self.editor.drag(index, x, y, phase)

    # ------------------------------------------------------------------ readouts
    def on_snapshot(self, snap: FleetSnapshot) -> None:
        i = snap.view.robot
        if self.robot.value != i:
            with self._sync():
                self._set(self.robot, i)
        self.budget.content = budget_markdown(snap.view, snap.params, int(snap.status[i]), snap.cmd[i])
        self.positions_gui.refresh(snap.ghosts, snap.live)

    def refresh_readout(self) -> None:
        sc = self.session.scenario
        c, p = sc.controller, self.session.sim.params
        if c.mode == "dvc":
            n = 5 if c.law == "nonomni" else 3
            text = (f"ω = 1 − β = {1 - c.beta:.3g}; every robot gets its own c1..c{n} each step from its "
                    "sector gaps (see the selected robot above).")
        else:
            c_hat = c.c1 + c.c2 + (c.c3 if c.law != "robot-centred" else 0.0)
            U = c_hat * 2 ** 0.5 / (1 - c.omega)
            bound = "" if c.law == "rpso" else f"; U = ĉ√2/(1 − ω) = {fmt(U, 'm/s')}"
            text = f"c1 = {c.c1:.4g}, c2 = {c.c2:.4g}, c3 = {c.c3:.4g}, ω = {c.omega:.3g}{bound}"
            if c.law == "rpso":
                text += "; original RPSO: unbounded terms, clipped at the top speed"
        self.readout.content = text + f" · sensing range {p.sensing_range:g} m"

    def refresh_status(self) -> None:
        r = self.session.readout()
        sc = self.session.scenario
        state = "▶ playing" if self.session.playing else ("■ finished" if self.session.finished else "paused")
        edits = self.session.edits
        self.status.content = (
            f"**{sc.name}** · {state} · t = {r['t']:.0f} s · step {int(r['k'])}/{sc.sim.steps} · "
            f"CoM x = {r['com']:.1f} m"
            + (f" · layers passed {int(r['layers_passed'])}/{int(r['layers'])}" if r["layers"] else "")
            + f" · {int(r['operational'])}/{int(r['operational'] + r['collided'])} operational"
            + (f" · {edits} obstacle edit{'s' * (edits != 1)}" if edits else "")
        )

    def refresh_plots(self) -> None:
        s = self.session
        m, span = self.shown_metrics(self.PLOT_HISTORY)
        world = s.sim.world
        layers = np.asarray(world.layer_x)
        data = fleet_plots.com_data(m["t"], m["com"], layers)
        self.push_uplot(self.com_plot, data, fleet_plots.com_series(layers), fleet_plots.com_scales(span, world.bounds),
                        twin=("com", "CoM x"))
        data = fleet_plots.robots_data(m["t"], m["operational"], m["collided"])
        self.robots_plot.data = data
        self.robots_plot.scales = fleet_plots.robots_scales(span, s.sim.robots)
