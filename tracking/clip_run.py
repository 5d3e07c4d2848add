"""One site clip in closed loop (spec §8 "Closed loop on a clip"; paper §V-F, App. C, Table ``tab:realworld``).

The MuJoCo world is the clip's ground truth: the site boundary as walls, the static objects extruded, the movers
(pedestrians, pushed carts) as mocap bodies following their recorded poses (`tracking.movers`). The vehicle starts
at rest at the clip's start pose with the planner's plan from frame 0. Every ``replan_period_s`` (one clip frame,
0.1 s) of sim time the vehicle takes that frame's detections (`Clip.frame_scene(frame, pose=pose)`: the ten
detections nearest to the vehicle, held over missed frames; frame = ⌊t / 0.1 s⌉ clamped to the clip's last frame)
and, by ``ClipRunConfig.replan``:

* ``"on_invalid"`` (default): the planner replans from the simulated reference-point pose when the rest of the
  followed plan is no longer valid in this frame's scene (under the planner's own collision convention) or the
  vehicle is more than ``deviation_m`` off it or stands at its end outside the parking tolerance (the executor
  then holds the vehicle for up to ``ExecutorConfig.hold_max_s``); the tracker follows the newest successful plan.
  With ``ClipRunConfig.stitch`` a moving vehicle that is on its plan replans from the pose of that plan it can
  still stop at and drives the plan up to there first (`tracking.stitching`);
* ``"every_frame"``: the planner replans at every frame and the tracker always switches to the newest plan. With
  a search planner this never settles (successive plans from a moving vehicle pick different manoeuvres: Hybrid
  A* on eval-1000001 switched plans 529 times and timed out after 60 s), hence the default.

A successful plan the tracker cannot follow (`tracking.executor.plan_problem`: a steering curvature beyond κ_max)
counts as a failed call and is not followed, and so does a planner that raises on a start it considers in
collision. After a failed call the planner is called again no sooner than ``retry_period_s`` (0.5 s) later (a
failing rollout or search is the slowest call there is). When the very first call fails, the vehicle waits at
rest at its start and retries every ``retry_period_s`` with the frame of that time until a plan succeeds (then the
drive starts at that sim time) or ``first_plan_wait_s`` passes (``plan_failed``); a mover touching the waiting
vehicle is a contact (checked against the movers' interpolated outlines at the control rate). Once the vehicle
stands within the parking tolerance of the target it stops replanning (a parked vehicle does not start a new
manoeuvre). Obstacles, movers and walls are detection only (`WorldConfig.solid_obstacles=False`) and the run does
not stop at a touch, so one run gives both verdicts:

* **footprint success** — the executor's success: no chassis contact with any ground-truth object or wall during
  the run and parked within 0.3 m / 10° of the target;
* **reference-point success** — parked within the tolerance and the executed reference point never inside a
  ground-truth object at that instant (movers at their interpolated pose) nor outside the site boundary, checked
  at every control step (50 Hz) of the recorded trajectory.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import shapely

from np_sim.clips import Clip
from np_sim.collision import path_valid
from np_sim.errors import StartInCollisionError
from np_sim.frames import place
from np_sim.plan import Plan
from np_sim.planners import CONVENTIONS, Planner
from np_sim.scene import PolygonObstacle, Scene
from tracking.config import ExecutorConfig, TrackerConfig, WorldConfig
from tracking.executor import execute, parked, plan_problem
from tracking.movers import Mover, poses_at
from tracking.observer import Observers, RunObserver, TrajectoryRecorder
from tracking.perception import perceived_scene, tracked_detections
from tracking.record import Contact, ExecutionRecord
from tracking.stitching import StitchedPlan, stitch_distance
from tracking.validators import validate_plan
from tracking.world import World, build_world


def clip_tracker_config() -> TrackerConfig:
    """The tracker of the clip runs: detection-only obstacles, no stop at a contact, 60 s of sim time at most."""
    return dataclasses.replace(TrackerConfig(), world=WorldConfig(solid_obstacles=False),
                               executor=ExecutorConfig(stop_on_contact=False, max_time_s=60.0))


REPLAN_MODES = ("on_invalid", "every_frame")
"""When a clip run calls the planner (module docstring)."""


@dataclass(frozen=True)
class ClipRunConfig:
    """Settings of a clip run."""

    tracker: TrackerConfig = field(default_factory=clip_tracker_config)
    """Tracker, world and executor settings (default `clip_tracker_config`)."""
    replan: str = "on_invalid"
    """``"on_invalid"`` or ``"every_frame"`` (module docstring)."""
    deviation_m: float = 0.5
    """``on_invalid``: replan when the reference point is farther than this from the followed plan (m)."""
    check_ds_m: float = 0.1
    """Spacing of the followed plan's samples checked against each frame (m)."""
    retry_period_s: float = 0.5
    """Least sim time between a failed planner call and the next call (s)."""
    first_plan_wait_s: float = 5.0
    """How long a vehicle whose first plan failed waits at its start, retrying every ``retry_period_s`` (s)."""
    track_window: int = 1
    """Frames the planner's detections are filtered over (`tracking.perception.tracked_detections`); 1 = each
    frame's raw detections, as the paper's vehicle used them."""
    stitch: bool = False
    """``on_invalid``: a replan of a moving vehicle that is on its followed plan starts from the pose of that plan
    it can still stop at (`tracking.stitching`) and the vehicle drives the followed plan up to there, when that
    stretch is still free in the frame's scene; False = every replan starts from the simulated pose."""
    stitch_margin_m: float = 0.2
    """Distance added to the braking distance and one replanning period of driving to place the stitch (m)."""

    def __post_init__(self) -> None:
        if self.replan not in REPLAN_MODES:
            raise ValueError(f"ClipRunConfig.replan: expected one of {REPLAN_MODES}, got {self.replan!r}")
        if not 0.0 <= self.first_plan_wait_s < self.tracker.executor.max_time_s:
            raise ValueError(f"ClipRunConfig.first_plan_wait_s: expected 0 <= wait < max_time_s "
                             f"({self.tracker.executor.max_time_s}), got {self.first_plan_wait_s!r}")
        if self.track_window < 1:
            raise ValueError(f"ClipRunConfig.track_window: expected >= 1 frame, got {self.track_window!r}")
        if not (self.deviation_m > 0 and self.check_ds_m > 0 and self.stitch_margin_m >= 0):
            raise ValueError(f"ClipRunConfig: deviation_m and check_ds_m must be > 0 and stitch_margin_m >= 0, got "
                             f"{self.deviation_m!r}, {self.check_ds_m!r}, {self.stitch_margin_m!r}")


