"""Frozen evaluation starts and benchmark files (spec §4.3, §10): shapes, validity, seed-0 protocol, errors, CLIs."""

import numpy as np
import pytest
from shapely.geometry import Point
from shapely.geometry import Polygon as ShapelyPolygon

from np_sim.benchmarks import BENCHMARK_NAMES, frozen_starts, load_benchmark, validation_starts
from np_sim.benchmarks import __main__ as bench_cli
from np_sim.benchmarks import generate as generate_cli
from np_sim.benchmarks.frozen import (
    BenchmarkBuild,
    benchmark_json,
    benchmark_path,
    draw_frozen_starts,
    held_out,
    read_benchmark_file,
    split_episodes,
)
from np_sim.collision import path_valid
from np_sim.errors import ConfigError
from np_sim.geodesic import geodesic_grid


@pytest.mark.parametrize("name, shape", [("factorial", (27, 40, 3)), ("topology", (18, 40, 3))])
def test_frozen_start_shapes_and_episode_counts(name, shape):
    starts = frozen_starts(name)
    assert starts.shape == shape and starts.dtype == np.float64
    assert len(load_benchmark(name, "test")) == shape[0]
    starts[0, 0, 0] = 1e9  # a copy: the shipped starts are untouched
    assert frozen_starts(name)[0, 0, 0] != 1e9


@pytest.mark.parametrize("name", BENCHMARK_NAMES)
def test_every_frozen_start_is_footprint_free_inside_its_region_and_connected(name):
    scenes, starts = load_benchmark(name, "test"), frozen_starts(name)
    for scene, poses in zip(scenes, starts):
        assert path_valid(scene, poses, convention="footprint")
        assert all(path_valid(scene, p[None], convention="footprint") for p in poses)
        region = ShapelyPolygon(scene.start_region)
        assert all(region.contains(Point(p[:2])) for p in poses)
        assert np.all(np.isfinite(geodesic_grid(scene).distance_at(poses[:, :2])))
        assert np.all((poses[:, 2] >= -np.pi) & (poses[:, 2] < np.pi))
        assert np.ptp(poses[:, 2]) > 3.0  # uniform headings


def test_frozen_starts_follow_the_seed_0_protocol():
    scenes = load_benchmark("topology", "test")
    np.testing.assert_array_equal(draw_frozen_starts(scenes, seed=0), frozen_starts("topology"))
    assert not np.array_equal(draw_frozen_starts(scenes[:2], seed=1), frozen_starts("topology")[:2])


def test_validation_starts_lie_on_the_training_scenes_seeded_apart_from_the_frozen_ones():
    train = load_benchmark("topology", "train")
    starts = validation_starts("topology", per_scene=3)
    assert starts.shape == (len(train), 3, 3)
    np.testing.assert_array_equal(starts, validation_starts("topology", per_scene=3))  # deterministic
    np.testing.assert_array_equal(starts, draw_frozen_starts(train, n=3, seed=1))
    for scene, poses in zip(train, starts):
        region = ShapelyPolygon(scene.start_region)
        assert all(region.contains(Point(p[:2])) for p in poses)
        assert path_valid(scene, poses, convention="footprint")
        assert np.all(np.isfinite(geodesic_grid(scene).distance_at(poses[:, :2])))
    assert not np.array_equal(validation_starts("topology", per_scene=3, seed=2), starts)
    with pytest.raises(ConfigError, match="per_scene must be a positive integer, got 0"):
        validation_starts("topology", per_scene=0)
    with pytest.raises(ConfigError, match="unknown benchmark"):
        validation_starts("tpcap")


