"""RawDraws against each run's own Generator calls, bit for bit: the draws, the ziggurat's rare
slow paths, blocks running out in the middle of a normal, and the generators' states after
settling."""

from __future__ import annotations

import numpy as np
import pytest

from shoal.engine.core.raw_draws import RawDraws


def _gens(R, seed=0):
    return [np.random.Generator(np.random.PCG64(np.random.SeedSequence(seed, spawn_key=(r,)))) for r in range(R)]


@pytest.mark.parametrize("block", [7, 100, 5000])
def test_fills_are_the_generators_own_draws(block):
    """Many fills of varied sizes (zero included), with a block small enough to run out inside a
    fill, inside a normal's slow path, and large enough to span many fills."""
    R = 3
    raw, ref = RawDraws(_gens(R), block), _gens(R)
    rng = np.random.default_rng(1)
    for _ in range(40):
        nu, nn, nv = int(rng.integers(0, 50)), int(rng.integers(0, 400)), int(rng.integers(0, 9))
        u, z, w = np.empty((R, nu)), np.empty((R, 2, nn)), np.empty((R, nv))
        raw.fill(u, z, w, normal=(False, True, False))
        for r, g in enumerate(ref):
            want_u, want_z, want_w = np.empty(nu), np.empty((2, nn)), np.empty(nv)
            g.random(out=want_u)
            g.standard_normal(out=want_z)
            g.random(out=want_w)
            np.testing.assert_array_equal(u[r], want_u)
            np.testing.assert_array_equal(z[r], want_z)
            np.testing.assert_array_equal(w[r], want_w)
    raw.settle()
    for a, b in zip(raw.rngs, ref):
        assert a.bit_generator.state == b.bit_generator.state
        assert a.standard_normal(5).tolist() == b.standard_normal(5).tolist()


def test_the_slow_paths_of_the_ziggurat():
    """A million normals cross the wedge and the tail paths (exp and log1p) often: still numpy's."""
    raw, ref = RawDraws(_gens(1, 7), 1 << 16), _gens(1, 7)
    z = np.empty((1, 1_000_000))
    raw.fill(z, normal=(True,))
    want = ref[0].standard_normal(1_000_000)
    np.testing.assert_array_equal(z[0], want)
    assert (np.abs(want) > 3.6541528853610088).any()  # the tail beyond the ziggurat's r was drawn


def test_a_strided_array_is_refused():
    raw = RawDraws(_gens(2), 64)
    with pytest.raises(ValueError, match="C-contiguous"):
        raw.fill(np.empty((4, 2))[::2], np.empty((2, 3)), normal=(False, True))
