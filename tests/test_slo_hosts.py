"""SLO-estimated positions for the Chapter 4–5 fleet and the Chapter 7–8 acoustic swarm:
oracle vs SLO on the same seed, through the presets (``[slo] swarm = "host"``)."""

from __future__ import annotations

import numpy as np
import pytest

from shoal.engine.acoustics.frames import frame_draws
from shoal.engine.kinds.fleet import Fleet
from shoal.engine.kinds.sonar import AcousticSwarm
from shoal.engine.slo.positions import Estimated, Oracle
from shoal.presets.build import build
from shoal.presets.io import PresetError, load


def host(name: str, positions: str, errors: str = "none", *more: str):
    """The preset's own swarm with an [slo] section (full neighbourhood: every pair localised)."""
    return load(name, ["slo.swarm=host", f"slo.positions={positions}", f"slo.errors={errors}",
                       "slo.neighbourhood=full", *more])


def positions(sim, steps: int) -> np.ndarray:
    out = []
    for _ in range(steps):
        sim.step()
        out.append(sim.state.x.copy())
    return np.stack(out)


# ---------------------------------------------------------------------- fleet
@pytest.mark.parametrize("name", ["course-dvc", "course-nonomni"])
def test_fleet_oracle_positions_are_the_plain_fleet_bit_for_bit(name):
    plain = build(load(name), runs=2, seed=4)
    oracle = build(host(name, "oracle"), runs=2, seed=4)
    assert type(plain) is Fleet and type(oracle) is Fleet and isinstance(oracle.positions, Oracle)
    assert np.array_equal(positions(plain, 40), positions(oracle, 40))


@pytest.mark.parametrize("name", ["course-dvc", "course-nonomni", "course-rpso"])
def test_error_free_slo_fleet_follows_the_oracle_run(name):
    oracle = positions(build(host(name, "oracle"), runs=2, seed=4), 40)
    slo = build(host(name, "slo"), runs=2, seed=4)
    assert type(slo) is Fleet and isinstance(slo.positions, Estimated)
    np.testing.assert_allclose(positions(slo, 40), oracle, rtol=0, atol=1e-8)


def test_high_error_fleet_differs_stays_finite_and_keeps_collided_robots():
    scenario = host("course-rpso", "slo", "high")
    oracle = positions(build(host("course-rpso", "oracle"), runs=2, seed=1), 60)
    fleet = build(scenario, runs=2, seed=1)
    noisy = positions(fleet, 60)
    assert np.isfinite(noisy).all() and np.isfinite(fleet.positions.pbest).all()
    assert np.abs(noisy - oracle).max() > 1.0
    hit = fleet.state.status != 0
    assert hit.any(), "course-rpso should collide within 60 steps"
    assert np.array_equal(noisy[-1][hit], noisy[-10][hit])  # collided robots stand still ...
    est = fleet.positions.beliefs
    assert est.valid[hit].any()  # ... and still localise the others
    again = positions(build(scenario, runs=2, seed=1), 60)
    assert np.array_equal(noisy, again)


def test_slo_unit_scales_with_the_world():
    fleet = build(host("course-dvc", "slo", "low"))
    assert fleet.positions.unit == pytest.approx(0.62)  # the course is 62 m long
    sonar = build(host("sonar-xb-pso", "slo", "low"))
    assert sonar.positions.unit == pytest.approx(1.0)  # deployed in a disc 100 m across
    assert build(host("sonar-xb-pso", "slo", "low", "slo.unit=2.5")).positions.unit == 2.5


# ---------------------------------------------------------------------- sonar
SONAR_CASES = [  # (preset overrides, steps): nonomni with a ring flips discrete choices on rounding, and the
    # sample lag of the Chapter 7 preset adds one more such choice, so that case refines the lag
    (("acoustics.algorithm=xb-pso",), 40),
    (("acoustics.algorithm=b-pso", "acoustics.mode=surrogate", "acoustics.stop_on_converge=true"), 40),
    (("acoustics.algorithm=a-pso", "acoustics.mode=surrogate"), 40),
    (("acoustics.algorithm=gt-pso", "acoustics.controller=nonomni", "acoustics.mode=surrogate"), 40),
    (("acoustics.algorithm=xb-pso", "acoustics.controller=nonomni", "acoustics.mode=surrogate",
      "acoustics.r=20", "acoustics.v_n=0.3", "acoustics.start=source", "acoustics.lag_peak=parabolic"), 8),
]


@pytest.mark.parametrize(("more", "steps"), SONAR_CASES)
def test_error_free_slo_sonar_follows_the_oracle_run(more, steps):
    plain = build(load("sonar-xb-pso", list(more)), runs=2, seed=3)
    oracle = build(host("sonar-xb-pso", "oracle", "none", *more), runs=2, seed=3)
    slo = build(host("sonar-xb-pso", "slo", "none", *more), runs=2, seed=3)
    assert type(oracle) is type(slo) is AcousticSwarm and oracle.positions.exact and not slo.positions.exact
    truth = positions(plain, steps)
    assert np.array_equal(positions(oracle, steps), truth)
    np.testing.assert_allclose(positions(slo, steps), truth, rtol=0, atol=1e-8)
    np.testing.assert_allclose(slo.state.y_g, plain.state.y_g, rtol=0, atol=1e-6)
    np.testing.assert_allclose(slo.believed_gbest(), np.repeat(plain.state.y_g[:, None], 10, 1), rtol=0, atol=1e-6)


