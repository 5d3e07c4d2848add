"""Start-pose samplers for the environments.

A sampler is any callable ``sampler(rng, scene_index) -> pose (3,)``; the environments call it with their own
``numpy.random.Generator`` so the same seed gives the same starts. The curriculum sampler (benchmarks issue)
plugs in through the same interface.
"""

from __future__ import annotations

import math
from typing import Callable, Protocol

import numpy as np

from np_sim.kernels.sampling import first_free_draw
from np_sim.scene import Scene
from np_sim.scene_arrays import SceneArrays, pack_scenes
from np_sim.vehicle import VehicleSpec


class StartSampler(Protocol):
    def __call__(self, rng: np.random.Generator, scene_index: int) -> np.ndarray: ...


class UniformStartSampler:
    """Full-range sampler (SPEC §4.3): position uniform over the start region (default: the boundary) by
    rejection, heading uniform in [−π, π), kept only when the whole footprint is free.

    Draws come in blocks of ``block`` uniform triples from the caller's generator; the first accepted triple of a
    block is used and the rest of the block is discarded.
    """

    def __init__(self, scenes: list[Scene], vehicle: VehicleSpec | None = None, max_draws: int = 100_000,
                 arrays: SceneArrays | None = None, block: int = 32):
        self.scenes = list(scenes)
        self.vehicle = VehicleSpec() if vehicle is None else vehicle
        self.max_draws = int(max_draws)
        self.block = int(block)  # part of the sampler's definition: same seed → same starts for the same block
        self.arrays = pack_scenes(self.scenes) if arrays is None else arrays
        self._local = self.vehicle.footprint_local()
        self._regions = [np.asarray(s.start_region if s.start_region is not None else s.boundary, float)
                         for s in self.scenes]

    def __call__(self, rng: np.random.Generator, scene_index: int) -> np.ndarray:
        region = self._regions[scene_index]
        lo, hi = region.min(axis=0), region.max(axis=0)
        drawn = 0
        while drawn < self.max_draws:
            u = rng.random((self.block, 3))  # x, y, θ uniforms, consumed in order
            r = first_free_draw(self.arrays.geometry, scene_index, region, lo, hi, u, self._local)
            if r >= 0:
                return np.array([lo[0] + u[r, 0] * (hi[0] - lo[0]), lo[1] + u[r, 1] * (hi[1] - lo[1]),
                                 -math.pi + 2.0 * math.pi * u[r, 2]])
            drawn += self.block
        name = self.scenes[scene_index].name or f"scene {scene_index}"
        raise RuntimeError(
            f"UniformStartSampler: no footprint-free start found in {drawn} draws for {name}; "
            "the start region may be fully blocked"
        )


def fixed_start_sampler(poses: np.ndarray) -> Callable[[np.random.Generator, int], np.ndarray]:
    """A sampler that always returns ``poses[scene_index]`` (for tests and replays)."""
    poses = np.asarray(poses, float)

    def sample(rng: np.random.Generator, scene_index: int) -> np.ndarray:
        return poses[scene_index].copy()

    return sample
