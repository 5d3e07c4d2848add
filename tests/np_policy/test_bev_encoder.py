"""The BEV autoencoder and its pretraining (paper App. B), the env's BEV observation and the network's BEV branch:
parameter counts from the paper's sizes, a tiny pretraining that lowers the held-out error, exact resumption,
the frozen encoder in the env, one-line errors."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import torch

from cli_helpers import one_error_line
from np_policy.bev_encoder import (AutoencoderConfig, BevAutoencoder, FrozenBevEncoder, PretrainConfig, as_input,
                                   collect_images, parameter_count, pretrain, reconstruction_mse, split)
from np_policy.checkpoint import CheckpointError, load_checkpoint
from np_policy.network import ActorCritic
from np_policy.pretrain_bev import main
from np_sim.bev import render_bev
from np_sim.config import EnvConfig, ObservationConfig
from np_sim.env import ParkingVectorEnv
from np_sim.errors import ConfigError
from np_sim.examples import example_scenes
from np_sim.kernels import step as K
from np_sim.observation import observation_sections

TINY = PretrainConfig(benchmark="factorial", images=160, epochs=3, batch_size=16, collect_envs=16, seed=3)


def conv(c_in: int, c_out: int, k: int) -> int:
    return c_out * c_in * k * k + c_out


def linear(n_in: int, n_out: int) -> int:
    return n_in * n_out + n_out


def test_parameter_counts_follow_the_paper_sizes():
    """4- and 8-channel 3×3 stages with 1×1 shortcuts, 64 → 16 pixels, FC 2048 → 256 → 128 and back."""
    flat = 8 * 16 * 16
    encoder = (conv(3, 4, 3) + conv(3, 4, 1) + conv(4, 8, 3) + conv(4, 8, 1)
               + linear(flat, 256) + linear(256, 128))
    decoder = (linear(128, 256) + linear(256, flat)
               + conv(8, 4, 3) + conv(4, 4, 3) + conv(8, 4, 1) + conv(4, 4, 1)  # stage 8 → 4
               + conv(4, 3, 3) + conv(3, 3, 3) + conv(4, 3, 1) + conv(3, 3, 1))  # stage 4 → 3
    model = BevAutoencoder()
    assert parameter_count(model.encoder) == encoder == 557_904
    assert parameter_count(model) == encoder + decoder


def test_shapes_and_ranges():
    model = BevAutoencoder(AutoencoderConfig())
    x = torch.rand(5, 3, 64, 64)
    assert model.encoder(x).shape == (5, 128)
    with torch.no_grad():
        y = model(x)
    assert y.shape == x.shape and float(y.min()) > 0.0 and float(y.max()) < 1.0
    with pytest.raises(ConfigError, match="multiple of 2\\^2"):
        BevAutoencoder(size_px=30)


@pytest.fixture(scope="module", autouse=True)
def one_torch_thread():
    """Torch's worker threads spin-wait; on a loaded machine one thread trains these tiny batches many times
    faster."""
    before = torch.get_num_threads()
    torch.set_num_threads(1)
    yield
    torch.set_num_threads(before)


@pytest.fixture(scope="module")
def images() -> np.ndarray:
    return collect_images(example_scenes(), TINY)


@pytest.fixture(scope="module")
def pretrained(tmp_path_factory, images):
    out = tmp_path_factory.mktemp("ae") / "tiny.pt"
    rows = pretrain(TINY, out, images=images, log=lambda _: None)
    return out, rows


def test_collected_images_hold_trajectory_tails(images):
    assert images.shape == (TINY.images, 3, 64, 64) and images.dtype == np.uint8
    newest = (images[:, 0] == 10) & (images[:, 1] == 10) & (images[:, 2] == 200)  # the newest tail footprint
    ego = (images[:, 0] == 30) & (images[:, 1] == 144) & (images[:, 2] == 255)  # an ego without a tail
    with_tail = newest.any(axis=(1, 2))
    assert with_tail.any() and ego.any(axis=(1, 2)).any()
    assert not (with_tail & ego.any(axis=(1, 2))).any()  # the tail's newest pose covers the ego
    np.testing.assert_array_equal(collect_images(example_scenes(), dataclasses.replace(TINY, images=50)),
                                  images[:50])  # same seed, same images


def test_tiny_pretraining_lowers_the_held_out_error(pretrained, images):
    _, rows = pretrained
    _, held = split(len(images), TINY)
    torch.manual_seed(TINY.seed)
    untrained = reconstruction_mse(BevAutoencoder(), images[held])
    assert [r["epoch"] for r in rows] == [1, 2, 3]
    assert rows[-1]["held_out_mse"] < 0.8 * untrained
    assert rows[-1]["held_out_mse"] < rows[0]["held_out_mse"]


def test_the_finished_pretraining_draws_held_out_originals_above_their_reconstructions(pretrained):
    import matplotlib.image

    picture = matplotlib.image.imread(pretrained[0].with_suffix(".png"))
    assert picture.shape[0] > 200 and picture.shape[1] > 2 * picture.shape[0]  # two rows of eight images


def test_killed_pretraining_resumes_to_the_same_weights(tmp_path, pretrained, images):
    out = tmp_path / "resumed.pt"

    def kill_at_epoch_two(line: str) -> None:
        if line.startswith("epoch 2/"):
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        pretrain(TINY, out, images=images, log=kill_at_epoch_two)
    assert not out.exists() and (tmp_path / "resumed.snapshot.pt").exists()
    lines = []
    rows = pretrain(TINY, out, images=images, log=lines.append)
    assert any("resuming after epoch 1" in line for line in lines)
    assert not (tmp_path / "resumed.snapshot.pt").exists()
    first, second = load_checkpoint(pretrained[0]), load_checkpoint(out)
    for key, tensor in first["model"].items():
        torch.testing.assert_close(second["model"][key], tensor, rtol=0, atol=0)
    assert [r["held_out_mse"] for r in rows] == [r["held_out_mse"] for r in pretrained[1]]


def test_frozen_encoder_is_the_trained_encoder(pretrained, images):
    frozen = FrozenBevEncoder(pretrained[0])
    model = BevAutoencoder()
    model.load_state_dict(load_checkpoint(pretrained[0])["model"])
    with torch.no_grad():
        expected = model.encoder(as_input(images[:7])).numpy()
    np.testing.assert_allclose(frozen(images[:7]), expected, rtol=0, atol=1e-6)
    assert not any(p.requires_grad for p in frozen.encoder.parameters()) and not frozen.encoder.training


def test_a_policy_checkpoint_is_not_an_autoencoder():
    with pytest.raises(CheckpointError, match="expected a BEV autoencoder file"):
        FrozenBevEncoder("checkpoints/factorial_np_seed0.pt")


# ---------------------------------------------------------------------------------------------- env and network
def bev_observation(path) -> ObservationConfig:
    return ObservationConfig(use_obstacles=False, use_boundary=False, use_bev=True, bev_encoder_file=str(path))


def test_env_observation_holds_the_latent_of_the_untailed_raster(pretrained):
    obs_config = bev_observation(pretrained[0])
    scenes = example_scenes()
    env = ParkingVectorEnv(scenes, 4, EnvConfig(observation=obs_config), seed=1)
    frozen = FrozenBevEncoder(pretrained[0])
    a, b = observation_sections(obs_config)["bev"]
    obs, _ = env.reset(seed=1)
    for _ in range(3):
        poses, index = env.core.S[:, K.S_X: K.S_TH + 1], env.core.S[:, K.S_SCENE].astype(int)
        images = np.stack([render_bev(scenes[k], pose) for k, pose in zip(index, poses)])
        np.testing.assert_allclose(obs[:, a:b], frozen(images), rtol=0, atol=1e-5)
        assert b == obs.shape[1] == 4 + 120 + 128
        obs, *_ = env.step(np.random.default_rng(0).uniform(-1, 1, (4, 2)))


def test_network_bev_branch_replaces_the_geometry_tokens(pretrained):
    obs_config = bev_observation(pretrained[0])
    model = ActorCritic(obs_config)
    assert model.encoder.n_slots == 0 and model.encoder.n_tokens == 3 and model.encoder.bev is not None
    obs = torch.randn(6, 4 + 120 + 128)
    dist, value = model.distribution(obs)
    assert dist.mean.shape == (6, 2) and value.shape == (6,)
    before = model.encoder.bev[0].weight.grad
    dist.mean.sum().backward()
    assert before is None and model.encoder.bev[0].weight.grad.abs().sum() > 0  # the latent reaches the heads


def test_the_planners_actor_of_a_bev_network_is_its_torch_mean_action(pretrained):
    """The compiled kernel has no BEV stream: ``CompiledActor`` of a BEV network (the planner's actor) answers
    with the torch model's mean action, one row and batched (it raised a shape error before)."""
    from np_policy.inference import CompiledActor

    torch.manual_seed(0)
    model = ActorCritic(bev_observation(pretrained[0])).eval()
    with torch.no_grad():
        model.actor[-1].weight.mul_(300.0)
    obs = torch.randn(5, 4 + 120 + 128)
    expected = model.mean_action(obs).numpy()
    actor = CompiledActor(model)
    np.testing.assert_array_equal(actor.batch(obs.numpy()), expected)
    np.testing.assert_allclose(np.stack([actor(o) for o in obs.numpy()]), expected, atol=2e-5, rtol=1e-4)
    assert (np.abs(expected) < 1.0).any()


def test_bev_config_errors():
    with pytest.raises(ConfigError, match="bev_encoder_file: use_bev needs"):
        ObservationConfig(use_obstacles=False, use_boundary=False, use_bev=True)
    with pytest.raises(ConfigError, match="use_bev: the BEV latent replaces the vertex slots"):
        ObservationConfig(use_bev=True, bev_encoder_file="x.pt")


def test_latent_size_must_match_the_encoder(pretrained):
    config = dataclasses.replace(bev_observation(pretrained[0]), bev_latent_dim=64)
    with pytest.raises(ConfigError, match="bev_latent_dim: 64 differs from the latent size 128"):
        ParkingVectorEnv(example_scenes(), 2, EnvConfig(observation=config))


# ---------------------------------------------------------------------------------------------- CLI
def test_cli_refuses_to_overwrite_a_finished_file(capsys, pretrained):
    line = one_error_line(capsys, main, ["--benchmark", "topology", "--out", str(pretrained[0]), "--seed", "0"])
    assert "exists: a finished pretraining is never overwritten" in line


@pytest.mark.parametrize("argv", [["--benchmark", "site", "--out", "x.pt", "--seed", "0"],
                                  ["--benchmark", "topology", "--out", "x.pt", "--seed", "0", "--images", "0"]])
def test_cli_bad_arguments_exit_2(capsys, argv):
    one_error_line(capsys, main, argv)
