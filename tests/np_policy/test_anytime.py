"""The anytime footprint planner (``accept_mean_m``): the mean rollout when it keeps the wanted clearance, checked
with shapely; otherwise exactly the best-of-N answer; the stage of every plan named."""

import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from shapely.geometry import Polygon as ShapelyPolygon

from clearance_oracle import shapely_clearance  # tests/clearance_oracle.py
from clip_frames import first_frame  # tests/clip_frames.py
from np_policy.config import FOOTPRINT_ANYTIME, FOOTPRINT_BEST_OF_N, PRESETS, NeuralParkerConfig
from np_policy.planner import NeuralParkerPlanner, Policy
from np_sim.errors import ConfigError
from np_sim.validate import validation_failure

CHECKPOINT = Path("checkpoints/site_np_footprint.pt")
TRAIN_SEEDS = (9, 10)
"""Training-stream clips (never held-out ones): the mean rollout of the shipped footprint checkpoint keeps 0.2 m
from the first frame of clip 9 and fails from clip 10's, so both branches run."""
SMALL = {"samples": 4, "rescue": ((8, 2.0, "policy"),)}
"""Fewer sampled rollouts than the presets (the property holds for any number; the test stays fast)."""


@pytest.fixture(scope="module")
def first_frames():
    return [first_frame(seed) for seed in TRAIN_SEEDS]


@pytest.fixture(scope="module")
def planners():
    policy = Policy.load(CHECKPOINT)
    return (NeuralParkerPlanner(policy, dataclasses.replace(FOOTPRINT_ANYTIME, **SMALL, mean_margin_m=0.0)),
            NeuralParkerPlanner(policy, dataclasses.replace(FOOTPRINT_BEST_OF_N, **SMALL,
                                                            rollout_max_arcs=FOOTPRINT_ANYTIME.rollout_max_arcs)))


def test_the_mean_rollout_is_kept_when_clear_and_otherwise_the_answer_is_best_of_n(planners, first_frames):
    anytime, best_of_n = planners
    stages = []
    for scene, start in first_frames:
        plan = anytime.plan(scene, start)
        stages.append(plan.stage)
        if plan.stage == "mean":
            mean = anytime.mean(scene, start)[0]
            np.testing.assert_array_equal(plan.arcs, mean.arcs)
            rows = plan.sample(0.05)
            assert shapely_clearance(scene, rows, anytime.body) >= FOOTPRINT_ANYTIME.accept_mean_m - 1e-9
            assert anytime.accept_implies_valid(scene, plan) and plan.success  # accepted, not validated again …
            assert validation_failure(scene, plan, "footprint", anytime.body) == ""  # … which it would pass
        else:
            reference = best_of_n.plan(scene, start)
            np.testing.assert_array_equal(plan.arcs, reference.arcs)
            assert (plan.success, plan.stage) == (reference.success, reference.stage)
    assert "mean" in stages and set(stages) - {"mean"}


def test_a_clearance_no_plan_can_keep_sends_every_call_to_the_sampled_rounds(planners, first_frames):
    anytime, best_of_n = planners
    strict = NeuralParkerPlanner(anytime.policy, dataclasses.replace(anytime.config, accept_mean_m=50.0))
    scene, start = first_frames[0]
    plan, reference = strict.plan(scene, start), best_of_n.plan(scene, start)
    assert plan.stage in ("sampled", "rescue") and plan.stage == reference.stage
    np.testing.assert_array_equal(plan.arcs, reference.arcs)


def test_the_anytime_preset_is_best_of_n_with_the_wanted_margin_as_its_acceptance_and_an_arc_budget():
    """'footprint_anytime' is 'footprint_best_of_n' accepting a mean rollout with 0.2 m (played with the body grown
    by 0.2 m first) and cutting its sampled and rescue rollouts at 50 arcs (docs/best_of_n.md, 2026-12-03);
    'footprint_best_of_n' keeps the env's 200."""
    assert PRESETS["footprint_anytime"] is FOOTPRINT_ANYTIME
    assert FOOTPRINT_ANYTIME == dataclasses.replace(FOOTPRINT_BEST_OF_N, accept_mean_m=0.2, rollout_max_arcs=50,
                                                    mean_margin_m=0.2)
    assert FOOTPRINT_BEST_OF_N.rollout_max_arcs is None and FOOTPRINT_ANYTIME.rescue_stop_m is None
    assert FOOTPRINT_ANYTIME.accept_mean_m == FOOTPRINT_ANYTIME.weights.wanted_margin_m
    assert NeuralParkerConfig.from_dict(json.loads(json.dumps(FOOTPRINT_ANYTIME.to_dict()))) == FOOTPRINT_ANYTIME
    with pytest.raises(ConfigError, match=r"NeuralParkerConfig.accept_mean_m: expected a finite number >= 0 m"):
        NeuralParkerConfig(accept_mean_m=-0.1)
    with pytest.raises(ConfigError, match=r"NeuralParkerConfig.accept_mean_m: expected a number or null"):
        NeuralParkerConfig.from_dict({"accept_mean_m": "0.2"})


