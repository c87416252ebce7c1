"""CompiledDraws against each run's own Generator calls, bit for bit: the draws (U(0,1) and
normal parts in any order), the ziggurat's rare slow paths, and the generators' states after."""

from __future__ import annotations

import numpy as np
import pytest

from shoal.engine.core.compiled_draws import CompiledDraws


def _gens(R, seed=0):
    return [np.random.Generator(np.random.PCG64(np.random.SeedSequence(seed, spawn_key=(r,)))) for r in range(R)]


def test_fills_are_the_generators_own_draws():
    """Many fills of varied sizes (zero included); the generators step on exactly as numpy's calls
    step them, so other draws can follow at any time."""
    R = 3
    draws, ref = CompiledDraws(_gens(R)), _gens(R)
    rng = np.random.default_rng(1)
    for _ in range(40):
        nu, nn, nv = int(rng.integers(0, 50)), int(rng.integers(0, 400)), int(rng.integers(0, 9))
        u, z, w = np.empty((R, nu)), np.empty((R, 2, nn)), np.empty((R, nv))
        draws.fill(u, z, w, normal=(False, True, False))
        for r, g in enumerate(ref):
            want_u, want_z, want_w = np.empty(nu), np.empty((2, nn)), np.empty(nv)
            g.random(out=want_u)
            g.standard_normal(out=want_z)
            g.random(out=want_w)
            np.testing.assert_array_equal(u[r], want_u)
            np.testing.assert_array_equal(z[r], want_z)
            np.testing.assert_array_equal(w[r], want_w)
        for a, b in zip(draws.rngs, ref):
            assert a.bit_generator.state == b.bit_generator.state
    assert [g.standard_normal() for g in draws.rngs] == [g.standard_normal() for g in ref]


def test_the_slow_paths_of_the_ziggurat():
    """A million normals cross the wedge and the tail paths (exp and log1p) often: still numpy's."""
    draws, ref = CompiledDraws(_gens(1, 7)), _gens(1, 7)
    z = np.empty((1, 1_000_000))
    draws.fill(z, normal=(True,))
    want = ref[0].standard_normal(1_000_000)
    np.testing.assert_array_equal(z[0], want)
    assert (np.abs(want) > 3.6541528853610088).any()  # the tail beyond the ziggurat's r was drawn


def test_a_strided_array_and_mixed_generators_are_refused():
    with pytest.raises(ValueError, match="C-contiguous"):
        CompiledDraws(_gens(2)).fill(np.empty((4, 2))[::2], np.empty((2, 3)), normal=(False, True))
    with pytest.raises(ValueError, match="one bit-generator kind"):
        CompiledDraws([np.random.Generator(np.random.PCG64(1)), np.random.Generator(np.random.MT19937(1))])
