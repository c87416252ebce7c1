"""What a scene kind plugs into the app: :class:`AppKind` (the registry entry) and
:class:`BaseDriver` (the defaults of a kind's :class:`~shoal.app.session.driver.Driver`)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable

from shoal.presets.errors import PresetError
from shoal.presets.kinds import kind_for
from shoal.presets.models import Scenario

from ..panel.spec import KindPanel, PanelAPI
from ..session.beliefs import Ghosts, host_ghosts
from ..session.driver import Driver
from ..session.history import Frame, frame_of
from ..session.session import Session
from ..view.layers import Layer
from ..view.view import Camera, Fit, View


@dataclass(frozen=True)
class AppKind:
    """One kind of scene: which scenarios it shows and the parts it brings."""

    name: str
    title: str  # in words, for messages
    engine: str  # the engine kind it shows (``presets.build.kind_of``: the name of a ``presets.kinds.KINDS`` entry)
    refuse: Callable[[Scenario], None]  # raises PresetError saying why a scenario is not this kind's
    make_driver: Callable[[Session], Driver]
    notes: str  # teaching notes ``static/notes/<notes>.md``
    layers: Callable[[KindPanel | None], tuple[Layer, ...]]  # the arena's layers (a drag goes to the panel part)
    camera: Callable[[], Camera]
    make_panel: Callable[[PanelAPI], KindPanel]

    def check(self, scenario: Scenario) -> Scenario:
        """``scenario`` if this kind shows it, else :class:`PresetError` saying why not."""
        self.refuse(scenario)
        return scenario

    def driver(self, session: Session) -> Driver:
        return self.make_driver(session)

    def session(self, scenario: Scenario) -> Session:
        """A new session of this kind (raises :class:`PresetError` if it cannot show ``scenario``)."""
        return Session(scenario, self)

    def panel(self, api: PanelAPI) -> KindPanel:
        """This kind's part of a tab's panel (built by the shared :class:`~shoal.app.panel.panel.Panel`)."""
        return self.make_panel(api)

    def view(self, scene: Any, part: KindPanel | None, fit: Fit | None = None) -> View:
        """The arena of a tab showing this kind on viser ``scene`` (``part``: where drags go; None on
        a page that only plays a run back)."""
        return View(scene, self.name, self.camera(), self.layers(part), fit)


class BaseDriver:
    """Defaults of a :class:`Driver`; a kind's driver fills in the rest.

    Which changes a running engine takes is its kind's one rule
    (:meth:`shoal.presets.kinds.SceneKind.live_keywords`, as ``Scene.retune`` follows it). The
    session owns two fields the rule would call a rebuild: ``sim.runs`` (a tab runs one) and
    ``sim.seed`` (the session restarts the running engine with a new seed), unless
    ``seed_rebuilds``."""

    scene_sections: tuple[str, ...] = ()
    seed_rebuilds = False  # a new seed builds a new engine (else the session restarts the running one)

    def __init__(self, session: Session) -> None:
        self.session = session

    @property
    def sim(self) -> Any:
        return self.session.sim

    def loaded(self) -> None:
        pass

    def rebuilds(self, old: Scenario, new: Scenario) -> bool:
        return self._keywords(old, new) is None

    def live(self, old: Scenario, new: Scenario) -> dict[str, Any]:
        keywords = self._keywords(old, new)
        if keywords is None:
            raise PresetError([f"{kind_for(old).label}: this change needs a new engine"])
        return keywords

    def _keywords(self, old: Scenario, new: Scenario) -> dict[str, Any] | None:
        owned = {"runs": old.sim.runs, **({} if self.seed_rebuilds else {"seed": old.sim.seed})}
        return kind_for(old).live_keywords(old, new.model_copy(update={"sim": new.sim.model_copy(update=owned)}))

    def cleared(self) -> None:
        pass

    def before_step(self) -> None:
        pass

    def dt(self) -> float:
        return float(self.sim.dt)

    def frame(self, t: float) -> Frame:
        return frame_of(self.sim.state, t, scene=self.scene())

    def scene(self) -> dict[str, Any]:
        """The parts of the scene that may change while the run goes on, as drawn now (none)."""
        return {}

    def metrics(self) -> dict[str, float]:
        return {}

    def recorded(self, frame: Frame) -> dict[str, Any]:
        return {}

    def export_extra(self) -> dict[str, Any]:
        return {}

    def kept(self, scenario: Scenario) -> Scenario:
        return scenario

    def ghosts(self, selected: int, true_best: Any) -> Ghosts | None:
        """The selected robot's beliefs when the swarm acts on SLO-estimated positions."""
        return host_ghosts(self.sim, selected, true_best)
