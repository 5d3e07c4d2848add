"""Topology-Stress Benchmark (paper §IV-A, spec §4.2): counts, checks, route stress beyond the LiDAR range."""

from collections import Counter

import numpy as np
import pytest
from shapely.geometry import LineString, Point
from shapely.geometry import Polygon as ShapelyPolygon

from np_sim.benchmarks import frozen_starts, load_benchmark
from np_sim.benchmarks.frozen import benchmark_json, benchmark_path
from np_sim.benchmarks.topology import (
    FAMILIES,
    TopologyConfig,
    generate_topology,
    opening_segment,
    route_blocked,
    structure_beyond_range,
    topology_cells,
)
from np_sim.benchmarks.validity import run_checks
from np_sim.geodesic import geodesic_grid
from np_sim.scene import PolygonObstacle, Scene, SceneCapacity


@pytest.fixture(scope="module")
def scenes():
    return {split: load_benchmark("topology", split) for split in ("train", "test")}


def test_counts_per_split_and_cell(scenes):
    assert len(scenes["train"]) == 48 and len(scenes["test"]) == 18
    cells = {c.name for c in topology_cells()}
    assert len(cells) == 6
    assert Counter(s.tags["cell"] for s in scenes["train"]) == {c: 8 for c in cells}
    assert Counter(s.tags["cell"] for s in scenes["test"]) == {c: 3 for c in cells}
    for s in scenes["train"] + scenes["test"]:
        assert s.tags["benchmark"] == "topology" and s.tags["family"] in FAMILIES
        assert {"layout_seed", "n_structure", "opening_x0", "opening_y1"} <= set(s.tags)


def test_every_scene_fits_capacity_and_passes_the_four_checks(scenes):
    for s in scenes["train"] + scenes["test"]:
        s.validate(capacity=SceneCapacity())
        results = run_checks(s, stop_at_first=False)
        assert all(r.passed for r in results), (s.name, [r.detail for r in results if not r.passed])


def test_most_frozen_starts_are_route_blocked_with_the_structure_out_of_lidar_range(scenes):
    starts = frozen_starts("topology")
    for f in FAMILIES:
        rows = [k for k, s in enumerate(scenes["test"]) if s.tags["family"] == f]
        blocked = np.concatenate([route_blocked(scenes["test"][k], starts[k, :, :2]) for k in rows])
        beyond = np.concatenate([structure_beyond_range(scenes["test"][k], starts[k, :, :2]) for k in rows])
        assert blocked.mean() >= TopologyConfig().min_route_blocked and beyond.mean() > 0.5, f


def test_route_blocked_definition_on_a_hand_checked_start(scenes):
    s = scenes["test"][0]
    start = s.start_region.mean(axis=0)
    opening = LineString(opening_segment(s))
    obstacles = [ShapelyPolygon(o.vertices) for o in s.obstacles if hasattr(o, "vertices")]
    hits = any(LineString([start, s.target[:2]]).intersects(o) for o in obstacles)
    assert route_blocked(s, start[None])[0] == (hits and opening.distance(Point(start)) > 10.0)


def test_the_decisive_opening_is_the_only_way_in(scenes):
    # closing the opening with a wall cuts the start region off from the target on the geodesic grid
    for s in scenes["test"]:
        a, b = opening_segment(s)
        wall = np.array(LineString([a, b]).buffer(0.4, cap_style="flat").exterior.coords)[:-1]
        closed = Scene(s.boundary, s.obstacles + (PolygonObstacle(wall),), s.target, s.start_region)
        centre = s.start_region.mean(axis=0)
        assert np.isfinite(geodesic_grid(s).distance_at(centre)), s.name
        assert np.isinf(geodesic_grid(closed).distance_at(centre)), s.name


def test_regeneration_reproduces_the_shipped_file_byte_for_byte():
    build = generate_topology()
    assert benchmark_json(build).encode("utf-8") == benchmark_path("topology").read_bytes()
    assert build.nearest_train_m.min() >= TopologyConfig().disjointness_floor_m