class _FollowedPath:
    """The followed plan's samples and the vehicle's progress along them (nearest sample, searched forward)."""

    WINDOW = 40
    """Samples searched ahead of the last progress index (4 m at 0.1 m: far more than 0.1 s of driving)."""

    def __init__(self, plan: Plan, ds_m: float):
        self.plan = plan
        self.rows = plan.sample(ds_m)
        self.poses = self.rows[:, :3]
        self.index = 0

    def advance(self, pose: np.ndarray) -> float:
        """Move the progress index to the nearest sample ahead; the distance to it (m)."""
        window = self.poses[self.index: self.index + self.WINDOW]
        d = np.hypot(window[:, 0] - pose[0], window[:, 1] - pose[1])
        k = int(np.argmin(d))
        self.index += k
        return float(d[k])

    def remaining(self) -> np.ndarray:
        """Poses from the progress index to the end."""
        return self.poses[self.index:]

    @property
    def at_end(self) -> bool:
        """The progress index is at the last sample or the one before (the executor ends a segment 0.05 m short)."""
        return self.index >= len(self.poses) - 2


@dataclass(frozen=True)
class ClipWorld:
    """A clip's ground truth as the executor's inputs."""

    scene: Scene
    """Site boundary, the static objects (scene obstacle i = object ``static_ids[i]``) and the clip target."""
    static_ids: tuple[int, ...]
    """Object id of each static scene obstacle."""
    movers: tuple[Mover, ...]
    """The moving objects, named ``mover_<object id>``."""


