"""The site's rule for scenes with more obstacles than slots (np_sim.nearest, ``BatchCore(nearest=True)``): the
policy's obstacle slots hold the nearest obstacles to the current pose, re-selected after every arc, while LiDAR and
every collision check see the whole scene.

The compiled distance is checked against shapely, the selection against the clips' own point-to-polygon distance
(a numpy even-odd test); the slots against `obstacle_slots` of a scene built from the expected obstacles;
the LiDAR against `cast_rays` on the whole scene; the checks by an arc through an obstacle that is not observed.
"""

from __future__ import annotations

import numpy as np
import pytest

from np_sim.clips.geometry import polygon_distances
from np_sim.config import EnvConfig
from np_sim.env_core import BatchCore
from np_sim.errors import CapacityError
from np_sim.kernels import step as K
from np_sim.kernels.nearest import point_polygon_distances
from np_sim.lidar import cast_rays, footprint_ranges
from np_sim.lots import LotConfig, generate_lot
from np_sim.nearest import NearestObjects, exceeds_slots
from np_sim.observation import obstacle_slots, observation_sections
from np_sim.scene import PolygonObstacle, Scene
from np_sim.scene_starts import draw_starts

CONFIG = EnvConfig()


@pytest.fixture(scope="module")
def lot() -> Scene:
    scene = generate_lot(LotConfig(bays_per_row=24), seed=3)
    assert len(scene.obstacles) >= 80 and exceeds_slots(scene, CONFIG.observation)
    return scene


def _expected_order(scene: Scene, pose) -> list[int]:
    """Obstacle indices by distance from the pose's reference point (clips' numpy distance), ties by index."""
    polygons = scene.polygons_for_observation()
    distance = np.array([polygon_distances(pose[:2], p[None])[0] for p in polygons])
    return sorted(range(len(polygons)), key=lambda i: (distance[i], i))[: CONFIG.observation.max_obstacles]


def test_the_nearest_obstacles_are_selected_nearest_first(lot):
    selector = NearestObjects(lot, CONFIG.observation)
    rng = np.random.default_rng(0)
    poses = np.column_stack([rng.uniform(0, 70, 25), rng.uniform(0, 36, 25), rng.uniform(-3, 3, 25)])
    chosen = selector.indices(poses)
    assert chosen.shape == (25, 20)
    for pose, row in zip(poses, chosen):
        assert row.tolist() == _expected_order(lot, pose)


def test_the_distance_kernel_matches_shapely(lot):
    from shapely.geometry import Point, Polygon

    selector = NearestObjects(lot, CONFIG.observation)
    rng = np.random.default_rng(1)
    points = np.column_stack([rng.uniform(0, 70, 40), rng.uniform(0, 36, 40)])
    points[:5] = [o.vertices.mean(axis=0) for o in lot.obstacles[:5]]  # inside a car: distance 0
    distance = np.empty((40, len(lot.obstacles)))
    point_polygon_distances(points, selector._verts, selector._counts, distance)
    expected = [[Polygon(o.vertices).distance(Point(p)) for o in lot.obstacles] for p in points]
    np.testing.assert_allclose(distance, expected, atol=1e-12)
    assert np.all(distance[np.arange(5), np.arange(5)] == 0.0)


def _sub_scene_slots(scene: Scene, pose) -> np.ndarray:
    order = _expected_order(scene, pose)
    sub = Scene(scene.boundary, tuple(scene.obstacles[i] for i in order), scene.target, None)
    return obstacle_slots(sub, CONFIG.observation).reshape(-1)


