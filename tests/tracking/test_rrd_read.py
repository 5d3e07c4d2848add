"""tracking.rrd_read: a recording read back equals what the closed loop itself recorded (contacts, tracking
error, final pose, the plan and the body it drove; in a clip run the planner calls and what they detected)."""

import dataclasses

import numpy as np
import pytest
import rerun as rr
import shapely
from tracking_helpers import open_scene, plan_from_arcs

from np_sim.clips import load_clips
from np_sim.plan import Plan
from np_sim.vehicle import VehicleSpec
from tracking.clip_run import ClipRunConfig, clip_tracker_config, run_clip
from tracking.config import PlantConfig
from tracking.executor import execute
from tracking.observer import TrajectoryRecorder
from tracking.rrd_read import read_run

EXTRA_M = 0.47
"""The driven body is this much longer than planned, half at each end (body_length, severe)."""


@pytest.fixture(scope="module")
def box_run(tmp_path_factory):
    """6 m forward, then 3 m back, from the origin facing +x, with a box ahead that the front end reaches at about
    x = 4.5 m (8.5 m − the 3.76 m front overhang − half the added length), driven through (detection only)."""
    plan = plan_from_arcs([[0.0, 6.0], [0.0, -3.0]], start=(0.0, 0.0, 0.0))
    box = {"polygon": [[8.5, -0.5], [9.5, -0.5], [9.5, 0.5], [8.5, 0.5]]}
    tracker = clip_tracker_config()
    tracker = dataclasses.replace(tracker, plant=PlantConfig(extra_length_m=EXTRA_M))
    path = tmp_path_factory.mktemp("box") / "box.rrd"
    recorder = TrajectoryRecorder()
    record = execute(open_scene((3.0, 0.0, 0.0), obstacles=[box], half=14.0), plan, rerun_path=path, config=tracker,
                     observer=recorder)
    return record, recorder.array(), read_run(path)


def test_the_contacts_the_tracking_error_and_the_end_read_back_as_the_executor_recorded_them(box_run):
    record, _, run = box_run
    assert record.reason == "contact" and len(record.contacts) == 1
    assert [(c.time_s, c.geom) for c in run.contacts] == [
        (pytest.approx(c.time_s, abs=1e-9), c.geom) for c in record.contacts]
    assert np.allclose([c.position for c in run.contacts], [c.position for c in record.contacts])
    assert run.contacts[0].geom.startswith("obstacle_0") and 8.4 < run.contacts[0].position[0] < 8.6
    assert run.outcome.reason == "contact" and not run.outcome.success
    assert run.outcome.cross_track_max_m == record.cross_track_max_m
    times, lateral = run.controller["cross_track_m"]
    assert len(times) == len(lateral) > 100 and np.abs(lateral).max() >= record.cross_track_max_m
    assert np.array_equal(run.outcome.final_pose, record.final_pose)
    assert np.allclose(run.executed[-1], record.final_pose[:2])
    assert run.outcome.sim_time_s == pytest.approx(record.sim_time_s) and run.outcome.plans_used == 1


def test_the_plan_reads_back_with_its_gears_and_ends(box_run):
    _, _, run = box_run
    (plan,) = run.plans
    assert plan.time_s == 0.0 and [s.gear for s in plan.segments] == [1, -1]
    forward, back = plan.segments
    assert np.allclose(forward.poses[0], [0.0, 0.0, 0.0], atol=1e-9)
    assert np.allclose(forward.poses[-1], [6.0, 0.0, 0.0], atol=1e-6)
    assert np.allclose(back.poses[-1], [3.0, 0.0, 0.0], atol=1e-6)
    assert np.allclose(forward.poses[:, 1:], 0.0, atol=1e-9) and np.all(np.diff(forward.poses[:, 0]) > 0)
    assert run.plan_at(5.0) is plan and run.plan_at(-1.0) is None


def test_the_footprints_are_the_longer_body_the_simulator_drove(box_run):
    _, trajectory, run = box_run
    assert len(run.footprint_times) > 10
    driven = VehicleSpec(front_overhang_m=0.96 + EXTRA_M / 2, rear_overhang_m=0.929 + EXTRA_M / 2)
    for t, ring, point in zip(run.footprint_times, run.footprints, run.reference_points):
        k = int(np.argmin(np.abs(trajectory[:, 0] - t)))
        assert abs(trajectory[k, 0] - t) < 1e-9
        assert np.allclose(ring[:4], driven.footprint(trajectory[k, 1:]), atol=1e-4)  # float32 in the file
        assert np.allclose(point, trajectory[k, 1:3], atol=1e-4)
    first = shapely.Polygon(run.footprints[0])
    assert first.bounds == pytest.approx((-0.929 - EXTRA_M / 2, -0.971, 3.76 + EXTRA_M / 2, 0.971), abs=1e-4)


class StraightAfterOneFailure:
    """Fails its first call, then drives 2 m ahead and 1 m back from wherever it is asked."""

    name, convention = "straight", "reference_point"

    def __init__(self):
        self.calls = 0

    def plan(self, scene, start):
        self.calls += 1
        if self.calls == 1:
            return Plan(start=np.asarray(start, float), reason="first call fails")
        return plan_from_arcs([[0.0, 2.0], [0.0, -1.0]], start=start)


def test_a_clip_runs_calls_read_back_with_what_each_detected(tmp_path):
    clip = next(c for c in load_clips("eval") if c.name == "eval-1000016")
    tracker = clip_tracker_config()
    tracker = dataclasses.replace(tracker, executor=dataclasses.replace(tracker.executor, max_time_s=9.0))
    path = tmp_path / "clip.rrd"
    result = run_clip(clip, StraightAfterOneFailure(), config=ClipRunConfig(tracker=tracker), rerun_path=path)
    run = read_run(path)
    assert run.clip == clip.name and run.name == "clip"
    assert len(result.calls) >= 3  # the failure, the first plan and replans from the end of each plan
    assert [(c.time_s, c.frame, c.success, c.rejected) for c in run.calls] == [
        (pytest.approx(c.time_s, abs=1e-9), c.frame, c.success, c.rejected) for c in result.calls]
    assert not run.calls[0].usable and run.calls[1].usable
    assert run.plans[0].time_s == pytest.approx(0.5) and run.call_of(run.plans[0]) is run.calls[1]
    assert len(run.plans) == sum(c.usable for c in result.calls) == result.record.plans_used
    for call in run.calls:
        assert len(call.detections) == len(call.labels) == 10
        for ring, label in zip(call.detections, call.labels):
            kind, object_id = label.split()
            truth = clip.objects[int(object_id)]
            assert truth.kind == kind
            outline = shapely.Polygon(truth.polygon(call.frame))
            assert shapely.Polygon(ring).centroid.distance(outline.centroid) < 0.3  # a detection of that object


def test_a_recording_of_the_old_format_or_no_recording_is_a_clear_error(tmp_path):
    old = tmp_path / "old.rrd"
    rec = rr.RecordingStream("neuralparker_tracking")
    rec.save(str(old))
    rec.set_time("sim_time", duration=0.0)
    rec.log("world/plan", rr.LineStrips2D([np.zeros((2, 2))]))  # a plan without its headings and gears
    rec.flush()
    rec.disconnect()
    with pytest.raises(ValueError, match="drive the run again"):
        read_run(old)
    with pytest.raises(FileNotFoundError, match="expected a closed-loop .rrd"):
        read_run(tmp_path / "missing.rrd")
