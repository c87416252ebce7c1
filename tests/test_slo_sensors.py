"""SLO error model (Mai §4.4, Tab. 4.3): statistics of the seeded range and odometry errors."""

from __future__ import annotations

import numpy as np
import pytest

from shoal.engine.slo.sensors import (
    ERROR_PRESETS,
    ErrorModel,
    OdometryErrors,
    RangeErrors,
    draw_permanent,
    error_model,
    measure_odometry,
    measure_ranges,
)

N = 40


def gens(k: int = 4, seed: int = 0) -> list[np.random.Generator]:
    return [np.random.default_rng([seed, i]) for i in range(k)]


def dist_matrix(value: float, k: int = 4) -> np.ndarray:
    d = np.full((k, N, N), value)
    idx = np.arange(N)
    d[:, idx, idx] = np.inf
    return d


def off_diagonal(a: np.ndarray) -> np.ndarray:
    return a[:, ~np.eye(N, dtype=bool)]


def test_presets_match_table_4_3():
    low, high = ERROR_PRESETS["low"], ERROR_PRESETS["high"]
    assert (low.range.sigma_m, low.range.sigma_a, low.range.perm_sigma_m, low.range.perm_sigma_a, low.range.p_fail) == (
        0.010, 0.050, 0.015, 0.150, 0.050)
    assert (high.odometry.sigma_m, high.odometry.sigma_a, high.odometry.perm_sigma_m, high.odometry.perm_sigma_a,
            high.odometry.p_fail, high.odometry.sigma_r, high.odometry.perm_sigma_r) == (
        0.20, 0.30, 0.06, 0.30, 0.20, 0.20, 0.20)
    assert error_model("None") == ErrorModel()
    with pytest.raises(ValueError, match="errors"):
        error_model("medium")


def test_none_preset_is_exact():
    model, rngs = ERROR_PRESETS["none"], gens()
    perm = draw_permanent(model, rngs, N)
    d = dist_matrix(7.3)
    assert np.array_equal(off_diagonal(measure_ranges(d, model.range, perm, rngs)), off_diagonal(d))
    v = np.stack([g.normal(size=(N, 2)) for g in rngs])
    assert np.array_equal(measure_odometry(v, model.odometry, perm, rngs), v)


def test_stochastic_multiplicative_range_error():
    """[4.2] with σ_m only: d*/d has mean 1 and std σ_m."""
    model = ErrorModel(RangeErrors(sigma_m=0.2))
    rngs = gens()
    ratio = off_diagonal(measure_ranges(dist_matrix(50.0), model.range, draw_permanent(model, rngs, N), rngs)) / 50.0
    assert ratio.mean() == pytest.approx(1.0, abs=0.01)
    assert ratio.std() == pytest.approx(0.2, rel=0.03)


def test_additive_and_permanent_range_errors_belong_to_the_robot():
    """[4.3]: σ̂_a is one offset per ranging robot, constant over steps (docs/readings.md, "Who
    owns a permanent error")."""
    model = ErrorModel(RangeErrors(perm_sigma_a=1.0))
    rngs = gens(8)
    perm = draw_permanent(model, rngs, N)
    a = measure_ranges(dist_matrix(100.0, 8), model.range, perm, rngs) - 100.0
    b = measure_ranges(dist_matrix(100.0, 8), model.range, perm, rngs) - 100.0
    off = ~np.eye(N, dtype=bool)
    assert np.allclose(a[:, off], b[:, off])  # no stochastic part: the same every step
    row = np.where(off, a, np.nan)
    assert np.allclose(np.nanstd(row, axis=2), 0.0, atol=1e-12)  # one offset per observer
    assert np.nanmean(row, axis=2).std() == pytest.approx(1.0, rel=0.15)  # σ̂_a across robots
    model = ErrorModel(RangeErrors(sigma_a=0.3))
    noise = off_diagonal(measure_ranges(dist_matrix(100.0), model.range, draw_permanent(model, rngs[:4], N), rngs[:4]))
    assert (noise - 100.0).std() == pytest.approx(0.3, rel=0.03)


def test_range_failures_and_clamping():
    model = ErrorModel(RangeErrors(sigma_a=5.0, p_fail=0.3))
    rngs = gens()
    d = measure_ranges(dist_matrix(100.0), model.range, draw_permanent(model, rngs, N), rngs)
    assert (off_diagonal(d) == 0).mean() == pytest.approx(0.3, abs=0.02)
    short = measure_ranges(dist_matrix(0.5), model.range, draw_permanent(model, rngs, N), rngs)
    assert short.min() >= 0.0  # docs/readings.md, "Negative ranges"
    far = measure_ranges(dist_matrix(100.0), RangeErrors(), draw_permanent(model, rngs, N), rngs, max_range=50.0)
    assert np.all(far == 0)


def test_directions_are_measured_independently():
    model = ErrorModel(RangeErrors(sigma_m=0.1))
    rngs = gens()
    d = measure_ranges(dist_matrix(10.0), model.range, draw_permanent(model, rngs, N), rngs)
    assert not np.allclose(d, np.swapaxes(d, 1, 2))


def test_odometry_errors():
    """[4.4]: per-axis multiplicative and additive errors, rotation, whole-vector failure."""
    rngs = gens(8)
    v = np.zeros((8, N, 2))
    v[..., 0] = 3.0
    model = ErrorModel(odometry=OdometryErrors(sigma_m=0.1))
    out = measure_odometry(v, model.odometry, draw_permanent(model, rngs, N), rngs)
    assert (out[..., 0] / 3.0).std() == pytest.approx(0.1, rel=0.1) and np.all(out[..., 1] == 0)
    model = ErrorModel(odometry=OdometryErrors(sigma_r=0.2))
    out = measure_odometry(v, model.odometry, draw_permanent(model, rngs, N), rngs)
    assert np.allclose(np.linalg.norm(out, axis=-1), 3.0)
    assert np.arctan2(out[..., 1], out[..., 0]).std() == pytest.approx(0.2, rel=0.15)
    model = ErrorModel(odometry=OdometryErrors(p_fail=0.2))
    out = measure_odometry(v, model.odometry, draw_permanent(model, rngs, N), rngs)
    failed = np.all(out == 0, axis=-1)
    assert failed.mean() == pytest.approx(0.2, abs=0.05)  # acceptance 4: v* = (0, 0)
    assert np.array_equal(out[~failed], v[~failed])


def test_permanent_odometry_offsets_are_per_robot_and_axis():
    model = ErrorModel(odometry=OdometryErrors(perm_sigma_a=0.3))
    rngs = gens(8)
    perm = draw_permanent(model, rngs, N)
    out = measure_odometry(np.zeros((8, N, 2)), model.odometry, perm, rngs)
    assert np.array_equal(out, perm.odo_a)
    assert perm.odo_a.std() == pytest.approx(0.3, rel=0.1)
    assert abs(np.corrcoef(perm.odo_a[..., 0].ravel(), perm.odo_a[..., 1].ravel())[0, 1]) < 0.15


def test_additive_errors_scale_with_the_arena():
    low = ERROR_PRESETS["low"].scaled(0.4)
    assert low.range.sigma_a == pytest.approx(0.02) and low.odometry.perm_sigma_a == pytest.approx(0.02)
    assert low.range.sigma_m == ERROR_PRESETS["low"].range.sigma_m
    swept = ErrorModel().with_values(range_sigma_m=0.3, odometry_p_fail=0.1)
    assert swept.range.sigma_m == 0.3 and swept.odometry.p_fail == 0.1
    with pytest.raises(ValueError, match="range_bogus"):
        ErrorModel().with_values(range_bogus=1.0)
