"""Six-sector sensing and virtual forces: known answers, brute force and finiteness."""

import math

import numpy as np
import pytest
from hypothesis import assume, example, given, settings
from hypothesis import strategies as st

from shoal.engine.robots.sensing import (
    FRONT,
    LEFT,
    RIGHT,
    S_FLOOR,
    SECTORS,
    SectorReading,
    sector_of,
    sense,
    sorted_gaps,
    virtual_force,
)
from shoal.engine.robots.world import RunSpace, WorldSpec, obstacle_course

RANGE = 3.0


def _spec(circles, polygons=(), walls=None) -> WorldSpec:
    return WorldSpec(
        name="test",
        circles=np.array(circles, dtype=float).reshape(-1, 3),
        polygons=tuple(polygons),
        walls=np.zeros((0, 2, 2)) if walls is None else np.asarray(walls, dtype=float),
        wall_radius=0.1,
        start_box=(-1.0, -1.0, 1.0, 1.0),
        source=(50.0, 0.0),
        layer_x=np.zeros(0),
        bounds=(-50.0, -50.0, 50.0, 50.0),
    )


def _read(spec, robots, heading=None, **kw):
    robots = np.asarray(robots, dtype=float)
    sp = RunSpace(spec, robots)
    h = np.zeros((1, len(robots))) if heading is None else np.asarray(heading, dtype=float).reshape(1, -1)
    return sp, sense([sp], robots[None], h, sensing_range=RANGE, **kw)


def test_sector_boundaries():
    deg = np.array([-180, -150, -120, -60, -1e-9, 0, 59.9, 60, 90, 120, 179.9, 180])
    assert sector_of(np.radians(deg)).tolist() == [0, 0, 1, 2, 2, 3, 3, 4, 4, 5, 5, 0]
    assert SECTORS == 6 and RIGHT == (0, 1, 2) and LEFT == (3, 4, 5) and FRONT == (1, 2, 3, 4)


def test_one_circle_ahead_known_gap_and_empty_sectors_read_the_range():
    _, rd = _read(_spec([[3.0, 0.0, 1.0]]), [[0.0, 0.0]])
    expected = np.full(6, RANGE)
    expected[3] = 3.0 - 1.0 - 0.5
    assert np.allclose(rd.gap[0, 0], expected)
    assert rd.hit[0, 0].tolist() == [False, False, False, True, False, False]
    assert np.allclose(rd.point[0, 0, 3], [2.0, 0.0]) and np.allclose(rd.centre[0, 0, 3], [3.0, 0.0])
    assert np.all(np.isnan(rd.point[0, 0, [0, 1, 2, 4, 5]]))
    assert np.all(np.isnan(rd.centre[0, 0, [0, 1, 2, 4, 5]]))


def test_obstacle_at_90_degrees_is_in_sector_4():
    _, rd = _read(_spec([[0.0, 3.0, 1.0]]), [[0.0, 0.0]])
    assert np.flatnonzero(rd.hit[0, 0]).tolist() == [4]
    assert rd.gap[0, 0, 4] == pytest.approx(1.5)


def test_robot_frame_rotates_the_sectors_with_heading():
    spec = _spec([[3.0, 0.0, 1.0]])
    _, rd = _read(spec, [[0.0, 0.0]], heading=[math.pi / 2], robot_frame=True)
    assert np.flatnonzero(rd.hit[0, 0]).tolist() == [1]  # body at −90° relative: right side
    _, rd = _read(spec, [[0.0, 0.0]], heading=[-math.pi / 4], robot_frame=True)
    assert np.flatnonzero(rd.hit[0, 0]).tolist() == [3]  # +45° relative
    _, rd = _read(spec, [[0.0, 0.0]], heading=[math.pi], robot_frame=True)
    assert np.flatnonzero(rd.hit[0, 0]).tolist() == [0]  # straight behind
    _, rd = _read(spec, [[0.0, 0.0]], heading=[math.pi / 2], robot_frame=False)
    assert np.flatnonzero(rd.hit[0, 0]).tolist() == [3]  # world frame ignores heading
    with pytest.raises(ValueError, match="heading"):
        sense([RunSpace(spec, np.zeros((1, 2)))], np.zeros((1, 1, 2)), None, robot_frame=True)


