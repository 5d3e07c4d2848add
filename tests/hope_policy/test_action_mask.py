"""HOPE's 42-anchor action mask: anchor sweeps against HOPE's mask circles, swept distances against shapely,
the compiled mask against a plain numpy version of HOPE's rule and against brute-force shapely sweeps, the
post-processing against scipy's minimum filter, and the masked anchor choice against a hand computation."""

import math

import numpy as np
import pytest
from scipy.ndimage import minimum_filter1d
from shapely.affinity import affine_transform
from shapely.geometry import LineString, Point, Polygon

from hope_policy.action_mask import (MASK_SECTOR, anchor_actions, anchor_poses, anchor_probabilities, apply_mask,
                                     free_poses, post_process, sector_maxima, swept_distances, upsample_circular)
from hope_policy.config import HopeEnvConfig
from hope_policy.env import HopeParkingEnv
from np_sim.examples import example_scenes
from np_sim.lidar import cast_rays, footprint_ranges
from np_sim.scene import Scene

CONFIG = HopeEnvConfig()
LOCAL = CONFIG.vehicle.footprint_local()


def hope_sweep_pose(steer, speed, k):
    """HOPE ActionMask.init_vehicle_box: after k of n = 10 increments Δφ = 0.5 · speed / 10 / R on the circle of
    radius R = L / tan δ about (0, R): (R sin φ, R (1 − cos φ), φ); the straight line when δ = 0."""
    if steer == 0.0:
        return np.array([0.05 * speed * k, 0.0, 0.0])
    radius = 2.8 / math.tan(steer)
    phi = k * 0.5 * speed / 10 / radius
    return np.array([radius * math.sin(phi), radius * (1 - math.cos(phi)), phi])


def box_at(pose):
    c, s = math.cos(pose[2]), math.sin(pose[2])
    return affine_transform(Polygon(LOCAL), [c, -s, s, c, pose[0], pose[1]])


def test_anchors_are_hopes_discrete_actions():
    a = anchor_actions()
    steer = np.arange(0.75, -0.825, -0.075)  # HOPE configs.py discrete_actions, PRECISION = 10
    np.testing.assert_allclose(a[:21, 0] * 0.75, steer, atol=1e-12)
    np.testing.assert_allclose(a[21:, 0] * 0.75, steer, atol=1e-12)
    assert a[:21, 1].tolist() == [1.0] * 21 and a[21:, 1].tolist() == [-1.0] * 21


def test_anchor_sweeps_are_hopes_mask_circles():
    poses = anchor_poses(CONFIG)
    for j in range(42):
        steer, speed = anchor_actions()[j] * [0.75, 1.0]
        for k in range(10):
            np.testing.assert_allclose(poses[j, k], hope_sweep_pose(steer, speed, k + 1), atol=1e-12)


def test_swept_distances_are_the_far_crossing_with_each_box():
    d_star = swept_distances(CONFIG)  # (42, 10, 1200): beam b at up-sampled index 10 b
    poses = anchor_poses(CONFIG)
    rng = np.random.default_rng(0)
    for _ in range(40):
        a, k, b = rng.integers(42), rng.integers(10), rng.integers(120)
        psi = 2 * math.pi * b / 120
        ray = LineString([(0, 0), (50 * math.cos(psi), 50 * math.sin(psi))])
        hit = ray.intersection(box_at(poses[a, k]).exterior)
        points = getattr(hit, "geoms", [hit])
        far = max((Point(0, 0).distance(p) for p in points if not p.is_empty), default=0.0)
        assert d_star[a, k, 10 * b] == pytest.approx(far, abs=1e-9)


def test_upsampling_is_circular_linear_interpolation():
    x = np.array([1.0, 3.0, 2.0])
    np.testing.assert_allclose(upsample_circular(x, 2), [1.0, 2.0, 3.0, 2.5, 2.0, 1.5])


def hope_rule(distances, b, d_star, rate=10, lidar_range=10.0):
    """HOPE's get_steps before post-processing, written with numpy over every beam (no shortcut)."""
    obs = upsample_circular(np.clip(distances - b, 0, lidar_range) + b, rate)
    blocked = (d_star > obs[None, None, :]).any(-1)  # (42, n)
    return np.where(blocked.any(1), blocked.argmax(1), d_star.shape[1])


