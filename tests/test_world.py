"""Worlds as data and their pymunk spaces: course layout, edits, and RunSpace sync."""

import dataclasses

import numpy as np
import pymunk
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from shoal.engine.robots.world import (
    CAT_ROBOT,
    OBSTACLE,
    ROBOT,
    RunSpace,
    WorldSpec,
    empty_arena,
    forest,
    obstacle_course,
    world_from_name,
)


def _layers(spec: WorldSpec) -> list[np.ndarray]:
    """Circles of each layer (nearest layer_x), sorted across the course (by y)."""
    which = np.argmin(np.abs(spec.circles[:, :1] - spec.layer_x[None, :]), axis=1)
    out = []
    for k in range(len(spec.layer_x)):
        c = spec.circles[which == k]
        out.append(c[np.argsort(c[:, 1])])
    return out


def _neighbour_gaps(c: np.ndarray) -> np.ndarray:
    """Surface gaps between circles next to each other in a layer."""
    return np.hypot(*(c[1:, :2] - c[:-1, :2]).T) - c[1:, 2] - c[:-1, 2]


def _wall_gaps(spec: WorldSpec, c: np.ndarray) -> tuple[float, float]:
    _, y0, _, y1 = spec.bounds
    w = spec.wall_radius
    return c[0, 1] - c[0, 2] - (y0 + w), (y1 - w) - (c[-1, 1] + c[-1, 2])


def _box_distance(box, c: np.ndarray) -> np.ndarray:
    """Distance from each circle's surface to an axis-aligned box (negative = overlap)."""
    x0, y0, x1, y1 = box
    dx = np.maximum(np.maximum(x0 - c[:, 0], c[:, 0] - x1), 0.0)
    dy = np.maximum(np.maximum(y0 - c[:, 1], c[:, 1] - y1), 0.0)
    return np.hypot(dx, dy) - c[:, 2]


def test_course_has_layers_getting_denser_toward_the_source():
    spec = obstacle_course(seed=0)
    assert len(spec.layer_x) >= 6
    assert np.all(np.diff(spec.layer_x) > 0)
    assert spec.source[0] > spec.layer_x[-1] + 2.0 > spec.start_box[2]
    layers = _layers(spec)
    assert all(len(c) >= 2 for c in layers)
    mean_gap = np.array([_neighbour_gaps(c).mean() for c in layers])
    assert np.all(np.diff(mean_gap) < 0), mean_gap
    counts = np.array([len(c) for c in layers])
    assert counts[-1] > counts[0]
    assert np.all((spec.circles[:, 2] >= 0.5) & (spec.circles[:, 2] <= 1.0))


def test_course_start_box_and_source_are_clear():
    spec = obstacle_course(seed=3)
    assert np.all(_box_distance(spec.start_box, spec.circles) > 1.0)
    sx, sy = spec.source
    assert np.all(np.hypot(spec.circles[:, 0] - sx, spec.circles[:, 1] - sy) - spec.circles[:, 2] > 2.0)
    x0, y0, x1, y1 = spec.bounds
    assert x0 < spec.start_box[0] and spec.start_box[2] < sx < x1 and y0 < sy < y1


def test_course_first_layer_admits_a_1m_robot():
    for seed in range(10):
        spec = obstacle_course(seed=seed)
        first = _layers(spec)[0]
        assert np.all(_neighbour_gaps(first) > 1.0)
        assert min(_wall_gaps(spec, first)) > 1.0


def test_course_is_reproducible_and_seed_dependent():
    a, b = obstacle_course(seed=5), obstacle_course(seed=5)
    assert a == b and np.array_equal(a.circles, b.circles)
    assert obstacle_course(seed=np.random.default_rng(5)) == a
    assert not np.array_equal(obstacle_course(seed=6).circles, a.circles)


@settings(max_examples=30, deadline=None)
@given(
    seed=st.integers(0, 2**31 - 1),
    layers=st.integers(1, 10),
    length=st.floats(45.0, 150.0),
    width=st.floats(15.0, 60.0),
    jitter=st.floats(0.0, 0.3),
)
def test_course_gaps_never_fall_below_the_jitter_bound(seed, layers, length, width, jitter):
    first_gap, last_gap = 4.0, 1.5
    spec = obstacle_course(seed=seed, layers=layers, length=length, width=width, jitter=jitter)
    assert len(spec.layer_x) == layers
    targets = np.linspace(first_gap, last_gap, layers)
    for g, c in zip(targets, _layers(spec)):
        if len(c) > 1:
            assert _neighbour_gaps(c).min() >= (1 - 2 * jitter) * g - 1e-9
        if len(c):
            assert min(_wall_gaps(spec, c)) >= g - 1e-9
    assert np.all(_box_distance(spec.start_box, spec.circles) > 0)


