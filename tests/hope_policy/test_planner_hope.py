"""Tests of hope_policy/planner.py: the planner rebuilds the trained policy with its statistics, acts as a hand
computation of HOPE's masked anchor choice says (drawn as HOPE evaluates, or the most probable anchor), plays the
clipped Gaussian sample without the mask, plans reproducibly whatever was planned before, and claims only
validated successes."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import torch

from hope_policy.checkpoint import load_hope_checkpoint
from hope_policy.config import HopeEnvConfig
from hope_policy.env import HopeParkingEnv
from hope_policy.planner import HopePlanner
from hope_policy.ppo import HopePPOConfig
from hope_policy.train import HopeTrainConfig, train
from np_policy.checkpoint import CheckpointError
from np_sim.benchmarks import load_benchmark
from np_sim.errors import ConfigError
from np_sim.plan import Plan
from np_sim.starts import UniformStartSampler
from np_sim.validate import scoring_rule, validate_plan

NP_CHECKPOINT = Path(__file__).resolve().parents[2] / "checkpoints" / "factorial_np_seed0.pt"


@pytest.fixture(scope="module")
def final_checkpoint(tmp_path_factory):
    out = tmp_path_factory.mktemp("hope_run")
    config = HopeTrainConfig(num_envs=2, episodes=1, ppo=HopePPOConfig(batch_size=16, minibatch_size=8, epochs=1))
    train(config, out, progress=False)
    return out / "final.pt"


@pytest.fixture(scope="module")
def queries():
    scenes = load_benchmark("factorial", "train")[:3]
    starts = UniformStartSampler(scenes)(np.random.default_rng(7), np.arange(3))
    return list(zip(scenes, starts))


@pytest.fixture(scope="module")
def unmasked_checkpoint(tmp_path_factory):
    out = tmp_path_factory.mktemp("hope_backbone_run")
    config = HopeTrainConfig(num_envs=2, episodes=1, env=HopeEnvConfig.backbone("none"),
                             ppo=HopePPOConfig(batch_size=16, minibatch_size=8, epochs=1))
    train(config, out, progress=False)
    return out / "final.pt"


def hand_mean(payload, model, obs):
    """The actor's mean and σ for one observation, LiDAR and target normalised with the stored (count, mean, M2)."""
    x = {}
    for key, value in obs.items():
        stats = payload["obs_norm"].get(key)
        if stats is None:
            x[key] = torch.tensor(np.asarray(value, np.float32)[None])
            continue
        std = np.sqrt(stats["m2"] / stats["count"])
        x[key] = torch.tensor(((value - stats["mean"]) / (std + 1e-8)).astype(np.float32)[None])
    with torch.no_grad():
        mean = model.actor(x).clamp(-1, 1)[0].numpy().astype(float)
    return mean, np.exp(model.log_std.detach().numpy().astype(float)).reshape(-1)


def hand_anchor_weights(payload, model, obs):
    """HOPE's choice written out: the actor's mean, the 42 anchors (21 steering angles 1 … −1, forward then
    reverse) weighted by exp(Σ_d clip(log N(anchor_d; μ_d, σ_d), −10, 10)) · mask."""
    mean, sigma = hand_mean(payload, model, obs)
    steer = 1.0 - np.arange(21) / 10.0
    anchors = np.array([(s, g) for g in (1.0, -1.0) for s in steer])
    log_density = -0.5 * ((anchors - mean) / sigma) ** 2 - np.log(math.sqrt(2 * math.pi) * sigma)
    return anchors, np.exp(np.clip(log_density, -10, 10).sum(1)) * obs["action_mask"]


def first_observations(planner, queries):
    for scene, start in queries:
        env = HopeParkingEnv(scene, planner.config.env)
        yield env.reset(options={"scene_index": 0, "start": start})[0]


def test_the_mean_variant_picks_the_hand_computed_heaviest_anchor(final_checkpoint, queries):
    planner = HopePlanner.from_checkpoint(final_checkpoint, action="mean")
    payload = load_hope_checkpoint(final_checkpoint)
    for obs in first_observations(planner, queries):
        anchors, weights = hand_anchor_weights(payload, planner.model, obs)
        np.testing.assert_allclose(planner.action(obs), anchors[np.argmax(weights)], atol=1e-6)


