"""CompiledDraws against each run's own Generator calls, bit for bit: the draws (U(0,1) and
normal parts in any order), the ziggurat's rare slow paths, and the generators' states after."""

from __future__ import annotations

import copy
import pickle

import numpy as np
import pytest

from shoal.engine.core.compiled_draws import CompiledDraws
from shoal.engine.kinds.slo_swarm import SLOSwarm


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


def test_a_strided_array_and_other_bit_generators_are_refused():
    with pytest.raises(ValueError, match="C-contiguous"):
        CompiledDraws(_gens(2)).fill(np.empty((4, 2))[::2], np.empty((2, 3)), normal=(False, True))
    with pytest.raises(ValueError, match="PCG64"):  # MT19937 makes its doubles from two 32-bit outputs
        CompiledDraws([np.random.Generator(np.random.PCG64(1)), np.random.Generator(np.random.MT19937(1))])


def test_a_copied_or_unpickled_swarm_draws_from_its_own_generators():
    """The C state addresses are the generators' own: a deep copy or an unpickled SLO swarm goes on
    exactly as the original, and leaves the original's streams alone."""
    a = SLOSwarm(runs=2, seed=3, particles=6, errors="high")
    a.step()
    for b in (copy.deepcopy(a), pickle.loads(pickle.dumps(a))):
        before = [g.bit_generator.state for g in a.streams["range"]]
        for _ in range(3):
            b.step()
        assert [g.bit_generator.state for g in a.streams["range"]] == before
    for _ in range(3):
        a.step()
    np.testing.assert_array_equal(a.state.est, b.state.est)
    np.testing.assert_array_equal(a.state.x, b.state.x)
