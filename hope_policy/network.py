"""The adapted HOPE actor and critic (paper §IV-B, App. ``app:hope-adaptation``; HOPE's ``MultiObsEmbedding``).

Each active modality (LiDAR, target, the action mask when it is used, and the added scene input of a HOPE-style
backbone) is embedded in 128-D: a flat vector (LiDAR, target, mask) by ``Linear → tanh → Linear``; the BEV
raster's frozen-autoencoder latent (`hope_policy.inputs`) by HOPE's re-embedding of its image latent,
``tanh → Linear``; the target-relative vertices by the attention-based vertex branch the paper names
(``VertexBranch``: NeuralParker's slot tokens and self-attention). The embeddings form a sequence of tokens fused
by one pre-norm attention block (eight 32-D heads, a 128-unit tanh feed-forward sublayer, residual connections);
the flattened tokens pass a 128-unit tanh hidden layer to the output. The actor's output is squashed by tanh and is
the mean of a diagonal Gaussian over the normalised 2-D action with a state-independent learned log standard
deviation (initially 0); the critic's output is the value. Weights are orthogonal with gain 1 and biases zero, as
in HOPE.

HOPE's unused ``view_embed`` parameter (created as zeros and never added) is left out.
"""

from __future__ import annotations

from dataclasses import dataclass

import torch
from torch import nn

from np_policy.config import NetworkConfig
from np_policy.network import SelfAttentionBlock, mlp

EMBED = 128
"""Width of each modality's embedding (paper App. ``app:hope-adaptation``)."""
HEADS = 8
HEAD_DIM = 32
FEEDFORWARD = 128
HIDDEN = 128
ACTION_DIM = 2


@dataclass(frozen=True)
class Modalities:
    """Input branches of a network: name and feature count of each flat vector input, in token order."""

    sizes: tuple[tuple[str, int], ...]
    """(observation key, features) pairs, e.g. (("lidar", 120), ("target", 5), ("action_mask", 42)); for ``bev``
    the latent size of its frozen encoder."""
    vertex_slots: tuple[tuple[int, int], ...] = ()
    """With a ``vertices`` input: its flat vector's parts as (slots, features per slot), in order — the obstacle
    slots (20, 16) then the boundary slots (10, 4) (`hope_policy.spaces.vertex_shapes`)."""


LATENT_KEYS = ("bev",)
"""Inputs that are a frozen encoder's latent, re-embedded as HOPE's ``re_embed_img`` (tanh → Linear)."""


def _embedding(key: str, features: int, modalities: Modalities) -> nn.Module:
    if key in LATENT_KEYS:
        return nn.Sequential(nn.Tanh(), nn.Linear(features, EMBED))
    if key == "vertices":
        return VertexBranch(modalities.vertex_slots, features)
    return nn.Sequential(nn.Linear(features, EMBED), nn.Tanh(), nn.Linear(EMBED, EMBED))


class VertexBranch(nn.Module):
    """The attention-based vertex input branch of the HOPE-style vertices backbone (App. B, "Controlled
    Representation Inputs"): NeuralParker's slot-token encoder (paper §III-C, `np_policy.network.SceneEncoder`'s
    geometry stream, the same sizes): each obstacle slot (its target-frame vertices) and each boundary slot (a
    segment) embedded into a token by the MLP of its kind, a learned position per slot added, one self-attention
    layer over the slots, the mean over slots, and a linear map to the 128-D embedding the fusion block reads."""

    def __init__(self, slots: tuple[tuple[int, int], ...], features: int):
        super().__init__()
        if not slots or sum(n * width for n, width in slots) != features:
            raise ValueError(f"VertexBranch: slots {slots} do not make up the {features} vertex features")
        net = NetworkConfig()
        self.slots = tuple(slots)
        self.tokens = nn.ModuleList([mlp([width, net.stream_hidden, net.token_dim]) for _, width in self.slots])
        self.position = nn.Parameter(torch.randn(sum(n for n, _ in self.slots), net.token_dim) * 0.02)
        self.attention = SelfAttentionBlock(net.token_dim, net.token_heads, net.token_ff_dim)
        self.summary = nn.Linear(net.token_dim, EMBED)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        """``x``: (batch, features) → (batch, 128)."""
        parts, start = [], 0
        for (n, width), embed in zip(self.slots, self.tokens):
            parts.append(embed(x[:, start:start + n * width].reshape(x.shape[0], n, width)))
            start += n * width
        return self.summary(self.attention(torch.cat(parts, dim=1) + self.position).mean(dim=1))


