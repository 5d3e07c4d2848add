"""tracking.executor: closed-loop runs on the MuJoCo vehicle (real physics, no mocks)."""

import dataclasses
import math

import numpy as np
import pytest

from np_sim.kinematics import arc_step
from np_sim.plan import Plan
from tracking.config import ExecutorConfig, TrackerConfig
from tracking.errors import TrackingError
from tracking.executor import execute

from tracking_helpers import open_scene, plan_end, plan_from_arcs


@pytest.mark.parametrize("kappa,length", [(0.0, 8.0), (0.0, -8.0), (0.3, 8.0), (0.3, -8.0), (-0.5, 6.0),
                                          (-0.5, -6.0)])
def test_executed_motion_matches_eq_arc_with_the_spec_steering_sign(kappa, length):
    plan = plan_from_arcs([[kappa, length]], start=(1.0, -2.0, 0.4))
    end = arc_step(plan.start, kappa, length)
    record = execute(open_scene(end), plan)
    assert record.success, record.detail
    # eq:arc: heading change −sgn(κ)|lκ| whatever the gear
    turned = math.remainder(record.final_pose[2] - plan.start[2], 2 * math.pi)
    assert turned == pytest.approx(-np.sign(kappa) * abs(length * kappa), abs=math.radians(1.5))
    assert np.hypot(*(record.final_pose[:2] - end[:2])) < 0.1
    assert record.path_length_m == pytest.approx(abs(length), abs=0.15)
    assert record.reversals == 0 and record.cross_track_max_m < 0.05


def test_a_plan_with_a_cusp_is_tracked_closely(cusp_plan):
    record = execute(open_scene(plan_end(cusp_plan)), cusp_plan, controller="lqr")
    assert record.success, record.detail
    assert record.cross_track_rms_m < 0.1
    assert record.final_error[0] < 0.3 and record.final_error[1] < math.radians(10)
    assert record.reversals == 1
    assert record.path_length_m == pytest.approx(16.0, abs=0.3)
    assert record.sim_time_s > 0 and record.wall_time_s > 0


@pytest.mark.parametrize("controller", ["stanley", "pure_pursuit"])
def test_other_controllers_track_the_cusp_plan(cusp_plan, controller):
    record = execute(open_scene(plan_end(cusp_plan)), cusp_plan, controller=controller)
    assert record.success, record.detail
    assert record.controller == controller and record.cross_track_rms_m < 0.15


def test_driving_into_an_obstacle_is_a_contact_with_that_geom():
    plan = plan_from_arcs([[0.0, 12.0]], start=(0.0, 0.0, 0.0))
    wall = {"polygon": [[8.0, -3.0], [9.0, -3.0], [9.0, 3.0], [8.0, 3.0]]}
    record = execute(open_scene((-10.0, 0.0, 0.0), obstacles=[{"circle": [-15.0, 15.0, 1.0]}, wall]), plan)
    assert not record.success and record.reason == "contact"
    first = record.contacts[0]
    assert first.geom == "obstacle_1"
    # the front bumper (3.76 m ahead of the rear axle) reaches x = 8 when the reference point is near x = 4.24
    assert first.position[0] == pytest.approx(8.0, abs=0.1)
    assert record.final_pose[0] == pytest.approx(8.0 - 3.76, abs=0.15)


def test_driving_into_the_boundary_is_a_contact_with_that_edge_wall():
    plan = plan_from_arcs([[0.0, -30.0]], start=(0.0, 0.0, math.pi / 2))  # reverse towards y = −25
    record = execute(open_scene((10.0, 0.0, 0.0)), plan)
    assert record.reason == "contact"
    assert record.contacts[0].geom.startswith("wall_0_")  # edge 0 runs from (−25, −25) to (25, −25)


def test_bad_inputs_give_a_failure_reason_or_a_clear_error():
    scene = open_scene((5.0, 0.0, 0.0), obstacles=[{"circle": [0.0, 0.0, 1.0]}])
    sharp = execute(open_scene((0, 0, 0)), plan_from_arcs([[1.0, 3.0]]))
    assert sharp.reason == "steering_limit" and "κ_max" in sharp.detail
    empty = execute(open_scene((0, 0, 0)), Plan(start=np.zeros(3), success=True))
    assert empty.reason == "empty_plan"
    failed = execute(open_scene((0, 0, 0)), Plan(start=np.zeros(3), success=False, reason="timeout"))
    assert failed.reason == "plan_failed" and "timeout" in failed.detail
    overlap = execute(scene, plan_from_arcs([[0.0, 3.0]], start=(0.0, 0.0, 0.0)))
    assert overlap.reason == "start_in_collision" and not overlap.success
    with pytest.raises(TrackingError, match="Plan"):
        execute(scene, [[0.0, 3.0]])
    with pytest.raises(TrackingError, match="controller"):
        execute(open_scene((0, 0, 0)), plan_from_arcs([[0.0, 3.0]]), controller="mpc")


def test_replanning_follows_the_newest_plan():
    target = np.array([12.0, 0.0, 0.0])
    calls = []

    def replan(pose, t):
        calls.append(t)
        # straight to the target's x from wherever the vehicle is, steering back onto y = 0 is not needed here
        return plan_from_arcs([[0.0, target[0] - pose[0]]], start=pose)

    config = dataclasses.replace(TrackerConfig(), executor=ExecutorConfig(replan_period_s=0.5, max_time_s=30.0))
    first = plan_from_arcs([[0.0, 6.0]], start=(0.0, 0.0, 0.0))  # a short first plan: only replanning reaches 12 m
    record = execute(open_scene(target), first, replan=replan, config=config)
    assert record.success, record.detail
    assert record.plans_used > 1 and len(calls) >= record.plans_used - 1
    assert calls[:2] == pytest.approx([0.5, 1.0])


def test_a_vehicle_that_ends_its_plan_short_of_the_target_stands_and_takes_a_corrective_plan():
    target = np.array([6.0, 0.0, 0.0])
    first = plan_from_arcs([[0.0, 4.5]], start=(0.0, 0.0, 0.0))  # ends 1.5 m short
    finished = []

    def replan(pose, t):
        if abs(pose[0] - 4.5) > 0.1:
            return None  # keep following the first plan until it has ended
        finished.append(t)
        return plan_from_arcs([[0.0, target[0] - pose[0]]], start=pose)

    config = dataclasses.replace(TrackerConfig(), executor=ExecutorConfig(replan_period_s=0.1, max_time_s=60.0))
    record = execute(open_scene(target), first, replan=replan, config=config)
    assert record.success, record.detail
    assert record.plans_used >= 2 and finished

    def never(pose, t):
        return None

    stuck = execute(open_scene(target), first, replan=never, config=config)
    assert stuck.reason == "not_parked" and "1.5" in stuck.detail
    assert stuck.replans_failed == 0  # None means "no new plan needed", not a failed call

    def failing(pose, t):
        return Plan(start=np.asarray(pose, float), reason="no path")

    refused = execute(open_scene(target), first, replan=failing, config=config)
    assert refused.reason == "not_parked" and refused.plans_used == 1
    assert refused.replans_failed == pytest.approx(refused.sim_time_s / 0.1, abs=1)
    alone = execute(open_scene(target), first, config=config)  # the plan's own end, no replanning
    assert stuck.sim_time_s == pytest.approx(alone.sim_time_s + config.executor.hold_max_s, abs=0.05)
