"""Every kind of app session keeps a bounded history, so a tab left playing for hours holds
a constant amount of memory (``benchmarks/bench_memory.py`` measures the hour)."""

import pytest

from shoal.app.kinds.registry import kind_for
from shoal.presets import io as presets_io
from shoal.testing import example_presets


@pytest.mark.parametrize("preset", list(example_presets().values()))  # every registered kind
def test_history_and_metrics_stay_capped_while_playing(preset):
    scenario = presets_io.load(preset, ["sim.steps=100000"])
    s = kind_for(scenario).session(scenario)
    s.history.max_steps, s.history.max_metrics = 30, 40
    for _ in range(3):
        s.step(40)
        assert len(s.frames) <= 30 and len(s.history.metrics) <= 40
    assert len(s.frames) == 30 and len(s.history.metrics) == 40 and s.sim.state.k == 120
    assert s.frames[-1].k == 120  # the newest steps are the ones kept
    assert s.metric_arrays()["t"].shape == (40,)
