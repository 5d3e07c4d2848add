"""HOPE's PPO update for the adapted HOPE (paper App. ``app:hope-adaptation``; HOPE's ``PPOAgent.update``).

One update consumes a batch of ``batch_size`` transitions (8,192): generalised advantage estimation (γ 0.98,
λ 0.95) with the current critic, value targets ``A + V_target(s)`` from HOPE's slowly tracking copy of the critic,
advantages normalised over the batch (no reward normalisation), then ten epochs of shuffled minibatches of 32, each
step taking the clipped surrogate (ratio clip 0.2) for the actor (Adam, 5e-6, the log standard deviation included)
and the mean squared value error for the critic (Adam, 2.5e-5), without entropy bonus or gradient clipping. After
each epoch the critic copy moves a step τ = 0.1 toward the critic.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass
from typing import Any

import numpy as np
import torch

from hope_policy.network import HopeActorCritic
from np_policy.ppo import clipped_ppo_loss, gae
from np_sim.errors import ConfigError

ADV_EPS = 1e-5
"""Added to the advantages' standard deviation when normalising them (HOPE)."""
_NO_ENTROPY = torch.zeros(1)


@dataclass(frozen=True)
class HopePPOConfig:
    """HOPE's PPO settings (paper App. ``app:hope-adaptation``)."""

    actor_lr: float = 5e-6
    """Adam learning rate of the actor and its log standard deviation."""
    critic_lr: float = 2.5e-5
    """Adam learning rate of the critic."""
    gamma: float = 0.98
    """Discount γ."""
    gae_lambda: float = 0.95
    """GAE λ."""
    clip: float = 0.2
    """Probability-ratio clip ε."""
    batch_size: int = 8192
    """Transitions per update."""
    minibatch_size: int = 32
    """Transitions per gradient step."""
    epochs: int = 10
    """Passes over each batch."""
    target_tau: float = 0.1
    """Step of the value-target critic copy toward the critic after every epoch (HOPE's TAU)."""

    def __post_init__(self) -> None:
        for name in ("actor_lr", "critic_lr", "batch_size", "minibatch_size", "epochs", "target_tau"):
            if not getattr(self, name) > 0:
                raise ConfigError(f"HopePPOConfig.{name}: expected a positive value, got {getattr(self, name)!r}")
        for name in ("gamma", "gae_lambda", "clip", "target_tau"):
            if not 0 <= getattr(self, name) <= 1:
                raise ConfigError(f"HopePPOConfig.{name}: expected a value in [0, 1], got {getattr(self, name)!r}")


def normalise_advantages(advantages: torch.Tensor) -> torch.Tensor:
    """``(A − mean A) / (std A + 1e-5)`` over the batch (sample standard deviation, as HOPE)."""
    return (advantages - advantages.mean()) / (advantages.std() + ADV_EPS)


def _index(obs: dict[str, torch.Tensor], idx: torch.Tensor) -> dict[str, torch.Tensor]:
    return {key: value[idx] for key, value in obs.items()}


class HopePPO:
    """The model, HOPE's value-target critic copy and the two Adam optimisers; `update` is one PPO update."""

    def __init__(self, model: HopeActorCritic, config: HopePPOConfig):
        self.model = model
        self.config = config
        self.critic_target = copy.deepcopy(model.critic)
        self.critic_target.requires_grad_(False)
        self.actor_optimizer = torch.optim.Adam(model.actor_parameters(), lr=config.actor_lr, eps=1e-8)
        self.critic_optimizer = torch.optim.Adam(model.critic.parameters(), lr=config.critic_lr, eps=1e-8)

    @torch.no_grad()
    def targets(self, obs: dict[str, torch.Tensor], next_values: np.ndarray, rewards: np.ndarray,
                terminated: np.ndarray, truncated: np.ndarray) -> tuple[torch.Tensor, torch.Tensor]:
        """(advantages, value targets) of a time-major ``(T, N)`` rollout whose observations ``obs`` are flattened
        to ``T·N`` rows (time-major); ``next_values`` are the critic's values of each step's successor (of the
        final observation where the step ended an episode). GAE (`np_policy.ppo.gae`: a terminated step is not
        bootstrapped, a truncated one is, and the recursion restarts at every episode end and at the end of the
        batch) with the current critic; value targets ``A + V_target(s)`` with HOPE's critic copy."""
        values = self.model.value(obs).numpy().reshape(rewards.shape)
        adv, _ = gae(rewards, values, next_values, terminated, truncated, self.config.gamma, self.config.gae_lambda)
        adv = torch.as_tensor(adv.reshape(-1), dtype=torch.float32)
        return adv, adv + self.critic_target(obs).squeeze(-1)

    def update(self, obs: dict[str, torch.Tensor], actions: torch.Tensor, old_log_probs: torch.Tensor,
               advantages: torch.Tensor, value_targets: torch.Tensor, rng: np.random.Generator) -> dict[str, float]:
        """``epochs`` shuffled passes of ``minibatch_size`` gradient steps over one batch; mean losses."""
        cfg = self.config
        advantages = normalise_advantages(advantages)
        n = actions.shape[0]
        actor_losses, critic_losses = [], []
        for _ in range(cfg.epochs):
            order = torch.from_numpy(rng.permutation(n))
            for start in range(0, n, cfg.minibatch_size):
                idx = order[start:start + cfg.minibatch_size]
                batch = _index(obs, idx)
                log_prob = self.model.distribution(batch).log_prob(actions[idx]).sum(-1)
                actor_loss, critic_loss, _ = clipped_ppo_loss(log_prob, old_log_probs[idx], advantages[idx],
                                                              self.model.value(batch), value_targets[idx],
                                                              _NO_ENTROPY, cfg.clip)
                self.actor_optimizer.zero_grad()
                self.critic_optimizer.zero_grad()
                actor_loss.backward()
                critic_loss.backward()
                self.actor_optimizer.step()
                self.critic_optimizer.step()
                actor_losses.append(actor_loss.item())
                critic_losses.append(critic_loss.item())
            self._track_critic()
        return {"actor_loss": float(np.mean(actor_losses)), "critic_loss": float(np.mean(critic_losses)),
                "action_std_0": float(self.model.log_std[0].detach().exp()),
                "action_std_1": float(self.model.log_std[1].detach().exp())}

    @torch.no_grad()
    def _track_critic(self) -> None:
        tau = self.config.target_tau
        for target, source in zip(self.critic_target.parameters(), self.model.critic.parameters()):
            target.mul_(1.0 - tau).add_(source, alpha=tau)

    def state_dict(self) -> dict[str, Any]:
        """Critic copy and both optimisers (the model's weights are stored separately)."""
        return {"critic_target": self.critic_target.state_dict(), "actor_optimizer": self.actor_optimizer.state_dict(),
                "critic_optimizer": self.critic_optimizer.state_dict()}

    def load_state_dict(self, state: dict[str, Any]) -> None:
        """Inverse of ``state_dict``."""
        self.critic_target.load_state_dict(state["critic_target"])
        self.actor_optimizer.load_state_dict(state["actor_optimizer"])
        self.critic_optimizer.load_state_dict(state["critic_optimizer"])
