"""PPO pieces with Tianshou semantics, as pure functions the trainer composes (spec §6, paper Table V).

Phases of one update (the trainer calls them in this order):

1. collect T steps from N envs: ``act`` → ``clip_action`` → env; store the *unclipped* action and its log-prob;
   for every step store ``next_values`` = V(s_{t+1}), where for a step that ended an episode s_{t+1} is
   ``info["final_obs"]`` (same-step autoreset puts the next episode's first observation in the returned row);
2. ``compute_targets``: values are un-normalised with the running return std, ``gae`` gives advantages and
   λ-returns, returns are divided by the running std, which is then updated with the raw returns (Tianshou
   ``reward_normalization``);
3. ``ppo_update``: ``repeats`` passes of shuffled minibatches, per-minibatch advantage normalisation,
   ``clipped_ppo_loss`` (forward/backward in cache-sized chunks whose gradients add up), gradient-norm clipping.

Losses follow Tianshou's ``PPOPolicy``: ``loss = L_clip + vf_coef · mean((R − V)²) − ent_coef · H``.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import torch
from torch import nn

from np_policy.config import PPOConfig


def gae(rewards: np.ndarray, values: np.ndarray, next_values: np.ndarray, terminated: np.ndarray,
        truncated: np.ndarray, gamma: float, lam: float) -> tuple[np.ndarray, np.ndarray]:
    """Generalised advantage estimation over (T, N) arrays; returns (advantages, returns = advantages + values).

    δ_t = r_t + γ · V'_t · (1 − term_t) − V_t, with V'_t the value of the step's successor (of ``final_obs`` when
    the step ended an episode), so a truncated step bootstraps and a terminated one does not;
    A_t = δ_t + γλ · (1 − done_t) · A_{t+1}, done = term ∨ trunc, so no advantage flows across an episode end;
    the last row bootstraps from V'_{T−1} only (Tianshou treats unfinished episodes at the end of the data so).
    Inputs are not modified.
    """
    rewards = np.asarray(rewards, dtype=np.float64)
    values = np.asarray(values, dtype=np.float64)
    next_values = np.asarray(next_values, dtype=np.float64)
    term = np.asarray(terminated, dtype=bool)
    done = term | np.asarray(truncated, dtype=bool)
    delta = rewards + gamma * next_values * ~term - values
    advantages = np.zeros_like(rewards)
    running = np.zeros(rewards.shape[1:])
    for t in range(rewards.shape[0] - 1, -1, -1):
        running = delta[t] + gamma * lam * ~done[t] * running
        advantages[t] = running
    return advantages, advantages + values


class RunningMeanStd:
    """Running mean and variance of a stream of batches (parallel-variance update, as Tianshou's; starts at 0, 1)."""

    def __init__(self, shape: tuple[int, ...] = ()):
        self.mean = np.zeros(shape)
        self.var = np.ones(shape)
        self.count = 0

    def update(self, x: np.ndarray) -> None:
        """Fold the batch ``x`` (leading axis = samples) into the statistics."""
        x = np.asarray(x, dtype=np.float64)
        batch_mean, batch_var, batch_count = x.mean(axis=0), x.var(axis=0), x.shape[0]
        total = self.count + batch_count
        delta = batch_mean - self.mean
        m2 = self.var * self.count + batch_var * batch_count + delta**2 * self.count * batch_count / total
        self.mean = self.mean + delta * batch_count / total
        self.var = m2 / total
        self.count = total

    def state_dict(self) -> dict[str, Any]:
        """JSON-safe statistics (saved in checkpoints)."""
        return {"mean": np.asarray(self.mean).tolist(), "var": np.asarray(self.var).tolist(), "count": self.count}

    def load_state_dict(self, state: dict[str, Any]) -> None:
        self.mean, self.var, self.count = np.asarray(state["mean"]), np.asarray(state["var"]), int(state["count"])


def compute_targets(rewards: np.ndarray, values: np.ndarray, next_values: np.ndarray, terminated: np.ndarray,
                    truncated: np.ndarray, config: PPOConfig,
                    return_rms: RunningMeanStd | None) -> tuple[np.ndarray, np.ndarray]:
    """(advantages, critic targets) over (T, N); updates ``return_rms`` when reward normalisation is on.

    With ``config.norm_rewards`` the critic's outputs are in units of the running return std σ: values are
    multiplied by σ = √(var + ε) before ``gae``, the returns are divided by the same σ, then the statistics are
    updated with the raw returns (Tianshou ``PPOPolicy._compute_returns``). Advantages stay in reward units
    (they are normalised per minibatch anyway).
    """
    scale = np.sqrt(return_rms.var + config.norm_eps) if (config.norm_rewards and return_rms is not None) else 1.0
    advantages, returns = gae(rewards, np.asarray(values) * scale, np.asarray(next_values) * scale, terminated,
                              truncated, config.gamma, config.gae_lambda)
    if config.norm_rewards and return_rms is not None:
        targets = returns / scale
        return_rms.update(returns.reshape(-1))
        return advantages, targets
    return advantages, returns


def clipped_ppo_loss(new_log_prob: torch.Tensor, old_log_prob: torch.Tensor, advantages: torch.Tensor,
                     values: torch.Tensor, returns: torch.Tensor, entropy: torch.Tensor, clip_coef: float,
                     old_values: torch.Tensor | None = None) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
    """(policy loss, value loss, entropy mean) of one minibatch: the clipped surrogate of paper eq:ppo.

    ρ = exp(log π_new − log π_old); L_clip = −mean(min(ρ·A, clip(ρ, 1−ε, 1+ε)·A));
    L_V = mean((R − V)²), or with ``old_values`` the clipped form mean(max((R − V)², (R − V_clip)²)),
    V_clip = V_old + clip(V − V_old, −ε, ε). Advantages are used as given (normalise before calling).
    """
    ratio = (new_log_prob - old_log_prob).exp()
    surrogate = torch.min(ratio * advantages, ratio.clamp(1.0 - clip_coef, 1.0 + clip_coef) * advantages)
    policy_loss = -surrogate.mean()
    if old_values is None:
        value_loss = (returns - values).pow(2).mean()
    else:
        clipped = old_values + (values - old_values).clamp(-clip_coef, clip_coef)
        value_loss = torch.max((returns - values).pow(2), (returns - clipped).pow(2)).mean()
    return policy_loss, value_loss, entropy.mean()


def minibatch_indices(n: int, batch_size: int, generator: torch.Generator) -> list[torch.Tensor]:
    """Shuffled index chunks of ``batch_size``; a short last chunk is merged into the previous (``merge_last``)."""
    perm = torch.randperm(n, generator=generator)
    chunks = list(torch.split(perm, batch_size))
    if len(chunks) > 1 and len(chunks[-1]) < batch_size:
        last = chunks.pop()
        chunks[-1] = torch.cat([chunks[-1], last])
    return chunks


def accumulate_minibatch_gradient(model: nn.Module, batch: dict[str, torch.Tensor], idx: torch.Tensor,
                                  config: PPOConfig, shared_geometry: bool = False) -> dict[str, float]:
    """Add the gradient of one minibatch's PPO loss to ``.grad``; returns the minibatch's mean statistics.

    loss = L_clip + vf_coef · L_V − ent_coef · H over the minibatch ``idx`` (advantages normalised over all of
    it). The forward/backward passes run in chunks of ``config.update_chunk`` samples, each chunk's loss weighted
    by its share of the minibatch, so the summed gradient is the whole-minibatch gradient up to float rounding.
    ``shared_geometry`` runs the network's geometry branch once per distinct scene of a chunk
    (``SceneEncoder.geometry_token``): the same gradient up to float rounding, about 1.5× faster on Factorial.
    """
    adv = batch["advantages"][idx]
    if config.norm_advantages:
        adv = (adv - adv.mean()) / (adv.std() + config.norm_eps)
    n = len(idx)
    sums = dict.fromkeys(("policy_loss", "value_loss", "entropy", "approx_kl", "clip_fraction"), 0.0)
    for start in range(0, n, config.update_chunk):
        part = idx[start:start + config.update_chunk]
        share = len(part) / n
        log_prob, entropy, value = model.evaluate(batch["obs"][part], batch["actions"][part],
                                                  shared_geometry=shared_geometry)
        old_log_prob = batch["log_probs"][part]
        policy_loss, value_loss, entropy_mean = clipped_ppo_loss(
            log_prob, old_log_prob, adv[start:start + config.update_chunk], value, batch["returns"][part], entropy,
            config.clip_coef, batch["values"][part] if config.value_clip else None)
        loss = policy_loss + config.vf_coef * value_loss - config.ent_coef * entropy_mean
        (loss * share).backward()
        with torch.no_grad():
            log_ratio = log_prob - old_log_prob
            sums["approx_kl"] += share * ((log_ratio.exp() - 1) - log_ratio).mean().item()
            sums["clip_fraction"] += ((log_ratio.exp() - 1).abs() > config.clip_coef).sum().item() / n
        sums["policy_loss"] += share * policy_loss.item()
        sums["value_loss"] += share * value_loss.item()
        sums["entropy"] += share * entropy_mean.item()
    return sums


def ppo_update(model: nn.Module, optimizer: torch.optim.Optimizer, batch: dict[str, torch.Tensor],
               config: PPOConfig, generator: torch.Generator, shared_geometry: bool = False) -> dict[str, float]:
    """``config.repeats`` passes of shuffled minibatches over ``batch``; returns mean loss statistics.

    ``batch`` holds flat (M, ...) tensors: ``obs``, ``actions`` (unclipped), ``log_probs``, ``advantages``,
    ``returns`` (critic targets from ``compute_targets``) and, when ``config.value_clip``, ``values``.
    ``model`` is an ``ActorCritic`` (``evaluate(obs, action) -> (log_prob, entropy, value)``). Per minibatch:
    ``accumulate_minibatch_gradient`` (with ``shared_geometry``), gradient-norm clipping, one optimiser step.
    """
    stats: dict[str, list[float]] = {"policy_loss": [], "value_loss": [], "entropy": [], "approx_kl": [],
                                     "clip_fraction": [], "grad_norm": []}
    n = batch["obs"].shape[0]
    model.train()
    for _ in range(config.repeats):
        for idx in minibatch_indices(n, config.batch_size, generator):  # drawn on the CPU whatever the device
            idx = idx.to(batch["obs"].device)
            optimizer.zero_grad()
            for key, value in accumulate_minibatch_gradient(model, batch, idx, config, shared_geometry).items():
                stats[key].append(value)
            stats["grad_norm"].append(float(nn.utils.clip_grad_norm_(model.parameters(), config.max_grad_norm)))
            optimizer.step()
    return {k: float(np.mean(v)) for k, v in stats.items()}


def make_optimizer(model: nn.Module, config: PPOConfig) -> torch.optim.Adam:
    """Adam over the model's parameters at ``config.learning_rate``."""
    return torch.optim.Adam(model.parameters(), lr=config.learning_rate, eps=config.adam_eps)


def set_learning_rate(optimizer: torch.optim.Optimizer, lr: float) -> None:
    """Set every parameter group's learning rate (the trainer calls it with ``config.lr_at(update)``)."""
    for group in optimizer.param_groups:
        group["lr"] = lr
