"""How fast a shipped scene first plays in the app: slow enough that its run does not end before
anyone has looked.

The figure presets of Chapter 3 (Figs. 3-4a, b and 3-5) run 100 steps at the default 20
steps/s: five seconds, over before a hall has found the plot. The app opens a shipped preset at
most at ``sim.steps / FIRST_RUN_SECONDS`` steps per second (the speed slider shows it and a
student may raise it); a run is numbers per step, so its numbers do not change. An uploaded
preset and a lesson's scene keep their own speed.
"""

from __future__ import annotations

from shoal.presets.models import Scenario

FIRST_RUN_SECONDS = 20.0  # a shipped scene's run lasts at least this long at the speed it opens with


def paced(scenario: Scenario) -> Scenario:
    """``scenario`` played so that its ``sim.steps`` last at least :data:`FIRST_RUN_SECONDS`."""
    most = scenario.sim.steps / FIRST_RUN_SECONDS
    if scenario.view.steps_per_second <= most:
        return scenario
    speed = max(1.0, float(round(most)))
    return scenario.model_copy(update={"view": scenario.view.model_copy(update={"steps_per_second": speed})})