def clip_world(clip: Clip) -> ClipWorld:
    """Static ground-truth scene and movers of ``clip``."""
    static = [obj for obj in clip.objects if not obj.moving]
    scene = clip.site.scene(clip.target, [PolygonObstacle(obj.polygon(0)) for obj in static],
                            name=f"{clip.name}/ground_truth", tags={"clip": clip.name, "source": "ground_truth"})
    movers = tuple(Mover(f"mover_{obj.id}", obj.outline, obj.poses, clip.frame_dt_s)
                   for obj in clip.objects if obj.moving)
    return ClipWorld(scene=scene, static_ids=tuple(obj.id for obj in static), movers=movers)


def clip_mujoco_world(clip: Clip, tracker: TrackerConfig, ground: ClipWorld | None = None) -> World:
    """The MuJoCo world of ``clip``'s ground truth (``ground``, default `clip_world`) with the vehicle of
    ``tracker`` at rest at the clip's start."""
    ground = clip_world(clip) if ground is None else ground
    return build_world(ground.scene, np.asarray(clip.start, float), tracker, ground.movers)


def object_of_geom(clip: Clip, world: ClipWorld, geom: str) -> str:
    """'<kind> <id>' of the clip object a touchable geom belongs to, 'boundary' for a wall."""
    if geom.startswith("wall_"):
        return "boundary"
    index = int(geom.split("_")[1])
    object_id = index if geom.startswith("mover_") else world.static_ids[index]
    return f"{clip.objects[object_id].kind} {object_id}"


def reference_point_violation(clip: Clip, world: ClipWorld, trajectory: np.ndarray) -> str:
    """'' when every executed reference point (rows t, x, y, θ) is inside the site boundary and outside every
    ground-truth object at its time; otherwise what the first violation was."""
    t, x, y = trajectory[:, 0], trajectory[:, 1], trajectory[:, 2]
    bad = np.zeros(len(t), bool)
    what = np.full(len(t), "", dtype=object)
    outside = ~shapely.contains_xy(shapely.Polygon(world.scene.boundary), x, y)
    bad |= outside
    what[outside] = "outside the site boundary"
    for index, obstacle in enumerate(world.scene.obstacles):
        inside = shapely.contains_xy(shapely.Polygon(obstacle.vertices), x, y) & ~bad
        bad |= inside
        what[inside] = f"inside {object_of_geom(clip, world, f'obstacle_{index}')}"
    for mover in world.movers:
        pose = poses_at(mover.poses, mover.frame_dt_s, t)
        c, s = np.cos(pose[:, 2]), np.sin(pose[:, 2])
        dx, dy = x - pose[:, 0], y - pose[:, 1]  # into the object frame: R(−yaw)·(p − position)
        inside = shapely.contains_xy(shapely.Polygon(mover.outline), c * dx + s * dy, -s * dx + c * dy) & ~bad
        bad |= inside
        what[inside] = f"inside {object_of_geom(clip, world, mover.name)}"
    if not bad.any():
        return ""
    first = int(np.argmax(bad))
    return f"reference point {what[first]} at t = {t[first]:.2f} s"


@dataclass
class PlanCall:
    """One planner call of a clip run."""

    time_s: float
    """Sim time of the call (s)."""
    frame: int
    """Clip frame whose detections were used."""
    success: bool
    """The planner returned a successful plan."""
    plan_time_s: float
    """The plan's own planning time (s)."""
    rejected: str = ""
    """'' or why the tracker refused the successful plan (`tracking.executor.plan_problem`, e.g. 'steering_limit')."""
    stage: str = ""
    """The stage of a staged-effort planner that gave the plan (`np_sim.plan.Plan.stage`), '' for others."""

    @property
    def usable(self) -> bool:
        """A successful plan the tracker can follow."""
        return self.success and not self.rejected


