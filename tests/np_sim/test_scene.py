"""Tests for np_sim.scene: JSON format, validation messages, round trips, derived geometry, shipped examples."""

from __future__ import annotations

import copy
import json
import math
import re

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from np_sim.errors import CapacityError, SceneError
from np_sim.examples import example_names, example_path, example_scenes
from np_sim.scene import CircleObstacle, PolygonObstacle, Scene, SceneCapacity
from np_sim.vehicle import VehicleSpec


def valid_dict() -> dict:
    """A small valid scene: 30 × 20 m lot, one box, one bin, target at the centre heading +x."""
    return {
        "version": 1,
        "name": "unit",
        "tags": {"benchmark": "unit", "cell": 3},
        "boundary": [[0, 0], [30, 0], [30, 20], [0, 20]],
        "obstacles": [
            {"polygon": [[2, 2], [6, 2], [6, 5], [2, 5]]},
            {"circle": [25.0, 15.0, 0.5]},
        ],
        "target": [15.0, 10.0, 0.0],
        "start_region": [[1, 14], [10, 14], [10, 19], [1, 19]],
    }


def with_change(path: tuple, value) -> dict:
    """valid_dict() with the item at ``path`` (keys/indices) set to ``value``."""
    data = copy.deepcopy(valid_dict())
    node = data
    for key in path[:-1]:
        node = node[key]
    node[path[-1]] = value
    return data


# ---------------------------------------------------------------- round trips


def test_from_dict_builds_float64_read_only_arrays():
    scene = Scene.from_dict(valid_dict())
    assert scene.boundary.dtype == np.float64 and scene.boundary.shape == (4, 2)
    assert scene.target.dtype == np.float64 and scene.target.shape == (3,)
    assert isinstance(scene.obstacles[0], PolygonObstacle) and isinstance(scene.obstacles[1], CircleObstacle)
    assert scene.obstacles[1].radius == 0.5
    assert scene.name == "unit" and scene.tags == {"benchmark": "unit", "cell": 3} and scene.version == 1
    with pytest.raises(ValueError):
        scene.boundary[0, 0] = 1.0


def test_optional_fields_default():
    data = valid_dict()
    for key in ("version", "name", "tags", "start_region"):
        del data[key]
    scene = Scene.from_dict(data)
    assert scene.start_region is None and scene.name == "" and scene.tags == {} and scene.version == 1
    assert "start_region" not in scene.to_dict()


def assert_same_scene(a: Scene, b: Scene) -> None:
    np.testing.assert_array_equal(a.boundary, b.boundary)
    np.testing.assert_array_equal(a.target, b.target)
    np.testing.assert_array_equal(a.start_region, b.start_region)
    assert len(a.obstacles) == len(b.obstacles)
    for oa, ob in zip(a.obstacles, b.obstacles):
        assert type(oa) is type(ob)
        if isinstance(oa, PolygonObstacle):
            np.testing.assert_array_equal(oa.vertices, ob.vertices)
        else:
            np.testing.assert_array_equal(oa.center, ob.center)
            assert oa.radius == ob.radius
    assert (a.name, a.tags, a.version) == (b.name, b.tags, b.version)


def test_to_dict_round_trips_exactly_and_is_json_safe():
    data = valid_dict()
    data["target"] = [15.123456789012345, 10.1, 0.1 + 0.2]
    scene = Scene.from_dict(data)
    out = scene.to_dict()
    assert json.loads(json.dumps(out, allow_nan=False)) == out
    assert list(out) == ["version", "name", "tags", "boundary", "obstacles", "target", "start_region"]
    assert_same_scene(scene, Scene.from_dict(out))


def test_save_load_round_trip_is_deterministic(tmp_path):
    scene = Scene.from_dict(valid_dict())
    first, second = tmp_path / "a.json", tmp_path / "b.json"
    scene.save(first)
    loaded = Scene.load(first)
    assert_same_scene(scene, loaded)
    loaded.save(second)
    assert first.read_text() == second.read_text()
    assert json.loads(first.read_text()) == scene.to_dict()


# ---------------------------------------------------------------- derived geometry


