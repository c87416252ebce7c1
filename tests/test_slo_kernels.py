"""The compiled SLO kernels against their numpy references (the ``numpy_*`` functions below),
bit for bit: the pair step, neighbour search, sensors, carried estimates, PSO local best and
SPSO update, metrics and their statistics (random and singular inputs, whole seeded runs of
every selection with every kernel swapped for its reference, the generators' states included),
and the metrics and candidate sets worked out when read equal to those worked out at once."""

from __future__ import annotations

import numpy as np
import pytest

import shoal.engine.kinds.slo_swarm as slo_swarm_module
import shoal.engine.slo.beliefs as beliefs_module
import shoal.engine.slo.metrics as metrics_module
import shoal.engine.slo.neighbourhoods as neighbourhoods_module
from shoal.engine.core import sums
from shoal.engine.core.compiled_draws import CompiledDraws
from shoal.engine.kinds.slo_swarm import SLOSwarm
from shoal.engine.pso import spso2011, spso_kernels
from shoal.engine.pso.spso2011 import SPSO2011, SPSODraws
from shoal.engine.slo import kernels, metric_kernels, select_kernels, selection
from shoal.engine.slo.candidates import Candidates, candidates
from shoal.engine.slo.metrics import STATS, dead_reckoning_share, pair_distances, pair_errors, round_trip_errors, stats
from shoal.engine.slo.selection import Kind, css
from shoal.engine.slo.sensors import draw_permanent, error_model, measure_odometry, measure_ranges

CANDIDATE_FIELDS = ("points", "mask", "flag", "cos_alpha", "thinness")


def numpy_localise(d0, d1, v, prev, *, delta_cos, delta_v, literal_eq_3_1, prediction_weight=0.5, entry=None,
                   coin=None, candidates_=True, **kw):
    """The numpy reference of :func:`kernels.localise`: candidates [3.1]–[3.6] and css [3.7]."""
    c = candidates(d0, d1, v[:, None, :, :] - v[:, :, None, :], prev, delta_cos, delta_v, literal_eq_3_1)
    est, kind = css(c, prediction_weight, entry, coin)
    return kernels.Localised(est, kind, c.flag, c if kw.get("candidates", candidates_) else None)


def _candidates(points, mask):
    shape = mask.shape[:-1]
    return Candidates(points, mask, np.zeros(shape, np.int8), np.full(shape, np.nan), np.full(shape, np.nan))


def numpy_rts(points, mask, adjacency, fallback, triangle="first", prefer_geometric=False, tolerance=0.0):
    """The numpy reference of :func:`select_kernels.rts`."""
    res = selection.rts(_candidates(points, mask), adjacency, fallback, triangle, prefer_geometric, tolerance)
    return res.est, res.kind, res.triangle, res.round_trip


def numpy_akcan(points, mask, adjacency, ranges, fallback):
    """The numpy reference of :func:`select_kernels.akcan`."""
    return selection.akcan(_candidates(points, mask), adjacency, ranges, fallback)


def numpy_distances(x):
    d = np.linalg.norm(x[:, None, :, :] - x[:, :, None, :], axis=-1)
    idx = np.arange(x.shape[1])
    d[:, idx, idx] = np.inf
    return d


def numpy_nearest(dist, k):
    adj = np.zeros(dist.shape, bool)
    if k:
        np.put_along_axis(adj, np.argsort(dist, axis=-1, kind="stable")[..., :k], True, axis=-1)
    return adj


