"""The NeuralParker observation layout (paper §III-B, App. A Table IV).

Flat vector, in this order (streams switched off in ``ObservationConfig`` are absent):

| part      | size                         | content                                                              |
|-----------|------------------------------|----------------------------------------------------------------------|
| ego       | 4                            | x̃, ỹ (m), cos θ̃, sin θ̃ of the reference point in the target frame  |
| lidar     | n_beams (120)                | max(d_i − b_i, 0) (m), beam 0 along the heading, counter-clockwise   |
| obstacles | max_obstacles × 2·vertices   | target-frame vertices x0, y0, …, x7, y7 per obstacle (m)             |
| boundary  | max_boundary_segments × 4    | target-frame segment endpoints x0, y0, x1, y1 (m)                    |
| bev       | bev_latent_dim (128)         | frozen-encoder latent of the ego-aligned BEV raster (``use_bev``)    |

Obstacles keep scene order; a polygon with fewer vertices repeats its vertices cyclically; circles are
inscribed octagons. Unused slots hold the sentinel (−1e4). The geometry slots depend only on the scene (the
target frame is fixed per scene), so they are computed once per scene.

The BEV latent (paper App. B, the NeuralParker-backbone BEV control) is written by the environment after each step
and reset: `np_sim.bev` renders the ego-aligned raster without a trajectory tail and the frozen encoder of
``bev_encoder_file`` maps it to the latent. ``np_sim`` never imports torch, so the encoder is loaded by the loader
that ``np_policy.bev_encoder`` registers here when it is imported (``np_policy.network`` imports it).
"""

from __future__ import annotations

import functools

from collections.abc import Callable
from typing import Protocol

import numpy as np

from np_sim.bev import BevConfig
from np_sim.config import ObservationConfig
from np_sim.errors import ConfigError
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
    if config.use_bev:
        sizes.append(("bev", config.bev_latent_dim))
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
    if config.use_bev:
        shapes["bev"] = (config.bev_latent_dim,)
    return shapes


def obstacle_slots(scene: Scene, config: ObservationConfig) -> np.ndarray:
    """(max_obstacles, 2·vertices) target-frame obstacle slots of s^p and s^o (sentinel-padded)."""
    scene.check_capacity(config.capacity(), source=scene.name or "<scene>")
    return _obstacle_slots(scene, config)


def _obstacle_slots(scene: Scene, config: ObservationConfig) -> np.ndarray:
    slots = np.full((config.max_obstacles, 2 * config.vertices_per_obstacle), config.sentinel)
    polygons = scene.polygons_for_observation()
    if polygons:
        # each polygon's vertices repeated cyclically to the slot's vertex count, all moved in one call
        cyclic = np.concatenate([np.asarray(v, float)[_cyclic_index(len(v), config.vertices_per_obstacle)]
                                 for v in polygons])
        slots[: len(polygons)] = to_target_frame(cyclic, scene.target).reshape(len(polygons), -1)
    return slots


@functools.lru_cache(maxsize=64)
def _cyclic_index(n: int, slots: int) -> np.ndarray:
    """Vertex indices 0, 1, …, n−1, 0, 1, … filling ``slots`` places."""
    return np.arange(slots) % n


def boundary_slots(scene: Scene, config: ObservationConfig) -> np.ndarray:
    """(max_boundary_segments, 4) target-frame boundary segments of s^b (sentinel-padded)."""
    scene.check_capacity(config.capacity(), source=scene.name or "<scene>")
    return _boundary_slots(scene, config)


def _boundary_slots(scene: Scene, config: ObservationConfig) -> np.ndarray:
    # segment i joins vertex i to vertex i+1 (`Scene.boundary_segments`); each vertex is moved once
    ends = to_target_frame(scene.boundary, scene.target)
    slots = np.full((config.max_boundary_segments, 4), config.sentinel)
    slots[: len(ends), 0:2] = ends
    slots[: len(ends) - 1, 2:4] = ends[1:]
    slots[len(ends) - 1, 2:4] = ends[0]
    return slots


def static_slots(scene: Scene, config: ObservationConfig) -> np.ndarray:
    """The scene-constant tail of the flat observation (obstacle then boundary slots, as enabled)."""
    scene.check_capacity(config.capacity(), source=scene.name or "<scene>")
    parts = []
    if config.use_obstacles:
        parts.append(_obstacle_slots(scene, config).reshape(-1))
    if config.use_boundary:
        parts.append(_boundary_slots(scene, config).reshape(-1))
    return np.concatenate(parts) if parts else np.zeros(0)


def split_observation(flat: np.ndarray, config: ObservationConfig) -> dict[str, np.ndarray]:
    """Dict view of flat observations (..., size): each part reshaped to ``section_shapes``."""
    shapes = section_shapes(config)
    lead = flat.shape[:-1]
    return {name: flat[..., a:b].reshape(*lead, *shapes[name]) for name, (a, b) in observation_sections(config).items()}


class BevEncoder(Protocol):
    """A frozen BEV encoder: uint8 images (N, 3, S, S) → float32 latents (N, latent_dim), with the raster it was
    trained on."""

    raster: BevConfig
    latent_dim: int

    def __call__(self, images: np.ndarray) -> np.ndarray: ...


_BEV_LOADER: list[Callable[[str], BevEncoder]] = []


def register_bev_encoder_loader(loader: Callable[[str], BevEncoder]) -> None:
    """Make ``loader`` (file path → `BevEncoder`) the one `bev_encoder` uses (``np_policy.bev_encoder`` registers
    its frozen-encoder loader on import)."""
    _BEV_LOADER[:] = [loader]


def bev_encoder(config: ObservationConfig) -> BevEncoder:
    """The frozen encoder of ``config.bev_encoder_file``; ConfigError when no loader is registered or its latent
    size is not ``bev_latent_dim``."""
    if not _BEV_LOADER:
        raise ConfigError("ObservationConfig.use_bev: the BEV latent needs the frozen encoder, which "
                          "np_policy.bev_encoder loads; import np_policy.bev_encoder before building the environment")
    encoder = _BEV_LOADER[0](config.bev_encoder_file)
    if encoder.latent_dim != config.bev_latent_dim:
        raise ConfigError(f"ObservationConfig.bev_latent_dim: {config.bev_latent_dim} differs from the latent size "
                          f"{encoder.latent_dim} of {config.bev_encoder_file}")
    return encoder
