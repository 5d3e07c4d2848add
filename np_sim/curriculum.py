"""Geodesic start curriculum (paper §III-E, App. A Table V "curriculum start scale / distance: 0.05 / geodesic";
spec §5 curriculum paragraph).

**Candidate starts.** For each scene, a pool of ``pool_size`` start poses is drawn once from the full-range
`UniformStartSampler` (uniform position in the start region, uniform heading, footprint-free) with its own
``numpy.random.default_rng(seed)``, keeping only starts whose cell of the 1.5 m footprint-inflated geodesic grid
(`np_sim.geodesic`) is reachable from the target — the same procedure as the frozen evaluation starts
(`np_sim.benchmarks.frozen.draw_frozen_starts`), with a different seed. Each pool is then ordered by the geodesic
distance of the start's cell to the target (stable: ties keep draw order).

**Fraction.** At fraction f the sampler draws uniformly among the nearest ``max(1, ceil(f · pool_size))`` starts
of each scene's pool: f = 0.05 is "the nearest 5 % of each scene's start range" (a quantile of the pool, not 5 %
of the distance interval), f = 1 is the whole pool, i.e. the full-range distribution.

**Schedule.** `CurriculumSchedule` maps training progress p ∈ [0, 1] (e.g. environment steps done / total) to f:
f = start_fraction at p = 0, f = 1 from p = full_at_progress on; in between linear, or in ``n_stages`` equal
steps (``mode="staged"``). The paper fixes the start (0.05) but not the ramp; the default reaches the full range
at half of the training budget, linearly. ``enabled=False`` is the no-curriculum ablation (f = 1 throughout,
paper §V "Start-Curriculum Ablation"). The schedule is part of the training config (`to_dict` / `from_dict`).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np

from np_sim.benchmarks.frozen import draw_frozen_starts
from np_sim.config import config_from_dict
from np_sim.errors import ConfigError
from np_sim.geodesic import GeodesicGrid, geodesic_grid
from np_sim.scene import Scene
from np_sim.vehicle import VehicleSpec

__all__ = ["CurriculumSchedule", "CurriculumStartSampler", "active_count"]


@dataclass(frozen=True)
class CurriculumSchedule:
    """Start-range schedule of the geodesic curriculum (paper §III-E); see the module docstring."""

    enabled: bool = True
    """False disables the curriculum: the full start range from the first episode (ablation)."""
    start_fraction: float = 0.05
    """Fraction of each scene's ordered start pool used at progress 0 (paper: 5 %)."""
    full_at_progress: float = 0.5
    """Training progress (0–1] from which the full range (fraction 1) is used."""
    mode: Literal["linear", "staged"] = "linear"
    """Ramp between start_fraction and 1: 'linear', or 'staged' in n_stages equal steps."""
    n_stages: int = 5
    """Number of equal steps of the 'staged' ramp (after the first stage at start_fraction)."""

    def __post_init__(self) -> None:
        if not isinstance(self.enabled, bool):
            raise ConfigError(f"CurriculumSchedule.enabled: expected a boolean, got {self.enabled!r}")
        if not (isinstance(self.start_fraction, (int, float)) and 0.0 < self.start_fraction <= 1.0):
            raise ConfigError("CurriculumSchedule.start_fraction: expected a number in (0, 1], "
                              f"got {self.start_fraction!r}")
        if not (isinstance(self.full_at_progress, (int, float)) and 0.0 < self.full_at_progress <= 1.0):
            raise ConfigError(
                f"CurriculumSchedule.full_at_progress: expected a number in (0, 1], got {self.full_at_progress!r}")
        if self.mode not in ("linear", "staged"):
            raise ConfigError(f"CurriculumSchedule.mode: expected 'linear' or 'staged', got {self.mode!r}")
        if isinstance(self.n_stages, bool) or not isinstance(self.n_stages, int) or self.n_stages < 1:
            raise ConfigError(f"CurriculumSchedule.n_stages: expected an integer >= 1, got {self.n_stages!r}")

    def fraction(self, progress: float) -> float:
        """Start-pool fraction at training progress ``progress`` (clipped to [0, 1]); 1 when disabled."""
        if not self.enabled:
            return 1.0
        p = min(max(float(progress), 0.0), 1.0) / self.full_at_progress
        p = min(p, 1.0)
        if self.mode == "staged":
            p = math.floor(p * self.n_stages) / self.n_stages
        return float(self.start_fraction + (1.0 - self.start_fraction) * p)

    def to_dict(self) -> dict[str, Any]:
        """Plain JSON-safe dict of the fields."""
        return dataclasses.asdict(self)

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> "CurriculumSchedule":
        """Inverse of `to_dict`; an unknown key or a bad value is a ConfigError naming it."""
        return config_from_dict(cls, data)