def test_course_rejects_impossible_parameters():
    with pytest.raises(ValueError, match="length"):
        obstacle_course(length=15.0)
    with pytest.raises(ValueError, match="layers"):
        obstacle_course(layers=0)
    with pytest.raises(ValueError, match="radius"):
        obstacle_course(radius_min=1.0, radius_max=0.5)


def test_empty_arena_has_walls_only():
    spec = empty_arena(40.0)
    assert spec.circles.shape == (0, 3) and spec.polygons == () and spec.walls.shape == (4, 2, 2)
    x0, y0, x1, y1 = spec.bounds
    assert x1 - x0 == 40.0 and y1 - y0 == 40.0
    sx, sy = spec.source
    bx0, by0, bx1, by1 = spec.start_box
    assert not (bx0 <= sx <= bx1 and by0 <= sy <= by1)
    assert (sx, sy) != (0.0, 0.0) and x0 < bx0 < bx1 < x1


def test_forest_circles_do_not_overlap_and_keep_start_and_source_clear():
    spec = forest(seed=1, size=40.0, density=0.05, radius=(0.3, 0.8))
    c = spec.circles
    assert len(c) > 20
    d = np.hypot(c[:, None, 0] - c[None, :, 0], c[:, None, 1] - c[None, :, 1]) - c[:, None, 2] - c[None, :, 2]
    np.fill_diagonal(d, np.inf)
    assert d.min() >= 1.2
    assert np.all(_box_distance(spec.start_box, c) > 0)
    assert np.all(np.hypot(c[:, 0] - spec.source[0], c[:, 1] - spec.source[1]) - c[:, 2] >= 3.0)
    cover = np.sum(np.pi * c[:, 2] ** 2) / 40.0**2
    assert 0.04 < cover < 0.06
    assert np.all((c[:, 2] >= 0.3) & (c[:, 2] <= 0.8))
    assert forest(seed=1) == spec and forest(seed=2) != spec


def test_world_from_name_dispatches_and_validates():
    assert world_from_name("obstacle-course", seed=2, layers=7).layer_x.size == 7
    assert world_from_name("empty", size=30.0) == empty_arena(30.0)
    assert world_from_name("forest", seed=4) == forest(seed=4)
    with pytest.raises(ValueError, match="unknown world"):
        world_from_name("maze")
    with pytest.raises(TypeError):
        world_from_name("forest", layers=3)
    assert world_from_name("forest", ignore_unknown=True, seed=4, layers=3) == forest(seed=4)


def _tiny() -> WorldSpec:
    return WorldSpec(
        name="tiny",
        circles=np.array([[3.0, 0.0, 1.0], [-4.0, 0.0, 0.5]]),
        polygons=(np.array([[0.0, 5.0], [0.0, 6.0], [1.0, 6.0], [1.0, 5.0]]),),  # clockwise on purpose
        walls=np.array([[[-10.0, -10.0], [10.0, -10.0]]]),
        wall_radius=0.1,
        start_box=(-1.0, -1.0, 1.0, 1.0),
        source=(8.0, 0.0),
        layer_x=np.zeros(0),
        bounds=(-10.0, -10.0, 10.0, 10.0),
    )


def test_spec_is_frozen_and_edits_return_new_specs():
    spec = _tiny()
    with pytest.raises(dataclasses.FrozenInstanceError):
        spec.name = "other"  # type: ignore[misc]
    with pytest.raises(ValueError):
        spec.circles[0, 0] = 9.0
    p = spec.polygons[0]
    assert np.sum(p[:, 0] * np.roll(p[:, 1], -1) - np.roll(p[:, 0], -1) * p[:, 1]) > 0  # now CCW
    more = spec.with_circle(0.0, -5.0, 0.7)
    assert more is not spec and len(more.circles) == 3 and len(spec.circles) == 2
    assert np.array_equal(more.circles[2], [0.0, -5.0, 0.7])
    fewer = spec.without_obstacle_near(2.2, 0.0)
    assert np.array_equal(fewer.circles, [[-4.0, 0.0, 0.5]])
    assert spec.without_obstacle_near(0.0, -5.0) is spec  # nothing within tolerance
    no_poly = spec.without_obstacle_near(0.5, 5.5)  # inside the square
    assert no_poly.polygons == () and len(no_poly.circles) == 2
    moved = spec.moved_obstacle(1, 1.0, 2.0)
    assert np.array_equal(moved.circles[1], [1.0, 2.0, 0.5]) and np.array_equal(spec.circles[1], [-4.0, 0.0, 0.5])
    moved_poly = spec.moved_obstacle(2, -5.0, -5.0)
    assert np.allclose(moved_poly.polygons[0].mean(axis=0), [-5.0, -5.0])
    with pytest.raises(IndexError):
        spec.moved_obstacle(3, 0.0, 0.0)


