"""Velocity laws: known answers and the speed/acceleration bounds of Adapted PSO."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from shoal.engine.pso.laws import Law, adapted_velocity, squash, standard_velocity


def test_sgn_keeps_zero_at_zero():
    assert np.array_equal(squash(np.array([-2.0, 0.0, 3.0])), [-1.0, 0.0, 1.0])


@pytest.mark.parametrize("kind", ["tanh", "logistic"])
def test_smooth_squash_is_sgn_far_and_linear_near(kind):
    far = squash(np.array([-50.0, 50.0]), kind, width=1.0)
    assert np.allclose(far, [-1.0, 1.0])
    near = squash(np.array([1e-4]), kind, width=1.0)[0]
    assert 0 < near < 1e-3  # proportional, not saturated
    assert squash(np.array([0.0]), kind)[0] == 0.0
    huge = squash(np.array([1e308, -1e308]), kind, width=1e-3)
    assert np.all(np.isfinite(huge)) and np.allclose(huge, [1.0, -1.0])


def test_squash_rejects_bad_width():
    with pytest.raises(ValueError, match="width"):
        squash(np.ones(2), "tanh", width=0.0)


def test_standard_velocity_known_answer():
    u = np.array([[[1.0, -1.0]]])
    g = np.array([[[[2.0, 4.0]]], [[[-6.0, 0.0]]]])  # y − x, y_g − x
    r = np.full_like(g, 0.5)
    out = standard_velocity(u, g, np.array([1.0, 2.0]), 0.5, r)
    # 0.5*u + 1*0.5*g1 + 2*0.5*g2
    assert np.allclose(out, [[[0.5 + 1.0 - 6.0, -0.5 + 2.0 + 0.0]]])


def test_adapted_velocity_uses_only_the_sign():
    u = np.zeros((1, 1, 2))
    g = np.array([[[[1e6, -1e-6]]], [[[3.0, 0.0]]]])
    r = np.ones_like(g)
    out = adapted_velocity(u, g, np.array([1.0, 2.0]), 0.7, r)
    assert np.allclose(out, [[[1.0 + 2.0, -1.0 + 0.0]]])


def test_per_robot_coefficients_broadcast():
    u = np.zeros((2, 3, 2))
    g = np.ones((2, 2, 3, 2))
    r = np.ones_like(g)
    c = np.arange(12, dtype=float).reshape(2, 2, 3)  # (n, R, N)
    out = adapted_velocity(u, g, c, np.zeros((2, 3)), r)
    assert np.allclose(out[..., 0], c.sum(axis=0))


def test_position_update_uses_new_velocity_and_dt():
    x, u = np.zeros((1, 1, 2)), np.ones((1, 1, 2))
    assert np.allclose(Law("adapted-sgn").position(x, u, 0.2), 0.2)  # [3.10]
    assert np.allclose(Law("standard").position(x, u, 0.2), 1.0)  # [2.2]


bounded = st.floats(-1e3, 1e3, allow_nan=False, allow_infinity=False)


@settings(max_examples=300, deadline=None)
@given(
    law=st.sampled_from(["adapted-sgn", "adapted-tanh", "adapted-logistic"]),
    omega=st.floats(0.0, 0.999),
    c1=st.floats(0.0, 50.0),
    c2=st.floats(0.0, 50.0),
    dt=st.floats(1e-3, 10.0),
    frac=arrays(np.float64, (1, 4, 2), elements=st.floats(-1.0, 1.0)),
    g=arrays(np.float64, (2, 1, 4, 2), elements=bounded),
    r=arrays(np.float64, (2, 1, 4, 2), elements=st.floats(0.0, 1.0)),
)
def test_adapted_speed_and_acceleration_stay_within_limits(law, omega, c1, c2, dt, frac, g, r):
    """For any state with |u_j| ≤ U_j: |u'_j| ≤ ĉ/(1−ω) [3.26], speed grows at most
    A+_j = ĉ/Δt [3.27] and changes at most A−_j = 2ĉ/Δt [3.28]."""
    c_hat = c1 + c2
    U_j = c_hat / (1.0 - omega)
    u = frac * U_j
    new = Law(law, smooth_width=0.5).velocity(u, g, np.array([c1, c2]), omega, r)
    tol = 1e-9 * (1.0 + U_j)
    assert np.all(np.abs(new) <= U_j + tol)
    accel = (new - u) / dt
    assert np.all(np.abs(accel) <= 2.0 * c_hat / dt + tol / dt)
    speed_gain = (np.abs(new) - np.abs(u)) / dt
    assert np.all(speed_gain <= c_hat / dt + tol / dt)


def test_standard_pso_has_no_speed_limit():
    """Standard PSO steps grow with the distance to the bests (Rossides §3.1, p. 59): the motivation
    of Adapted PSO (§3.2, p. 62)."""
    u = np.zeros((1, 1, 1))
    g = np.full((2, 1, 1, 1), 1e4)
    new = Law("standard").velocity(u, g, np.array([1.5, 1.5]), 0.7, np.ones_like(g))
    assert new[0, 0, 0] == pytest.approx(3e4)


@settings(max_examples=200, deadline=None)
@given(
    n=st.integers(1, 6),
    omega=st.floats(0.0, 0.99),
    seed=st.integers(0, 2**32 - 1),
    frac=st.floats(-1.0, 1.0),
)
def test_generalised_law_bound_uses_the_sum_of_all_terms(n, omega, seed, frac):
    """[3.36]–[3.38]: with n accelerating terms the bound is ĉ/(1−ω) with ĉ = Σ c_n, and it
    is tight: all pushes at full strength in one direction reach it exactly from U_j."""
    rng = np.random.default_rng(seed)
    c = rng.uniform(0.0, 5.0, n)
    U_j = c.sum() / (1.0 - omega)
    u = np.full((1, 3, 2), frac * U_j)
    g = rng.normal(size=(n, 1, 3, 2))
    new = adapted_velocity(u, g, c, omega, rng.random(g.shape))
    assert np.all(np.abs(new) <= U_j * (1 + 1e-12) + 1e-12)
    top = adapted_velocity(np.full((1, 1, 1), U_j), np.ones((n, 1, 1, 1)), c, omega, np.ones((n, 1, 1, 1)))
    assert top[0, 0, 0] == pytest.approx(U_j)
