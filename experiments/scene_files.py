"""Episodes from the user's own scene files, shared by the experiment CLIs (``--scenes FILE... [--starts N]
[--seed S]``).

Each file is a scene in the project's JSON format (`np_sim.scene`, schema ``np_sim/data/scene.schema.json``). Its
starts are the file's explicit ``starts`` when it lists some, else ``--starts N`` drawn from its start region and
heading range with ``--seed S`` (`np_sim.scene_starts`), rejecting starts in collision under the strictest
convention of the planners run (footprint when any plans under it): the same file, N and seed always give the same
starts. Records name the file and the start pose (`scene_columns`); ``config.json`` says where each file's starts
came from and how many drawn ones were rejected (`describe`).

``load_scene_files(paths, n_starts, seed, convention, vehicle)`` is the one call an experiment needs: it returns one
`SceneFile` (path, validated scene, starts) per path.
"""

from __future__ import annotations

import argparse
import dataclasses
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from np_sim.benchmarks.frozen import VALIDATION_STARTS_PER_SCENE, split_episodes
import np_sim.examples
from np_sim.cli import non_negative_int, positive_int
from np_sim.config import Convention
from np_sim.errors import ConfigError
from np_sim.scene import Scene
from np_sim.scene_starts import SceneStarts, scene_starts
from np_sim.vehicle import VehicleSpec


@dataclass(frozen=True)
class SceneFile:
    """One user scene file with its starts."""

    path: Path
    """The JSON file."""
    scene: Scene
    """The validated scene (for the vehicle it was loaded for)."""
    starts: SceneStarts
    """Its start poses: the file's, or drawn from its start region."""


def strictest(conventions: Iterable[str]) -> Convention:
    """'footprint' when any of ``conventions`` is (a footprint-free start is free under both), else
    'reference_point'."""
    return "footprint" if "footprint" in set(conventions) else "reference_point"


def load_scene_files(paths: Iterable[Path], n_starts: int | None = None, seed: int = 0,
                     convention: Convention = "footprint", vehicle: VehicleSpec | None = None) -> list[SceneFile]:
    """Load and validate every file for ``vehicle`` and resolve its starts (module docstring); SceneError naming
    the file on a bad scene or start, ConfigError on two files with one scene name (records key on it)."""
    files = []
    for path in paths:
        scene = Scene.load(path, vehicle=vehicle)
        if not scene.name:
            scene = dataclasses.replace(scene, name=Path(path).stem)
        starts = scene_starts(scene, n_starts, seed, convention, vehicle, source=str(path))
        files.append(SceneFile(Path(path), scene, starts))
    names = [f.scene.name for f in files]
    twice = sorted({n for n in names if names.count(n) > 1})
    if twice:
        raise ConfigError(f"--scenes: scene name(s) {twice} appear in more than one file; records key on the name, "
                          "so give each scene its own \"name\"")
    return files


def episode_scenes(benchmark: str, files: list[SceneFile] | None, split: str = "test",
                   starts_per_scene: int = VALIDATION_STARTS_PER_SCENE, vehicle: VehicleSpec | None = None,
                   holdout_every: int = 0) -> tuple[list[Scene], list[np.ndarray]]:
    """(scenes, per-scene (n, 3) starts): the scene files' when given, else the benchmark's ``split``
    (`np_sim.benchmarks.frozen.split_episodes`: the test scenes and frozen starts, or the validation starts on the
    training scenes, or on those ``holdout_every`` left out)."""
    if files:
        return [f.scene for f in files], [f.starts.poses for f in files]
    scenes, starts = split_episodes(benchmark, split, starts_per_scene, vehicle, holdout_every)
    return scenes, list(starts)


def common_holdout(values: dict[str, int]) -> int:
    """The ``holdout_every`` all the checkpoints named in ``values`` (path → its value) were trained with, for
    ``--split holdout``; ConfigError naming them when there are none, they differ or none left scenes out."""
    if not values or len(set(values.values())) != 1 or next(iter(values.values())) < 2:
        raise ConfigError("--split holdout: the checkpoints must all have been trained with the same "
                          f"holdout_every >= 2 (TrainConfig or HopeTrainConfig), got {values or 'no checkpoint'}")
    return next(iter(values.values()))


