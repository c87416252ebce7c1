"""SLO scenes in a real headless Chromium: switching to slo-walk through the preset dropdown
draws the ghost overlay of the observer robot, and the oracle/SLO switch of a Positions
folder changes the engine that runs, in the Chapter 3 scene (slo-adapted, whose controller
still changes live) and in a fleet scene. One server and one page for the module; tests run
in file order."""

from __future__ import annotations

import shutil

import numpy as np
import pytest

CHROMIUM = shutil.which("chromium")
pytestmark = [
    pytest.mark.browser,
    pytest.mark.skipif(CHROMIUM is None, reason="Debian's chromium is not on PATH (apt-get install chromium)"),
]

sync_api = pytest.importorskip("playwright.sync_api")

from shoal.app.kinds import swarm  # noqa: E402
from shoal.engine.kinds.fleet import Fleet  # noqa: E402
from shoal.engine.kinds.slo_swarm import SLOSwarm  # noqa: E402

from browser_helpers import choose, dismiss_toasts, number_box, open_folder, wait_until  # noqa: E402


def test_the_dropdown_switches_to_slo_walk_and_the_ghosts_are_drawn(server, page, cid):
    dismiss_toasts(page)
    choose(page, "preset", "slo-walk")
    wait_until(lambda: server.tabs[cid].session.kind.name == "mai", what="an SLO session")
    page.wait_for_selector("label:has-text('selection')", timeout=20000)
    tab = server.tabs[cid]
    session = tab.session
    assert isinstance(session.sim, SLOSwarm)
    page.get_by_role("button", name="Step", exact=True).click()
    wait_until(lambda: session.sim.state.k >= 1, what="a step")
    wait_until(lambda: tab.arena.drawn_revision == session.revision, what="the overlay redrawn")
    st = session.sim.state
    i = session.selected_robot
    j = np.flatnonzero(st.valid[0, i])
    ghosts = np.asarray(tab.arena.nodes["ghosts"].points, dtype=float)[:, :2] / tab.arena.scale + tab.arena.centre
    np.testing.assert_allclose(ghosts, st.x[0, i] + st.est[0, i, j], atol=1e-4)
    assert tab.arena.nodes["ghosts"].visible and len(j) >= 1


def test_the_chapter3_positions_switch_and_controller_in_the_gui(server, page, cid):
    dismiss_toasts(page)
    choose(page, "preset", "slo-adapted")
    wait_until(lambda: server.tabs[cid].session.kind.name == "swarm", what="the Chapter 3 scene")
    session = server.tabs[cid].session
    assert not session.sim.positions.exact
    page.get_by_role("tab", name="Controller", exact=True).click()
    sim = session.sim
    box = number_box(page, "U [m/s]")  # physical mode: A+ = 30, Δt = 0.1, so ω = 1 − 3/U
    box.fill("4")
    box.press("Enter")
    wait_until(lambda: session.scenario.controller.U == 4.0, what="U = 4")
    assert session.sim is sim and swarm.driver(session).coefficients()[0] == pytest.approx(0.25)  # no rebuild
    open_folder(page, "Positions", "error set")  # the Positions folder starts closed (the controls fit)
    choose(page, "positions", "oracle (true)")
    wait_until(lambda: session.sim.positions.exact, what="the oracle swarm")
    assert server.tabs[cid].session is session and session.scenario.controller.U == 4.0
    choose(page, "positions", "SLO (estimated)")
    wait_until(lambda: not session.sim.positions.exact, what="SLO positions again")
    page.get_by_role("button", name="Step", exact=True).click()
    wait_until(lambda: session.sim.state.k >= 1 and server.tabs[cid].arena.drawn_revision == session.revision,
               what="a step drawn")
    assert server.tabs[cid].arena.nodes["ghosts"].visible


def test_the_positions_switch_of_a_fleet_scene_changes_the_engine(server, page, cid):
    dismiss_toasts(page)
    choose(page, "preset", "course-dvc")
    wait_until(lambda: server.tabs[cid].session.kind.name == "fleet", what="a fleet session")
    session = server.tabs[cid].session
    assert type(session.sim) is Fleet and session.sim.positions.exact
    page.get_by_text("Positions", exact=True).click()  # the folder starts closed on true positions
    choose(page, "positions", "SLO (estimated)")
    wait_until(lambda: isinstance(session.sim, Fleet) and not session.sim.positions.exact,
               what="the fleet on SLO positions")
    assert server.tabs[cid].session is session  # the fleet view stays
    page.get_by_role("button", name="Step", exact=True).click()
    wait_until(lambda: session.sim.state.k >= 1 and server.tabs[cid].arena.drawn_revision == session.revision,
               what="a step drawn")
    assert server.tabs[cid].arena.nodes["ghosts"].visible
    choose(page, "positions", "oracle (true)")
    wait_until(lambda: session.sim.positions.exact, what="the fleet on true positions")
