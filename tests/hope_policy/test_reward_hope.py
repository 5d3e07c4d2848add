"""HOPE's reward terms: the box intersection and IoU against shapely, the shaping sum against a hand computation,
and a whole episode's rewards against an oracle written from HOPE's formulas over the visited poses."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from shapely.affinity import affine_transform
from shapely.geometry import Polygon

from hope_policy.config import HopeEnvConfig, HopeRewardConfig
from hope_policy.env import HopeParkingEnv
from hope_policy.reward import box_iou, convex_intersection_area, reward_parameters, shaping_reward
from np_sim.scene import Scene

LOCAL = HopeEnvConfig().vehicle.footprint_local()
coord = st.floats(-6.0, 6.0)
angle = st.floats(-math.pi, math.pi)


def box(pose):
    c, s = math.cos(pose[2]), math.sin(pose[2])
    return affine_transform(Polygon(LOCAL), [c, -s, s, c, pose[0], pose[1]])


@settings(max_examples=150, deadline=None)
@given(coord, coord, angle, coord, coord, angle)
def test_intersection_area_and_iou_against_shapely(x0, y0, t0, x1, y1, t1):
    a, b = box((x0, y0, t0)), box((x1, y1, t1))
    corners = np.array(a.exterior.coords)[:4]
    assert convex_intersection_area(corners, np.array(b.exterior.coords)[:4]) == pytest.approx(
        a.intersection(b).area, abs=1e-9)
    iou = a.intersection(b).area / a.union(b).area
    assert box_iou(x0, y0, t0, np.array([x1, y1, t1]), LOCAL) == pytest.approx(iou, abs=1e-9)


def test_iou_of_identical_and_disjoint_boxes():
    target = np.array([1.0, 2.0, 0.3])
    assert box_iou(1.0, 2.0, 0.3, target, LOCAL) == pytest.approx(1.0)
    assert box_iou(20.0, 2.0, 0.3, target, LOCAL) == 0.0


def test_shaping_reward_by_hand():
    w = reward_parameters(HopeRewardConfig())
    # t = 4, distance 8 → 7.5 m with a 6 m start (normaliser 10 m), IoU 0.3 over a best of 0.1
    expected = 0.1 * (1 * -math.tanh(4 / 2000) + 5 * 0.5 / 10 + 10 * 0.2)
    assert shaping_reward(w, 4.0, 8.0, 7.5, 6.0, 0.3, 0.1) == pytest.approx(expected, rel=1e-12)
    # the IoU term pays only improvements on the best so far; a 25 m start normalises by 25 m
    expected = 0.1 * (-math.tanh(7 / 2000) + 5 * -0.5 / 25)
    assert shaping_reward(w, 7.0, 8.0, 8.5, 25.0, 0.2, 0.4) == pytest.approx(expected, rel=1e-12)


def test_episode_rewards_against_hopes_formulas():
    scene = Scene.from_dict({"boundary": [[-30, -30], [30, -30], [30, 30], [-30, 30]], "obstacles": [],
                             "target": [0.0, 0.0, math.pi / 2]})
    env = HopeParkingEnv(scene, HopeEnvConfig(rs_takeover=False))
    start = np.array([0.4, 4.0, -math.pi / 2])  # heading against the target's: the Hermite gate stays closed
    env.reset(options={"start": start})
    target_box = box(scene.target)
    prev, best = start, target_box.intersection(box(start)).area / target_box.union(box(start)).area
    start_dist = math.hypot(*start[:2])
    ious = []
    for k in range(1, 13):
        _, reward, terminated, truncated, info = env.step(np.array([0.1, 0.4], np.float32))  # 0.5 m arcs
        assert not (terminated or truncated)
        pose = info["pose"]
        iou = target_box.intersection(box(pose)).area / target_box.union(box(pose)).area
        expected = 0.1 * (-math.tanh((k + 1) / 2000)
                          + 5 * (math.hypot(*prev[:2]) - math.hypot(*pose[:2])) / max(start_dist, 10)
                          + 10 * max(iou - best, 0.0))
        assert reward == pytest.approx(expected, abs=1e-9)
        best, prev = max(best, iou), pose
        ious.append(iou)
    assert max(ious) > 0.3 and ious[-1] < max(ious)  # the run passes over the target and leaves it
