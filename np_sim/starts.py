"""Start-pose samplers for the environments.

A sampler is any callable ``sampler(rng, scene_index) -> pose (3,)``; the environments call it with their own
``numpy.random.Generator`` so the same seed gives the same starts. The curriculum sampler (benchmarks issue)
plugs in through the same interface.
"""

from __future__ import annotations

import math
from typing import Callable, Protocol

import numpy as np

from np_sim.kernels.collision import footprint_valid
from np_sim.kernels.geometry import INSIDE, point_in_polygon
from np_sim.scene import Scene
from np_sim.scene_arrays import SceneArrays, pack_scenes
from np_sim.vehicle import VehicleSpec


class StartSampler(Protocol):
    def __call__(self, rng: np.random.Generator, scene_index: int) -> np.ndarray: ...


class UniformStartSampler:
    """Full-range sampler (SPEC §4.3): position uniform over the start region (default: the boundary) by
    rejection, heading uniform in [−π, π), kept only when the whole footprint is free."""

    def __init__(self, scenes: list[Scene], vehicle: VehicleSpec | None = None, max_draws: int = 100_000,
                 arrays: SceneArrays | None = None):
        self.scenes = list(scenes)
        self.vehicle = VehicleSpec() if vehicle is None else vehicle
        self.max_draws = int(max_draws)
        self.arrays = pack_scenes(self.scenes) if arrays is None else arrays
        self._local = self.vehicle.footprint_local()
        self._regions = [np.asarray(s.start_region if s.start_region is not None else s.boundary, float)
                         for s in self.scenes]

    def __call__(self, rng: np.random.Generator, scene_index: int) -> np.ndarray:
        region = self._regions[scene_index]
        lo, hi = region.min(axis=0), region.max(axis=0)
        corners = np.empty((4, 2))
        geo = self.arrays.geometry
        for _ in range(self.max_draws):
            x, y = rng.uniform(lo, hi)
            th = rng.uniform(-math.pi, math.pi)
            if point_in_polygon(x, y, region, len(region)) != INSIDE:
                continue
            if footprint_valid(geo, scene_index, x, y, th, self._local, corners):
                return np.array([x, y, th])
        name = self.scenes[scene_index].name or f"scene {scene_index}"
        raise RuntimeError(
            f"UniformStartSampler: no footprint-free start found in {self.max_draws} draws for {name}; "
            "the start region may be fully blocked"
        )


def fixed_start_sampler(poses: np.ndarray) -> Callable[[np.random.Generator, int], np.ndarray]:
    """A sampler that always returns ``poses[scene_index]`` (for tests and replays)."""
    poses = np.asarray(poses, float)

    def sample(rng: np.random.Generator, scene_index: int) -> np.ndarray:
        return poses[scene_index].copy()

    return sample
