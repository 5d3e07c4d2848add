"""The NeuralParker scene encoder and actor–critic (paper §III-C, Fig. architecture, App. A Table IV).

Streams follow ``ObservationConfig`` and are sliced from the flat observation with ``observation_sections``:

| stream     | input                  | embedding                                                              |
|------------|------------------------|------------------------------------------------------------------------|
| ego        | 4                      | MLP 4 → 64 → 128 (one fusion token)                                    |
| lidar      | n_beams (120)          | MLP 120 → 64 → 128 (one fusion token), when ``use_lidar``              |
| obstacles  | 20 slots × 16          | per-slot MLP 16 → 64 → 16 (geometry tokens), when ``use_obstacles``    |
| boundary   | 10 slots × 4           | per-slot MLP 4 → 64 → 16 (geometry tokens), when ``use_boundary``      |
| bev        | bev_latent_dim (128)   | MLP 128 → 64 → 128 (one fusion token), when ``use_bev``                |

Geometry tokens get a learned positional embedding per slot (30 slots) and pass one self-attention block
(``Attn(Z) = softmax((Z W_Q)(Z W_K)^T / √d) Z W_V``, d = 16, one head) followed by a feed-forward block, each
with a residual connection and LayerNorm (post-norm). There is **no padding mask**: unused slots carry the −1e4
sentinel through the stream MLP and attention as they are (paper App. A). The tokens are mean-pooled and
projected to one 128-D fusion token (the global geometry summary).

The BEV branch (paper App. B, the NeuralParker-backbone BEV control) replaces the geometry tokens: the env's
frozen-encoder latent of the BEV raster (``np_policy.bev_encoder``) passes a stream MLP to one fusion token, so the
fusion sees ego, LiDAR and BEV tokens. Without ``use_bev`` the network, its parameters and their initialisation
are those of the other configurations unchanged.

Global–local fusion: the geometry, ego and LiDAR tokens (128-D each) pass ``fusion_depth`` (1) transformer layers
with 4 heads of 32; the output tokens are flattened (so each stream keeps its identity) and projected to the
128-D feature.

Actor and critic: the paper's caption says "the shared representation is passed to the actor and critic
networks" and Table IV says "separate [64, 128, 256, 64] networks", so the **encoder is shared** and the two MLP
heads are separate. The actor outputs the mean of a diagonal Gaussian over the normalised 2-D action with a
state-independent learned log-std; samples are clipped to [−1, 1] before the env (``clip_action``), log-probs are
those of the unclipped sample (Tianshou ``action_bound_method="clip"``).

Attention runs on a fused QKV projection (``attention``): ``torch.nn.functional.scaled_dot_product_attention`` for
the geometry tokens, where it was faster than ``nn.MultiheadAttention`` at batch 8,192, and broadcast products for
the three fusion tokens, where it is not (see ``np_policy/bench_update.py`` and the README).
Initialisation follows Tianshou's MuJoCo PPO example: orthogonal weights (gain √2), zero biases, the actor's last
layer scaled by 0.01.
"""

from __future__ import annotations

import math

import numpy as np
import torch
import torch.nn.functional as F
from torch import nn

import np_policy.bev_encoder  # noqa: F401 (registers the frozen-encoder loader of the env's BEV observation)
from np_sim.config import ObservationConfig
from np_sim.observation import observation_sections, observation_size
from np_policy.config import NetworkConfig


def mlp(sizes: list[int], activate_last: bool = False) -> nn.Sequential:
    """Linear layers of ``sizes`` with a ReLU between two (and after the last with ``activate_last``)."""
    layers: list[nn.Module] = []
    for i, (a, b) in enumerate(zip(sizes[:-1], sizes[1:])):
        layers.append(nn.Linear(a, b))
        if i < len(sizes) - 2 or activate_last:
            layers.append(nn.ReLU())
    return nn.Sequential(*layers)