def active_count(fraction: float, pool_size: int) -> int:
    """Number of nearest pool starts in use at ``fraction``: max(1, ceil(fraction · pool_size))."""
    return max(1, min(pool_size, math.ceil(fraction * pool_size - 1e-9)))


class CurriculumStartSampler:
    """Start sampler of the geodesic curriculum (paper §III-E), implementing the sampler protocol of
    `np_sim.starts`: ``sampler(rng, scene_indices) -> (n, 3)``. Plug it into
    ``ParkingVectorEnv(scenes, n, start_sampler=sampler)`` with the *same scene list*, and move the curriculum
    on with `set_fraction` (or `set_progress`).

    Parameters
    ----------
    scenes
        The environment's scenes (same order).
    fraction
        Initial fraction of each scene's ordered pool, in (0, 1] (paper: 0.05).
    pool_size
        Candidate starts per scene.
    seed
        Seed of the pool draw (``numpy.random.default_rng(seed)``); independent of the env's own generator,
        which only picks among the pool.
    vehicle
        Vehicle for footprint checks and the grid; default `VehicleSpec()`.
    grids
        Precomputed geodesic grids of the scenes (built when not given).
    """

    def __init__(self, scenes: Sequence[Scene], fraction: float = 0.05, pool_size: int = 256, seed: int = 0,
                 vehicle: VehicleSpec | None = None, grids: Sequence[GeodesicGrid] | None = None):
        self.scenes = list(scenes)
        if not self.scenes:
            raise ConfigError("CurriculumStartSampler: expected at least one scene, got none")
        if isinstance(pool_size, bool) or not isinstance(pool_size, (int, np.integer)) or pool_size < 1:
            raise ConfigError(f"CurriculumStartSampler: pool_size must be an integer >= 1, got {pool_size!r}")
        self.pool_size = int(pool_size)
        grids = [geodesic_grid(s, vehicle=vehicle) for s in self.scenes] if grids is None else list(grids)
        if len(grids) != len(self.scenes):
            raise ConfigError(f"CurriculumStartSampler: got {len(grids)} grids for {len(self.scenes)} scenes")
        pool = draw_frozen_starts(self.scenes, grids, n=self.pool_size, seed=seed, vehicle=vehicle)
        distance = np.stack([g.distance_at(p[:, :2]) for g, p in zip(grids, pool)])
        order = np.argsort(distance, axis=1, kind="stable")
        self.pool = np.take_along_axis(pool, order[:, :, None], axis=1)
        """(M, pool_size, 3) candidate starts per scene, nearest (geodesic) first."""
        self.distance = np.take_along_axis(distance, order, axis=1)
        """(M, pool_size) geodesic distance (m) of each pool start's cell, ascending per scene."""
        self.pool.flags.writeable = False
        self.distance.flags.writeable = False
        self._fraction = 1.0
        self.set_fraction(fraction)

    @property
    def fraction(self) -> float:
        """Current fraction of each scene's ordered pool in use."""
        return self._fraction

    @property
    def n_active(self) -> int:
        """Number of nearest pool starts per scene in use (`active_count`)."""
        return active_count(self._fraction, self.pool_size)

    def set_fraction(self, fraction: float) -> None:
        """Use the nearest ``fraction`` ∈ (0, 1] of each scene's pool from the next reset on."""
        if isinstance(fraction, bool) or not isinstance(fraction, (int, float)) or not 0.0 < fraction <= 1.0:
            raise ConfigError(f"CurriculumStartSampler.set_fraction: expected a number in (0, 1], got {fraction!r}")
        self._fraction = float(fraction)

    def set_progress(self, progress: float, schedule: CurriculumSchedule) -> float:
        """Set the fraction ``schedule.fraction(progress)``; returns it."""
        self.set_fraction(schedule.fraction(progress))
        return self._fraction

    def __call__(self, rng: np.random.Generator, scene_indices) -> np.ndarray:
        """(n, 3) starts: for each requested scene, one uniform pick among its `n_active` nearest pool starts."""
        idx = np.atleast_1d(np.asarray(scene_indices, np.int64))
        if len(idx) and (idx.min() < 0 or idx.max() >= len(self.scenes)):
            raise ConfigError(f"CurriculumStartSampler: scene index out of range [0, {len(self.scenes)}): "
                              f"{idx.tolist()}")
        picks = rng.integers(self.n_active, size=len(idx))
        return self.pool[idx, picks].copy()