class AttentionBlock(nn.Module):
    """One pre-norm transformer block: ``x + MHA(LN(x))`` then ``x + FF(LN(x))`` with a tanh feed-forward."""

    def __init__(self):
        super().__init__()
        inner = HEADS * HEAD_DIM
        self.norm1 = nn.LayerNorm(EMBED)
        self.qkv = nn.Linear(EMBED, 3 * inner, bias=False)
        self.out = nn.Linear(inner, EMBED)
        self.norm2 = nn.LayerNorm(EMBED)
        self.ff = nn.Sequential(nn.Linear(EMBED, FEEDFORWARD), nn.Tanh(), nn.Linear(FEEDFORWARD, EMBED))

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        """``x``: (batch, tokens, 128) → same shape."""
        b, n, _ = x.shape
        q, k, v = self.qkv(self.norm1(x)).view(b, n, 3, HEADS, HEAD_DIM).permute(2, 0, 3, 1, 4)
        attn = torch.softmax(q @ k.transpose(-1, -2) * HEAD_DIM ** -0.5, dim=-1)
        x = x + self.out((attn @ v).transpose(1, 2).reshape(b, n, HEADS * HEAD_DIM))
        return x + self.ff(self.norm2(x))


class FusionNetwork(nn.Module):
    """Modality embeddings → attention block → flattened tokens → 128 tanh → output (HOPE's fused backbone)."""

    def __init__(self, modalities: Modalities, output: int, tanh_output: bool):
        super().__init__()
        self.keys = tuple(key for key, _ in modalities.sizes)
        self.embed = nn.ModuleDict({key: _embedding(key, n, modalities) for key, n in modalities.sizes})
        self.block = AttentionBlock()
        self.head = nn.Sequential(nn.Linear(len(self.keys) * EMBED, HIDDEN), nn.Tanh(), nn.Linear(HIDDEN, output))
        self.tanh_output = tanh_output
        for module in self.modules():
            if isinstance(module, nn.Linear):
                nn.init.orthogonal_(module.weight, gain=1.0)
                if module.bias is not None:
                    nn.init.zeros_(module.bias)

    def forward(self, obs: dict[str, torch.Tensor]) -> torch.Tensor:
        """``obs``: each key of the modalities as (batch, features) → (batch, output)."""
        tokens = torch.stack([self.embed[key](obs[key]) for key in self.keys], dim=1)
        out = self.head(self.block(tokens).flatten(1))
        return torch.tanh(out) if self.tanh_output else out


class HopeActorCritic(nn.Module):
    """Actor (Gaussian mean, tanh-squashed), learned log standard deviation and critic (value)."""

    def __init__(self, modalities: Modalities):
        super().__init__()
        self.modalities = modalities
        self.actor = FusionNetwork(modalities, ACTION_DIM, tanh_output=True)
        self.log_std = nn.Parameter(torch.zeros(ACTION_DIM))
        self.critic = FusionNetwork(modalities, 1, tanh_output=False)

    def distribution(self, obs: dict[str, torch.Tensor]) -> torch.distributions.Normal:
        """The policy ``N(clamp(μ(o), −1, 1), exp(log σ)²)`` over the normalised action (HOPE's gaussian head)."""
        mean = self.actor(obs).clamp(-1.0, 1.0)
        return torch.distributions.Normal(mean, self.log_std.exp().expand_as(mean))

    def value(self, obs: dict[str, torch.Tensor]) -> torch.Tensor:
        """V(o), shape (batch,)."""
        return self.critic(obs).squeeze(-1)

    def actor_parameters(self) -> list[nn.Parameter]:
        """What the actor optimiser trains: the actor network and the log standard deviation."""
        return [*self.actor.parameters(), self.log_std]
