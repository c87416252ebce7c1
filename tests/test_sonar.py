"""The acoustic swarm of Chapters 7–8 (engine/kinds/sonar.py) and open-sea sensing."""

from __future__ import annotations

import numpy as np
import pytest

from shoal.engine.acoustics.strategies import STRATEGIES
from shoal.engine.kinds.sonar import AcousticSwarm, SonarParams, straight_line_steps
from shoal.engine.robots.sensing import sense
from shoal.engine.robots.swarm_sensing import sense_robots
from shoal.engine.robots.world import RunSpace, WorldSpec

ARRAYS = ("x", "heading", "u", "cmd", "y", "f_hat", "y_g", "source", "snr_db", "steps", "first_converged")


def advance(sw: AcousticSwarm, k: int) -> AcousticSwarm:
    for _ in range(k):
        sw.step()
    return sw


def same_state(a, b, run_a=slice(None), run_b=slice(None)) -> None:
    for name in ARRAYS:
        np.testing.assert_array_equal(getattr(a.state, name)[run_a], getattr(b.state, name)[run_b], err_msg=name)


CASES = [
    SonarParams(algorithm="xb-pso"),
    SonarParams(algorithm="a-pso", mode="surrogate"),
    SonarParams(algorithm="gt-pso", controller="nonomni", r_trap=30.0, v_n=0.1),
]


@pytest.mark.parametrize("params", CASES, ids=lambda p: f"{p.algorithm}-{p.controller}-{p.mode}")
def test_seeded_runs_repeat_and_a_run_is_the_same_alone_or_in_a_batch(params):
    a = advance(AcousticSwarm(params, robots=6, runs=3, seed=5), 25)
    b = advance(AcousticSwarm(params, robots=6, runs=3, seed=5), 25)
    same_state(a, b)
    alone = advance(AcousticSwarm(params, robots=6, runs=1, seed=5, first_run=2), 25)
    same_state(a, alone, 2, 0)
    other = advance(AcousticSwarm(params, robots=6, runs=1, seed=6, first_run=2), 25)
    assert not np.array_equal(other.state.x[0], alone.state.x[0])


def test_initial_layout_follows_initial_state_and_partners():
    p = SonarParams(snr0_db=4.0)
    sw = AcousticSwarm(p, robots=50, runs=4, seed=1)
    s = sw.state
    assert np.all(np.linalg.norm(s.x, axis=-1) <= p.d0)
    np.testing.assert_allclose(np.linalg.norm(s.source, axis=-1), p.r_ref * 10 ** (-4 / 20))  # d_s
    assert p.r_ref == pytest.approx(1000.0) and p.D == pytest.approx(0.75)
    assert np.all(s.f_hat == 0) and np.array_equal(s.y, s.x) and np.all(s.u == 0)
    assert straight_line_steps(p) == pytest.approx((631.0 - 50.0) / 2.0, abs=0.1)


def test_bpso_at_high_snr_converges_quickly():
    p = SonarParams(algorithm="b-pso", snr0_db=20.0, stop_on_converge=True)  # d_s = 100 m
    sw = AcousticSwarm(p, robots=10, runs=4, seed=3)
    for _ in range(400):
        if not sw.running.any():
            break
        info = sw.step()
    assert info.converged.all()
    assert np.all(info.steps_to_converge >= straight_line_steps(p))
    assert np.all(info.com_dist <= p.dc)


def test_stopping_converged_runs_freezes_them_and_keeps_their_times():
    free = SonarParams(algorithm="xb-pso", snr0_db=20.0, mode="surrogate")
    stop = SonarParams(algorithm="xb-pso", snr0_db=20.0, mode="surrogate", stop_on_converge=True)
    a, b = AcousticSwarm(free, robots=8, runs=3, seed=2), AcousticSwarm(stop, robots=8, runs=3, seed=2)
    for _ in range(300):
        a.step(), b.step()
    assert b.state.first_converged.min() >= 0
    np.testing.assert_array_equal(a.state.first_converged, b.state.first_converged)
    np.testing.assert_array_equal(b.state.steps, b.state.first_converged)  # frozen at convergence
    assert not b.running.any() and a.running.all()


def test_escorting_robots_settle_near_the_ring():
    r = 30.0
    p = SonarParams(algorithm="gt-pso", controller="nonomni", r_trap=r, start="source", d0=40.0)
    sw = AcousticSwarm(p, robots=16, runs=2, seed=4)
    d = []
    for k in range(500):
        info = sw.step()
        if k >= 300:
            d.append(info.mean_dist_to_source)
    mean = np.mean(d, axis=0)
    assert np.all((mean > 0.8 * r) & (mean < r + 25.0)), mean
    assert np.all(info.frac_inside_ring < 0.35)


def test_moving_source_speed_is_vn_times_u():
    p = SonarParams(algorithm="gt-pso", controller="nonomni", v_n=0.25, source_heading=0.0)
    sw = advance(AcousticSwarm(p, robots=5, runs=2, seed=0), 10)
    np.testing.assert_allclose(sw.state.source - sw.source0, [[5.0, 0.0]] * 2)  # 10 s × 0.5 m/s along +x