SPLIT_HELP = {"test": "the frozen test starts (default)",
              "validation": "seeded starts on the training scenes (np_sim.benchmarks.validation_starts), where "
                            "choices may be made",
              "holdout": "the same starts on only the training scenes the checkpoints were trained without "
                         "(TrainConfig.holdout_every)"}


def add_split_arguments(parser: argparse.ArgumentParser, splits: tuple[str, ...] = ("test", "validation")) -> None:
    """``--split`` (one of ``splits``) and ``--starts-per-scene N`` (`np_sim.benchmarks.frozen.split_episodes`)."""
    parser.add_argument("--split", choices=splits, default="test",
                        help="; ".join(f"{name}: {SPLIT_HELP[name]}" for name in splits))
    parser.add_argument("--starts-per-scene", type=positive_int, default=VALIDATION_STARTS_PER_SCENE, metavar="N",
                        help=f"validation starts per training scene (--split validation or holdout; default "
                             f"{VALIDATION_STARTS_PER_SCENE})")


def scene_columns(files: list[SceneFile] | None, k: int, j: int) -> dict[str, Any]:
    """The record columns naming scene file ``k`` and its start ``j`` (none for benchmark episodes)."""
    if not files:
        return {}
    x, y, theta = (float(v) for v in files[k].starts.poses[j])
    return {"scene_file": str(files[k].path), "start_source": files[k].starts.source, "start_x": x, "start_y": y,
            "start_theta": theta}


def describe(files: list[SceneFile] | None) -> list[dict[str, Any]] | None:
    """For ``config.json``: per file its path, scene name, start source, count, rejected draws and convention."""
    if not files:
        return None
    return [{"path": str(f.path), "scene": f.scene.name, "starts": f.starts.source, "n_starts": len(f.starts.poses),
             "rejected_in_collision": f.starts.rejected, "convention": f.starts.convention} for f in files]


def starts_summary(files: list[SceneFile] | None) -> str:
    """One line per file: where its starts came from and how many drawn ones were rejected."""
    lines = []
    for f in files or ():
        how = ("from the file" if f.starts.source == "file" else
               f"drawn from the start region ({f.starts.rejected} rejected in collision under the "
               f"{f.starts.convention} convention)")
        lines.append(f"{f.path}: {len(f.starts.poses)} starts {how}")
    return "\n".join(lines)


EXAMPLES = Path(np_sim.examples.__file__).parent
"""Folder of the shipped example scenes (``*.json`` and ``lots/*.json``)."""


def scene_file(text: str) -> Path:
    """Argument type: an existing scene file, or the name of a shipped example scene (``own_lot``,
    ``reverse_bay`` …, looked up in ``np_sim/examples`` and its ``lots`` folder)."""
    path = Path(text)
    if path.is_file():
        return path
    shipped = {p.stem: p for p in sorted([*EXAMPLES.glob("*.json"), *EXAMPLES.glob("lots/*.json")])}
    if text in shipped and not path.exists():
        return shipped[text]
    if path.exists():
        raise argparse.ArgumentTypeError(f"expected a scene file, got the folder {text}")
    raise argparse.ArgumentTypeError(f"no such file: {text} (nor a shipped example scene: {', '.join(shipped)})")


def add_scene_arguments(parser: argparse.ArgumentParser) -> None:
    """``--scenes FILE...``, ``--starts N`` and ``--seed S`` (module docstring)."""
    parser.add_argument("--scenes", nargs="+", type=scene_file, metavar="FILE",
                        help="your own scene JSON files instead of the benchmark (np_sim/data/scene.schema.json) "
                             "or names of shipped example scenes (own_lot); starts from each file, or --starts N "
                             "drawn from its start region")
    parser.add_argument("--starts", type=positive_int, metavar="N",
                        help="with --scenes: starts drawn from the start region of each file that lists none")
    parser.add_argument("--seed", type=non_negative_int, default=0,
                        help="with --scenes: seed of the drawn starts (default 0)")
