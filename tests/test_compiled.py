"""While kernels compile in the background, a kernel not compiled yet runs as Python in every
other thread (``engine/core/compiled.py:defer``): the same bits as compiled, for every SLO
preset (whose kernels have no numpy tick) and for the draws (their generators' own calls then).

Each comparison runs in a fresh interpreter, where no kernel is compiled yet (the disk cache is
read at a kernel's first compiled call), so the deferred run really is Python."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from shoal.app.warmup import group_of
from shoal.presets.io import list_presets, load

SLO = [p for p in list_presets() if group_of(load(p)) == "slo"]

BOTH_WAYS = r"""
import hashlib, json, sys
import numpy as np
from shoal.engine.core import compiled
from shoal.engine.slo import kernels
from shoal.presets.build import build
from shoal.presets.io import load

def run(preset):
    sim = build(load(preset, ["sim.runs=2", "sim.seed=3"]))
    h = hashlib.sha256()
    for _ in range(25):
        info = sim.step()
        for part in (sim.state.x, sim.state.heading, *(np.asarray(v) for _, v in sorted(info.columns().items()))):
            h.update(np.ascontiguousarray(part, dtype=float).tobytes())
    return h.hexdigest()

out = {}
for preset in sys.argv[1:]:
    compiled.defer(True)
    python = run(preset)
    out[preset] = {"python": python, "compiled_before": len(kernels._pairs.overloads)}
    compiled.defer(False)
    out[preset]["numba"] = run(preset)
    out[preset]["compiled_after"] = len(kernels._pairs.overloads)
print(json.dumps(out))
"""


def test_every_slo_preset_gives_the_same_bits_with_its_kernels_as_python_and_compiled():
    done = subprocess.run([sys.executable, "-c", BOTH_WAYS, *SLO], capture_output=True, text=True, timeout=900)
    assert done.returncode == 0, done.stderr[-3000:]
    got = json.loads(done.stdout.strip().splitlines()[-1])
    assert set(got) == set(SLO) and "slo-walk" in got
    first = got[SLO[0]]
    assert first["compiled_before"] == 0 and first["compiled_after"] >= 1  # really Python, then really compiled
    for preset, r in got.items():
        assert r["python"] == r["numba"], preset


def test_the_thread_that_compiles_compiles_and_a_compiled_kernel_is_called_compiled():
    from shoal.engine.core import compiled

    @compiled.kernel
    def twice(x: float) -> float:
        return 2.0 * x

    compiled.defer(True)
    try:
        assert compiled.interpreted(twice) and twice(2.0) == 4.0 and not twice.overloads
        compiled.compile_here()  # (this thread compiles from now on)
        assert not compiled.interpreted(twice) and twice(3.0) == 6.0 and twice.overloads
    finally:
        compiled.defer(False)
        compiled._here.compiles = False
    assert not compiled.interpreted(twice)


@pytest.mark.parametrize("normal", [False, True])
def test_draws_made_as_python_are_the_generators_own(normal):
    import numpy as np

    from shoal.engine.core import compiled
    from shoal.engine.core.compiled_draws import CompiledDraws

    rngs = [np.random.default_rng(s) for s in (1, 2)]
    ref = [np.random.default_rng(s) for s in (1, 2)]
    a, b = np.zeros((2, 5)), np.zeros((2, 3))
    compiled.defer(True)
    try:
        if not compiled.interpreted(__import__("shoal.engine.core.compiled_draws", fromlist=["_fill"])._fill):
            pytest.skip("the draws are compiled in this process already")
        CompiledDraws(rngs).fill(a, b, normal=[normal, not normal])
    finally:
        compiled.defer(False)
    for r, g in enumerate(ref):
        want_a = g.standard_normal(5) if normal else g.random(5)
        want_b = g.random(3) if normal else g.standard_normal(3)
        assert np.array_equal(a[r], want_a) and np.array_equal(b[r], want_b)
    assert all(x.bit_generator.state == y.bit_generator.state for x, y in zip(rngs, ref))
