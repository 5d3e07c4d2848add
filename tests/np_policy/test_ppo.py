"""Tests of np_policy/ppo.py (GAE, return normalisation, clipped loss, update determinism) and np_policy/config.py."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import torch

from np_sim.config import ObservationConfig
from np_sim.errors import ConfigError
from np_sim.observation import observation_size
from np_policy.config import NetworkConfig, PPOConfig
from np_policy.network import ActorCritic
from np_policy.ppo import (RunningMeanStd, accumulate_minibatch_gradient, clipped_ppo_loss, compute_targets, gae,
                           make_optimizer, minibatch_indices, ppo_update)


def tiny_rollout():
    """3 steps × 2 envs: env 0 terminates at t=1, env 1 is truncated at t=1."""
    rewards = np.array([[1.0, 0.0], [2.0, 1.0], [3.0, -1.0]])
    values = np.array([[0.5, 1.0], [0.6, 2.0], [0.7, 3.0]])
    # row t holds V(s_{t+1}); at t=1 both come from info["final_obs"] (9.0 must be ignored: termination)
    next_values = np.array([[0.6, 2.0], [9.0, 4.0], [0.8, 0.0]])
    terminated = np.array([[False, False], [True, False], [False, False]])
    truncated = np.array([[False, False], [False, True], [False, False]])
    return rewards, values, next_values, terminated, truncated


def gae_loop(rewards, values, next_values, terminated, truncated, gamma, lam):
    """Test oracle, written without np_policy.ppo: GAE env by env, step by step backwards. A terminated step
    bootstraps nothing, a truncated one bootstraps V(final obs); both end the λ-chain."""
    steps, envs = rewards.shape
    advantages = np.zeros((steps, envs))
    for n in range(envs):
        running = 0.0
        for t in reversed(range(steps)):
            bootstrap = 0.0 if terminated[t, n] else next_values[t, n]
            delta = rewards[t, n] + gamma * bootstrap - values[t, n]
            if terminated[t, n] or truncated[t, n]:
                running = 0.0
            running = delta + gamma * lam * running
            advantages[t, n] = running
    return advantages, advantages + values


def test_gae_matches_a_hand_computation_with_termination_and_truncation():
    rewards, values, next_values, terminated, truncated = tiny_rollout()
    gamma, lam = 0.9, 0.5
    # env 0: δ = [1 + .9·.6 − .5, 2 − .6, 3 + .9·.8 − .7] = [1.04, 1.4, 3.02]; A0 = 1.04 + .45·1.4
    # env 1: δ = [0 + .9·2 − 1, 1 + .9·4 − 2, −1 + 0 − 3] = [0.8, 2.6, −4.0]; A0 = 0.8 + .45·2.6
    expected = np.array([[1.67, 1.97], [1.4, 2.6], [3.02, -4.0]])
    inputs = [x.copy() for x in tiny_rollout()]
    advantages, returns = gae(rewards, values, next_values, terminated, truncated, gamma, lam)
    np.testing.assert_allclose(advantages, expected, atol=1e-12)
    np.testing.assert_allclose(returns, expected + values, atol=1e-12)
    np.testing.assert_allclose(gae_loop(*tiny_rollout(), gamma, lam)[0], expected, atol=1e-12)  # the oracle too
    for before, after in zip(inputs, tiny_rollout()):
        np.testing.assert_array_equal(before, after)


def test_running_mean_std_matches_numpy_over_batches():
    rng = np.random.default_rng(0)
    batches = [rng.normal(3.0, 2.0, n) for n in (5, 17, 1)]
    rms = RunningMeanStd()
    for b in batches:
        rms.update(b)
    allx = np.concatenate(batches)
    assert rms.count == len(allx)
    np.testing.assert_allclose([rms.mean, rms.var], [allx.mean(), allx.var()], rtol=1e-12)


def test_compute_targets_scales_values_and_returns_by_the_running_std():
    rewards, values, next_values, terminated, truncated = tiny_rollout()
    config = PPOConfig(gamma=0.9, gae_lambda=0.5)
    rms = RunningMeanStd()
    rms.update(np.array([0.0, 4.0]))  # population variance 4: σ = √(4 + ε) ≈ 2
    sigma = np.sqrt(4.0 + config.norm_eps)
    adv, targets = compute_targets(rewards, values, next_values, terminated, truncated, config, rms)
    # the critic speaks in units of σ: GAE on σ·V in reward units, targets divided back by σ
    want_adv, want_returns = gae_loop(rewards, values * sigma, next_values * sigma, terminated, truncated, 0.9, 0.5)
    np.testing.assert_allclose(adv, want_adv, atol=1e-12)
    np.testing.assert_allclose(targets, want_returns / sigma, atol=1e-12)
    # env 1 at t = 2 by hand: δ = −1 + 0 − 3σ (next value 0, not terminated), chain cut by the truncation before
    assert adv[2, 1] == pytest.approx(-1.0 - 3.0 * sigma) and targets[2, 1] == pytest.approx(-1.0 / sigma)
    # the statistics then take the six raw (reward-unit) returns
    seen = np.concatenate([[0.0, 4.0], want_returns.reshape(-1)])
    assert rms.count == 8
    np.testing.assert_allclose([rms.mean, rms.var], [seen.mean(), seen.var()], rtol=1e-12)
    off = dataclasses.replace(config, norm_rewards=False)
    plain_adv, plain = compute_targets(rewards, values, next_values, terminated, truncated, off, None)
    want_adv, want_returns = gae_loop(rewards, values, next_values, terminated, truncated, 0.9, 0.5)
    np.testing.assert_allclose(plain_adv, want_adv, atol=1e-12)
    np.testing.assert_allclose(plain, want_returns, atol=1e-12)


def test_clipped_loss_matches_a_hand_computation():
    new = torch.log(torch.tensor([1.0, 1.5, 0.5]))
    old = torch.zeros(3)
    adv = torch.tensor([1.0, 1.0, -1.0])
    values, returns = torch.tensor([1.0, 2.0, 0.0]), torch.tensor([0.0, 4.0, 0.0])
    entropy = torch.tensor([0.3, 0.6, 0.9])
    policy, value, ent = clipped_ppo_loss(new, old, adv, values, returns, entropy, clip_coef=0.2)
    # ratios 1, 1.5, 0.5 → min terms 1, 1.2 (clipped), −0.8 (clipped: 0.8·−1 < 0.5·−1)
    assert policy.item() == pytest.approx(-(1.0 + 1.2 - 0.8) / 3)
    assert value.item() == pytest.approx((1.0 + 4.0 + 0.0) / 3)
    assert ent.item() == pytest.approx(0.6)
    _, clipped_value, _ = clipped_ppo_loss(new, old, adv, values, returns, entropy, 0.2,
                                           old_values=torch.tensor([0.9, 1.0, 0.0]))
    # V_clip = [1.0, 1.2, 0.0]: max((R−V)², (R−V_clip)²) = [1, 7.84, 0]
    assert clipped_value.item() == pytest.approx((1.0 + 7.84) / 3)


def test_minibatches_merge_a_short_last_chunk_and_cover_every_index():
    chunks = minibatch_indices(10, 4, torch.Generator().manual_seed(0))
    assert [len(c) for c in chunks] == [4, 6]
    assert sorted(torch.cat(chunks).tolist()) == list(range(10))


def _update_once(seed: int):
    torch.manual_seed(seed)
    obs_config = ObservationConfig()
    model = ActorCritic(obs_config, NetworkConfig())
    config = PPOConfig(batch_size=32, repeats=2)
    g = torch.Generator().manual_seed(seed)
    n = 64
    obs = torch.randn(n, observation_size(obs_config), generator=g)
    obs[:, 124 + 3 * 16: 124 + 320] = -1e4
    batch = {"obs": obs}
    batch["actions"], batch["log_probs"], _ = model.act(obs)
    batch["advantages"] = torch.randn(n, generator=g)
    batch["returns"] = torch.randn(n, generator=g)
    stats = ppo_update(model, make_optimizer(model, config), batch, config, g)
    return model.state_dict(), stats


def test_same_seed_gives_the_same_update_on_cpu():
    state_a, stats_a = _update_once(0)
    state_b, stats_b = _update_once(0)
    assert stats_a == stats_b
    for key in state_a:
        assert torch.equal(state_a[key], state_b[key]), key
    assert np.isfinite(list(stats_a.values())).all()
    state_c, _ = _update_once(1)
    assert not torch.equal(state_a["log_std"], state_c["log_std"]) or not torch.equal(
        state_a["actor.0.weight"], state_c["actor.0.weight"])


def _float64_minibatch(seed: int, scenes: int | None = None):
    """(model, batch, shuffled indices) of 40 random float64 samples, 3 obstacle and all boundary slots used; with
    ``scenes`` the slot part of each sample is one of that many scene rows (ego and LiDAR stay the sample's own)."""
    torch.manual_seed(seed)
    obs_config = ObservationConfig()
    model = ActorCritic(obs_config, NetworkConfig()).double()
    g = torch.Generator().manual_seed(seed)
    n = 40
    obs = torch.randn(n, observation_size(obs_config), generator=g, dtype=torch.float64)
    if scenes:
        obs[:, 124:] = torch.randn(scenes, 360, generator=g, dtype=torch.float64)[torch.randint(0, scenes, (n,),
                                                                                                generator=g)]
    obs[:, 124 + 3 * 16: 124 + 320] = -1e4
    batch = {"obs": obs}
    batch["actions"], batch["log_probs"], batch["values"] = model.act(obs)
    batch["log_probs"] = batch["log_probs"] + 0.3 * torch.randn(n, generator=g, dtype=torch.float64)  # clip some
    batch["advantages"] = torch.randn(n, generator=g, dtype=torch.float64)
    batch["returns"] = torch.randn(n, generator=g, dtype=torch.float64)
    return model, batch, torch.randperm(n, generator=g)


def _assert_same_gradient_and_stats(model, batch, idx, first: dict, second: dict) -> dict:
    """The minibatch gradient and stats of ``accumulate_minibatch_gradient(**first)`` equal those of ``second``
    (float64: tolerances above summation-order noise, far below a wrong term); returns the first's stats."""
    grads, stats = [], []
    for kwargs in (first, second):
        model.zero_grad()
        stats.append(accumulate_minibatch_gradient(model, batch, idx, **kwargs))
        grads.append({name: p.grad.clone() for name, p in model.named_parameters()})
    for name, grad in grads[0].items():
        torch.testing.assert_close(grads[1][name], grad, rtol=1e-7, atol=1e-10, msg=name)
    for key in stats[0]:
        assert stats[1][key] == pytest.approx(stats[0][key], rel=1e-9, abs=1e-12), key
    geometry = ("encoder.slot_position", "encoder.obstacle.0.weight", "encoder.boundary.0.weight",
                "encoder.geometry_summary.weight")
    assert all(grads[0][name].abs().max() > 0 for name in geometry)  # the comparison covers the geometry branch
    return stats[0]


def test_chunked_minibatch_gradient_equals_the_whole_minibatch_gradient():
    """Chunks of 7 (uneven last chunk) against one pass over the 40-sample minibatch: same gradient, same stats."""
    model, batch, idx = _float64_minibatch(3)
    n = len(idx)
    stats = _assert_same_gradient_and_stats(
        model, batch, idx, {"config": PPOConfig(batch_size=n, update_chunk=n, value_clip=True)},
        {"config": PPOConfig(batch_size=n, update_chunk=7, value_clip=True)})
    assert 0.0 < stats["clip_fraction"] < 1.0


def test_shared_geometry_gives_the_minibatch_gradient_of_the_per_sample_branch():
    """40 samples of 5 scenes, chunks of 7: the gradient and the stats with the geometry branch run once per scene
    equal those with it run per sample."""
    model, batch, idx = _float64_minibatch(4, scenes=5)
    config = PPOConfig(batch_size=len(idx), update_chunk=7)
    _assert_same_gradient_and_stats(model, batch, idx, {"config": config},
                                    {"config": config, "shared_geometry": True})


def test_update_chunk_must_be_positive():
    with pytest.raises(ConfigError, match="PPOConfig.update_chunk"):
        PPOConfig(update_chunk=0)


def test_ppo_config_defaults_are_table_v():
    c = PPOConfig()
    assert (c.learning_rate, c.gamma, c.gae_lambda, c.clip_coef, c.vf_coef, c.ent_coef, c.max_grad_norm) == (
        3e-4, 0.99, 0.95, 0.15, 0.25, 0.005, 0.5)
    assert (c.epochs, c.steps_per_epoch, c.steps_per_collect, c.repeats, c.batch_size) == (
        240, 60_000, 16_384, 10, 8_192)
    assert (c.num_train_envs, c.num_test_envs, c.steps_per_env_per_collect, c.collects_per_epoch) == (128, 32, 128, 4)
    assert c.lr_at(0) == 3e-4 and c.lr_at(c.total_updates) == 0.0
    assert c.lr_at(c.total_updates // 2) == pytest.approx(1.5e-4)


def test_configs_round_trip_and_reject_unknown_keys():
    assert PPOConfig.from_dict(PPOConfig().to_dict()) == PPOConfig()
    assert NetworkConfig.from_dict(NetworkConfig().to_dict()) == NetworkConfig()
    with pytest.raises(ConfigError, match=r"PPOConfig: unknown key\(s\) \['clip'\]"):
        PPOConfig.from_dict({"clip": 0.2})
    with pytest.raises(ConfigError, match=r"NetworkConfig: unknown key"):
        NetworkConfig.from_dict({"token_dims": 8})
    with pytest.raises(ConfigError, match="multiple of num_train_envs"):
        PPOConfig(steps_per_collect=1000)
