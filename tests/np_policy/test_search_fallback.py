"""The anytime planner's grown-body search stage (``NeuralParkerConfig.search_margin_m``), on training clips only."""

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from clearance_oracle import shapely_clearance  # tests/clearance_oracle.py
from clip_frames import first_frame  # tests/clip_frames.py
from np_policy.config import FOOTPRINT_ANYTIME, FOOTPRINT_BEST_OF_N, NeuralParkerConfig
from np_policy.planner import NeuralParkerPlanner, Policy
from np_sim.errors import ConfigError
from np_sim.planners import HybridAStar, HybridAStarConfig
from np_sim.validate import validation_failure

CHECKPOINT = Path("checkpoints/site_np_footprint.pt")
SMALL = {"samples": 4, "rescue": ((8, 2.0, "policy"),)}
"""Fewer sampled rollouts than the presets: the rounds only run where the search does not answer."""


@pytest.fixture(scope="module")
def policy():
    return Policy.load(CHECKPOINT)


def _planner(policy, **fields) -> NeuralParkerPlanner:
    return NeuralParkerPlanner(policy, dataclasses.replace(FOOTPRINT_ANYTIME, **SMALL, **fields))


def test_where_the_mean_rollouts_are_refused_the_grown_body_search_answers_with_the_clearance(policy):
    """Training clip 37: neither mean rollout keeps 0.2 m; the planner's answer is the plan of a Hybrid A* search
    built here for the body grown by 0.2 m (steering priced at 0.649 m, the test below), and shapely finds the real
    body 0.2 m off everything along it."""
    planner = _planner(policy, search_margin_m=0.2)
    scene, start = first_frame(37)
    assert not planner.grown_answer(scene, start)[1]
    plan = planner.plan(scene, start)
    assert plan.stage == "search" and plan.success
    search = HybridAStar(HybridAStarConfig(vehicle=planner.body.inflated(0.2), max_expanded=2000,
                                           steer_cost_m=0.6492424, time_budget_s=3600.0), convention="footprint")
    np.testing.assert_array_equal(plan.arcs, search.plan(scene, start).arcs)
    assert shapely_clearance(scene, plan.sample(0.05), planner.body) >= 0.2 - 1e-9
    assert validation_failure(scene, plan, "footprint", planner.body) == ""


def test_the_search_runs_only_after_the_mean_rollouts_and_a_failed_one_changes_nothing(policy):
    """Clip 39: the grown-body mean rollout answers before any search. Clip 10 with a one-node budget: the search
    fails and the answer is the one of the planner without a search, arc for arc."""
    with_search, without = _planner(policy, search_margin_m=0.2), _planner(policy)
    scene, start = first_frame(39)
    plan = with_search.plan(scene, start)
    assert plan.stage == "mean"
    np.testing.assert_array_equal(plan.arcs, without.plan(scene, start).arcs)
    starved = _planner(policy, search_margin_m=0.2, search_max_expanded=1)
    scene, start = first_frame(10)
    assert not starved.search_answer(scene, start)[0].success
    plan, reference = starved.plan(scene, start), without.plan(scene, start)
    assert plan.stage == reference.stage != "search"
    np.testing.assert_array_equal(plan.arcs, reference.arcs)


@pytest.mark.parametrize("fields, message", [
    ({"search_margin_m": -0.1}, r"search_margin_m: expected a finite number >= 0 m"),
    ({"search_max_expanded": 0}, r"search_max_expanded: expected an integer >= 1"),
    ({"search_max_expanded": 2.5}, r"search_max_expanded: expected an integer >= 1"),
    ({"start_limited_clearance": 1}, r"start_limited_clearance: expected true or false"),
    ({"target_limited_clearance": "yes"}, r"target_limited_clearance: expected true or false"),
])
def test_bad_search_settings_are_refused(fields, message):
    with pytest.raises(ConfigError, match=message):
        dataclasses.replace(FOOTPRINT_ANYTIME, **fields)


def test_a_search_answer_needs_the_anytime_test():
    with pytest.raises(ConfigError, match=r"search_margin_m: .* needs accept_mean_m"):
        dataclasses.replace(FOOTPRINT_BEST_OF_N, search_margin_m=0.2)
    assert NeuralParkerConfig.from_dict(dataclasses.replace(FOOTPRINT_ANYTIME, search_margin_m=0.2).to_dict()
                                        ).search_margin_m == 0.2


