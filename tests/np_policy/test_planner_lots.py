"""NeuralParker on a lot with more parked cars than its slots (the site's rule, ``over_capacity='nearest'``): it
plans, its plans hold against the whole lot, and scenes within the slots plan exactly as with the rule off.

Validity is checked with shapely on the paper's samples (30 per arc from `sample_arc`, eq:arc, and the Hermite
points), not with the planner's collision kernels.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest
from shapely.geometry import Point, Polygon

from np_policy.config import PAPER
from np_policy.planner import NeuralParkerPlanner, Policy
from np_sim.benchmarks import frozen_starts, load_benchmark
from np_sim.errors import CapacityError
from np_sim.kinematics import arc_step, sample_arc
from np_sim.lots import LotConfig, generate_lot
from np_sim.scene_starts import draw_starts

CHECKPOINT = Path("checkpoints/factorial_np_seed0.pt")


@pytest.fixture(scope="module")
def policy() -> Policy:
    return Policy.load(CHECKPOINT)


def _reference_points(plan) -> np.ndarray:
    """The paper's samples of a plan: 30 per arc by eq:arc, then the Hermite points."""
    pose, points = np.asarray(plan.start, float), []
    for kappa, length in plan.arcs:
        points.append(sample_arc(pose, kappa, length, 30)[:, :2])
        pose = arc_step(pose, kappa, length)
    if plan.hermite is not None:
        points.append(plan.hermite.points)
    return np.concatenate(points)


def test_neuralparker_plans_a_lot_of_80_cars_and_its_plans_hold_against_every_car(policy):
    lot = generate_lot(LotConfig(bays_per_row=24), seed=3)
    assert len(lot.obstacles) >= 80
    planner = NeuralParkerPlanner(policy)
    boundary, cars = Polygon(lot.boundary), [Polygon(o.vertices) for o in lot.obstacles]
    plans = [planner.plan(lot, start) for start in draw_starts(lot, 4, seed=0, convention="reference_point").poses]
    assert sum(plan.success for plan in plans) >= 2, [plan.reason for plan in plans]
    for plan in plans:
        if plan.success:
            for x, y in _reference_points(plan):
                point = Point(x, y)
                assert boundary.contains(point) and not any(car.intersects(point) for car in cars)
    with pytest.raises(CapacityError, match="max_obstacles = 20"):
        NeuralParkerPlanner(policy, dataclasses.replace(PAPER, over_capacity="refuse")).plan(lot, plans[0].start)


def test_scenes_within_the_slots_plan_exactly_as_with_the_rule_off(policy):
    scenes, starts = load_benchmark("factorial", "test"), frozen_starts("factorial")
    with_rule = NeuralParkerPlanner(policy)
    without = NeuralParkerPlanner(policy, dataclasses.replace(PAPER, over_capacity="refuse"))
    for k in range(0, len(scenes), 3):
        a, b = with_rule.plan(scenes[k], starts[k, k % 40]), without.plan(scenes[k], starts[k, k % 40])
        assert (a.success, a.reason) == (b.success, b.reason)
        np.testing.assert_array_equal(a.arcs, b.arcs)
        assert (a.hermite is None) == (b.hermite is None)
        if a.hermite is not None:
            np.testing.assert_array_equal(a.hermite.points, b.hermite.points)