def test_octagon_and_ring_vertices_lie_on_the_circle_ccw_from_angle_zero():
    circle = CircleObstacle(np.array([3.0, -2.0]), 1.5)
    for points, n in ((circle.octagon(), 8), (circle.ring(), 16), (circle.ring(5), 5)):
        assert points.shape == (n, 2) and points.dtype == np.float64
        np.testing.assert_allclose(np.hypot(points[:, 0] - 3.0, points[:, 1] + 2.0), 1.5, atol=1e-12)
        angles = np.arctan2(points[:, 1] + 2.0, points[:, 0] - 3.0)
        np.testing.assert_allclose(np.cos(angles), np.cos(2 * np.pi * np.arange(n) / n), atol=1e-12)
        np.testing.assert_allclose(np.sin(angles), np.sin(2 * np.pi * np.arange(n) / n), atol=1e-12)


def test_polygons_for_observation_and_rays_keep_scene_order():
    scene = Scene.from_dict(valid_dict())
    observed, rays = scene.polygons_for_observation(), scene.polygons_for_rays()
    np.testing.assert_array_equal(observed[0], scene.obstacles[0].vertices)
    np.testing.assert_array_equal(rays[0], scene.obstacles[0].vertices)
    np.testing.assert_array_equal(observed[1], scene.obstacles[1].octagon())
    np.testing.assert_array_equal(rays[1], scene.obstacles[1].ring(16))
    assert observed[1].shape == (8, 2) and rays[1].shape == (16, 2)


def test_boundary_segments_close_the_ring():
    scene = Scene.from_dict(valid_dict())
    segments = scene.boundary_segments()
    assert segments.shape == (4, 4)
    np.testing.assert_array_equal(segments[:, :2], scene.boundary)
    np.testing.assert_array_equal(segments[:-1, 2:], segments[1:, :2])
    np.testing.assert_array_equal(segments[-1, 2:], scene.boundary[0])


# ---------------------------------------------------------------- validation messages


def test_unreadable_files_raise_scene_error_naming_the_file(tmp_path):
    (tmp_path / "folder.json").mkdir()
    with pytest.raises(SceneError, match=r"folder\.json: cannot read the scene file: Is a directory"):
        Scene.load(tmp_path / "folder.json")
    with pytest.raises(SceneError, match=r"absent\.json: cannot read the scene file: No such file or directory"):
        Scene.load(tmp_path / "absent.json")
    latin = tmp_path / "latin1.json"
    latin.write_bytes('{"name": "Stra\u00dfe"}'.encode("latin-1"))
    with pytest.raises(SceneError, match=r"latin1\.json: expected UTF-8 text, got byte 0xdf at offset 14"):
        Scene.load(latin)


def test_deep_nesting_and_huge_integers_raise_scene_error(tmp_path):
    deep = tmp_path / "deep.json"
    deep.write_text("[" * 200_000 + "]" * 200_000)
    with pytest.raises(SceneError, match=r"deep\.json: invalid JSON: nested too deeply to parse"):
        Scene.load(deep)
    huge = tmp_path / "huge.json"
    huge.write_text(json.dumps(valid_dict()).replace('"target": [15.0', '"target": [1' + "0" * 400))
    with pytest.raises(SceneError, match=r"huge\.json: target\[0\]: expected a finite number, got an integer of "
                       r"401 digits"):
        Scene.load(huge)
    endless = tmp_path / "endless.json"
    endless.write_text(json.dumps(valid_dict()).replace('"target": [15.0', '"target": [1' + "0" * 5000))
    with pytest.raises(SceneError, match=r"endless\.json: invalid JSON: "):
        Scene.load(endless)
    nested = [1.0]
    for _ in range(100_000):  # repr() of this raises RecursionError; the message must stay short
        nested = [nested]
    with pytest.raises(SceneError, match=r"<dict>: target\[0\]: expected a number, got list \[{7}\.\.\.\]{7}$"):
        Scene.from_dict(with_change(("target", 0), nested))


def test_bad_json_names_file_line_and_column(tmp_path):
    path = tmp_path / "broken.json"
    path.write_text('{\n  "boundary": [[0, 0], [1, 0]\n  "target": [0, 0, 0]\n}\n')
    with pytest.raises(SceneError, match=r"broken\.json: invalid JSON at line 3, column 3: Expecting ','"):
        Scene.load(path)


