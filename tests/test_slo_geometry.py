"""SLO candidate geometry (Mai §3.5.1–3.5.2): exact candidates, mitigation, singular inputs."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from shoal.engine.slo.candidates import Flag, candidates
from shoal.engine.slo.selection import Kind, css

coord = st.floats(-1e3, 1e3, allow_nan=False, allow_infinity=False)
vec = st.tuples(coord, coord).map(np.array)


def exact(r1: np.ndarray, v: np.ndarray, prev: np.ndarray | None = None, **kw):
    """Candidates from error-free inputs: B is at r1 now and was at r1 − v before."""
    r0 = r1 - v
    prev = r0 if prev is None else prev
    return candidates(np.linalg.norm(r0), np.linalg.norm(r1), v, prev, **kw)


@settings(max_examples=150, deadline=None)
@given(r1=vec, v=vec)
def test_one_mirror_candidate_is_the_true_vector(r1, v):
    """Acceptance 1: with exact inputs one of x1, x2 equals r_ij (1e-9 relative)."""
    d1, sv = np.linalg.norm(r1), np.linalg.norm(v)
    assume(d1 > 1e-3 and sv > 1e-3)
    c = exact(r1, v)
    if c.flag == Flag.GEOMETRIC:
        err = np.linalg.norm(c.points[:2] - r1, axis=-1).min()
        assert err <= 1e-9 * d1
        assert c.mask.tolist() == [True, True, True]
    else:
        assert c.mask.tolist() == [False, False, True]
        assert np.array_equal(c.points[0], c.x3)


@settings(max_examples=100, deadline=None)
@given(r1=vec, v=vec)
def test_clip_only_mode_keeps_geometric_candidates_exact(r1, v):
    """δ_cos = −inf, δ_v = 0: every non-degenerate triangle is used, away from |cos α| ≈ 1."""
    d1, sv = np.linalg.norm(r1), np.linalg.norm(v)
    assume(d1 > 1e-3 and sv > 1e-3 and np.linalg.norm(r1 - v) > 1e-3)
    c = exact(r1, v, delta_cos=-np.inf, delta_v=0.0)
    assert c.flag == Flag.GEOMETRIC
    cos = abs(np.dot(r1, v)) / (d1 * sv)
    assume(cos < 0.999)
    assert np.linalg.norm(c.points[:2] - r1, axis=-1).min() <= 1e-9 * d1 / np.sqrt(1 - cos**2)


@settings(max_examples=150, deadline=None)
@given(
    d0=st.one_of(st.just(0.0), st.just(-1.0), st.just(np.inf), st.just(np.nan), st.floats(0, 1e6)),
    d1=st.one_of(st.just(0.0), st.just(-2.0), st.just(np.inf), st.just(np.nan), st.floats(0, 1e6)),
    v=st.one_of(st.just(np.zeros(2)), vec, st.tuples(st.floats(-1e-300, 1e-300), st.floats(-1e-300, 1e-300)).map(
        np.array)),
    prev=vec,
    delta_cos=st.sampled_from([0.03, 0.0, -np.inf, -0.5, 1.0]),
    delta_v=st.sampled_from([0.03, 0.0, 0.5]),
    literal=st.booleans(),
)
def test_no_nan_for_any_singular_input(d0, d1, v, prev, delta_cos, delta_v, literal):
    c = candidates(d0, d1, v, prev, delta_cos, delta_v, literal)
    assert np.all(np.isfinite(c.points))
    assert c.mask[2]
    if not c.mask[0]:
        assert np.array_equal(c.points[0], prev + v)
    if not (d0 > 0 and d1 > 0 and np.isfinite(d0) and np.isfinite(d1) and np.any(v != 0)):
        assert c.flag == Flag.FALLBACK
    est, kind = css(c, 0.5)
    assert np.all(np.isfinite(est))


def test_range_failure_gives_exactly_dead_reckoning():
    """Acceptance 4 (range part): d* = 0 at either end → x3 exactly."""
    prev, v = np.array([3.0, 4.0]), np.array([0.5, -0.25])
    for d0, d1 in [(0.0, 5.0), (5.0, 0.0)]:
        c = candidates(d0, d1, v, prev)
        est, kind = css(c, 0.5)
        assert c.flag == Flag.FALLBACK and kind == Kind.X3
        assert np.array_equal(est, prev + v)


def test_mitigation_flags():
    r1 = np.array([10.0, 0.0])
    radial = exact(r1, np.array([1.0, 0.0]))  # B moves straight away from A: cos α = 1
    assert radial.flag == Flag.MITIGATED_COS
    slow = exact(r1, np.array([0.0, 0.1]))  # |v|/d = 0.01 ≤ δ_v
    assert slow.flag == Flag.MITIGATED_V
    assert exact(r1, np.array([0.0, 0.1]), delta_v=0.0).flag == Flag.GEOMETRIC
    impossible = candidates(1.0, 10.0, np.array([1.0, 0.0]), np.zeros(2))  # |cos α| > 1
    assert impossible.flag == Flag.MITIGATED_COS
    clipped = candidates(1.0, 10.0, np.array([1.0, 0.0]), np.zeros(2), delta_cos=-np.inf, delta_v=0.0)
    assert clipped.flag == Flag.GEOMETRIC and np.allclose(clipped.points[0], clipped.points[1])


def test_literal_eq_3_1_is_wrong_for_unequal_ranges():
    r1, v = np.array([3.0, 7.0]), np.array([2.0, -1.0])
    lit = exact(r1, v, literal_eq_3_1=True)
    assert lit.flag == Flag.GEOMETRIC
    assert np.linalg.norm(lit.points[:2] - r1, axis=-1).min() > 1e-2
    assert np.linalg.norm(exact(r1, v).points[:2] - r1, axis=-1).min() < 1e-12


def test_candidates_are_mirror_images_about_v():
    r1, v = np.array([5.0, 2.0]), np.array([1.0, 1.5])
    c = exact(r1, v)
    u = v / np.linalg.norm(v)
    x1, x2 = c.points[0], c.points[1]
    assert np.dot(x1, u) == pytest.approx(np.dot(x2, u))
    assert np.linalg.norm(x1) == pytest.approx(np.linalg.norm(r1))
    assert np.linalg.norm(x2) == pytest.approx(np.linalg.norm(r1))


def test_css_blends_with_prediction_weight():
    r1, v = np.array([5.0, 2.0]), np.array([1.0, 1.5])
    wrong_prev = r1 - v + np.array([0.4, -0.3])
    c = exact(r1, v, prev=wrong_prev)
    x3 = c.x3
    assert np.array_equal(css(c, 1.0)[0], x3)  # w = 1 never corrects
    est0, kind = css(c, 0.0)
    assert np.allclose(est0, r1) and kind in (Kind.X1, Kind.X2)
    assert np.allclose(css(c, 0.25)[0], 0.25 * x3 + 0.75 * r1)  # [3.7]


def test_dead_reckoning_increments_cancel_around_a_triangle():
    """Acceptance 3: (v*_b − v*_a) + (v*_c − v*_b) + (v*_a − v*_c) = 0 whatever the errors."""
    from shoal.engine.slo.sensors import ERROR_PRESETS, draw_permanent, measure_odometry

    rngs = [np.random.default_rng(5)]
    model = ERROR_PRESETS["high"]
    perm = draw_permanent(model, rngs, 3)
    v = measure_odometry(np.array([[[1.0, 2.0], [-3.0, 0.5], [0.2, 0.1]]]), model.odometry, perm, rngs)[0]
    loop = (v[1] - v[0]) + (v[2] - v[1]) + (v[0] - v[2])
    assert np.allclose(loop, 0.0, atol=1e-14)
    prev = np.array([[2.0, 1.0], [-1.0, 3.0], [-1.0, -4.0]])  # a consistent loop of estimates
    x3 = prev + np.array([v[1] - v[0], v[2] - v[1], v[0] - v[2]])
    assert np.allclose(x3.sum(axis=0), 0.0, atol=1e-14)