def test_sampled_anchors_follow_the_hand_computed_masked_probabilities(final_checkpoint, queries):
    planner = HopePlanner.from_checkpoint(final_checkpoint)
    payload = load_hope_checkpoint(final_checkpoint)
    obs = next(first_observations(planner, queries))
    anchors, weights = hand_anchor_weights(payload, planner.model, obs)
    rng = np.random.default_rng(3)
    draws = np.array([planner.action(obs, rng) for _ in range(3000)])
    index = [int(np.argmin(np.abs(anchors - a).sum(1))) for a in draws]
    np.testing.assert_allclose(np.abs(anchors[index] - draws).max(), 0.0, atol=1e-6)  # every draw is an anchor
    frequency = np.bincount(index, minlength=42) / len(index)
    p = weights / weights.sum()
    assert frequency[p == 0].sum() == 0  # a masked-out anchor is never drawn
    assert np.abs(frequency - p).max() < 4 * np.sqrt(p.max() / len(index)) + 1e-3


def test_without_the_mask_the_planner_plays_the_clipped_gaussian_sample(unmasked_checkpoint, queries):
    planner = HopePlanner.from_checkpoint(unmasked_checkpoint)
    payload = load_hope_checkpoint(unmasked_checkpoint)
    for k, obs in enumerate(first_observations(planner, queries)):
        assert "action_mask" not in obs
        mean, sigma = hand_mean(payload, planner.model, obs)
        noise = np.random.default_rng(k).standard_normal(2)
        np.testing.assert_allclose(planner.action(obs, np.random.default_rng(k)),
                                   np.clip(mean + sigma * noise, -1, 1), atol=1e-6)
        np.testing.assert_allclose(planner.action(obs), mean, atol=1e-6)


def test_each_plan_draws_from_its_own_start_and_seed(final_checkpoint, queries):
    planner = HopePlanner.from_checkpoint(final_checkpoint)
    (scene_a, start_a), (scene_b, start_b) = queries[:2]
    first = planner.plan(scene_a, start_a)
    planner.plan(scene_b, start_b)
    np.testing.assert_array_equal(planner.plan(scene_a, start_a).arcs, first.arcs)
    draws = {seed: HopePlanner.from_checkpoint(final_checkpoint, seed=seed).episode_rng(start_a).random(4)
             for seed in (0, 1)}
    assert not np.array_equal(draws[0], draws[1])
    assert not np.array_equal(planner.episode_rng(start_a).random(4), planner.episode_rng(start_b).random(4))
    assert HopePlanner.from_checkpoint(final_checkpoint, action="mean").episode_rng(start_a) is None


def test_an_unknown_action_mode_is_refused(final_checkpoint):
    with pytest.raises(ConfigError, match="HopePlanner.action: expected one of"):
        HopePlanner.from_checkpoint(final_checkpoint, action="greedy")


@pytest.mark.parametrize("action", ["sampled", "mean"])
def test_plans_are_reproducible_and_successes_are_validated(final_checkpoint, queries, action):
    planner = HopePlanner.from_checkpoint(final_checkpoint, action=action)
    assert (planner.name, planner.convention) == ("hope", "reference_point")
    for scene, start in queries:
        plan = planner.plan(scene, start)
        again = planner.plan(scene, start)
        assert isinstance(plan, Plan) and plan.plan_time_s > 0
        np.testing.assert_array_equal(plan.arcs, again.arcs)
        assert (plan.success, plan.reason) == (again.success, again.reason)
        np.testing.assert_array_equal(plan.start, start)
        assert plan.success == (plan.reason == "")
        if plan.success:
            assert validate_plan(scene, plan, scoring_rule("reference_point"), convention="reference_point").valid


def test_a_neuralparker_checkpoint_is_refused_with_its_name():
    with pytest.raises(CheckpointError, match="expected an adapted-HOPE checkpoint"):
        HopePlanner.from_checkpoint(NP_CHECKPOINT)
