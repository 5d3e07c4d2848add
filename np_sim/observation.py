"""The NeuralParker observation layout (paper §III-B, App. A Table IV).

Flat vector, in this order (streams switched off in ``ObservationConfig`` are absent):

| part      | size                         | content                                                              |
|-----------|------------------------------|----------------------------------------------------------------------|
| ego       | 4                            | x̃, ỹ (m), cos θ̃, sin θ̃ of the reference point in the target frame  |
| lidar     | n_beams (120)                | max(d_i − b_i, 0) (m), beam 0 along the heading, counter-clockwise   |
| obstacles | max_obstacles × 2·vertices   | target-frame vertices x0, y0, …, x7, y7 per obstacle (m)             |
| boundary  | max_boundary_segments × 4    | target-frame segment endpoints x0, y0, x1, y1 (m)                    |

Obstacles keep scene order; a polygon with fewer vertices repeats its vertices cyclically; circles are
inscribed octagons. Unused slots hold the sentinel (−1e4). The geometry slots depend only on the scene (the
target frame is fixed per scene), so they are computed once per scene.
"""

from __future__ import annotations

import numpy as np

from np_sim.config import ObservationConfig
from np_sim.frames import to_target_frame
from np_sim.scene import Scene

EGO_SIZE = 4


def observation_sections(config: ObservationConfig) -> dict[str, tuple[int, int]]:
    """Name -> (start, stop) of each present part in the flat vector."""
    sizes = [("ego", EGO_SIZE)]
    if config.use_lidar:
        sizes.append(("lidar", config.n_beams))
    if config.use_obstacles:
        sizes.append(("obstacles", config.max_obstacles * 2 * config.vertices_per_obstacle))
    if config.use_boundary:
        sizes.append(("boundary", config.max_boundary_segments * 4))
    out, start = {}, 0
    for name, size in sizes:
        out[name] = (start, start + size)
        start += size
    return out


def observation_size(config: ObservationConfig) -> int:
    """Length of the flat observation."""
    return max(stop for _, stop in observation_sections(config).values())


def section_shapes(config: ObservationConfig) -> dict[str, tuple[int, ...]]:
    """Shapes of the parts in the Dict observation."""
    shapes = {"ego": (EGO_SIZE,)}
    if config.use_lidar:
        shapes["lidar"] = (config.n_beams,)
    if config.use_obstacles:
        shapes["obstacles"] = (config.max_obstacles, 2 * config.vertices_per_obstacle)
    if config.use_boundary:
        shapes["boundary"] = (config.max_boundary_segments, 4)
    return shapes


def obstacle_slots(scene: Scene, config: ObservationConfig) -> np.ndarray:
    """(max_obstacles, 2·vertices) target-frame obstacle slots of s^p and s^o (sentinel-padded)."""
    scene.check_capacity(config.capacity(), source=scene.name or "<scene>")
    slots = np.full((config.max_obstacles, 2 * config.vertices_per_obstacle), config.sentinel)
    for j, verts in enumerate(scene.polygons_for_observation()):
        local = to_target_frame(verts, scene.target)
        cyclic = local[np.arange(config.vertices_per_obstacle) % len(local)]
        slots[j] = cyclic.reshape(-1)
    return slots


def boundary_slots(scene: Scene, config: ObservationConfig) -> np.ndarray:
    """(max_boundary_segments, 4) target-frame boundary segments of s^b (sentinel-padded)."""
    scene.check_capacity(config.capacity(), source=scene.name or "<scene>")
    segs = scene.boundary_segments()
    slots = np.full((config.max_boundary_segments, 4), config.sentinel)
    slots[: len(segs), 0:2] = to_target_frame(segs[:, 0:2], scene.target)
    slots[: len(segs), 2:4] = to_target_frame(segs[:, 2:4], scene.target)
    return slots


def static_slots(scene: Scene, config: ObservationConfig) -> np.ndarray:
    """The scene-constant tail of the flat observation (obstacle then boundary slots, as enabled)."""
    parts = []
    if config.use_obstacles:
        parts.append(obstacle_slots(scene, config).reshape(-1))
    if config.use_boundary:
        parts.append(boundary_slots(scene, config).reshape(-1))
    return np.concatenate(parts) if parts else np.zeros(0)


def split_observation(flat: np.ndarray, config: ObservationConfig) -> dict[str, np.ndarray]:
    """Dict view of flat observations (..., size): each part reshaped to ``section_shapes``."""
    shapes = section_shapes(config)
    lead = flat.shape[:-1]
    return {name: flat[..., a:b].reshape(*lead, *shapes[name]) for name, (a, b) in observation_sections(config).items()}
