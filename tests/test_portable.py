"""Arithmetic with the same bits on every CPU (engine/core/portable.py), and the receiver that
uses it: the golden presets give the stored hashes when numpy and BLAS run as on other CPUs
(tests/test_golden.py::test_golden_on_other_cpus)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from shoal.engine.acoustics.band import Band
from shoal.engine.acoustics.receiver import _project, angle_of_arrival, correlate, lag_table
from shoal.engine.core.portable import arccos, arctan2, exp, ordered_matmul
from shoal.engine.slo import metrics
from shoal.engine.slo.formation import AttractionRepulsion
from shoal.engine.slo.metrics import angular_errors


def _by_index(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Σ_k a_k·b_kl from +0, one k after another, in Python floats (IEEE double)."""
    rows = a.reshape(-1, a.shape[-1])
    out = np.empty((rows.shape[0], b.shape[1]))
    for i, row in enumerate(rows):
        for j in range(b.shape[1]):
            acc = 0.0
            for k in range(b.shape[0]):
                acc += float(row[k]) * float(b[k, j])
            out[i, j] = acc
    return out.reshape(a.shape[:-1] + (b.shape[1],))


@settings(max_examples=40, deadline=None)
@given(st.integers(1, 4), st.integers(1, 3), st.integers(1, 40), st.integers(1, 9), st.integers(0, 2**32 - 1),
       st.booleans())
def test_ordered_matmul_sums_in_index_order(r, n, k, l, seed, compiled):
    rng = np.random.default_rng(seed)
    a = rng.standard_normal((r, n, k)) * 10.0 ** rng.integers(-3, 4, (r, n, k))
    b = rng.standard_normal((k, l))
    got = ordered_matmul(a, b, compiled)
    assert got.shape == (r, n, l)
    assert np.array_equal(got, _by_index(a, b))  # bit for bit, compiled or numpy
    np.testing.assert_allclose(got, a @ b, rtol=1e-9, atol=1e-9 * np.abs(a).max() * np.abs(b).max() * k)


def test_ordered_matmul_refuses_mismatched_shapes():
    with pytest.raises(ValueError, match="terms"):
        ordered_matmul(np.ones((2, 3)), np.ones((4, 2)))


def test_arccos_is_the_c_librarys():
    x = np.random.default_rng(1).uniform(-1.0, 1.0, 5000)
    x[:4] = (-1.0, 1.0, 0.0, -0.0)
    got = arccos(x)
    assert got.dtype == np.float64
    assert np.array_equal(got, np.array([math.acos(v) for v in x]))
    assert arccos(np.float64(0.5)) == math.acos(0.5)
    np.testing.assert_allclose(got, np.arccos(x), rtol=0, atol=1e-15)


@pytest.mark.parametrize("compiled", [True, False])
def test_arctan2_and_exp_are_the_c_librarys(compiled):
    rng = np.random.default_rng(2)
    y, x = rng.uniform(-5.0, 5.0, (2, 3000))
    y[:8], x[:8] = (0.0, -0.0, 0.0, -0.0, 1.0, -1.0, np.inf, np.nan), (0.0, 0.0, -0.0, -0.0, 0.0, 0.0, np.inf, 1.0)
    got = arctan2(y.reshape(3, 1000), x.reshape(3, 1000), compiled)
    assert got.dtype == np.float64 and got.shape == (3, 1000)
    assert np.array_equal(got.ravel(), np.array([math.atan2(a, b) for a, b in zip(y, x)]), equal_nan=True)
    assert np.array_equal(np.signbit(got.ravel()[:4]), [False, True, False, True])  # atan2's signed zeros and π
    assert arctan2(np.ones((2, 1)), np.ones(4), compiled).shape == (2, 4)  # broadcast as numpy does
    assert arctan2(1.0, -2.0, compiled) == math.atan2(1.0, -2.0)
    e = exp(x * 100.0, compiled)  # overflow to inf and underflow to 0 too
    assert np.array_equal(e, np.array([math.exp(v) if v < 709 else math.inf for v in x * 100.0]), equal_nan=True)
    np.testing.assert_allclose(got, np.arctan2(y, x).reshape(3, 1000), rtol=1e-15, atol=1e-15)


@pytest.mark.parametrize("compiled", [True, False])  # False: the path taken where numba would use SVML
def test_slo_angles_use_the_portable_forms(compiled, monkeypatch):
    monkeypatch.setattr(metrics, "LIBM_KERNELS", compiled)
    rng = np.random.default_rng(3)
    x, est = rng.uniform(-20.0, 20.0, (2, 6, 2)), rng.uniform(-40.0, 40.0, (2, 6, 6, 2))
    valid = rng.random((2, 6, 6)) < 0.7
    truth = x[:, None] - x[:, :, None]
    ang = np.array([math.atan2(a, b) - math.atan2(c, d) for a, b, c, d in
                    zip(est[..., 1].ravel(), est[..., 0].ravel(), truth[..., 1].ravel(), truth[..., 0].ravel())])
    want = np.abs(np.pi - np.mod(np.pi - ang.reshape(2, 6, 6), 2.0 * np.pi))
    assert np.array_equal(angular_errors(x, est, valid), np.where(valid, want, np.nan), equal_nan=True)
    ar = AttractionRepulsion(gain=1.0)
    y = -est
    sq = np.sum(y * y, axis=-1)
    g = -y * (ar.a - ar.b * np.vectorize(math.exp)(-sq / ar.c))[..., None]
    assert np.array_equal(ar.velocity(est, valid), np.where(valid[..., None], g, 0.0).sum(axis=2))


def test_receiver_correlation_and_angle_use_the_portable_forms():
    band = Band(f_c=1000.0, Q=1.5, tbp=100.0, fs=48_000.0)
    rng = np.random.default_rng(5)
    X = rng.standard_normal((2, 3, band.freqs.size)) + 1j * rng.standard_normal((2, 3, band.freqs.size))
    lags, cos, sin = lag_table(band, 0.75)
    want = _by_index(X.real, cos) - _by_index(X.imag, sin)
    assert np.array_equal(correlate(X, band, lags), want)
    assert np.array_equal(_project(X, cos, sin, compiled=False), want)
    tau = rng.uniform(-6e-4, 6e-4, (2, 3))
    alpha = angle_of_arrival(tau, 0.75, band.c)
    assert np.array_equal(alpha, np.array([math.acos(v) for v in np.clip(band.c * tau / 0.75, -1, 1).ravel()])
                          .reshape(2, 3))


def test_slo_swarm_headings_are_the_c_librarys():
    from shoal.engine.kinds.slo_swarm import SLOSwarm

    sw = SLOSwarm(runs=3, seed=4, particles=20, selection="css", errors="low")
    sw.step()
    u, heading = sw.state.u, sw.state.heading
    moving = np.any(u != 0, axis=-1)
    assert moving.any()
    want = np.array([math.atan2(b, a) for a, b in zip(u[..., 0].ravel(), u[..., 1].ravel())]).reshape(heading.shape)
    assert np.array_equal(heading[moving], want[moving])
