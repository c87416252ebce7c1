"""Two-hydrophone receiver: known-answer bearings, sign convention, normalisation, the
mirror and phase-wrap ambiguities emerging from the signals, finiteness and batching."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from shoal.engine.acoustics.band import Band
from shoal.engine.acoustics.receiver import (
    MINUS,
    PLUS,
    angle_of_arrival,
    bearing,
    correlate,
    cross_spectrum,
    lag_samples,
)
from shoal.engine.acoustics.signals import hydrophone_positions, intensity, synthesise, to_time


def _rngs(n: int, seed: int = 0) -> list[np.random.Generator]:
    return [np.random.default_rng([seed, i]) for i in range(n)]


def _scene(band: Band, D: float, true_deg, heading=0.0, dist=1e4, snr_db=30.0, seed=0, full_lag=False):
    """One robot per run at the origin; the source at ``dist`` and world bearing
    heading + true_deg; R_ref chosen for the requested SNR at the robot."""
    rel = np.radians(np.atleast_1d(np.asarray(true_deg, dtype=float)))
    runs = rel.size
    o = np.broadcast_to(np.asarray(heading, dtype=float), (runs,)).reshape(runs, 1)
    world = o[:, 0] + rel
    src = dist * np.stack([np.cos(world), np.sin(world)], axis=-1)
    pos = hydrophone_positions(np.zeros((runs, 1, 2)), o, D)
    rr = dist * 10 ** (snr_db / 20)
    return bearing(synthesise(_rngs(runs, seed), pos, src, band, rr), band, D, o, full_lag=full_lag), rel, o


def _alpha_bounds(band: Band, D: float, alpha: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Interval of α the receiver may return: the refined lag lies within half a grid step
    (1/(2 fs)) of the true lag, i.e. |c·τ/D − cos α| ≤ c/(2·fs·D)."""
    tol = band.c / (2 * band.fs * D)
    return np.arccos(np.minimum(1.0, np.cos(alpha) + tol)), np.arccos(np.maximum(-1.0, np.cos(alpha) - tol))