def test_load_names_the_file_in_validation_errors(tmp_path):
    path = tmp_path / "scene.json"
    path.write_text(json.dumps(with_change(("obstacles", 1, "circle"), [25, 15, 0])))
    with pytest.raises(SceneError, match=r"scene\.json: obstacles\[1\]\.circle\[2\]: expected a radius > 0, got 0\.0"):
        Scene.load(path)


@pytest.mark.parametrize(
    ("data", "message"),
    [
        ([1, 2], r"<dict>: expected a JSON object at the top level, got list"),
        ({k: v for k, v in valid_dict().items() if k != "target"}, r"<dict>: target: missing required field"),
        ({k: v for k, v in valid_dict().items() if k != "boundary"}, r"<dict>: boundary: missing required field"),
        ({**valid_dict(), "targte": [0, 0, 0]}, r"<dict>: targte: unknown field; expected only version, name"),
        (with_change(("obstacles", 0, "colour"), "red"), r"<dict>: obstacles\[0\]\.colour: unknown field"),
        (with_change(("obstacles", 0), {}), r'obstacles\[0\]: expected exactly one of "polygon" or "circle"'),
        (
            with_change(("obstacles", 0), {"polygon": [[0, 0], [1, 0], [0, 1]], "circle": [1, 1, 1]}),
            r"obstacles\[0\]: expected exactly one of",
        ),
        (with_change(("obstacles", 0), [[0, 0], [1, 0], [0, 1]]), r"obstacles\[0\]: expected an object"),
        (with_change(("obstacles",), {"polygon": []}), r"<dict>: obstacles: expected a list of obstacle objects"),
        (with_change(("target", 1), "10"), r"<dict>: target\[1\]: expected a number, got string '10'"),
        (with_change(("target", 2), True), r"<dict>: target\[2\]: expected a number, got boolean True"),
        (with_change(("target",), [1.0, 2.0]), r"<dict>: target: expected an \[x, y, theta\] pose, got list"),
        (with_change(("target", 0), float("nan")), r"<dict>: target\[0\]: expected a finite number, got nan"),
        (
            with_change(("obstacles", 0, "polygon", 2), [6, 5, 1]),
            r"<dict>: obstacles\[0\]\.polygon\[2\]: expected an \[x, y\] pair, got list \[6, 5, 1\]",
        ),
        (
            with_change(("obstacles", 0, "polygon", 1, 0), float("inf")),
            r"obstacles\[0\]\.polygon\[1\]\[0\]: expected a finite number, got inf",
        ),
        (
            with_change(("obstacles", 0, "polygon"), "square"),
            r"obstacles\[0\]\.polygon: expected a list of \[x, y\] points, got string 'square'",
        ),
        (with_change(("boundary",), 5), r"<dict>: boundary: expected a list of \[x, y\] points, got integer 5"),
        (
            with_change(("obstacles", 1, "circle"), [1, 2]),
            r"obstacles\[1\]\.circle: expected a \[cx, cy, r\] triple, got list \[1, 2\]",
        ),
        (
            with_change(("obstacles", 1, "circle"), [25, 15, -0.5]),
            r"obstacles\[1\]\.circle\[2\]: expected a radius > 0, got -0\.5",
        ),
        (with_change(("name",), 7), r"<dict>: name: expected a string, got integer 7"),
        (with_change(("tags",), ["a"]), r"<dict>: tags: expected an object"),
        (with_change(("tags", "split"), None), r"<dict>: tags\.split: expected a string or number, got null"),
        (with_change(("version",), 2), r"<dict>: version: expected 1, got integer 2"),
        (with_change(("version",), "1"), r"<dict>: version: expected 1, got string '1'"),
    ],
)
def test_malformed_fields_raise_scene_error_naming_the_field(data, message):
    with pytest.raises(SceneError, match=message):
        Scene.from_dict(data)


