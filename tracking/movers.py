"""Moving ground-truth objects of a clip (spec §4.4, §8): pedestrians and pushed carts as kinematic bodies.

A `Mover` holds an object's outline in its own frame and its recorded 10 Hz poses; `Mover.pose_at(t)` is the pose
at sim time ``t``: linear interpolation between the two frames around ``t`` (the heading along the shorter way
round), the first pose before frame 0 and the last pose after the last frame. `tracking.world` turns movers into
MuJoCo mocap bodies whose pose the executor sets from `pose_at` every control step.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from tracking.errors import TrackingError


@dataclass(frozen=True, eq=False)
class Mover:
    """An object moving along recorded poses."""

    name: str
    """Body and geom name stem in the world (``mover_<object id>``); contacts report it."""
    outline: np.ndarray
    """(k, 2) outline in the object frame (m), any simple polygon."""
    poses: np.ndarray
    """(n, 3) poses x (m), y (m), yaw (rad), one per frame."""
    frame_dt_s: float
    """Time between two recorded poses (s)."""

    def __post_init__(self) -> None:
        outline, poses = np.asarray(self.outline, float), np.asarray(self.poses, float)
        if outline.ndim != 2 or outline.shape[1] != 2 or len(outline) < 3:
            raise TrackingError(f"Mover {self.name}: outline must be (k >= 3, 2), got shape {outline.shape}")
        if poses.ndim != 2 or poses.shape[1] != 3 or len(poses) < 1 or not np.all(np.isfinite(poses)):
            raise TrackingError(f"Mover {self.name}: poses must be finite (n >= 1, 3), got shape {poses.shape}")
        if not self.frame_dt_s > 0:
            raise TrackingError(f"Mover {self.name}: frame_dt_s must be > 0, got {self.frame_dt_s!r}")
        object.__setattr__(self, "outline", outline)
        object.__setattr__(self, "poses", poses)

    def pose_at(self, t: float) -> np.ndarray:
        """[x, y, yaw] at sim time ``t`` (s): linear between frames, held before the first and after the last."""
        return poses_at(self.poses, self.frame_dt_s, np.array([t]))[0]

    def polygon_at(self, t: float) -> np.ndarray:
        """(k, 2) world-frame outline at sim time ``t``."""
        x, y, yaw = self.pose_at(t)
        c, s = math.cos(yaw), math.sin(yaw)
        return self.outline @ np.array([[c, s], [-s, c]]) + (x, y)


def poses_at(poses: np.ndarray, frame_dt_s: float, times: np.ndarray) -> np.ndarray:
    """(m, 3) poses at ``times`` (s) of a (n, 3) per-frame trajectory: linear interpolation between the frames
    i = ⌊t / dt⌋ and i + 1 with weight a = t/dt − i, yaw θ_i + a·wrap(θ_{i+1} − θ_i); clamped outside
    [0, (n − 1)·dt]."""
    u = np.clip(np.asarray(times, float) / frame_dt_s, 0.0, len(poses) - 1)
    i = np.minimum(np.floor(u).astype(int), len(poses) - 1)
    j = np.minimum(i + 1, len(poses) - 1)
    a = (u - i)[:, None]
    delta = poses[j] - poses[i]
    delta[:, 2] = np.remainder(delta[:, 2] + math.pi, 2.0 * math.pi) - math.pi
    return poses[i] + a * delta
