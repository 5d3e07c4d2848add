"""Rerun logging of a closed-loop run: one ``.rrd`` per run, world frame in metres, timeline ``sim_time`` (s).

Entity paths:

* ``world/scene/boundary``, ``world/scene/obstacles``, ``world/scene/target`` (static): the scene and the target
  footprint;
* ``world/plan`` (on ``sim_time``: the first plan when the drive starts, each replan at its time; never static,
  since static data would hide every replan): the planned path per gear segment (forward green, reverse red), with
  a ``PlanPoses`` archetype carrying each sample's heading (``heading_rad``, the segments' samples one after the
  other) and each segment's ``gear`` (+1 / −1);
* ``world/vehicle/footprint``, ``world/vehicle/reference_point`` (on ``sim_time``): the rectangle of the body the
  simulator drives (`tracking.config.PlantConfig.body`: longer than the planned `VehicleSpec` under a
  ``body_length`` disturbance);
* ``world/executed`` (static, at the end): the executed reference-point trajectory;
* ``world/contacts`` (on ``sim_time``): chassis contact points, labelled with the touched geom;
* ``controller/<name>`` (scalars on ``sim_time``): cross_track_m, heading_error_rad, steer_curvature_cmd,
  steer_curvature_ref, speed_mps, speed_target_mps;
* ``camera/topdown``, ``camera/chase`` (JPEG frames on ``sim_time``) when rendering;
* ``run/outcome`` (text log at the run's end time): success, reason and the tracking figures, with an
  ``Outcome`` archetype holding them as values (``success``, ``reason``, ``final_pose``, ``final_error``,
  ``cross_track_rms_m``, ``cross_track_max_m``, ``sim_time_s``, ``plans_used``).

`tracking.rrd_read.read_run` reads a recording back.

Every recording is named after its file (``<clip>_<planner>`` in a clip run) and carries the viewer layout
`run_blueprint`; `merge_recordings` merges the recordings of several runs into one optimised file.
"""

from __future__ import annotations

import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
import rerun as rr
import rerun.blueprint as rrb
from rerun.chunk import RrdReader

from np_sim.scene import CircleObstacle
from tracking.config import TrackerConfig
from tracking.observer import RunObserver

_GEAR_COLORS = {1: (40, 170, 60), -1: (210, 50, 50)}
"""Planned path colour per gear (forward green, reverse red)."""

_PLAN_RADIUS_M = 0.12
"""Half-width of the drawn plan (m): wide enough to show its gear colour on both sides of the executed path."""

_PLAN_DRAW_ORDER, _EXECUTED_DRAW_ORDER = 15.0, 25.0
"""Rerun draw orders (higher on top; by default line strips draw at 20, points at 30): the plan under the other
outlines, the executed path over them and under the points."""

_SCALARS = ("cross_track_m", "heading_error_rad", "steer_curvature_cmd", "steer_curvature_ref", "speed_mps",
            "speed_target_mps")
"""Controller scalars, logged under ``controller/``."""


APPLICATION_ID = "neuralparker_tracking"
"""Rerun application id of every closed-loop recording (the viewer applies a blueprint per application)."""

WORLD_ORIGIN = "world"
"""Origin of the 2-D world view: every ``world/...`` entity is drawn in it."""


def _closed(ring: np.ndarray) -> np.ndarray:
    return np.vstack([ring, ring[:1]])


def run_blueprint() -> rrb.Blueprint:
    """The viewer layout of a run: the 2-D world (scene, movers, detections, plans, footprint, executed path,
    contacts) on the left; on the right the two cameras side by side, the controller scalars in one time-series
    panel and the outcome text. The selection panel and the time panel start collapsed (the time panel keeps its
    playback bar), leaving the room to the views."""
    return rrb.Blueprint(
        rrb.Horizontal(
            rrb.Spatial2DView(name="World", origin=WORLD_ORIGIN),
            rrb.Vertical(
                rrb.Horizontal(rrb.Spatial2DView(name="Top-down camera", origin="camera/topdown"),
                               rrb.Spatial2DView(name="Chase camera", origin="camera/chase")),
                rrb.TimeSeriesView(name="Controller", origin="controller"),
                rrb.TextLogView(name="Outcome", origin="run"),
                row_shares=[3, 3, 1]),
            column_shares=[3, 2]),
        rrb.SelectionPanel(state="collapsed"),
        rrb.TimePanel(state="collapsed"),
        auto_views=False)