@pytest.mark.parametrize("field", ["boundary", "obstacles[0].polygon", "start_region"])
@pytest.mark.parametrize(
    ("vertices", "message"),
    [
        ([[0, 0], [1, 0]], r": expected a polygon with at least 3 distinct vertices, got 2"),
        ([[0, 0], [1, 0], [1, 0], [0, 0]], r": expected a polygon with at least 3 distinct vertices, got 2"),
        ([[0, 0], [1, 0], [2, 0], [3, 0]], r": degenerate polygon: zero area \(all 4 vertices are collinear\)"),
        ([[0, 0], [1, 1], [1, 0], [0, 1]], r": expected a simple polygon, but it self-intersects at \(0\.5, 0\.5\)"),
        (
            [[0, 0], [2, 0], [1, 1], [2, 2], [0, 2], [1, 1]],
            r": expected a simple polygon, but it self-intersects at \(1, 1\) \(shapely: Ring Self-intersection",
        ),
    ],
)
def test_bad_polygons_are_rejected_for_every_polygon_field(field, vertices, message):
    if field == "boundary":
        data = with_change(("boundary",), vertices)
    elif field == "start_region":
        data = with_change(("start_region",), vertices)
    else:
        data = with_change(("obstacles", 0, "polygon"), vertices)
    with pytest.raises(SceneError, match=re.escape(f"<dict>: {field}") + message):
        Scene.from_dict(data)


def footprint_hits_box(target) -> bool:
    """Shapely verdict, written without np_sim.scene: does the default footprint at ``target`` touch the box?"""
    from shapely.geometry import Polygon, box

    return not Polygon(VehicleSpec().footprint(np.asarray(target, float))).disjoint(box(2, 2, 6, 5))


@pytest.mark.parametrize("reverse_boundary", [False, True])
@pytest.mark.parametrize("reverse_box", [False, True])
def test_polygon_orientation_does_not_change_the_verdicts(reverse_boundary, reverse_box):
    targets = [[6.5, 3.0, 0.0], [6.7, 3.0, 0.0], [15.0, 10.0, 0.0], [8.0, 3.5, 0.0], [4.0, 8.5, -1.5708]]
    expected = [footprint_hits_box(t) for t in targets]
    assert any(expected) and not all(expected)  # both verdicts occur, so the comparison can fail
    for target, hits in zip(targets, expected):
        data = valid_dict()
        if reverse_boundary:
            data["boundary"] = data["boundary"][::-1]
        if reverse_box:
            data["obstacles"][0]["polygon"] = data["obstacles"][0]["polygon"][::-1]
        data["target"] = target
        if hits:
            with pytest.raises(SceneError, match=r"obstacles\[0\] \(polygon\)"):
                Scene.from_dict(data)
        else:
            scene = Scene.from_dict(data)
            np.testing.assert_array_equal(scene.boundary, data["boundary"])  # kept as given, not reoriented
    with pytest.raises(SceneError, match=r"start_region: expected a polygon inside the boundary"):
        Scene.from_dict(with_change(("boundary",), valid_dict()["boundary"][::-1 if reverse_boundary else 1][:3]))


# ---------------------------------------------------------------- repeated and closing vertices


@pytest.mark.parametrize(
    "vertices",
    [
        [[2, 2], [6, 2], [6, 5], [2, 5], [2, 2]],  # GeoJSON: closing vertex equal to the first
        [[2, 2], [6, 2], [6, 2], [6, 5], [2, 5]],  # one exact consecutive repeat
        [[2, 2], [2, 2], [6, 2], [6, 5], [6, 5], [6, 5], [2, 5], [2, 2], [2, 2]],  # runs and a closing run
    ],
)
@pytest.mark.parametrize("field", ["boundary", "obstacles[0].polygon", "start_region"])
def test_closing_and_repeated_vertices_describe_the_same_polygon(field, vertices):
    ring = [[2, 2], [6, 2], [6, 5], [2, 5]]
    if field == "boundary":
        scale = [[5 * x - 10, 5 * y - 10] for x, y in vertices]  # a 20 x 15 m lot around the target
        data, expected = with_change(("boundary",), scale), [[5 * x - 10, 5 * y - 10] for x, y in ring]
        data["obstacles"] = data["obstacles"][:1]
        del data["start_region"]  # it lies beyond the smaller lot
    elif field == "start_region":
        data, expected = with_change(("start_region",), [[x + 10, y + 12] for x, y in vertices]), None
        expected = [[x + 10, y + 12] for x, y in ring]
    else:
        data, expected = with_change(("obstacles", 0, "polygon"), vertices), ring
    scene = Scene.from_dict(data)
    got = {"boundary": scene.boundary, "start_region": scene.start_region}.get(field)
    got = scene.obstacles[0].vertices if got is None else got
    np.testing.assert_array_equal(got, expected)
    assert Scene.from_dict(scene.to_dict()).to_dict() == scene.to_dict()


