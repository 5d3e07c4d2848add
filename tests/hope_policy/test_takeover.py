"""Shortest-first Reeds–Shepp takeover: every candidate word reaches the goal and the shortest is the project's
shortest path; chunking; the search against a shapely re-implementation of HOPE's shortest-first rule; an
episode under takeover passes the project's plan validator."""

import math

import numpy as np
import pytest
from shapely.geometry import Point, Polygon

from hope_policy.config import HopeEnvConfig
from hope_policy.env import HopeParkingEnv
from hope_policy.takeover import MAX_CHUNKS, MAX_WORDS, candidate_arcs, chunk_arcs, find_takeover
from np_sim.kernels.kinematics import arc_point
from np_sim.plan import Plan
from np_sim.reeds_shepp import shortest_length
from np_sim.scene import Scene
from np_sim.scene_arrays import packed_scene
from np_sim.validate import scoring_rule, validate_plan

KAPPA = math.tan(0.75) / 2.8
BOUNDARY = [[-30, -30], [30, -30], [30, 30], [-30, 30]]
TARGET_BOX = Polygon(HopeEnvConfig().vehicle.footprint((0.0, 0.0, math.pi / 2)))


def candidates(start, target):
    arcs, counts, totals = np.empty((MAX_WORDS, 5, 2)), np.zeros(MAX_WORDS, np.int64), np.empty(MAX_WORDS)
    n = candidate_arcs(*start, np.asarray(target, float), KAPPA, arcs, counts, totals)
    return [arcs[w, :counts[w]].copy() for w in range(n)], totals[:n].copy()


def end_pose(start, arcs):
    x, y, th = start
    for kappa, length in arcs:
        x, y, th = arc_point(x, y, th, kappa, length)
    return np.array([x, y, th])


def test_every_candidate_reaches_the_goal_and_the_shortest_is_reeds_shepps():
    rng = np.random.default_rng(0)
    for _ in range(40):
        start = np.array([*rng.uniform(-8, 8, 2), rng.uniform(-math.pi, math.pi)])
        goal = np.array([0.0, 0.0, rng.uniform(-math.pi, math.pi)])
        words, totals = candidates(start, goal)
        assert len(words) >= 4
        for arcs, total in zip(words, totals):
            end = end_pose(start, arcs)
            np.testing.assert_allclose(end[:2], goal[:2], atol=1e-8)
            assert abs(math.remainder(end[2] - goal[2], 2 * math.pi)) < 1e-8
            assert np.all(np.isclose(np.abs(arcs[:, 0]), KAPPA) | (arcs[:, 0] == 0))
            assert total == pytest.approx(np.abs(arcs[:, 1]).sum())
        assert totals.min() == pytest.approx(shortest_length(start, goal, KAPPA), rel=1e-9)


def test_chunks_are_at_most_one_full_speed_action_full_chunks_first():
    arcs = np.array([[0.3, 2.7], [0.0, -0.4], [-0.3, 1.25]])
    out = np.empty((MAX_CHUNKS, 2))
    m = chunk_arcs(arcs, 3, 1.25, out)
    np.testing.assert_allclose(out[:m], [[0.3, 1.25], [0.3, 1.25], [0.3, 0.2], [0.0, -0.4], [-0.3, 1.25]])
    assert chunk_arcs(arcs, 3, 1.25, np.empty((3, 2))) == -1


def shapely_free(scene, start, arcs, spacing=0.1):
    """Reference-point points of ``arcs`` at spacing ≤ 0.1 m strictly inside the boundary and outside obstacles."""
    boundary = Polygon(scene.boundary)
    obstacles = [Polygon(o.vertices) for o in scene.obstacles]
    for x, y in Plan(start=start, arcs=arcs).sample(spacing)[1:, :2]:
        p = Point(x, y)
        if not boundary.contains(p) or any(o.intersects(p) for o in obstacles):
            return False
    return True


