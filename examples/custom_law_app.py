"""A velocity law of your own, in the browser app: register it from Python, then serve. The
Chapter 3 panel's law dropdown lists it, its readout uses its label and the presets accept its
name (a package does the same through an entry point: see examples/plugin).

    python examples/custom_law_app.py --serve     # then open http://127.0.0.1:8080
    python examples/custom_law_app.py             # check it and exit (what the test suite runs)
"""

from __future__ import annotations

import sys

import numpy as np

import shoal
from shoal.engine.pso.laws import VelocityLaw, standard_velocity


def inertia_free(u: np.ndarray, g: np.ndarray, c: np.ndarray, omega: np.ndarray | float, r: np.ndarray,
                 width: float) -> np.ndarray:
    """Standard PSO [2.1] without memory of the last velocity (ω ignored): each step only pulls."""
    return standard_velocity(np.zeros_like(u), g, c, 0.0, r)


LAW = VelocityLaw("inertia-free", "Inertia-free PSO", adapted=False, velocity=inertia_free, region="order-2")


def main(serve: bool) -> int:
    shoal.register(LAW)
    from shoal.app.kinds.registry import session_for
    from shoal.presets.io import load

    scenario = load("default", ["controller.law=inertia-free", "controller.mode=raw"])
    session = session_for(scenario)
    session.play()
    session.step(10)
    print(f"{LAW.label} in the app: step {session.sim.state.k}, best f = {session.sim.state.best_fitness[0]:.4g}")
    if serve:
        from shoal.app.server import serve as serve_app

        serve_app(preset="default")
    return 0


if __name__ == "__main__":
    sys.exit(main("--serve" in sys.argv[1:]))
