"""The SLO control panel of Mai's swarm (spec §15.2, item 4): candidate selection,
prediction weight and mitigation thresholds, the error set and its single errors, the
neighbourhood, objective, motion and swarm size; the observer robot and the pair whose
triangle is inspected; live plots. On top of the shared header, Export and Notes.

Every control is a preset field and goes through the model; a change that needs a new swarm
rebuilds it with the same seed (the panel says so). The oracle/SLO switch of a scene's own
swarm lives in that scene's *Positions* folder (:mod:`.positions_panel`).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from shoal.engine.slo.selection import SELECTIONS as SLO_SELECTIONS
from shoal.engine.slo.sensors import error_model
from shoal.presets.models import Scenario, SLOErrorValues

from . import slo_plots
from .panel_base import TRAIL, PanelsBase, SliderSpec, fmt
from .slo_session import FLAG_NAMES, KIND_NAMES, SLOSession

SELECTIONS = SLO_SELECTIONS.labels()
ERROR_SETS = {"None": "none", "Low": "low", "High": "high"}
NEIGHBOURHOODS = ("knn", "radius", "full", "random", "ring")
OBJECTIVES = ("sphere", "ackley", "griewank", "rastrigin", "rosenbrock", "plane", "line")
MOTIONS = ("pso", "random_walk")
PARAM_DEFAULT = {"knn": 5, "radius": 25, "ring": 2, "random": 0.5, "full": math.nan}

SLIDERS = (
    SliderSpec("slo.prediction_weight", "w (prediction weight)", 0.0, 1.0, 0.01,
               "CSS: how far the kept estimate leans to dead reckoning x3 [3.7]"),
    SliderSpec("slo.delta_cos", "δ_cos", 0.0, 0.2, 0.005,
               "mitigation: dead reckoning when |cos α| is within δ_cos of 1"),
    SliderSpec("slo.delta_v", "δ_v", 0.0, 0.5, 0.005, "mitigation: dead reckoning when |v|/d < δ_v (thin triangle)"),
    SliderSpec("slo.walk_speed", "walk speed", 0.5, 20.0, 0.5, "random walk: longest step (thesis units)"),
    SliderSpec("sim.robots", "robots", 2, 60, 1, "swarm size P; RTS and Akcan slow down above ~30", True),
    TRAIL,
)


def _error_range(name: str) -> tuple[float, float, float]:
    """On-screen (max, step, default shown) of one single error slider."""
    if name.endswith("p_fail"):
        return 0.5, 0.01, 0.0
    if name.endswith("sigma_r"):
        return 0.5, 0.005, 0.0
    if name.endswith("sigma_a"):
        return 3.0, 0.01, 0.0
    return 0.5, 0.005, 0.0


ERROR_FIELDS = tuple(SLOErrorValues.model_fields)


def _key(mapping: dict[str, str], value: str) -> str:
    return next((k for k, v in mapping.items() if v == value), value)


class SLOPanels(PanelsBase):
    """The panel of a tab running an SLO scene (:class:`SLOSession`)."""

    PLOT_HISTORY = 2000
    SLIDERS = SLIDERS
    EXPORT_NOTE = " The JSON export adds the selected robot's estimates of the others."
    session: SLOSession

    def _build_tabs(self) -> None:
        gui, sc = self.gui, self.session.scenario
        slo = sc.slo
        with self.tabs.add_tab("SLO"):
            self.selection = gui.add_dropdown(
                "selection", tuple(SELECTIONS), initial_value=_key(SELECTIONS, slo.selection),
                hint="which candidate becomes the estimate [3.7]-[3.9]")
            for spec in SLIDERS[:3]:
                self._slider(spec)
            self.errors = gui.add_dropdown("error set", tuple(ERROR_SETS), initial_value=_key(ERROR_SETS, slo.errors),
                                           hint="Tab. 4.3; choosing a set clears the single errors below")
            self.error_sliders: dict[str, Any] = {}
            with gui.add_folder("single errors", expand_by_default=False):
                for name in ERROR_FIELDS:
                    hi, step, _ = _error_range(name)
                    h = gui.add_slider(name, min=0.0, max=hi, step=step, initial_value=0.0,
                                       hint=SLOErrorValues.model_fields[name].description or name)
                    self.error_sliders[name] = h
                    h.on_update(self._error_cb(name, h))
            self.neighbourhood = gui.add_dropdown("neighbourhood", NEIGHBOURHOODS, initial_value=slo.neighbourhood,
                                                  hint="who localises whom (computed from truth)")
            self.neigh_param = gui.add_number("neighbourhood parameter", initial_value=5.0, min=0.0, step=0.1,
                                              hint="k (knn), r (radius), n (ring), p (random)")
            self.engine = gui.add_markdown("")
            gui.add_markdown("*An SLO change restarts the run with the same seed, so settings compare run "
                             "for run.*")
        with self.tabs.add_tab("Swarm"):
            self.motion = gui.add_dropdown("motion", MOTIONS, initial_value=slo.motion,
                                           hint="SLO swarm: SPSO 2011 in each robot's frame, or a random walk")
            self.objective = gui.add_dropdown("objective", OBJECTIVES, initial_value=slo.objective,
                                              hint="SLO swarm: 2-D benchmark, minimised")
            for spec in SLIDERS[3:]:
                self._slider(spec)
        with self.tabs.add_tab("Inspect"):
            n = self.session.robots
            self.robot = gui.add_number("observer robot", initial_value=0, min=0, max=n - 1, step=1,
                                        hint="whose beliefs are drawn as ghosts; or click a robot")
            self.neighbour = gui.add_number("inspected neighbour", initial_value=-1, min=-1, max=n - 1, step=1,
                                            hint="the pair of the triangle inspector; −1 = the first neighbour")
            self.inspector = gui.add_markdown("")
        with self.tabs.add_tab("Plots"):
            gen = self._generations()
            z = np.zeros(0)
            self.error_plot = gui.add_uplot(
                data=slo_plots.error_data(z, z, z, z), series=slo_plots.error_series(gen),
                scales=slo_plots.error_scales(z), title="localisation error", aspect=1.8,
                axes=({}, {"size": 45}, {"scale": "rel", "side": 1, "size": 40}))
            self.distance_plot = gui.add_uplot(
                data=slo_plots.distance_data(z, z), series=slo_plots.distance_series(gen),
                scales=slo_plots.plain_scales(z), title="median distance between robots", aspect=2.2,
                axes=({}, {"size": 45}))
            self.fitness_plot = gui.add_uplot(
                data=slo_plots.fitness_data(z, z), series=slo_plots.fitness_series(gen),
                scales=slo_plots.plain_scales(z), title="best fitness, log10 |f|", aspect=2.2,
                axes=({}, {"size": 45}))
        self._wire()

    def _generations(self) -> bool:
        return self.session.scenario.slo.swarm == "slo"

    def _error_cb(self, name: str, h: Any) -> Any:
        def cb(event: Any) -> None:
            if self._syncing:
                return
            value = float(h.value)
            if math.isclose(value, self._error_value(name), abs_tol=1e-12):
                return
            self.apply({f"slo.error_values.{name}": value}, f"{name} = {value:g}")

        return cb

    def _error_value(self, name: str) -> float:
        slo = self.session.scenario.slo
        set_value = getattr(slo.error_values, name)
        if set_value is not None:
            return float(set_value)
        model = error_model(slo.errors)
        part, _, field = name.partition("_")
        return float(getattr(getattr(model, part), field))

    def _wire(self) -> None:
        @self.selection.on_update
        def _(event: Any) -> None:
            self._mapped("slo.selection", SELECTIONS, self.selection)

        @self.errors.on_update
        def _(event: Any) -> None:
            if self._syncing:
                return
            value = ERROR_SETS.get(self.errors.value, self.errors.value)
            slo = self.session.scenario.slo
            if value == slo.errors and not slo.error_values.values():
                return
            self.apply({"slo.errors": value, "slo.error_values": {}}, f"error set = {self.errors.value}")

        @self.neighbourhood.on_update
        def _(event: Any) -> None:
            if self._syncing or self.neighbourhood.value == self.session.scenario.slo.neighbourhood:
                return
            self.apply({"slo.neighbourhood": self.neighbourhood.value, "slo.neighbourhood_param": None},
                       f"neighbourhood = {self.neighbourhood.value}")

        @self.neigh_param.on_update
        def _(event: Any) -> None:
            if self._syncing:
                return
            try:
                value = float(self.neigh_param.value)
            except (TypeError, ValueError):
                value = -1.0
            if value == self.session.scenario.slo.neighbourhood_param:
                return
            self.apply({"slo.neighbourhood_param": value}, f"neighbourhood parameter = {self.neigh_param.value}")

        @self.motion.on_update
        def _(event: Any) -> None:
            self._choice_changed("slo.motion", self.motion)

        @self.objective.on_update
        def _(event: Any) -> None:
            self._choice_changed("slo.objective", self.objective)

        @self.robot.on_update
        def _(event: Any) -> None:
            if not self._syncing:
                self.session.select(int(self.robot.value))

        @self.neighbour.on_update
        def _(event: Any) -> None:
            if self._syncing:
                return
            j = int(self.neighbour.value)
            with self.session.lock:
                self.session.selected_neighbour = None if j < 0 else min(j, self.session.robots - 1)
                self.session.revision += 1

    def _mapped(self, path: str, mapping: dict[str, str], handle: Any) -> None:
        if self._syncing:
            return
        value = mapping.get(handle.value, handle.value)
        section, name = path.split(".")
        if value == getattr(getattr(self.session.scenario, section), name):
            return
        self.apply({path: value}, f"{name} = {handle.value}")

    # ------------------------------------------------------------------ sync
    def _sync_body(self, sc: Scenario) -> None:
        slo = sc.slo
        self._set(self.selection, _key(SELECTIONS, slo.selection))
        self._set(self.errors, _key(ERROR_SETS, slo.errors))
        for name, h in self.error_sliders.items():
            v = self._error_value(name)
            if v > h.max:
                h.max = float(min(100.0, 2 * v))
            self._set(h, v)
        self._set(self.neighbourhood, slo.neighbourhood)
        p = slo.neighbourhood_param if slo.neighbourhood_param is not None else PARAM_DEFAULT[slo.neighbourhood]
        if not math.isnan(p):
            self._set(self.neigh_param, float(p))
        self._set(self.motion, slo.motion)
        self._set(self.objective, slo.objective)
        n = self.session.robots
        if self.robot.max != n - 1:
            self.robot.max = n - 1
            self.neighbour.max = n - 1
        self._set(self.robot, min(self.session.selected_robot, n - 1))

    def _visibility(self) -> None:
        slo = self.session.scenario.slo
        self.objective.visible = slo.motion == "pso"
        self.sliders["slo.walk_speed"].visible = slo.motion == "random_walk"
        self.neigh_param.visible = slo.neighbourhood != "full"

    def compare_choices(self) -> dict[str, dict[str, Any]]:
        """B with another candidate selection."""
        slo = self.session.scenario.slo
        out: dict[str, dict[str, Any]] = {}
        for label, value in SELECTIONS.items():
            if value != slo.selection:
                out[f"selection: {label}"] = {"slo.selection": value}
        return out

    def apply(self, changes: dict[str, Any], what: str) -> bool:
        before = self.session.scene_revision
        ok = super().apply(changes, what)
        if ok and self.session.scene_revision != before and not all(k.startswith("view.") for k in changes):
            self.notify("Run restarted", f"{what}: same seed, step 0 ({self.session.engine_name})", "blue")
        return ok

    # ------------------------------------------------------------------ clicks
    def handle_click(self, x: float, y: float, modifier: str | None) -> str:
        """Click a robot: it becomes the observer; shift-click: the inspected neighbour."""
        half = self.session.scenario.arena.half_size
        j = self.session.robot_near(x, y, tol=0.04 * half)
        if j is None:
            return "nothing"
        if modifier == "shift":
            with self.session.lock:
                self.session.selected_neighbour = j
                self.session.revision += 1
            with self._sync():
                self._set(self.neighbour, j)
            return "neighbour"
        self.session.select(j)
        with self._sync():
            self._set(self.robot, j)
        return "observer"

    # ------------------------------------------------------------------ readouts
    def refresh_readout(self) -> None:
        s = self.session
        sc = s.scenario
        what = "SPSO 2011 in each robot's frame" if sc.slo.motion == "pso" else "a random walk"
        self.engine.content = (f"engine: **{s.engine_name}**, Mai's SLO swarm ({what}) · "
                               f"selection {sc.slo.selection.upper()}")

    def on_snapshot(self, snap: Any) -> None:
        if self.robot.value != snap.selected:
            with self._sync():
                self._set(self.robot, snap.selected)
        p = snap.pair
        if p is None:
            self.inspector.content = f"Robot {snap.selected} has no neighbour this step."
            return
        cand = " · ".join(f"{n}" for n, m in zip(("x1", "x2", "x3"), p.mask) if m)
        err = float(np.hypot(*(p.chosen - p.b)))
        lines = [
            f"**pair ({p.i} → {p.j})**{'' if p.neighbour else ' (not a neighbour this step: stale)'}",
            f"candidates: {cand or '—'} · {FLAG_NAMES.get(p.flag, p.flag)}",
            f"chosen: **{KIND_NAMES.get(p.kind, p.kind)}** · error |x̂ − r| = {fmt(err)}",
            f"cos α = {fmt(p.cos_alpha)} · |v|/d = {fmt(p.thinness)}",
        ]
        if self.session.scenario.slo.selection == "rts":
            lines.append(f"RTS loop error e_r = {fmt(p.round_trip)}")
        lines.append(f"robot {snap.selected} localised {len(snap.ghost_of)} neighbour(s) this step")
        self.inspector.content = "  \n".join(lines)

    def refresh_status(self) -> None:
        s = self.session
        r = s.readout()
        sc = s.scenario
        state = "▶ playing" if s.playing else ("■ finished" if s.finished else "paused")
        unit = "gen" if self._generations() else "step"
        self.status.content = (
            f"**{sc.name}** · {state} · {unit} {int(r['k'])}/{sc.sim.steps} · "
            f"mean e_abs {fmt(r['e_abs_mean'])} · best f {fmt(r['best'])}")

    def refresh_plots(self) -> None:
        m, span = self.shown_metrics(self.PLOT_HISTORY)
        t = m["t"]
        data = slo_plots.error_data(t, m["e_abs_mean"], m["e_abs_median"], m["e_rel_median"])
        self.push_uplot(self.error_plot, data, slo_plots.error_series(self._generations()),
                        slo_plots.error_scales(span), twin=("e_abs_mean", "mean e_abs"))
        data = slo_plots.distance_data(t, m["distance_median"])
        self.distance_plot.data = data
        self.distance_plot.scales = slo_plots.plain_scales(span)
        data = slo_plots.fitness_data(t, m["best"])
        self.fitness_plot.data = data
        self.fitness_plot.scales = slo_plots.plain_scales(span)
