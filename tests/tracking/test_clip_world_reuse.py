"""tracking.clip_run: one compiled MuJoCo world serves every run of a clip; a run on a world an earlier run left
behind drives exactly like a run on a freshly built one."""

import numpy as np
import pytest

from np_sim.clips import load_clips
from np_sim.plan import Plan
from np_sim.planners import HybridAStar
from tracking.clip_run import ClipRunConfig, clip_mujoco_world, run_clip

TIMING = ("wall_time_s", "realtime_factor")
"""Record columns measured on the wall clock."""


class Replay:
    """The plan given for a call from its start, a failed call from anywhere else (no time budget involved)."""

    name, convention = "replay", "footprint"

    def __init__(self, plan: Plan):
        self.fixed = plan

    def plan(self, scene, start):
        if np.array_equal(np.asarray(start, float), self.fixed.start):
            return self.fixed
        return Plan(start=np.asarray(start, float), reason="replay: no plan from here")


@pytest.fixture(scope="module")
def clips():
    return {c.name: c for c in load_clips("eval")}


def _row(run) -> dict:
    row = {k: v for k, v in run.record.to_row().items() if k not in TIMING}
    return row | {"parked": run.parked, "detail_rp": run.reference_point_detail, "calls": len(run.calls)}


def test_a_reused_world_drives_like_a_fresh_one(clips):
    clip = clips["eval-1000016"]
    plan = HybridAStar(convention="footprint").plan(clip.frame_scene(0, pose=clip.start), clip.start)
    assert plan.success, plan.reason
    fresh = run_clip(clip, Replay(plan))
    world = clip_mujoco_world(clip, ClipRunConfig().tracker)
    run_clip(clip, Replay(plan), world=world)  # leaves the world at the end of a drive
    reused = run_clip(clip, Replay(plan), world=world)
    assert fresh.record.sim_time_s > 1.0
    assert _row(reused) == _row(fresh)
    assert np.array_equal(reused.trajectory, fresh.trajectory)


def test_a_world_of_another_clip_is_refused(clips):
    clip, other = clips["eval-1000016"], clips["eval-1000009"]
    world = clip_mujoco_world(other, ClipRunConfig().tracker)
    with pytest.raises(ValueError, match="eval-1000009.*eval-1000016"):
        run_clip(clip, Replay(Plan(start=np.asarray(clip.start, float))), world=world)
