"""Observation and action spaces of the adapted HOPE environment (paper App. B; spec §7): the contract between the
environment (``hope_policy.env``) and the agent.

Observation: a ``Dict`` with

| key           | shape              | content                                                                      |
|---------------|--------------------|------------------------------------------------------------------------------|
| ``lidar``     | (n_beams,) = (120,) | signed footprint clearance d_i − b_i (m), raw (no normalisation)             |
| ``target``    | (5,)               | HOPE's target representation: distance (m), cos/sin of the target bearing,  |
|               |                    | cos/sin of the target heading, both relative to the ego heading              |
| ``action_mask``| (42,)             | HOPE's anchor mask in [0, 1]; present only when ``config.action_mask``       |
| ``vertices``  | (S,)               | only for ``added_input="vertices"``: target-frame obstacle slots then        |
|               |                    | boundary slots of ``np_sim.observation`` (sentinel −1e4); see `vertex_shapes` |
| ``bev``       | (3, 64, 64) uint8  | only for ``added_input="bev"``: ``np_sim.bev`` ego-aligned RGB raster with    |
|               |                    | the trajectory tail (``config.bev_tail``)                                    |

Action: ``Box(-1, 1, (2,), float32)`` mapped linearly to steering angle δ = a_0 · δ_max (rad, positive = left)
and speed v = a_1 · v_max (m/s, sign = gear), held for ``rollout_s`` (`action_to_arc`).
"""

from __future__ import annotations

import numpy as np
from gymnasium import spaces

from hope_policy.config import HopeEnvConfig
from np_sim.lidar import footprint_ranges

N_ANCHORS = 42
"""HOPE's discrete anchors: 21 steering angles × forward/reverse (``configs.py`` ``discrete_actions``)."""
TARGET_SIZE = 5
"""Length of HOPE's target representation."""


def vertex_shapes(config: HopeEnvConfig) -> dict[str, tuple[int, int]]:
    """Shapes of the parts of the flat ``vertices`` observation, in order: obstacles (max_obstacles, 16) and
    boundary (max_boundary_segments, 4)."""
    ob = config.observation
    return {"obstacles": (ob.max_obstacles, 2 * ob.vertices_per_obstacle), "boundary": (ob.max_boundary_segments, 4)}


def _vertex_size(config: HopeEnvConfig) -> int:
    return sum(a * b for a, b in vertex_shapes(config).values())


def observation_space(config: HopeEnvConfig) -> spaces.Dict:
    """The single-env observation space for ``config`` (table in the module docstring)."""
    ob = config.observation
    b = footprint_ranges(config.vehicle, ob.n_beams)
    parts = {
        "lidar": spaces.Box((-b).astype(np.float32), (ob.lidar_range_m - b).astype(np.float32), (ob.n_beams,),
                            np.float32),
        "target": spaces.Box(np.array([0, -1, -1, -1, -1], np.float32), np.array([np.inf, 1, 1, 1, 1], np.float32),
                             (TARGET_SIZE,), np.float32),
    }
    if config.action_mask:
        parts["action_mask"] = spaces.Box(0.0, 1.0, (N_ANCHORS,), np.float32)
    if config.added_input == "vertices":
        parts["vertices"] = spaces.Box(-np.inf, np.inf, (_vertex_size(config),), np.float32)
    elif config.added_input == "bev":
        size = config.bev.size_px
        parts["bev"] = spaces.Box(0, 255, (3, size, size), np.uint8)
    return spaces.Dict(parts)


def action_space() -> spaces.Box:
    """``Box(-1, 1, (2,), float32)``: the normalised (steering angle, speed)."""
    return spaces.Box(-1.0, 1.0, (2,), np.float32)


def action_to_arc(actions, config: HopeEnvConfig) -> np.ndarray:
    """(…, 2) normalised actions → (…, 2) arcs (κ, l) of paper eq:arc.

    δ = a_0 · δ_max, v = a_1 · v_max held for T = rollout_s drive the kinematic bicycle θ' = v tan δ / L on a
    circle of physical curvature c = tan δ / L over the signed length l = v · T; in the project's convention
    (spec §2, heading change −sgn(κ)|lκ|) that is the arc κ = −sgn(l) · c, l = v · T.
    """
    a = np.asarray(actions, float)
    steer_curvature = np.tan(a[..., 0] * config.max_steer_rad) / config.vehicle.wheelbase_m
    length = a[..., 1] * config.max_length_m
    return np.stack([-np.sign(length) * steer_curvature, length], axis=-1)