@dataclass
class ClipRun:
    """Outcome of one clip × planner closed-loop run."""

    record: ExecutionRecord
    """The executor's record (footprint success = ``record.success``)."""
    first_plan: Plan
    """The plan from the clip start at frame 0."""
    calls: list[PlanCall] = field(default_factory=list)
    """Every planner call, the first one included."""
    trajectory: np.ndarray = field(default_factory=lambda: np.zeros((0, 4)))
    """(n, 4) executed t, x, y, θ at every control step."""
    parked: bool = False
    """The run ended (not a timeout or a plan failure) with the vehicle within the parking tolerance."""
    reference_point_detail: str = ""
    """'' or the first reference-point violation (`reference_point_violation`)."""
    first_plan_valid: dict[str, bool] = field(default_factory=dict)
    """The planned-path validators (`tracking.validators.VALIDATOR_NAMES`: sampled and exact) on the first plan
    against the frame-0 ground truth (movers included)."""

    @property
    def footprint_success(self) -> bool:
        """No body contact during the run and parked."""
        return bool(self.record.success)

    @property
    def reference_point_success(self) -> bool:
        """Parked and the executed reference point never inside a ground-truth object or outside the boundary."""
        return self.parked and not self.reference_point_detail


def _waiting_contacts(ground: ClipWorld, start: np.ndarray, times: np.ndarray, vehicle) -> list[Contact]:
    """Movers touching the vehicle standing at ``start`` at ``times`` (the first touch of each mover)."""
    body = shapely.Polygon(vehicle.footprint(start))
    touches = []
    for mover in ground.movers:
        poses = poses_at(mover.poses, mover.frame_dt_s, times)
        outlines = shapely.polygons(place(mover.outline, poses))
        hit = np.flatnonzero(shapely.intersects(outlines, body))
        if len(hit):
            k = int(hit[0])
            touches.append(Contact(time_s=float(times[k]), geom=mover.name, position=tuple(map(float, poses[k, :2]))))
    return sorted(touches, key=lambda c: c.time_s)


