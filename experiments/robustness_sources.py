"""What the robustness study (`experiments.robustness`) drives: the site clips in the closed loop of the main job,
or frozen-start episodes (a benchmark's test starts or your own scene files) planned once and tracked in MuJoCo.

A source is built from a picklable spec (`ClosedLoopConfig` for the clips, `StartSpec` for the episodes), so every
Ray worker rebuilds the same one; its ``units`` are the names of what it runs (clip names, or
``<scene>#<start>``), ``key`` the record column that holds them.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from experiments.closed_loop import ClosedLoopConfig, clip_indices, clip_rows, disturbed, split_clips
from experiments.common import first
from experiments.registry import PlannerOptions
from experiments.scene_files import episode_scenes, load_scene_files, scene_columns
from tracking.config import TrackerConfig
from tracking.disturbance import Disturbance


def disturbance_at(factor: str, level: str, seed: int) -> Disturbance | None:
    """The disturbance of (``factor``, ``level``), None for the undisturbed run ('none')."""
    return None if factor == "none" else Disturbance.at(factor, level, seed)


class ClipSource:
    """The site clips of ``loop`` (its split and selection), each driven as the main job does."""

    key = "clip"
    noun = "clip"

    def __init__(self, loop: ClosedLoopConfig):
        self.loop = loop
        every = split_clips(loop.split)
        self.clips = [every[k] for k in clip_indices(every, loop)]
        self.units = [c.name for c in self.clips]
        self.options = loop.planner

    def rows(self, unit: int, planners: dict[str, Any], factor: str, level: str, seed: int) -> list[dict]:
        """One record row per planner of clip ``unit`` under ``factor`` at ``level``."""
        return clip_rows(self.clips[unit], planners, self.loop.controller, None, False, self.loop.clip_run,
                         disturbance_at(factor, level, seed))

    def record(self, unit: int, planner, factor: str, level: str, seed: int, path: Path) -> None:
        """Drive clip ``unit`` again with a Rerun recording at ``path``."""
        from tracking.clip_run import run_clip

        disturbance = disturbance_at(factor, level, seed)
        run_clip(self.clips[unit], planner, self.loop.controller, config=disturbed(self.loop.clip_run, disturbance),
                 rerun_path=path, disturbance=disturbance)


@dataclass(frozen=True)
class StartSpec:
    """Frozen-start episodes: a benchmark's test starts, or scene files with their own or drawn starts."""

    options: PlannerOptions
    """The planners' checkpoints, convention, vehicle and benchmark."""
    benchmark: str = "factorial"
    scenes: tuple[Path, ...] = ()
    """Scene files instead of the benchmark (`experiments.scene_files`)."""
    n_starts: int | None = None
    """Starts drawn from each file's start region (files without explicit starts)."""
    starts_seed: int = 0
    per_scene: int | None = None
    """Only the first K starts of every scene."""
    limit: int | None = None
    """Only the first N episodes in scene order."""
    controller: str = "lqr"


class StartSource:
    """The episodes of a `StartSpec`, each planned once and tracked (`tracking.episode_run`)."""

    key = "episode"
    noun = "episode"

    def __init__(self, spec: StartSpec):
        self.spec = spec
        self.options = spec.options
        files = load_scene_files(spec.scenes, spec.n_starts, spec.starts_seed, spec.options.convention,
                                 spec.options.vehicle) if spec.scenes else None
        self.files = files
        self.scenes, self.starts = episode_scenes(spec.benchmark, files)
        pairs = [(k, j) for k in range(len(self.scenes))
                 for j in first(range(len(self.starts[k])), spec.per_scene, "--per-scene")]
        self.episodes = first(pairs, spec.limit)
        self.units = [f"{self.scenes[k].name}#{j:02d}" for k, j in self.episodes]
        self.tracker = dataclasses.replace(TrackerConfig(), vehicle=spec.options.vehicle)

    def rows(self, unit: int, planners: dict[str, Any], factor: str, level: str, seed: int) -> list[dict]:
        """One record row per planner of episode ``unit`` under ``factor`` at ``level``."""
        from tracking.episode_run import episode_columns, run_episode

        k, j = self.episodes[unit]
        head = {"episode": self.units[unit], "scene": self.scenes[k].name, "start_id": j,
                **scene_columns(self.files, k, j)}
        disturbance = disturbance_at(factor, level, seed)
        return [{**head, "planner": name,
                 **episode_columns(run_episode(self.scenes[k], self.starts[k][j], planner, self.spec.controller,
                                               self.tracker, disturbance, self.units[unit]))}
                for name, planner in planners.items()]

    def record(self, unit: int, planner, factor: str, level: str, seed: int, path: Path) -> None:
        """Drive episode ``unit`` again with a Rerun recording at ``path``."""
        from tracking.episode_run import run_episode

        k, j = self.episodes[unit]
        run_episode(self.scenes[k], self.starts[k][j], planner, self.spec.controller, self.tracker,
                    disturbance_at(factor, level, seed), self.units[unit], rerun_path=path)


def build_source(spec: ClosedLoopConfig | StartSpec) -> ClipSource | StartSource:
    """The source a spec describes."""
    return ClipSource(spec) if isinstance(spec, ClosedLoopConfig) else StartSource(spec)