@settings(max_examples=60, deadline=None)
@given(kappa=st.floats(-1.5, 1.5), ds=st.floats(0.001, 0.05), theta=st.floats(-np.pi, np.pi),
       gear=st.sampled_from([1.0, -1.0]))
def test_clearance_at_samples_covers_the_body_between_them(kappa, ds, theta, gear):
    """clearance_covers_sweep's claim, brute force with shapely: for a margin at its bound, the real body at every
    pose between two samples ds apart on an arc of curvature κ lies inside the union of the two grown bodies."""
    from np_policy.sampling import clearance_covers_sweep
    from np_sim.vehicle import VehicleSpec

    def arc_point(x, y, th, k, s):  # the unicycle's closed form (hand-derived, not the kernel's)
        if abs(k * s) < 1e-12:
            return (x + s * np.cos(th), y + s * np.sin(th), th)
        return (x + (np.sin(th + k * s) - np.sin(th)) / k, y - (np.cos(th + k * s) - np.cos(th)) / k, th + k * s)

    body = VehicleSpec()
    r_max = max(np.hypot(*body.footprint_local().T))
    margin = 0.5 * ds * (1.0 + abs(kappa) * r_max)
    assert clearance_covers_sweep(body, margin, ds, abs(kappa))
    assert not clearance_covers_sweep(body, 0.99 * margin, ds, abs(kappa))
    start = (1.0, -2.0, theta)
    end = arc_point(*start, kappa, gear * ds)
    grown = body.inflated(margin)
    covered = ShapelyPolygon(grown.footprint(start)).union(ShapelyPolygon(grown.footprint(end))).buffer(1e-9)
    for f in np.linspace(0.0, 1.0, 21):
        assert covered.covers(ShapelyPolygon(body.footprint(arc_point(*start, kappa, gear * ds * f))))


def test_the_grown_body_mean_rollout_answers_first_and_keeps_the_clearance_with_the_real_body(planners):
    """Training clip 39 (never a held-out one): the plain mean rollout parks with under 0.1 m to spare, the mean
    rollout played with the body grown by 0.2 m keeps 0.2 m and answers the call; shapely measures the real body."""
    anytime, _ = planners
    grown = NeuralParkerPlanner(anytime.policy, dataclasses.replace(anytime.config, mean_margin_m=0.2))
    scene, start = first_frame(39)
    assert anytime.plan(scene, start).stage != "mean"
    plan = grown.plan(scene, start)
    assert plan.stage == "mean" and plan.success
    np.testing.assert_array_equal(plan.arcs, grown.grown_mean_rollout(scene, start).arcs)
    assert shapely_clearance(scene, plan.sample(0.05), grown.body) >= 0.2 - 1e-9
    assert validation_failure(scene, plan, "footprint", grown.body) == ""


def test_where_the_grown_body_cannot_start_the_plain_anytime_answer_stands(planners):
    """Training clip 35 starts closer than 0.2 m to an object: no grown-body rollout, the same answer as without."""
    anytime, _ = planners
    grown = NeuralParkerPlanner(anytime.policy, dataclasses.replace(anytime.config, mean_margin_m=0.2))
    scene, start = first_frame(35)
    assert grown.grown_mean_rollout(scene, start) is None
    plan, reference = grown.plan(scene, start), anytime.plan(scene, start)
    assert plan.stage == reference.stage
    np.testing.assert_array_equal(plan.arcs, reference.arcs)
    with pytest.raises(ConfigError, match=r"mean_margin_m: .* needs accept_mean_m"):
        dataclasses.replace(FOOTPRINT_BEST_OF_N, mean_margin_m=0.2)


def test_with_accept_aligned_a_mean_rollout_ending_at_the_tolerance_edge_goes_to_the_sampled_round():
    """Training clip 224: the anytime preset answers with a mean rollout that ends 10° off the target's heading
    (the connector's 80°/100° candidate, on the parking tolerance's edge); with ``accept_aligned`` that plan is
    refused and the sampled round answers with one ending on the target's heading. Clip 9's mean rollout ends
    aligned and is still accepted. End poses from `np_sim.validate.end_pose_error`, not the planner."""
    from np_sim.validate import end_pose_error

    policy = Policy.load(CHECKPOINT)
    small = dataclasses.replace(FOOTPRINT_ANYTIME, **SMALL)
    plain, aligned = NeuralParkerPlanner(policy, small), NeuralParkerPlanner(policy, dataclasses.replace(
        small, accept_aligned=True))
    scene, start = first_frame(224)
    before, after = plain.plan(scene, start), aligned.plan(scene, start)
    assert before.stage == "mean" and end_pose_error(scene, before)[1] == pytest.approx(np.radians(10.0), abs=1e-6)
    assert after.stage == "sampled" and after.success and end_pose_error(scene, after)[1] < np.radians(5.0)
    scene, start = first_frame(9)
    assert aligned.plan(scene, start).stage == "mean"
    with pytest.raises(ConfigError, match=r"accept_aligned: .* needs accept_mean_m"):
        NeuralParkerConfig(accept_aligned=True)