def log_outcome(rec: rr.RecordingStream, record, figures: str = "") -> None:
    """Log a run's outcome line (success, reason, detail, then ``figures``) to ``run/outcome`` at the run's end
    time, on the timeline (the viewer's text-log view lists no static rows), and its figures as values (an
    ``Outcome`` archetype, read back by `tracking.rrd_read`)."""
    rec.set_time("sim_time", duration=record.sim_time_s)
    values = {"success": [bool(record.success)], "reason": [record.reason],
              "final_pose": np.asarray(record.final_pose, float), "final_error": np.asarray(record.final_error, float),
              "cross_track_rms_m": [record.cross_track_rms_m], "cross_track_max_m": [record.cross_track_max_m],
              "sim_time_s": [record.sim_time_s], "plans_used": [record.plans_used]}
    rec.log("run/outcome", rr.TextLog(f"success={record.success} reason={record.reason or '-'} {record.detail} "
                                      f"{figures}".rstrip(), level="INFO" if record.success else "WARN"),
            rr.DynamicArchetype("Outcome", components=values))


def merge_recordings(files: list[Path], out: Path) -> Path:
    """Merge the recordings in ``files`` into ``out`` with one copy of `run_blueprint` and optimise it (``rerun rrd
    optimize``: each recording's many small chunks compacted into about one per entity); returns ``out``.

    The blueprint each file carries is left out (they are all `run_blueprint`; one copy per run would add a dozen
    chunks per run to the merged file)."""
    if not files:
        raise ValueError(f"merge_recordings: expected at least one .rrd file to merge into {out}, got none")
    exe = Path(sys.executable).parent / "rerun"
    exe = str(exe) if exe.exists() else shutil.which("rerun")
    if exe is None:
        raise FileNotFoundError("merge_recordings: the 'rerun' command is missing; install rerun-sdk into the venv")
    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(dir=out.parent) as folder:
        parts = []
        for k, path in enumerate(files):
            reader = RrdReader(str(path))
            for entry in reader.recordings():
                parts.append(Path(folder) / f"{k}_{entry.recording_id}.rrd")
                reader.store(store=entry).write_rrd(parts[-1], application_id=entry.application_id,
                                                    recording_id=entry.recording_id)
        layout = Path(folder) / "layout.rbl"
        run_blueprint().save(APPLICATION_ID, str(layout))
        subprocess.run([exe, "rrd", "optimize", "-o", str(out), *map(str, parts), str(layout)], check=True,
                       capture_output=True)
    return out