def test_repeats_are_dropped_for_scenes_built_in_code():
    obstacle = PolygonObstacle([[0, 0], [1, 0], [1, 0], [0, 1], [0, 0]])
    np.testing.assert_array_equal(obstacle.vertices, [[0, 0], [1, 0], [0, 1]])
    with pytest.raises(SceneError, match=r"obstacles\[0\]\.polygon: expected a polygon with at least 3 distinct "
                       r"vertices, got 1 \(exact repeats"):
        Scene.from_dict(with_change(("obstacles", 0, "polygon"), [[3, 3]] * 4))


# ---------------------------------------------------------------- start region


def test_start_region_leaving_the_boundary_is_rejected_with_a_point_outside():
    with pytest.raises(SceneError, match=r"<dict>: start_region: expected a polygon inside the boundary, but it "
                       r"leaves the boundary \(e\.g\. at \((3[0-9.]*|4[0-9.]*), 1[0-9.]*\)\)"):
        Scene.from_dict(with_change(("start_region",), [[25, 14], [40, 14], [40, 19], [25, 19]]))
    with pytest.raises(SceneError, match=r"start_region: expected a polygon inside the boundary"):
        Scene.from_dict(with_change(("start_region",), [[40, 0], [50, 0], [50, 5]]))  # wholly outside


def test_start_region_touching_the_boundary_is_accepted():
    scene = Scene.from_dict(with_change(("start_region",), [[0, 14], [10, 14], [10, 20], [0, 20]]))
    assert scene.start_region is not None


@pytest.mark.parametrize(
    ("obstacles", "region", "named"),
    [
        ([{"polygon": [[2, 2], [6, 2], [6, 5], [2, 5]]}], [[3, 3], [5, 3], [5, 4]], "obstacles[0]"),
        ([{"polygon": [[2, 2], [6, 2], [6, 5], [2, 5]]}], [[2, 2], [6, 2], [6, 5], [2, 5]], "obstacles[0]"),
        ([{"circle": [25.0, 15.0, 2.0]}], [[24, 14], [26, 14], [26, 16], [24, 16]], "obstacles[0]"),  # half-diag 1.41
        (
            [{"polygon": [[2, 2], [4, 2], [4, 5], [2, 5]]}, {"polygon": [[4, 2], [6, 2], [6, 5], [4, 5]]}],
            [[3, 3], [5, 3], [5, 4], [3, 4]],
            "obstacles[0], obstacles[1]",
        ),
    ],
)
def test_start_region_wholly_inside_obstacles_is_rejected(obstacles, region, named):
    data = {**valid_dict(), "obstacles": obstacles, "start_region": region}
    with pytest.raises(SceneError, match=r"<dict>: start_region: expected some area free of obstacles, but it lies "
                       r"wholly inside " + re.escape(named) + r" \(no start"):
        Scene.from_dict(data)


def test_start_region_partly_covered_by_obstacles_is_accepted():
    data = {**valid_dict(), "start_region": [[3, 3], [8, 3], [8, 4], [3, 4]]}  # x in (6, 8] is free
    Scene.from_dict(data)
    data["obstacles"] = [{"circle": [25.0, 15.0, 1.0]}]
    data["start_region"] = [[24, 14], [26, 14], [26, 16], [24, 16]]  # the square's corners lie outside the disc
    Scene.from_dict(data)


