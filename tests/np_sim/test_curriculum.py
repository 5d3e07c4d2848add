"""Geodesic start curriculum (paper §III-E): schedule, pool ordering, fractions, and the env plug-in."""

import numpy as np
import pytest

from np_sim.benchmarks import load_benchmark
from np_sim.collision import path_valid
from np_sim.curriculum import CurriculumSchedule, CurriculumStartSampler, active_count
from np_sim.env import ParkingVectorEnv
from np_sim.errors import ConfigError
from np_sim.geodesic import geodesic_grid
from np_sim.kernels import step as K


@pytest.fixture(scope="module")
def scenes():
    train = load_benchmark("factorial", "train")
    return [train[0], train[40], train[80]]


@pytest.fixture(scope="module")
def sampler(scenes):
    return CurriculumStartSampler(scenes, fraction=0.05, pool_size=80, seed=7)


def test_schedule_ramps_from_5_percent_to_the_full_range():
    s = CurriculumSchedule()
    assert s.fraction(0.0) == pytest.approx(0.05) and s.fraction(0.5) == 1.0 and s.fraction(1.0) == 1.0
    values = [s.fraction(p) for p in np.linspace(0, 1, 21)]
    assert values == sorted(values) and s.fraction(0.25) == pytest.approx(0.525)
    staged = CurriculumSchedule(mode="staged", n_stages=4, full_at_progress=1.0)
    assert [staged.fraction(p) for p in (0.0, 0.2, 0.3, 0.99, 1.0)] == pytest.approx([0.05, 0.05, 0.2875, 0.7625, 1.0])
    assert CurriculumSchedule(enabled=False).fraction(0.0) == 1.0


def test_schedule_round_trips_and_rejects_unknown_keys_and_bad_values():
    s = CurriculumSchedule(mode="staged", n_stages=3, full_at_progress=0.8)
    assert CurriculumSchedule.from_dict(s.to_dict()) == s
    with pytest.raises(ConfigError, match=r"unknown key\(s\) \['start_frac'\]"):
        CurriculumSchedule.from_dict({"start_frac": 0.1})
    with pytest.raises(ConfigError, match="start_fraction"):
        CurriculumSchedule(start_fraction=0.0)
    with pytest.raises(ConfigError, match="mode"):
        CurriculumSchedule(mode="cosine")


def test_pool_is_ordered_by_geodesic_distance_and_footprint_free(scenes, sampler):
    assert sampler.pool.shape == (3, 80, 3) and np.all(np.diff(sampler.distance, axis=1) >= 0)
    for k, scene in enumerate(scenes):
        grid = geodesic_grid(scene)
        np.testing.assert_array_equal(grid.distance_at(sampler.pool[k, :, :2]), sampler.distance[k])
        assert path_valid(scene, sampler.pool[k], convention="footprint")


def test_the_5_percent_starts_are_nearer_than_the_rest(sampler):
    assert sampler.n_active == active_count(0.05, 80) == 4
    rng = np.random.default_rng(0)
    ks = np.repeat(np.arange(3), 200)
    starts = sampler(rng, ks)
    for k in range(3):
        chosen = {tuple(p) for p in starts[ks == k]}
        active = {tuple(p) for p in sampler.pool[k, :4]}
        assert chosen == active  # uniform among exactly the nearest 4
        assert sampler.distance[k, :4].max() <= sampler.distance[k, 4:].min()


def test_fraction_one_covers_the_whole_pool_and_bad_fractions_raise(scenes):
    s = CurriculumStartSampler(scenes[:1], fraction=1.0, pool_size=30, seed=1)
    starts = s(np.random.default_rng(2), np.zeros(3000, int))
    assert {tuple(p) for p in starts} == {tuple(p) for p in s.pool[0]}
    assert s.set_progress(0.0, CurriculumSchedule()) == pytest.approx(0.05) and s.n_active == 2
    for bad in (0.0, 1.5, -0.1):
        with pytest.raises(ConfigError, match=r"expected a number in \(0, 1\]"):
            s.set_fraction(bad)
    np.testing.assert_array_equal(CurriculumStartSampler(scenes[:1], pool_size=30, seed=1).pool, s.pool)


def test_plugs_into_the_vector_env(scenes, sampler):
    env = ParkingVectorEnv(scenes, 6, seed=3, start_sampler=sampler)
    env.reset()
    poses, ks = env.core.S[:, K.S_X: K.S_TH + 1], env.core.S[:, K.S_SCENE].astype(int)
    for pose, k in zip(poses, ks):
        assert any(np.allclose(pose, p) for p in sampler.pool[k, : sampler.n_active])
    sampler.set_fraction(1.0)
    try:
        env.set_start_sampler(sampler)
        env.reset(seed=4)
        poses, ks = env.core.S[:, K.S_X: K.S_TH + 1], env.core.S[:, K.S_SCENE].astype(int)
        assert all(any(np.allclose(pose, p) for p in sampler.pool[k]) for pose, k in zip(poses, ks))
    finally:
        sampler.set_fraction(0.05)