ALL_MASKS = pymunk.ShapeFilter.ALL_MASKS()


def _nearest(rs: RunSpace, pt, mask=ALL_MASKS):
    return rs.space.point_query_nearest(pt, 0.05, pymunk.ShapeFilter(mask=mask))


def test_runspace_builds_shapes_with_types_and_filters():
    spec = _tiny()
    rs = RunSpace(spec, np.array([[0.0, 0.0], [0.0, 2.0]]))
    assert len(rs.circle_shapes) == 2 and len(rs.polygon_shapes) == 1 and len(rs.wall_shapes) == 1
    assert all(s.collision_type == OBSTACLE for s in rs.obstacle_shapes + rs.wall_shapes)
    assert all(s.collision_type == ROBOT and s.radius == 0.5 for s in rs.robot_shapes)
    assert rs.space.collision_slop <= 0.01
    assert [s.filter.group for s in rs.robot_shapes] == [1, 2]
    assert rs.robot_of(rs.robot_shapes[1]) == 1 and rs.robot_of(rs.circle_shapes[0]) is None
    # a robot's own filter skips its own shape but sees the other robot
    hits = rs.space.point_query((0.0, 0.0), 2.5, rs.filters[0])
    assert rs.robot_shapes[0] not in [h.shape for h in hits]
    assert rs.robot_shapes[1] in [h.shape for h in hits]
    assert _nearest(rs, (0.5, 5.5)).shape is rs.polygon_shapes[0]


def test_runspace_set_positions_reindexes_for_queries():
    rs = RunSpace(_tiny(), np.array([[0.0, 0.0], [0.0, 2.0]]))
    new = np.array([[6.0, 6.0], [-6.0, -6.0]])
    rs.set_positions(new)
    assert np.array_equal(rs.positions(), new)
    hit = _nearest(rs, (6.0, 6.0), CAT_ROBOT)
    assert hit is not None and hit.shape is rs.robot_shapes[0]
    assert _nearest(rs, (0.0, 0.0), CAT_ROBOT) is None
    with pytest.raises(ValueError):
        rs.set_positions(np.zeros((3, 2)))


def test_runspace_edits_keep_spec_and_space_in_sync():
    rs = RunSpace(_tiny(), np.zeros((1, 2)))
    i = rs.add_circle(0.0, -5.0, 0.7)
    assert i == 2 and len(rs.spec.circles) == 3
    assert _nearest(rs, (0.0, -5.0)).shape is rs.circle_shapes[2]
    assert rs.remove_obstacle_near(2.2, 0.0) == 0
    assert len(rs.spec.circles) == 2 and _nearest(rs, (3.0, 0.0)) is None
    assert rs.remove_obstacle_near(9.0, 9.0) is None
    rs.move_obstacle(0, 5.0, 5.0 - 10.0)  # the former circle 1 at (-4, 0)
    assert np.array_equal(rs.spec.circles[0], [5.0, -5.0, 0.5])
    assert _nearest(rs, (-4.0, 0.0)) is None and _nearest(rs, (5.0, -5.0)).shape is rs.circle_shapes[0]
    rs.move_obstacle(2, -6.0, 6.0)  # the polygon
    assert _nearest(rs, (-6.0, 6.0)).shape is rs.polygon_shapes[0]
    assert len(rs.space.shapes) == 1 + 2 + 1 + 1  # wall, 2 circles, polygon, robot
    assert len(rs.spec.circles) == len(rs.circle_shapes)


def test_runspace_touching_flags_contact():
    rs = RunSpace(_tiny(), np.array([[1.55, 0.0], [-2.0, 3.0], [-2.0, 3.99]]))
    assert rs.touching().tolist() == [True, True, True]
    rs.set_positions(np.array([[1.0, 0.0], [-2.0, 3.0], [-2.0, 5.0]]))
    assert rs.touching().tolist() == [False, False, False]
    assert rs.touching(tol=0.6).tolist() == [True, False, False]


def test_dynamic_robot_is_stopped_by_an_obstacle():
    rs = RunSpace(_tiny(), np.array([[0.0, 0.0]]), body_type="dynamic", mass=2.0)
    body = rs.robot_bodies[0]
    assert body.body_type == pymunk.Body.DYNAMIC and body.mass == 2.0
    for _ in range(300):
        body.apply_force_at_local_point((4.0, 0.0))
        rs.space.step(0.01)
    x = rs.positions()[0, 0]
    assert 1.45 < x < 1.51  # stopped at the circle of radius 1 at x = 3 (slop 0.01)