def test_high_error_sonar_differs_but_keeps_the_oracle_partners():
    more = ("acoustics.mode=surrogate",)
    oracle = build(host("sonar-xb-pso", "oracle", "none", *more), runs=2, seed=3)
    noisy = build(host("sonar-xb-pso", "slo", "high", *more), runs=2, seed=3)
    oracle.step(), noisy.step()
    assert np.array_equal(noisy.state.loc.partner, oracle.state.loc.partner)  # the same draws
    a, b = positions(oracle, 60), positions(noisy, 60)
    assert np.isfinite(b).all() and np.isfinite(noisy.believed_gbest()).all()
    assert np.abs(a - b).max() > 1.0
    spread = np.linalg.norm(noisy.believed_gbest() - noisy.state.y_g[:, None], axis=-1)
    assert spread.max() > 0.0  # each robot has its own belief of the global best


# ---------------------------------------------------------------------- pieces
def test_estimated_positions_with_exact_beliefs_are_the_oracle_vectors():
    rng = np.random.default_rng(2)
    x = rng.uniform(-10, 10, (2, 5, 2))
    y = x + rng.uniform(-1, 1, x.shape)
    oracle, est = Oracle(), Estimated(errors="none")
    est.start(x, y, 0, seed=0, first_run=0)
    owner = np.array([3, 1])
    for pos in (oracle, est):
        np.testing.assert_allclose(pos.to_personal(x, y), y - x, atol=1e-12)
        np.testing.assert_allclose(pos.to_owner(x, y, owner), y[np.arange(2), owner][:, None] - x, atol=1e-12)
        np.testing.assert_allclose(pos.to_centroid(x, y), y.mean(axis=1)[:, None] - x, atol=1e-12)
        np.testing.assert_allclose(pos.placed(x), np.broadcast_to(x[:, None], (2, 5, 5, 2)), atol=1e-12)
    move = rng.uniform(-1, 1, x.shape)
    assert est.observe(x + move, 1) and not est.observe(x + move, 1)  # once per tick
    assert not oracle.observe(x + move, 1)
    np.testing.assert_allclose(est.pbest, y - x - move, atol=1e-12)
    est.keep(np.array([[True, False, False, False, False]] * 2))
    assert np.all(est.pbest[:, 0] == 0) and np.all(est.pbest[:, 1] != 0)
    with pytest.raises(ValueError, match="^slo: this swarm acts on true positions"):
        oracle.retune(errors="high")
    with pytest.raises(ValueError, match="d = 2"):
        Estimated().start(np.zeros((1, 4, 3)), np.zeros((1, 4, 3)), 0, 0, 0)


def test_frames_of_one_run_share_its_draws():
    gens = [np.random.default_rng(5), np.random.default_rng(6)]
    ref = [np.random.default_rng(5).random(4), np.random.default_rng(6).random(4)]
    frames = frame_draws(gens, 3)
    rows = [f.random(4) for f in frames]
    for r in range(2):
        for i in range(3):
            assert np.array_equal(rows[3 * r + i], ref[r])


# ---------------------------------------------------------------------- presets
@pytest.mark.parametrize(("name", "plain", "engine"), [("course-dvc-slo", "course-dvc", Fleet),
                                                       ("sonar-xb-pso-slo", "sonar-xb-pso", AcousticSwarm)])
def test_shipped_presets_run_on_slo_and_switch_to_the_plain_scene(name, plain, engine):
    scenario = load(name)
    assert scenario.slo.errors == "low" and scenario.slo.swarm == "host"
    sim = build(scenario)
    assert type(sim) is engine and isinstance(sim.positions, Estimated)
    assert np.isfinite(positions(sim, 10)).all()
    oracle = build(load(name, ["slo.positions=oracle"]))
    assert type(oracle) is type(build(load(plain))) and oracle.positions.exact
    assert np.array_equal(positions(oracle, 20), positions(build(load(plain)), 20))


def test_chapter3_is_read_as_host():
    assert load("slo-adapted", ["slo.swarm=chapter3"]).slo.swarm == "host"


@pytest.mark.parametrize(("preset", "override", "field"), [
    ("course-dvc-slo", "slo.swarm=slo", "slo.swarm"),
    ("sonar-xb-pso-slo", "slo.swarm=slo", "slo.swarm"),
    ("course-dvc-slo", "slo.swarm=fleet", "slo.swarm"),
    ("course-dvc-slo", "slo.positions=true", "slo.positions"),
    ("sonar-xb-pso-slo", "slo.errors=medium", "slo.errors"),
    ("course-dvc-slo", "sim.robots=1", "sim.robots"),
    ("sonar-xb-pso-slo", "slo.unit=0", "slo.unit"),
])
def test_bad_slo_host_settings_name_the_field(preset, override, field):
    with pytest.raises(PresetError) as err:
        load(preset, [override])
    assert any(m.startswith(field) for m in err.value.messages), err.value.messages
