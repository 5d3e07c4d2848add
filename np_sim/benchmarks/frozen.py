"""The versioned benchmark files, their frozen evaluation starts, and the build loop both generators share
(paper §IV-A and the evaluation protocol of §III, spec §4.3, §10).

**Files.** ``np_sim/benchmarks/data/<name>_v1.json`` holds one benchmark: the generator parameters, the
rejection counts of the generation, the training and test scenes (`Scene.to_dict`, world frame) and, for each
test scene in order, its 40 frozen starts. The text is deterministic — keys sorted, one scene (or one scene's
starts) per line, Python's shortest float repr, scene coordinates rounded to millimetres — so regenerating
from the fixed seeds reproduces it byte for byte (``python -m np_sim.benchmarks.generate --check``).

**Frozen starts** (paper §III "one fixed full-range start protocol"): one ``numpy.random.default_rng(0)``
(sampling seed 0) and one full-range `UniformStartSampler` over the test scenes (uniform position in the start
region, uniform heading, footprint-free; block 32). For each test scene k in order: draw ``40 − kept`` poses for
scene k, keep in draw order those whose 1.5 m geodesic-grid cell is reachable from the target (the connected
start check), repeat until 40 are kept. No distance rejection or banding: the regime lives in the start region.
The poses are stored in the world frame (the scenes' frames are fixed, so they are the same target-relative
poses for every method); 27 × 40 = 1080 Factorial and 18 × 40 = 720 Topology-Stress episodes.
"""

from __future__ import annotations

import functools
import json
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from np_sim.benchmarks.common import DraftRejected
from np_sim.benchmarks.layout import hausdorff, layout_points
from np_sim.benchmarks.validity import (
    CHECK_NAMES,
    ValidityConfig,
    check_connected_start,
    check_object_capacity,
    check_target_validity,
    first_failure,
    reachable,
    run_checks,
)
from np_sim.errors import ConfigError, SceneError
from np_sim.geodesic import GeodesicGrid, geodesic_grid
from np_sim.scene import Scene, SceneCapacity
from np_sim.starts import UniformStartSampler
from np_sim.vehicle import VehicleSpec

BENCHMARK_NAMES = ("factorial", "topology")
"""Names accepted by `load_benchmark` and `frozen_starts`."""
SPLITS = ("train", "test")
"""Splits accepted by `load_benchmark`."""
FORMAT_VERSION = 1
"""Version of the benchmark file format (and the ``_v1`` in the file names)."""
STARTS_PER_SCENE = 40
"""Frozen starts per test scene."""
SAMPLING_SEED = 0
"""Seed of the frozen-start generator (independent of every training seed)."""
VALIDATION_SEED = 1
"""Seed of the validation starts on the training scenes (`validation_starts`)."""
VALIDATION_STARTS_PER_SCENE = 10
"""Validation starts per training scene by default."""
DATA_DIR = Path(__file__).resolve().parent / "data"
"""Where the shipped benchmark files live."""


def benchmark_path(name: str, data_dir: str | Path | None = None) -> Path:
    """Path of benchmark ``name``'s file (``<name>_v1.json``) in ``data_dir`` (default: the shipped data)."""
    _check_name(name, "benchmark_path")
    return Path(DATA_DIR if data_dir is None else data_dir) / f"{name}_v{FORMAT_VERSION}.json"


def _check_name(name: str, where: str) -> None:
    if name not in BENCHMARK_NAMES:
        raise ConfigError(f"{where}: unknown benchmark {name!r}; expected one of "
                          f"{', '.join(map(repr, BENCHMARK_NAMES))}")


# ---------------------------------------------------------------------------------------------- frozen starts


def draw_frozen_starts(scenes: Sequence[Scene], grids: Sequence[GeodesicGrid] | None = None,
                       n: int = STARTS_PER_SCENE, seed: int = SAMPLING_SEED, vehicle: VehicleSpec | None = None,
                       max_rounds: int = 10_000) -> np.ndarray:
    """(len(scenes), n, 3) frozen starts, drawn as the module docstring says (paper §III evaluation protocol).

    ``grids`` are the scenes' geodesic grids (built when not given); raises RuntimeError when a scene cannot
    yield ``n`` reachable starts.
    """
    scenes = list(scenes)
    grids = [geodesic_grid(s, vehicle=vehicle) for s in scenes] if grids is None else list(grids)
    sampler = UniformStartSampler(scenes, vehicle)
    rng = np.random.default_rng(seed)
    out = np.zeros((len(scenes), n, 3))
    for k, grid in enumerate(grids):
        kept = 0
        for _ in range(max_rounds):
            if kept == n:
                break
            poses = sampler(rng, np.full(n - kept, k))
            ok = poses[reachable(grid, poses[:, :2])]
            out[k, kept: kept + len(ok)] = ok
            kept += len(ok)
        if kept < n:
            raise RuntimeError(f"draw_frozen_starts: scene {scenes[k].name!r} gave only {kept} reachable starts")
    return out


