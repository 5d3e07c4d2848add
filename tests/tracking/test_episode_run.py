"""Frozen-start episodes under a disturbance (tracking.episode_run, Disturbance.perceive_scene): perception acts on
the planner's scene only, a zero level is the undisturbed episode, which is experiments.track's."""

import math
import zlib

import numpy as np
import pytest
import shapely

from experiments.track import track
from np_sim.benchmarks import frozen_starts, load_benchmark
from np_sim.planners import HybridAStar, HybridAStarConfig
from np_sim.scene import CircleObstacle, PolygonObstacle, Scene
from tracking.config import TrackerConfig
from tracking.disturbance import Disturbance
from tracking.episode_run import episode_columns, run_episode

TIMING = ("plan_time_ms", "wall_time_s", "realtime_factor")


def _scene() -> Scene:
    square = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    obstacles = tuple(PolygonObstacle(square + [3.0 * k, 8.0]) for k in range(6)) + (
        CircleObstacle(np.array([4.0, -6.0]), 0.5),)
    return Scene(boundary=np.array([[-20.0, -20.0], [20.0, -20.0], [20.0, 20.0], [-20.0, 20.0]]),
                 obstacles=obstacles, target=np.array([0.0, 0.0, 0.0]), start_region=None, name="t")


def test_detection_noise_shifts_each_obstacle_rigidly_by_a_seeded_offset_of_the_stated_sigma():
    scene = _scene()
    offsets = []
    for seed in range(200):
        seen = Disturbance("detection_noise", 0.3, seed).perceive_scene("run", scene)
        for before, after in zip(scene.obstacles, seen.obstacles):
            if isinstance(before, CircleObstacle):
                assert after.radius == before.radius
                offsets.append(after.center - before.center)
            else:
                d = after.vertices - before.vertices
                assert np.allclose(d, d[0])  # a rigid shift
                offsets.append(d[0])
    offsets = np.array(offsets)  # 1,400 draws of N(0, 0.3²) per axis
    assert np.all(np.abs(offsets.mean(axis=0)) < 0.03) and np.all(np.abs(offsets.std(axis=0) - 0.3) < 0.03)
    again = Disturbance("detection_noise", 0.3, 7).perceive_scene("run", scene)
    assert all(np.array_equal(a.vertices, b.vertices) for a, b in zip(
        again.obstacles[:6], Disturbance("detection_noise", 0.3, 7).perceive_scene("run", scene).obstacles[:6]))


def test_the_scene_draws_are_those_of_frame_zero_detections_numbered_in_scene_order():
    scene = _scene()
    seen = Disturbance("detection_noise", 0.15, 3).perceive_scene("key", scene)
    polygons = np.stack([o.vertices for o in scene.obstacles[:6]])
    _, moved = Disturbance("detection_noise", 0.15, 3).perceive("key", 0, np.arange(6), polygons)
    assert all(np.array_equal(a.vertices, b) for a, b in zip(seen.obstacles[:6], moved))


def test_an_obstacle_shifted_into_the_kept_clear_area_keeps_its_place():
    scene = _scene()
    keep = shapely.box(-20.0, 7.0, 20.0, 10.0)  # around the row of squares: any shift of σ = 5 m leaves or enters
    moved = Disturbance("detection_noise", 5.0, 0).perceive_scene("run", scene, keep_clear=keep)
    for before, after in zip(scene.obstacles[:6], moved.obstacles[:6]):
        assert np.array_equal(before.vertices, after.vertices) or not shapely.Polygon(after.vertices).intersects(keep)


def test_dropped_detections_remove_whole_obstacles_at_the_stated_rate_and_zero_changes_nothing():
    scene = _scene()
    kept = [len(Disturbance("detection_drop", 0.3, s).perceive_scene("run", scene).obstacles) for s in range(300)]
    assert abs(np.mean(kept) / len(scene.obstacles) - 0.7) < 0.03
    seen = Disturbance("detection_drop", 0.5, 1).perceive_scene("run", scene)
    assert all(any(o is p for p in scene.obstacles) for o in seen.obstacles)
    assert Disturbance("detection_drop", 0.0, 1).perceive_scene("run", scene) is scene
    assert Disturbance("latency", 0.1, 1).perceive_scene("run", scene) is scene


@pytest.fixture(scope="module")
def episode():
    scene = load_benchmark("factorial", "test")[0]
    return scene, frozen_starts("factorial")[0][0], HybridAStar(HybridAStarConfig(), convention="footprint")


def _plain(row: dict) -> dict:
    return {k: v for k, v in row.items() if k not in TIMING}


def test_a_zero_level_of_every_group_is_the_undisturbed_episode(episode):
    scene, start, planner = episode
    tracker = TrackerConfig()
    plain = _plain(episode_columns(run_episode(scene, start, planner, "lqr", tracker)))
    assert plain["footprint_success"] == 1
    for factor in ("detection_noise", "pose_noise", "latency", "friction"):
        zero = run_episode(scene, start, planner, "lqr", tracker, Disturbance(factor, 0.0, 5), "k")
        assert _plain(episode_columns(zero)) == plain, factor


def test_the_undisturbed_episode_is_the_track_experiments_episode(episode, tmp_path):
    scene, start, planner = episode
    tracked = track("factorial", "hybrid_astar", limit=1, out=tmp_path / "t", rrd_episodes=0, progress=False)
    ours = episode_columns(run_episode(scene, start, planner, "lqr", TrackerConfig()))
    theirs = tracked["records"][0]
    shared = set(ours) & set(theirs) - set(TIMING) - {"plan_time_ms"}
    assert len(shared) >= 20 and {k: ours[k] for k in shared} == {k: theirs[k] for k in shared}


def test_pose_noise_plans_from_the_sensed_start_and_drives_from_the_true_one(episode):
    scene, start, planner = episode
    run = run_episode(scene, start, planner, "lqr", TrackerConfig(), Disturbance("pose_noise", 0.2, 0), "k")
    rng = np.random.default_rng([0, zlib.crc32(b"k")])
    drift = rng.normal(0.0, 1.0, (256, 3))[0] * np.array([0.2, 0.2, 0.02]) * math.sqrt(0.1 / 30.0)
    white = rng.normal(0.0, 1.0, (256, 3))[0] * np.array([0.2, 0.2, 0.02])
    assert np.allclose(run.plan.start, start + drift + white)
    assert run.record.path_length_m > 0  # it drove
