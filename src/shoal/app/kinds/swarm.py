"""The Chapter 3 swarm in free space (a :class:`Simulation`), on true or SLO-estimated positions.

Its controller (law, ω, c1, c2 or U, A+, Δt), the swarm size, the bests and the objective
change the running swarm; the SLO error set and localisation settings retune its running SLO
source; the dimension, the start, the oracle/SLO switch and the SLO unit rebuild it with the
same seed.
"""

from __future__ import annotations

import math
import time
from typing import Any

import numpy as np

from shoal.engine.core.objectives import OBJECTIVES, Objective
from shoal.engine.kinds.swarm import Simulation
from shoal.engine.pso import tuning
from shoal.engine.pso.laws import LAWS
from shoal.engine.pso.stability import diverged
from shoal.presets.builders.swarm import build_simulation, objective_for
from shoal.presets.io import PresetError
from shoal.presets.kinds import kind_of
from shoal.presets.models import Scenario

from ..markdown import escape
from ..panel import figures
from ..panel.panel import TRAIL_SLIDER
from ..panel.plots import PlotSpec, Series, log10_abs
from ..panel.positions import positions_choices, positions_folder
from ..panel.selection import robot_number
from ..panel.spec import Dropdown, Figure, Folder, KindPanel, PanelAPI, Slider, Tab, Text, fmt, round_sig
from ..session.history import Frame, frame_of
from ..session.session import Session
from ..session.snapshot import Snapshot
from ..view.canvas import Canvas
from ..view.layers import (
    Ghosts,
    GlobalBest,
    Ground,
    Headings,
    Landscape,
    Layer,
    LegendEntry,
    PersonalBests,
    Robots,
    Static,
    Trails,
    Twin,
)
from ..view.view import KeepSwarmInView
from .base import AppKind, BaseDriver

ROBOT = (220, 50, 50)
ROBOT_SIZE = 0.24  # scene units: the disc drawn has this radius
HEADING = (120, 20, 20)
TRAIL = (80, 120, 255)
PBEST = (110, 110, 110)
GBEST = (240, 170, 0)
SOURCE = (20, 150, 60)
ARENA = (40, 40, 40)


def second_moment(x: np.ndarray, yg: np.ndarray) -> float:
    """Mean over robots and coordinates of (x − y_g)² [m²]: what the order-2 region [3.9] bounds,
    measured (our reading: about the global best, the part of every attractor the robots share)."""
    with np.errstate(over="ignore", invalid="ignore"):
        return float(np.mean((np.asarray(x, float) - np.asarray(yg, float)) ** 2))


class SwarmDriver(BaseDriver):
    """A Chapter 3 swarm's side of a session."""

    scene_sections = ("objective", "arena")
    sim: Simulation

    def build(self, scenario: Scenario) -> Simulation:
        return build_simulation(scenario, runs=1)

    def frame(self, t: float) -> Frame:
        return frame_of(self.sim.state, t, accelerations=True)

    def snapshot(self, selected: int) -> dict[str, Any]:
        s = self.sim.state
        return {"y": s.y[0].copy(), "yg": s.yg[0].copy(), "ghosts": self.ghosts(selected, s.yg[0])}

    def metrics(self) -> dict[str, float]:
        """The measured second moment of the swarm (see :func:`second_moment`)."""
        s = self.sim.state
        return {"second_moment": second_moment(s.x[0], s.yg[0])}

    def coefficients(self) -> tuple[float, float]:
        """The (ω, ĉ) the controller uses at the current time (means over robots for per-robot policies)."""
        with self.session.lock:
            sim = self.sim
            omega, c = sim.policy.coefficients(sim.t, sim.dt, sim.d)
            c = np.asarray(c, dtype=float)
            c_hat = float(np.sum(c.reshape(c.shape[0], -1).mean(axis=1))) if c.ndim else float(c)
            return float(np.mean(omega)), c_hat

    def readout(self) -> dict[str, float]:
        """Derived quantities for the panel: ω, ĉ, β, U, U_j, A+, A− (NaN where undefined)."""
        omega, c_hat = self.coefficients()
        d, dt = self.sim.d, self.sim.dt
        adapted = self.sim.law.adapted
        bounded = adapted and 0.0 <= omega < 1.0
        U_j = c_hat / (1.0 - omega) if bounded else math.nan
        A_plus = c_hat * math.sqrt(d) / dt if adapted else math.nan
        return {
            "omega": omega, "c_hat": c_hat, "beta": (1.0 - omega) if bounded else math.nan,
            "U": U_j * math.sqrt(d), "U_j": U_j, "A_plus": A_plus, "A_minus": 2 * A_plus,
            "t": self.session.clock(), "k": float(self.sim.state.k), "best": float(self.sim.state.best_fitness[0]),
            "outside": float(self.outside_arena()), "diverged": float(diverged(self.sim.state.u[:1])[0]),
        }

    def outside_arena(self) -> int:
        """How many robots are outside the arena square (a diverging swarm leaves the picture)."""
        with self.session.lock:
            x = self.sim.state.x[0, :, :2]
            return int(np.sum(np.any(np.abs(x) > self.session.scenario.arena.half_size, axis=-1)))

    def particle_history(self, robot: int, dim: int, n: int = 120) -> tuple[np.ndarray, np.ndarray]:
        """The last ``n`` (u_j, a_j) of one particle and dimension, oldest first."""
        with self.session.lock:
            frames = list(self.session.history.frames)[-n:]
        pts = [(f.u[robot, dim], f.a[robot, dim]) for f in frames
               if f.a is not None and robot < f.u.shape[0] and dim < f.u.shape[1]]
        arr = np.array(pts, dtype=float).reshape(-1, 2)
        return arr[:, 0], arr[:, 1]