@pytest.mark.parametrize("controller", ["adapted", "nonomni"])
@pytest.mark.parametrize("algorithm", sorted(STRATEGIES))
def test_a_robot_on_top_of_the_source_gives_no_nan(algorithm, controller):
    p = SonarParams(algorithm=algorithm, controller=controller, r_trap=20.0 if controller == "nonomni" else 0.0)
    sw = AcousticSwarm(p, robots=5, runs=2, seed=1)
    sw.state.x[:, 0] = sw.state.source
    sw.state.x[:, 1] = sw.state.source + [0.3, 0.0]  # a hydrophone almost on it too
    for _ in range(4):
        info = sw.step()
        for name in ARRAYS:
            assert np.all(np.isfinite(getattr(sw.state, name))), name
        assert np.all(np.isfinite(info.com_dist))


def test_surrogate_full_lag_and_escort_without_nonomni_are_refused():
    with pytest.raises(ValueError, match="full_lag"):
        SonarParams(mode="surrogate", full_lag=True)
    with pytest.raises(ValueError, match="r_trap"):
        SonarParams(r_trap=50.0)
    with pytest.raises(ValueError, match="gt-pso"):
        AcousticSwarm(SonarParams(algorithm="gt-pso"), robots=3)


def test_state_exposes_what_the_app_draws():
    sw = advance(AcousticSwarm(SonarParams(algorithm="xb-pso"), robots=4, runs=1, seed=0), 2)
    s = sw.state
    assert s.bearing.rays.shape == (1, 4, 2, 2) and s.bearing.corr.shape[:2] == (1, 4)
    assert s.loc.points.shape == (1, 4, 4, 2) and s.loc.selected.shape == (1, 4)
    assert s.snr_db.shape == (1, 4) and s.y_g.shape == (1, 2)
    gt = advance(AcousticSwarm(SonarParams(algorithm="gt-pso", controller="nonomni"), robots=5, seed=0), 2)
    assert gt.state.loc.triangles.members.shape == (1, 5, 3) and gt.state.reading.gap.shape == (1, 5, 6)


def test_open_sea_sensing_matches_pymunk_sensing():
    sea = WorldSpec("sea", np.zeros((0, 3)), (), np.zeros((0, 2, 2)), 0.1, (-50, -50, 50, 50), (0.0, 0.0),
                    bounds=(-1e5, -1e5, 1e5, 1e5))
    rng = np.random.default_rng(7)
    x = rng.uniform(-25, 25, (3, 30, 2))
    o = rng.uniform(-np.pi, np.pi, (3, 30))
    ref = sense([RunSpace(sea, x[r], 1.0) for r in range(3)], x, o, sensing_range=10.0, robot_frame=True)
    got = sense_robots(x, o, robot_radius=1.0, sensing_range=10.0)
    np.testing.assert_allclose(got.gap, ref.gap, atol=1e-12)
    np.testing.assert_array_equal(got.hit, ref.hit)
    apart = ref.hit & (ref.gap > 0)  # overlapping robots tie at gap 0 (either may be kept)
    np.testing.assert_allclose(got.point[apart], ref.point[apart], atol=1e-9)
    np.testing.assert_allclose(got.centre[apart], ref.centre[apart], atol=1e-12)


@pytest.mark.parametrize("preset", ["sonar-xb-pso", "sonar-gt-pso", "escort-stationary", "escort-moving"])
def test_shipped_acoustic_presets_build_and_record(preset, tmp_path):
    from shoal.engine.core.runs import run_to_dir
    from shoal.presets.build import build
    from shoal.presets.io import load

    scenario = load(preset, ["sim.runs=2", "sim.steps=3"])
    sw = build(scenario)
    assert isinstance(sw, AcousticSwarm) and sw.robots == scenario.sim.robots
    run_to_dir(sw, 3, tmp_path / "out", {"preset": preset})
    traj = (tmp_path / "out" / "trajectories.csv").read_text().splitlines()
    assert traj[0] == "run,step,t,robot,x,y,heading,vx,vy,status"
    assert len(traj) == 1 + 4 * 2 * scenario.sim.robots
    metrics = (tmp_path / "out" / "metrics.csv").read_text().splitlines()
    cols = metrics[0].split(",")
    assert {"com_dist", "converged", "steps_to_converge", "frac_inside_ring", "mean_dist_to_source"} <= set(cols)
    assert len(metrics) == 1 + 4 * 2


def test_acoustic_preset_rules_name_the_field():
    from shoal.presets.io import PresetError, validate

    for patch, words in [
        ({"acoustics": {"mode": "surrogate", "full_lag": True}}, ("acoustics", "full_lag")),
        ({"acoustics": {"r": 50.0}}, ("acoustics", "nonomni")),
        ({"acoustics": {"algorithm": "gt-pso"}, "sim": {"robots": 3}}, ("sim.robots", "gt-pso")),
        ({"acoustics": {"Q": 0.0}}, ("acoustics.Q",)),
        ({"acoustics": {"speed": 1.0}}, ("acoustics.speed",)),
        ({"acoustics": {}, "world": {}}, ("[world]",)),
    ]:
        with pytest.raises(PresetError) as e:
            validate(patch)
        assert any(all(w in m for w in words) for m in e.value.messages), e.value.messages


def test_lag_peak_reaches_the_receiver_in_both_acoustic_modes():
    from shoal.presets.build import build_sonar
    from shoal.presets.io import load

    for mode in ("waveform", "surrogate"):
        sw = build_sonar(load("sonar-xb-pso", [f"acoustics.mode={mode}", "acoustics.lag_peak=sample",
                                               "acoustics.fs=4000"]), runs=2, seed=3)
        assert sw.params.lag_peak == "sample"
        sw.step()
        tau = sw.state.bearing.tau
        assert np.allclose(tau * 4000.0, np.round(tau * 4000.0))