def test_compiled_mask_equals_hopes_rule_on_random_scans():
    d_star = swept_distances(CONFIG)
    sec = sector_maxima(d_star, MASK_SECTOR)
    b = footprint_ranges(CONFIG.vehicle, 120)
    rng = np.random.default_rng(1)
    out = np.empty(42, np.int64)
    for trial in range(30):
        distances = np.clip(b + rng.gamma(1.0 + trial % 3, 0.4 + 0.1 * trial, 120), 0, 10)
        free_poses(distances, b, 10.0, d_star, sec, MASK_SECTOR, 10, out)
        np.testing.assert_array_equal(out, hope_rule(distances, b, d_star))


def test_mask_against_brute_force_shapely_sweeps():
    wall = [[4.0, -3.0], [5.0, -3.0], [5.0, 3.0], [4.0, 3.0]]  # 0.24 m ahead of the front bumper
    scene = Scene.from_dict({"boundary": [[-30, -30], [30, -30], [30, 30], [-30, 30]], "obstacles": [{"polygon": wall}],
                             "target": [-15.0, 0.0, math.pi / 2]})
    d_star = swept_distances(CONFIG)
    b = footprint_ranges(CONFIG.vehicle, 120)
    out = np.empty(42, np.int64)
    free_poses(cast_rays(scene, (0.0, 0.0, 0.0)), b, 10.0, d_star, sector_maxima(d_star, MASK_SECTOR), MASK_SECTOR, 10,
               out)
    obstacle = Polygon(wall)
    exact = []
    for steer, speed in anchor_actions() * [0.75, 1.0]:
        hits = [box_at(hope_sweep_pose(steer, speed, k)).intersects(obstacle) for k in range(1, 11)]
        exact.append(hits.index(True) if any(hits) else 10)
    exact = np.array(exact)
    assert exact[21:].tolist() == [10] * 21 and exact[10] == 4  # reverse all free; straight ahead 4 poses
    assert np.all(np.abs(out - exact) <= 1) and np.mean(out == exact) >= 0.9


def test_post_processing_against_scipy_minimum_filter():
    rng = np.random.default_rng(3)
    out = np.empty(42)
    for _ in range(20):
        free = rng.integers(0, 11, 42)
        post_process(free, 10, 5, out)
        halves = []
        for half in (free[:21].astype(float), free[21:].astype(float)):
            half[[0, -1]] -= 1
            halves.append(minimum_filter1d(half, 5, mode="reflect"))
        expected = np.clip(np.concatenate(halves), 0, 10) / 10
        np.testing.assert_allclose(out, expected if expected.sum() > 0 else np.full(42, 0.01))
    post_process(np.zeros(42, np.int64), 10, 5, out)
    np.testing.assert_array_equal(out, np.full(42, 0.01))


def test_env_mask_is_the_post_processed_rule():
    env = HopeParkingEnv(example_scenes()[0], CONFIG)
    obs, _ = env.reset(seed=5)
    pose = env.core.S[0, :3]
    b = footprint_ranges(CONFIG.vehicle, 120)
    expected = np.empty(42)
    post_process(hope_rule(cast_rays(env.core.scenes[0], pose), b, swept_distances(CONFIG)), 10, 5, expected)
    np.testing.assert_allclose(obs["action_mask"], expected, atol=1e-7)


def test_anchor_probabilities_by_hand_and_the_masked_choice():
    mean, std = np.array([0.2, 0.9]), np.array([0.5, 0.3])
    mask = np.zeros(42)
    mask[[3, 10, 30]] = [1.0, 0.5, 0.2]
    p = anchor_probabilities(mean, std, mask)
    anchors = anchor_actions()

    def score(a):
        terms = [-0.5 * ((a[d] - mean[d]) / std[d]) ** 2 - math.log(math.sqrt(2 * math.pi) * std[d]) for d in range(2)]
        return math.exp(sum(min(max(t, -10.0), 10.0) for t in terms))

    weights = {j: score(anchors[j]) * mask[j] for j in (3, 10, 30)}
    total = sum(weights.values())
    for j, w in weights.items():
        assert p[j] == pytest.approx(w / total, rel=1e-12)
    assert p.sum() == pytest.approx(1.0) and np.count_nonzero(p) == 3
    np.testing.assert_array_equal(apply_mask(mean, std, mask), anchors[max(weights, key=weights.get)])
    draws = apply_mask(np.tile(mean, (4000, 1)), np.tile(std, (4000, 1)), np.tile(mask, (4000, 1)),
                       np.random.default_rng(0))
    for j in (3, 10, 30):
        share = np.mean(np.all(draws == anchors[j], axis=1))
        assert share == pytest.approx(p[j], abs=0.03)
