"""Layout distance (Hausdorff of target-frame outlines) and the structural-disjointness floor (paper §IV-A)."""

import math

import numpy as np
import pytest
import shapely
from shapely.geometry import MultiPoint

from np_sim.benchmarks import load_benchmark
from np_sim.benchmarks.layout import (
    DISJOINTNESS_FLOOR_M,
    disjointness_floor,
    hausdorff,
    layout_distance,
    layout_points,
    nearest_train_distances,
)
from np_sim.frames import from_target_frame, to_target_frame
from np_sim.scene import CircleObstacle, PolygonObstacle, Scene

LOT = {"boundary": [[0, 0], [30, 0], [30, 20], [0, 20]],
       "obstacles": [{"polygon": [[5, 5], [9, 5], [9, 7], [5, 7]]}, {"circle": [20.0, 12.0, 0.6]}],
       "target": [15.0, 3.0, math.pi / 2]}


def _moved(scene: Scene, pose) -> Scene:
    """The same layout placed with its target at ``pose`` (a rigid motion of everything)."""
    def move(p):
        return from_target_frame(to_target_frame(p, scene.target), pose)
    obstacles = [PolygonObstacle(move(o.vertices)) if isinstance(o, PolygonObstacle)
                 else CircleObstacle(move(o.center), o.radius) for o in scene.obstacles]
    return Scene(move(scene.boundary), obstacles, np.asarray(pose, float), None)


def test_hausdorff_matches_shapely_on_random_point_sets():
    rng = np.random.default_rng(3)
    for _ in range(5):
        a, b = rng.uniform(-10, 10, (200, 2)), rng.uniform(-10, 10, (150, 2))
        assert hausdorff(a, b) == pytest.approx(shapely.hausdorff_distance(MultiPoint(a), MultiPoint(b)), abs=1e-9)
        assert hausdorff(a, b) == hausdorff(b, a)


def test_layout_distance_is_zero_for_the_same_layout_anywhere():
    scene = Scene.from_dict(LOT)
    assert layout_distance(scene, scene) == 0.0
    assert layout_distance(scene, _moved(scene, [-40.0, 7.0, 0.3])) == pytest.approx(0.0, abs=1e-6)


def test_layout_distance_measures_a_moved_obstacle():
    shifted = dict(LOT, obstacles=[{"polygon": [[5, 6.5], [9, 6.5], [9, 8.5], [5, 8.5]]}, LOT["obstacles"][1]])
    d = layout_distance(Scene.from_dict(LOT), Scene.from_dict(shifted))
    assert d == pytest.approx(1.5, abs=0.01)
    assert layout_points(Scene.from_dict(LOT)).shape[1] == 2


def test_factorial_test_scenes_exceed_the_disjointness_floor():
    train, test = load_benchmark("factorial", "train"), load_benchmark("factorial", "test")
    assert disjointness_floor(train, test) >= DISJOINTNESS_FLOOR_M
    assert np.all(np.isfinite(nearest_train_distances(train, test)))


def test_topology_scenes_of_a_cell_are_no_copies_of_each_other():
    # the whole benchmark's floor is pinned by the regeneration test; recompute one cell here
    train, test = load_benchmark("topology", "train"), load_benchmark("topology", "test")
    cell = test[0].tags["cell"]
    same_train = [s for s in train if s.tags["cell"] == cell]
    same_test = [s for s in test if s.tags["cell"] == cell]
    assert disjointness_floor(same_train, same_test) >= DISJOINTNESS_FLOOR_M
    pairs = [(a, b) for i, a in enumerate(same_train) for b in same_train[i + 1:]]
    assert min(layout_distance(a, b) for a, b in pairs[:10]) >= DISJOINTNESS_FLOOR_M