# ---------------------------------------------------------------------------------------------- build loop


@dataclass(frozen=True, eq=False)
class BenchmarkBuild:
    """A generated benchmark, ready to be written (`benchmark_json`)."""

    name: str
    """Benchmark name (`BENCHMARK_NAMES`)."""
    generator: dict
    """The generator's parameters (JSON-safe), stored in the file."""
    train: tuple[Scene, ...]
    """Training scenes, cell by cell."""
    test: tuple[Scene, ...]
    """Test scenes, cell by cell."""
    frozen_starts: np.ndarray
    """(n_test, 40, 3) frozen starts, world frame."""
    rejections: dict
    """Rejected draws per reason: the four checks, the generator's own checks, ``disjointness``."""
    nearest_train_m: np.ndarray
    """Per test scene, layout distance to the nearest training scene of its cell (m)."""
    floor_m: float
    """Documented disjointness floor the generation enforced (m)."""


def build_benchmark(name: str, cells: Sequence[Any], draft: Callable[[Any, int, str, int], Scene],
                    layout_seed: Callable[[int, int, int], int], n_train: int, n_test: int,
                    validity: ValidityConfig, floor_m: float, max_attempts: int, generator: dict,
                    extra_checks: Sequence[tuple[str, Callable[[Scene, GeodesicGrid], str | None]]] = (),
                    on_scene: Callable[[Scene], None] | None = None,
                    vehicle: VehicleSpec | None = None) -> BenchmarkBuild:
    """Generate every scene of a benchmark with validity checks, regeneration and the disjointness floor
    (paper §IV-A), then draw the frozen starts of the test split.

    For each cell (in order), ``n_train`` training then ``n_test`` test scenes: draw ``attempt = 0, 1, …`` with
    ``draft(cell, layout_seed(cell_index, slot, attempt), split, index)`` until a draw passes the four checks
    (`run_checks`), every ``extra_checks`` entry (``(counter name, check)``, a check returning a reason or None)
    and lies at least ``floor_m`` (layout distance) from every scene already accepted in its cell. Every rejected
    draw increments its counter. ``on_scene`` is called with each accepted scene (progress bars).
    """
    rejections = {key: 0 for key in (*CHECK_NAMES, *(k for k, _ in extra_checks), "disjointness")}
    train: list[Scene] = []
    test: list[Scene] = []
    test_grids: list[GeodesicGrid] = []
    nearest: list[float] = []
    for c_index, cell in enumerate(cells):
        accepted: list[tuple[str, np.ndarray]] = []
        slots = [("train", i, i) for i in range(n_train)] + [("test", i, n_train + i) for i in range(n_test)]
        for split, index, slot in slots:
            for attempt in range(max_attempts):
                try:
                    scene = draft(cell, layout_seed(c_index, slot, attempt), split, index)
                except DraftRejected as rejected:
                    rejections[rejected.check] = rejections.get(rejected.check, 0) + 1
                    continue
                failed = first_failure([check_target_validity(scene, vehicle),
                                        check_object_capacity(scene, validity.capacity)])
                if failed is None:
                    grid = geodesic_grid(scene, cell_m=validity.cell_m, vehicle=vehicle)
                    failed = first_failure(run_checks(scene, validity, grid=grid, vehicle=vehicle))
                if failed is not None:
                    rejections[failed.name] += 1
                    continue
                reason = None
                for key, check in extra_checks:
                    if check(scene, grid) is not None:
                        reason = key
                        break
                if reason is not None:
                    rejections[reason] += 1
                    continue
                points = layout_points(scene)
                distances = [hausdorff(points, p) for _, p in accepted]
                if distances and min(distances) < floor_m:
                    rejections["disjointness"] += 1
                    continue
                if split == "test":
                    train_d = [d for (s, _), d in zip(accepted, distances) if s == "train"]
                    nearest.append(min(train_d) if train_d else float("inf"))
                    test.append(scene)
                    test_grids.append(grid)
                else:
                    train.append(scene)
                accepted.append((split, points))
                if on_scene is not None:
                    on_scene(scene)
                break
            else:
                raise RuntimeError(f"{name}: no valid scene for cell {getattr(cell, 'name', cell)!r} {split} "
                                   f"#{index} in {max_attempts} attempts (rejections so far: {rejections})")
    starts = draw_frozen_starts(test, test_grids, vehicle=vehicle)
    for scene, grid, s in zip(test, test_grids, starts):
        result = check_connected_start(scene, grid, validity, s)
        if not result.passed:
            raise RuntimeError(f"{name}: frozen starts of {scene.name} fail the connected-start check: {result.detail}")
    return BenchmarkBuild(name, generator, tuple(train), tuple(test), starts, rejections, np.array(nearest), floor_m)


