"""Propagation, SNR and frequency-domain signal synthesis (Rossides §6.1, p. 130;
§6.2.4, p. 135; §7.3.2, p. 161)."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from shoal.engine.acoustics.band import Band
from shoal.engine.acoustics.propagation import (
    R_FLOOR_M,
    alpha_abs,
    noise_intensity,
    r_ref,
    received_level_db,
    snr_db,
    snr_general_db,
    source_distance_for_snr,
    source_intensity,
)
from shoal.engine.acoustics.signals import hydrophone_positions, intensity, synthesise, to_time


def _rngs(n: int, seed: int = 0) -> list[np.random.Generator]:
    return [np.random.default_rng([seed, i]) for i in range(n)]


# --- propagation [6.1]–[6.6] -------------------------------------------------------------


def test_spherical_loses_6db_per_doubling_and_60db_at_1km():
    L = received_level_db(180.0, np.array([1000.0, 2000.0, 4000.0]))
    assert L[0] == pytest.approx(120.0)  # [6.1] at R = 1 km
    assert np.diff(L) == pytest.approx([-20 * np.log10(2)] * 2)


def test_cylindrical_equals_hybrid_with_r1_1km_beyond_r1():
    r = np.array([1500.0, 3000.0, 10_000.0])
    cyl = received_level_db(170.0, r, "cylindrical", alpha_db_per_km=0.1)
    hyb = received_level_db(170.0, r, "hybrid", alpha_db_per_km=0.1, R1_km=1.0)
    assert cyl == pytest.approx(hyb)  # docs/readings.md, "The −60 in the spreading laws"


def test_hybrid_is_continuous_at_r1_and_spherical_inside():
    r1 = 2.0
    r = np.array([500.0, 1999.999, 2000.0, 2000.001])
    hyb = received_level_db(160.0, r, "hybrid", R1_km=r1, A_db_per_km=0.5)
    sph = received_level_db(160.0, r[:2], "spherical") - 0.5 * r[:2] / 1000
    assert hyb[:2] == pytest.approx(sph)
    assert np.abs(np.diff(hyb[1:])).max() < 1e-4


def test_absorption_is_subtracted_linearly_in_range():
    base = received_level_db(150.0, 5000.0)
    assert received_level_db(150.0, 5000.0, alpha_db_per_km=0.2) == pytest.approx(base - 1.0)


def test_unknown_model_names_the_choice():
    with pytest.raises(ValueError, match="model"):
        received_level_db(150.0, 10.0, "conical")


def test_absorption_fit_hits_the_anchors():
    assert alpha_abs(100.0) == pytest.approx(0.001, rel=0.02)
    assert alpha_abs(10_000.0) == pytest.approx(1.0, rel=0.02)
    assert alpha_abs(1000.0) == pytest.approx(0.032, rel=0.02)


def test_levels_are_finite_at_zero_range():
    for model in ("spherical", "cylindrical", "hybrid"):
        L = received_level_db(120.0, np.array([0.0, -1.0, R_FLOOR_M]), model)
        assert np.all(np.isfinite(L)) and L[0] == L[2]
    assert np.isfinite(snr_db(0.0, 120, 60)) and np.isfinite(snr_general_db(150, 1e-3, 0.0))


# --- SNR [6.7], [7.13]–[7.17] ------------------------------------------------------------


def test_simulation_snr_law():
    rr = r_ref(120.0, 60.0)
    assert rr == pytest.approx(1000.0)
    assert snr_db(rr, 120.0, 60.0) == pytest.approx(0.0, abs=1e-12)
    r = rr * 2.0 ** np.arange(-3, 4)
    assert np.diff(snr_db(r, 120.0, 60.0)) == pytest.approx([-6.0206] * 6, abs=1e-4)
    B = 666.7
    assert np.sqrt(source_intensity(120.0, B) / noise_intensity(60.0, B)) == pytest.approx(rr)  # B cancels


def test_source_distance_for_the_thesis_snr_list():
    d = source_distance_for_snr(np.array([10.0, 6.0, 4.0, 0.0]), r_ref(120.0, 60.0))
    assert d == pytest.approx([316.2, 501.2, 631.0, 1000.0], abs=0.05)
    assert snr_db(d, 120.0, 60.0) == pytest.approx([10.0, 6.0, 4.0, 0.0])


def test_general_snr_matches_simulation_form():
    # [6.7] with N = PSD_n·B and L_s = PSD_s + 10 log B agrees with [7.16]
    B = 100.0
    Ls = 120.0 + 10 * np.log10(B)
    N = noise_intensity(60.0, B)
    assert snr_general_db(Ls, N, 250.0) == pytest.approx(snr_db(250.0, 120.0, 60.0))


# --- band ---------------------------------------------------------------------------------


def test_default_band_values():
    b = Band()
    assert (b.B, b.T, b.lam_c, b.n) == pytest.approx((666.667, 0.15, 1.5, 7200), rel=1e-4)
    assert abs(b.K - b.tbp) <= 1
    assert b.freqs.min() >= b.f_c - b.B / 2 - 1e-6 and b.freqs.max() <= b.f_c + b.B / 2 + 1e-6


@pytest.mark.parametrize("Q,tbp", [(0.5, 10), (1.5, 100), (20, 100), (10, 0.5)])
def test_band_has_positive_bins_and_exact_phasors(Q, tbp):
    b = Band(Q=Q, tbp=tbp)
    assert b.K >= 1 and b.bins.min() >= 1
    tau = np.array([-1e-3, 0.0, 3.7e-4])
    assert np.allclose(b.phasor(tau), np.exp(2j * np.pi * b.freqs * tau[:, None]), atol=1e-12)


def test_band_rejects_bad_values():
    with pytest.raises(ValueError, match="band.Q"):
        Band(Q=0)
    with pytest.raises(ValueError, match="band.fs"):
        Band(f_c=30_000.0)


# --- synthesis ----------------------------------------------------------------------------


def test_hydrophone_layouts():
    x = np.array([[[1.0, 2.0]]])
    o = np.array([[np.pi / 2]])
    assert hydrophone_positions(x, o).shape == (1, 1, 1, 2)
    p = hydrophone_positions(x, o, D=0.75)
    assert p.shape == (1, 1, 2, 2)
    assert np.allclose(p[0, 0], [[1.0, 2.375], [1.0, 1.625]])  # bow ahead, stern behind


def test_mean_intensity_is_signal_plus_noise():
    b, runs, r = Band(), 3000, 500.0
    pos = np.zeros((runs, 1, 1, 2))
    src = np.tile([r, 0.0], (runs, 1))
    I = intensity(synthesise(_rngs(runs), pos, src, b, 1000.0))
    expected = (1000.0 / r) ** 2 + 1.0
    sem = expected / np.sqrt(b.K * runs)  # std of I is about (I + N)/sqrt(K)
    assert I.mean() == pytest.approx(expected, abs=5 * sem)
    assert I.std() == pytest.approx(expected / np.sqrt(b.K), rel=0.1)


def test_noise_alone_has_unit_power_and_is_independent():
    b, runs = Band(), 400
    pos = np.random.default_rng(1).uniform(-50, 50, (runs, 3, 2, 2))
    sp = synthesise(_rngs(runs, 5), pos, np.zeros((runs, 2)), b, 0.0)  # R_ref = 0: noise only
    assert intensity(sp).mean() == pytest.approx(1.0, abs=5 / np.sqrt(b.K * sp[..., 0].size))
    flat = sp.transpose(1, 2, 0, 3).reshape(6, -1)  # (robot·hydrophone, samples)
    power = np.mean(np.abs(flat) ** 2, axis=1)
    coh = np.abs(flat.conj() @ flat.T / flat.shape[1]) / np.sqrt(np.outer(power, power))
    off = coh[~np.eye(6, dtype=bool)]
    assert off.max() < 5 / np.sqrt(flat.shape[1])  # ~0: independent between hydrophones and robots


def test_signal_is_common_to_hydrophones_and_delayed_by_geometry():
    b = Band()
    pos = np.array([[[[0.0, 0.0], [-3.0, 0.0]]]])  # second hydrophone 3 m further from the source
    sp = synthesise(_rngs(1), pos, np.array([[100.0, 0.0]]), b, 1e13)  # noise negligible
    ratio = sp[0, 0, 1] / sp[0, 0, 0]
    expect = (100.0 / 103.0) * np.exp(-2j * np.pi * b.freqs * 3.0 / b.c)
    assert np.allclose(ratio, expect, rtol=1e-8)


def test_renormalise_gives_unit_power_windows():
    b, runs = Band(), 20
    pos = np.zeros((runs, 2, 1, 2))
    sp = synthesise(_rngs(runs), pos, np.tile([1e6, 0.0], (runs, 1)), b, 0.0, renormalise=True)
    assert intensity(sp) == pytest.approx(np.ones((runs, 2, 1)))


def test_time_series_has_the_spectral_power():
    b = Band(Q=2.0, tbp=20)
    sp = synthesise(_rngs(2), np.zeros((2, 1, 2, 2)), np.tile([300.0, 0.0], (2, 1)), b, 1000.0)
    x = to_time(sp, b)
    assert x.shape[-1] == b.n and np.isrealobj(x)
    assert np.mean(x**2, axis=-1) == pytest.approx(intensity(sp))


def test_synthesis_is_finite_with_the_source_on_a_hydrophone():
    b = Band()
    pos = hydrophone_positions(np.array([[[5.0, 5.0], [0.0, 0.0]]]), np.zeros((1, 2)), D=0.75)
    src = pos[:, 0, 0]  # exactly on robot 0's bow hydrophone
    sp = synthesise(_rngs(1), pos, src, b, 1000.0)
    assert np.all(np.isfinite(sp))
    assert intensity(sp)[0, 0, 0] < 10 * (1000.0 / R_FLOOR_M) ** 2


def test_batched_runs_equal_runs_alone():
    b, runs = Band(Q=3.0), 5
    rng = np.random.default_rng(3)
    pos = rng.uniform(-100, 100, (runs, 4, 2, 2))
    src = rng.uniform(-300, 300, (runs, 2))
    rr = np.array([1000.0, 500.0, 800.0, 1000.0, 2000.0])
    batch = synthesise(_rngs(runs, 9), pos, src, b, rr)
    for i in range(runs):
        alone = synthesise([np.random.default_rng([9, i])], pos[i : i + 1], src[i : i + 1], b, rr[i])
        assert np.array_equal(batch[i], alone[0])


@settings(max_examples=40, deadline=None)
@given(
    st.floats(-1e4, 1e4), st.floats(-1e4, 1e4), st.floats(0, 2 * np.pi), st.floats(0.0, 1e5), st.integers(0, 2**32 - 1)
)
def test_synthesis_always_finite(sx, sy, heading, rr, seed):
    b = Band(Q=4.0, tbp=20)
    x = np.array([[[0.0, 0.0], [sx, sy]]])
    pos = hydrophone_positions(x, np.full((1, 2), heading), D=0.75)
    sp = synthesise([np.random.default_rng(seed)], pos, np.array([[sx, sy]]), b, rr)
    assert np.all(np.isfinite(sp))
