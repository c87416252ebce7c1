"""Every shipped preset shows its point within its first 200 steps, as its description promises.

A lecture opens a preset and plays it: within about a minute (200 steps: 20 simulated seconds at
Δt = 0.1 s, 10–40 s of playback at the presets' rates) the scene must show what it is for: the
swarm's best or its distance to the source improves, layers are passed, the estimate error falls,
the robots keep moving. Each preset is run headless through the app's own ``Session`` (what the
status line and plots of the page read) and judged on the recorded metric rows, first row against
the row at the horizon. A new preset needs its promise here (``test_every_preset_has_a_point``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np
import pytest

from shoal.app.kinds.registry import session_for
from shoal.presets.io import list_presets, load
from shoal.presets.models import Scenario

HORIZON = 200  # steps (or the whole run when shorter)
Rows = dict[str, np.ndarray]


@dataclass(frozen=True)
class Point:
    """What the description promises, and how the metric rows show it."""

    promise: str
    shown: Callable[[Rows, Scenario], bool]
    reading: Callable[[Rows, Scenario], str]


def falls(column: str, by: float, *, share: bool = False) -> tuple[Callable, Callable]:
    """``column`` ends at least ``by`` below where it started (``share``: ``by`` of its start)."""
    def drop(m: Rows, sc: Scenario) -> float:
        return float(m[column][0] - m[column][-1])

    def shown(m: Rows, sc: Scenario) -> bool:
        need = by * abs(float(m[column][0])) if share else by
        return drop(m, sc) >= need

    return shown, lambda m, sc: f"{column}: {m[column][0]:.4g} → {m[column][-1]:.4g}"


def rises(column: str, by: float) -> tuple[Callable, Callable]:
    return (lambda m, sc: float(m[column][-1] - m[column][0]) >= by,
            lambda m, sc: f"{column}: {m[column][0]:.4g} → {m[column][-1]:.4g}")


def at_least(column: str, value: float) -> tuple[Callable, Callable]:
    return (lambda m, sc: float(m[column][-1]) >= value, lambda m, sc: f"{column} at the horizon: {m[column][-1]:.4g}")


def both(a: tuple[Callable, Callable], b: tuple[Callable, Callable]) -> tuple[Callable, Callable]:
    return (lambda m, sc: a[0](m, sc) and b[0](m, sc), lambda m, sc: f"{a[1](m, sc)}; {b[1](m, sc)}")


def escorting() -> tuple[Callable, Callable]:
    """The swarm keeps up with the source (CoM within r of it) and its mean distance to the source
    moves towards the ring r."""
    def shown(m: Rows, sc: Scenario) -> bool:
        r = float(sc.acoustics.r)
        d = m["mean_dist_to_source"]
        return float(m["com_dist"][-1]) < r and abs(float(d[-1]) - r) < abs(float(d[0]) - r)

    return shown, lambda m, sc: (f"r = {sc.acoustics.r:g} m, mean distance {m['mean_dist_to_source'][0]:.1f} → "
                                 f"{m['mean_dist_to_source'][-1]:.1f} m, CoM {m['com_dist'][-1]:.1f} m from it")


def losing() -> tuple[Callable, Callable]:
    """The swarm falls behind the moving source: its CoM ends outside the ring r and its mean
    distance to the source grows past r."""
    def shown(m: Rows, sc: Scenario) -> bool:
        r = float(sc.acoustics.r)
        return float(m["com_dist"][-1]) > r and float(m["mean_dist_to_source"][-1]) > r

    return shown, escorting()[1]


def keeps_moving() -> tuple[Callable, Callable]:
    """No collision, and the robots still move over the last 50 steps."""
    return (lambda m, sc: float(m["collided"][-1]) == 0 and float(np.min(m["mean_speed"][-50:])) >= 0.1,
            lambda m, sc: f"collided {m['collided'][-1]:g}, lowest mean speed of the last 50 steps "
                          f"{np.min(m['mean_speed'][-50:]):.3g} m/s")


def point(promise: str, check: tuple[Callable, Callable]) -> Point:
    return Point(promise, *check)


CLOSES_IN = "the swarm's best distance to the source falls"
DRIFTS = "f = x1 is maximised: the swarm drifts along +x"
THREADS = "the robots pass obstacle layers"
NEARS = "the swarm closes on the source (|CoM − source| falls)"

POINTS: dict[str, Point] = {
    "default": point(CLOSES_IN, falls("best_fitness", 0.25, share=True)),
    "smooth-tanh": point(CLOSES_IN + " (onto the source)", falls("best_fitness", 0.9, share=True)),
    "standard-pso": point(CLOSES_IN, falls("best_fitness", 0.25, share=True)),
    "slo-adapted": point(CLOSES_IN + " on estimated positions", falls("best_fitness", 0.25, share=True)),
    "rastrigin": point("the best f on the Rastrigin landscape falls", falls("best_fitness", 0.25, share=True)),
    **{name: point(DRIFTS, rises("best_fitness", 100.0))
       for name in ("fig3-4a", "fig3-4b", "fig3-4c", "fig3-4d", "fig3-5a", "fig3-5b", "fig3-5c")},
    "course-dvc": point(THREADS, at_least("layers_passed", 1)),
    "course-dvc-slo": point(THREADS + " on estimated positions", at_least("layers_passed", 1)),
    "course-nonomni": point(THREADS, at_least("layers_passed", 1)),
    "course-physics": point(THREADS, at_least("layers_passed", 1)),
    # constant coefficients (Table 4.1): the swarm advances, losing robots to contacts on its way, and by
    # 200 steps no layer is passed (Fig. 4-6: the constant cases trail DVC); its point is the contrast
    "course-adapted-c3-equal": point("the swarm advances into the course (CoM fitness [4.17] rises) while robots "
                                     "collide: compare with course-dvc",
                                     both(rises("com_fitness", 2.0), at_least("collided", 1))),
    "course-rpso": point("unbounded terms: robots head for the source and collide",
                         both(falls("best_fitness", 5.0), at_least("collided", 1))),
    "forest-dvc": point(CLOSES_IN + " through the trees", falls("best_fitness", 5.0)),
    "open-nonomni": point("they never settle and never collide", keeps_moving()),
    "sonar-gt-pso": point(NEARS, falls("com_dist", 20.0)),
    "sonar-x-pso": point(NEARS, falls("com_dist", 20.0)),
    "sonar-xb-pso": point(NEARS, falls("com_dist", 20.0)),
    "sonar-xb-pso-nonomni": point(NEARS, falls("com_dist", 20.0)),
    "sonar-xb-pso-slo": point(NEARS + " on estimated positions", falls("com_dist", 20.0)),
    "escort-stationary": point(NEARS + " to hold the ring", falls("com_dist", 20.0)),
    "escort-moving": point("the swarm keeps the ring r round the moving source", escorting()),
    # one receiver per algorithm (issue 23): with Chapter 7's (4 kHz, the sample lag) XB-PSO loses the
    # moving source as GT-PSO does; the refined one keeps it (test_the_refined_receiver_keeps_the_ring)
    "escort-xb-pso": point("with the Chapter 7 receiver the swarm loses the moving source, as GT-PSO does",
                           losing()),
    "slo-walk": point("the robots localise each other: the mean estimate error falls",
                      falls("e_abs_mean", 0.5, share=True)),
    "slo-pso-sphere": point("SPSO on Sphere from estimated positions: the best f falls",
                            falls("best_fitness", 0.9, share=True)),
}


def test_every_preset_has_a_point():
    assert sorted(POINTS) == sorted(list_presets())


@pytest.mark.parametrize("preset", sorted(POINTS))
def test_preset_shows_its_point_in_the_first_minute(preset):
    session = session_for(load(preset))
    start = session.snapshot().x.copy()
    n = min(HORIZON, session.scenario.sim.steps)
    assert session.step(n) == n
    rows = session.metric_arrays()
    moved = float(np.median(np.linalg.norm(session.snapshot().x - start, axis=-1)))
    assert moved > 0.0, f"{preset}: no robot moved in {n} steps"
    p = POINTS[preset]
    assert p.shown(rows, session.scenario), (
        f"{preset} does not show its point in its first {n} steps ({p.promise}): {p.reading(rows, session.scenario)}")


def test_the_refined_receiver_keeps_the_ring():
    """escort-xb-pso's description: with the refined lag peak at 48 kHz the swarm keeps contact."""
    session = session_for(load("escort-xb-pso", ["acoustics.lag_peak=parabolic", "acoustics.fs=48000.0"]))
    assert session.step(HORIZON) == HORIZON
    shown, reading = escorting()
    assert shown(session.metric_arrays(), session.scenario), reading(session.metric_arrays(), session.scenario)