def test_observed_slots_follow_the_pose_and_lidar_sees_the_whole_lot(lot):
    core = BatchCore([lot], 3, CONFIG, None, nearest=True)
    starts = draw_starts(lot, 3, seed=2, convention="footprint").poses
    core.reset_envs(np.arange(3), np.random.default_rng(0), 0, starts)
    a, b = observation_sections(CONFIG.observation)["obstacles"]
    lo, hi = observation_sections(CONFIG.observation)["lidar"]
    clearance = footprint_ranges(CONFIG.vehicle, CONFIG.observation.n_beams)
    for _ in range(2):
        for row in range(3):
            pose = core.S[row, K.S_X: K.S_TH + 1].copy()
            np.testing.assert_array_equal(core.obs[row, a:b], _sub_scene_slots(lot, pose).astype(np.float32))
            lidar = np.maximum(cast_rays(lot, pose) - clearance, 0.0).astype(np.float32)
            np.testing.assert_allclose(core.obs[row, lo:hi], lidar, atol=1e-5)
        core.step(np.array([[0.0, 0.15], [0.3, -0.1], [-0.2, 0.1]]))  # short arcs that stay in the aisle
        assert not core.R[:, K.R_COLLISION].any()


def test_an_obstacle_outside_the_observed_set_still_blocks_the_arc():
    # 24 bollards less than 6 m behind the start fill the 20 slots; the wall 6.5 m ahead is not observed
    bollards = [{"polygon": [[x, y], [x + 0.4, y], [x + 0.4, y + 0.4], [x, y + 0.4]]}
                for x in (5.0, 6.0, 7.0, 8.0) for y in (13.0, 14.0, 15.0, 16.0, 17.0, 11.5)]
    wall = {"polygon": [[17.0, 10.0], [18.0, 10.0], [18.0, 20.0], [17.0, 20.0]]}
    data = {"boundary": [[0, 0], [60, 0], [60, 30], [0, 30]], "target": [50.0, 5.0, 1.5707963]}
    start = np.array([10.5, 15.0, 0.0])
    blocked = Scene.from_dict({**data, "obstacles": bollards + [wall]})
    wall_index = len(bollards)
    assert wall_index not in NearestObjects(blocked, CONFIG.observation).indices(start)[0]
    outcomes = []
    for scene in (blocked, Scene.from_dict({**data, "obstacles": bollards})):
        core = BatchCore([scene], 1, CONFIG, None, nearest=True)
        core.reset_envs(np.arange(1), np.random.default_rng(0), 0, start)
        core.step(np.array([[0.0, 1.0]]))  # 10 m straight ahead, through the wall at 6.5 m
        outcomes.append(bool(core.R[0, K.R_COLLISION]))
    assert outcomes == [True, False]


def test_without_the_rule_or_beyond_the_vertex_limit_it_is_a_capacity_error(lot):
    with pytest.raises(CapacityError, match=r"obstacles exceed SceneCapacity.max_obstacles = 20"):
        BatchCore([lot], 1, CONFIG, None)
    nine = PolygonObstacle(np.array([[3 + np.cos(t), 30 + np.sin(t)] for t in np.linspace(0, 6, 9)]))
    odd = Scene(lot.boundary, lot.obstacles + (nine,), lot.target, lot.start_region)
    with pytest.raises(CapacityError, match=r"obstacles\[\d+\].polygon: 9 vertices exceed"):
        BatchCore([odd], 1, CONFIG, None, nearest=True)


def test_a_scene_within_the_slots_is_observed_as_without_the_rule():
    scene = generate_lot(LotConfig(rows=2, bays_per_row=8), seed=1)
    assert not exceeds_slots(scene, CONFIG.observation)
    cores = [BatchCore([scene], 2, CONFIG, None, nearest=flag) for flag in (False, True)]
    starts = draw_starts(scene, 2, seed=0).poses
    for core in cores:
        core.reset_envs(np.arange(2), np.random.default_rng(0), 0, starts)
        core.step(np.array([[0.1, 0.2], [-0.3, 0.1]]))
    assert not cores[1].selectors
    np.testing.assert_array_equal(cores[0].obs, cores[1].obs)
    np.testing.assert_array_equal(cores[0].S, cores[1].S)