# ---------------------------------------------------------------------------------------------- file I/O


def benchmark_document(build: BenchmarkBuild) -> dict:
    """The JSON object of a benchmark file (see the module docstring)."""
    return {
        "benchmark": build.name,
        "format_version": FORMAT_VERSION,
        "generator": build.generator,
        "generation": {
            "rejections": dict(build.rejections),
            "disjointness_floor_m": float(build.floor_m),
            "min_test_to_train_layout_distance_m": round(float(build.nearest_train_m.min()), 6),
        },
        "sampling": {
            "seed": SAMPLING_SEED,
            "starts_per_scene": STARTS_PER_SCENE,
            "protocol": "UniformStartSampler (block 32) over the test scenes, one default_rng(seed), scene by scene "
                        "in order; footprint-free, start cell reachable on the 1.5 m geodesic grid",
        },
        "train": [s.to_dict() for s in build.train],
        "test": [s.to_dict() for s in build.test],
        "frozen_starts": [[[float(v) for v in pose] for pose in scene_starts] for scene_starts in build.frozen_starts],
    }


def benchmark_json(build: BenchmarkBuild) -> str:
    """Deterministic text of a benchmark file: sorted keys, one list item (scene, starts of a scene) per line."""
    doc = benchmark_document(build)
    keys = sorted(doc)
    lines = ["{"]
    for i, key in enumerate(keys):
        value, comma = doc[key], ("," if i < len(keys) - 1 else "")
        if isinstance(value, list) and value and isinstance(value[0], (dict, list)):
            lines.append(f" {json.dumps(key)}: [")
            for j, item in enumerate(value):
                sep = "," if j < len(value) - 1 else ""
                lines.append("  " + json.dumps(item, sort_keys=True, separators=(",", ":"), allow_nan=False) + sep)
            lines.append(" ]" + comma)
        else:
            lines.append(f" {json.dumps(key)}: {json.dumps(value, sort_keys=True, allow_nan=False)}{comma}")
    lines.append("}")
    return "\n".join(lines) + "\n"


@functools.lru_cache(maxsize=8)
def _read(path: str, mtime_ns: int) -> tuple[dict, dict[str, tuple[Scene, ...]], np.ndarray]:
    """Parsed, validated content of a benchmark file (cached per path and modification time)."""
    try:
        doc = json.loads(Path(path).read_text(encoding="utf-8"))
    except json.JSONDecodeError as error:
        raise SceneError(f"{path}: invalid JSON at line {error.lineno}, column {error.colno}: {error.msg}") from None
    for key in ("benchmark", "format_version", "train", "test", "frozen_starts"):
        if key not in doc:
            raise SceneError(f"{path}: {key}: missing required field")
    if doc["format_version"] != FORMAT_VERSION:
        raise SceneError(f"{path}: format_version: expected {FORMAT_VERSION}, got {doc['format_version']!r}")
    scenes = {
        split: tuple(Scene.from_dict(d, source=f"{path}: {split}[{i}]", capacity=SceneCapacity())
                     for i, d in enumerate(doc[split]))
        for split in SPLITS
    }
    starts = np.array(doc["frozen_starts"], dtype=np.float64)
    if starts.shape != (len(scenes["test"]), STARTS_PER_SCENE, 3):
        raise SceneError(f"{path}: frozen_starts: expected shape ({len(scenes['test'])}, {STARTS_PER_SCENE}, 3), "
                         f"got {starts.shape}")
    starts.flags.writeable = False
    return doc, scenes, starts