def hope_shortest_first(scene, start, ratio=1.6):
    """HOPE's find_rs_path: candidates by length, stop past ratio × shortest from the third on, first free one."""
    words, totals = candidates(start, scene.target)
    order = np.argsort(totals, kind="stable")
    for idx, w in enumerate(order, start=1):
        if totals[w] > ratio * totals[order[0]] and idx > 2:
            return None
        if shapely_free(scene, start, words[w]):
            return words[w]
    return None


def merged(arcs):
    """Consecutive pieces of equal curvature and gear merged, empty pieces dropped: a path's word."""
    out = []
    for kappa, length in arcs:
        if abs(length) < 1e-9:
            continue
        if out and np.isclose(out[-1][0], kappa) and out[-1][1] * length > 0:
            out[-1][1] += length
        else:
            out.append([kappa, length])
    return np.array(out)


def test_search_matches_hopes_shortest_first_rule_with_shapely_checks():
    rng = np.random.default_rng(4)
    outcomes = {"shortest": 0, "longer": 0, "none": 0}
    for _ in range(40):
        start = np.array([*rng.uniform(-9, 9, 2), rng.uniform(-math.pi, math.pi)])
        cx, cy = 0.5 * start[:2] + rng.uniform(-1.5, 1.5, 2)
        block = Polygon([[cx - 1.2, cy - 1.2], [cx + 1.2, cy - 1.2], [cx + 1.2, cy + 1.2], [cx - 1.2, cy + 1.2]])
        if block.distance(TARGET_BOX) < 0.3 or block.distance(Point(start[:2])) < 0.3:
            continue
        scene = Scene.from_dict({"boundary": BOUNDARY, "obstacles": [{"polygon": list(block.exterior.coords)[:4]}],
                                 "target": [0.0, 0.0, math.pi / 2]})
        queue = np.empty((MAX_CHUNKS, 2))
        m = find_takeover(packed_scene(scene).geometry, 0, *start, np.asarray(scene.target, float), KAPPA, 0.1, 1.6,
                          False, HopeEnvConfig().vehicle.footprint_local(), 1.25, queue)
        expected = hope_shortest_first(scene, start)
        if expected is None:
            assert m == 0
            outcomes["none"] += 1
            continue
        np.testing.assert_allclose(merged(queue[:m]), merged(expected), atol=1e-9)
        longer = np.abs(expected[:, 1]).sum() > shortest_length(start, scene.target, KAPPA) + 1e-6
        outcomes["longer" if longer else "shortest"] += 1
    assert min(outcomes.values()) >= 1, outcomes  # every branch of the rule was exercised


def test_takeover_episode_passes_the_plan_validator():
    obstacle = [[-6.0, -2.0], [-4.0, -2.0], [-4.0, 2.0], [-6.0, 2.0]]
    scene = Scene.from_dict({"boundary": BOUNDARY, "obstacles": [{"polygon": obstacle}],
                             "target": [0.0, 0.0, math.pi / 2]})
    env = HopeParkingEnv(scene, HopeEnvConfig())
    env.reset(options={"start": [3.0, 6.0, -math.pi / 2]})  # 6.7 m away, facing against the target heading
    _, _, terminated, _, info = env.step(np.array([0.0, 0.2], np.float32))
    assert info["rs_found"] and not info["rs_takeover"] and not terminated
    queued = env.core.queue[0, :int(env.core.S[0, 8])].copy()
    assert np.abs(queued[:, 1]).max() <= 1.25 + 1e-12
    steps = 0
    while not terminated:
        # the policy asks for full lock left at full speed; the queued chunks override it
        _, _, terminated, truncated, info = env.step(np.array([1.0, 1.0], np.float32))
        assert info["rs_takeover"] and not truncated
        np.testing.assert_allclose(info["arc"], queued[steps])
        assert abs(info["executed_action"][0]) in (0.0, pytest.approx(1.0)) and abs(info["executed_action"][1]) <= 1
        steps += 1
    plan = info["plan"]
    assert info["success"] and plan.success
    assert validate_plan(scene, plan, scoring_rule("reference_point")).valid
    end = plan.sample(0.1)[-1]
    assert math.hypot(*end[:2]) <= 0.1 + 1e-6 and abs(math.remainder(end[2] - math.pi / 2, 2 * math.pi)) <= 0.18
