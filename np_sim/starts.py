"""Start-pose samplers for the environments.

A sampler is any callable ``sampler(rng, scene_indices) -> poses (n, 3)``, batched over the episodes being
reset; the environments call it with their own ``numpy.random.Generator`` so the same seed gives the same
starts. The curriculum sampler (benchmarks issue) plugs in through the same interface.
"""

from __future__ import annotations

from typing import Callable, Protocol

import numpy as np

from np_sim.kernels.sampling import first_free_draws
from np_sim.scene import Scene
from np_sim.scene_arrays import SceneArrays, pack_scenes
from np_sim.vehicle import VehicleSpec


class StartSampler(Protocol):
    """What an env calls on reset: (n, 3) start poses for the scenes ``scene_indices``, drawn with ``rng``."""

    def __call__(self, rng: np.random.Generator, scene_indices: np.ndarray) -> np.ndarray: ...


class UniformStartSampler:
    """Full-range sampler (spec §4.3): position uniform over the start region (default: the boundary) by
    rejection, heading uniform in [−π, π), kept only when the whole footprint is free.

    Each request draws blocks of ``block`` uniform triples (x, y, θ) from the caller's generator, all requests'
    blocks in one array per round; the first accepted triple of a block is used, the rest discarded. The block
    size is part of the sampler's definition: the same seed gives the same starts for the same block.
    """

    def __init__(self, scenes: list[Scene], vehicle: VehicleSpec | None = None, max_draws: int = 100_000,
                 arrays: SceneArrays | None = None, block: int = 32):
        self.scenes = list(scenes)
        self.vehicle = VehicleSpec() if vehicle is None else vehicle
        self.max_draws = int(max_draws)
        self.block = int(block)
        self.arrays = pack_scenes(self.scenes) if arrays is None else arrays
        self._local = self.vehicle.footprint_local()
        regions = [np.asarray(s.start_region if s.start_region is not None else s.boundary, float) for s in self.scenes]
        self._n_region = np.array([len(r) for r in regions], np.int64)
        self._regions = np.zeros((len(regions), int(self._n_region.max()), 2))
        for k, r in enumerate(regions):
            self._regions[k, : len(r)] = r

    def __call__(self, rng: np.random.Generator, scene_indices) -> np.ndarray:
        idx = np.atleast_1d(np.asarray(scene_indices, np.int64))
        out = np.zeros((len(idx), 3))
        pending = np.arange(len(idx))
        drawn = 0
        while len(pending):
            if drawn >= self.max_draws:
                names = sorted({self.scenes[k].name or f"scene {k}" for k in idx[pending]})
                raise RuntimeError(
                    f"UniformStartSampler: no footprint-free start found in {drawn} draws for {', '.join(names)}; "
                    "the start region may be fully blocked"
                )
            u = rng.random((len(pending), self.block, 3))
            poses = np.zeros((len(pending), 3))
            found = first_free_draws(self.arrays.geometry, idx[pending], self._regions, self._n_region, u,
                                     self._local, poses)
            out[pending[found]] = poses[found]
            pending = pending[~found]
            drawn += self.block
        return out


def fixed_start_sampler(poses: np.ndarray) -> Callable[[np.random.Generator, np.ndarray], np.ndarray]:
    """A sampler that returns ``poses[k]`` for each requested scene k (for tests and replays)."""
    poses = np.asarray(poses, float)

    def sample(rng: np.random.Generator, scene_indices) -> np.ndarray:
        return poses[np.atleast_1d(np.asarray(scene_indices, np.int64))].copy()

    return sample