class RerunObserver(RunObserver):
    """Writes one run to ``path`` (frames too when ``render``); scalars are sent as columns at the end."""

    def __init__(self, world, config: TrackerConfig, path: Path, render: bool):
        self.config, self.vehicle = config, config.vehicle
        self.body = config.plant.body(config.vehicle)
        self.start_time_s = 0.0
        """Sim time the drive starts at (later than 0 after a vehicle waited for its first plan)."""
        path.parent.mkdir(parents=True, exist_ok=True)
        self.rec = rr.RecordingStream(APPLICATION_ID)
        self.rec.save(str(path), default_blueprint=run_blueprint())
        self.rec.send_recording_name(path.stem)
        self.every = max(1, config.executor.log_every)
        self.steps = 0
        self.times: list[float] = []
        self.scalars: list[tuple[float, ...]] = []
        self.trajectory: list[tuple[float, float]] = []
        self.renderer = None
        if render:
            from tracking.render import RenderObserver

            self.renderer = RenderObserver(world, config, sink=self._frame)

    @property
    def frames_rendered(self) -> int:
        return 0 if self.renderer is None else self.renderer.frames_rendered

    def _frame(self, t: float, camera: str, frame: np.ndarray) -> None:
        self.rec.set_time("sim_time", duration=t)
        self.rec.log(f"camera/{camera}", rr.Image(frame).compress(jpeg_quality=80))

    def _log_plan(self, t: float, segments) -> None:
        self.rec.set_time("sim_time", duration=t)
        self.rec.log("world/plan", rr.LineStrips2D([seg.xy for seg in segments], radii=_PLAN_RADIUS_M,
                                                   colors=[_GEAR_COLORS[seg.gear] for seg in segments],
                                                   draw_order=_PLAN_DRAW_ORDER),
                     rr.DynamicArchetype("PlanPoses", components={
                         "heading_rad": np.concatenate([seg.theta for seg in segments]),
                         "gear": np.array([seg.gear for seg in segments], np.int8)}))

    def on_start(self, world, plan, segments) -> None:
        scene, rec = world.scene, self.rec
        rec.log("world/scene/boundary", rr.LineStrips2D([_closed(scene.boundary)], colors=[(90, 90, 90)]), static=True)
        rings = [o.ring(32) if isinstance(o, CircleObstacle) else o.vertices for o in scene.obstacles]
        rec.log("world/scene/obstacles", rr.LineStrips2D([_closed(r) for r in rings], colors=[(60, 90, 200)],
                                                         labels=[f"obstacle_{i}" for i in range(len(rings))]),
                static=True)
        rec.log("world/scene/target", rr.LineStrips2D([_closed(self.vehicle.footprint(scene.target))],
                                                      colors=[(230, 180, 0)]), static=True)
        self._log_plan(self.start_time_s, segments)
        self._log_vehicle(self.start_time_s, world.pose())
        if self.renderer is not None:
            self.renderer.on_start(world, plan, segments)

    def on_plan(self, t, plan, segments) -> None:
        self._log_plan(t, segments)

    def _log_vehicle(self, t: float, pose: np.ndarray) -> None:
        self.rec.set_time("sim_time", duration=t)
        self.rec.log("world/vehicle/footprint", rr.LineStrips2D([_closed(self.body.footprint(pose))],
                                                                colors=[(230, 120, 20)]))
        self.rec.log("world/vehicle/reference_point", rr.Points2D([pose[:2]], radii=0.08))

    def on_step(self, t, world, state, command, target_speed) -> None:
        p = state.projection
        self.times.append(t)
        self.scalars.append((p.lateral_m, p.heading_rad, command, p.steer_curvature_ref, state.speed_mps,
                             target_speed))
        pose = world.pose()
        self.trajectory.append((pose[0], pose[1]))
        self.steps += 1
        if self.steps % self.every == 0:
            self._log_vehicle(t, pose)
        if self.renderer is not None:
            self.renderer.on_step(t, world, state, command, target_speed)

    def on_end(self, record) -> None:
        rec = self.rec
        if self.times:
            values = np.asarray(self.scalars)
            index = [rr.TimeColumn("sim_time", duration=np.asarray(self.times))]
            for j, name in enumerate(_SCALARS):
                rec.send_columns(f"controller/{name}", indexes=index, columns=rr.Scalars.columns(scalars=values[:, j]))
        if self.trajectory:
            rec.log("world/executed", rr.LineStrips2D([np.asarray(self.trajectory)], colors=[(20, 20, 20)],
                                                      draw_order=_EXECUTED_DRAW_ORDER), static=True)
        for c in record.contacts:
            rec.set_time("sim_time", duration=c.time_s)
            rec.log("world/contacts", rr.Points2D([c.position], labels=[c.geom], colors=[(255, 0, 0)], radii=0.15))
        log_outcome(rec, record, f"cross_track_rms_m={record.cross_track_rms_m:.3f} final_error="
                                 f"({record.final_error[0]:.3f} m, {np.degrees(record.final_error[1]):.1f} deg)")
        if self.renderer is not None:
            self.renderer.on_end(record)
        rec.flush()
        rec.disconnect()