def test_other_robots_are_sensed_and_inactive_robots_stay_obstacles():
    _, rd = _read(_spec([]), [[0.0, 0.0], [-2.5, 0.0]])
    assert rd.gap[0, 0, 0] == pytest.approx(1.5) and rd.hit[0, 0].sum() == 1  # at 180°: sector 0
    assert rd.gap[0, 1, 3] == pytest.approx(1.5) and np.allclose(rd.centre[0, 1, 3], [0.0, 0.0])
    _, rd = _read(_spec([]), [[0.0, 0.0], [-2.5, 0.0]], active=np.array([[True, False]]))
    assert rd.hit[0, 0, 0] and not rd.hit[0, 1].any() and np.all(rd.gap[0, 1] == RANGE)


def test_body_beyond_range_is_not_sensed_but_one_at_the_edge_is():
    _, rd = _read(_spec([[5.0, 0.0, 1.0]]), [[0.0, 0.0]])  # gap 3.5
    assert not rd.hit.any() and np.all(rd.gap == RANGE)
    _, rd = _read(_spec([[4.49, 0.0, 1.0]]), [[0.0, 0.0]])  # gap 2.99
    assert rd.hit[0, 0, 3] and rd.gap[0, 0, 3] == pytest.approx(2.99)


def test_closest_body_in_a_sector_wins():
    far, near = [2.5, 2.0, 0.5], [2.0, 0.5, 0.5]  # both in sector 3, [0°, 60°)
    _, rd = _read(_spec([far, near]), [[0.0, 0.0]])
    assert np.flatnonzero(rd.hit[0, 0]).tolist() == [3]
    assert rd.gap[0, 0, 3] == pytest.approx(math.hypot(2.0, 0.5) - 1.0)
    assert np.allclose(rd.centre[0, 0, 3], near[:2])


def test_straddling_circle_counts_in_the_sector_of_its_closest_point():
    # a big circle centred at bearing 55° reaches across the 60° border: counted once, in sector 3
    c = 2.5 * np.array([math.cos(math.radians(55)), math.sin(math.radians(55))])
    _, rd = _read(_spec([[*c, 1.5]]), [[0.0, 0.0]])
    assert np.flatnonzero(rd.hit[0, 0]).tolist() == [3]


def test_walls_and_polygons_use_the_closest_point_as_centre():
    wall = [[[-5.0, -2.0], [5.0, -2.0]]]
    square = np.array([[2.0, 1.0], [3.0, 1.0], [3.0, 2.0], [2.0, 2.0]])
    _, rd = _read(_spec([], [square], wall), [[0.0, 0.0]])
    assert rd.gap[0, 0, 1] == pytest.approx(2.0 - 0.1 - 0.5)  # wall straight below, at −90°
    assert np.allclose(rd.centre[0, 0, 1], [0.0, -1.9])
    assert rd.gap[0, 0, 3] == pytest.approx(math.hypot(2.0, 1.0) - 0.5)  # square corner at ~27°
    assert np.allclose(rd.centre[0, 0, 3], [2.0, 1.0]) and np.allclose(rd.point[0, 0, 3], [2.0, 1.0])


def test_contact_reads_zero_and_many_runs_are_independent():
    spec_a, spec_b = _spec([[1.4, 0.0, 1.0]]), _spec([[0.0, -2.0, 1.0]])
    x = np.zeros((2, 1, 2))
    rd = sense([RunSpace(spec_a, x[0]), RunSpace(spec_b, x[1])], x, np.zeros((2, 1)))
    assert rd.gap[0, 0, 3] == 0.0 and rd.hit[0, 0].sum() == 1
    assert rd.gap[1, 0, 1] == pytest.approx(0.5) and rd.hit[1, 0].sum() == 1