@pytest.mark.parametrize(
    "polygon",
    [
        [[-3, 2], [4, 2], [4, 5], [-3, 5]],  # crosses the left wall
        [[-8, -8], [-2, -8], [-2, -2], [-8, -2]],  # wholly beyond the boundary
        [[-5, 18], [35, 18], [35, 25], [-5, 25]],  # cuts across the whole top of the lot
    ],
)
def test_obstacles_crossing_or_beyond_the_boundary_load(polygon):
    scene = Scene.from_dict(with_change(("obstacles", 0, "polygon"), polygon))
    np.testing.assert_array_equal(scene.obstacles[0].vertices, polygon)


# ---------------------------------------------------------------- target footprint


def test_target_footprint_crossing_the_boundary_is_rejected():
    with pytest.raises(SceneError, match=r"<dict>: target: the vehicle footprint at \(0.5, 10, 0\) must lie strictly "
                       r"inside the boundary"):
        Scene.from_dict(with_change(("target",), [0.5, 10.0, 0.0]))


def test_target_footprint_touching_the_boundary_is_rejected():
    spec = VehicleSpec()
    x = 30.0 - spec.front_m  # front bumper exactly on the right wall
    with pytest.raises(SceneError, match=r"strictly inside the boundary"):
        Scene.from_dict(with_change(("target",), [x, 10.0, 0.0]))
    Scene.from_dict(with_change(("target",), [x - 1e-6, 10.0, 0.0]))


def test_target_footprint_overlapping_a_polygon_names_the_obstacle():
    with pytest.raises(SceneError, match=r"target: .* disjoint from every obstacle, but it touches or overlaps "
                       r"obstacles\[0\] \(polygon\)"):
        Scene.from_dict(with_change(("target",), [6.5, 3.0, 0.0]))


def test_target_footprint_against_circles_is_exact():
    spec = VehicleSpec()
    # rear-left corner region: the circle sits above the footprint's left side at clearance d - r.
    target_y = 15.0 - 0.5 - 0.5 * spec.width_m
    with pytest.raises(SceneError, match=r"obstacles\[1\] \(circle\)"):
        Scene.from_dict(with_change(("target",), [23.0, target_y, 0.0]))  # tangent: distance == r
    Scene.from_dict(with_change(("target",), [23.0, target_y - 1e-9, 0.0]))
    # the circle's bounding box overlaps the footprint corner but the circle does not
    corner = np.array([25.0, 15.0]) - 0.5 * np.array([math.sqrt(0.5), math.sqrt(0.5)]) - 0.05
    target = [corner[0] - spec.front_m, corner[1] - 0.5 * spec.width_m, 0.0]
    Scene.from_dict(with_change(("target",), target))


def test_target_check_uses_the_given_vehicle():
    target = [6.7, 3.0, 0.0]  # default rear bumper at x = 5.771 overlaps the box (x <= 6); a 0.3 m overhang clears it
    with pytest.raises(SceneError, match=r"obstacles\[0\]"):
        Scene.from_dict(with_change(("target",), target))
    small = VehicleSpec(wheelbase_m=1.5, front_overhang_m=0.4, rear_overhang_m=0.3, width_m=1.2)
    Scene.from_dict(with_change(("target",), target), vehicle=small)


# ---------------------------------------------------------------- capacity


def test_format_has_no_limit_without_capacity():
    data = valid_dict()
    data["obstacles"] = [{"circle": [1.0 + 1.2 * i, 18.0, 0.4]} for i in range(22)]
    data["obstacles"].append({"polygon": [[2 + math.cos(a), 7 + math.sin(a)] for a in np.linspace(0, 6, 12)]})
    scene = Scene.from_dict(data)
    message = r"<dict>: obstacles: 23 obstacles exceed SceneCapacity\.max_obstacles = 20"
    with pytest.raises(CapacityError, match=message):
        Scene.from_dict(data, capacity=SceneCapacity())
    with pytest.raises(CapacityError, match=r"<scene>: obstacles: 23 obstacles exceed"):
        scene.check_capacity(SceneCapacity())
    scene.check_capacity(SceneCapacity(max_obstacles=23, max_polygon_vertices=12))


