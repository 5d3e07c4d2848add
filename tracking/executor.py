"""The closed-loop executor (spec §8, §10): a plan, or a planner replanning at a fixed rate, driven on the MuJoCo
vehicle by a path-tracking controller until parked, body contact or timeout.

```python
record = execute(scene, plan, controller="lqr", render=False, rerun_path=None)
record = execute(scene, first_plan, replan=lambda pose, t: planner.plan(scene_at(t), pose))  # replanning mode
```

Each control step (``ExecutorConfig.control_dt_s``): read the reference-point pose and signed speed; project onto
the current gear segment; at a segment start, wait at rest until the steering reaches the segment's initial
feed-forward angle; otherwise steer with the lateral controller (through the angle and rate limits) and drive the
profile speed (at least the creep speed until the segment end) with the PI speed loop; a segment ends when the
path left is under the tolerance and the vehicle is at rest. Then ``mj_step`` runs the physics substeps and the
chassis contacts are read. A run ends when the last segment ends (success if no contact and the final pose is
within the parking tolerance of the scene target), at the first contact (``stop_on_contact``) or at the timeout.
In replanning mode a vehicle that ends its plan outside the parking tolerance stands (brakes, holds its steering)
and keeps calling the replanner for up to ``hold_max_s``; a new plan starts a corrective manoeuvre.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from pathlib import Path

import mujoco
import numpy as np

from np_sim.collision import path_valid
from np_sim.plan import Plan
from np_sim.scene import Scene
from tracking.config import ExecutorConfig, TrackerConfig
from tracking.controllers import SpeedController, SteeringLimiter, make_lateral
from tracking.controllers.base import TrackingState
from tracking.errors import TrackingError
from tracking.mjcf import max_steer_rad
from tracking.observer import Observers, RunObserver
from tracking.projection import project
from tracking.record import Contact, ExecutionRecord
from tracking.reference import Segment, reference_segments
from tracking.world import World, build_world

Replanner = Callable[[np.ndarray, float], "Plan | None"]
"""``replan(pose, t) -> Plan | None``: a new plan from the vehicle's reference-point pose at sim time t, or None when
no new plan is needed (not counted as a failed replan)."""


def _check_plan(plan: Plan, segments: list[Segment], config: TrackerConfig) -> tuple[str, str]:
    """('', '') for a trackable plan, else (reason, detail): failed plan, no motion, curvature beyond κ_max."""
    if not plan.success:
        return "plan_failed", f"the planner failed: {plan.reason or 'no reason given'}"
    if not segments:
        return "empty_plan", "the plan has no motion (no arcs of nonzero length and no Hermite segment)"
    limit = config.vehicle.kappa_max * (1.0 + config.executor.curvature_tolerance)
    for k, seg in enumerate(segments):
        worst = int(np.argmax(np.abs(seg.steer_curvature)))
        if abs(seg.steer_curvature[worst]) > limit:
            return "steering_limit", (f"segment {k} steers |c| = {abs(seg.steer_curvature[worst]):.3f} 1/m at "
                                      f"s = {seg.s[worst]:.2f} m, beyond κ_max = {config.vehicle.kappa_max} 1/m")
    return "", ""


class _Loop:
    """State of one closed-loop run (kept in one object so the step stays a flat sequence of cheap calls)."""

    def __init__(self, world: World, controller: str, config: TrackerConfig, observer: RunObserver, hooks=None):
        ec, mc = config.executor, config.model
        self.world, self.config, self.observer = world, config, observer
        self.hooks = hooks
        self.lateral = make_lateral(controller, config)
        self.dt = ec.control_dt_s
        self.substeps = max(1, round(ec.control_dt_s / mc.timestep_s))
        self.steering = SteeringLimiter(config.vehicle.wheelbase_m, max_steer_rad(config.vehicle, mc),
                                        mc.steer_rate_max_rps, self.dt)
        self.speed_ctl = SpeedController(config.longitudinal, mc.wheel_radius_m, self.dt)
        self.t = 0.0
        self.segments: list[Segment] = []
        self.k = 0
        self.hint = 0
        self.aligning = True
        self.holding = False
        self.lateral_sq, self.heading_sq, self.lateral_max, self.n_err = 0.0, 0.0, 0.0, 0
        self.length, self.reversals, self.direction = 0.0, 0, 0
        self.contacts: list[Contact] = []
        self.touching: set[str] = set()
        self.plans_used, self.replans_failed = 1, 0

    def follow(self, segments: list[Segment], moving: bool) -> None:
        """Track ``segments`` from their start; without motion, align the steering first."""
        self.segments, self.k, self.hint, self.aligning, self.holding = segments, 0, 0, not moving, False

    def adopt(self, new: Plan | None) -> bool:
        """Follow the replanner's ``new`` plan if the tracker can (its first segment starts at the current speed
        when its gear is the moving one); whether it was adopted. None is no request, not a failed replan."""
        world, ec = self.world, self.config.executor
        moving_gear = self.direction if abs(world.speed(world.pose()[2])) > ec.rest_speed_mps else 0
        new_segments = _segments(new, self.config) if new is not None and new.success else []
        if new_segments and not _check_plan(new, new_segments, self.config)[0]:
            speed = abs(world.speed(world.pose()[2])) if new_segments[0].gear == moving_gear else 0.0
            new_segments = _segments(new, self.config, speed)
            self.follow(new_segments, moving=speed > 0)
            self.plans_used += 1
            self.observer.on_plan(self.t, new, new_segments)
            return True
        if new is not None:
            self.replans_failed += 1
        return False

    def sensed_pose(self) -> np.ndarray:
        """The reference-point pose the vehicle believes it has now (the true one without a disturbance)."""
        truth = self.world.pose()
        return truth if self.hooks is None else self.hooks.sensed(truth, self.t)

    def hold(self) -> None:
        """Stand at the end of the finished plan (projected on its last segment) until `follow` is called."""
        self.k, self.holding = len(self.segments) - 1, True

    def step(self) -> bool:
        """One control step and its physics substeps; False once the last segment has ended."""
        world, ec, a_max = self.world, self.config.executor, self.config.profile.accel_mps2
        truth = world.pose()
        speed = world.speed(truth[2])
        pose = truth if self.hooks is None else self.hooks.sensed(truth, self.t)
        seg = self.segments[self.k]
        proj = project(seg, pose, self.hint)
        self.hint = proj.index
        steer_now = math.tan(world.steer_angle()) / self.config.vehicle.wheelbase_m
        state = TrackingState(pose=pose, speed_mps=speed, steer_curvature=steer_now, segment=seg, projection=proj)
        if self.holding:
            command, target, accel = self.steering(steer_now), 0.0, 0.0
        elif self.aligning:
            command = self.steering(seg.steer_feedforward[0])
            target, accel = 0.0, 0.0
            wanted = self.steering.target_angle(seg.steer_feedforward[0])
            if abs(wanted - world.steer_angle()) < ec.steer_settle_rad and abs(speed) < ec.rest_speed_mps:
                self.aligning = False
        else:
            command = self.steering(self.lateral.steer_curvature(state))
            if proj.remaining_m > ec.segment_end_tol_m:
                # profile speed, but at least the creep speed (itself capped by the stopping curve √(2·a·r))
                creep = min(self.config.profile.creep_speed_mps, math.sqrt(2.0 * a_max * proj.remaining_m))
                i = proj.index
                slope = (seg.speed[i + 1] - seg.speed[i]) / max(seg.s[i + 1] - seg.s[i], 1e-9)
                target, accel = seg.gear * max(proj.speed_ref, creep), seg.gear * proj.speed_ref * slope
            elif abs(speed) >= ec.rest_speed_mps:
                target, accel = 0.0, -a_max * math.copysign(1.0, speed)  # stop zone: brake at the profile's bound
            else:
                return self._next_segment()
            self.lateral_sq += proj.lateral_m ** 2
            self.heading_sq += proj.heading_rad ** 2
            self.lateral_max = max(self.lateral_max, abs(proj.lateral_m))
            self.n_err += 1
        torque = self.speed_ctl.wheel_torque(target, accel, speed, world.effective_mass(steer_now))
        world.apply(*((command, torque) if self.hooks is None else self.hooks.actuate(command, torque)))
        if world.movers:
            world.move_objects(self.t)
        mujoco.mj_step(world.model, world.data, nstep=self.substeps)
        self.t += self.substeps * world.model.opt.timestep
        self._account(truth, speed)
        self.observer.on_step(self.t, world, state, command, target)
        return True

    def _next_segment(self) -> bool:
        self.k += 1
        self.hint, self.aligning = 0, True
        return self.k < len(self.segments)

    def _account(self, pose_before: np.ndarray, speed_before: float) -> None:
        """Path length, direction reversals and new chassis contacts after a step."""
        q = self.world.data.qpos
        self.length += math.hypot(q[0] - pose_before[0], q[1] - pose_before[1])
        if abs(speed_before) > self.config.executor.rest_speed_mps:
            direction = 1 if speed_before > 0 else -1
            if self.direction and direction != self.direction:
                self.reversals += 1
            self.direction = direction
        touching = set()
        for geom, pos in self.world.body_contacts():
            touching.add(geom)
            if geom not in self.touching:
                self.contacts.append(Contact(time_s=self.t, geom=geom, position=(float(pos[0]), float(pos[1]))))
        self.touching = touching


def _segments(plan: Plan, config: TrackerConfig, start_speed_mps: float = 0.0) -> list[Segment]:
    rate = config.profile.steer_rate_share * config.model.steer_rate_max_rps
    return reference_segments(plan, config.executor.reference_ds_m, config.profile, rate, config.vehicle.wheelbase_m,
                              start_speed_mps)


def plan_problem(plan: Plan, config: TrackerConfig) -> tuple[str, str]:
    """('', '') when the tracker can follow ``plan``, else the (reason, detail) with which `execute` would refuse it.

    Reasons: 'plan_failed', 'empty_plan', 'steering_limit' (a sampled steering curvature beyond κ_max by more than
    ``ExecutorConfig.curvature_tolerance``; the connector's discrete check, paper eq:hermite-kappa with 100 samples,
    can miss a sharper peak between its samples).
    """
    segments = _segments(plan, config) if plan.success else []
    return _check_plan(plan, segments, config)


def execute(scene: Scene, plan: Plan, controller: str = "lqr", render: bool = False,
            rerun_path: str | Path | None = None, *, replan: Replanner | None = None,
            config: TrackerConfig | None = None, observer: RunObserver | None = None,
            world: World | None = None, start_time_s: float = 0.0, hooks=None,
            vehicle_start=None) -> ExecutionRecord:
    """Drive ``plan`` on the MuJoCo vehicle in ``scene`` from ``plan.start`` (see the module docstring).

    Parameters
    ----------
    scene, plan
        The world and the plan to track (its start is the vehicle's start pose).
    controller
        Lateral controller: 'lqr', 'stanley' or 'pure_pursuit'.
    render
        Render top-down and chase frames off-screen (``MUJOCO_GL=egl`` by default) at ``render_fps``.
    rerun_path
        Write a Rerun ``.rrd`` of the run here (scene, plan, trajectory, footprint, scalars, frames if rendering).
    replan
        Replanning mode: called every ``replan_period_s`` of sim time with the pose; a successful plan it returns
        replaces the followed one (its first segment starts at the current speed if the gear matches). The run
        then times out after ``max_time_s``.
    config
        Tracker configuration (default `TrackerConfig()`).
    observer
        Extra per-step observer (logging); `rerun_path`/`render` add their own.
    world
        A world already built from ``scene`` by `build_world` with this ``config`` (e.g. with moving objects);
        the vehicle is placed at ``plan.start``. Default: built here from ``scene``. ``config`` defaults to the
        world's.
    start_time_s
        Sim time at which the run starts (moving objects are at their pose of that time; replanning mode's
        ``max_time_s`` stays an absolute time): a vehicle that waited at its start for a first plan.
    hooks
        A disturbance's run-time side (`tracking.disturbance.RunHooks`): ``sensed(pose, t)`` is the pose the
        controller and the end-of-plan decisions see (a localisation error), ``actuate(curvature, torque)`` what
        reaches the steering servos and drive motors (latency, a slower steering actuator); the ``replan`` hook
        still gets the true pose (its caller applies the same localisation error). None: the ideal vehicle.
    vehicle_start
        Where the vehicle really starts when that is not ``plan.start`` (a plan made from a mislocalised start).

    Returns
    -------
    ExecutionRecord
        Bad plans and starts give a record with a failure reason; bad arguments raise `TrackingError`.
    """
    config = _resolved_config(plan, config, world)
    start = np.asarray(plan.start if vehicle_start is None else vehicle_start, dtype=float)
    if start.shape != (3,) or not np.all(np.isfinite(start)):
        raise TrackingError(f"execute: the start (vehicle_start, else plan.start) must be a finite [x, y, θ], got "
                            f"{start.tolist()!r}")
    segments = _segments(plan, config) if plan.success else []
    reason, detail = _refusal(scene, plan, start, segments, config)
    if reason:
        return ExecutionRecord(success=False, reason=reason, detail=detail, controller=controller, final_pose=start,
                               final_error=_pose_error(start, scene.target))
    if world is None:
        world = build_world(scene, start, config)
    else:
        world.set_pose(start)
    observers = _observers(world, config, render, rerun_path, observer)
    loop = _Loop(world, controller, config, observers, hooks)
    loop.t = float(start_time_s)
    loop.follow(segments, moving=False)
    observers.on_start(world, plan, segments)
    ec = config.executor
    if replan is None:
        t_max = loop.t + ec.timeout_factor * sum(s.duration_s() for s in segments) + ec.timeout_margin_s
    else:
        t_max = ec.max_time_s
    wall0 = time.perf_counter()
    stop = _drive(loop, scene.target, replan, t_max)
    record = _record(loop, scene.target, controller, stop, t_max, time.perf_counter() - wall0,
                     observers.frames_rendered)
    observers.on_end(record)
    return record


def _resolved_config(plan: Plan, config: TrackerConfig | None, world: World | None) -> TrackerConfig:
    """The run's tracker configuration (``config``, else the world's, else the default); `TrackingError` when
    ``plan`` is no Plan or the world was built with another configuration."""
    if config is None:
        config = TrackerConfig() if world is None else world.config
    if world is not None and world.config != config:
        raise TrackingError("execute: the world was built with another TrackerConfig than the one passed")
    if not isinstance(plan, Plan):
        raise TrackingError(f"execute: expected an np_sim.plan.Plan, got {type(plan).__name__}")
    return config


def _refusal(scene: Scene, plan: Plan, start: np.ndarray, segments: list[Segment],
             config: TrackerConfig) -> tuple[str, str]:
    """('', '') when the run can start, else (reason, detail): an untrackable plan or a start in collision."""
    reason, detail = _check_plan(plan, segments, config)
    if not reason and not path_valid(scene, start[None], "footprint", config.vehicle):
        reason, detail = "start_in_collision", (f"the vehicle footprint at the start {start.round(3).tolist()} "
                                                f"overlaps an obstacle or leaves the boundary")
    return reason, detail


def _drive(loop: _Loop, target: np.ndarray, replan: Replanner | None, t_max: float) -> str:
    """Step ``loop`` (calling ``replan`` every ``replan_period_s``) until the run ends; the stop reason: 'contact',
    'timeout' or '' (plan finished, or no new plan while standing short of the target: judged by `_record`)."""
    world, ec = loop.world, loop.config.executor
    next_replan, hold_until = loop.t + ec.replan_period_s, math.inf
    while True:
        if replan is not None and loop.t >= next_replan - 1e-9:
            next_replan += ec.replan_period_s
            if loop.adopt(replan(world.pose(), loop.t)):
                hold_until = math.inf
        if not loop.step():
            if replan is None or parked(loop.sensed_pose(), target, ec):
                return ""
            loop.hold()
            hold_until = loop.t + ec.hold_max_s
        if loop.t >= hold_until:
            return ""
        if loop.contacts and ec.stop_on_contact:
            return "contact"
        if loop.t >= t_max:
            return "timeout"


def _record(loop: _Loop, target: np.ndarray, controller: str, stop: str, t_max: float, wall_s: float,
            frames_rendered: int) -> ExecutionRecord:
    """The record of a finished run: the stop reason, else a contact, else 'not_parked' outside the tolerance."""
    ec = loop.config.executor
    final = loop.world.pose()
    err = _pose_error(final, target)
    if stop:
        reason = stop
    elif loop.contacts:
        reason = "contact"
    else:
        reason = "" if _within_tolerance(err, ec) else "not_parked"
    if reason == "contact":
        detail = f"chassis touched {loop.contacts[0].geom} at t = {loop.contacts[0].time_s:.2f} s"
    elif reason == "timeout":
        detail = f"not finished after {t_max:.1f} s of sim time"
    elif reason == "not_parked":
        detail = (f"stopped {err[0]:.3f} m / {math.degrees(err[1]):.1f}° from the target "
                  f"(tolerance {ec.goal_position_tol_m} m / {ec.goal_heading_tol_deg}°)")
    else:
        detail = ""
    n = max(loop.n_err, 1)
    return ExecutionRecord(
        success=not reason, reason=reason, detail=detail, controller=controller, contacts=loop.contacts,
        final_pose=final, final_error=err, cross_track_rms_m=math.sqrt(loop.lateral_sq / n),
        cross_track_max_m=loop.lateral_max, heading_error_rms_rad=math.sqrt(loop.heading_sq / n),
        path_length_m=loop.length, reversals=loop.reversals, sim_time_s=loop.t, wall_time_s=wall_s,
        plans_used=loop.plans_used, replans_failed=loop.replans_failed, frames_rendered=frames_rendered)


def parked(pose: np.ndarray, target: np.ndarray, ec: ExecutorConfig) -> bool:
    """``pose`` is within the parking tolerance of ``target`` (``goal_position_tol_m`` / ``goal_heading_tol_deg``)."""
    return _within_tolerance(_pose_error(pose, target), ec)


def _within_tolerance(error: tuple[float, float], ec: ExecutorConfig) -> bool:
    return error[0] <= ec.goal_position_tol_m and error[1] <= math.radians(ec.goal_heading_tol_deg)


def _pose_error(pose: np.ndarray, target: np.ndarray) -> tuple[float, float]:
    """(|Δ position| (m), |wrapped Δθ| (rad))."""
    return (float(math.hypot(pose[0] - target[0], pose[1] - target[1])),
            abs(math.remainder(float(pose[2] - target[2]), 2.0 * math.pi)))


def _observers(world: World, config: TrackerConfig, render: bool, rerun_path, extra: RunObserver | None):
    """The run's observers combined: Rerun logging (with frames when rendering) or rendering alone, and a
    caller's observer. Rendering and Rerun are imported only when asked for."""
    parts: list[RunObserver] = []
    if rerun_path is not None:
        from tracking.rerun_log import RerunObserver

        parts.append(RerunObserver(world, config, Path(rerun_path), render))
    elif render:
        from tracking.render import RenderObserver

        parts.append(RenderObserver(world, config))
    if extra is not None:
        parts.append(extra)
    return Observers(parts)