def read_benchmark_file(name: str, data_dir: str | Path | None = None
                        ) -> tuple[dict, dict[str, tuple[Scene, ...]], np.ndarray]:
    """(document, scenes per split, frozen starts) of benchmark ``name`` (validated; errors name the file)."""
    path = benchmark_path(name, data_dir)
    if not path.exists():
        raise FileNotFoundError(f"{path}: benchmark file missing; run `python -m np_sim.benchmarks.generate "
                                f"--benchmark {name}` to create it")
    return _read(str(path), path.stat().st_mtime_ns)


def load_benchmark(name: str, split: str, data_dir: str | Path | None = None) -> list[Scene]:
    """The scenes of benchmark ``name`` ("factorial" | "topology") and ``split`` ("train" | "test"), in the
    benchmark's cell order (spec §10; paper §IV-A). Each is validated against `SceneCapacity()` on load.

    Raises
    ------
    ConfigError
        For an unknown benchmark or split, listing the valid ones.
    """
    _check_name(name, "load_benchmark")
    if split not in SPLITS:
        raise ConfigError(f"load_benchmark: unknown split {split!r}; expected one of {', '.join(map(repr, SPLITS))}")
    return list(read_benchmark_file(name, data_dir)[1][split])


def validation_starts(name: str, per_scene: int = VALIDATION_STARTS_PER_SCENE, seed: int = VALIDATION_SEED,
                      vehicle: VehicleSpec | None = None) -> np.ndarray:
    """(n_train_scenes, per_scene, 3) starts on the **training** scenes of benchmark ``name``, row k for training
    scene k of `load_benchmark(name, "train")`, drawn by the frozen-start protocol (`draw_frozen_starts`) with its
    own seed: the validation set on which a recipe, threshold or checkpoint may be chosen, since the frozen test
    starts may not be looked at for that (paper §III evaluation protocol; the training itself samples its own
    starts). Deterministic for a given seed; about a second per scene to build the geodesic grids."""
    _check_name(name, "validation_starts")
    if per_scene < 1:
        raise ConfigError(f"validation_starts: per_scene must be a positive integer, got {per_scene!r}")
    return draw_frozen_starts(load_benchmark(name, "train"), n=per_scene, seed=seed, vehicle=vehicle)


def held_out(n_scenes: int, every: int) -> np.ndarray:
    """Indices of the training scenes a run trained with ``TrainConfig.holdout_every = every`` leaves out: every
    ``every``-th scene (``every − 1``, ``2·every − 1``, …), so with the benchmarks' cell-by-cell scene order each
    cell loses the same share (Topology-Stress, 8 scenes per cell, ``every`` 4: two per cell, 12 of 48). Empty for
    ``every`` 0."""
    if every < 0 or every == 1:
        raise ConfigError(f"holdout_every: expected 0 (none) or an integer >= 2, got {every!r}")
    return np.arange(every - 1, n_scenes, every) if every else np.zeros(0, int)


def split_episodes(name: str, split: str = "test", per_scene: int = VALIDATION_STARTS_PER_SCENE,
                   vehicle: VehicleSpec | None = None, holdout_every: int = 0) -> tuple[list[Scene], np.ndarray]:
    """(scenes, (n_scenes, n, 3) starts) of benchmark ``name``: ``split`` 'test' gives the test scenes and their
    frozen starts, 'validation' the training scenes and their `validation_starts` (``per_scene`` each), 'holdout'
    only the training scenes `held_out` by ``holdout_every`` with the same validation starts."""
    if split == "test":
        return load_benchmark(name, "test"), frozen_starts(name)
    if split not in ("validation", "holdout"):
        raise ConfigError(f"split_episodes: unknown split {split!r}; expected 'test', 'validation' or 'holdout'")
    scenes, starts = load_benchmark(name, "train"), validation_starts(name, per_scene, vehicle=vehicle)
    if split == "validation":
        return scenes, starts
    if not holdout_every:
        raise ConfigError("split_episodes: the 'holdout' split needs checkpoints trained with "
                          "TrainConfig.holdout_every >= 2 (their held-out training scenes)")
    keep = held_out(len(scenes), holdout_every)
    return [scenes[k] for k in keep], starts[keep]


def frozen_starts(name: str, data_dir: str | Path | None = None) -> np.ndarray:
    """(n_test_scenes, 40, 3) frozen evaluation starts of benchmark ``name``, world frame, row k for test scene k
    of `load_benchmark(name, "test")` (spec §4.3, §10; paper §III evaluation protocol). A fresh writable copy.

    Raises
    ------
    ConfigError
        For an unknown benchmark name, listing the valid ones.
    """
    _check_name(name, "frozen_starts")
    return np.array(read_benchmark_file(name, data_dir)[2])