def test_sensing_follows_set_positions():
    spec = _spec([])
    sp = RunSpace(spec, np.array([[0.0, 0.0], [20.0, 0.0]]))
    x = np.array([[[0.0, 0.0], [0.0, 2.0]]])
    assert not sense([sp], x, np.zeros((1, 2))).hit[0, 0].any()  # body 1 still at (20, 0)
    sp.set_positions(x[0])
    assert sense([sp], x, np.zeros((1, 2))).gap[0, 0, 4] == pytest.approx(1.0)


def test_virtual_force_known_answer_and_sorted_gaps():
    x = np.zeros((1, 1, 2))
    _, rd = _read(_spec([[3.0, 0.0, 1.0], [0.0, 2.5, 1.0]]), x[0])
    f = virtual_force(x, rd, gamma=2.0)
    assert np.allclose(f[0, 0], [-2.0 / 1.5, -2.0 / 1.0])  # [4.4]: γ·unit/s_p, summed [4.3]
    assert np.allclose(sorted_gaps(rd)[0, 0], [1.0, 1.5, 3, 3, 3, 3])
    assert np.allclose(sorted_gaps(rd, LEFT)[0, 0], [1.0, 1.5, 3.0])
    assert np.allclose(sorted_gaps(rd, RIGHT)[0, 0], [3.0, 3.0, 3.0])
    assert np.allclose(sorted_gaps(rd, FRONT)[0, 0], [1.0, 1.5, 3.0, 3.0])


def test_virtual_force_is_finite_at_contact_and_coincident_centres():
    # robot centre exactly on a circle's centre, and one touching a wall
    spec = _spec([[0.0, 0.0, 1.0]], walls=[[[-5.0, 3.0], [5.0, 3.0]]])
    x = np.array([[[0.0, 0.0], [0.0, 2.45]]])  # robot 1 overlaps the wall by 0.05 m
    sp = RunSpace(spec, x[0])
    rd = sense([sp], x, np.zeros((1, 2)))
    assert rd.gap[0, 0, 1] == 0.0 and rd.gap[0, 1, 4] == 0.0  # inside the circle; on the wall
    assert np.allclose(rd.centre[0, 0, 1], [0.0, 0.0])  # coincides with the robot centre
    f = virtual_force(x, rd)
    assert np.all(np.isfinite(f))
    assert f[0, 1, 1] < 0 and abs(f[0, 1, 1]) == pytest.approx(1.0 / S_FLOOR, rel=0.01)  # pushed off the wall


circle = st.tuples(st.floats(-6, 6), st.floats(-6, 6), st.floats(0.1, 2.0))
point = st.tuples(st.floats(-6, 6), st.floats(-6, 6))


def _expected(circles: np.ndarray, robots: np.ndarray, rr: float, rng_: float) -> tuple[np.ndarray, bool]:
    """Brute-force sector gaps; ``ok`` is False if a case sits on a border (float ties)."""
    n = len(robots)
    gaps = np.full((n, 6), rng_)
    ok = True
    for i in range(n):
        others = [np.append(robots[j], rr) for j in range(n) if j != i]
        bodies = np.vstack([circles.reshape(-1, 3), *others]) if others else circles.reshape(-1, 3)
        d = bodies[:, :2] - robots[i]
        dist = np.hypot(d[:, 0], d[:, 1])
        gap = np.maximum(dist - bodies[:, 2] - rr, 0.0)
        deg = np.degrees(np.arctan2(d[:, 1], d[:, 0]))
        near_border = np.min(np.abs(((deg + 180.0) % 60.0 + 30.0) % 60.0 - 30.0)) if len(deg) else 99
        # centres 1e-5 m apart or closer: pymunk's gradient there is a fixed direction, not the
        # bearing (its test is d > 1e-5, so exactly 1e-5 falls back too)
        if len(deg) and (dist.min() <= 1e-5 or near_border < 1e-6 or np.min(np.abs(gap - rng_)) < 1e-6):
            ok = False
        k = (np.floor((deg + 180.0) / 60.0).astype(int)) % 6
        for g, s in zip(gap, k):
            if g <= rng_:
                gaps[i, s] = min(gaps[i, s], g)
    return gaps, ok


