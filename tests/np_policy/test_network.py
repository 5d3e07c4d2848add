"""Tests of np_policy/network.py: shapes per observation config, sentinel slots, positional embeddings."""

from __future__ import annotations

import math

import numpy as np
import pytest
import torch

from np_sim.config import ObservationConfig
from np_sim.errors import CapacityError
from np_sim.observation import obstacle_slots, observation_sections, observation_size
from np_sim.scene import Scene
from np_policy.config import NetworkConfig
from np_policy.network import SHORT_SEQUENCE, ActorCritic, SceneEncoder, attention, clip_action

CONFIGS = {
    "default": ObservationConfig(),
    "no_lidar": ObservationConfig(use_lidar=False),
    "ego_lidar": ObservationConfig(use_obstacles=False, use_boundary=False),
}
OPEN_LOT = {"boundary": [[-20, -25], [20, -25], [20, 25], [-20, 25]], "obstacles": [],
            "target": [0.0, 0.0, math.pi / 2]}


def make_obs(config: ObservationConfig, batch: int, used_obstacles: int = 3, used_segments: int = 4, seed: int = 0):
    """Random flat observations with the given slots used and the rest at the sentinel."""
    rng = np.random.default_rng(seed)
    obs = rng.normal(0.0, 5.0, (batch, observation_size(config))).astype(np.float32)
    sec = observation_sections(config)
    if "lidar" in sec:
        a, b = sec["lidar"]
        obs[:, a:b] = rng.uniform(0.0, 10.0, (batch, b - a))
    if "obstacles" in sec:
        a, _ = sec["obstacles"]
        obs[:, a + used_obstacles * 16: sec["obstacles"][1]] = config.sentinel
    if "boundary" in sec:
        a, _ = sec["boundary"]
        obs[:, a + used_segments * 4: sec["boundary"][1]] = config.sentinel
    return torch.from_numpy(obs)


@pytest.mark.parametrize("name", list(CONFIGS))
def test_output_shapes_follow_the_observation_config(name):
    torch.manual_seed(0)
    config = CONFIGS[name]
    model = ActorCritic(config)
    obs = make_obs(config, 5)
    assert model.encoder(obs).shape == (5, 128)
    action, log_prob, value = model.act(obs)
    assert action.shape == (5, 2) and log_prob.shape == (5,) and value.shape == (5,)
    log_prob2, entropy, value2 = model.evaluate(obs, action)
    assert log_prob2.shape == entropy.shape == value2.shape == (5,)
    torch.testing.assert_close(log_prob2, log_prob)
    mean = model.mean_action(obs)
    assert mean.shape == (5, 2) and mean.abs().max() <= 1.0
    assert model.encoder.n_tokens == {"default": 3, "no_lidar": 2, "ego_lidar": 2}[name]


SLOT_CONFIGS = {**CONFIGS, "obstacles_only": ObservationConfig(use_boundary=False),
                "boundary_only": ObservationConfig(use_obstacles=False, use_lidar=False)}


@pytest.mark.parametrize("name", list(SLOT_CONFIGS))
def test_the_shared_geometry_branch_runs_once_per_scene_and_gives_each_sample_its_own_output(name):
    """Twelve samples of three scenes (equal slot rows; ego and LiDAR their own): each sample's feature with the
    branch shared over the batch equals that sample's feature computed alone; the attention block sees three rows."""
    torch.manual_seed(1)
    config = SLOT_CONFIGS[name]
    encoder = SceneEncoder(config)
    obs = make_obs(config, 12, seed=1)
    scene_rows = make_obs(config, 3, seed=2)
    a, b = encoder.slot_span
    assert b - a == sum(stop - start for key, (start, stop) in observation_sections(config).items()
                        if key in ("obstacles", "boundary"))
    obs[:, a:b] = scene_rows[torch.arange(12) % 3, a:b]
    seen = []
    if encoder.n_slots:
        encoder.geometry_attention.register_forward_hook(lambda module, args, out: seen.append(args[0].shape[0]))
    with torch.no_grad():
        shared = encoder(obs, shared_geometry=True)
        alone = torch.cat([encoder(obs[i:i + 1]) for i in range(12)])
    torch.testing.assert_close(shared, alone, rtol=1e-5, atol=1e-5)
    assert seen[:1] == ([3] if encoder.n_slots else [])