class ReplanningLoop:
    """The planner side of a clip run (spec §8 "Closed loop on a clip"; module docstring): the first plan and its
    retries at the start (`first_plan`), the replan decision at each frame (`replan`, the executor's ``replan``
    hook) and stitching (`stitched`).

    State: ``calls`` (every planner call), ``followed`` (the plan the tracker follows and the vehicle's progress
    along it, None before the first usable plan), ``retry_at_s`` (no planner call before this sim time: set after a
    failed call) and ``previous_pose`` (the pose of the last replan decision, telling a standing vehicle).
    ``log``: None or the run's `tracking.clip_log.ClipRerunObserver`, given every call and its detections.
    ``disturbance``: None or a `tracking.disturbance.Disturbance`, whose perception factors perturb each frame's
    detections; ``hooks``: None or its `tracking.disturbance.RunHooks` of this run, whose localisation error is
    added to the pose the planner gets (the standing test keeps the true displacement: wheel odometry)."""

    def __init__(self, clip: Clip, planner, config: ClipRunConfig, log=None, disturbance=None, hooks=None):
        self.clip, self.planner, self.config, self.log = clip, planner, config, log
        self.tracker = config.tracker
        self.hooks = hooks
        self.disturbance = disturbance if disturbance is not None and disturbance.group == "perception" else None
        if not isinstance(planner, Planner):
            raise TypeError(f"run_clip: expected a planner (np_sim.planners.Planner: plan, convention and name), got "
                            f"{type(planner).__name__}")
        if planner.convention not in CONVENTIONS:
            raise ValueError(f"run_clip: {type(planner).__name__}.convention: expected one of {CONVENTIONS}, got "
                             f"{planner.convention!r}")
        self.convention = planner.convention
        self.calls: list[PlanCall] = []
        self.followed: _FollowedPath | None = None
        self.retry_at_s = 0.0
        self.previous_pose = np.asarray(clip.start, float)

    @property
    def last_usable(self) -> bool:
        """The latest planner call gave a plan the tracker follows."""
        return self.calls[-1].usable

    def frame_scene(self, t: float, pose: np.ndarray) -> tuple[int, Scene]:
        """The clip frame of sim time ``t`` (⌊t / frame period⌉, clamped to the last frame) and its detections
        around ``pose``."""
        frame = min(int(round(t / self.clip.frame_dt_s)), self.clip.n_frames - 1)
        if self.disturbance is None:
            return frame, perceived_scene(self.clip, frame, pose=pose, track_window=self.config.track_window)
        return frame, self.clip.frame_scene(frame, pose=pose, detections=self.detections(frame))

    def detections(self, frame: int) -> tuple[np.ndarray, np.ndarray]:
        """Object ids (n,) and polygons (n, 5, 2) the perception reports at ``frame``, before the nearest ten are
        kept: the held (or, with ``track_window`` > 1, tracked) detections, perturbed by a perception disturbance."""
        held = self.clip.detection_frame(frame)
        window = self.config.track_window
        ids, polygons = self.clip.detections(held) if window == 1 else tracked_detections(self.clip, frame, window)
        if self.disturbance is None:
            return ids, polygons
        target = shapely.Polygon(self.tracker.vehicle.footprint(self.clip.target))
        # seeded by the frame whose detections are held: a held detection keeps its perturbation
        return self.disturbance.perceive(self.clip.name, held, ids, polygons, keep_clear=target)

    def detection_labels(self, frame: int, scene: Scene) -> list[str]:
        """'<kind> <id>' of the object each obstacle of ``scene`` (planned in at ``frame``) is a detection of: the
        detection of `detections` whose vertices it has (a scene obstacle drops repeated vertices)."""
        ids, polygons = self.detections(frame)
        labels = []
        for obstacle in scene.obstacles:
            gaps = np.linalg.norm(obstacle.vertices[None, :, None] - polygons[:, None], axis=-1).min(2).max(1)
            k = int(np.argmin(gaps))
            if gaps[k] > 1e-9:
                raise RuntimeError(f"clip {self.clip.name} frame {frame}: an obstacle of the planner's scene is none "
                                   f"of the frame's detections (nearest {gaps[k]:.3g} m off)")
            labels.append(f"{self.clip.objects[int(ids[k])].kind} {int(ids[k])}")
        return labels

    def sensed(self, pose: np.ndarray, t: float) -> np.ndarray:
        """The pose the vehicle believes it has at sim time ``t`` (``pose`` without a localisation error)."""
        return pose if self.hooks is None else self.hooks.sensed(pose, t)

    def call(self, pose: np.ndarray, t: float, frame: int, scene: Scene, prefix: tuple | None = None) -> Plan:
        """Call the planner from ``pose``; a usable plan becomes the followed one, after the stretch ``prefix`` =
        (followed path, s_from, s_to) of the followed plan when given (a `StitchedPlan`)."""
        try:
            plan = self.planner.plan(scene, pose)
        except StartInCollisionError as error:
            plan = Plan(start=np.asarray(pose, float), reason=f"refused: {error}")
        rejected = plan_problem(plan, self.tracker)[0] if plan.success else ""
        self.calls.append(PlanCall(time_s=t, frame=frame, success=bool(plan.success), plan_time_s=plan.plan_time_s,
                                   rejected=rejected, stage=plan.stage))
        if not self.last_usable:
            self.retry_at_s = t + self.config.retry_period_s
        if self.log is not None:
            self.log.log_call(self.calls[-1], scene, self.detection_labels(frame, scene))
        if self.last_usable:
            if prefix is not None:
                plan = StitchedPlan.join(prefix[0].plan, prefix[1], prefix[2], plan)
            self.followed = _FollowedPath(plan, self.config.check_ds_m)
        return plan

    def first_plan(self) -> tuple[Plan, Plan, float]:
        """(plan of the call at t = 0, plan to drive, sim time it was planned at): the vehicle waits at its start,
        calling again every ``retry_period_s`` until a plan is usable or ``first_plan_wait_s`` has passed."""
        start = np.asarray(self.clip.start, float)
        believed = self.sensed(start, 0.0)
        first = self.call(believed, 0.0, *self.frame_scene(0.0, believed))
        driven, t0 = first, 0.0
        while not self.last_usable and t0 + self.config.retry_period_s <= self.config.first_plan_wait_s + 1e-9:
            t0 += self.config.retry_period_s
            believed = self.sensed(start, t0)
            driven = self.call(believed, t0, *self.frame_scene(t0, believed))
        return first, driven, t0

    def replan(self, pose: np.ndarray, t: float) -> Plan | None:
        """The executor's replanning hook: a new plan from ``pose`` at sim time ``t``, or None when the vehicle is
        parked, a failed call was too recent or (``on_invalid``) the followed plan still holds."""
        moved = math.hypot(pose[0] - self.previous_pose[0], pose[1] - self.previous_pose[1])
        period_s = self.tracker.executor.replan_period_s
        standing = moved < self.tracker.executor.rest_speed_mps * period_s
        self.previous_pose = np.array(pose, float)
        pose = self.sensed(pose, t)
        if parked(pose, self.clip.target, self.tracker.executor):
            return None  # a parked vehicle starts no new manoeuvre
        if t < self.retry_at_s - 1e-9:
            return None
        frame, scene = self.frame_scene(t, pose)
        path = self.followed
        if self.config.replan == "on_invalid" and path is not None:
            off = path.advance(pose)
            if (off <= self.config.deviation_m and not (standing and path.at_end)
                    and path_valid(scene, path.remaining(), self.convention, self.tracker.vehicle)):
                return None  # the followed plan still holds (standing at its end short of the target: it does not)
            if self.config.stitch and not standing and off <= self.config.deviation_m:
                plan = self.stitched(path, moved / period_s, t, frame, scene)
                if plan is not None:
                    return plan
        return self.call(pose, t, frame, scene)

    def stitched(self, path: _FollowedPath, speed_mps: float, t: float, frame: int, scene: Scene) -> Plan | None:
        """A replan from the followed plan's pose the vehicle can still stop at (`tracking.stitching`), or None
        when that pose is past the plan's end or the stretch up to it is no longer free in ``scene``."""
        s_now = float(path.rows[path.index, 5])
        ahead = stitch_distance(speed_mps, self.tracker.profile.accel_mps2, self.tracker.executor.replan_period_s,
                                self.config.stitch_margin_m)
        k = int(np.searchsorted(path.rows[:, 5], s_now + ahead))
        ahead_poses = path.poses[path.index:k + 1]
        if k >= len(path.rows) - 1 or not path_valid(scene, ahead_poses, self.convention, self.tracker.vehicle):
            return None
        # planned in the frame's scene around the vehicle, the one the next frames check the plan against
        return self.call(path.poses[k].copy(), t, frame, scene, prefix=(path, s_now, float(path.rows[k, 5])))


