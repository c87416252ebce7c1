"""Stability regions [3.7], [3.9], [3.13]/[3.14] and the reduced state model [3.22]–[3.25]."""

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from shoal.engine.pso import stability as sb
from shoal.engine.pso.laws import Law


def test_order2_region_inside_order1():
    w, c = np.meshgrid(np.linspace(-0.999, 0.999, 201), np.linspace(0.001, 8, 201))
    assert not np.any(sb.order2_stable(w, c) & ~sb.order1_stable(w, c))
    assert np.any(sb.order1_stable(w, c) & ~sb.order2_stable(w, c))


def test_region_boundaries_known_points():
    assert sb.order2_boundary(0.0) == pytest.approx(24 / 7)
    w = np.linspace(-1, 1, 20001)
    peak = np.argmax(sb.order2_boundary(w))
    assert w[peak] == pytest.approx(0.420, abs=2e-3)
    assert sb.order2_boundary(w[peak]) == pytest.approx(4.03, abs=5e-3)
    assert sb.order1_boundary(-1.0) == 0 and sb.order1_boundary(1.0) == 8
    assert not sb.order1_stable(1.0, 4.0)  # dPSO ω = 1, c1 = c2 = 2 lies on the boundary


def test_adapted_region():
    assert sb.adapted_stable(0.0, 100.0)
    assert not sb.adapted_stable(-0.5, 1.0)
    assert sb.adapted_stable(-0.5, 1.0, robot_subset=False)
    assert not sb.adapted_stable(1.0, 1.0) and not sb.adapted_stable(0.5, 0.0)


def test_reduced_matrix_eigen_structure():
    M = sb.reduced_state_matrix(0.6, 0.5)
    assert sorted(np.linalg.eigvals(M)) == pytest.approx([0.0, 0.6])


@given(u=st.floats(-50, 50), a=st.floats(-50, 50), omega=st.floats(0.05, 0.95), dt=st.floats(0.01, 2.0))
def test_deterministic_part_lies_on_a1(u, a, omega, dt):
    """Lemma 1: M̂ẑ lies on the line a1 [3.24]."""
    z = sb.reduced_state_matrix(omega, dt) @ np.array([u, a])
    assert z[1] == pytest.approx(float(sb.a1(z[0], omega, dt)), abs=1e-7 * (1 + abs(z[1])))


@given(
    u_frac=st.floats(-1, 1), omega=st.floats(0.0, 0.95), c_hat=st.floats(0.1, 10),
    dt=st.floats(0.05, 2.0), sign=st.sampled_from([-1.0, 0.0, 1.0]), r=st.floats(0, 1),
)
def test_next_state_in_reachable_parallelogram(u_frac, omega, c_hat, dt, sign, r):
    """Lemma 2: from |u| ≤ U_j, ẑ[k+1] lies between a2 and a3, inside the parallelogram."""
    U_j = c_hat / (1 - omega)
    z1 = sb.reduced_step(np.array([u_frac * U_j, 0.0]), omega, c_hat, sign, r, dt)
    poly = sb.reachable_parallelogram(omega, c_hat, dt)
    # inside a convex polygon: same-side test on each edge (counter-clockwise order)
    edges = np.roll(poly, -1, axis=0) - poly
    rel = z1 - poly
    cross = edges[:, 0] * rel[:, 1] - edges[:, 1] * rel[:, 0]
    scale = 1e-9 * (1 + U_j) * (1 + c_hat / dt)
    assert np.all(cross >= -scale) or np.all(cross <= scale)
    if omega > 1e-3:
        assert sb.a3(z1[0], omega, dt, c_hat) - 1e-7 <= z1[1] <= sb.a2(z1[0], omega, dt, c_hat) + 1e-7


def test_figure_3_3_markers():
    m = sb.phase_markers(0.6, 4.0, 1.0)
    assert m["star"][0] == pytest.approx([10, 0])
    assert m["square"][0] == pytest.approx([2, -8])
    assert m["diamond"][0] == pytest.approx([4, 4])


def test_a1_at_zero_omega_is_the_vertical_axis():
    with pytest.raises(ValueError):
        sb.a1(1.0, 0.0, 1.0)
    assert np.allclose(sb.line_a1(0.0, 1.0, 10, 5)[:, 0], 0.0)
    seg = sb.line_a1(0.5, 1.0, 10, 3)
    assert np.all(np.abs(seg) <= [10, 3 + 1e-12])


def test_merged_model_matches_the_law():
    """[3.18]/[3.22]: one merged term ĉ r̂ gives the acceleration of the reduced model."""
    rng = np.random.default_rng(1)
    omega, c_hat, dt = 0.7, 2.0, 0.3
    u = rng.uniform(-5, 5, (1, 50, 1))
    g = rng.uniform(-3, 3, (1, 1, 50, 1))
    r = rng.random(g.shape)
    new = Law("adapted-sgn").velocity(u, g, np.array([c_hat]), omega, r)
    z = sb.reduced_step(
        np.stack([u[0, :, 0], np.zeros(50)], -1), omega, c_hat, np.sign(g[0, 0, :, 0]), r[0, 0, :, 0], dt
    )
    assert np.allclose(z[:, 0], new[0, :, 0])
    assert np.allclose(z[:, 1], (new - u)[0, :, 0] / dt)
