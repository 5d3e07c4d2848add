"""Tests of hope_policy/ppo.py: GAE against a brute-force sum, the clipped loss on a hand-computed batch, advantage
normalisation, HOPE's critic copy and the config checks."""

from __future__ import annotations

import copy

import numpy as np
import pytest
import torch

from hope_policy.network import HopeActorCritic, Modalities
from hope_policy.ppo import HopePPO, HopePPOConfig, normalise_advantages
from np_sim.errors import ConfigError

SMALL = Modalities((("lidar", 4), ("target", 5)))


def brute_force_advantages(rewards, values, next_values, terminated, truncated, gamma, lam):
    """A_t = Σ_k (γλ)^k δ_{t+k}, summed explicitly until the episode or the batch ends."""
    T, N = rewards.shape
    out = np.zeros((T, N))
    for n in range(N):
        for t in range(T):
            total, weight = 0.0, 1.0
            for u in range(t, T):
                boot = 0.0 if terminated[u, n] else gamma * next_values[u, n]
                total += weight * (rewards[u, n] + boot - values[u, n])
                if terminated[u, n] or truncated[u, n]:
                    break
                weight *= gamma * lam
            out[t, n] = total
    return out


def test_targets_gae_matches_brute_force_and_uses_the_critic_copy():
    torch.manual_seed(0)
    model = HopeActorCritic(SMALL)
    ppo = HopePPO(model, HopePPOConfig())
    with torch.no_grad():  # make the critic copy differ from the critic
        for p in ppo.critic_target.parameters():
            p.add_(0.05)
    rng = np.random.default_rng(1)
    T, N = 6, 3
    obs = {"lidar": torch.randn(T * N, 4), "target": torch.randn(T * N, 5)}
    rewards = rng.normal(size=(T, N))
    next_values = rng.normal(size=(T, N))
    terminated = np.zeros((T, N), bool)
    truncated = np.zeros((T, N), bool)
    terminated[2, 0] = truncated[3, 1] = terminated[5, 2] = True
    adv, targets = ppo.targets(obs, next_values, rewards, terminated, truncated)
    values = model.value(obs).detach().numpy().reshape(T, N).astype(np.float64)
    expected = brute_force_advantages(rewards, values, next_values, terminated, truncated, 0.98, 0.95)
    np.testing.assert_allclose(adv.numpy().reshape(T, N), expected, rtol=1e-5, atol=1e-5)
    copy_values = ppo.critic_target(obs).squeeze(-1).detach().numpy()
    np.testing.assert_allclose(targets.numpy(), expected.reshape(-1) + copy_values, rtol=1e-5, atol=1e-5)


def test_advantage_normalisation_uses_the_sample_std():
    a = torch.tensor([1.0, 2.0, 4.0, 9.0])
    x = a.numpy()
    np.testing.assert_allclose(normalise_advantages(a).numpy(), (x - x.mean()) / (x.std(ddof=1) + 1e-5), rtol=1e-6)


def one_step_ppo(lr=1e-3):
    torch.manual_seed(3)
    model = HopeActorCritic(SMALL)
    config = HopePPOConfig(actor_lr=lr, critic_lr=lr, batch_size=3, minibatch_size=3, epochs=1)
    return model, HopePPO(model, config)


def test_first_gradient_step_is_the_hand_computed_clipped_loss():
    """One minibatch of 3 with ratios 1.5, 0.5, 1.1 and advantages 1, −1, 2. Normalised (mean 2/3, sample std
    √(7/3)) they are (1/3, −5/3, 4/3)/√(7/3); sample 0 (A > 0, ρ > 1.2) and sample 1 (A < 0, ρ < 0.8) take the
    clipped branch, so L = −(1.2·1/3 + 0.8·(−5/3) + 1.1·4/3) / (3√(7/3)) and only sample 2 has a gradient:
    ∂L/∂θ = −(1/3)·A_2·ρ_2·∇ log π(a_2|o_2). Adam's first step moves every weight by −lr·sign(∂L/∂θ)."""
    model, ppo = one_step_ppo()
    obs = {"lidar": torch.randn(3, 4), "target": torch.randn(3, 5)}
    actions = torch.tensor([[0.1, -0.2], [0.3, 0.4], [-0.5, 0.0]])
    with torch.no_grad():
        logp = model.distribution(obs).log_prob(actions).sum(-1)
    old = logp - torch.log(torch.tensor([1.5, 0.5, 1.1]))
    expected_loss = -(1.2 / 3 - 0.8 * 5 / 3 + 1.1 * 4 / 3) / (3 * np.sqrt(7 / 3))
    model.zero_grad()
    model.distribution({k: v[2:] for k, v in obs.items()}).log_prob(actions[2:]).sum().backward()
    ascent = {name: p.grad.clone() for name, p in model.named_parameters() if p.grad is not None}
    before = {name: p.detach().clone() for name, p in model.named_parameters()}
    stats = ppo.update(obs, actions, old, torch.tensor([1.0, -1.0, 2.0]), torch.zeros(3), np.random.default_rng(0))
    assert abs(stats["actor_loss"] - expected_loss) < 1e-4
    checked = 0
    for name, grad in ascent.items():
        moved = grad.abs() > 1e-4
        step = (dict(model.named_parameters())[name].detach() - before[name])[moved]
        np.testing.assert_allclose(step.numpy(), 1e-3 * grad[moved].sign().numpy(), rtol=1e-3)
        checked += int(moved.sum())
    assert checked > 1000


def test_critic_copy_tracks_the_critic_after_each_epoch():
    model, ppo = one_step_ppo()
    obs = {"lidar": torch.randn(3, 4), "target": torch.randn(3, 5)}
    old_copy = copy.deepcopy(ppo.critic_target.state_dict())
    ppo.update(obs, torch.zeros(3, 2), torch.zeros(3), torch.tensor([1.0, 0.0, -1.0]), torch.ones(3),
               np.random.default_rng(0))
    for name, value in ppo.critic_target.state_dict().items():
        expected = 0.9 * old_copy[name] + 0.1 * model.critic.state_dict()[name]
        torch.testing.assert_close(value, expected)


def test_config_is_hope_and_bad_values_are_named():
    c = HopePPOConfig()
    assert (c.actor_lr, c.critic_lr, c.gamma, c.gae_lambda, c.clip) == (5e-6, 2.5e-5, 0.98, 0.95, 0.2)
    assert (c.batch_size, c.minibatch_size, c.epochs) == (8192, 32, 10)
    with pytest.raises(ConfigError, match="HopePPOConfig.gamma"):
        HopePPOConfig(gamma=1.5)
    with pytest.raises(ConfigError, match="HopePPOConfig.minibatch_size"):
        HopePPOConfig(minibatch_size=0)
