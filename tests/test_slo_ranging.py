"""Neighbour-only SLO ranging (``slo.ranging = "neighbours"``, ``engine/slo/ranging.py``) against
the thesis' all-pairs step: the neighbour lists to the bit, the estimates to the bit without
error, in distribution with error; O(N·k) memory; refused settings name the field."""

from __future__ import annotations

import tracemalloc

import numpy as np
import pytest
from scipy import stats

from shoal.engine.kinds.slo_swarm import SLOSwarm
from shoal.engine.slo import kernels as slo_kernels
from shoal.engine.slo import neighbour_kernels, ranging
from shoal.engine.slo.neighbourhoods import Neighbourhood, knn, radius, ring
from shoal.presets.build import build
from shoal.presets.io import load


def _dense(nb: np.ndarray, n: int) -> np.ndarray:
    R = nb.shape[0]
    adj = np.zeros((R, n, n), bool)
    r, i, s = np.nonzero(nb >= 0)
    adj[r, i, nb[r, i, s]] = True
    return adj


def _positions(kind: str, rng: np.random.Generator, n: int) -> np.ndarray:
    if kind == "uniform":
        return rng.uniform(-50, 50, (3, n, 2))
    if kind == "clustered":  # a converged swarm with a few far away
        x = rng.normal(0.0, 1e-3, (3, n, 2))
        x[:, :3] = rng.uniform(-1e3, 1e3, (3, min(n, 3), 2))
        return x
    if kind == "lattice":  # exact ties everywhere
        side = int(np.ceil(np.sqrt(n)))
        g = np.stack(np.meshgrid(np.arange(side), np.arange(side)), -1).reshape(-1, 2)[:n].astype(float)
        return np.stack([g, g * 0.5, g[::-1]])
    x = rng.uniform(-5, 5, (3, n, 2))  # coincident robots and one that is not finite
    x[:, 5:9] = x[:, min(4, n - 1), None]
    x[1, min(2, n - 1)] = np.nan
    x[2, min(3, n - 1)] = np.inf
    return x


@pytest.mark.parametrize("kind", ["uniform", "clustered", "lattice", "degenerate"])
def test_the_neighbour_lists_are_the_dense_neighbourhoods(kind):
    rng = np.random.default_rng(7)
    for n in (2, 9, 60, 400):
        x = _positions(kind, rng, n)
        dist = slo_kernels.distances(np.ascontiguousarray(x))
        for k in (1, 5, 12):
            nb = neighbour_kernels.knn_slots(x, k)
            assert np.array_equal(_dense(nb, n), knn(dist, k)), (n, k)
            assert (np.diff(np.where(nb >= 0, nb, n + 1), axis=-1) > 0).all()  # ascending, then empty
        for r in (0.0, 0.7, 3.0, 25.0):
            assert np.array_equal(_dense(neighbour_kernels.radius_slots(x, r), n), radius(dist, r)), (n, r)
        for width in (1, 2, 5):
            assert np.array_equal(_dense(neighbour_kernels.ring_slots(3, n, width), n), ring(3, n, width))


def _zero_error(**kw):
    return dict(errors="none", initial_estimates="truth", runs=2, seed=3, particles=24) | kw


STATE = ("x", "u", "P", "fP", "f", "heading")


@pytest.mark.parametrize("rule", [dict(neighbourhood="knn"), dict(neighbourhood="radius", neighbourhood_param=20.0),
                                  dict(neighbourhood="ring", neighbourhood_param=2),
                                  dict(neighbourhood="knn", local_best="pbest", entry_policy="stale")])
def test_without_error_a_pso_run_is_the_all_pairs_run_to_the_bit(rule):
    """With a memory for every robot nobody is forgotten: the whole run is the thesis' one."""
    a = SLOSwarm(**_zero_error(**rule))
    b = SLOSwarm(**_zero_error(**rule), ranging="neighbours", memory=23)
    for t in range(60):
        ia, ib = a.step(), b.step()
        for name in STATE:
            assert getattr(a.state, name).tobytes() == getattr(b.state, name).tobytes(), (t, name)
        adj = a.state.adjacency
        assert np.array_equal(adj, b.state.adjacency), t
        assert a.state.est[adj].tobytes() == b.state.est[adj].tobytes(), t
        assert a.state.kind[adj].tobytes() == b.state.kind[adj].tobytes(), t
        assert ia.best_so_far.tobytes() == ib.best_so_far.tobytes()
        assert np.array_equal(ia.e_abs["median"], ib.e_abs["median"]), t  # the same pairs' values


def test_without_error_every_pair_that_never_left_has_the_all_pairs_bits_with_the_default_memory():
    kw = _zero_error(motion="random_walk", particles=40)
    a, b = SLOSwarm(**kw), SLOSwarm(**kw, ranging="neighbours")
    assert b.localiser.memory == 20  # 4 × knn's 5
    gone = np.zeros((2, 40, 40), bool)
    checked = 0
    prev = a.state.adjacency
    for t in range(50):
        a.step(), b.step()
        adj = a.state.adjacency
        assert np.array_equal(adj, b.state.adjacency)
        gone |= prev & ~adj
        prev = adj
        same = adj & ~gone
        assert a.state.est[same].tobytes() == b.state.est[same].tobytes(), t
        checked += int(same.sum())
    assert checked > 2000 and gone.sum() > 100  # robots came and went