# ---------------------------------------------------------------------------- view
class Optimum(Static):
    """Where the objective is best (a benchmark's optimum, or the source), with its name."""

    name = "optimum"
    keys = ("source", "source_label")
    legend = (LegendEntry("●", SOURCE, "optimum / source"),)

    def build(self, canvas: Canvas, snap: Snapshot) -> None:
        o = snap.scenario.objective
        if o.kind == "linear":
            return
        where = np.asarray(o.source, dtype=float) if snap.scenario.sim.d >= 2 else np.array([o.source[0], 0.0])
        canvas.points("source", where[None], SOURCE, 0.3, "circle", 0.01)
        canvas.label("source_label", "source" if o.kind == "source-distance" else "optimum", where + 0.5 / canvas.scale)


def landscape(scenario: Scenario) -> Objective | None:
    """The objective of a 2-D (or 3-D) swarm is drawn as a heat map (the distance to a source too)."""
    return objective_for(scenario.objective) if scenario.sim.d >= 2 else None


def layers(panels: Any) -> tuple[Layer, ...]:
    """The Chapter 3 arena: the square with its grid, the landscape or the source, the robots
    with their headings, trails and bests; swarm B and the selected robot's beliefs."""
    return (
        Ground(cell=lambda half: half / 10, cell_colour=(225, 225, 225), section_colour=(185, 185, 185), z=-0.02,
               border=ARENA, border_px=2.5, border_z=0.0),
        Landscape(landscape, z=-0.04),
        Optimum(),
        Trails(TRAIL, 1.5, 0.0),
        PersonalBests(PBEST, 0.1, 0.005),
        Headings(HEADING, lambda canvas, snap: 0.35 / canvas.scale, 0.015),
        Robots(ROBOT, ROBOT_SIZE, 0.02),
        GlobalBest(GBEST, 0.4, 0.012),
        Twin(ROBOT_SIZE, (0.018, -0.001), px=1.5),
        Ghosts(ROBOT_SIZE),
    )


# ---------------------------------------------------------------------------- panel
MODES = ("raw", "physical")
SMOOTH_LAWS = ("adapted-tanh", "adapted-logistic")  # a smooth squash in place of sgn (§3.2.1)
DIMS = ("x", "y", "z")


def _adapted(sc: Scenario) -> bool:
    return LAWS[sc.controller.law].adapted


def _raw(s: Session) -> bool:
    return s.scenario.controller.mode == "raw"


def _mode_changes(s: Session, target: str) -> dict[str, Any] | None:
    """Switch raw ↔ physical keeping the controller's behaviour: carry (ω, c1, c2) ↔ (U, A+, split)."""
    sc = s.scenario
    if target == sc.controller.mode:
        return None
    with s.lock:
        sim = s.sim
        omega, c = sim.policy.coefficients(sim.t, sim.dt, sim.d)
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
    return changes


def _dims(s: Session) -> tuple[str, ...]:
    """The names of the swarm's axes: x, y, z up to three; x1 … xd beyond (the arena draws the first two)."""
    d = s.scenario.sim.d
    return DIMS[:d] if d <= len(DIMS) else tuple(f"x{i + 1}" for i in range(d))


def _dim(s: Session) -> str:
    return _dims(s)[min(s.selected_dim, s.scenario.sim.d - 1)]


def _pick_dim(panel: PanelAPI, value: Any) -> None:
    dims = _dims(panel.session)
    if value in dims:
        panel.session.selected_dim = dims.index(value)