def test_the_holdout_split_is_every_kth_training_scene_with_its_validation_starts():
    assert held_out(48, 4).tolist() == [3, 7, 11, 15, 19, 23, 27, 31, 35, 39, 43, 47]
    assert held_out(48, 0).tolist() == []
    with pytest.raises(ConfigError, match="expected 0 \\(none\\) or an integer >= 2, got 1"):
        held_out(48, 1)
    train = load_benchmark("topology", "train")
    scenes, starts = split_episodes("topology", "holdout", per_scene=2, holdout_every=4)
    cells = [s.name.rsplit("-", 1)[0] for s in scenes]
    assert len(scenes) == 12 and all(cells.count(c) == 2 for c in cells)  # two of the eight scenes of each cell
    assert [s.name for s in scenes] == [train[k].name for k in range(3, 48, 4)]
    np.testing.assert_array_equal(starts, validation_starts("topology", per_scene=2)[3::4])
    with pytest.raises(ConfigError, match="needs checkpoints trained with TrainConfig.holdout_every >= 2"):
        split_episodes("topology", "holdout")
    with pytest.raises(ConfigError, match="unknown split 'train'"):
        split_episodes("topology", "train")


def test_unknown_names_are_config_errors_listing_the_valid_ones(tmp_path):
    with pytest.raises(ConfigError, match=r"unknown benchmark 'tpcap'; expected one of 'factorial', 'topology'"):
        load_benchmark("tpcap", "test")
    with pytest.raises(ConfigError, match=r"unknown split 'val'; expected one of 'train', 'test'"):
        load_benchmark("factorial", "val")
    with pytest.raises(ConfigError, match="unknown benchmark"):
        frozen_starts("Factorial")
    with pytest.raises(FileNotFoundError, match="np_sim.benchmarks.generate"):
        load_benchmark("factorial", "test", data_dir=tmp_path)


def test_files_are_versioned_and_record_their_rejections():
    for name in BENCHMARK_NAMES:
        assert benchmark_path(name).name == f"{name}_v1.json"
        doc, _, _ = read_benchmark_file(name)
        assert doc["benchmark"] == name and doc["format_version"] == 1 and doc["sampling"]["seed"] == 0
        assert {"target_validity", "object_capacity", "connected_start", "analytic_feasibility"} <= set(
            doc["generation"]["rejections"])


def _shipped_build(name):
    """The shipped file as a BenchmarkBuild (what the generator would return), without regenerating."""
    doc, scenes, starts = read_benchmark_file(name)
    gen = doc["generation"]
    return BenchmarkBuild(name, doc["generator"], scenes["train"], scenes["test"], np.array(starts),
                          gen["rejections"], np.array([gen["min_test_to_train_layout_distance_m"]]),
                          gen["disjointness_floor_m"])


def test_file_text_round_trips_through_the_deterministic_writer():
    for name in BENCHMARK_NAMES:
        assert benchmark_json(_shipped_build(name)).encode("utf-8") == benchmark_path(name).read_bytes()


def test_generate_cli_writes_and_checks(tmp_path, monkeypatch, capsys):
    build = _shipped_build("topology")  # the real regeneration is pinned in test_topology / test_factorial
    monkeypatch.setattr(generate_cli, "generate", lambda name, on_scene=None: build)
    assert generate_cli.main(["--benchmark", "topology", "--out", str(tmp_path)]) == 0
    written = tmp_path / "topology_v1.json"
    assert written.read_bytes() == benchmark_path("topology").read_bytes()
    assert generate_cli.main(["--benchmark", "topology", "--check"]) == 0
    out = capsys.readouterr().out
    assert "OK, identical" in out and "connected_start" in out
    monkeypatch.setattr(generate_cli, "benchmark_path", lambda name, data_dir=None: written)
    written.write_text(benchmark_json(build).replace('"topology"', '"topology" ', 1))
    assert generate_cli.main(["--benchmark", "topology", "--check"]) == 1
    assert "DIFFERS" in capsys.readouterr().out


def test_summary_cli_prints_the_statistics_and_writes_figures(tmp_path, capsys):
    result = bench_cli.main(["--summary", "--benchmark", "topology", "--figure", str(tmp_path), "--dpi", "25"])
    out = capsys.readouterr().out
    assert "route-blocked" in out and "structural disjointness" in out and "720 episodes" in out
    assert [p.name for p in result["figures"]] == ["topology_test.png"]
    assert all(p.stat().st_size > 5_000 for p in result["figures"])
    with pytest.raises(SystemExit):
        bench_cli.main([])
