"""Factorial Parking Benchmark (paper §IV-A, spec §4.1): counts, the four checks, regimes, byte-exact regeneration."""

import math
from collections import Counter

import numpy as np
import pytest

from np_sim.benchmarks import frozen_starts, load_benchmark
from np_sim.benchmarks.factorial import (
    DIFFICULTIES,
    DISTANCES,
    PARKING_TYPES,
    FactorialCell,
    FactorialConfig,
    distance_band_check,
    factorial_cells,
    factorial_scene,
    generate_factorial,
)
from np_sim.benchmarks.frozen import benchmark_json, benchmark_path
from np_sim.benchmarks.validity import CHECK_NAMES, run_checks
from np_sim.errors import ConfigError
from np_sim.geodesic import geodesic_grid
from np_sim.scene import SceneCapacity

TAGS = {"benchmark", "split", "distance", "type", "difficulty", "cell", "layout_seed"}


@pytest.fixture(scope="module")
def scenes():
    return {split: load_benchmark("factorial", split) for split in ("train", "test")}


@pytest.fixture(scope="module")
def test_grids(scenes):
    return [geodesic_grid(s) for s in scenes["test"]]


def test_counts_per_split_and_cell(scenes):
    assert len(scenes["train"]) == 81 and len(scenes["test"]) == 27
    cells = {c.name for c in factorial_cells()}
    assert len(cells) == 27
    assert Counter(s.tags["cell"] for s in scenes["train"]) == {c: 3 for c in cells}
    assert Counter(s.tags["cell"] for s in scenes["test"]) == {c: 1 for c in cells}
    for split, group in scenes.items():
        for s in group:
            assert TAGS <= set(s.tags) and s.tags["benchmark"] == "factorial" and s.tags["split"] == split
            assert s.tags["cell"] == f"{s.tags['distance']}-{s.tags['type']}-{s.tags['difficulty']}"
            assert s.tags["distance"] in DISTANCES and s.tags["type"] in PARKING_TYPES
            assert s.tags["difficulty"] in DIFFICULTIES
    names = [s.name for g in scenes.values() for s in g]
    assert len(set(names)) == len(names)


def test_every_scene_fits_capacity_and_passes_the_four_checks(scenes):
    for group in scenes.values():
        for s in group:
            s.validate(capacity=SceneCapacity())
            assert len(s.obstacles) <= 20 and len(s.boundary) <= 10
            results = run_checks(s, stop_at_first=False)
            assert [r.name for r in results] == list(CHECK_NAMES)
            assert all(r.passed for r in results), (s.name, [r.detail for r in results if not r.passed])


def test_start_regions_sit_in_their_regime_band(scenes, test_grids):
    for s, g in zip(scenes["test"], test_grids):
        assert distance_band_check(s, g) is None, s.name
    starts = frozen_starts("factorial")
    medians = {}
    for d in DISTANCES:
        rows = [k for k, s in enumerate(scenes["test"]) if s.tags["distance"] == d]
        dist = np.concatenate([test_grids[k].distance_at(starts[k, :, :2]) for k in rows])
        assert np.all(np.isfinite(dist))
        medians[d] = float(np.median(dist))
    assert 5.0 < medians["near"] < 12.0 < medians["medium"] < 22.0 < medians["long"] < 40.0


def test_target_headings_follow_the_parking_type(scenes):
    for s in scenes["train"] + scenes["test"]:
        th = float(s.target[2])
        if s.tags["type"] == "reverse":  # out of the bay, away from the kerb at y = 0
            assert th == pytest.approx(math.pi / 2)
        elif s.tags["type"] == "lateral":  # along the kerb
            assert min(abs(th), abs(abs(th) - math.pi)) < 1e-9


def test_unknown_cell_is_a_config_error():
    with pytest.raises(ConfigError, match="unknown cell"):
        factorial_scene(FactorialCell("far", "reverse", "easy"), 0, "train", 0)


def test_regeneration_reproduces_the_shipped_file_byte_for_byte():
    build = generate_factorial()
    assert benchmark_json(build).encode("utf-8") == benchmark_path("factorial").read_bytes()
    assert set(CHECK_NAMES) <= set(build.rejections)
    # each accepted scene's layout_seed ends in its attempt number (layout_seed_of) and every earlier attempt of
    # its slot was rejected exactly once: the counters must add up to the attempts the tags record
    attempts = sum(s.tags["layout_seed"] % 1000 for s in build.train + build.test)
    assert attempts > 0 and sum(build.rejections.values()) == attempts
    assert build.nearest_train_m.min() >= FactorialConfig().disjointness_floor_m