def _table(rows: list[tuple[str, str]]) -> str:
    """A two-column markdown table: what, value."""
    return "| | |\n|---|---|\n" + "\n".join(f"| {escape(what)} | {escape(value)} |" for what, value in rows)


def _readout(s: Session) -> str:
    """The controller's coefficients and bounds as a table [3.26]–[3.35] (the derived ones in
    physical mode: β, ω, ĉ, U_j, A−; in raw mode U and A+ too)."""
    r, c = s.readout(), s.scenario.controller
    law = LAWS[c.law]
    if r["diverged"]:
        return (_table([("ω", fmt(r["omega"])), ("ĉ = c1 + c2", fmt(r["c_hat"]))])
                + f"\n\n*The swarm {DIVERGED_WORDS}; Reset starts it again.*")
    if not law.adapted:
        return (_table([("ω", fmt(r["omega"])), ("ĉ = c1 + c2", fmt(r["c_hat"]))])
                + f"\n\n*{escape(law.label)}: ĉ has no unit and nothing bounds the speed.*")
    rows = [("β = A+Δt/U [3.34]", fmt(r["beta"])), ("ω = 1 − β [3.35]", fmt(r["omega"])),
            ("ĉ = A+Δt/√d [3.32]", fmt(r["c_hat"], "m/s")), ("U_j = ĉ/(1 − ω) [3.26]", fmt(r["U_j"], "m/s"))]
    if c.mode == "physical":
        return (_table(rows + [("A− = 2A+ [3.31]", fmt(r["A_minus"], "m/s²"))])
                + "\n\n*ω, c1 and c2 follow from U, A+ and Δt; moving one of them switches to raw mode.*")
    return (_table(rows + [("U = U_j√d [3.29]", fmt(r["U"], "m/s")), ("A+ = ĉ√d/Δt", fmt(r["A_plus"], "m/s²")),
                           ("A− = 2A+ [3.31]", fmt(r["A_minus"], "m/s²"))])
            + "\n\n*Raw mode: U and A+ follow from ω and ĉ = c1 + c2 [m/s].*")


def _physical(s: Session) -> bool:
    return not _raw(s)


def _coefficient(name: str) -> Any:
    """``read`` of a raw coefficient slider: the field in raw mode, the value in force (derived
    from U, A+, Δt) in physical mode."""
    key = f"controller.{name}"

    def read(s: Session) -> float:
        return float(getattr(s.scenario.controller, name)) if _raw(s) else round_sig(_raw_coefficients(s)[key], 4)
    return read


def _set_coefficient(name: str) -> Any:
    """``write`` of a raw coefficient slider: in physical mode, switch to raw mode at the
    coefficients in force with this one changed."""
    key = f"controller.{name}"

    def write(s: Session, value: float) -> dict[str, Any] | None:
        if _raw(s):
            return None if value == getattr(s.scenario.controller, name) else {key: value}
        return {**_raw_coefficients(s), key: value}
    return write


def _status(s: Session, r: dict[str, float], state: str) -> str:
    sc = s.scenario
    best = DIVERGED_WORDS if r["diverged"] else f"best f = {r['best']:.4g}"
    return (f"**{escape(sc.name)}** · {state} · t = {r['t']:.1f} s · {s.progress()} · {best}"
            + (f" · {int(r['outside'])} outside the arena" if r["outside"] else ""))


DIVERGED_WORDS = "**diverged** (robots faster than 10⁹ m/s: these coefficients are outside the law's stable region)"


def _compare(s: Session) -> dict[str, dict[str, Any]]:
    """B with another law: the standard law at the same (ω, c1, c2), or an Adapted one; in 2-D
    also on the other positions (oracle vs SLO)."""
    sc = s.scenario
    out: dict[str, dict[str, Any]] = {}
    if LAWS[sc.controller.law].adapted and "standard" in LAWS:
        out["standard PSO law (same ω, c1, c2)"] = {"controller.law": "standard", **_raw_coefficients(s)}
    for law in LAWS.names():
        if LAWS[law].adapted and law != sc.controller.law:
            out[f"{law} law"] = {"controller.law": law}
    if sc.sim.d == 2:
        out.update(positions_choices(sc))
    return out


def _raw_coefficients(s: Session) -> dict[str, Any]:
    """The controller's current (ω, c1, c2) as raw-mode fields (physical mode derives them)."""
    with s.lock:
        sim = s.sim
        omega, c = sim.policy.coefficients(sim.t, sim.dt, sim.d)
    c = np.asarray(c, dtype=float).reshape(-1)
    return {"controller.mode": "raw", "controller.omega": round_sig(float(np.mean(omega))),
            "controller.c1": round_sig(float(c[0])), "controller.c2": round_sig(float(c[1:].sum()))}


