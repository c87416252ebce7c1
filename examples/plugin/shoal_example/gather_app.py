"""The ``gather`` kind in the browser app: a driver, the arena's layers, a camera and a panel
(one tab: speed, noise, the trail and a plot of the spread). The shared session, view and panel
do the rest: playback, history, replays, Compare, Share, export."""

from __future__ import annotations

from typing import Any

from shoal.app.kinds.base import AppKind, BaseDriver
from shoal.app.panel.panel import TRAIL_SLIDER
from shoal.app.panel.plots import PlotSpec, Series
from shoal.app.panel.spec import KindPanel, PanelAPI, Slider, Tab
from shoal.app.session.session import Session
from shoal.app.view.layers import Ground, Headings, Layer, Robots, Trails, Twin
from shoal.app.view.view import KeepSwarmInView
from shoal.presets.io import PresetError

from .gather import Gather, build_gather


class GatherDriver(BaseDriver):
    """The gather kind's side of a session (which changes retune it: the kind's ``live`` rule)."""

    def build(self, scenario: Any) -> Gather:
        return build_gather(scenario, runs=1)

    def snapshot(self, selected: int) -> dict[str, Any]:
        return {}

    def readout(self) -> dict[str, float]:
        info = self.sim.info()
        return {"spread": float(info.spread[0]), "k": float(self.sim.state.k)}


def layers(panels: Any) -> tuple[Layer, ...]:
    return (
        Ground(cell=lambda half: half / 10, cell_colour=(225, 225, 225), section_colour=(185, 185, 185), z=-0.02,
               border=(40, 40, 40), border_px=2.5, border_z=0.0),
        Trails((80, 120, 255), 1.5, 0.0),
        Headings((20, 90, 40), lambda canvas, snap: 0.35 / canvas.scale, 0.015),
        Robots((40, 160, 80), 0.24, 0.02),
        Twin(0.24, (0.018, -0.001), px=1.5),
    )


SPREAD = PlotSpec("spread", "spread round the centroid [m]", (
    Series("spread [m]", "spread", "rgb(40,160,80)", 2),
    Series("radius [m]", "radius", "rgb(120,120,120)", 1),
), twin="spread", aspect=2.4)


def panel(api: PanelAPI) -> KindPanel:
    return KindPanel(
        tabs=(Tab("Gather", (
            Slider("gather.speed", "speed [m/s]", 0.1, 5.0, 0.1, "walking speed towards the centroid"),
            Slider("gather.noise", "noise [m/s]", 0.0, 2.0, 0.05, "random velocity added each tick"),
            TRAIL_SLIDER,
            SPREAD,
        )),),
        status=lambda s, r, state: f"**{s.scenario.name}** · {state} · {s.progress()} · spread {r['spread']:.3g} m",
        compare=lambda s: {"slower (half the speed)": {"gather.speed": s.scenario.section("gather").speed / 2}},
    )


def refuse(scenario: Any) -> None:
    if scenario.section("gather") is None:
        raise PresetError(["gather: not a gathering scene"])


KIND = AppKind(name="gather", title="gathering swarm", engine="gather", refuse=refuse, make_driver=GatherDriver,
               notes="", layers=layers, camera=KeepSwarmInView, make_panel=panel)


def driver(session: Session) -> GatherDriver:
    assert isinstance(session.driver, GatherDriver)
    return session.driver
