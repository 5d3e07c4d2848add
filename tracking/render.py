"""Off-screen frames of a world from the top-down and chase cameras.

MuJoCo picks its OpenGL backend from ``MUJOCO_GL`` when it is first imported; `tracking/__init__.py` defaults it
to ``egl`` (CPU rendering through Mesa's software EGL, spec §8) before anything imports mujoco.
"""

from __future__ import annotations

import mujoco
import numpy as np

from tracking.config import TrackerConfig
from tracking.observer import RunObserver

CAMERAS = ("topdown", "chase")
"""Cameras of every world: a fixed top-down view of the whole scene and one riding behind the vehicle."""


class FrameRenderer:
    """RGB frames (height, width, 3) uint8 of a world's cameras."""

    def __init__(self, model: mujoco.MjModel, width: int, height: int):
        try:
            self.renderer = mujoco.Renderer(model, height=height, width=width)
        except Exception as error:  # the GL backend reports its own failure types
            raise RuntimeError(f"off-screen rendering failed ({error}); set MUJOCO_GL=egl before mujoco is imported "
                               "and install Mesa's EGL (Debian: libegl1 libegl-mesa0 libgl1-mesa-dri)") from error

    def render(self, data: mujoco.MjData, camera: str) -> np.ndarray:
        """A frame of ``camera`` for the current state."""
        self.renderer.update_scene(data, camera=camera)
        return self.renderer.render()

    def close(self) -> None:
        """Free the GL context."""
        self.renderer.close()


class RenderObserver(RunObserver):
    """Renders every camera at ``render_fps`` of sim time; ``frames`` holds the latest frame of each camera and
    ``sink(t, camera, frame)``, when given, receives every frame."""

    def __init__(self, world, config: TrackerConfig, sink=None):
        ec = config.executor
        self.renderer = FrameRenderer(world.model, ec.render_width, ec.render_height)
        self.period_s = 1.0 / ec.render_fps
        self.next_t = 0.0
        self.sink = sink
        self.frames: dict[str, np.ndarray] = {}
        self.frames_rendered = 0

    def _render(self, t: float, world) -> None:
        for camera in CAMERAS:
            frame = self.renderer.render(world.data, camera)
            self.frames[camera] = frame
            self.frames_rendered += 1
            if self.sink is not None:
                self.sink(t, camera, frame)
        self.next_t = t + self.period_s

    def on_start(self, world, plan, segments) -> None:
        self._render(0.0, world)

    def on_step(self, t, world, state, command, target_speed) -> None:
        if t >= self.next_t - 1e-9:
            self._render(t, world)

    def on_end(self, record) -> None:
        self.renderer.close()