def _bound(j: int) -> Any:
    """Series of U (j = 0) or U_j (j = 1): drawn for Adapted laws; elsewhere (and where undefined)
    it repeats max|u| (max|u_j|) so that the hidden series never stretch the y axis."""
    def values(m: dict[str, np.ndarray], sc: Scenario) -> np.ndarray:
        speed = m["max_speed"] if j == 0 else m["max_component"]
        if not _adapted(sc):
            return speed.copy()
        bound = figures.speed_bounds(m["omega"], m["c_hat"], sc.sim.d)[j]
        return np.where(np.isfinite(bound), bound, speed)
    return values


def _source(s: Session) -> bool:
    return s.scenario.objective.kind == "source-distance"


SPREAD = PlotSpec(
    "spread", "measured spread: log₁₀ of mean (x − y_g)² [m²]", (
        Series("log10 spread", lambda m, sc: log10_abs(m["second_moment"]), "rgb(120,60,200)", 2),
    ), y_range=(None, None), aspect=3.4, legend={"show": False})
BEST_DISTANCE = PlotSpec(
    "best_distance", "best position's distance to the source [m]", (
        Series("|y_g − source| [m]", "best_fitness", "rgb(30,140,70)", 2),
    ), twin="best_fitness", aspect=2.4, visible=_source)
BEST_F = PlotSpec(
    "best_f", "best f, log₁₀ |f|", (
        Series("log10 |best f|", lambda m, sc: log10_abs(m["best_fitness"]), "rgb(30,140,70)", 2),
    ), y_range=(None, None), aspect=2.4, visible=lambda s: not _source(s))
SPEED = PlotSpec(
    "speed", "highest speed [m/s]", (
        Series("max |u|", "max_speed", "rgb(220,50,50)", 2),
        Series("max |u_j|", "max_component", "rgb(240,160,40)", 1),
        Series("U", _bound(0), "rgb(40,90,200)", 2, dash=(6.0, 4.0), show=_adapted),
        Series("U_j", _bound(1), "rgb(90,170,230)", 1, dash=(3.0, 3.0), show=_adapted),
    ), twin="max_speed", aspect=2.0)


class _Figures:
    """The (ω, ĉ) plane and the phase plane of one panel, moved rather than rebuilt where they can.
    Each plotly update is a whole figure for the page to lay out again, so while the run plays the
    phase plane follows at most once every ``PHASE_PERIOD`` seconds (control feedback first)."""

    PHASE_PERIOD = 1.0

    def __init__(self) -> None:
        self._stability: tuple | None = None
        self._phase: tuple | None = None
        self._phase_at = -math.inf

    def stability(self, s: Session) -> Any:
        return figures.stability_figure(0.5, 1.0, adapted=True)

    def phase(self, s: Session) -> Any:
        return figures.phase_figure(0.5, 1.0, 0.1)

    def _key(self, s: Session) -> tuple:
        omega, c_hat = driver(s).coefficients()
        return round(omega, 9), round(c_hat, 9), LAWS[s.scenario.controller.law].region == "adapted"

    def refresh_stability(self, panel: PanelAPI, handle: Any) -> None:
        key = self._key(panel.session)
        if key != self._stability:  # move the point; building a new figure costs ~50 ms
            handle.figure = figures.update_stability_point(handle.figure, key[0], key[1], adapted=key[2])
            self._stability = key

    def refresh_phase(self, panel: PanelAPI, handle: Any) -> None:
        s = panel.session
        now = time.monotonic()
        if s.playing and now - self._phase_at < self.PHASE_PERIOD:
            return
        self._phase_at = now
        key = self._key(s)
        omega, c_hat, adapted = key
        robot, dim = s.selected_robot, s.selected_dim
        u, a = driver(s).particle_history(robot, dim)
        label = f"particle {robot}, {_dims(s)[min(dim, s.scenario.sim.d - 1)]}"
        phase_key = (key, round(s.sim.dt, 12), label)
        fig = handle.figure
        if phase_key != self._phase or not figures.update_phase_points(fig, u, a):
            fig = figures.phase_figure(omega, c_hat, s.sim.dt, u, a, adapted=adapted, label=label)
            self._phase = phase_key
        handle.figure = fig


