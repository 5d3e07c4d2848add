"""Rerun logging of a clip run (`tracking.clip_run`): everything `tracking.rerun_log` logs, plus the clip's
moving objects and the detections each planner call used.

Extra entity paths (world frame, metres, timeline ``sim_time``):

* ``world/scene/movers``: ground-truth outlines of the moving objects, every ``log_every`` control steps;
* ``world/detections``: the five-vertex detections of the frame scene a planner call used, at that call;
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

    def log_detections(self, t: float, scene: Scene) -> None:
        """The detections a planner call at sim time ``t`` saw."""
        self.rec.set_time("sim_time", duration=t)
        self.rec.log("world/detections", rr.LineStrips2D([_closed(o.vertices) for o in scene.obstacles],
                                                         colors=[(0, 170, 200)]))

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