def numpy_stats(values, keys=STATS):
    """The numpy reference of :func:`metrics.stats`."""
    flat = values.reshape(values.shape[0], -1)
    good = np.isfinite(flat)
    n = good.sum(axis=1)
    empty = n == 0
    out = {"count": n}
    if {"mean", "std", "sem"} & set(keys):
        safe = np.where(good, flat, 0.0)
        with np.errstate(invalid="ignore", divide="ignore"):
            mean = safe.sum(axis=1) / n
            var = np.where(good, (safe - mean[:, None]) ** 2, 0.0).sum(axis=1) / n
            std = np.sqrt(var)
            sem = std / np.sqrt(n)
        out |= {"mean": np.where(empty, np.nan, mean), "std": np.where(empty, np.nan, std),
                "sem": np.where(empty, np.nan, sem)}
    if "median" in keys:
        ordered = np.sort(np.where(good, flat, np.inf), axis=1)
        lo, hi = np.maximum((n - 1) // 2, 0), np.maximum(n // 2, 0)
        rows = np.arange(flat.shape[0])
        out["median"] = np.where(n > 0, 0.5 * (ordered[rows, lo] + ordered[rows, hi]), np.nan)
    return {k: out[k] for k in keys}


def numpy_distance_errors(x, est, valid):
    """The numpy reference of :func:`metrics.distance_errors`."""
    truth = x[:, None, :, :] - x[:, :, None, :]
    e_abs = np.linalg.norm(est - truth, axis=-1)
    dist = np.linalg.norm(truth, axis=-1)
    e_rel = np.divide(e_abs, dist, out=np.full_like(e_abs, np.nan), where=dist > 0)
    return np.where(valid, e_abs, np.nan), np.where(valid, e_rel, np.nan)


def numpy_dead_reckoning_share(kind, valid):
    """The numpy reference of :func:`metrics.dead_reckoning_share`."""
    n = valid.sum(axis=(1, 2))
    dr = (valid & (kind == Kind.X3)).sum(axis=(1, 2))
    return np.divide(dr, n, out=np.full(n.shape, np.nan), where=n > 0)


def numpy_pair_distances(x):
    """The numpy reference of :func:`metrics.pair_distances`."""
    i, j = np.triu_indices(x.shape[1], k=1)
    return np.linalg.norm(x[:, j] - x[:, i], axis=-1)


def numpy_carry(adjacency, new, kind, prev, v, dead_reckoning):
    """The numpy reference of :func:`kernels.carry`."""
    carried = prev + (v[:, None, :, :] - v[:, :, None, :]) if dead_reckoning else prev
    return np.where(adjacency[..., None], new, carried), np.where(adjacency, kind, Kind.NONE).astype(np.int8)


def _generators(rngs):
    """The generators behind compiled draws."""
    return rngs.rngs if isinstance(rngs, CompiledDraws) else rngs


def numpy_local_best(f, fP, P, adjacency, est, pbest):
    """The numpy reference of :func:`kernels.local_best` (steps 2–4 of Alg. 1)."""
    better = f < fP
    P = np.where(better[..., None], 0.0, P)
    fP = np.where(better, f, fP)
    n = f.shape[1]
    score = fP if pbest else f
    ranked = np.where(adjacency | np.eye(n, dtype=bool), score[:, None, :], np.inf)
    self_best = score <= ranked.min(axis=-1)
    j = np.where(self_best, np.arange(n), np.argmin(ranked, axis=-1))
    to_j = np.take_along_axis(est, j[..., None, None], axis=2)[:, :, 0, :]
    L = np.where(self_best[..., None], 0.0, to_j)
    if pbest:
        L = np.where(self_best[..., None], P, to_j + np.take_along_axis(P, j[..., None], axis=1))
    return P, fP, self_best, L


def numpy_draw(rngs, n):
    """SPSO's draws of a generation from one generator call each, the reference of compiled draws."""
    return spso2011.draw(_generators(rngs), n)


def numpy_measure_ranges(dist, model, perm, rngs, max_range=np.inf):
    """The numpy reference of :func:`sensors.measure_ranges`, one generator call a run."""
    rngs = _generators(rngs)
    R, n, _ = dist.shape
    fail, z = np.empty((R, n, n)), np.empty((R, 2, n, n))
    for r, g in enumerate(rngs):
        g.random(out=fail[r])
        g.standard_normal(out=z[r])
    e_m = 1.0 + model.sigma_m * z[:, 0] + perm.range_m[:, :, None]
    e_a = model.sigma_a * z[:, 1] + perm.range_a[:, :, None]
    finite = np.isfinite(dist) & (dist <= max_range)
    d = np.where(finite, dist, 0.0)
    reading = np.maximum(d * e_m + e_a, 0.0)
    out = np.where((fail < model.p_fail) | ~finite, 0.0, reading)
    idx = np.arange(n)
    out[:, idx, idx] = 0.0
    return out


def numpy_measure_odometry(v, model, perm, rngs):
    """The numpy reference of :func:`sensors.measure_odometry`, one generator call a run."""
    rngs = _generators(rngs)
    R, n = v.shape[:2]
    fail, z = np.empty((R, n)), np.empty((R, 5, n))
    for r, g in enumerate(rngs):
        g.random(out=fail[r])
        g.standard_normal(out=z[r])
    e_m = 1.0 + model.sigma_m * np.stack([z[:, 0], z[:, 1]], axis=-1) + perm.odo_m
    e_a = model.sigma_a * np.stack([z[:, 2], z[:, 3]], axis=-1) + perm.odo_a
    w = v * e_m + e_a
    theta = model.sigma_r * z[:, 4] + perm.odo_r
    c, s = np.cos(theta), np.sin(theta)
    rotated = np.stack([c * w[..., 0] - s * w[..., 1], s * w[..., 0] + c * w[..., 1]], axis=-1)
    return np.where((fail < model.p_fail)[..., None], 0.0, rotated)


def _pairs(rng, R, n):
    """Ranges, displacements and previous estimates with every singular case mixed in."""
    d0 = rng.uniform(0.0, 60.0, (R, n, n))
    d1 = np.abs(d0 + rng.normal(0.0, 3.0, (R, n, n)))
    v = rng.normal(0.0, 3.0, (R, n, 2))
    prev = rng.normal(0.0, 30.0, (R, n, n, 2))
    pick = rng.random((R, n, n))
    d0[pick < 0.05] = 0.0  # range failures
    d1[(pick > 0.05) & (pick < 0.08)] = 0.0
    d0[(pick > 0.08) & (pick < 0.09)] = np.inf
    d1[(pick > 0.09) & (pick < 0.10)] = np.nan
    prev[(pick > 0.10) & (pick < 0.11)] = np.nan
    v[:, 0] = v[:, 1]  # robots 0 and 1 moved alike: |v*_j − v*_i| = 0
    d1[(pick > 0.2) & (pick < 0.3)] = d0[(pick > 0.2) & (pick < 0.3)] + 1e-9  # |cos α| near 1
    return d0, d1, v, prev


@pytest.mark.parametrize("literal", [False, True])
@pytest.mark.parametrize("delta_cos, delta_v", [(0.03, 0.03), (-np.inf, 0.0), (0.5, 0.2)])
def test_compiled_pair_step_equals_candidates_and_css(literal, delta_cos, delta_v):
    rng = np.random.default_rng(7)
    d0, d1, v, prev = _pairs(rng, 3, 12)
    entry = rng.random((3, 12, 12)) < 0.3
    coin = rng.random((3, 12, 12)) < 0.5
    for ent, cn, w in ((None, None, 0.5), (entry, coin, 0.25), (None, None, 1.0)):
        kw = dict(delta_cos=delta_cos, delta_v=delta_v, literal_eq_3_1=literal, prediction_weight=w, entry=ent,
                  coin=cn)
        got, want = kernels.localise(d0, d1, v, prev, **kw), numpy_localise(d0, d1, v, prev, **kw)
        for name in ("est", "kind", "flag"):
            np.testing.assert_array_equal(getattr(got, name), getattr(want, name), err_msg=name)
        for name in CANDIDATE_FIELDS:
            np.testing.assert_array_equal(getattr(got.candidates, name), getattr(want.candidates, name),
                                          err_msg=name)
        assert kernels.localise(d0, d1, v, prev, **kw, candidates=False).candidates is None


@pytest.mark.parametrize("level", ["none", "low", "high"])
def test_compiled_sensors_equal_numpy(level):
    """Ranges and odometry of every error level, from the same streams, to the bit: failures,
    negative readings clamped, infinite and out-of-reach distances, the generators left alike."""
    rng = np.random.default_rng(5)
    model = error_model(level).with_values(range_sigma_a=3.0 if level == "high" else 0.05)  # negative readings
    for trial in range(6):
        R, n = int(rng.integers(1, 4)), int(rng.integers(2, 14))
        perm = draw_permanent(model, [np.random.default_rng(trial)] * R, n)
        dist = kernels.distances(rng.normal(0.0, 20.0, (R, n, 2)))
        dist[rng.random(dist.shape) < 0.05] = np.nan
        v = rng.normal(0.0, 2.0, (R, n, 2))
        reach = (np.inf, 15.0)[trial % 2]
        ours, theirs = ([np.random.default_rng([trial, r]) for r in range(R)] for _ in range(2))
        draws = CompiledDraws(ours) if trial % 3 else ours  # compiled, or a call a run
        for _ in range(3):
            np.testing.assert_array_equal(measure_ranges(dist, model.range, perm, draws, reach),
                                          numpy_measure_ranges(dist, model.range, perm, theirs, reach))
            np.testing.assert_array_equal(measure_odometry(v, model.odometry, perm, draws),
                                          numpy_measure_odometry(v, model.odometry, perm, theirs))
        assert [g.random() for g in ours] == [g.random() for g in theirs]


def test_compiled_local_best_equals_numpy():
    """Personal bests, best informants and local bests: ties (to the particle, then the first),
    NaN and infinite fitness, lone particles, both local-best modes."""
    rng = np.random.default_rng(6)
    for trial in range(40):
        R, n = int(rng.integers(1, 4)), int(rng.integers(2, 12))
        f = rng.integers(0, 4, (R, n)).astype(float) if trial % 2 else rng.exponential(5.0, (R, n))
        fP = np.where(rng.random((R, n)) < 0.3, np.inf, rng.exponential(5.0, (R, n)))
        f[rng.random((R, n)) < 0.1] = np.nan
        fP[rng.random((R, n)) < 0.05] = np.nan
        P, est = rng.normal(0, 5, (R, n, 2)), rng.normal(0, 5, (R, n, n, 2))
        adjacency = rng.random((R, n, n)) < (0.1, 0.5, 1.0)[trial % 3]
        for pbest in (False, True):
            got, want = kernels.local_best(f, fP, P, adjacency, est, pbest), numpy_local_best(f, fP, P, adjacency,
                                                                                               est, pbest)
            for name, a, b in zip(("P", "fP", "self_best", "L"), got, want):
                assert a.dtype == b.dtype
                np.testing.assert_array_equal(a, b, err_msg=f"{name} {trial} {pbest}")


@pytest.mark.parametrize("law", [SPSO2011(), SPSO2011(c3=0.5, c4=-2.0, radial="uniform_area"),
                                 SPSO2011(spso_self_best_halving=True, c4=1.5)], ids=["thesis", "area", "halving"])
def test_compiled_local_velocity_equals_numpy(law):
    """[3.10]–[3.11] to the bit: degenerate directions, negative radii (clamped), own bests."""
    rng = np.random.default_rng(8)
    R, n = 3, 11
    v, p, l = (rng.normal(0, 5, (R, n, 2)) for _ in range(3))
    d = SPSODraws(rng.random((R, n, 2)), rng.random((R, n, 2)), rng.normal(size=(R, n, 2)), rng.random((R, n)))
    d.normal[0, :3] = 0.0  # no direction
    p[1, :2] = l[1, :2] = 0.0  # G = 0: radius c4
    own = rng.random((R, n)) < 0.3
    for self_best in (own, None):
        np.testing.assert_array_equal(spso_kernels.local_velocity(law, v, p, l, d, self_best),
                                      law.local_velocity(v, p, l, d, self_best))


def test_compiled_carry_equals_numpy():
    """Neighbours take the selected estimate and kind, the others their previous estimate,
    dead-reckoned or kept (non-finite values and odometry failures mixed in)."""
    rng = np.random.default_rng(4)
    for _ in range(10):
        R, n = int(rng.integers(1, 4)), int(rng.integers(2, 14))
        adjacency = rng.random((R, n, n)) < 0.4
        new, prev = rng.normal(0, 10, (R, n, n, 2)), rng.normal(0, 10, (R, n, n, 2))
        prev[rng.random((R, n, n)) < 0.05] = np.nan
        v = rng.normal(0, 2, (R, n, 2)) * (rng.random((R, n, 1)) > 0.1)
        kind = rng.integers(0, 6, (R, n, n)).astype(np.int8)
        for dead_reckoning in (True, False):
            for got, want in zip(kernels.carry(adjacency, new, kind, prev, v, dead_reckoning),
                                 numpy_carry(adjacency, new, kind, prev, v, dead_reckoning)):
                assert got.dtype == want.dtype
                np.testing.assert_array_equal(got, want)


def test_compiled_distances_and_nearest_equal_numpy():
    rng = np.random.default_rng(3)
    for trial in range(60):
        R, n = int(rng.integers(1, 4)), int(rng.integers(2, 22))
        x = rng.normal(0.0, 10.0, (R, n, 2))
        np.testing.assert_array_equal(kernels.distances(x), numpy_distances(x))
        d = rng.integers(0, 5, (R, n, n)).astype(float) if trial % 2 else rng.uniform(0, 10, (R, n, n))  # ties
        d[rng.random(d.shape) < 0.05] = np.nan
        d[rng.random(d.shape) < 0.05] = np.inf
        for k in range(n + 1):
            np.testing.assert_array_equal(kernels.nearest(d, k), numpy_nearest(d, k))


def test_pairwise_sum_is_numpys():
    """numpy's add.reduce along a contiguous row, to the bit, at every length up to two blocks and
    beyond (values of mixed magnitude and sign, so the order of the additions shows)."""
    rng = np.random.default_rng(11)
    for n in [*range(0, 300), 399, 400, 1000, 4097]:
        a = rng.normal(size=(2, n)) * 10.0 ** rng.uniform(-8, 8, (2, n))
        want = a.sum(axis=1)
        for r in range(2):
            assert 0.0 + sums.pairwise_sum(a[r], 0, n) == want[r], n
    for n in range(1, 20):  # negative zeros: numpy's sum is +0, a block's own sum keeps −0
        z = np.full(n, -0.0)
        assert np.signbit(sums.pairwise_sum(z, 0, n)) and not np.signbit(0.0 + sums.pairwise_sum(z, 0, n))
        assert not np.signbit(z.sum())


def test_compiled_statistics_equal_numpy():
    """Count, mean, std, SEM and median per row, NaN and ±inf ignored, rows with no finite value,
    ties, odd and even counts, and the pair metrics they are taken of."""
    rng = np.random.default_rng(12)
    for trial in range(80):
        R, m = int(rng.integers(1, 5)), int(rng.integers(1, 420))
        v = rng.exponential(3.0, (R, m)) if trial % 3 else rng.integers(0, 6, (R, m)).astype(float)
        v[rng.random(v.shape) < rng.uniform(0, 0.6)] = np.nan
        v[rng.random(v.shape) < 0.05] = np.inf
        v[rng.random(v.shape) < 0.02] = -np.inf
        v[0, : m // 2 if trial % 4 else m] = np.nan  # a row with no value at all, now and then
        layout = (v, np.asfortranarray(v), v[:, ::-1])[trial % 3]  # numpy sums in the order of the layout
        for keys in (STATS, ("mean",), ("median",), ("count",), ("median", "sem")):
            got, want = stats(layout, keys), numpy_stats(layout, keys)
            assert list(got) == list(want)
            for k in keys:
                assert got[k].dtype == want[k].dtype
                np.testing.assert_array_equal(got[k], want[k], err_msg=f"{k} {trial}")
    for trial in range(20):
        R, n = int(rng.integers(1, 4)), int(rng.integers(2, 22))
        x = rng.normal(0.0, 10.0, (R, n, 2))
        x[:, 1] = x[:, 0] if trial % 2 else x[:, 1]  # coincident particles
        est = x[:, None, :, :] - x[:, :, None, :] + rng.normal(0.0, 1.0, (R, n, n, 2))
        est[rng.random((R, n, n)) < 0.05] = np.nan
        valid = rng.random((R, n, n)) < 0.6
        for got, want in zip(metric_kernels.distance_errors(x, est, valid), numpy_distance_errors(x, est, valid)):
            np.testing.assert_array_equal(got, want)
        np.testing.assert_array_equal(pair_distances(x), numpy_pair_distances(x))
        kind = rng.integers(0, 6, (R, n, n)).astype(np.int8)
        valid = valid & (trial % 5 > 0)  # now and then no valid pair at all
        np.testing.assert_array_equal(dead_reckoning_share(kind, valid), numpy_dead_reckoning_share(kind, valid))
        for k, v in stats(pair_distances(x)).items():
            np.testing.assert_array_equal(v, numpy_stats(numpy_pair_distances(x))[k], err_msg=k)


@pytest.mark.parametrize("kw", [
    dict(selection="css", errors="low"),
    dict(selection="css", errors="low", local_best="pbest", pbest_shift="measured", fitness_noise=5.0),
    dict(selection="css", errors="high", entry_policy="geometric_random", neighbourhood="radius"),
    dict(selection="rts", errors="high", neighbourhood="random"),
    dict(selection="akcan", errors="low", particles=9),
    dict(selection="akcan", errors="high", neighbourhood="random"),
    dict(selection="rts", errors="low", rts_triangle="best", rts_prefer_geometric=True),
    dict(selection="perfect", errors="none", motion="random_walk"),
], ids=["css", "css-pbest-noise", "css-entry-radius", "rts", "akcan", "akcan-random", "rts-best-geometric",
        "perfect-walk"])
def test_whole_runs_equal_the_numpy_localiser(kw, monkeypatch):
    kw = {"particles": 12, **kw}
    compiled = SLOSwarm(runs=3, seed=5, **kw)
    compiled_rows = [compiled.info().series()] + [compiled.step().series() for _ in range(12)]
    monkeypatch.setattr(beliefs_module, "localise", numpy_localise)
    monkeypatch.setattr(beliefs_module, "pair_candidates", lambda *a: numpy_localise(
        *a[:4], delta_cos=a[4], delta_v=a[5], literal_eq_3_1=a[6]).candidates)
    monkeypatch.setattr(neighbourhoods_module.kernels, "distances", numpy_distances)
    monkeypatch.setattr(neighbourhoods_module.kernels, "nearest", numpy_nearest)
    monkeypatch.setattr(select_kernels, "rts", numpy_rts)
    monkeypatch.setattr(select_kernels, "akcan", numpy_akcan)
    monkeypatch.setattr(beliefs_module, "carry", numpy_carry)
    monkeypatch.setattr(slo_swarm_module, "draw", numpy_draw)
    monkeypatch.setattr(slo_swarm_module, "local_best", numpy_local_best)
    monkeypatch.setattr(slo_swarm_module, "local_velocity", lambda law, *a: law.local_velocity(*a))
    monkeypatch.setattr(beliefs_module, "measure_ranges", numpy_measure_ranges)
    monkeypatch.setattr(beliefs_module, "measure_odometry", numpy_measure_odometry)
    monkeypatch.setattr(metrics_module, "stats", numpy_stats)
    monkeypatch.setattr(metrics_module, "distance_errors", numpy_distance_errors)
    monkeypatch.setattr(metrics_module, "pair_distances", numpy_pair_distances)
    monkeypatch.setattr(metrics_module, "dead_reckoning_share", numpy_dead_reckoning_share)
    reference = SLOSwarm(runs=3, seed=5, **kw)
    rows = [reference.info().series()] + [reference.step().series() for _ in range(12)]
    for got, want in zip(compiled_rows, rows):
        assert got.keys() == want.keys()
        for name in got:
            np.testing.assert_array_equal(got[name], want[name], err_msg=name)
    for name in ("range", "odometry", "pso"):
        for g, h in zip(compiled.streams[name], reference.streams[name]):
            assert g.bit_generator.state == h.bit_generator.state
    a, b = compiled.state, reference.state
    for name in ("x", "u", "P", "est", "kind", "flag", "adjacency"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name), err_msg=name)
    for name in CANDIDATE_FIELDS:
        np.testing.assert_array_equal(getattr(a.candidates, name), getattr(b.candidates, name), err_msg=name)


def test_metrics_read_late_equal_metrics_worked_out_at_once():
    sw = SLOSwarm(runs=4, seed=2, particles=10, selection="rts", errors="high")
    infos, eager = [], []
    for _ in range(6):
        info = sw.step()
        s = sw.state
        err = pair_errors(s.x, s.est, s.valid)  # as every generation used to record them
        eager.append({"e_abs": stats(err["abs"]), "e_rel": stats(err["rel"]), "e_ang": stats(err["ang"]),
                      "distance": stats(pair_distances(s.x)), "dead_reckoning": dead_reckoning_share(s.kind, s.valid),
                      "round_trip": stats(round_trip_errors(s.est, s.adjacency))["mean"]})
        infos.append(info)
    for info, want in zip(infos, eager):  # read only now, after the swarm moved on
        for name in ("e_abs", "e_rel", "e_ang", "distance"):
            for k, v in want[name].items():
                np.testing.assert_array_equal(getattr(info, name)[k], v)
        np.testing.assert_array_equal(info.dead_reckoning, want["dead_reckoning"])
        np.testing.assert_array_equal(info.round_trip, want["round_trip"])
        some = info.series(["e_abs_mean", "distance_median", "best_fitness"])
        assert list(some) == ["best_fitness", "e_abs_mean", "distance_median"]
        full = info.series()
        for name, v in some.items():
            np.testing.assert_array_equal(v, full[name])


def test_css_candidate_sets_worked_out_when_read_are_the_steps_own():
    sw = SLOSwarm(runs=2, seed=9, particles=8, selection="css", errors="high")
    sw.step()
    b0 = sw.state.beliefs
    sw.step()
    b1 = sw.state.beliefs
    assert callable(b1.pairs)  # CSS did not keep them
    want = numpy_localise(b0.ranges, b1.ranges, b1.odometry, b0.est, delta_cos=0.03, delta_v=0.03,
                          literal_eq_3_1=False).candidates
    for name in CANDIDATE_FIELDS:
        np.testing.assert_array_equal(getattr(b1.candidates, name), getattr(want, name), err_msg=name)
    np.testing.assert_array_equal(b1.flag, want.flag)


def _bytes(a) -> bytes:
    return np.ascontiguousarray(a).tobytes()


@pytest.mark.parametrize("density", [0.15, 0.4, 0.9])
def test_compiled_rts_and_akcan_equal_numpy(density):
    """On random candidate sets (singular pairs included), random neighbourhoods (not symmetric)
    and ranges with failures, to the byte: estimates, kinds, RTS closing vertices and e_r."""
    rng = np.random.default_rng(int(density * 100))
    for trial in range(4):
        R, n = 3, int(rng.integers(3, 16))
        d0, d1, v, prev = _pairs(rng, R, n)
        loc = kernels.localise(d0, d1, v, prev, delta_cos=0.03, delta_v=0.03, literal_eq_3_1=False)
        adjacency = rng.random((R, n, n)) < density
        idx = np.arange(n)
        adjacency[:, idx, idx] = False
        ranges = np.abs(d1) * (rng.random((R, n, n)) > 0.1)
        if trial == 3:  # ties and non-finite values in the sets
            loc.candidates.points[..., :2, :] = np.round(loc.candidates.points[..., :2, :])
            loc.candidates.points[rng.random((R, n, n)) < 0.03] = np.nan
        c, base = loc.candidates, (loc.est, loc.kind)
        got, want = select_kernels.akcan(c.points, c.mask, adjacency, ranges, base), selection.akcan(
            c, adjacency, ranges, base)
        assert _bytes(got[0]) == _bytes(want[0]) and _bytes(got[1]) == _bytes(want[1])
        for triangle, prefer, tol in (("first", False, 0.0), ("best", False, 0.0), ("first", True, 5.0),
                                      ("best", True, 1.0)):
            got = select_kernels.rts(c.points, c.mask, adjacency, base, triangle, prefer, tol)
            want = selection.rts(c, adjacency, base, triangle, prefer, tol)
            for name, g in zip(("est", "kind", "triangle", "round_trip"), got):
                assert _bytes(g) == _bytes(getattr(want, name)), (name, triangle, prefer, trial)