def run_clip(clip: Clip, planner, controller: str = "lqr", *, config: ClipRunConfig | None = None,
             rerun_path: str | Path | None = None, render: bool = False, world: World | None = None,
             disturbance=None) -> ClipRun:
    """Drive ``clip`` in closed loop with ``planner`` replanning once per frame (module docstring).

    Parameters
    ----------
    clip
        A site clip (`np_sim.clips.load_clips`).
    planner
        A `np_sim.planners.Planner` (NeuralParker, NP-Guided A*, Hybrid A*); replans are checked under its
        ``convention``. A `np_sim.errors.StartInCollisionError` it raises counts as a failed call, any other error
        propagates.
    controller
        Lateral controller of the tracker.
    config
        Replanning and tracker settings; default `ClipRunConfig()` (replan on an invalid plan, detection-only
        obstacles, no stop at a contact).
    rerun_path, render
        Write the run to this ``.rrd`` (`tracking.clip_log.ClipRerunObserver`), with off-screen frames if
        ``render``.
    world
        The clip's MuJoCo world from `clip_mujoco_world` with ``config.tracker``, to reuse across runs of the clip
        (each run resets it to the start); default: built here.
    disturbance
        None or a `tracking.disturbance.Disturbance`: its perception, localisation and actuation factors act
        here, seeded by the clip's name; its physical factors act through ``config.tracker``, which the caller
        gives as ``disturbance.tracker(...)`` (`experiments.closed_loop.clip_rows` does).
    """
    config = ClipRunConfig() if config is None else config
    tracker = config.tracker
    hooks = None if disturbance is None else disturbance.hooks(clip.name, tracker)
    loop = ReplanningLoop(clip, planner, config, disturbance=disturbance, hooks=hooks)
    ground = clip_world(clip)
    start = np.asarray(clip.start, float)
    world = clip_mujoco_world(clip, tracker, ground) if world is None else world
    if world.config != tracker or world.scene.name != ground.scene.name:
        raise ValueError(f"run_clip: the world passed was built for {world.scene.name} with another tracker "
                         f"config, not for {ground.scene.name} with config.tracker")
    recorder = TrajectoryRecorder()
    parts: list[RunObserver] = [recorder]
    if rerun_path is not None:
        from tracking.clip_log import ClipRerunObserver

        loop.log = ClipRerunObserver(world, tracker, Path(rerun_path), render, clip_name=clip.name)
        parts.append(loop.log)
    first, driven, t0 = loop.first_plan()
    if t0 > 0.0:
        recorder.start_time_s = t0
    record = execute(ground.scene, driven, controller, replan=loop.replan, config=tracker,
                     observer=Observers(parts), world=world, start_time_s=t0 if loop.last_usable else 0.0,
                     hooks=hooks, vehicle_start=None if hooks is None else start)
    waiting = np.arange(0.0, t0, tracker.executor.control_dt_s) if loop.last_usable else np.zeros(0)
    record = _with_waiting_contacts(record, ground, start, waiting, tracker.plant.body(tracker.vehicle))
    if loop.log is not None and record.reason in ("plan_failed", "empty_plan", "steering_limit",
                                                  "start_in_collision"):
        loop.log.finish_unrun(record)  # the executor returned before the loop started: no hooks were called
    trajectory = recorder.array() if recorder.rows else np.array([[0.0, *start]])
    if len(waiting):
        trajectory = np.vstack([np.column_stack([waiting, np.tile(start, (len(waiting), 1))]), trajectory])
    stands_parked = record.reason in ("", "contact") and parked(record.final_pose, clip.target, tracker.executor)
    return ClipRun(record=record, first_plan=first, calls=loop.calls, trajectory=trajectory,
                   parked=stands_parked,
                   reference_point_detail=reference_point_violation(clip, ground, trajectory) if stands_parked else "",
                   first_plan_valid=validate_plan(clip.frame_scene(0, ground_truth=True), first))


def _with_waiting_contacts(record: ExecutionRecord, ground: ClipWorld, start: np.ndarray, waiting: np.ndarray,
                           vehicle) -> ExecutionRecord:
    """``record`` with the movers' touches of the vehicle waiting at ``start`` at the times ``waiting`` before
    its drive began (a failed contact-free run when there are any)."""
    touches = _waiting_contacts(ground, start, waiting, vehicle) if len(waiting) else []
    if not touches:
        return record
    return dataclasses.replace(
        record, success=False, contacts=touches + list(record.contacts), reason="contact",
        detail=f"chassis touched {touches[0].geom} at t = {touches[0].time_s:.2f} s (waiting at the start)")
