"""Tests of hope_policy/normalization.py: running statistics against numpy over the whole stream, the branches
that are normalised, and the stored statistics."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from hope_policy.normalization import EPS, ObservationNormaliser, RunningMeanStd


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), sizes=st.lists(st.integers(1, 7), min_size=1, max_size=8),
       scale=st.floats(1e-3, 1e3))
def test_running_statistics_equal_numpy_over_the_stream(seed, sizes, scale):
    rng = np.random.default_rng(seed)
    batches = [rng.normal(3.0, scale, size=(n, 4)) for n in sizes]
    stats = RunningMeanStd((4,))
    for batch in batches:
        stats.update(batch)
    stream = np.concatenate(batches)
    assert stats.count == len(stream)
    np.testing.assert_allclose(stats.mean, stream.mean(axis=0), rtol=1e-9, atol=1e-9 * scale)
    np.testing.assert_allclose(stats.std, stream.std(axis=0), rtol=1e-7, atol=1e-7 * scale)
    x = rng.normal(size=(3, 4))
    expected = (x - stream.mean(axis=0)) / (stream.std(axis=0) + EPS)
    np.testing.assert_allclose(stats.normalise(x), expected, rtol=1e-4, atol=1e-4)


def test_first_observation_normalises_to_zero_like_hope():
    """HOPE starts its statistics at the first observation (mean = x, so x maps to 0)."""
    stats = RunningMeanStd((3,))
    x = np.array([[2.0, -1.0, 5.0]])
    stats.update(x)
    np.testing.assert_array_equal(stats.normalise(x), np.zeros((1, 3), np.float32))


def test_only_lidar_target_and_vertices_are_normalised():
    shapes = {"lidar": (2,), "target": (5,), "action_mask": (3,), "vertices": (4,)}
    norm = ObservationNormaliser(shapes)
    assert sorted(norm.stats) == ["lidar", "target", "vertices"]
    rng = np.random.default_rng(0)
    stream = {key: rng.normal(1.0, 2.0, size=(10, *shape)) for key, shape in shapes.items()}
    norm.update(stream)
    out = norm(stream)
    np.testing.assert_array_equal(out["action_mask"], stream["action_mask"].astype(np.float32))
    for key in ("lidar", "target", "vertices"):
        np.testing.assert_allclose(out[key].mean(axis=0), 0.0, atol=1e-5)
        np.testing.assert_allclose(out[key].std(axis=0), 1.0, atol=1e-5)


def test_state_round_trip_and_mismatch():
    norm = ObservationNormaliser({"lidar": (2,), "target": (5,)})
    norm.update({"lidar": np.ones((3, 2)) * [1, 2], "target": np.arange(15.0).reshape(3, 5)})
    other = ObservationNormaliser({"lidar": (2,), "target": (5,)})
    other.load_state_dict(norm.state_dict())
    x = {"lidar": np.array([[0.5, 3.0]]), "target": np.ones((1, 5))}
    for key in x:
        np.testing.assert_array_equal(other(x)[key], norm(x)[key])
    with pytest.raises(ValueError, match="stored branches"):
        ObservationNormaliser({"lidar": (2,)}).load_state_dict(norm.state_dict())
    with pytest.raises(ValueError, match="expected a batch of shape"):
        RunningMeanStd((2,)).update(np.zeros((3, 4)))


SENTINEL = -1e4


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), sizes=st.lists(st.integers(1, 7), min_size=1, max_size=8),
       empty=st.floats(0.0, 0.9))
def test_padding_is_left_out_of_the_statistics_feature_by_feature(seed, sizes, empty):
    """Each feature's statistics equal numpy's over its real entries only, whatever share of the stream pads it and
    however the stream is split; padded entries come out unchanged, real ones as (x − mean) / (std + ε)."""
    rng = np.random.default_rng(seed)
    batches = [np.where(rng.random((n, 4)) < empty, SENTINEL, rng.normal(5.0, 2.0, size=(n, 4))) for n in sizes]
    stats = RunningMeanStd((4,), padding=SENTINEL)
    for batch in batches:
        stats.update(batch)
    stream = np.concatenate(batches)
    for f in range(4):
        real = stream[:, f][stream[:, f] != SENTINEL]
        assert stats.count[f] == len(real)
        if len(real):
            assert stats.mean[f] == pytest.approx(real.mean(), rel=1e-9)
            assert stats.std[f] == pytest.approx(real.std(), rel=1e-7, abs=1e-9)
    x = np.array([[SENTINEL, 5.0, SENTINEL, 1.0]])
    out = stats.normalise(x)
    assert out[0, 0] == out[0, 2] == np.float32(SENTINEL)
    np.testing.assert_allclose(out[0, [1, 3]], (x[0, [1, 3]] - stats.mean[[1, 3]]) / (stats.std[[1, 3]] + EPS),
                               rtol=1e-5)


def test_a_slot_empty_in_most_scenes_keeps_its_coordinates_apart():
    """The defect this replaced: counting the padding made a slot filled in one scene of ten normalise every real
    coordinate in it to nearly the same value."""
    filled = np.array([[-3.0], [4.0]])
    stream = np.vstack([filled, np.full((18, 1), SENTINEL)])
    padded, counted = RunningMeanStd((1,), padding=SENTINEL), RunningMeanStd((1,))
    padded.update(stream)
    counted.update(stream)
    assert np.ptp(padded.normalise(filled)) == pytest.approx(2.0)  # (4 − (−3)) / 3.5: one std apart on each side
    assert np.ptp(counted.normalise(filled)) < 0.003


def test_padded_statistics_round_trip_and_refuse_statistics_made_the_other_way():
    shapes = {"lidar": (2,), "vertices": (3,)}
    norm = ObservationNormaliser(shapes, padding={"vertices": SENTINEL})
    norm.update({"lidar": np.ones((2, 2)), "vertices": np.array([[1.0, SENTINEL, 2.0], [3.0, SENTINEL, SENTINEL]])})
    other = ObservationNormaliser(shapes, padding={"vertices": SENTINEL})
    other.load_state_dict(norm.state_dict())
    x = {"lidar": np.ones((1, 2)), "vertices": np.array([[2.0, SENTINEL, 7.0]])}
    np.testing.assert_array_equal(other(x)["vertices"], norm(x)["vertices"])
    with pytest.raises(ValueError, match="count has shape"):
        ObservationNormaliser(shapes).load_state_dict(norm.state_dict())
    with pytest.raises(ValueError, match="count has shape"):
        norm.load_state_dict(ObservationNormaliser(shapes).state_dict())