def test_capacity_names_the_polygon_and_its_vertex_count():
    data = valid_dict()
    data["obstacles"].insert(1, {"polygon": [[8 + math.cos(a), 7 + math.sin(a)] for a in np.linspace(0, 6, 9)]})
    with pytest.raises(CapacityError, match=r"obstacles\[1\]\.polygon: 9 vertices exceed "
                       r"SceneCapacity\.max_polygon_vertices = 8"):
        Scene.from_dict(data, capacity=SceneCapacity())


def test_capacity_counts_circles_as_octagons():
    with pytest.raises(CapacityError, match=r"obstacles\[1\]\.circle: 8 vertices \(a circle is observed as its "
                       r"octagon\) exceed SceneCapacity\.max_polygon_vertices = 5"):
        Scene.from_dict(valid_dict(), capacity=SceneCapacity(max_polygon_vertices=5))


def test_capacity_names_the_boundary_segment_count():
    data = valid_dict()
    data["boundary"] = [[15 + 15 * math.cos(a), 10 + 10 * math.sin(a)] for a in np.linspace(0, 2 * np.pi, 12)[:-1]]
    data["start_region"] = [[4, 8], [10, 8], [10, 12], [4, 12]]  # inside the 11-gon
    with pytest.raises(CapacityError, match=r"boundary: 11 segments exceed SceneCapacity\.max_boundary_segments = 10"):
        Scene.from_dict(data, capacity=SceneCapacity())
    assert isinstance(CapacityError("x"), SceneError)


# ---------------------------------------------------------------- property: arbitrary valid scenes round-trip


@settings(max_examples=30, deadline=None)
@given(
    x=st.floats(8.0, 22.0),
    y=st.floats(8.0, 12.0),
    theta=st.floats(-math.pi, math.pi),
    radius=st.floats(0.05, 1.0),
    scale=st.floats(0.5, 3.0),
)
def test_random_valid_scenes_round_trip(x, y, theta, radius, scale):
    data = valid_dict()
    data["target"] = [x, y, theta]
    data["obstacles"][1]["circle"] = [27.0, 17.0, radius]
    data["obstacles"][0]["polygon"] = [[2, 2], [2 + scale, 2], [2 + scale, 2 + scale], [2, 2 + scale]]
    scene = Scene.from_dict(data)
    assert_same_scene(scene, Scene.from_dict(json.loads(json.dumps(scene.to_dict()))))


# ---------------------------------------------------------------- shipped examples


def test_four_examples_ship():
    assert example_names() == ["clutter_random", "enclosed_target", "parallel_slot", "reverse_bay"]
    assert example_path("reverse_bay") == example_path("reverse_bay.json")
    with pytest.raises(ValueError, match=r"unknown example scene 'nope'; expected one of clutter_random"):
        example_path("nope")


@pytest.mark.parametrize("name", ["clutter_random", "enclosed_target", "parallel_slot", "reverse_bay"])
def test_every_example_loads_within_capacity_with_a_free_target(name):
    scene = Scene.load(example_path(name), capacity=SceneCapacity())
    assert scene.name == name
    assert len(scene.boundary) <= 10 and scene.start_region is not None
    scene.validate(vehicle=VehicleSpec())  # target footprint free, all polygons simple
    extent = scene.boundary.max(axis=0) - scene.boundary.min(axis=0)
    assert 20.0 <= extent.max() <= 45.0


def test_example_scenes_loads_all():
    scenes = example_scenes()
    assert [s.name for s in scenes] == example_names()


def test_reverse_bay_target_points_out_of_the_bay():
    scene = Scene.load(example_path("reverse_bay"))
    _, y, theta = scene.target
    assert math.isclose(theta, math.pi / 2)  # heading +y, away from the bay's back (y = 0)
    assert 0.0 < y - VehicleSpec().rear_overhang_m < 1.0


def test_enclosed_target_is_sealed_by_walls():
    from shapely.geometry import Point, Polygon
    from shapely.ops import unary_union

    scene = Scene.load(example_path("enclosed_target"))
    walls = unary_union([Polygon(p) for p in scene.polygons_for_observation()])
    pocket = [g for g in getattr(walls, "geoms", [walls]) if len(g.interiors) > 0]
    assert pocket, "expected the walls to enclose a hole"
    assert any(Polygon(hole).contains(Point(scene.target[:2])) for g in pocket for hole in g.interiors)