@settings(max_examples=60, deadline=None)
@given(st.lists(circle, max_size=8), st.lists(point, min_size=1, max_size=5), st.floats(0.5, 4.0))
@example([(0.0, 0.0, 1.0)], [(0.0, -1e-05)], 1.0)  # a centre exactly 1e-5 m from an obstacle's: skipped
@example([(0.0, 0.0, 1.0)], [(0.0, -2e-05)], 1.0)  # inside, just beyond it: the bearing to the centre
def test_gaps_match_brute_force_geometry(circles, robots, rng_):
    circles = np.array(circles, dtype=float).reshape(-1, 3)
    robots = np.array(robots, dtype=float)
    expected, ok = _expected(circles, robots, 0.5, rng_)
    assume(ok)
    sp = RunSpace(_spec(circles), robots)
    rd = sense([sp], robots[None], np.zeros((1, len(robots))), sensing_range=rng_)
    assert np.all((rd.gap >= 0) & (rd.gap <= rng_))
    assert np.allclose(rd.gap[0], expected, atol=1e-9)
    assert np.array_equal(rd.hit[0], expected < rng_)
    assert np.all(np.isfinite(virtual_force(robots[None], rd)))


@settings(max_examples=100, deadline=None)
@given(
    st.integers(0, 2**32 - 1),
    st.floats(0.0, 1.0),  # share of gaps forced to 0 (contact)
    st.floats(0.0, 1.0),  # share of centres forced onto x_i
    st.floats(1e-6, 1e6),
)
def test_virtual_force_is_finite_for_any_reading(seed, p_contact, p_coincide, gamma):
    g = np.random.default_rng(seed)
    R, N = 3, 4
    x = g.uniform(-10, 10, (R, N, 2))
    hit = g.random((R, N, 6)) < 0.7
    gap = np.where(g.random((R, N, 6)) < p_contact, 0.0, g.uniform(0, 3, (R, N, 6)))
    centre = np.where((g.random((R, N, 6)) < p_coincide)[..., None], x[:, :, None, :], g.uniform(-10, 10, (R, N, 6, 2)))
    centre = np.where(hit[..., None], centre, np.nan)
    rd = SectorReading(gap=np.where(hit, gap, 3.0), point=centre.copy(), centre=centre, hit=hit)
    f = virtual_force(x, rd, gamma=gamma)
    assert f.shape == (R, N, 2) and np.all(np.isfinite(f))
    assert np.all(np.linalg.norm(f, axis=-1) <= 6 * gamma / S_FLOOR * (1 + 1e-9))


def test_obstacle_course_reading_shapes():
    spec = obstacle_course(seed=0)
    g = np.random.default_rng(0)
    R, N = 3, 6
    x = np.stack([np.column_stack([g.uniform(8, 40, N), g.uniform(-10, 10, N)]) for _ in range(R)])
    spaces = [RunSpace(spec, x[r]) for r in range(R)]
    rd = sense(spaces, x, np.zeros((R, N)))
    assert rd.gap.shape == (R, N, 6) and rd.point.shape == (R, N, 6, 2) and rd.centre.shape == (R, N, 6, 2)
    assert np.all((rd.gap >= 0) & (rd.gap <= RANGE))
    assert np.array_equal(np.isnan(rd.point[..., 0]), ~rd.hit)