def _angle_between(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    return np.abs(np.arctan2(u[..., 0] * v[..., 1] - u[..., 1] * v[..., 0], np.sum(u * v, axis=-1)))


# --- known answers -------------------------------------------------------------------------


@pytest.mark.parametrize("deg", [30, 60, 120, 150, -30, -60, -120, -150])
def test_known_bearing_and_rays(deg):
    b = Band()
    D = b.lam_c / 2
    br, rel, o = _scene(b, D, deg)
    true_alpha = np.abs(rel)
    lo, hi = _alpha_bounds(b, D, true_alpha)
    assert lo <= br.alpha[0, 0] <= hi
    width = hi - lo
    to_src = np.stack([np.cos(rel), np.sin(rel)], -1)[0]
    mirror = np.stack([np.cos(-rel), np.sin(-rel)], -1)[0]
    hit, miss = (PLUS, MINUS) if deg > 0 else (MINUS, PLUS)  # r_+ is the left (CCW) candidate
    assert _angle_between(br.rays[0, 0, hit], to_src) <= width
    assert _angle_between(br.rays[0, 0, miss], mirror) <= width


def test_known_bearings_with_turned_robots():
    b = Band()
    D = b.lam_c / 2
    rng = np.random.default_rng(11)
    rel = rng.uniform(20, 160, 40) * rng.choice([-1, 1], 40)
    heading = rng.uniform(-np.pi, np.pi, 40)
    br, rel, o = _scene(b, D, rel, heading=heading, seed=3)
    lo, hi = _alpha_bounds(b, D, np.abs(rel))
    assert np.all((lo <= br.alpha[:, 0]) & (br.alpha[:, 0] <= hi))
    world = o[:, 0] + rel
    to_src = np.stack([np.cos(world), np.sin(world)], -1)
    best = np.minimum(_angle_between(br.rays[:, 0, PLUS], to_src), _angle_between(br.rays[:, 0, MINUS], to_src))
    assert np.all(best <= hi - lo)  # one of the two rays points at the source


def test_sign_convention_bow_hears_first():
    b = Band()
    D = b.lam_c / 2
    ahead, _, _ = _scene(b, D, 0.0)
    astern, _, _ = _scene(b, D, 180.0)
    tol = b.c / (2 * b.fs * D)
    assert ahead.tau[0, 0] > 0 and ahead.alpha[0, 0] <= np.arccos(1 - tol)
    assert astern.tau[0, 0] < 0 and astern.alpha[0, 0] >= np.arccos(-1 + tol)
    assert ahead.tau[0, 0] == pytest.approx(D / b.c, abs=1 / (2 * b.fs))


def test_correlation_equals_time_domain_mean_xcorr():
    b = Band(Q=2.0, tbp=20)
    D = 2.0
    pos = hydrophone_positions(np.zeros((1, 1, 2)), np.zeros((1, 1)), D)
    sp = synthesise(_rngs(1), pos, np.array([[40.0, 25.0]]), b, 300.0)
    s1, s2 = to_time(sp[0, 0], b)
    ell = lag_samples(b, D)
    direct = np.array([np.mean(s1 * np.roll(s2, -k)) for k in ell])  # (1/n) Σ s1[m] s2[m+ℓ]
    assert np.allclose(correlate(cross_spectrum(sp), b, ell / b.fs)[0, 0], direct, atol=1e-10)


def test_full_lag_grid_agrees_with_the_restricted_one():
    b = Band(Q=3.0, tbp=30)
    D = b.lam_c / 2
    pos = hydrophone_positions(np.zeros((2, 1, 2)), np.zeros((2, 1)), D)
    sp = synthesise(_rngs(2), pos, np.array([[30.0, 10.0], [-5.0, 40.0]]), b, 200.0)
    full = bearing(sp, b, D, np.zeros((2, 1)), full_lag=True)
    assert full.lags.size == b.n and np.all(np.diff(full.lags) > 0)
    assert np.allclose(full.corr, correlate(cross_spectrum(sp), b, full.lags), atol=1e-9)


# --- normalisation of R and ρ ---------------------------------------------------------------


def test_rho_of_a_window_with_itself_is_its_intensity():
    b = Band()
    s = synthesise(_rngs(3), np.zeros((3, 2, 1, 2)), np.tile([100.0, 0.0], (3, 1)), b, 1000.0)
    pair = np.concatenate([s, s], axis=2)  # identical bow and stern: zero lag
    br = bearing(pair, b, 0.75, np.zeros((3, 2)))
    assert np.allclose(br.tau, 0.0, atol=1e-9)
    assert br.rho == pytest.approx(intensity(s)[..., 0])


def test_rho_estimates_received_signal_intensity():
    b = Band()
    D, runs, r = b.lam_c / 2, 2000, 1000 / np.sqrt(10)  # SNR 10 dB: I = 10, N = 1
    rel = np.random.default_rng(2).uniform(30, 150, runs)
    br, _, _ = _scene(b, D, rel, dist=r, snr_db=10.0, seed=4)
    assert br.rho.mean() == pytest.approx(10.0, rel=0.03)


# --- ambiguities emerge from the signals ----------------------------------------------------


@settings(max_examples=30, deadline=None)
@given(st.floats(-np.pi, np.pi), st.floats(-np.pi, np.pi), st.floats(-20, 30), st.integers(0, 2**32 - 1))
def test_mirror_ray_always_present(heading, rel, snr, seed):
    b = Band(tbp=20)
    br, _, o = _scene(b, b.lam_c / 2, np.degrees(rel), heading=heading, dist=200.0, snr_db=snr, seed=seed)
    h = np.array([np.cos(heading), np.sin(heading)])
    plus, minus = br.rays[0, 0, PLUS], br.rays[0, 0, MINUS]
    assert np.allclose(np.linalg.norm(br.rays, axis=-1), 1.0)
    assert np.allclose(minus, 2 * np.dot(plus, h) * h - plus, atol=1e-12)  # reflection across the bow axis
    assert 0.0 <= br.alpha[0, 0] <= np.pi


def _wrong_fraction(Q: float, d_over_lam: float, snr_db: float = 3.0, runs: int = 100) -> float:
    b = Band(Q=Q)
    D = d_over_lam * b.lam_c
    rel = np.repeat([60.0, 90.0, 120.0], runs)
    br, rel, _ = _scene(b, D, rel, dist=300.0, snr_db=snr_db, seed=17)
    return float(np.mean(np.abs(br.alpha[:, 0] - np.abs(rel)) > np.radians(10)))


def test_phase_wrap_appears_with_narrowband_signals_and_wide_spacing():
    assert _wrong_fraction(Q=20, d_over_lam=2.0) > 0.3
    assert _wrong_fraction(Q=20, d_over_lam=0.5) < 0.02


def test_wide_band_suppresses_phase_wrap():
    assert _wrong_fraction(Q=1.5, d_over_lam=2.0) < 0.02


def test_narrowband_side_peaks_are_one_period_apart():
    b = Band(Q=20)
    D = 2 * b.lam_c
    br, _, _ = _scene(b, D, 90.0, snr_db=40.0, full_lag=True)
    c = br.corr[0, 0]
    near = np.abs(br.lags) <= 3.5 / b.f_c
    peak = (c[1:-1] > c[:-2]) & (c[1:-1] >= c[2:]) & near[1:-1]
    spacing = np.diff(br.lags[1:-1][peak])
    assert spacing.size >= 4
    assert spacing == pytest.approx(np.full(spacing.size, 1 / b.f_c), abs=1.5 / b.fs)


# --- finiteness ------------------------------------------------------------------------------


def test_no_nan_with_source_on_a_hydrophone_or_under_the_robot():
    b = Band()
    D = b.lam_c / 2
    x = np.array([[[0.0, 0.0], [10.0, 0.0]]])
    o = np.zeros((1, 2))
    pos = hydrophone_positions(x, o, D)
    for src in (pos[:, 0, 0], x[:, 1]):  # on robot 0's bow hydrophone; under robot 1's centre
        br = bearing(synthesise(_rngs(1), pos, src, b, 1000.0), b, D, o)
        for v in (br.tau, br.rho, br.alpha, br.rays, br.corr):
            assert np.all(np.isfinite(v))


def test_no_nan_with_zero_signal():
    b = Band()
    zero = np.zeros((2, 3, 2, b.K), dtype=complex)
    br = bearing(zero, b, 0.75, np.zeros((2, 3)))
    assert np.all(br.tau == 0) and np.all(br.rho == 0) and np.allclose(br.alpha, np.pi / 2)
    assert np.all(np.isfinite(br.rays))
    noise_only = synthesise(_rngs(2), np.zeros((2, 3, 2, 2)), np.zeros((2, 2)), b, 0.0)
    assert np.all(np.isfinite(bearing(noise_only, b, 0.75, np.zeros((2, 3))).alpha))


def test_arccos_argument_is_clipped():
    D, c = 0.75, 1500.0
    tau = np.array([-1.0, -2 * D / c, -D / c, 0.0, D / c, 3 * D / c, 1.0])
    a = angle_of_arrival(tau, D, c)
    assert np.all(np.isfinite(a))
    assert a == pytest.approx([np.pi, np.pi, np.pi, np.pi / 2, 0.0, 0.0, 0.0])


def test_full_lag_noise_peaks_clip_to_endfire():
    b = Band(tbp=30)
    sp = synthesise(_rngs(200), np.zeros((200, 1, 2, 2)), np.zeros((200, 2)), b, 0.0)
    br = bearing(sp, b, b.lam_c / 2, np.zeros((200, 1)), full_lag=True)
    assert np.all(np.isfinite(br.alpha)) and np.all((br.alpha >= 0) & (br.alpha <= np.pi))
    outside = np.abs(br.tau) > b.lam_c / 2 / b.c
    assert outside.mean() > 0.5  # noise peaks mostly fall outside ±D/c ...
    assert np.all(np.isin(br.alpha[outside], [0.0, np.pi]))  # ... and read as endfire


def test_bad_separation_is_named():
    with pytest.raises(ValueError, match="D"):
        bearing(np.zeros((1, 1, 2, Band().K), dtype=complex), Band(), 0.0, np.zeros((1, 1)))


# --- batching --------------------------------------------------------------------------------


def test_batched_bearing_equals_runs_alone():
    b = Band(Q=2.0)
    D = b.lam_c / 2
    runs = 6
    rng = np.random.default_rng(8)
    x = rng.uniform(-100, 100, (runs, 5, 2))
    o = rng.uniform(-np.pi, np.pi, (runs, 5))
    src = rng.uniform(-300, 300, (runs, 2))
    pos = hydrophone_positions(x, o, D)
    batch = bearing(synthesise(_rngs(runs, 4), pos, src, b, 1000.0), b, D, o)
    for i in range(runs):
        spectra = synthesise([np.random.default_rng([4, i])], pos[i : i + 1], src[i : i + 1], b, 1000.0)
        alone = bearing(spectra, b, D, o[i : i + 1])
        for name in ("tau", "rho", "alpha", "rays", "corr"):
            assert np.allclose(getattr(batch, name)[i], getattr(alone, name)[0], rtol=1e-12, atol=1e-12), name


# --- approximate surrogate mode, validated against the waveform mode -----------------------


def _both_modes(Q: float, d_over_lam: float, snr_db: float, degs, runs: int = 200):
    from shoal.engine.acoustics.surrogate import surrogate

    b = Band(Q=Q)
    D = d_over_lam * b.lam_c
    rel = np.radians(np.repeat(degs, runs))
    n = rel.size
    o = np.zeros((n, 1))
    dist = 300.0
    src = dist * np.stack([np.cos(rel), np.sin(rel)], -1)
    pos = hydrophone_positions(np.zeros((n, 1, 2)), o, D)
    rr = dist * 10 ** (snr_db / 20)
    sp = synthesise(_rngs(n, 1), pos, src, b, rr)
    wave = (intensity(sp), bearing(sp, b, D, o))
    s = surrogate(_rngs(n, 2), pos, src, b, rr, heading=o, D=D)
    return rel, wave, (s.intensity, s.bearing)


@pytest.mark.parametrize("Q,d_over_lam,snr", [(1.5, 0.5, 10.0), (1.5, 0.5, 0.0), (20.0, 2.0, 3.0), (20.0, 0.5, 3.0)])
def test_surrogate_statistics_match_waveform_mode(Q, d_over_lam, snr):
    rel, (wi, wb), (si, sb) = _both_modes(Q, d_over_lam, snr, [60.0, 90.0, 120.0])
    assert si.mean() == pytest.approx(wi.mean(), rel=0.03)
    assert si.std() == pytest.approx(wi.std(), rel=0.15)
    assert sb.rho.mean() == pytest.approx(wb.rho.mean(), rel=0.05)
    assert sb.rho.std() == pytest.approx(wb.rho.std(), rel=0.2)
    werr, serr = wb.alpha[:, 0] - np.abs(rel), sb.alpha[:, 0] - np.abs(rel)
    assert np.std(serr) == pytest.approx(np.std(werr), rel=0.3)
    wrong_w, wrong_s = np.mean(np.abs(werr) > np.radians(10)), np.mean(np.abs(serr) > np.radians(10))
    assert abs(wrong_s - wrong_w) < 0.08


def test_surrogate_is_finite_batch_independent_and_single_hydrophone_aware():
    from shoal.engine.acoustics.surrogate import surrogate

    b = Band()
    D = b.lam_c / 2
    x = np.array([[[0.0, 0.0], [10.0, 0.0]], [[3.0, 4.0], [-50.0, 20.0]]])
    o = np.zeros((2, 2))
    pos = hydrophone_positions(x, o, D)
    src = np.stack([pos[0, 0, 0], x[1, 1]])  # on a hydrophone; under a robot
    batch = surrogate(_rngs(2, 6), pos, src, b, 1000.0, heading=o, D=D)
    for v in (batch.intensity, batch.bearing.tau, batch.bearing.rho, batch.bearing.alpha, batch.bearing.rays):
        assert np.all(np.isfinite(v))
    alone = surrogate([np.random.default_rng([6, 1])], pos[1:], src[1:], b, 1000.0, heading=o[1:], D=D)
    assert np.array_equal(batch.intensity[1], alone.intensity[0])
    assert np.allclose(batch.bearing.alpha[1], alone.bearing.alpha[0], rtol=1e-12, atol=1e-12)
    quiet = surrogate(_rngs(2), pos, src, b, 0.0, heading=o, D=D)
    assert np.all(np.isfinite(quiet.bearing.alpha)) and np.all(np.isfinite(quiet.intensity))
    single = surrogate(_rngs(2), hydrophone_positions(x, o), src, b, 1000.0)
    assert single.bearing is None and single.intensity.shape == (2, 2, 1)


def test_sample_lag_stays_on_the_grid_and_resolves_bearings_only_that_finely():
    """Alg. 5 lines 28–31 take the sample lag τ[I_lag]: with refine=False τ is a whole number
    of samples, so at fs = 4 kHz and D = λ_c/2 (two samples across) α takes five values."""
    b = Band(fs=4000.0)
    D = b.lam_c / 2
    degs = np.arange(5.0, 180.0, 7.0)
    rel = np.radians(degs)
    src = 1e4 * np.stack([np.cos(rel), np.sin(rel)], -1)
    pos = hydrophone_positions(np.zeros((degs.size, 1, 2)), np.zeros((degs.size, 1)), D)
    spectra = synthesise(_rngs(degs.size), pos, src, b, 1e4 * 10 ** 1.5)
    o = np.zeros((degs.size, 1))
    coarse = bearing(spectra, b, D, o, refine=False)
    fine = bearing(spectra, b, D, o)
    assert np.allclose(coarse.tau * b.fs, np.round(coarse.tau * b.fs))
    assert set(np.round(np.degrees(coarse.alpha[:, 0]))) <= {0.0, 60.0, 90.0, 120.0, 180.0}
    assert not np.allclose(fine.tau * b.fs, np.round(fine.tau * b.fs))  # refined lags fall between samples
    assert np.max(np.abs(fine.alpha[:, 0] - rel)) < np.max(np.abs(coarse.alpha[:, 0] - rel))
