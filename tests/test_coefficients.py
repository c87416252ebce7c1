"""Coefficients checked where they live: a Chapter 3 law carries its own coefficient rule
(``VelocityLaw.check``), and the preset model, the engine (so ``make`` and ``Scene.retune``) and
the app apply it through that one function; a diverging swarm's readout says "diverged" and never
prints its runaway numbers."""

from __future__ import annotations

import dataclasses
import re

import numpy as np
import pytest

import shoal
from shoal.app.kinds import swarm as app_swarm
from shoal.app.kinds.registry import session_for
from shoal.engine.kinds.swarm import Simulation
from shoal.engine.pso.coeffs import Constant
from shoal.engine.pso.laws import LAWS, Law, VelocityLaw
from shoal.engine.pso.stability import diverged
from shoal.presets.io import PresetError, load


@pytest.fixture
def narrow_law():
    """A plug-in law whose rule is 0 <= ω < 0.5 (the standard velocity, its own rule)."""
    law = dataclasses.replace(LAWS["adapted-sgn"], name="narrow", label="Narrow PSO", omega_range=(0.0, 0.5),
                              rule="0 <= omega < 0.5 (ours)")
    LAWS.register(law)
    yield law
    LAWS.unregister("narrow")


RAW = {"law": "narrow", "mode": "raw", "omega": 0.3, "c1": 0.5, "c2": 0.5}


def test_the_rule_is_the_laws_and_every_path_applies_it(narrow_law, monkeypatch):
    calls = []
    original = VelocityLaw.check
    monkeypatch.setattr(VelocityLaw, "check", lambda self, w, c: calls.append(self.name) or original(self, w, c))
    with pytest.raises(PresetError, match=r"omega = 0.7: Narrow PSO needs 0 <= omega < 0.5 \(ours\)"):
        shoal.make("default", controller={**RAW, "omega": 0.7})  # make → the model
    scene = shoal.make("default", controller=RAW)
    with pytest.raises(ValueError, match="policy: omega = 0.9: Narrow PSO needs"):
        scene.retune(policy=Constant(0.9, (0.5, 0.5)))  # Scene.retune's engine keywords → the engine
    assert scene.engine.policy == Constant(0.3, (0.5, 0.5))  # refused: nothing changed
    with pytest.raises(ValueError, match="policy: omega = 0.6"):
        Simulation(robots=3, law=Law("narrow"), policy=Constant(0.6, (0.5, 0.5)))
    session = session_for(load("default", [f"controller.{k}={v}" for k, v in RAW.items()]))
    with pytest.raises(PresetError, match="Narrow PSO needs 0 <= omega < 0.5"):
        session.apply({"controller.omega": 0.8})  # the app → the model
    assert session.scenario.controller.omega == 0.3
    assert calls.count("narrow") >= 4


def test_switching_the_law_checks_the_coefficients_in_force():
    sim = Simulation(robots=3, law=Law("standard"), policy=Constant(1.1, (0.5, 0.5)))  # standard PSO: no ω rule
    with pytest.raises(ValueError, match=r"policy: omega = 1.1: Adapted PSO \(sgn\) needs 0 <= omega < 1 \[3.14\]"):
        sim.retune(law=Law("adapted-sgn"))
    assert sim.law == Law("standard")


@pytest.mark.parametrize("c", [(-0.5, 0.5), (np.nan, 0.5), (np.inf, 0.1)])
def test_coefficients_are_finite_and_not_negative(c):
    with pytest.raises(ValueError, match="needs finite coefficients c_n >= 0"):
        Simulation(robots=3, policy=Constant(0.5, c))


def test_a_diverging_swarm_reads_diverged():
    """Standard PSO at ω = 1.2, ĉ = 4 (outside its stable region [3.9]) on f = x₁: |u| passes 10³³."""
    scenario = load("fig3-4a", ["controller.law=standard", "controller.mode=raw", "controller.omega=1.2",
                                "controller.c1=2.0", "controller.c2=2.0", "sim.runs=1"])
    session = session_for(scenario)
    for _ in range(420):
        session.sim.step()
    assert diverged(session.sim.state.u).all() and np.abs(session.sim.state.best_fitness).max() > 1e30
    readout = session.readout()
    status = app_swarm._status(session, readout, "playing")
    table = app_swarm._readout(session)
    for text in (status, table):
        assert "diverged" in text
        assert not re.search(r"e\+?[1-9]\d", text), text  # no 1e33 (nor 1e+33) anywhere
    assert "best f" not in status


def test_a_stable_swarm_does_not_read_diverged():
    session = session_for(load("default"))
    for _ in range(30):
        session.sim.step()
    assert not diverged(session.sim.state.u).any()
    assert "diverged" not in app_swarm._status(session, session.readout(), "playing")
