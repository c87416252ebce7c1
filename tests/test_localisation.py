"""Source-localisation strategies on hand-built geometries (Rossides §7.1–§8.1, pp. 148–174;
docs/readings.md)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from shoal.engine.acoustics.escort import escort_gap, moving_source, with_escort
from shoal.engine.acoustics.forgetting import centroid_of, forget_update
from shoal.engine.acoustics.intersections import PAIRS_I, PAIRS_J, cross2, intersect, rho_consistent
from shoal.engine.acoustics.partners import random_partner
from shoal.engine.acoustics.strategies import STRATEGIES, LocInfo, Sensed, initial_memory, make_strategy
from shoal.engine.acoustics.triangulation import triangles
from shoal.engine.robots.sensing import SectorReading

E = np.exp(-1.0)


def rays_from(heading: float, theta: float) -> np.ndarray:
    """[7.7]: [r_+, r_−] for a bow heading and an arrival angle in [0, π]."""
    return np.array([[np.cos(heading + theta), np.sin(heading + theta)],
                     [np.cos(heading - theta), np.sin(heading - theta)]])


def bearing(p: np.ndarray, q: np.ndarray) -> float:
    d = q - p
    return float(np.arctan2(d[1], d[0]))


def rays_at(p: np.ndarray, source: np.ndarray, phantom: np.ndarray) -> np.ndarray:
    """Rays of a robot whose true ray hits ``source`` and whose mirror ray hits ``phantom``:
    the bow bisects the two bearings."""
    b_s, b_f = bearing(p, source), bearing(p, phantom)
    half = np.angle(np.exp(1j * (b_f - b_s))) / 2
    return rays_from(b_s + half, abs(half))


def step(name: str, x, sensed: Sensed, f_hat=None, y=None, seed: int = 0, **kw):
    x = np.asarray(x, dtype=float)
    f0, y0 = initial_memory(x)
    f_hat = f0 if f_hat is None else np.asarray(f_hat, dtype=float)
    y = y0 if y is None else np.asarray(y, dtype=float)
    rngs = [np.random.default_rng(seed + r) for r in range(x.shape[0])]
    return make_strategy(name, **kw).update(f_hat, y, x, sensed, rngs)


def all_finite(*arrays) -> bool:
    return all(np.all(np.isfinite(np.asarray(a, dtype=float))) for a in arrays if a is not None)


def info_arrays(info: LocInfo) -> list:
    out = [info.candidate, info.fitness, info.points]
    if info.triangles is not None:
        t = info.triangles
        out += [t.centroid, t.direction, t.normal]
    return out


# ----------------------------------------------------------------------------- forgetting
def test_forgetting_replaces_on_improvement_and_decays_otherwise():
    f_hat = np.array([[1.0, 2.0, 3.0, 4.0]])
    y = np.zeros((1, 4, 2))
    f_new = np.array([[1.5, 2.0, 10.0, np.nan]])
    cand = np.ones((1, 4, 2))
    valid = np.array([[True, True, False, True]])
    f, yy = forget_update(f_hat, y, f_new, cand, valid, a=1.0)
    assert f[0, 0] == 1.5 and np.all(yy[0, 0] == 1.0)  # improvement replaces
    assert f[0, 1] == pytest.approx(2.0 * E, rel=1e-15)  # a tie is not an improvement
    assert f[0, 2] == pytest.approx(3.0 * E, rel=1e-15)  # invalid candidate: decay only
    assert f[0, 3] == pytest.approx(4.0 * E, rel=1e-15)  # NaN fitness counts as invalid
    assert np.all(yy[0, 1:] == 0.0)


def test_forgetting_scale_a():
    f, _ = forget_update(np.array([[2.0]]), np.zeros((1, 1, 2)), np.array([[0.0]]),
                         np.zeros((1, 1, 2)), np.array([[True]]), a=0.25)
    assert f[0, 0] == pytest.approx(2.0 * np.exp(-0.25), rel=1e-15)


def test_centroid_is_mean_of_personal_bests():  # [7.11]
    y = np.random.default_rng(1).normal(size=(3, 7, 2))
    assert np.allclose(centroid_of(y), y.mean(axis=1))
    x = np.random.default_rng(2).normal(size=(3, 7, 2)) * 50
    rays = np.stack([rays_from(h, t) for h, t in np.random.default_rng(3).uniform(0, 3, (21, 2))]).reshape(3, 7, 2, 2)
    f, y, yg, _ = step("b-pso", x, Sensed(rays=rays))
    assert np.allclose(yg, y.mean(axis=1))


# ----------------------------------------------------------------------------- A/X-PSO
def test_apso_candidate_is_own_position_and_gbest_is_best_robot():
    x = np.array([[[0.0, 0.0], [5.0, 0.0], [9.0, 1.0]]])
    f, y, yg, info = step("a-pso", x, Sensed(intensity=np.array([[1.0, 3.0, 2.0]])))
    assert np.allclose(f, [[1.0, 3.0, 2.0]]) and np.allclose(y, x)
    assert np.allclose(yg, [[5.0, 0.0]]) and info.f_g[0] == 3.0
    # next step, weaker field: memory decays, bests stay
    f2, y2, yg2, _ = step("a-pso", x + 1, Sensed(intensity=np.array([[0.1, 0.1, 2.5]])), f, y)
    assert np.allclose(f2, [[E, 3 * E, 2.5]]) and np.allclose(y2[0, :2], x[0, :2])
    assert np.allclose(yg2, [[10.0, 2.0]])


def test_xpso_negative_rho_reads_as_zero():  # docs/readings.md, "Negative fitness"
    x = np.zeros((1, 2, 2))
    f, y, yg, info = step("x-pso", x, Sensed(rho=np.array([[-2.0, 0.5]])), f_hat=np.array([[0.2, 0.0]]))
    assert info.fitness[0, 0] == 0.0 and f[0, 0] == pytest.approx(0.2 * E)
    assert f[0, 1] == 0.5 and np.all(f >= 0)


def test_registry_names_and_needs():
    assert set(STRATEGIES) == {"a-pso", "x-pso", "b-pso", "xb-pso", "gt-pso"}
    with pytest.raises(ValueError, match="sensed.rays"):
        step("b-pso", np.zeros((1, 2, 2)), Sensed(rho=np.zeros((1, 2))))
    with pytest.raises(ValueError, match="unknown"):
        make_strategy("c-pso")


# ----------------------------------------------------------------------------- B-PSO
A, B = np.array([0.0, 0.0]), np.array([20.0, 0.0])


def two_robots(source, phantom):
    x = np.array([[A, B]])
    rays = np.array([[rays_at(A, source, phantom), rays_at(B, source, phantom)]])
    return x, rays


def test_bpso_picks_source_intersection_when_it_is_furthest():
    S, F = np.array([10.0, 100.0]), np.array([10.0, 20.0])  # mirror rays cross near the swarm
    x, rays = two_robots(S, F)
    f, y, yg, info = step("b-pso", x, Sensed(rays=rays))
    assert np.all(info.partner == [[1, 0]])
    assert info.forward.sum() == 8  # all four pairings cross ahead of both robots
    assert np.allclose(info.candidate, S) and np.allclose(y, S)
    assert np.allclose(f, 1.0 / np.linalg.norm(S - x[0], axis=-1))  # [7.10]
    assert np.allclose(yg, S)
    # the mirror × mirror point is among the candidates but was not chosen
    assert np.any(np.all(np.isclose(info.points, F), axis=-1))


def test_bpso_furthest_rule_takes_mirror_point_when_it_is_further():
    S, F = np.array([10.0, 20.0]), np.array([10.0, 100.0])
    x, rays = two_robots(S, F)
    f, y, yg, info = step("b-pso", x, Sensed(rays=rays))
    assert np.allclose(info.candidate, F)  # Alg. 5's furthest rule, an "unhealthy" type-3 point
    assert np.allclose(f, 1.0 / np.linalg.norm(F - x[0], axis=-1))


DEGENERATE = {
    "parallel": ([[0, 0], [10, 0]], [(np.pi / 2, 0.0), (np.pi / 2, 0.0)]),
    "anti-parallel, collinear": ([[0, 0], [10, 0]], [(0.0, 0.0), (np.pi, 0.0)]),
    "anti-parallel, offset": ([[0, 0], [10, 5]], [(0.0, 0.0), (np.pi, 0.0)]),
    "coincident robots": ([[3, 4], [3, 4]], [(0.0, 0.7), (1.0, 0.3)]),
    "behind robot i": ([[0, 0], [-10, -10]], [(0.0, 0.0), (np.pi / 2, 0.0)]),
    "behind the partner": ([[0, 0], [5, 10]], [(0.0, 0.0), (np.pi / 2, 0.0)]),
    "endfire both ways": ([[0, 0], [10, 10]], [(0.0, np.pi), (0.0, np.pi)]),
}


@pytest.mark.parametrize("name", ["b-pso", "xb-pso"])
@pytest.mark.parametrize("case", list(DEGENERATE))
def test_degenerate_pairs_give_no_candidate_and_decay(case, name):
    pos, ht = DEGENERATE[case]
    x = np.array([pos], dtype=float)
    rays = np.array([[rays_from(h, t) for h, t in ht]])
    f0, y0 = np.array([[0.5, 2.0]]), np.array([[[7.0, 7.0], [-1.0, 2.0]]])
    f, y, yg, info = step(name, x, Sensed(rays=rays, rho=np.array([[1.0, 2.0]])), f0, y0)
    assert not info.valid.any() and not info.forward.any()
    assert np.allclose(f, f0 * E, rtol=1e-15) and np.array_equal(y, y0)
    assert all_finite(f, y, yg, *info_arrays(info))


def test_empty_intersection_set_single_robot():
    x = np.zeros((2, 1, 2))
    rays = np.broadcast_to(rays_from(0.3, 1.0), (2, 1, 2, 2))
    f, y, yg, info = step("b-pso", x, Sensed(rays=rays), f_hat=np.ones((2, 1)))
    assert np.all(info.partner == -1) and np.allclose(f, E) and all_finite(f, y, yg, *info_arrays(info))


def test_intersect_forward_only():
    p, t, s, ok = intersect(np.array([0.0, 0]), np.array([1.0, 0]), np.array([5.0, -5]), np.array([0.0, 1]))
    assert ok and np.allclose(p, [5, 0]) and t == pytest.approx(5) and s == pytest.approx(5)
    _, _, _, ok = intersect(np.array([0.0, 0]), np.array([-1.0, 0]), np.array([5.0, -5]), np.array([0.0, 1]))
    assert not ok


# ----------------------------------------------------------------------------- XB-PSO
def test_rho_consistent_table():  # [7.12]
    d_i, d_j = np.array([1.0, 1.0, 3.0, 3.0, 2.0, 1.0]), np.array([2.0, 2.0, 2.0, 2.0, 2.0, 2.0])
    rho_i, rho_j = np.array([5.0, 1.0, 1.0, 5.0, 5.0, 3.0]), np.array([3.0, 3.0, 3.0, 3.0, 3.0, 3.0])
    assert rho_consistent(d_i, d_j, rho_i, rho_j).tolist() == [True, False, True, False, False, False]


def test_xbpso_keeps_source_when_nearer_robot_hears_more():
    S, F = np.array([2.0, 60.0]), np.array([10.0, 15.0])  # S nearer A
    x, rays = two_robots(S, F)
    f, y, yg, info = step("xb-pso", x, Sensed(rays=rays, rho=np.array([[2.0, 1.0]])))
    assert np.allclose(info.candidate[0, 0], S)  # A: nearer and louder → kept
    assert np.allclose(info.candidate[0, 1], S)  # B: further and quieter → kept


def test_xbpso_rejects_source_on_the_wrong_side():
    S, F = np.array([2.0, 60.0]), np.array([10.0, 15.0])
    x, rays = two_robots(S, F)
    f, y, yg, info = step("xb-pso", x, Sensed(rays=rays, rho=np.array([[1.0, 2.0]])))
    at_s = np.all(np.isclose(info.points, S), axis=-1)
    assert at_s.any(axis=-1).all() and not (info.kept & at_s).any()
    assert not np.any(np.all(np.isclose(info.candidate, S), axis=-1))
    # what survives lies nearer B, the louder robot
    d_a = np.linalg.norm(info.points - A, axis=-1)
    d_b = np.linalg.norm(info.points - B, axis=-1)
    assert np.all(d_b[info.kept] < d_a[info.kept])
    # B-PSO, with no check, would have taken S
    _, _, _, plain = step("b-pso", x, Sensed(rays=rays))
    assert np.allclose(plain.candidate, S)


def test_xbpso_equal_rho_drops_everything():  # docs/readings.md, "Ties in the cell deletion"
    x, rays = two_robots(np.array([2.0, 60.0]), np.array([10.0, 15.0]))
    f, y, yg, info = step("xb-pso", x, Sensed(rays=rays, rho=np.ones((1, 2))), f_hat=np.ones((1, 2)))
    assert info.forward.all() and not info.kept.any() and np.allclose(f, E)


# ----------------------------------------------------------------------------- GT-PSO
def inverse_square(x: np.ndarray, source: np.ndarray) -> np.ndarray:
    return 1e6 / np.sum((x - source) ** 2, axis=-1)


def test_gtpso_two_triplets_triangulate_the_source():
    src = np.array([3.0, -2.0])
    tri_a = np.array([[100.0, 0.0], [101.0, 0.5], [100.3, 1.2]])
    tri_b = np.array([[0.0, 100.0], [0.7, 101.0], [-0.6, 100.8]])
    x = np.concatenate([tri_a, tri_b])[None] + src
    f, y, yg, info = step("gt-pso", x, Sensed(intensity=inverse_square(x, src)))
    t = info.triangles
    assert t.valid.all()
    assert np.all(np.isin(info.partner[0, :3], [3, 4, 5])) and np.all(np.isin(info.partner[0, 3:], [0, 1, 2]))
    # plane gradient points at the source within the near-field approximation ([8.2]–[8.4], Rossides §8.1, p. 174)
    to_src = src - t.centroid
    cos = np.sum(t.direction * to_src, axis=-1) / np.linalg.norm(to_src, axis=-1)
    assert np.all(cos > 0.999)
    assert info.valid.all()
    err = np.linalg.norm(info.candidate - src, axis=-1)
    assert np.all(err < 0.02 * 100)  # 2 % of the 100 m range, for 1 m triangles
    assert np.allclose(f, 1.0 / np.linalg.norm(x - info.candidate, axis=-1))  # [8.5], from the robot
    assert np.allclose(yg, y.mean(axis=1))


def test_gtpso_plane_on_a_linear_field_gives_its_gradient():
    x = np.array([[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]])
    g = np.array([2.0, -1.0])
    t = triangles(x, x @ g + 5.0)
    assert t.valid.all() and np.allclose(t.direction, g / np.linalg.norm(g))
    assert np.allclose(triangles(x, x @ g, maximise=False).direction, -g / np.linalg.norm(g))


def test_gtpso_degenerate_triangles():
    line = np.array([[[0.0, 0.0], [1.0, 0.0], [2.0, 0.0], [3.0, 0.0], [4.0, 0.0]]])
    t = triangles(line, inverse_square(line, np.array([2.0, 50.0])))
    assert not t.valid.any() and all_finite(t.centroid, t.direction, t.normal)  # collinear
    tri = np.array([[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [50.0, 50.0], [51.0, 50.0], [50.0, 51.0]]])
    assert not triangles(tri, np.full((1, 6), 4.0)).valid.any()  # equal intensities
    same = np.zeros((1, 4, 2))
    assert not triangles(same, np.arange(4.0)[None]).valid.any()  # coincident robots
    f, y, yg, info = step("gt-pso", line, Sensed(intensity=np.ones((1, 5))), f_hat=np.ones((1, 5)))
    assert not info.valid.any() and np.allclose(f, E) and all_finite(f, y, yg, *info_arrays(info))


def test_gtpso_too_few_robots_for_a_partner():
    x = np.array([[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]])
    sensed = Sensed(intensity=inverse_square(x, np.array([30.0, 40.0])))
    f, y, yg, info = step("gt-pso", x, sensed, f_hat=np.ones((1, 3)))
    assert info.triangles.valid.all() and np.all(info.partner == -1) and np.allclose(f, E)
    f, y, yg, info = step("gt-pso", x[:, :2], Sensed(intensity=np.ones((1, 2))))
    assert not info.triangles.valid.any() and all_finite(f, y, yg, *info_arrays(info))


# ----------------------------------------------------------------------------- partners
def test_partner_is_uniform_over_others():
    rng = np.random.default_rng(5)
    p = np.concatenate([random_partner(rng, (50, 4)) for _ in range(100)])
    assert not np.any(p == np.arange(4))
    counts = np.array([[np.sum(p[:, i] == j) for j in range(4)] for i in range(4)])
    assert np.all(counts[~np.eye(4, dtype=bool)] > 1500)  # 5000 draws over 3 choices


def test_partner_stream_is_per_run():
    gens = lambda: [np.random.default_rng(s) for s in (11, 12, 13)]  # noqa: E731
    batch = random_partner(gens(), (3, 6))
    alone = random_partner([np.random.default_rng(12)], (1, 6))
    assert np.array_equal(batch[1], alone[0])


# ----------------------------------------------------------------------------- escorting
def test_escort_gap_sector_and_value():
    x = np.array([[[0.0, 0.0], [100.0, 0.0], [0.0, 10.0]]])
    heading = np.array([[0.0, np.pi / 2, 0.0]])
    yg = np.array([[0.0, 60.0]])
    gap = escort_gap(x, heading, yg, 50.0, sensing_range=20.0)
    assert gap.shape == (1, 3, 6)
    assert gap[0, 0, 4] == pytest.approx(10.0) and np.sum(gap[0, 0] < 20.0) == 1  # 90° left → sector 5
    assert np.all(gap[0, 1] == 20.0)  # ring too far to sense
    assert gap[0, 2, 4] == 0.0  # inside the ring: contact toward y_g
    far = escort_gap(x, heading, yg, 50.0)[0, 1]  # unlimited range: seen, once
    assert far[3] == pytest.approx(np.hypot(100, 60) - 50) and np.sum(np.isfinite(far)) == 1


def test_with_escort_merges_closer_ring():
    R, N = 1, 1
    empty = SectorReading(gap=np.full((R, N, 6), 10.0), point=np.full((R, N, 6, 2), np.nan),
                          centre=np.full((R, N, 6, 2), np.nan), hit=np.zeros((R, N, 6), bool))
    out = with_escort(empty, np.zeros((1, 1, 2)), np.zeros((1, 1)), np.array([[8.0, 0.0]]), 5.0, sensing_range=10.0)
    assert out.hit[0, 0, 3] and out.gap[0, 0, 3] == pytest.approx(3.0)  # dead ahead → sector 4
    assert np.allclose(out.point[0, 0, 3], [3.0, 0.0]) and np.allclose(out.centre[0, 0, 3], [8.0, 0.0])
    assert out.hit.sum() == 1


def test_moving_source():  # [8.8]
    x0 = np.array([10.0, -5.0])
    assert np.allclose(moving_source(x0, 0.0, 0.25, 2.0, 1.0, 4), [12.0, -5.0])
    path = moving_source(x0, np.pi / 2, 0.1, 2.0, 1.0, np.arange(3))
    assert np.allclose(path, [[10, -5], [10, -4.8], [10, -4.6]])


# ----------------------------------------------------------------------------- properties
coord = st.one_of(st.floats(-200, 200, allow_nan=False), st.sampled_from([0.0, 1.0, 10.0]))
angle = st.one_of(st.floats(0, np.pi), st.sampled_from([0.0, np.pi / 2, np.pi]))


@st.composite
def swarms(draw):
    R, N = draw(st.integers(1, 3)), draw(st.integers(1, 7))
    n = R * N
    x = np.array(draw(st.lists(coord, min_size=2 * n, max_size=2 * n))).reshape(R, N, 2)
    heading = np.array(draw(st.lists(st.floats(-4, 4), min_size=n, max_size=n))).reshape(R, N)
    theta = np.array(draw(st.lists(angle, min_size=n, max_size=n))).reshape(R, N)
    rho = np.array(draw(st.lists(st.floats(-1, 5), min_size=n, max_size=n))).reshape(R, N)
    intensity = np.array(draw(st.lists(st.sampled_from([0.0, 1.0, 2.0, 1e3]) | st.floats(0, 1e3),
                                       min_size=n, max_size=n))).reshape(R, N)
    fhat = np.array(draw(st.lists(st.floats(0, 10), min_size=n, max_size=n))).reshape(R, N)
    rays = np.stack([np.stack([np.cos(heading + theta), np.sin(heading + theta)], -1),
                     np.stack([np.cos(heading - theta), np.sin(heading - theta)], -1)], axis=2)
    return x, rays, rho, intensity, fhat, draw(st.integers(0, 2**32 - 1))


def ahead(p: np.ndarray, origin: np.ndarray, d: np.ndarray) -> bool:
    v = p - origin
    along = float(v @ d)
    return along > 0 and abs(float(cross2(v, d))) <= 1e-6 * max(along, 1.0)


@settings(max_examples=200, deadline=None)
@given(swarms())
def test_outputs_finite_and_selected_points_ahead_of_both_robots(case):
    x, rays, rho, intensity, fhat, seed = case
    sensed = Sensed(intensity=intensity, rho=rho, rays=rays)
    for name in sorted(STRATEGIES):
        f, y, yg, info = step(name, x, sensed, f_hat=fhat, y=x.copy(), seed=seed)
        assert all_finite(f, y, yg, *info_arrays(info)), name
        assert np.all(f >= 0)
        decayed = ~info.improved
        assert np.allclose(f[decayed], fhat[decayed] * E, rtol=1e-12)
        if name in ("b-pso", "xb-pso"):
            for r, i in zip(*np.nonzero(info.valid)):
                k, j = info.selected[r, i], info.partner[r, i]
                p = info.candidate[r, i]
                assert ahead(p, x[r, i], rays[r, i, PAIRS_I[k]]) and ahead(p, x[r, j], rays[r, j, PAIRS_J[k]])
                dists = np.linalg.norm(info.points[r, i][info.kept[r, i]] - x[r, i], axis=-1)
                assert np.linalg.norm(p - x[r, i]) == pytest.approx(dists.max())
        if name == "gt-pso":
            t = info.triangles
            for r, i in zip(*np.nonzero(info.valid)):
                o, p = info.partner[r, i], info.candidate[r, i]
                assert o not in t.members[r, i]
                assert ahead(p, t.centroid[r, i], t.direction[r, i]) and ahead(p, t.centroid[r, o], t.direction[r, o])