def panel(api: PanelAPI) -> KindPanel:
    """Controller sliders (raw ω, c1, c2 or physical U, A+, Δt), the (ω, ĉ) and phase-plane
    plots and the speed plot; in 2-D the *Positions* folder."""
    figs = _Figures()
    return KindPanel(
        tabs=(
            Tab("Controller", (
                Dropdown("controller.law", "law", lambda s: LAWS.names(),
                         hint="velocity update: standard PSO [2.1], Adapted PSO [3.11] or an installed plug-in's"),
                Dropdown("objective.kind", "objective", lambda s: OBJECTIVES.names(),
                         hint="what the swarm optimises: the distance to the source, a benchmark or an installed "
                              "plug-in's function"),
                Dropdown("controller.mode", "mode", MODES, write=_mode_changes,
                         hint="raw: set ω, c1, c2; physical: set U, A+, Δt and derive ω, ĉ"),
                Slider("controller.dt", "Δt [s]", 0.01, 2.0, 0.01,
                       "controller period: the real time of one PSO iteration"),
                Slider("sim.robots", "robots", 1, 1000, 1,
                       "number of particles; changes at once, new ones spawn at the start", integer=True),
                Folder("Coefficients", key="coefficients", items=(  # ω, c1, c2 always: moving one gives raw mode
                    Slider("controller.omega", "omega ω", -1.0, 1.2, 0.01,
                           "inertia weight; Adapted laws need 0 ≤ ω < 1 (in physical mode: moving it switches to raw)",
                           read=_coefficient("omega"), write=_set_coefficient("omega")),
                    Slider("controller.c1", "c1", 0.0, 5.0, 0.05,
                           "cognitive coefficient: pull towards the personal best", widen=True,
                           read=_coefficient("c1"), write=_set_coefficient("c1")),
                    Slider("controller.c2", "c2", 0.0, 5.0, 0.05, "social coefficient: pull towards the global best",
                           widen=True, read=_coefficient("c2"), write=_set_coefficient("c2")),
                    Slider("controller.U", "U [m/s]", 0.1, 30.0, 0.1, "top speed (physical mode)", visible=_physical),
                    Slider("controller.A_plus", "A+ [m/s²]", 0.1, 200.0, 0.1, "top acceleration (physical mode)",
                           visible=_physical),
                    Slider("controller.c1_share", "c1 : c2 split", 0.0, 1.0, 0.05,
                           "c1/(c1+c2): 0 = all social, 1 = all cognitive", visible=_physical),
                )),
                Slider("controller.smooth_width", "smooth width [m]", 0.05, 10.0, 0.05,
                       "width of tanh / logistic in place of sgn",
                       visible=lambda s: s.scenario.controller.law in SMOOTH_LAWS),
                TRAIL_SLIDER,
                Text("readout", compute=_readout),
                positions_folder(" The robot is the *particle* of the Plots tab.",
                                 visible=lambda s: s.scenario.sim.d == 2),  # SLO localises in the plane
            )),
            Tab("Plots", (
                Figure("stability", figs.stability, figs.refresh_stability, aspect=0.7),
                SPREAD,
                BEST_DISTANCE,
                BEST_F,
                robot_number("particle", "which particle the phase plane shows", key="particle"),
                Dropdown("dimension", "dimension", _dims, read=_dim, act=_pick_dim),
                Figure("phase", figs.phase, figs.refresh_phase),
                SPEED,
            )),
        ),
        status=_status, compare=_compare)


def supported(scenario: Scenario) -> None:
    """A free-space swarm needs mode raw or physical (DVC needs a [world])."""
    if scenario.world is None and scenario.controller.mode not in ("raw", "physical"):
        raise PresetError([f"controller.mode: {scenario.controller.mode!r} needs a [world]; the browser app "
                           "offers 'raw' and 'physical' without one"])


def accepts(scenario: Scenario) -> bool:
    """Free-space swarms, on true or (``[slo] swarm = "host"``) SLO-estimated positions."""
    return kind_of(scenario) == "swarm"


def refuse(scenario: Scenario) -> None:
    supported(scenario)
    if scenario.world is not None:
        raise PresetError([f"world: {scenario.name} has obstacles; it runs as a fleet, not a free swarm"])
    if not accepts(scenario):
        raise PresetError([f"slo.swarm: {scenario.name} runs Mai's SLO swarm (swarm = 'slo'), not the "
                           "Chapter 3 swarm; set slo.swarm = 'host' for the Chapter 3 swarm on SLO positions"])


KIND = AppKind(name="swarm", title="Chapter 3 swarm", engine="swarm", refuse=refuse,
               make_driver=SwarmDriver, notes="ch3", layers=layers, camera=KeepSwarmInView, make_panel=panel)


def driver(session: Session) -> SwarmDriver:
    """``session``'s driver, typed (a session of this kind)."""
    assert isinstance(session.driver, SwarmDriver), session.kind.name
    return session.driver
