"""Tests of hope_policy/network.py: shapes, parameter counts hand-computed from the paper's sizes (App.
app:hope-adaptation: 128-D embeddings, one attention block of eight 32-D heads with a 128-unit feed-forward, a
128-unit hidden layer), the attention block against torch's own attention, and HOPE's initialisation."""

from __future__ import annotations

import math

import numpy as np
import torch
import torch.nn.functional as F

from hope_policy.network import AttentionBlock, HopeActorCritic, Modalities

FULL = Modalities((("lidar", 120), ("target", 5), ("action_mask", 42)))
NO_MASK = Modalities((("lidar", 120), ("target", 5)))


def linear(n_in, n_out, bias=True):
    return n_in * n_out + (n_out if bias else 0)


def expected_backbone(inputs, outputs):
    """Parameters of one network, counted layer by layer from the paper's sizes."""
    d, heads, head_dim, ff, hidden = 128, 8, 32, 128, 128
    embeddings = sum(linear(n, d) + linear(d, d) for n in inputs)
    attention = 2 * d + linear(d, 3 * heads * head_dim, bias=False) + linear(heads * head_dim, d)
    feedforward = 2 * d + linear(d, ff) + linear(ff, d)
    head = linear(len(inputs) * d, hidden) + linear(hidden, outputs)
    return embeddings + attention + feedforward + head


def count(module):
    return sum(p.numel() for p in module.parameters())


def test_parameter_counts_follow_the_paper_sizes():
    model = HopeActorCritic(FULL)
    assert count(model.actor) == expected_backbone([120, 5, 42], 2)
    assert count(model.critic) == expected_backbone([120, 5, 42], 1)
    assert model.log_std.numel() == 2
    # written out once by hand: embeddings 32000 + 17280 + 22016, attention 131456, feed-forward 33280,
    # hidden 49280, output 258 (actor)
    assert count(model.actor) == 32000 + 17280 + 22016 + 131456 + 33280 + 49280 + 258
    assert count(HopeActorCritic(NO_MASK).actor) == expected_backbone([120, 5], 2)


def test_shapes_and_ranges():
    model = HopeActorCritic(FULL)
    obs = {"lidar": torch.randn(7, 120) * 5, "target": torch.randn(7, 5), "action_mask": torch.rand(7, 42)}
    dist = model.distribution(obs)
    assert dist.mean.shape == (7, 2) and model.value(obs).shape == (7,)
    assert dist.mean.abs().max() <= 1.0
    np.testing.assert_allclose(dist.stddev.detach().numpy(), 1.0)  # log σ starts at 0


def test_attention_block_matches_torch_attention():
    torch.manual_seed(0)
    block = AttentionBlock()
    with torch.no_grad():
        for p in block.parameters():
            p.add_(0.1 * torch.randn_like(p))
    x = torch.randn(4, 3, 128)
    h = F.layer_norm(x, (128,), block.norm1.weight, block.norm1.bias)
    q, k, v = (t.view(4, 3, 8, 32).transpose(1, 2) for t in block.qkv(h).chunk(3, dim=-1))
    attended = F.scaled_dot_product_attention(q, k, v).transpose(1, 2).reshape(4, 3, 256)
    y = x + block.out(attended)
    y = y + block.ff(F.layer_norm(y, (128,), block.norm2.weight, block.norm2.bias))
    torch.testing.assert_close(block(x), y, rtol=1e-5, atol=1e-5)


def test_orthogonal_initialisation_and_zero_bias():
    model = HopeActorCritic(FULL)
    w = model.actor.embed["lidar"][2].weight.detach()  # square 128 × 128
    torch.testing.assert_close(w @ w.T, torch.eye(128), rtol=0, atol=1e-5)
    assert all(float(m.bias.detach().abs().max()) == 0.0 for m in model.modules()
               if isinstance(m, torch.nn.Linear) and m.bias is not None)
    assert math.isclose(float(model.actor.embed["target"][0].weight.detach().T.matmul(
        model.actor.embed["target"][0].weight.detach()).trace()), 5.0, rel_tol=1e-5)
