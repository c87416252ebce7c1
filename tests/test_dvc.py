"""DVC coefficient policies (Ch. 4 Algorithm 1, Ch. 5 Algorithm 2): known answers and bounds."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from shoal.engine.pso.laws import adapted_velocity
from shoal.engine.robots.dvc import TABLE_4_1, constant_rpso, dvc_nonomni, dvc_omni, w_max
from shoal.engine.robots.laws import nonomni_velocity

RANGE = 3.0
SHAPE = (2, 3)
gaps = arrays(float, SHAPE + (6,), elements=st.floats(0.0, RANGE))
unit = st.floats(0.0, 1.0)
signs = st.sampled_from([-1.0, 0.0, 1.0])
coef = st.floats(0.05, 1.0)


# --------------------------------------------------------------------------- omni


def test_open_space_decodes_table_4_1():
    omega, c = dvc_omni(np.full((1, 1, 6), RANGE), alpha=0.9, beta=0.9, dt=1.0)
    assert c.shape == (3, 1, 1) and omega.shape == (1, 1)
    assert c.sum() == pytest.approx(0.9 * 2.7 / math.sqrt(2))
    assert c.sum() == pytest.approx(1.7183, abs=1e-4)
    assert c[2, 0, 0] == 0.0 and c[0, 0, 0] == c[1, 0, 0]
    assert omega[0, 0] == pytest.approx(0.1)


def test_table_4_1_cases_share_one_budget_with_ratios_2_1_half():
    for name, ratio in [("c3-high", 2.0), ("c3-equal", 1.0), ("c3-low", 0.5)]:
        case = TABLE_4_1[name]
        assert case["c1"] + case["c2"] + case["c3"] == pytest.approx(1.7183, abs=2e-4)
        assert case["c3"] / (case["c1"] + case["c2"]) == pytest.approx(ratio, rel=1e-3)
        assert case["omega"] == pytest.approx(0.1)


def test_constant_rpso_shapes():
    omega, c = constant_rpso(**TABLE_4_1["c3-high"], shape=SHAPE)
    assert omega.shape == SHAPE and c.shape == (3,) + SHAPE
    assert np.all(c[2] == 1.1455) and np.all(omega == 0.1)
    c[0, 0, 0] = 9.0  # writable copy, not a broadcast view
    assert c[0, 1, 1] == 0.2864


def test_one_obstacle_known_answer():
    gap = np.array([[[1.0, 3.0, 3.0, 3.0, 2.0, 3.0]]])
    _, c = dvc_omni(gap, alpha=0.9, beta=0.9, dt=1.0)
    k = 0.81 / math.sqrt(2)
    assert np.allclose(c[:, 0, 0], [k / 2, k / 2, k * (2.0 - 1.0)])


@given(gaps, st.floats(0.1, 1.0), st.floats(0.1, 1.0), st.floats(0.05, 2.0), unit)
def test_omni_closed_forms_and_signs(gap, alpha, beta, dt, share):
    omega, c = dvc_omni(gap, alpha=alpha, beta=beta, dt=dt, c1_share=share)
    s = np.sort(gap, axis=-1)
    k = alpha * beta / (dt * math.sqrt(2))
    assert np.all(np.isfinite(c)) and np.all(c >= 0)
    assert np.allclose(c[0] + c[1], k * s[..., 0])
    assert np.allclose(c[2], k * (s[..., 1] - s[..., 0]))
    assert np.allclose(c.sum(axis=0), k * s[..., 1])  # ĉ = β α ν_2/√2
    assert np.allclose(c[0], share * (c[0] + c[1]))
    assert np.allclose(omega, 1.0 - beta)


@given(gaps)
def test_c3_is_zero_exactly_when_two_nearest_gaps_are_equal(gap):
    gap = gap.copy()
    gap[0, 0, 1] = gap[0, 0, 4] = 0.5 * min(gap[0, 0].min(), 1.0)  # tie for nearest
    _, c = dvc_omni(gap)
    assert c[2, 0, 0] == 0.0
    s = np.sort(gap, axis=-1)
    assert np.array_equal(c[2] == 0.0, s[..., 0] == s[..., 1])


@settings(max_examples=200)
@given(
    gaps,
    arrays(float, SHAPE + (2,), elements=st.floats(-1.0, 1.0)),
    arrays(float, (3,) + SHAPE + (2,), elements=unit),
    arrays(float, (3,) + SHAPE + (2,), elements=signs),
    st.floats(0.1, 0.99),
    st.floats(0.1, 1.0),
    st.floats(0.1, 2.0),
)
def test_dvc_one_step_displacement_bounds(gap, u_dir, r, sgn, alpha, beta, dt):
    """What DVC provably guarantees in one step, from any prior velocity u.

    Per component the attraction terms add at most c1 + c2, so their vector length is
    ≤ √2 (c1 + c2) = αβ s_1/Δt, and all three terms ≤ √2 ĉ = αβ s_2/Δt. Hence

        Δt |ω u + attraction| ≤ αβ s_1 + ω Δt |u|   (< s_1 + ω Δt |u| when s_1 > 0),
        Δt |u_new|            ≤ αβ s_2 + ω Δt |u|,

    and from rest (u = 0) the step is ≤ α s_1 resp. ≤ α s_2. The thesis' "never reaches
    the nearest body within one step" is approximate (docs/readings.md, "The DVC guard (ours)"): the carried
    ω u (up to (1 − β)·αR_s/Δt) is not shrunk when s_1 drops, other robots move too, and
    sgn(F_t) points only within 45° of the push. So only these bounds are asserted.
    """
    omega, c = dvc_omni(gap, alpha=alpha, beta=beta, dt=dt)
    s = np.sort(gap, axis=-1)
    u = u_dir * (alpha * RANGE / (dt * math.sqrt(2)))  # |u_j| ≤ open-space limit
    carried = (omega * np.linalg.norm(u, axis=-1)) * dt
    attract = adapted_velocity(u, sgn[:2], c[:2], omega, r[:2])
    full = adapted_velocity(u, sgn, c, omega, r)
    tol = 1e-9
    assert np.all(dt * np.linalg.norm(attract, axis=-1) <= alpha * beta * s[..., 0] + carried + tol)
    assert np.all(dt * np.linalg.norm(full, axis=-1) <= alpha * beta * s[..., 1] + carried + tol)
    rest = np.zeros_like(u)
    from_rest_att = dt * np.linalg.norm(adapted_velocity(rest, sgn[:2], c[:2], omega, r[:2]), axis=-1)
    from_rest = dt * np.linalg.norm(adapted_velocity(rest, sgn, c, omega, r), axis=-1)
    assert np.all(from_rest_att <= alpha * s[..., 0] + tol)
    assert np.all(from_rest <= alpha * s[..., 1] + tol)
    hit = s[..., 0] > 1e-6  # strict margin, away from float absorption by `carried`
    assert np.all((dt * np.linalg.norm(attract, axis=-1) < s[..., 0] + carried)[hit])


def test_thesis_guarantee_is_only_approximate():
    """Carried velocity can overshoot a nearest body that just appeared (Algorithm 1, Rossides p. 90)."""
    gap = np.array([[[0.1, 3.0, 3.0, 3.0, 3.0, 3.0]]])
    omega, c = dvc_omni(gap)
    u = np.full((1, 1, 2), 0.9 * RANGE / math.sqrt(2))  # open-space top speed 2.7 m/s
    out = adapted_velocity(u, np.ones((3, 1, 1, 2)), c, omega, np.ones((3, 1, 1, 2)))
    assert np.linalg.norm(out) * 1.0 > 0.1  # would cover more than s_1 in Δt = 1 s


def test_omni_rejects_bad_parameters():
    with pytest.raises(ValueError, match="beta"):
        dvc_omni(np.ones((1, 1, 6)), beta=1.5)
    with pytest.raises(ValueError, match="two"):
        dvc_omni(np.ones((1, 1, 1)))


# --------------------------------------------------------------------------- w_max


def test_w_max_cap_binds_for_thesis_robot():
    assert w_max(3.0, 1.0) == pytest.approx(math.pi / 2)
    assert w_max(2.0, 1.0) == pytest.approx(math.pi / 2)


def test_w_max_readings_below_cap():
    assert w_max(1.0, 0.1) == pytest.approx(math.sqrt(2 / math.pi))
    assert w_max(1.0, 0.1, inertia="disc", body_radius=0.5) == pytest.approx(2 * math.sqrt(2))
    with pytest.raises(ValueError, match="body_radius"):
        w_max(1.0, 0.1, inertia="disc")


# --------------------------------------------------------------------------- non-omni

W_MAX = math.pi / 2


def test_nonomni_open_space_known_answer():
    omega, c = dvc_nonomni(np.full((1, 1, 6), RANGE), w_max=W_MAX)
    assert np.allclose(c[:, 0, 0], [0.45 * W_MAX, 0.45 * W_MAX, 0.0, 0.0, 0.9 * 2.7])
    assert omega[0, 0] == pytest.approx(0.1)
    _, c = dvc_nonomni(np.full((1, 1, 6), RANGE), w_max=W_MAX, v_max=2.0)
    assert c[4, 0, 0] == pytest.approx(0.9 * 2.0)


def test_nonomni_sectors():
    gap = np.full((1, 1, 6), RANGE)
    gap[0, 0, 0] = 1.5  # right, behind: turns left (c4) but does not slow v
    _, c = dvc_nonomni(gap, w_max=W_MAX)
    assert c[3, 0, 0] == pytest.approx(0.9 * 0.5 * W_MAX) and c[2, 0, 0] == 0.0
    assert c[4, 0, 0] == pytest.approx(0.9 * 2.7)
    gap[0, 0, 3] = 0.3  # left, front: turns right (c3) and slows v
    _, c = dvc_nonomni(gap, w_max=W_MAX)
    assert c[2, 0, 0] == pytest.approx(0.9 * 0.9 * W_MAX)
    assert c[4, 0, 0] == pytest.approx(0.9 * 0.9 * 0.3)


@given(gaps, st.floats(0.1, 1.0), st.floats(0.1, 1.0), unit, st.floats(0.1, 3.0))
def test_nonomni_steady_state_turn_bounds(gap, alpha, beta, share, wm):
    omega, c = dvc_nonomni(gap, alpha=alpha, beta=beta, c1_share=share, w_max=wm)
    assert np.all(np.isfinite(c)) and np.all(c >= 0)
    tol = 1e-9
    assert np.all((c[0] + c[1] + c[3]) / (1 - omega) <= wm + tol)  # left-turn bound
    assert np.all((c[0] + c[1] + c[2]) / (1 - omega) <= wm + tol)  # right-turn bound


@given(gaps, st.floats(0.0, RANGE))
def test_equal_side_clearances_give_equal_turn_budgets(gap, clearance):
    gap = gap.copy()
    gap[..., :3] = np.maximum(gap[..., :3], clearance)
    gap[..., 3:] = np.maximum(gap[..., 3:], clearance)
    gap[..., 1] = gap[..., 4] = clearance
    _, c = dvc_nonomni(gap, w_max=W_MAX)
    assert np.array_equal(c[2], c[3])


@settings(max_examples=200)
@given(
    gaps,
    arrays(float, SHAPE + (2,), elements=st.floats(-1.0, 1.0)),
    arrays(float, SHAPE + (2,), elements=st.floats(-5.0, 5.0)),
    arrays(float, SHAPE + (2,), elements=st.floats(-5.0, 5.0)),
    arrays(float, (5,) + SHAPE, elements=unit),
    st.floats(0.1, 1.0),
)
def test_nonomni_step_keeps_v_nonnegative_and_w_within_limit(gap, state, yt, ygt, r, beta):
    """|w| ≤ w_max and 0 ≤ v ≤ αR/Δt are invariant: ω·limit + β·limit = limit."""
    omega, c = dvc_nonomni(gap, beta=beta, w_max=W_MAX)
    vw = np.stack([np.abs(state[..., 0]) * 0.9 * RANGE, state[..., 1] * W_MAX], axis=-1)
    out = nonomni_velocity(vw, yt, ygt, c, omega, r)
    assert np.all(out[..., 0] >= 0)
    assert np.all(out[..., 0] <= 0.9 * RANGE + 1e-9)
    assert np.all(np.abs(out[..., 1]) <= W_MAX + 1e-9)


def test_nonomni_rejects_wrong_sector_count():
    with pytest.raises(ValueError, match="6"):
        dvc_nonomni(np.ones((1, 1, 5)), w_max=1.0)
