"""tracking.clip_run: a vehicle whose first planner calls fail waits at its start and retries; a start in
collision is a failed call, any other configuration error stops the run; a planner must name its collision
convention; stitched replans."""

import dataclasses

import numpy as np
import pytest
import shapely

from np_sim.clips import load_clips
from np_sim.errors import ConfigError, StartInCollisionError
from np_sim.plan import Plan
from np_sim.planners import HybridAStar
from tracking.clip_run import ClipRunConfig, run_clip
from tracking.executor import plan_problem


class FailingFirst:
    """Hybrid A* (footprint) behind ``failures`` failed calls."""

    name, convention = "failing_first", "footprint"

    def __init__(self, failures: int):
        self.failures, self.search = failures, HybridAStar(convention="footprint")

    def plan(self, scene, start):
        if self.failures:
            self.failures -= 1
            return Plan(start=np.asarray(start, float), reason="budget")
        return self.search.plan(scene, start)


def test_a_failed_first_plan_is_retried_from_the_start_and_the_drive_begins_later():
    clip = next(c for c in load_clips("eval") if c.name == "eval-1000016")
    run = run_clip(clip, FailingFirst(3))
    retry = ClipRunConfig().retry_period_s
    assert [c.success for c in run.calls[:4]] == [False, False, False, True]
    assert np.allclose([c.time_s for c in run.calls[:4]], [0.0, retry, 2 * retry, 3 * retry])
    assert run.footprint_success, run.record.detail
    t = run.trajectory[:, 0]
    assert t[0] == 0.0 and np.all(np.diff(t) > 0)
    waiting = t < 3 * retry
    assert np.allclose(run.trajectory[waiting, 1:], clip.start)  # stood still while waiting
    assert run.record.sim_time_s > 3 * retry


def test_a_planner_that_never_succeeds_ends_as_plan_failed_after_the_wait():
    clip = next(c for c in load_clips("eval") if c.name == "eval-1000016")
    config = ClipRunConfig(first_plan_wait_s=2.0)
    run = run_clip(clip, FailingFirst(10_000), config=config)
    assert run.record.reason == "plan_failed" and not run.parked
    assert [c.time_s for c in run.calls] == [0.0, 0.5, 1.0, 1.5, 2.0]


class SharpFirst(FailingFirst):
    """Hybrid A* (footprint) behind ``failures`` successful plans that steer at 1.5 κ_max (untrackable)."""

    def plan(self, scene, start):
        if self.failures:
            self.failures -= 1
            sharp = Plan(start=np.asarray(start, float), arcs=np.array([[1.5 * 0.68, 2.0]]), success=True)
            assert plan_problem(sharp, ClipRunConfig().tracker)[0] == "steering_limit"
            return sharp
        return self.search.plan(scene, start)


def test_a_plan_the_tracker_refuses_counts_as_a_failed_call_and_is_retried():
    clip = next(c for c in load_clips("eval") if c.name == "eval-1000016")
    run = run_clip(clip, SharpFirst(2))
    assert [(c.success, c.rejected) for c in run.calls[:3]] == [(True, "steering_limit"), (True, "steering_limit"),
                                                                (True, "")]
    assert not any(c.rejected for c in run.calls[3:])
    assert run.footprint_success, run.record.detail
    assert np.allclose(run.trajectory[run.trajectory[:, 0] < 1.0, 1:], clip.start)  # waited, not driven sharp


class Recording(FailingFirst):
    """Hybrid A* (footprint) that keeps every start it was asked to plan from and every plan it returned."""

    def __init__(self):
        super().__init__(0)
        self.starts, self.plans = [], []

    def plan(self, scene, start):
        self.starts.append(np.array(start, float))
        self.plans.append(self.search.plan(scene, start))
        return self.plans[-1]


def test_stitched_replans_start_ahead_on_the_followed_plan():
    clip = next(c for c in load_clips("eval") if c.name == "eval-1000009")
    planner = Recording()
    run = run_clip(clip, planner, config=ClipRunConfig(stitch=True))
    assert run.footprint_success, run.record.detail
    t, poses = run.trajectory[:, 0], run.trajectory[:, 1:]
    stitched = 0
    for k in range(1, len(run.calls)):
        vehicle = poses[np.argmin(np.abs(t - run.calls[k].time_s))]
        start = planner.starts[k]
        if np.hypot(*(start[:2] - vehicle[:2])) < 1e-9:
            continue  # planned from the simulated pose (standing, or off its plan)
        stitched += 1
        earlier = np.vstack([p.sample(0.01)[:, :2] for p in planner.plans[:k] if p.success])
        assert np.min(np.hypot(*(earlier - start[:2]).T)) < 0.01  # a pose of the plan it was following
        assert np.hypot(*(start[:2] - vehicle[:2])) >= ClipRunConfig().stitch_margin_m - 0.05  # ahead of it
    assert stitched >= 1


def test_a_start_in_collision_is_a_failed_call_and_the_vehicle_waits_at_its_start():
    from np_policy.planner import NeuralParkerPlanner

    clip = next(c for c in load_clips("eval") if c.name == "eval-1000016")
    nearest = clip.frame_scene(0, pose=clip.start).obstacles[0].vertices
    inside = shapely.Polygon(nearest).representative_point()  # a point inside the nearest detected object
    moved = dataclasses.replace(clip, start=np.array([inside.x, inside.y, clip.start[2]]))
    planner = NeuralParkerPlanner.from_checkpoint("checkpoints/site_np.pt", benchmark="site")  # reference point
    with pytest.raises(StartInCollisionError, match="in collision"):
        planner.plan(moved.frame_scene(0, pose=moved.start), moved.start)
    run = run_clip(moved, planner, config=ClipRunConfig(first_plan_wait_s=1.0))
    assert run.first_plan.reason.startswith("refused: reset: start pose") and "in collision" in run.first_plan.reason
    assert [(c.time_s, c.success) for c in run.calls] == [(0.0, False), (0.5, False), (1.0, False)]
    assert run.record.reason == "plan_failed" and not run.parked


class Misconfigured(FailingFirst):
    """A planner whose first call raises a configuration error that is not a start in collision."""

    def plan(self, scene, start):
        raise ConfigError("HybridAStarConfig.step_m: expected a finite positive number, got -1.0")


def test_a_configuration_error_other_than_a_start_in_collision_propagates():
    clip = next(c for c in load_clips("eval") if c.name == "eval-1000016")
    with pytest.raises(ConfigError, match="step_m") as caught:
        run_clip(clip, Misconfigured(0))
    assert not isinstance(caught.value, StartInCollisionError)


class NoConvention:
    """Plans like a planner but names no collision convention."""

    name = "no_convention"

    def plan(self, scene, start):
        return HybridAStar(convention="footprint").plan(scene, start)


def test_a_planner_without_a_known_collision_convention_is_refused():
    clip = next(c for c in load_clips("eval") if c.name == "eval-1000016")
    with pytest.raises(TypeError, match="run_clip: expected a planner .* got NoConvention"):
        run_clip(clip, NoConvention())
    planner = FailingFirst(0)
    planner.convention = "corners"
    expected = r"FailingFirst.convention: expected one of \('reference_point', 'footprint'\), got 'corners'"
    with pytest.raises(ValueError, match=expected):
        run_clip(clip, planner)
