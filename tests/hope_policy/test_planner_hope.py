"""Tests of hope_policy/planner.py: the planner rebuilds the trained policy with its statistics, acts as a hand
computation of HOPE's masked anchor choice says, plans deterministically, and claims only validated successes."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import torch

from hope_policy.checkpoint import load_hope_checkpoint
from hope_policy.env import HopeParkingEnv
from hope_policy.planner import HopePlanner
from hope_policy.ppo import HopePPOConfig
from hope_policy.train import HopeTrainConfig, train
from np_policy.checkpoint import CheckpointError
from np_sim.benchmarks import load_benchmark
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


def hand_action(payload, model, obs):
    """HOPE's choice written out: normalise LiDAR and target with the stored (count, mean, M2), take the actor's
    mean, weight the 42 anchors (21 steering angles 1 … −1, forward then reverse) by
    exp(Σ_d clip(log N(anchor_d; μ_d, σ_d), −10, 10)) · mask and pick the heaviest."""
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
    sigma = np.exp(model.log_std.detach().numpy().astype(float))
    steer = 1.0 - np.arange(21) / 10.0
    anchors = np.array([(s, g) for g in (1.0, -1.0) for s in steer])
    log_density = -0.5 * ((anchors - mean) / sigma) ** 2 - np.log(math.sqrt(2 * math.pi) * sigma)
    weights = np.exp(np.clip(log_density, -10, 10).sum(1)) * obs["action_mask"]
    return anchors[np.argmax(weights)]


def test_planner_acts_as_the_hand_computed_masked_choice(final_checkpoint, queries):
    planner = HopePlanner.from_checkpoint(final_checkpoint)
    payload = load_hope_checkpoint(final_checkpoint)
    for scene, start in queries:
        env = HopeParkingEnv(scene, planner.config.env)
        obs, _ = env.reset(options={"scene_index": 0, "start": start})
        np.testing.assert_allclose(planner.action(obs), hand_action(payload, planner.model, obs), atol=1e-6)


def test_plans_are_deterministic_and_successes_are_validated(final_checkpoint, queries):
    planner = HopePlanner.from_checkpoint(final_checkpoint)
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
