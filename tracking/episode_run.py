"""One frozen-start episode under a disturbance (beyond the paper; `experiments.robustness` with ``--benchmark``
or ``--scenes``): the planner plans once from what the vehicle perceives, the MuJoCo vehicle drives the plan in
the true scene.

Where each factor of `tracking.disturbance` acts in an episode:

* perception (``detection_noise``, ``detection_drop``): the planner gets the scene with its obstacles shifted or
  dropped once (`Disturbance.perceive_scene`); an obstacle that the shift would push into the target's or the
  start's footprint keeps its place (a detector does not report an object inside the ego body, and a scene keeps
  its target free). MuJoCo and the validators keep the true obstacles;
* localisation (``pose_noise``): the planner plans from the sensed start (truth plus the error at t = 0), the
  vehicle starts at the truth, and the controller follows the plan from the sensed pose throughout;
* control and vehicle: as in the clip runs (`RunHooks.actuate`, `Disturbance.tracker`).

The undisturbed episode (``disturbance`` None) is exactly `experiments.track`'s: the same plan, validation and
`tracking.executor.execute` call.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import shapely

from np_sim.errors import StartInCollisionError
from np_sim.plan import Plan
from np_sim.scene import Scene
from tracking.config import TrackerConfig
from tracking.executor import execute
from tracking.record import ExecutionRecord
from tracking.validators import validate_plan


@dataclass(frozen=True)
class EpisodeRun:
    """What one episode gave: the plan (made on the perceived scene from the sensed start), its validity in the
    true scene, the execution record and the perceived scene."""

    plan: Plan
    valid: dict[str, bool]
    record: ExecutionRecord
    perceived: Scene


def run_episode(scene: Scene, start: np.ndarray, planner, controller: str, tracker: TrackerConfig,
                disturbance=None, run_key: str = "", rerun_path: str | Path | None = None) -> EpisodeRun:
    """Plan ``scene`` from ``start`` with ``planner`` and drive the plan with ``controller`` on the MuJoCo vehicle
    of ``tracker``, under ``disturbance`` (None, or a `tracking.disturbance.Disturbance` whose draws are seeded by
    ``run_key``; module docstring). ``rerun_path``: write the drive to this ``.rrd``."""
    start = np.asarray(start, float)
    if disturbance is None:
        perceived, hooks, config, sensed_start = scene, None, tracker, start
    else:
        config = disturbance.tracker(tracker)
        vehicle = tracker.vehicle
        keep_clear = shapely.union(shapely.Polygon(vehicle.footprint(scene.target)),
                                   shapely.Polygon(vehicle.footprint(start)))
        perceived = disturbance.perceive_scene(run_key, scene, keep_clear=keep_clear)
        hooks = disturbance.hooks(run_key, config)
        sensed_start = start if hooks is None else hooks.sensed(start, 0.0)
    try:
        plan = planner.plan(perceived, sensed_start)
    except StartInCollisionError as error:
        plan = Plan(start=sensed_start, reason=f"refused: {error}")
    valid = validate_plan(scene, plan, tracker.vehicle)
    record = execute(scene, plan, controller=controller, rerun_path=rerun_path, config=config, hooks=hooks,
                     vehicle_start=None if hooks is None else start)
    return EpisodeRun(plan=plan, valid=valid, record=record, perceived=perceived)


def episode_columns(run: EpisodeRun) -> dict:
    """The record columns of ``run``: its plan (success, reason, time, length, reversals, validity in the true
    scene), then the execution record's; ``footprint_success`` is the executed success (no body contact, parked
    within tolerance)."""
    plan = run.plan
    L, rev, _ = plan.metrics() if plan.success else (float("nan"), -1, float("nan"))
    return {"footprint_success": int(run.record.success), "plan_success": int(plan.success),
            "plan_reason": plan.reason, "plan_time_ms": 1e3 * plan.plan_time_s, "L": L, "plan_reversals": rev,
            "ref_point_valid": int(run.valid["reference_point"]), "footprint_valid": int(run.valid["footprint"]),
            "exact_footprint_valid": int(run.valid["exact_footprint"]),
            "obstacles_perceived": len(run.perceived.obstacles), **run.record.to_row()}


__all__ = ["EpisodeRun", "episode_columns", "run_episode"]