def _e_abs(info) -> np.ndarray:
    values = info._values("e_abs")
    return values[np.isfinite(values)]


@pytest.mark.parametrize("motion, memory", [("random_walk", None), ("pso", 29)])
def test_with_error_the_estimates_agree_in_distribution(motion, memory):
    """Low errors: the neighbour pairs' absolute errors after 60 generations, 16 runs of 30, pooled,
    in the two modes (other draws, the same laws). Tolerance: a two-sample Kolmogorov–Smirnov
    statistic below 0.06 and p above 0.01 (about 2,400 pairs a side)."""
    kw = dict(runs=16, seed=5, particles=30, motion=motion, errors="low")
    a, b = SLOSwarm(**kw), SLOSwarm(**kw, ranging="neighbours", memory=memory)
    for _ in range(60):
        ia, ib = a.step(), b.step()
    ea, eb = _e_abs(ia), _e_abs(ib)
    assert ea.size == eb.size == 16 * 30 * 5
    test = stats.ks_2samp(ea, eb)
    assert test.statistic < 0.06 and test.pvalue > 0.01, (test, np.median(ea), np.median(eb))
    assert not np.array_equal(ea, eb)  # other draws indeed


def test_local_best_on_slots_is_the_dense_local_best():
    b = SLOSwarm(runs=3, seed=2, particles=30, ranging="neighbours", errors="low")
    for _ in range(5):
        b.step()
    s = b.state
    rng = np.random.default_rng(1)
    f = rng.normal(size=(3, 30))
    f[0, 4], f[1, :3], f[2, 7] = np.nan, np.inf, f[2, 8]  # NaN, infinite and tied fitness
    fP = np.where(rng.random((3, 30)) < 0.5, f + 0.1, f - 0.1)
    for pbest in (False, True):
        want = slo_kernels.local_best(f, fP, s.P, s.adjacency, s.est, pbest)
        got = ranging.local_best(f, fP, s.P, s.beliefs, pbest)
        for w, g in zip(want, got):
            assert np.asarray(w).tobytes() == np.asarray(g).tobytes()


def test_a_generation_of_many_particles_holds_no_pair_matrix():
    """3,000 particles: every pair would be 9 million estimates (over 200 MB); a generation here
    allocates a few megabytes."""
    sw = SLOSwarm(runs=1, seed=1, particles=3000, ranging="neighbours")
    sw.step()
    tracemalloc.start()
    info = sw.step()
    read = (info.e_abs, info.e_ang, info.dead_reckoning)  # the neighbour pairs' metrics too
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    assert peak < 20 * 2**20, f"{peak / 2**20:.1f} MiB"
    assert np.isfinite(read[0]["median"]).all() and np.isfinite(read[2]).all()


@pytest.mark.parametrize("override, words", [
    ("slo.selection=rts", "selection 'rts'"),
    ("slo.neighbourhood=full", "full neighbourhood"),
    ("slo.entry_policy=dead_reckoning", "carries every pair"),
    ("slo.swarm=host", "host swarm ranges all"),
])
def test_a_preset_asking_for_what_neighbour_ranging_cannot_do_is_refused_by_name(override, words):
    with pytest.raises(ValueError, match="ranging") as err:
        load("slo-pso-sphere", ["slo.ranging=neighbours", override])
    assert words in str(err.value)


def test_the_preset_field_builds_a_neighbour_ranging_swarm_and_defaults_to_all_pairs():
    assert load("slo-pso-sphere").slo.ranging is None  # unset: every pair, and dumps as before
    assert "ranging" not in load("slo-pso-sphere").model_dump()["slo"]
    assert build(load("slo-pso-sphere"), runs=1).config.ranging == "all"
    sw = build(load("slo-pso-sphere", ["slo.ranging=neighbours", "sim.robots=50"]), runs=2)
    assert isinstance(sw, SLOSwarm) and sw.config.ranging == "neighbours"
    sw.step()
    assert isinstance(sw.state.beliefs, ranging.SlotBeliefs) and sw.state.beliefs.nb.shape == (2, 50, 5)
    with pytest.raises(ValueError, match="ranging"):
        SLOSwarm(ranging="some")
    with pytest.raises(ValueError, match="neighbourhood"):
        ranging.neighbour_slots(Neighbourhood("full"), np.zeros((1, 3, 2)))


def test_a_snapshot_of_a_neighbour_ranging_scene_goes_on_with_the_same_bits():
    import shoal

    original = shoal.make("slo-pso-sphere", ["slo.ranging=neighbours", "sim.robots=40", "slo.errors=high"], runs=2,
                          seed=11)
    original.run(6)
    copy = shoal.make(snapshot=original.snapshot().to_bytes())
    for scene in (original, copy):
        scene.run(25)
    a, b = original.engine.state, copy.engine.state
    for name in ("x", "u", "P", "fP"):
        assert getattr(a, name).tobytes() == getattr(b, name).tobytes(), name
    assert a.beliefs.slot_est.tobytes() == b.beliefs.slot_est.tobytes()
    assert a.beliefs.memory[1].tobytes() == b.beliefs.memory[1].tobytes()
