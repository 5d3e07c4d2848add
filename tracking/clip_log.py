"""Rerun logging of a clip run (`tracking.clip_run`): everything `tracking.rerun_log` logs, plus the clip's
moving objects and the detections each planner call used.

Extra entity paths (world frame, metres, timeline ``sim_time``):

* ``world/scene/movers``: ground-truth outlines of the moving objects, every ``log_every`` control steps;
* ``world/detections``: the five-vertex detections of the frame scene a planner call used, at that call,
  labelled with the detected object ('<kind> <id>', as `tracking.clip_run.object_of_geom` names it);
* ``run/calls``: one text line per planner call, at its time, with a ``PlannerCall`` archetype holding its
  ``frame``, ``success``, ``rejected`` (why the tracker refused a successful plan, '' if it did not) and
  ``plan_time_s``;
* ``run/clip`` (static text): the clip's name.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import rerun as rr

from np_sim.scene import Scene
from tracking.config import TrackerConfig
from tracking.rerun_log import RerunObserver, log_outcome


def _closed(ring: np.ndarray) -> np.ndarray:
    return np.vstack([ring, ring[:1]])


class ClipRerunObserver(RerunObserver):
    """`RerunObserver` of a clip run, with movers and detections."""

    def __init__(self, world, config: TrackerConfig, path: Path, render: bool, clip_name: str):
        super().__init__(world, config, path, render)
        self.movers = world.movers
        self.rec.log("run/clip", rr.TextDocument(clip_name), static=True)
        self._log_movers(0.0)

    def _log_movers(self, t: float) -> None:
        if self.movers:
            self.rec.set_time("sim_time", duration=t)
            self.rec.log("world/scene/movers", rr.LineStrips2D([_closed(m.polygon_at(t)) for m in self.movers],
                                                               colors=[(200, 70, 150)],
                                                               labels=[m.name for m in self.movers]))

    def log_call(self, call, scene: Scene, labels: list[str]) -> None:
        """A planner call (`tracking.clip_run.PlanCall`) and the detections it saw (``scene``'s obstacles, named
        by ``labels``), at the call's sim time. The drive starts at the time of the last usable call before it."""
        self.rec.set_time("sim_time", duration=call.time_s)
        self.rec.log("world/detections", rr.LineStrips2D([_closed(o.vertices) for o in scene.obstacles],
                                                         colors=[(0, 170, 200)], labels=labels))
        verdict = "usable plan" if call.usable else (call.rejected or "failed")
        self.rec.log("run/calls", rr.TextLog(f"planner call on frame {call.frame}: {verdict} "
                                             f"({call.plan_time_s:.2f} s)", level="INFO" if call.usable else "WARN"),
                     rr.DynamicArchetype("PlannerCall", components={
                         "frame": [call.frame], "success": [call.success], "rejected": [call.rejected],
                         "plan_time_s": [call.plan_time_s]}))
        if call.usable and not self.steps:
            self.start_time_s = call.time_s

    def on_step(self, t, world, state, command, target_speed) -> None:
        super().on_step(t, world, state, command, target_speed)
        if self.steps % self.every == 0:
            self._log_movers(t)

    def finish_unrun(self, record) -> None:
        """Close the file of a run the executor refused before its loop (a failed first plan): the outcome only."""
        log_outcome(self.rec, record)
        if self.renderer is not None:
            self.renderer.on_end(record)
        self.rec.flush()
        self.rec.disconnect()
