"""The compiled SLO pair step and neighbour search against their numpy references, bit for
bit (random and singular pairs, whole seeded runs of every selection), and the metrics and
candidate sets worked out when read equal to those worked out at once."""

from __future__ import annotations

import numpy as np
import pytest

import shoal.engine.slo.beliefs as beliefs_module
import shoal.engine.slo.neighbourhoods as neighbourhoods_module
from shoal.engine.kinds.slo_swarm import SLOSwarm
from shoal.engine.slo import kernels
from shoal.engine.slo.candidates import candidates
from shoal.engine.slo.metrics import dead_reckoning_share, pair_distances, pair_errors, round_trip_errors, stats
from shoal.engine.slo.selection import css

CANDIDATE_FIELDS = ("points", "mask", "flag", "cos_alpha", "thinness")


def numpy_localise(d0, d1, v, prev, *, delta_cos, delta_v, literal_eq_3_1, prediction_weight=0.5, entry=None,
                   coin=None, candidates_=True, **kw):
    """The numpy reference of :func:`kernels.localise`: candidates [3.1]–[3.6] and css [3.7]."""
    c = candidates(d0, d1, v[:, None, :, :] - v[:, :, None, :], prev, delta_cos, delta_v, literal_eq_3_1)
    est, kind = css(c, prediction_weight, entry, coin)
    return kernels.Localised(est, kind, c.flag, c if kw.get("candidates", candidates_) else None)


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


@pytest.mark.parametrize("kw", [
    dict(selection="css", errors="low"),
    dict(selection="css", errors="high", entry_policy="geometric_random", neighbourhood="radius"),
    dict(selection="rts", errors="high", neighbourhood="random"),
    dict(selection="akcan", errors="low", particles=9),
    dict(selection="perfect", errors="none", motion="random_walk"),
], ids=["css", "css-entry-radius", "rts", "akcan", "perfect-walk"])
def test_whole_runs_equal_the_numpy_localiser(kw, monkeypatch):
    kw = {"particles": 12, **kw}
    compiled = SLOSwarm(runs=3, seed=5, **kw)
    compiled_rows = [compiled.info().series()] + [compiled.step().series() for _ in range(12)]
    monkeypatch.setattr(beliefs_module, "localise", numpy_localise)
    monkeypatch.setattr(beliefs_module, "pair_candidates", lambda *a: numpy_localise(
        *a[:4], delta_cos=a[4], delta_v=a[5], literal_eq_3_1=a[6]).candidates)
    monkeypatch.setattr(neighbourhoods_module.kernels, "distances", numpy_distances)
    monkeypatch.setattr(neighbourhoods_module.kernels, "nearest", numpy_nearest)
    reference = SLOSwarm(runs=3, seed=5, **kw)
    rows = [reference.info().series()] + [reference.step().series() for _ in range(12)]
    for got, want in zip(compiled_rows, rows):
        assert got.keys() == want.keys()
        for name in got:
            np.testing.assert_array_equal(got[name], want[name], err_msg=name)
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