class SelfAttentionBlock(nn.Module):
    """Post-norm transformer layer: x ← LN(x + MHA(x)); x ← LN(x + FF(x)). No mask, no dropout."""

    def __init__(self, dim: int, heads: int, ff_dim: int):
        super().__init__()
        self.heads = heads
        self.qkv = nn.Linear(dim, 3 * dim)
        self.out = nn.Linear(dim, dim)
        self.norm1 = nn.LayerNorm(dim)
        self.ff = nn.Sequential(nn.Linear(dim, ff_dim), nn.ReLU(), nn.Linear(ff_dim, dim))
        self.norm2 = nn.LayerNorm(dim)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        """x: (B, S, dim) -> (B, S, dim)."""
        b, s, d = x.shape
        q, k, v = self.qkv(x).view(b, s, 3, self.heads, d // self.heads).permute(2, 0, 3, 1, 4)
        attn = attention(q, k, v)  # (B, H, S, d_h)
        x = self.norm1(x + self.out(attn.transpose(1, 2).reshape(b, s, d)))
        return self.norm2(x + self.ff(x))


SHORT_SEQUENCE = 4
"""Up to this many tokens ``attention`` uses broadcast products instead of ``scaled_dot_product_attention``."""


def attention(q: torch.Tensor, k: torch.Tensor, v: torch.Tensor) -> torch.Tensor:
    """softmax(Q Kᵀ / √d_h) V over (B, H, S, d_h) tensors (paper §III-C, Attn; the attention of ``SelfAttentionBlock``).

    For the three fusion tokens the broadcast form is 3× faster forward + backward on CPU than
    ``scaled_dot_product_attention``, whose kernel is tuned for long sequences; for the 30 geometry tokens the
    library kernel is the faster one (``np_policy/bench_update.py`` times the whole update).
    """
    if q.shape[-2] > SHORT_SEQUENCE:
        return F.scaled_dot_product_attention(q, k, v)
    scores = (q.unsqueeze(-2) * k.unsqueeze(-3)).sum(-1) * (1.0 / math.sqrt(q.shape[-1]))  # (B, H, S, S)
    return (scores.softmax(-1).unsqueeze(-1) * v.unsqueeze(-3)).sum(-2)


class SceneEncoder(nn.Module):
    """Flat observation (B, obs_size) -> 128-D feature (B, fusion_dim); streams as in ``ObservationConfig``."""

    def __init__(self, obs_config: ObservationConfig, net_config: NetworkConfig | None = None):
        super().__init__()
        net = NetworkConfig() if net_config is None else net_config
        self.obs_config, self.net_config = obs_config, net
        self.sections = observation_sections(obs_config)
        self.obs_size = observation_size(obs_config)
        h, d, t = net.stream_hidden, net.fusion_dim, net.token_dim

        self.ego = mlp([self.sections["ego"][1] - self.sections["ego"][0], h, d])
        self.lidar = mlp([obs_config.n_beams, h, d]) if "lidar" in self.sections else None
        self.obstacle = mlp([2 * obs_config.vertices_per_obstacle, h, t]) if "obstacles" in self.sections else None
        self.boundary = mlp([4, h, t]) if "boundary" in self.sections else None
        n_slots = (obs_config.max_obstacles if self.obstacle is not None else 0) + (
            obs_config.max_boundary_segments if self.boundary is not None else 0)
        self.n_slots = n_slots
        slot_sections = [self.sections[name] for name in ("obstacles", "boundary") if name in self.sections]
        self.slot_span = (slot_sections[0][0], slot_sections[-1][1]) if slot_sections else (0, 0)
        if n_slots:
            self.slot_position = nn.Parameter(torch.randn(n_slots, t) * 0.02)
            self.geometry_attention = SelfAttentionBlock(t, net.token_heads, net.token_ff_dim)
            self.geometry_summary = nn.Linear(t, d)
        self.bev = mlp([obs_config.bev_latent_dim, h, d]) if "bev" in self.sections else None
        self.n_tokens = 1 + (self.lidar is not None) + (n_slots > 0) + (self.bev is not None)
        self.fusion = nn.Sequential(*[SelfAttentionBlock(d, net.fusion_heads, net.fusion_ff_dim)
                                      for _ in range(net.fusion_depth)])
        self.project = nn.Linear(self.n_tokens * d, d)
        self.feature_dim = d

    def _slice(self, obs: torch.Tensor, name: str) -> torch.Tensor:
        a, b = self.sections[name]
        return obs[:, a:b]

    def geometry_tokens(self, slots: torch.Tensor) -> torch.Tensor:
        """(B, n_slots, token_dim) embedded slot tokens plus positional embeddings (before attention).

        ``slots`` is the (B, span) slot part of the observations, ``obs[:, slice(*self.slot_span)]``: the obstacle
        slots, then the boundary slots (adjacent in the flat layout)."""
        parts, start = [], 0
        if self.obstacle is not None:
            size = self.obs_config.max_obstacles * 2 * self.obs_config.vertices_per_obstacle
            parts.append(self.obstacle(slots[:, :size].reshape(slots.shape[0], self.obs_config.max_obstacles, -1)))
            start = size
        if self.boundary is not None:
            boundary = slots[:, start:].reshape(slots.shape[0], self.obs_config.max_boundary_segments, 4)
            parts.append(self.boundary(boundary))
        return torch.cat(parts, dim=1) + self.slot_position

    def geometry_token(self, slots: torch.Tensor, shared: bool = False) -> torch.Tensor:
        """(B, fusion_dim) global geometry summary of (B, span) slot rows: slot MLPs, self-attention, mean pool,
        projection (paper §III-C, the geometry branch of Fig. architecture).

        With ``shared`` the branch runs once per distinct slot row and its result is gathered back: rows of one
        scene are equal (the slots are fixed in the target frame), so a PPO minibatch of 8,192 training samples
        holds at most as many distinct rows as there are training scenes (81 on Factorial). The values are the
        same; only the float summation order of the gradient differs (the duplicates' gradients are added
        before, not after, the branch's backward pass).
        """
        if not shared:
            return self.geometry_summary(self.geometry_attention(self.geometry_tokens(slots)).mean(dim=1))
        distinct, row = torch.unique(slots, dim=0, return_inverse=True)
        return self.geometry_token(distinct)[row]

    def forward(self, obs: torch.Tensor, shared_geometry: bool = False) -> torch.Tensor:
        """obs: (B, obs_size) float32 -> (B, fusion_dim); ``shared_geometry``: see ``geometry_token``."""
        if obs.shape[-1] != self.obs_size:
            raise ValueError(f"SceneEncoder: expected observations of size {self.obs_size} for "
                             f"sections {self.sections}, got shape {tuple(obs.shape)}")
        tokens = [self.ego(self._slice(obs, "ego"))]
        if self.lidar is not None:
            tokens.append(self.lidar(self._slice(obs, "lidar")))
        if self.n_slots:
            tokens.append(self.geometry_token(obs[:, self.slot_span[0]:self.slot_span[1]], shared_geometry))
        if self.bev is not None:
            tokens.append(self.bev(self._slice(obs, "bev")))
        fused = self.fusion(torch.stack(tokens, dim=1))
        return F.relu(self.project(fused.flatten(1)))


class ActorCritic(nn.Module):
    """Shared ``SceneEncoder``; separate actor and critic MLPs; diagonal Gaussian with a learned log-std."""

    def __init__(self, obs_config: ObservationConfig, net_config: NetworkConfig | None = None):
        super().__init__()
        net = NetworkConfig() if net_config is None else net_config
        self.net_config = net
        self.encoder = SceneEncoder(obs_config, net)
        d = self.encoder.feature_dim
        self.actor = mlp([d, *net.head_hidden, net.action_dim])
        self.critic = mlp([d, *net.head_hidden, 1])
        self.log_std = nn.Parameter(torch.full((net.action_dim,), float(net.init_log_std)))
        self._init_weights()

    def _init_weights(self) -> None:
        for m in self.modules():
            if isinstance(m, nn.Linear):
                nn.init.orthogonal_(m.weight, gain=math.sqrt(2))
                nn.init.zeros_(m.bias)
        with torch.no_grad():
            self.actor[-1].weight.mul_(0.01)

    def distribution(self, obs: torch.Tensor, shared_geometry: bool = False
                     ) -> tuple[torch.distributions.Normal, torch.Tensor]:
        """(per-dimension Normal over the normalised action, value (B,)); ``shared_geometry``: see
        ``SceneEncoder.geometry_token``."""
        feature = self.encoder(obs, shared_geometry)
        mean = self.actor(feature)
        std = self.log_std.exp().expand_as(mean)
        return torch.distributions.Normal(mean, std), self.critic(feature).squeeze(-1)

    @torch.no_grad()
    def act(self, obs: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
        """Sample: (unclipped action (B, 2), log-prob (B,), value (B,)). Clip with ``clip_action`` before the env."""
        dist, value = self.distribution(obs)
        action = dist.sample()
        return action, dist.log_prob(action).sum(-1), value

    def evaluate(self, obs: torch.Tensor, action: torch.Tensor, shared_geometry: bool = False
                 ) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
        """(log-prob (B,), entropy (B,), value (B,)) of stored unclipped actions; differentiable.
        ``shared_geometry``: see ``SceneEncoder.geometry_token``."""
        dist, value = self.distribution(obs, shared_geometry)
        return dist.log_prob(action).sum(-1), dist.entropy().sum(-1), value

    @torch.no_grad()
    def value(self, obs: torch.Tensor) -> torch.Tensor:
        """Critic value (B,)."""
        return self.critic(self.encoder(obs)).squeeze(-1)

    @torch.no_grad()
    def mean_action(self, obs: torch.Tensor) -> torch.Tensor:
        """Deterministic action: the Gaussian mean clipped to [−1, 1] (B, 2)."""
        return self.actor(self.encoder(obs)).clamp(-1.0, 1.0)


def clip_action(action: np.ndarray | torch.Tensor):
    """Map a sampled normalised action to the env's Box(−1, 1) (Tianshou ``action_bound_method='clip'``)."""
    if isinstance(action, torch.Tensor):
        return action.clamp(-1.0, 1.0)
    return np.clip(action, -1.0, 1.0)