def _inflated_free(scene, pose, body) -> bool:
    """Shapely: the rectangle of ``body`` at ``pose`` is inside the boundary and touches no obstacle."""
    from shapely.geometry import Point
    from shapely.geometry import Polygon as ShapelyPolygon

    from np_sim.scene import CircleObstacle
    footprint = ShapelyPolygon(body.footprint(pose))
    shapes = [Point(*o.center).buffer(o.radius, 64) if isinstance(o, CircleObstacle) else ShapelyPolygon(o.vertices)
              for o in scene.obstacles]
    return ShapelyPolygon(scene.boundary).contains(footprint) and not any(s.intersects(footprint) for s in shapes)


def test_start_limited_clearance_asks_no_more_than_the_start_pose_keeps(policy):
    """Training clip 35 starts closer than 0.2 m to an object: the clearance asked of its plans is the highest rung
    of the 0.2 / 0.1 / 0 m ladder whose grown rectangle shapely finds free at the start, and the plan keeps it."""
    planner = _planner(policy, search_margin_m=0.2, start_limited_clearance=True)
    scene, start = first_frame(35)
    expected = next(rung for rung in (0.2, 0.1, 0.0) if _inflated_free(scene, start, planner.body.inflated(rung)))
    assert expected < 0.2
    assert planner.limited_clearance(scene, start, 0.2) == expected
    assert _planner(policy, search_margin_m=0.2).limited_clearance(scene, start, 0.2) == 0.2  # off: as asked
    plan = planner.plan(scene, start)
    assert plan.success and shapely_clearance(scene, plan.sample(0.05), planner.body) >= expected - 1e-9
    assert validation_failure(scene, plan, "footprint", planner.body) == ""


def test_target_limited_clearance_asks_no_more_than_the_target_pose_keeps(policy):
    """Training clip 68's slot leaves less than 0.2 m beside the parked car while its start keeps 0.2 m: with
    the target cap the clearance asked is the highest rung whose grown rectangle shapely finds free at the target,
    the start cap alone asks 0.2 m, and the planner's plan keeps the capped clearance."""
    scene, start = first_frame(68)
    both = _planner(policy, search_margin_m=0.2, start_limited_clearance=True, target_limited_clearance=True)
    at_target = next(rung for rung in (0.2, 0.1, 0.0)
                     if _inflated_free(scene, scene.target, both.body.inflated(rung)))
    assert at_target < 0.2 and _inflated_free(scene, start, both.body.inflated(0.2))
    assert both.limited_clearance(scene, start, 0.2) == at_target
    start_only = _planner(policy, search_margin_m=0.2, start_limited_clearance=True)
    assert start_only.limited_clearance(scene, start, 0.2) == 0.2
    plan = both.plan(scene, start)
    assert plan.success and shapely_clearance(scene, plan.sample(0.05), both.body) >= at_target - 1e-9
    assert validation_failure(scene, plan, "footprint", both.body) == ""


def test_the_search_prices_curvature_as_the_choice_prices_drive_time(policy):
    """By hand: at κ = 0.68 m⁻¹ the lateral limit of 1 m/s² allows √(1/0.68) = 1.2127 m/s, so a 1 m primitive
    takes 0.8246 s instead of 0.5 s at 2 m/s, 0.6492 m more at cruise speed; at 0.2 m⁻¹ (2.236 m/s) the cruise speed
    binds and it costs nothing. The search's steering cost is that price unless set."""
    from np_policy.sampling import ChoiceWeights, curve_surcharge

    weights = ChoiceWeights()
    assert curve_surcharge(weights, 0.68, 1.0) == pytest.approx(2.0 * 0.8246211 - 1.0, abs=1e-6)
    assert curve_surcharge(weights, -0.68, 2.0) == pytest.approx(2.0 * (2.0 * 0.8246211 - 1.0), abs=1e-6)
    assert curve_surcharge(weights, 0.2, 1.0) == 0.0 and curve_surcharge(weights, 0.0, 1.0) == 0.0
    derived = _planner(policy, search_margin_m=0.2)
    assert derived.search_at(0.2).config.steer_cost_m == pytest.approx(0.6492, abs=1e-4)
    assert derived.body.kappa_max == 0.68
    assert _planner(policy, search_margin_m=0.2, search_steer_cost_m=0.1).search_at(0.2).config.steer_cost_m == 0.1
