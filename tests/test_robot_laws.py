"""Ch. 4–5 laws: RPSO, robot frame, non-omni controller, energy, arcs and mecanum limits."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from shoal.engine.pso.laws import adapted_velocity
from shoal.engine.robots.laws import (
    adapted_rpso_velocity,
    arc_pose_update,
    energy_limit,
    mecanum_body,
    mecanum_limit,
    mecanum_wheels,
    min_turning_radius,
    nonomni_velocity,
    robot_centred_velocity,
    rotational_energy_factor,
    rpso_velocity,
    to_body,
    to_world,
    wrap_angle,
)

SHAPE = (2, 3)
finite = st.floats(-50.0, 50.0)
angles = st.floats(-10.0, 10.0)
vecs = arrays(float, SHAPE + (2,), elements=finite)
heads = arrays(float, SHAPE, elements=angles)


# --------------------------------------------------------------------------- RPSO


def test_rpso_known_answer_unbounded():
    u = np.array([[[1.0, 0.0]]])
    gp, gg, F = (np.array([[[2.0, -2.0]]]), np.array([[[0.0, 4.0]]]), np.array([[[10.0, 0.0]]]))
    r = np.full((3, 1, 1, 2), 0.5)
    out = rpso_velocity(u, gp, gg, F, np.array([1.0, 1.0, 2.0]), 0.1, r)
    assert np.allclose(out, [[[0.1 + 1.0 + 0.0 + 10.0, -1.0 + 2.0]]])  # [4.2]


@given(vecs, vecs, vecs, vecs, arrays(float, (3,) + SHAPE + (2,), elements=st.floats(0, 1)))
def test_rpso_clipping_keeps_direction(u, gp, gg, F, r):
    c = np.array([0.4296, 0.4296, 0.8591])
    raw = rpso_velocity(u, gp, gg, F, c, 0.1, r)
    out = rpso_velocity(u, gp, gg, F, c, 0.1, r, v_max=3.0)
    speed = np.linalg.norm(out, axis=-1)
    assert np.all(speed <= 3.0 + 1e-9)
    cross = out[..., 0] * raw[..., 1] - out[..., 1] * raw[..., 0]
    assert np.allclose(cross, 0.0, atol=1e-6 * (1 + np.linalg.norm(raw, axis=-1)))
    assert np.all(np.sum(out * raw, axis=-1) >= 0)
    slow = np.linalg.norm(raw, axis=-1) <= 3.0
    assert np.array_equal(out[slow], raw[slow])


def test_adapted_rpso_is_generalised_adapted_with_force_term():
    rng = np.random.default_rng(1)
    u, gp, gg, F = (rng.normal(size=SHAPE + (2,)) for _ in range(4))
    r = rng.random((3,) + SHAPE + (2,))
    c = rng.random((3,) + SHAPE)
    out = adapted_rpso_velocity(u, gp, gg, F * 1e6, c, 0.1, r)
    assert np.allclose(out, adapted_velocity(u, np.stack([gp, gg, F]), c, 0.1, r))  # [4.5]


# --------------------------------------------------------------------------- frames


def test_body_frame_known_answers():
    # heading π/2 (facing +y): a point straight ahead in the world is +x in the body frame
    assert np.allclose(to_body(np.array([[[0.0, 2.0]]]), np.array([[math.pi / 2]])), [[[2.0, 0.0]]])
    # heading 0: a point at +y is on the left (positive lateral)
    assert np.allclose(to_body(np.array([[[0.0, 1.0]]]), np.zeros((1, 1))), [[[0.0, 1.0]]])


@given(vecs, heads)
def test_body_world_are_inverse_rotations(v, h):
    b = to_body(v, h)
    assert np.allclose(to_world(b, h), v, atol=1e-9)
    assert np.allclose(np.linalg.norm(b, axis=-1), np.linalg.norm(v, axis=-1))


@given(arrays(float, (7,), elements=st.floats(-1e3, 1e3)))
def test_wrap_angle_range(a):
    w = wrap_angle(a)
    assert np.all(w > -math.pi) and np.all(w <= math.pi)
    assert np.allclose(np.cos(w), np.cos(a), atol=1e-9)
    assert np.allclose(np.sin(w), np.sin(a), atol=1e-9)
    assert wrap_angle(-math.pi) == pytest.approx(math.pi)


# --------------------------------------------------------------------------- [5.4], [5.13]


def test_robot_centred_velocity_known_answer():
    vw = np.array([[[1.0, -1.0]]])
    y = np.array([[[[3.0, -2.0]]], [[[0.0, 5.0]]]])
    r = np.full((2, 1, 1, 2), 0.5)
    c = np.array([[1.0, 2.0], [4.0, 8.0]])
    out = robot_centred_velocity(vw, y, c, np.array([0.5, 0.25]), r)
    assert np.allclose(out, [[[0.5 + 0.5 + 0.0, -0.25 - 1.0 + 4.0]]])


@given(
    arrays(float, SHAPE + (2,), elements=st.floats(-3, 3)),
    vecs,
    vecs,
    arrays(float, (5,) + SHAPE, elements=st.floats(0, 1)),
    arrays(float, (5,) + SHAPE, elements=st.floats(0, 1)),
)
def test_nonomni_is_robot_centred_law_with_fixed_directions(vw, yt, ygt, c, r):
    """[5.13] is [5.4] with c_1..4 = [0; c_n], c_5 = [c5; 0] and fixed directions for 3–5."""
    vw = vw.copy()
    vw[..., 0] = np.abs(vw[..., 0])
    out = nonomni_velocity(vw, yt, ygt, c, 0.1, r)
    dirs = np.stack(
        [yt, ygt] + [np.broadcast_to(np.array(d, float), yt.shape) for d in ([0, -1], [0, 1], [1, 0])]
    )
    cvec = np.stack([np.zeros_like(c), c], axis=-1)
    cvec[4] = np.stack([c[4], np.zeros_like(c[4])], axis=-1)
    ref = robot_centred_velocity(vw, dirs, cvec, 0.1, np.repeat(r[..., None], 2, axis=-1))
    assert np.allclose(out, ref)


@given(
    arrays(float, SHAPE + (2,), elements=st.floats(-3, 3)),
    vecs,
    vecs,
    arrays(float, (5,) + SHAPE, elements=st.floats(0, 2)),
    arrays(float, (5,) + SHAPE, elements=st.floats(0, 1)),
    st.floats(0.0, 0.99),
)
def test_nonomni_never_reverses(vw, yt, ygt, c, r, omega):
    assert np.all(nonomni_velocity(vw, yt, ygt, c, omega, r)[..., 0] >= 0)


def test_nonomni_turns_toward_left_best():
    vw = np.zeros((1, 1, 2))
    left = np.array([[[1.0, 2.0]]])
    c = np.array([0.5, 0.5, 0.0, 0.0, 1.0])
    out = nonomni_velocity(vw, left, left, c, 0.1, np.ones((5, 1, 1)))
    assert np.allclose(out, [[[1.0, 1.0]]])


# --------------------------------------------------------------------------- energy, r_min


@settings(max_examples=200)
@given(
    arrays(float, SHAPE, elements=st.floats(0, 10)),
    arrays(float, SHAPE, elements=st.floats(-10, 10)),
    st.floats(0.0, 5.0),
    st.sampled_from(["pi", "disc"]),
)
def test_energy_limit_respects_budget_and_keeps_radius(v, w, v_max, inertia):
    k = rotational_energy_factor(inertia, 0.5)
    v2, w2 = energy_limit(v, w, v_max, inertia, body_radius=0.5)
    e_t = 0.5 * v2**2 + k * w2**2
    assert np.all(np.isfinite(v2)) and np.all(np.isfinite(w2))
    assert np.all(e_t <= 0.5 * v_max**2 * (1 + 1e-9) + 1e-12)
    assert np.allclose(v2 * w, w2 * v, atol=1e-9)  # v/w unchanged
    inside = 0.5 * v**2 + k * w**2 <= 0.5 * v_max**2
    assert np.array_equal(v2[inside], v[inside]) and np.array_equal(w2[inside], w[inside])


def test_energy_limit_known_answer_and_zero():
    v, w = energy_limit(np.array([3.0, 0.0]), np.array([0.0, 0.0]), 2.0)
    assert np.allclose(v, [2.0, 0.0]) and np.allclose(w, [0.0, 0.0])
    v, w = energy_limit(np.array(0.0), np.array(0.0), 0.0)
    assert v == 0.0 and w == 0.0


def test_min_turning_radius():
    v = np.array([1.0, 1.0, 0.0, 1.0])
    w = np.array([4.0, -4.0, 2.0, 0.5])
    assert np.allclose(min_turning_radius(v, w, 0.5), [2.0, -2.0, 0.0, 0.5])
    assert np.array_equal(min_turning_radius(v, w, 0.0), w)
    with pytest.raises(ValueError):
        min_turning_radius(v, w, -1.0)


# --------------------------------------------------------------------------- arcs


def _pose(x=(0.0, 0.0), h=0.0):
    return np.array([[x]], dtype=float), np.array([[h]], dtype=float)


@given(st.floats(-5, 5), st.floats(-5, 5), angles, st.floats(0, 3), st.floats(0.01, 2))
def test_straight_line_when_w_is_zero(x0, y0, h, v, dt):
    x, head = _pose((x0, y0), h)
    x2, h2 = arc_pose_update(x, head, np.array([[v]]), np.zeros((1, 1)), dt)
    assert np.allclose(x2, [[[x0 + v * dt * math.cos(h), y0 + v * dt * math.sin(h)]]])  # [5.7]
    assert np.allclose(np.cos(h2), math.cos(h)) and np.allclose(np.sin(h2), math.sin(h))


def test_quarter_circle_known_points():
    x, h = _pose()
    v, w = 1.0, math.pi / 2
    r = v / w
    x2, h2 = arc_pose_update(x, h, np.array([[v]]), np.array([[w]]), 1.0)
    assert np.allclose(x2, [[[r, r]]]) and h2[0, 0] == pytest.approx(math.pi / 2)  # left turn
    x2, h2 = arc_pose_update(x, h, np.array([[v]]), np.array([[-w]]), 1.0)
    assert np.allclose(x2, [[[r, -r]]]) and h2[0, 0] == pytest.approx(-math.pi / 2)
    x, h = _pose((1.0, 2.0), math.pi / 2)  # facing +y, turning left → ends at (1 − r, 2 + r)
    x2, h2 = arc_pose_update(x, h, np.array([[v]]), np.array([[w]]), 1.0)
    assert np.allclose(x2, [[[1.0 - r, 2.0 + r]]]) and h2[0, 0] == pytest.approx(math.pi)


@given(
    heads,
    arrays(float, SHAPE, elements=st.floats(0, 3)),
    arrays(float, SHAPE, elements=st.floats(-3, 3)),
)
def test_arc_stays_on_turning_circle(h, v, w):
    w = np.where(np.abs(w) < 1e-3, 1e-3, w)
    x = np.zeros(SHAPE + (2,))
    x2, h2 = arc_pose_update(x, h, v, w, 0.7)
    radius = v / w
    centre = to_world(np.stack([np.zeros_like(radius), radius], -1), h)  # [5.6]
    assert np.allclose(np.linalg.norm(x2 - centre, axis=-1), np.abs(radius), atol=1e-9)
    assert np.all(h2 > -math.pi) and np.all(h2 <= math.pi)


def test_arc_is_continuous_as_w_goes_to_zero():
    x, h = _pose((0.5, -0.5), 0.3)
    ref, _ = arc_pose_update(x, h, np.array([[2.0]]), np.zeros((1, 1)), 1.0)
    for w in (1e-3, 1e-6, 1e-9, 1e-15, 1e-300, -1e-300):
        x2, h2 = arc_pose_update(x, h, np.array([[2.0]]), np.array([[w]]), 1.0)
        assert np.all(np.isfinite(x2)) and np.all(np.isfinite(h2))
        assert np.allclose(x2, ref, rtol=0.0, atol=3 * abs(w) + 1e-15)


@given(
    heads,
    arrays(float, SHAPE, elements=st.floats(0, 10)),
    arrays(float, SHAPE, elements=st.floats(-1e3, 1e3)),
)
def test_arc_never_nan(h, v, w):
    x2, h2 = arc_pose_update(np.zeros(SHAPE + (2,)), h, v, w, 1.0)
    assert np.all(np.isfinite(x2)) and np.all(np.isfinite(h2))
    assert np.all(np.linalg.norm(x2, axis=-1) <= v + 1e-9)  # chord ≤ arc length


# --------------------------------------------------------------------------- mecanum


@given(heads, st.sampled_from([(1, 0), (-1, 0), (0, 1), (0, -1)]), st.floats(0.1, 5))
def test_mecanum_axial_demand_passes(h, axis, v_max):
    body = np.broadcast_to(np.array(axis, float) * v_max, SHAPE + (2,))
    u = to_world(body, h)
    assert np.allclose(mecanum_limit(u, h, v_max), u)


@given(heads, st.sampled_from([(1, 1), (-1, 1), (1, -1), (-1, -1)]), st.floats(0.1, 5))
def test_mecanum_diagonal_demand_is_reduced(h, diag, v_max):
    body = np.broadcast_to(np.array(diag, float) / math.sqrt(2) * v_max, SHAPE + (2,))
    out = mecanum_limit(to_world(body, h), h, v_max)
    assert np.allclose(np.linalg.norm(out, axis=-1), v_max / math.sqrt(2))


@given(vecs, heads, st.floats(0.1, 5))
def test_mecanum_limit_reaches_rotated_square(u, h, v_max):
    out = mecanum_limit(u, h, v_max)
    b = to_body(out, h)
    assert np.all(np.abs(b[..., 0]) + np.abs(b[..., 1]) <= v_max * (1 + 1e-9))
    cross = out[..., 0] * u[..., 1] - out[..., 1] * u[..., 0]
    assert np.allclose(cross, 0.0, atol=1e-6 * (1 + np.linalg.norm(u, axis=-1)))
    inside = np.abs(to_body(u, h)).sum(axis=-1) <= v_max
    assert np.array_equal(out[inside], u[inside])


@given(
    arrays(float, (4, 3), elements=st.floats(-5, 5)),
    st.floats(0.05, 0.5),
    st.floats(0.2, 2.0),
)
def test_mecanum_wheels_and_body_are_inverse(twist, r_w, L):
    vx, vy, wz = twist.T
    wheels = mecanum_wheels(vx, vy, wz, r_w, L)  # [4.19]
    assert wheels.shape == (4, 4)
    assert np.allclose(np.stack(mecanum_body(wheels, r_w, L), -1), twist, atol=1e-9)  # [4.18]
    again = mecanum_wheels(*mecanum_body(wheels, r_w, L), r_w, L)
    assert np.allclose(again, wheels, atol=1e-9)


def test_mecanum_known_wheels():
    assert np.allclose(mecanum_wheels(1.0, 0.0, 0.0, 0.5, 1.0), [2.0, 2.0, 2.0, 2.0])
    assert np.allclose(mecanum_wheels(0.0, 1.0, 0.0, 0.5, 1.0), [-2.0, 2.0, 2.0, -2.0])