def test_wrong_observation_size_is_an_error():
    model = SceneEncoder(ObservationConfig())
    with pytest.raises(ValueError, match="expected observations of size 484"):
        model(torch.zeros(2, 124))


def test_sentinel_slots_pass_without_nan_and_with_gradients():
    torch.manual_seed(0)
    config = ObservationConfig()
    model = ActorCritic(config)
    obs = make_obs(config, 8, used_obstacles=0, used_segments=1)  # almost every slot is the −1e4 sentinel
    log_prob, entropy, value = model.evaluate(obs, torch.zeros(8, 2))
    (log_prob.mean() + value.mean()).backward()
    assert torch.isfinite(log_prob).all() and torch.isfinite(value).all()
    assert all(torch.isfinite(p.grad).all() for p in model.parameters() if p.grad is not None)


def test_permuting_two_used_obstacle_slots_changes_the_output():
    torch.manual_seed(0)
    config = ObservationConfig()
    model = ActorCritic(config)
    obs = make_obs(config, 4, used_obstacles=3)
    a, _ = observation_sections(config)["obstacles"]
    swapped = obs.clone()
    swapped[:, a:a + 16], swapped[:, a + 16:a + 32] = obs[:, a + 16:a + 32], obs[:, a:a + 16]
    with torch.no_grad():
        difference = (model.encoder(obs) - model.encoder(swapped)).abs().max()
    assert difference > 1e-5  # learned per-slot positional embeddings make the slots distinguishable


def test_a_scene_over_capacity_cannot_be_observed():
    """The network never sees truncated geometry: np_sim raises CapacityError before an observation exists."""
    many = [{"circle": [-15 + 1.4 * i, 20.0, 0.5]} for i in range(21)]
    scene = Scene.from_dict(dict(OPEN_LOT, obstacles=many))
    with pytest.raises(CapacityError, match="21 obstacles exceed"):
        obstacle_slots(scene, ObservationConfig())


def test_clip_action_bounds_numpy_and_torch():
    assert np.array_equal(clip_action(np.array([[-3.0, 0.5]])), [[-1.0, 0.5]])
    assert torch.equal(clip_action(torch.tensor([[2.0, -0.25]])), torch.tensor([[1.0, -0.25]]))


def test_fusion_depth_and_heads_come_from_the_config():
    model = SceneEncoder(ObservationConfig(), NetworkConfig(fusion_depth=2))
    assert len(model.fusion) == 2 and model.fusion[0].heads == 4
    assert model.geometry_attention.heads == 1 and model.slot_position.shape == (30, 16)


@pytest.mark.parametrize("shape", [(5, 4, 3, 32), (5, 1, SHORT_SEQUENCE, 16), (5, 1, 30, 16)])
def test_attention_equals_the_library_kernel_values_and_gradients(shape):
    """Both paths of ``attention`` (broadcast for short sequences, the library kernel otherwise) against
    ``scaled_dot_product_attention`` and a hand softmax(QKᵀ/√d)V, in float64."""
    g = torch.Generator().manual_seed(sum(shape))
    q, k, v = (torch.randn(*shape, generator=g, dtype=torch.float64, requires_grad=True) for _ in range(3))
    ours = attention(q, k, v)
    library = torch.nn.functional.scaled_dot_product_attention(q, k, v)
    by_hand = torch.softmax(q @ k.transpose(-2, -1) / math.sqrt(shape[-1]), dim=-1) @ v
    torch.testing.assert_close(ours, library)
    torch.testing.assert_close(ours, by_hand)
    weights = torch.randn(*shape, generator=g, dtype=torch.float64)
    grads = [torch.autograd.grad((out * weights).sum(), (q, k, v)) for out in (attention(q, k, v), by_hand)]
    for ours_grad, hand_grad in zip(*grads):
        torch.testing.assert_close(ours_grad, hand_grad)
