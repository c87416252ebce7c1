"""SLO neighbourhoods (Mai §3.4): degrees, symmetry and tie rules."""

from __future__ import annotations

import numpy as np
import pytest

from shoal.engine.slo.neighbourhoods import Neighbourhood, distances

R, N = 3, 20


@pytest.fixture
def x() -> np.ndarray:
    return np.random.default_rng(1).uniform(0, 100, (R, N, 2))


def test_no_one_is_its_own_neighbour(x):
    rngs = [np.random.default_rng(i) for i in range(R)]
    for kind, p in [("knn", 5), ("radius", 30.0), ("full", None), ("random", 0.5), ("ring", 3)]:
        adj = Neighbourhood(kind, p).adjacency(x, rngs)
        assert adj.shape == (R, N, N) and adj.dtype == bool
        assert not adj[:, np.arange(N), np.arange(N)].any()


def test_full_and_ring_degrees(x):
    assert np.all(Neighbourhood("full").adjacency(x).sum(axis=2) == N - 1)
    for n in (1, 2, 3, 5):
        adj = Neighbourhood("ring", n).adjacency(x)
        assert np.all(adj.sum(axis=2) == 2 * n) and np.array_equal(adj, np.swapaxes(adj, 1, 2))
        assert adj[0, 0, N - 1] and adj[0, 0, n] and not adj[0, 0, n + 1]


def test_knn_picks_the_k_closest(x):
    adj = Neighbourhood("knn", 5).adjacency(x)
    assert np.all(adj.sum(axis=2) == 5)
    d = distances(x)
    worst_in = np.where(adj, d, -np.inf).max(axis=2)
    best_out = np.where(~adj & np.isfinite(d), d, np.inf).min(axis=2)
    assert np.all(worst_in <= best_out)
    assert Neighbourhood("knn", 50).adjacency(x).sum(axis=2).max() == N - 1


def test_knn_ties_break_by_index():
    x = np.zeros((1, 5, 2))
    x[0, :, 0] = [0.0, 1.0, -1.0, 2.0, -2.0]  # 1 and 2 are equally close to 0
    adj = Neighbourhood("knn", 1).adjacency(x)
    assert adj[0, 0].tolist() == [False, True, False, False, False]


def test_radius_is_symmetric_and_strict(x):
    adj = Neighbourhood("radius", 25.0).adjacency(x)
    d = distances(x)
    assert np.array_equal(adj, d < 25.0) and np.array_equal(adj, np.swapaxes(adj, 1, 2))


def test_random_links_are_symmetric_with_probability_p(x):
    rngs = [np.random.default_rng(i) for i in range(R)]
    rule = Neighbourhood("random", 0.3)
    a, b = rule.adjacency(x, rngs), rule.adjacency(x, rngs)
    assert np.array_equal(a, np.swapaxes(a, 1, 2))
    assert not np.array_equal(a, b)  # redrawn every step
    degrees = np.stack([rule.adjacency(x, rngs) for _ in range(30)]).sum(axis=3)
    assert degrees.mean() == pytest.approx(0.3 * (N - 1), rel=0.05)
    with pytest.raises(ValueError):
        rule.adjacency(x)


def test_default_parameters():
    assert Neighbourhood("knn").value == 5 and Neighbourhood("radius").value == 25.0
    assert Neighbourhood("random").value == 0.5 and Neighbourhood("ring").value == 2


def test_only_a_radius_scales_with_the_arena():
    from shoal.engine.slo.neighbourhoods import Neighbourhood

    assert Neighbourhood("radius", 25.0).scaled(2.0) == Neighbourhood("radius", 50.0)
    assert Neighbourhood("radius").scaled(0.5).value == Neighbourhood("radius").value * 0.5
    assert Neighbourhood("knn", 5).scaled(3.0) == Neighbourhood("knn", 5)
