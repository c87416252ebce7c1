"""SPSO 2011 (Mai §2.1.1, §3.6): global and robot-centred forms, hypersphere sampling."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from shoal.engine.pso.spso2011 import C_SPSO, OMEGA_SPSO, SPSO2011, SPSODraws, draw, sample_hypersphere


def test_defaults():
    assert OMEGA_SPSO == pytest.approx(0.721348, abs=1e-6) and C_SPSO == pytest.approx(1.193147, abs=1e-6)
    p = SPSO2011()
    assert (p.c3, p.c4, p.radial, p.spso_self_best_halving) == (1.0, 0.0, "uniform_radius", False)


@settings(max_examples=50, deadline=None)
@given(seed=st.integers(0, 2**31), halving=st.booleans(), c3=st.floats(0.0, 2.0), c4=st.floats(0.0, 3.0))
def test_global_form_equals_local_form(seed, halving, c3, c4):
    """[2.1]–[2.5] with the "− X" of docs/readings.md and [3.10]–[3.12] give the same move for X ≡ 0 in i's frame."""
    rng = np.random.default_rng(seed)
    x, v, p, l = (rng.uniform(-50, 50, (2, 6, 2)) for _ in range(4))
    d = draw([np.random.default_rng(seed + 1), np.random.default_rng(seed + 2)], 6)
    own = rng.random((2, 6)) < 0.3
    law = SPSO2011(c3=c3, c4=c4, spso_self_best_halving=halving)
    glob = law.global_velocity(x, v, p, l, d, own)
    loc = law.local_velocity(v, p - x, l - x, d, own)
    assert np.allclose(glob, loc, atol=1e-9)


def test_hypersphere_stays_inside_and_has_the_right_radial_law():
    rng = np.random.default_rng(3)
    n = 20000
    g = rng.normal(size=(n, 2))
    rho = rng.random(n)
    centre, r = np.array([2.0, -1.0]), 3.0
    for radial, mean in (("uniform_radius", 0.5), ("uniform_area", 2 / 3)):
        h = sample_hypersphere(centre, np.full(n, r), g, rho, radial)
        dist = np.linalg.norm(h - centre, axis=-1) / r
        assert dist.max() <= 1.0 + 1e-12 and dist.mean() == pytest.approx(mean, abs=0.01)
    angle = np.arctan2(g[:, 1], g[:, 0])
    assert np.histogram(angle, bins=8)[0].min() > 0.9 * n / 8  # uniform direction
    assert np.array_equal(sample_hypersphere(centre, 0.0, g[0], rho[0]), centre)
    assert np.array_equal(sample_hypersphere(centre, 1.0, np.zeros(2), 0.5), centre)  # no NaN


@pytest.mark.parametrize("radial", ["uniform_radius", "uniform_area"])
def test_both_hypersphere_laws_reach_the_engine_and_converge_on_sphere(radial):
    """slo.radial: the default draws the radius uniformly (SPSO 2011 reference code), the
    option uniformly over the disc; both run SLO-PSO to a tiny Sphere value without error."""
    from shoal.presets.build import build
    from shoal.presets.io import load

    sw = build(load("slo-pso-sphere", [f"slo.radial={radial}"]), runs=2)
    assert sw.spso.radial == radial and sw.config.radial == radial
    assert load("slo-pso-sphere").slo.radial == "uniform_radius"
    best = sw.run(300)["best_so_far"][-1]
    assert np.all(best < 1e-20)


def test_local_centre_uses_one_third_unless_halving():
    ones = SPSODraws(np.ones((1, 2)), np.ones((1, 2)), np.array([[1.0, 0.0]]), np.zeros(1))
    p, l = np.array([[3.0, 0.0]]), np.array([[0.0, 6.0]])
    thesis = SPSO2011(inertia=0.0, c1=1.0, c2=1.0)
    assert np.allclose(thesis.local_velocity(np.zeros((1, 2)), p, l, ones), [[1.0, 2.0]])  # [3.10]
    spso = SPSO2011(inertia=0.0, c1=1.0, c2=1.0, spso_self_best_halving=True)
    assert np.allclose(spso.local_velocity(np.zeros((1, 2)), p, 0 * l, ones, np.array([True])), [[1.5, 0.0]])
    v = np.array([[2.0, -2.0]])
    assert np.allclose(SPSO2011(inertia=0.5, c1=0.0, c2=0.0).local_velocity(v, p, l, ones), 0.5 * v)
